//! The files of `calbench simulate` (docs/formats.md § 2.5): a trial's measurements
//! (`measurements.csv`), its validation poses as a tracker reads them (`validation.csv`)
//! and the truth (`truth.json`); for an instruments study, the readings of one instrument
//! ([`Readings`]) and its truth ([`instrument_truth`]). [`trial_folder`] and
//! [`instrument_folder`] write the folder, for the command line and Python alike.

use std::path::Path;

use serde_json::{json, Map, Value};

use super::output::{Json, KindFile, MeasurementFile, Output};
use crate::error::{Error, Opt, Result};
use crate::measurement::csv::check_coordinate;
use crate::measurement::kind::{Instrument, Kind};
use crate::measurement::Measurements;
use crate::robot::Robot;
use crate::study::instruments::{InstrumentsScenario, Simulated};
use crate::study::scenario::RobotRef;
use crate::study::trial::SimulatedTrial;
use crate::study::Study;

/// The files written.
pub const FILES: [&str; 3] = ["measurements.csv", "validation.csv", "truth.json"];

/// The readings of one instrument in one trial (docs/formats.md § 5.3): a `position` entry
/// as the tracker's file in the base frame, every other kind as its own file. σ is written
/// when every reading has one (a noise-free instrument has none); a multi-target file has
/// no σ column.
pub struct Readings<'a> {
    /// The nominal robot, whose units the joints are written in.
    pub robot: &'a Robot,
    /// The trial (its `reading.measured` is `Some`).
    pub trial: &'a Simulated,
}

impl Output for Readings<'_> {
    fn name(&self) -> &str {
        FILES[0]
    }
    fn write(&self, path: &Path) -> Result<()> {
        let (robot, inst) = (self.robot, &self.trial.layout.instrument);
        let Some((qs, data, sigma)) = &self.trial.reading.measured else {
            unreachable!("InstrumentsScenario::simulate returns readings")
        };
        let multi = self.trial.settings.kind == Kind::MultiTarget;
        let sigma = (!multi && sigma.iter().all(|v| *v > 0.0)).then_some(&sigma[..]);
        if inst.kind() != Kind::Position {
            let (name, sigma_mm) = (FILES[0], sigma);
            return KindFile {
                name,
                robot,
                qs,
                data,
                sigma_mm,
            }
            .write(path);
        }
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
        MeasurementFile {
            name: FILES[0],
            robot,
            rows: &m,
        }
        .write(path)
    }
}

/// The validation poses of an instruments study's trial as a tracker reads them (the true
/// robot's tool points, base frame): the content of `validation.csv`.
pub fn validation(trial: &Simulated) -> Measurements {
    let (qs, points) = &trial.reading.validation;
    Measurements {
        qs: qs.clone(),
        points: points.clone(),
        ..Measurements::default()
    }
}

/// `truth.json` of an instruments study's trial `trial` with entry `entry` of the scenario
/// named `scenario`, on the nominal robot named `robot`: the true robot's errors and the
/// instrument's own unknowns.
pub fn instrument_truth(
    (scenario, robot): (&str, &str),
    (entry, trial): (usize, usize),
    sim: &Simulated,
) -> Value {
    let inst = &sim.layout.instrument;
    let errors: Map<String, Value> = sim
        .reading
        .errors
        .iter()
        .map(|(p, e)| (p.to_string(), json!(e)))
        .collect();
    let unknowns: Map<String, Value> = inst
        .nuisance_names()
        .into_iter()
        .zip(&sim.layout.nuisance)
        .map(|(n, v)| (n, json!(v)))
        .collect();
    let mut truth = json!({
        "scenario": scenario,
        "trial": trial,
        "seed": sim.seed,
        "robot": robot,
        "calibration_poses": "random",
        "kind": inst.kind().as_str(),
        "measurement": entry,
        "errors": errors,
        "instrument_unknowns": unknowns,
    });
    if let Instrument::Planes(axes) = inst {
        truth["plane_axes"] = json!(axes.iter().map(|&a| ["x", "y", "z"][a]).collect::<Vec<_>>());
    }
    if let Instrument::Distance { pivot } = inst {
        truth["pivot"] = json!(pivot);
    }
    truth
}

