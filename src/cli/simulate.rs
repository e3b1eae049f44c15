//! `calbench simulate SCENARIO [--trial I] --out DIR`: the measurement of one trial, as a
//! tracker would deliver it (docs/formats.md), with the truth beside it.

use std::path::PathBuf;

use anyhow::Result;

use calbench::measurement::csv::write_measurements;
use calbench::study::scenario::Scenario;
use calbench::study::{trial, Study};

use super::{check_out_folder, to_json_text, write_file};

/// The files written.
const OUTPUTS: [&str; 3] = ["measurements.csv", "validation.csv", "truth.json"];

/// Arguments of `calbench simulate`.
#[derive(clap::Args)]
pub struct SimulateArgs {
    /// The scenario file.
    pub scenario: PathBuf,
    /// The trial (0-based).
    #[arg(long, default_value_t = 0)]
    pub trial: usize,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// Simulates trial `--trial` of the scenario and writes its measurements and truth.
pub fn run(args: &SimulateArgs) -> Result<()> {
    let (out, trial) = (&args.out, args.trial);
    check_out_folder(out, &OUTPUTS)?;
    let study = Study::new(Scenario::load(&args.scenario)?)?;
    let sim = trial::simulate_trial(&study, trial, "--trial")?;
    let (m, v) = (&sim.calibration, &sim.validation);
    let truth_json = sim.truth_json(&study);
    let [measurements, validation, truth_file] = OUTPUTS;
    calbench::report::atomically(out, |dir| {
        write_measurements(&dir.join(measurements), &study.nominal, &m.data)?;
        write_measurements(&dir.join(validation), &study.nominal, &v.data)?;
        write_file(&dir.join(truth_file), &to_json_text(&truth_json)?)
    })?;
    out!(
        "{} calibration and {} validation poses of trial {trial} written to {}",
        m.data.len(),
        v.data.len(),
        out.display()
    );
    Ok(())
}
