//! The record of a study that runs whole (docs/formats.md § 7.11): a registration study's
//! or an instruments study's `summary.json` (it names its `kind`), one entry per cell, every
//! number of a cell one of its figures.

use std::path::Path;

use serde::Deserialize;
use serde_json::{Map, Value};

use super::folder::{scenario_as_run, Entry, Kind, Record};
use crate::analysis::figures::{check_figures, flatten, Reader};
use crate::error::{Error, Result};
use crate::study::registration_study;

/// The summary of a study that runs whole, by its `kind`; each cell kept whole for its
/// figures.
#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
enum Study {
    /// Ban fig. 3's registration study.
    RegistrationStudy,
    /// An instruments study.
    Instruments,
}

/// What every such summary holds.
#[derive(Deserialize)]
struct Whole {
    scenario: String,
    trials: usize,
    seed: u64,
    #[serde(flatten)]
    study: Study,
    cells: Vec<Map<String, Value>>,
}

/// What names a cell of an instruments study: the instrument, its poses and their strategy.
#[derive(Deserialize)]
struct InstrumentsCell {
    kind: String,
    poses: usize,
    strategy: String,
}

/// Whether the summary `v` is of a study that runs whole (a Monte-Carlo study's names no
/// `kind`).
pub(super) fn is_whole(v: &Value) -> bool {
    v.get("kind").is_some()
}

impl Record {
    /// The run folder `dir` of a registration or instruments study, whose `summary.json`
    /// (read from `path`) is `document`, parsed as `v`; its scenario as run found by
    /// [`scenario_as_run`] (`scenario`, a scenario file given). Each cell is an entry: a
    /// registration study's by its name (`16 × 0–1 mm`), of the methods `svd, wsvd`; an
    /// instruments study's `KIND / POSES poses / STRATEGY` (`#2`, … after a name already
    /// taken), of its instrument. The cell's settings are no figures.
    pub(super) fn of_whole(
        dir: &Path,
        (path, document): (&Path, String),
        v: Value,
        scenario: Option<&Path>,
    ) -> Result<Record> {
        let what = "summary.json of a registration or instruments study";
        let w: Whole = crate::error::read_typed(v, path, what)?;
        let run = (w.scenario.as_str(), Some(w.trials), Some(w.seed));
        let (text, named) = scenario_as_run(dir, run, scenario)?;
        super::folder::check_ran(path, (&w.scenario, Some(w.seed)), &named)?;
        let mut entries: Vec<Entry> = Vec::new();
        let mut figures = Vec::new();
        for (i, cell) in w.cells.iter().enumerate() {
            let at = |e: serde_json::Error| Error::file(path, format!("cells[{i}]"), e.to_string());
            let whole = Value::Object(cell.clone());
            let (mut name, method, settings): (String, String, &[&str]) = match w.study {
                Study::RegistrationStudy => {
                    let c: registration_study::Cell = serde_json::from_value(whole).map_err(at)?;
                    (
                        c.name(),
                        "svd, wsvd".into(),
                        &["outlier_count", "magnitude_mm"],
                    )
                }
                Study::Instruments => {
                    let c: InstrumentsCell = serde_json::from_value(whole).map_err(at)?;
                    let name = format!("{} / {} poses / {}", c.kind, c.poses, c.strategy);
                    (name, c.kind, &["poses", "noise_um", "scale_um_per_m"])
                }
            };
            let taken = |n: &str| entries.iter().any(|e| e.name == n);
            if taken(&name) {
                let k = (2..).find(|k| !taken(&format!("{name} #{k}"))).unwrap_or(2);
                name = format!("{name} #{k}");
            }
            let mut kept = cell.clone();
            kept.retain(|k, _| !settings.contains(&k.as_str()));
            flatten(&name, "", &kept, None, &mut figures);
            entries.push(Entry { name, method });
        }
        let at = |name: &str| {
            let i = entries.iter().position(|e| e.name == name)?;
            Some(format!("cells[{i}]"))
        };
        check_figures(path, Some(w.trials), &figures, Reader::Record, &at)?;
        let mut r = Record::new(Kind::Run, dir, document, w.scenario.clone(), text);
        r.output.seed = Some(w.seed);
        r.output.trials = Some(format!("0..{}", w.trials));
        (r.results.entries, r.results.figures) = (entries, figures);
        Ok(r)
    }
}