/// Writes trial `sim` of the Monte-Carlo study `study` to the folder `out`: the calibration
/// and validation measurements as the tracker reads them, and the truth.
pub fn trial_folder(out: &Path, study: &Study, sim: &SimulatedTrial) -> Result<()> {
    let [measurements, validation, truth] = FILES;
    let robot = &study.nominal;
    let sc = &study.scenario;
    let named = match &sc.robot {
        RobotRef::File(p) => p.display().to_string(),
        RobotRef::Builtin(n) => format!("the built-in robot {n}"),
    };
    for (file, m) in [
        (measurements, &sim.calibration.data),
        (validation, &sim.validation.data),
    ] {
        within_range((sc.path.as_deref(), &named), file, m)?;
    }
    super::output::folder(
        out,
        &[
            &MeasurementFile {
                name: measurements,
                robot,
                rows: &sim.calibration.data,
            },
            &MeasurementFile {
                name: validation,
                robot,
                rows: &sim.validation.data,
            },
            &Json {
                name: truth,
                value: &sim.truth_json(study),
            },
        ],
    )
}

/// The refusal of an instrument named for a study that has none: the scenario `path` is a
/// Monte-Carlo or registration study, measured by the tracker alone.
pub fn no_instruments(path: &Path) -> Error {
    Error::option(
        Opt::Measure,
        format!(
            "{} is not an instruments study ([instruments_study]): its measurement is the \
             tracker's",
            path.display()
        ),
    )
}

/// Simulates trial `trial` of the instruments study `sc` on its nominal robot, measured by
/// its first `[[measurement]]` entry of kind `measure` (the first entry when `None`), and
/// writes it to the folder `out`: the readings ([`Readings`]), the validation poses as a
/// tracker reads them ([`validation`]) and the truth ([`instrument_truth`]). Returns the
/// nominal robot, the trial and its truth.
pub fn instrument_folder(
    out: &Path,
    sc: &InstrumentsScenario,
    measure: Option<Kind>,
    trial: usize,
) -> Result<(Robot, Simulated, Value)> {
    let all = &sc.measurement;
    let entry = match measure {
        None => 0,
        Some(k) => all.iter().position(|s| s.kind == k).ok_or_else(|| {
            let kinds: Vec<&str> = all.iter().map(|s| s.kind.as_str()).collect();
            Error::option(
                Opt::Measure,
                format!(
                    "{} has no [[measurement]] of kind {} (it has {})",
                    sc.head.path.display(),
                    k.as_str(),
                    kinds.join(", ")
                ),
            )
        })?,
    };
    let chain = crate::robot::urdf::UrdfChain::default();
    let nominal = crate::robot::builtin::load_chain(&sc.robot, &chain)?;
    let sim = sc.simulate(&nominal, entry, trial)?;
    let truth = instrument_truth((&sc.head.name, &nominal.name), (entry, trial), &sim);
    let [measurements, validation_file, truth_file] = FILES;
    let scenario = (Some(sc.head.path.as_path()), sc.robot.as_str());
    if let Some((_, data, _)) = &sim.reading.measured {
        if sim.layout.instrument.kind() == Kind::Position {
            let points: Vec<_> = data
                .values
                .chunks(3)
                .map(|c| [c[0], c[1], c[2]].into())
                .collect();
            within_range(
                scenario,
                measurements,
                &Measurements {
                    points,
                    ..Measurements::default()
                },
            )?;
        }
    }
    within_range(scenario, validation_file, &validation(&sim))?;
    super::output::folder(
        out,
        &[
            &Readings {
                robot: &nominal,
                trial: &sim,
            },
            &MeasurementFile {
                name: validation_file,
                robot: &nominal,
                rows: &validation(&sim),
            },
            &Json {
                name: truth_file,
                value: &truth,
            },
        ],
    )?;
    Ok((nominal, sim, truth))
}

/// Refuses the simulated tracker file `file` (`m`, written as § 5.1 lays it out) of the
/// scenario `(path, robot)` (its file, when it has one, and its robot named) when a point lies
/// beyond the range a measurement file is read in ([`check_coordinate`]): `identify` would
/// refuse the file. A robot file whose lengths are written in mm under `length_unit = "m"` is
/// the usual cause. Checked before the folder is written: nothing is.
fn within_range((path, robot): (Option<&Path>, &str), file: &str, m: &Measurements) -> Result<()> {
    for (i, p) in m.points.iter().enumerate() {
        for (k, v) in [p.x, p.y, p.z].into_iter().enumerate() {
            let Err(msg) = check_coordinate(v) else {
                continue;
            };
            let msg = format!(
                "{robot}: the simulated {file} would hold at line {}, column {}: {msg}; are the \
                 robot's lengths in its length_unit? (nothing was written)",
                i + 2,
                ["x", "y", "z"][k]
            );
            return Err(match path {
                Some(path) => Error::file(path, "robot", msg),
                None => Error::setting("robot", msg),
            });
        }
    }
    Ok(())
}
