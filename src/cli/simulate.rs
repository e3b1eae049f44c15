//! `calbench simulate SCENARIO [--trial I] [--measure KIND] --out DIR`: the measurement of one
//! trial, as a tracker (or, for an instruments study, the instrument of `--measure`) would
//! deliver it (docs/formats.md § 2.5), with the truth beside it.

use std::path::PathBuf;

use anyhow::Result;

use calbench::error::Error;
use calbench::measurement::csv::write_measurements;
use calbench::measurement::kind::Kind;
use calbench::measurement::Measurements;
use calbench::study::instruments::InstrumentsScenario;
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
    /// Instruments studies (`[[measurement]]`): the instrument whose readings are written,
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
    check_out_folder(out, &OUTPUTS)?;
    let table = super::scenario_table(&args.scenario)?;
    if InstrumentsScenario::is_one(&table) {
        let sc = InstrumentsScenario::from_table(table, &args.scenario)?;
        return instrument(&sc, args);
    }
    if args.measure.is_some() {
        return Err(Error::setting(
            "--measure",
            format!(
                "{} is not an instruments study ([[measurement]] tables): its measurement is \
                 the tracker's",
                args.scenario.display()
            ),
        )
        .into());
    }
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

/// Simulates trial `--trial` of an instruments study with the instrument of `--measure` and
/// writes its readings (docs/formats.md § 5.3; a `position` entry: the tracker's file in the
/// base frame), the validation poses as a tracker reads them and the truth.
fn instrument(sc: &InstrumentsScenario, args: &SimulateArgs) -> Result<()> {
    let (out, trial) = (&args.out, args.trial);
    let all = sc.instruments();
    let entry = match args.measure {
        None => 0,
        Some(k) => all.iter().position(|s| s.kind == k).ok_or_else(|| {
            let kinds: Vec<&str> = all.iter().map(|s| s.kind.as_str()).collect();
            Error::setting(
                "--measure",
                format!(
                    "{} has no [[measurement]] of kind {} (it has {})",
                    args.scenario.display(),
                    k.as_str(),
                    kinds.join(", ")
                ),
            )
        })?,
    };
    let nominal = super::ChainArgs::default().load(&sc.robot)?;
    let sim = sc.simulate(&nominal, entry, trial)?;
    let r = &sim.reading;
    let Some((qs, data, sigma)) = &r.measured else {
        unreachable!("InstrumentsScenario::simulate returns readings")
    };
    // σ is written when every reading has one (a noise-free instrument has none); a
    // multi-target file has no σ column.
    let multi = all[entry].kind == Kind::MultiTarget;
    let sigma = (!multi && sigma.iter().all(|v| *v > 0.0)).then_some(&sigma[..]);
    let (vq, seen) = &r.validation;
    let validation = Measurements {
        qs: vq.clone(),
        points: seen.clone(),
        ..Measurements::default()
    };
    let inst = &sim.layout.instrument;
    let errors: serde_json::Map<String, serde_json::Value> = r
        .errors
        .iter()
        .map(|(p, e)| (p.to_string(), serde_json::json!(e)))
        .collect();
    let unknowns: serde_json::Map<String, serde_json::Value> = inst
        .nuisance_names()
        .into_iter()
        .zip(&sim.layout.nuisance)
        .map(|(n, v)| (n, serde_json::json!(v)))
        .collect();
    let mut truth = serde_json::json!({
        "scenario": sc.head.name,
        "trial": trial,
        "seed": sim.seed,
        "robot": nominal.name,
        "calibration_poses": "random",
        "kind": inst.kind().as_str(),
        "measurement": entry,
        "errors": errors,
        "instrument_unknowns": unknowns,
    });
    if let calbench::measurement::kind::Instrument::Planes(axes) = inst {
        truth["plane_axes"] =
            serde_json::json!(axes.iter().map(|&a| ["x", "y", "z"][a]).collect::<Vec<_>>());
    }
    if let calbench::measurement::kind::Instrument::Distance { pivot } = inst {
        truth["pivot"] = serde_json::json!(pivot);
    }
    let [measurements, validation_file, truth_file] = OUTPUTS;
    calbench::report::atomically(out, |dir| {
        let path = dir.join(measurements);
        if inst.kind() == Kind::Position {
            let m = Measurements {
                qs: qs.clone(),
                points: data
                    .values
                    .chunks(3)
                    .map(|c| [c[0], c[1], c[2]].into())
                    .collect(),
                sigma_mm: sigma.map(<[_]>::to_vec),
                ..Measurements::default()
            };
            write_measurements(&path, &nominal, &m)?;
        } else {
            let wr = calbench::measurement::kind_csv::write_kind_file;
            wr(&path, &nominal, qs, data, sigma)?;
        }
        write_measurements(&dir.join(validation_file), &nominal, &validation)?;
        write_file(&dir.join(truth_file), &to_json_text(&truth)?)
    })?;
    out!(
        "{} {} readings at {} poses and {} validation poses of trial {trial} written to {}",
        data.values.len() / inst.rows_per_observation(),
        inst.kind().as_str(),
        qs.len(),
        vq.len(),
        out.display()
    );
    Ok(())
}
