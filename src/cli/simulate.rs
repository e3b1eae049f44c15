//! `calbench simulate SCENARIO [--trial I] --out DIR`: the measurement of one trial, as a
//! tracker would deliver it (docs/formats.md), with the truth beside it.

use std::path::PathBuf;

use anyhow::Result;
use serde_json::json;

use calbench::error::Error;
use calbench::measurement::csv::write_measurements;
use calbench::numeric::rng;
use calbench::sim::measure_poses;
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
    let sc = Scenario::load(&args.scenario)?;
    if trial >= sc.trials {
        return Err(Error::setting(
            "--trial",
            format!(
                "trial {trial} does not exist: the scenario has {} trials (0-based)",
                sc.trials
            ),
        )
        .into());
    }
    let study = Study::new(sc)?;
    let sc = &study.scenario;
    let (errors, truth) = trial::true_robot(&study, trial);
    let seed = rng::trial_seed(sc.seed, trial as u64);
    let qs = trial::calibration_poses(&study, 0, trial)?;
    let vqs = trial::validation_poses(&study, trial)?;
    let sag = trial::sag_fn(&study);
    let sag_ref = sag.as_deref();
    let m = trial::measure_calibration(
        &study,
        &truth,
        &qs,
        sag_ref,
        &mut rng::stream(seed, "measure"),
    )?;
    // The validation file records its payload when the scenario measures under loads.
    let loaded = sc.calibration.payloads_kg.is_some() || sc.validation.payload_kg.is_some();
    let vloads = loaded.then(|| vec![study.validation_payload(); vqs.len()]);
    let v = measure_poses(
        &truth,
        &vqs,
        &study.tracker,
        None,
        sag_ref,
        vloads.as_deref(),
        &mut rng::stream(seed, "measure/validation"),
    )?;
    let errs: serde_json::Map<String, serde_json::Value> = errors
        .iter()
        .map(|(p, e)| (p.to_string(), json!(e)))
        .collect();
    let mut truth_json = json!({
        "scenario": sc.name,
        "trial": trial,
        "seed": seed,
        "robot": study.nominal.name,
        "calibration_poses": sc.calibration.strategies[0].name(),
        "errors": errs,
        "tracker_pose": sc.tracker.pose,
        "outliers": m.truth.outliers,
        "sag_mm": m.truth.sag_mm,
        "validation_sag_mm": v.truth.sag_mm,
    });
    if let Some(c) = study.true_compliance_json() {
        truth_json["true_compliance"] = c;
    }
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
