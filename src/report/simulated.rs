//! The files of `calbench simulate` (docs/formats.md § 2.5): a trial's measurements
//! (`measurements.csv`), its validation poses as a tracker reads them (`validation.csv`)
//! and the truth (`truth.json`); for an instruments study, the readings of one instrument
//! ([`Readings`]) and its truth ([`instrument_truth`]).

use std::path::Path;

use serde_json::{json, Map, Value};

use super::output::{KindFile, MeasurementFile, Output};
use crate::error::Result;
use crate::measurement::kind::{Instrument, Kind};
use crate::measurement::Measurements;
use crate::robot::Robot;
use crate::study::instruments::Simulated;

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
