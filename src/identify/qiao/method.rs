//! The derivative-free searches of Qiao 2021 (BAS, PSO, BAS-PSO; §3, eqs. 12–14) as
//! identification methods: each searches the errors of the problem's parameters in a box of
//! ± `bound_mm` (lengths) and ± `bound_rad` (angles) around the nominal values, minimising
//! Qiao's fitness (eq. 14, [`crate::identify::qiao::MetaProblem::fitness`]), or with the key
//! `error_model` the same fitness on one of Qiao's linear pose-error models (§2.2–2.3,
//! [`LinearFitness`]), as Qiao identified each model with BAS-PSO (§4.2, fig. 7). The
//! searches themselves are in [`crate::identify::qiao`].

use serde::Deserialize;

use crate::error::{finite_positive, Error, Result};
use crate::identify::options;
use crate::identify::qiao::error_models::{ErrorModel, ERROR_MODEL};
use crate::identify::qiao::{
    bas, bas_pso, pso, BasOptions, BasPsoOptions, Bounds, Fitness, MetaProblem, MetaResult,
    PsoOptions, Schedules,
};
use crate::identify::{CalibrationProblem, Identified, Method, Termination};
use crate::numeric::rng::Rng;
use crate::numeric::Real;
use crate::robot::Param;

/// A search over a box: the options of one of [`bas`], [`pso`], [`bas_pso`].
pub trait Search: std::fmt::Debug + Send + Sync {
    /// Checks the option values.
    fn check(&self) -> Result<()>;
    /// The schedules of eq. 13, when the search has them (their keys are read into them).
    fn schedules(&mut self) -> Option<&mut Schedules> {
        None
    }
    /// Minimises `f` over `b`.
    fn search(&self, f: &Fitness, b: &Bounds, rng: &mut Rng) -> Result<MetaResult>;
}

/// Each search's options check themselves and run their search.
macro_rules! search {
    ($options:ty, $run:path $(, $($schedules:ident).+)?) => {
        impl Search for $options {
            fn check(&self) -> Result<()> {
                <$options>::check(self)
            }
            $(fn schedules(&mut self) -> Option<&mut Schedules> {
                Some(&mut self.$($schedules).+)
            })?
            fn search(&self, f: &Fitness, b: &Bounds, rng: &mut Rng) -> Result<MetaResult> {
                $run(f, b, self, rng)
            }
        }
    };
}

search!(BasOptions, bas, schedules);
search!(PsoOptions, pso);
search!(BasPsoOptions, bas_pso, beetle.schedules);

/// Options of `bas`, `pso` and `bas-pso` (docs/formats.md `[[methods]]`): the search's own
/// options and the search box. Deserialised from one table: the keys [`SearchBox`] declares
/// go to `bounds`, every other key into the search's options (which refuse unknown keys).
#[derive(Clone, Debug, Default)]
pub struct Metaheuristic<S> {
    /// The search and its options.
    pub search: S,
    /// The box searched, and the fitness.
    pub bounds: SearchBox,
}

/// The box a search explores around the nominal values, and the fitness it minimises.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SearchBox {
    /// Half-width of the search box on length parameters, mm. Default 2.
    pub bound_mm: Real,
    /// Half-width of the search box on angle parameters, rad. Default 0.02.
    pub bound_rad: Real,
    /// Half-width of the search box on joint compliances, rad/(N·m). Default 1e-5 (ten
    /// times an industrial arm's main-axis compliance).
    pub bound_compliance: Real,
    /// The pose-error model whose fitness is searched: `differential` or
    /// `coordinate_transfer` (linearised at the nominal robot, [`LinearFitness`]), or
    /// `direct_fk`, the forward kinematics themselves, which is also the default (`None`).
    pub error_model: Option<ErrorModel>,
}

impl Default for SearchBox {
    fn default() -> Self {
        SearchBox {
            bound_mm: 2.0,
            bound_rad: 0.02,
            bound_compliance: 1e-5,
            error_model: None,
        }
    }
}

impl SearchBox {
    /// The pose-error model of the fitness searched: [`ErrorModel::DirectFk`] when none is
    /// named (the forward kinematics themselves, the same fitness).
    pub fn fitness_model(&self) -> ErrorModel {
        self.error_model.unwrap_or(ErrorModel::DirectFk)
    }

