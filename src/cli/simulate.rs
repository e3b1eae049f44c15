//! `calbench simulate SCENARIO [--trial I] [--measure KIND] --out DIR`: the measurement of one
//! trial, as a tracker (or, for an instruments study, the instrument of `--measure`) would
//! deliver it (docs/formats.md § 2.5), with the truth beside it.

use std::path::PathBuf;

use anyhow::Result;

use calbench::measurement::kind::Kind;
use calbench::report::simulated;
use calbench::study::instruments::InstrumentsScenario;
use calbench::study::kind::AnyScenario;
use calbench::study::scenario::Scenario;
use calbench::study::{trial, Study};

/// The files written.
const OUTPUTS: [&str; 3] = simulated::FILES;

/// Arguments of `calbench simulate`.
#[derive(clap::Args)]
pub struct SimulateArgs {
    /// The scenario file.
    pub scenario: PathBuf,
    /// The trial (0-based).
    #[arg(long, default_value_t = 0)]
    pub trial: usize,
    /// Instruments studies (`[instruments_study]`): the instrument whose readings are written,
    /// the first entry of this kind (default: the first entry).
    #[arg(long, value_parser = super::named::<Kind>())]
    pub measure: Option<Kind>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// Simulates trial `--trial` of the scenario and writes its measurements and truth.
pub fn run(args: &SimulateArgs) -> Result<()> {
    let (out, trial) = (&args.out, args.trial);
    super::guard_out(out, &OUTPUTS, [&args.scenario])?;
    let sc = match AnyScenario::load(&args.scenario)? {
        AnyScenario::Instruments(sc) => return instrument(&sc, args),
        AnyScenario::MonteCarlo(sc) => sc,
        // Refused as the commands that take a calibration scenario refuse it.
        AnyScenario::Registration(_) => Scenario::load(&args.scenario)?,
    };
    if args.measure.is_some() {
        return Err(simulated::no_instruments(&args.scenario).into());
    }
    // As `run` warns of them (`Scenario::warnings`): a robot too small for its length unit or
    // with limits in radians, settings not read.
    for w in sc.warnings() {
        eprintln!("warning: {w}");
    }
    let study = Study::new(sc)?;
    let sim = trial::simulate_trial(&study, trial, "--trial")?;
    simulated::trial_folder(out, &study, &sim)?;
    out!(
        "{} calibration and {} validation poses of trial {trial} written to {}",
        sim.calibration.data.len(),
        sim.validation.data.len(),
        out.display()
    );
    Ok(())
}

/// Simulates trial `--trial` of an instruments study with the instrument of `--measure` and
/// writes its readings (docs/formats.md § 5.3; a `position` entry: the tracker's file in the
/// base frame), the validation poses as a tracker reads them and the truth.
fn instrument(sc: &InstrumentsScenario, args: &SimulateArgs) -> Result<()> {
    let (out, trial) = (&args.out, args.trial);
    let (_, sim, _) = simulated::instrument_folder(out, sc, args.measure, trial)?;
    let (inst, r) = (&sim.layout.instrument, &sim.reading);
    let Some((qs, data, _)) = &r.measured else {
        unreachable!("InstrumentsScenario::simulate returns readings")
    };
    out!(
        "{} {} readings at {} poses and {} validation poses of trial {trial} written to {}",
        data.values.len() / inst.rows_per_observation(),
        inst.kind().as_str(),
        qs.len(),
        r.validation.0.len(),
        out.display()
    );
    Ok(())
}
