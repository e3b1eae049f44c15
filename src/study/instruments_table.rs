//! The `[instruments_study]` table of an instruments study (docs/formats.md § 4.15): its keys,
//! moved to the top level where [`super::instruments::InstrumentsScenario`] reads them, the
//! refusal of the layout before the table, saying how to migrate, and the reading of the
//! whole scenario, each refusal at the key and line it is about.

use std::path::Path;

use crate::error::{Error, Result};
use crate::sim::instrument::InstrumentSettings;
use crate::study::instruments::{strategy, InstrumentsScenario};
use crate::study::whole::Head;

/// The table that makes a scenario an instruments study.
pub const INSTRUMENTS_STUDY: &str = "instruments_study";

/// The keys of [`INSTRUMENTS_STUDY`].
pub const INSTRUMENTS_KEYS: [&str; 4] = ["poses", "strategies", "candidates", "validation"];

/// The keys an instruments study takes at the top level, beside [`Head`]'s.
const TOP_KEYS: [&str; 4] = ["robot", "errors", INSTRUMENTS_STUDY, "measurement"];

/// What an instruments study's file takes, as its refusals of another key say.
const TAKES: &str = "with [instruments_study] takes name, description, seed, \
    trials, robot, [errors], [instruments_study] and its [[measurement]] tables";

/// How a scenario written before [`INSTRUMENTS_STUDY`] existed is migrated.
pub const MIGRATE: &str = "an instruments study is declared by an [instruments_study] table \
    holding its poses, strategies, candidates and validation (CHANGELOG.md, docs/formats.md \
    § 4.15): add `[instruments_study]` and move those keys under it";

/// An instruments study's `table` with the keys of its `[instruments_study]` table moved to
/// the top level, where [`super::instruments::InstrumentsScenario`] reads them; `path` names the file in errors.
/// One of those keys at the top level (the layout before the table), a missing table and a
/// key the table does not take are refused, naming the key and saying how to migrate; so is
/// another key at the top level, naming what the file takes (not the table's keys, which
/// the scenario's fields would list once moved).
pub fn instruments_keys(mut table: toml::Table, path: &Path) -> Result<toml::Table> {
    let ferr = |place: &str, msg: String| Error::file(path, place, msg);
    if let Some(key) = INSTRUMENTS_KEYS.iter().find(|k| table.contains_key(**k)) {
        return Err(ferr(
            key,
            format!("{MIGRATE} (`{key}` is at the top level)"),
        ));
    }
    let known = |k: &String| {
        crate::study::whole::KEYS.contains(&k.as_str()) || TOP_KEYS.contains(&k.as_str())
    };
    if let Some(key) = table.keys().find(|k| !known(k)) {
        return Err(ferr(key, format!("unknown key: a scenario {TAKES}")));
    }
    let study = match table.remove(INSTRUMENTS_STUDY) {
        Some(toml::Value::Table(t)) => t,
        Some(_) => return Err(ferr(INSTRUMENTS_STUDY, "must be a table".into())),
        None => return Err(ferr(INSTRUMENTS_STUDY, format!("is missing: {MIGRATE}"))),
    };
    for (k, v) in study {
        if !INSTRUMENTS_KEYS.contains(&k.as_str()) {
            return Err(ferr(
                &format!("{INSTRUMENTS_STUDY}.{k}"),
                format!(
                    "unknown key: [{INSTRUMENTS_STUDY}] takes {}",
                    INSTRUMENTS_KEYS.join(", ")
                ),
            ));
        }
        table.insert(k, v);
    }
    Ok(table)
}

impl InstrumentsScenario {
    /// The robot file `robot` names, relative to the scenario file's folder as a Monte-Carlo
    /// scenario's `[robot] file` is (it had been read relative to the folder the run started
    /// in); `None` for a built-in robot.
    pub fn robot_file(&self) -> Option<std::path::PathBuf> {
        let dir = self.head.path.parent().unwrap_or(std::path::Path::new(""));
        let builtin = crate::robot::builtin::builtin(&self.robot).is_some();
        (!builtin).then(|| dir.join(&self.robot))
    }

    /// The nominal robot `robot` names: a built-in robot or its [`Self::robot_file`].
    pub fn load_robot(&self) -> Result<crate::robot::Robot> {
        match self.robot_file() {
            Some(f) => crate::robot::builtin::load(f),
            None => crate::robot::builtin::load(&self.robot),
        }
    }