    /// The box's half-widths, in [`super::fitness::box_side`]'s order, with the options that
    /// set them.
    fn sides(&self) -> [(&'static str, Real); 3] {
        [
            ("bound_mm", self.bound_mm),
            ("bound_rad", self.bound_rad),
            ("bound_compliance", self.bound_compliance),
        ]
    }

    /// The parameters of `params` whose errors `x` (in their order) lie on the box's edge,
    /// within a millionth of its half-width: where a search ends when the minimum lies
    /// beyond the box, so that the result is the box's corner, not the data's answer.
    pub fn at_edge(&self, params: &[Param], x: &[Real]) -> Vec<Param> {
        let sides = self.sides();
        let on_edge = |(&p, &v): (&Param, &Real)| {
            let w = sides[super::fitness::box_side(p)].1;
            v.abs() >= w * (1.0 - 1e-6)
        };
        params
            .iter()
            .zip(x)
            .filter(|&px| on_edge(px))
            .map(|(&p, _)| p)
            .collect()
    }

    /// The warning for a search that ended with parameters of `params` on the edge of the
    /// box ([`Self::at_edge`] of the errors `x`), naming them and the options that widen it;
    /// `None` when none is.
    pub fn edge_warning(&self, params: &[Param], x: &[Real]) -> Option<String> {
        let edge = self.at_edge(params, x);
        if edge.is_empty() {
            return None;
        }
        let mut used: Vec<usize> = edge.iter().map(|&p| super::fitness::box_side(p)).collect();
        used.sort_unstable();
        used.dedup();
        let sides = self.sides();
        let values: Vec<String> = (used.iter())
            .map(|&k| format!("{} = {}", sides[k].0, crate::error::shown(sides[k].1)))
            .collect();
        let keys: Vec<&str> = used.iter().map(|&k| sides[k].0).collect();
        let names: Vec<String> = edge.iter().map(Param::to_string).collect();
        Some(format!(
            "the search ended with {} of its parameters on the edge of its box ({}; {}): the \
             errors may lie beyond it, and the result is then the box's, not the data's; widen \
             the box (the method's {} {})",
            names.len(),
            names.join(", "),
            values.join(", "),
            if keys.len() == 1 { "option" } else { "options" },
            keys.join(" and ")
        ))
    }
}

impl<'de, S> Deserialize<'de> for Metaheuristic<S>
where
    S: Search + Default + serde::de::DeserializeOwned,
{
    /// The box's keys to [`SearchBox`], the schedules' keys (if the search has schedules) to
    /// [`Schedules`] over the search's defaults, the rest to the search's options.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let mut t = toml::Table::deserialize(d)?;
        let bounds = options::split::<SearchBox>(&mut t);
        let schedules = S::default()
            .schedules()
            .is_some()
            .then(|| options::split::<Schedules>(&mut t));
        let taken = [
            options::fields::<SearchBox>(),
            schedules
                .as_ref()
                .map_or(&[][..], |_| options::fields::<Schedules>()),
        ];
        let mut search = S::deserialize(toml::Value::Table(t))
            .map_err(|e| D::Error::custom(options::with_taken(e, &taken)))?;
        if let (Some(given), Some(s)) = (schedules, search.schedules()) {
            *s = options::with_defaults(&*s, given).map_err(D::Error::custom)?;
        }
        Ok(Metaheuristic {
            bounds: SearchBox::deserialize(toml::Value::Table(bounds)).map_err(D::Error::custom)?,
            search,
        })
    }
}

impl<S: Search> Method for Metaheuristic<S> {
    fn check(&self) -> Result<()> {
        self.search.check()?;
        for (key, half_width) in self.bounds.sides() {
            finite_positive(key, half_width)?;
        }
        Ok(())
    }

    fn fitness_model(&self) -> Option<ErrorModel> {
        Some(self.bounds.fitness_model())
    }

    fn search_box(&self) -> Option<&SearchBox> {
        Some(&self.bounds)
    }

