//! Which reader a recorded folder takes, by the document it holds: `task.json` (a task
//! entry), `summary.json` of a Monte-Carlo study ([`Record::of_run_text`]) or of a study that
//! runs whole ([`Record::of_whole`]), or `identified.json` (an identification).

use std::path::Path;

use super::folder::{read, scenario_as_run, Kind, RanSummary, Record};
use super::whole::is_whole;
use crate::analysis::regression::a_shard;
use crate::error::{Error, Result};

impl Record {
    /// Reads the folder `dir`: a task folder (`task.json`, its files found beside `task`, the
    /// task file it ran, else `tasks/<task>.toml` under the current folder), a run or merge
    /// folder (`summary.json`, of a Monte-Carlo study or of one that runs whole, whose
    /// scenario is the folder's `scenario.toml`, else the file given, else
    /// `scenarios/<name>.toml`) or an identify folder (`identified.json`).
    pub fn of_folder(dir: &Path, scenario: Option<&Path>, task: Option<&Path>) -> Result<Record> {
        if dir.join("task.json").is_file() {
            return Record::of_task(dir, task);
        }
        if dir.join("summary.json").is_file() {
            let path = dir.join("summary.json");
            let (document, v) = read(&path)?;
            if is_whole(&v) {
                return Record::of_whole(dir, (&path, document), v, scenario);
            }
            let ran = RanSummary::check(&path, document, v)?;
            let s = &ran.summary;
            let (text, named) = scenario_as_run(dir, (&s.scenario, s.trials, s.seed), scenario)?;
            let (name, seed, trials) = named;
            return Record::of_run_text(dir, (&name, seed, trials), text, Kind::Run, ran);
        }
        if dir.join("identified.json").is_file() {
            return Record::of_identify(dir);
        }
        // The document given in place of its folder (`record run/summary.json`).
        if dir.is_file() {
            let parent = dir.parent().filter(|p| !p.as_os_str().is_empty());
            let folder = parent.map_or(".".into(), |p| p.display().to_string());
            return Err(Error::file(
                dir,
                "folder",
                format!(
                    "is a file: record takes the folder that holds summary.json, \
                     identified.json or task.json (here {folder})"
                ),
            ));
        }
        if let Some(e) = a_shard(dir, "record the merged folder") {
            return Err(e);
        }
        Err(Error::file(
            dir,
            "folder",
            "holds none of summary.json (run, merge), identified.json (identify) and \
             task.json (task); nothing to record",
        ))
    }
}