    /// Parses and checks the scenario in `table`, read from `path` (named in errors): the
    /// keys of its `[instruments_study]` table are the study's
    /// ([`instruments_keys`]).
    pub fn from_table(table: toml::Table, path: &std::path::Path) -> Result<Self> {
        let ferr = |place: &str, msg: String| Error::file(path, place, msg);
        let whole = table.clone();
        let mut table = instruments_keys(table, path)?;
        // An entry's place: `measurement[i]`, or `measurement` for one `[measurement]` table.
        let (entries, single) = match table.remove("measurement") {
            Some(toml::Value::Array(a)) => (a, false),
            Some(t @ toml::Value::Table(_)) => (vec![t], true),
            _ => {
                return Err(ferr(
                    "measurement",
                    "must be a [measurement] table or [[measurement]] tables".into(),
                ))
            }
        };
        let entry = |i: usize| match single {
            true => "measurement".to_string(),
            false => format!("measurement[{i}]"),
        };
        // A refusal within entry `i`: at its key (`measurement[1].tracker_mm`), at its line.
        let in_entry = |i: usize, e: Error| match e {
            Error::Setting { key, msg } => {
                let key = key.strip_prefix("measurement.").unwrap_or(&key);
                ferr(&format!("{}.{key}", entry(i)), msg.to_string())
            }
            e => ferr(&entry(i), e.to_string()),
        };
        let mut measurement = Vec::with_capacity(entries.len());
        for (i, e) in entries.into_iter().enumerate() {
            let given = e.as_table().cloned().unwrap_or_default();
            let m: InstrumentSettings = e.try_into().map_err(|e: toml::de::Error| {
                let (msg, key) = crate::error::toml_value_error(&e);
                match key {
                    Some(k) => ferr(&format!("{}.{k}", entry(i)), msg),
                    None => ferr(&entry(i), msg),
                }
            })?;
            m.check_keys(&given).map_err(|e| in_entry(i, e))?;
            m.instrument().map_err(|e| in_entry(i, e))?;
            measurement.push(m);
        }
        let trials = (20, 2..=crate::study::scenario::MAX_TRIALS);
        let (head, mut s): (Head, InstrumentsScenario) =
            crate::study::whole::parse(table, path, trials, TAKES)?;
        s.measurement = measurement;
        s.head = head;
        s.head.table = whole;
        for (key, empty, what) in [
            ("measurement", s.measurement.is_empty(), "an instrument"),
            (
                "instruments_study.poses",
                s.poses.is_empty(),
                "a pose count",
            ),
            (
                "instruments_study.strategies",
                s.strategies.is_empty(),
                "a strategy",
            ),
        ] {
            if empty {
                return Err(ferr(key, format!("needs at least {what}")));
            }
        }
        let mut chosen = Vec::with_capacity(s.strategies.len());
        for (i, st) in s.strategies.iter().enumerate() {
            let one =
                strategy(st).map_err(|m| ferr(&format!("instruments_study.strategies[{i}]"), m))?;
            chosen.push((one, st));
        }
        // Each instrument, pose count and strategy is a row of the grid of cells: one given
        // twice (a strategy compared as parsed, whatever its spelling) would run a cell twice
        // under one name.
        let quoted = |(_, st): &(_, &String)| format!("\"{st}\"");
        let twice = [
            (
                "instruments_study.poses",
                crate::study::given_twice(&s.poses, PartialEq::eq, ToString::to_string, "cells"),
            ),
            (
                "instruments_study.strategies",
                crate::study::given_twice(&chosen, |a, b| a.0 == b.0, quoted, "cells"),
            ),
        ];
        if let Some((key, Some((j, msg)))) = twice.into_iter().find(|(_, m)| m.is_some()) {
            return Err(ferr(&format!("{key}[{j}]"), msg));
        }
        let same = |j: usize| (0..j).find(|&i| s.measurement[i] == s.measurement[j]);
        if let Some((i, j)) = (1..s.measurement.len()).find_map(|j| same(j).map(|i| (i, j))) {
            return Err(ferr(
                &entry(j),
                format!(
                    "the instrument of {} is given twice (every key the same): two cells \
                     would be one",
                    entry(i)
                ),
            ));
        }
        if s.poses.iter().any(|n| !(10..=s.candidates).contains(n)) {
            return Err(ferr(
                "instruments_study.poses",
                format!(
                    "each count must be between 10 and candidates = {}",
                    s.candidates
                ),
            ));
        }
        if s.validation == 0 {
            return Err(ferr(
                "instruments_study.validation",
                "must be at least 1".into(),
            ));
        }
        for (key, n) in [("candidates", s.candidates), ("validation", s.validation)] {
            if let Some(msg) = crate::study::scenario::pose_count_excess(n) {
                return Err(ferr(&format!("instruments_study.{key}"), msg));
            }
        }
        // `ErrorSettings::check` refuses settings only: each at its key.
        s.errors.check().map_err(|e| e.in_file(path))?;
        // A robot neither built in nor a file is refused at the scenario's `robot`.
        let robot = s.load_robot().map_err(|e| e.in_file(path))?;
        if let Some(msg) = crate::robot::loaded::unsimulated(&robot) {
            return Err(ferr("robot", msg));
        }
        s.check_readings(&robot)
            .map_err(|(key, msg)| ferr(&key, msg))?;
        Ok(s)
    }
}