    /// The search's best point; [`Termination::TargetReached`] when it stopped at its target
    /// fitness, [`Termination::MaxEvaluations`] when its `max_evaluations` budget ran out
    /// before its `iterations`, else [`Termination::MaxIterations`]. The trace is the best fitness per
    /// iteration (Qiao 2021 fig. 4).
    fn identify(&self, problem: &CalibrationProblem, rng: &mut Rng) -> Result<Identified> {
        let mp = MetaProblem::new(
            problem.nominal,
            problem.params.to_vec(),
            problem.poses().to_vec(),
            problem.points.clone(),
            problem.rotations.clone(),
            problem.k,
        )?
        .with_weights(problem.weights.as_deref())?
        .with_payloads(problem.data.payload_kg.as_deref())?;
        let b = &self.bounds;
        let bounds = mp.bounds(b.bound_mm, b.bound_rad, b.bound_compliance);
        let r = match b.error_model {
            None | Some(ErrorModel::DirectFk) => {
                let f = |x: &[Real]| mp.fitness(x);
                self.search.search(&f, &bounds, rng)?
            }
            Some(model) => {
                let lin = LinearFitness::new(model, problem)?;
                let f = |x: &[Real]| lin.fitness(x);
                self.search.search(&f, &bounds, rng)?
            }
        };
        let termination = if r.reached_target {
            Termination::TargetReached
        } else if r.budget_spent {
            Termination::MaxEvaluations
        } else {
            Termination::MaxIterations
        };
        let mut out = Identified::plain(
            r.x,
            r.iterations,
            r.evaluations,
            termination,
            problem.data.len(),
        );
        out.trace = Some(r.trace);
        Ok(out)
    }
}

/// Qiao's fitness (eq. 14) on a linear pose-error model (§2.2 differential, §2.3 coordinate
/// transfer): the model's residual `r₀ − J₀x` at the errors `x`, with `r₀` and `J₀` taken at
/// the nominal robot ([`crate::identify::qiao::error_models::stack`], orientation rows weighted by `k`), summed
/// as eq. 14 sums its terms: per pose, the norm of the position block plus the norm of each
/// three-row orientation block (`k(|Δn| + |Δo| + |Δa|)` for the differential model, `k|δ|`
/// for the coordinate transfer), times the pose's prior weight. Allocation-free.
#[derive(Clone, Debug)]
pub struct LinearFitness {
    /// `r₀`, one value per row.
    r0: Vec<Real>,
    /// `J₀`, row-major (`cols` values per row).
    j0: Vec<Real>,
    cols: usize,
    /// Rows per pose.
    rows: usize,
    /// Prior weight of each pose (1 without weights).
    weights: Vec<Real>,
}

impl LinearFitness {
    /// The model at the nominal robot of `problem`; needs full-pose data and a kinematic
    /// parameter list (`error_model` otherwise).
    pub fn new(model: ErrorModel, problem: &CalibrationProblem) -> Result<LinearFitness> {
        if problem.params.iter().any(|p| p.is_compliance()) {
            return Err(Error::setting(
                ERROR_MODEL,
                "the pose-error models (Qiao 2021 §2) are kinematic: search joint \
                 compliances without error_model",
            ));
        }
        let frames = problem.measured_frames(ERROR_MODEL)?;
        let (r, j) = crate::identify::qiao::error_models::stack(
            model,
            problem.nominal,
            problem.params,
            problem.poses(),
            &frames,
            problem.k,
        )?;
        let cols = j.ncols();
        let mut j0 = Vec::with_capacity(j.len());
        for row in j.row_iter() {
            j0.extend(row.iter());
        }
        Ok(LinearFitness {
            r0: r.as_slice().to_vec(),
            j0,
            cols,
            rows: model.rows(),
            weights: problem
                .weights
                .clone()
                .unwrap_or_else(|| vec![1.0; frames.len()]),
        })
    }

    /// The fitness of the errors `x`; `+∞` if `x` has the wrong length.
    pub fn fitness(&self, x: &[Real]) -> Real {
        if x.len() != self.cols {
            return Real::INFINITY;
        }
        let mut total = 0.0;
        for (pose, w) in self.weights.iter().enumerate() {
            let mut term = 0.0;
            for block in 0..self.rows / 3 {
                let mut sq = 0.0;
                for k in 0..3 {
                    let row = pose * self.rows + 3 * block + k;
                    let j = &self.j0[row * self.cols..(row + 1) * self.cols];
                    let e = self.r0[row] - j.iter().zip(x).map(|(a, b)| a * b).sum::<Real>();
                    sq += e * e;
                }
                term += sq.sqrt();
            }
            total += w * term;
        }
        total
    }
}
