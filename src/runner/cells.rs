//! The studies that run cells rather than calibration trials — Ban fig. 3's registration
//! study and an instruments study — as the runner sees them ([`Cells`]): blocks of trials,
//! each trial's result a record, the files written from every block's results. The runner
//! runs them whole ([`super::whole`]) or in shares merged after ([`super::shard`]).

use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::error::Result;
use crate::numeric::rng::trial_seed;
use crate::numeric::Real;
use crate::report::output::{Outputs, Text};
use crate::report::scenario_file;
use crate::robot::Robot;
use crate::study::instruments::{CellPlan, InstrumentsScenario, Trial};
use crate::study::kind::AnyScenario;
use crate::study::registration_study::RegistrationScenario;

/// A study whose work units are its blocks' trials, each trial's result a record
/// ([`crate::study::records`]), its files written from every block's results.
pub trait Cells: Sync {
    /// What a block's trials share.
    type Block: Send + Sync;
    /// One trial's result.
    type Trial: Serialize + DeserializeOwned + Send + Sync;
    /// Block `b`, from the previous one when it is given (what they share is not redone).
    fn block(&self, b: usize, prev: Option<&Self::Block>) -> Result<Self::Block>;
    /// Trial `i` of `block`.
    fn trial(&self, block: &Self::Block, i: usize) -> Result<Self::Trial>;
    /// Why `t`, read from a record, cannot be a trial of `block`, if it cannot: a record whose
    /// values the study's files would index past (its checksum made to match an edit).
    fn misfit(&self, _block: &Self::Block, _t: &Self::Trial) -> Option<String> {
        None
    }
    /// The study's files from every block's trials, in order, and the table the terminal
    /// shows.
    fn outputs(&self, done: Vec<(Self::Block, Vec<Self::Trial>)>) -> Result<(Outputs<'_>, String)>;
}

/// The study's files ([`Cells::outputs`]) with the scenario as run, `scenario.toml`
/// ([`crate::report::scenario_file`]), which `record` stores; and the table the terminal
/// shows.
pub fn study_files<'c, C: Cells>(
    cells: &'c C,
    sc: &AnyScenario,
    done: Vec<(C::Block, Vec<C::Trial>)>,
) -> Result<(Outputs<'c>, String)> {
    let (mut outputs, table) = cells.outputs(done)?;
    outputs.push(Box::new(Text {
        name: scenario_file::NAME,
        text: scenario_file::with_hash(&sc.settings()?),
    }));
    Ok((outputs, table))
}

impl Cells for RegistrationScenario {
    type Block = ();
    type Trial = Vec<(Real, Real)>;
    fn block(&self, _: usize, _: Option<&()>) -> Result<()> {
        self.registration_study.check()
    }
    fn trial(&self, _: &(), i: usize) -> Result<Self::Trial> {
        self.registration_study
            .draw(trial_seed(self.head.seed, i as u64))
    }
    fn misfit(&self, _: &(), t: &Self::Trial) -> Option<String> {
        let s = &self.registration_study;
        let cells = s.outlier_counts.len() * s.magnitude_mm.len();
        (t.len() != cells).then(|| {
            format!(
                "registration errors of {} cells, for a study of {cells}",
                t.len()
            )
        })
    }
    fn outputs(&self, done: Vec<((), Vec<Self::Trial>)>) -> Result<(Outputs<'_>, String)> {
        let draws = done.into_iter().next().map(|d| d.1).unwrap_or_default();
        let cells = self.registration_study.cells(&draws);
        let claims = self.evaluate_claims(&draws);
        crate::report::registration_study::outputs(self, &cells, &claims)
    }
}

/// An instruments study and its nominal robot.
pub struct Instruments<'a> {
    /// The study.
    pub scenario: &'a InstrumentsScenario,
    /// The nominal robot (`robot` of the scenario).
    pub robot: Robot,
    /// How many errors each trial's true robot carries (`[errors]`), when they can be
    /// counted: what a record of a trial must hold ([`Trial::misfit`]).
    errors: Option<usize>,
}

impl Cells for Instruments<'_> {
    type Block = CellPlan;
    type Trial = Option<Trial>;
    fn block(&self, b: usize, prev: Option<&CellPlan>) -> Result<CellPlan> {
        self.scenario.plan(&self.robot, b, prev)
    }
    fn trial(&self, block: &CellPlan, i: usize) -> Result<Self::Trial> {
        self.scenario.run_trial(&self.robot, block, i)
    }
    fn misfit(&self, block: &CellPlan, t: &Self::Trial) -> Option<String> {
        t.as_ref()?.misfit(block, self.errors)
    }
    fn outputs(&self, done: Vec<(CellPlan, Vec<Self::Trial>)>) -> Result<(Outputs<'_>, String)> {
        let cells: Vec<_> = done
            .iter()
            .map(|(p, t)| self.scenario.cell_of(p, t))
            .collect();
        crate::report::instruments::outputs(self.scenario, &cells)
    }
}

impl<'a> Instruments<'a> {
    /// The study `scenario` with its nominal robot loaded.
    pub fn new(scenario: &'a InstrumentsScenario) -> Result<Instruments<'a>> {
        let robot = scenario.load_robot()?;
        let e = &scenario.errors;
        let errors = if e.kind == crate::sim::settings::ErrorKind::None {
            Some(0)
        } else {
            let measure = crate::measurement::Measure::Position;
            crate::sim::truth::selected_params(&robot, &e.selection(), measure, e.key())
                .ok()
                .map(|p| p.len())
        };
        Ok(Instruments {
            scenario,
            robot,
            errors,
        })
    }
}
