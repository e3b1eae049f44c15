//! The files a scenario reads besides itself — a Monte-Carlo study's robot file and pose
//! lists, at every sweep point, and an instruments study's robot file — each with the
//! SHA-256 of its bytes when the run started (docs/formats.md § 7.3 `inputs`). A shard's
//! `shard.json` and a checkpoint's `checkpoint.json` hold them, and the records' checksums
//! bind them ([`super::records`]): `merge` and `run --resume` read the scenario's files
//! again, and refuse one that is missing or has changed since, whose trials would be mixed
//! with the trials of the file as it is now.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::calibrate::task::sha256::sha256_hex;
use crate::error::{Error, Result};
use crate::study::kind::AnyScenario;
use crate::study::scenario::{PoseStrategy, RobotRef};

/// A file the scenario reads, as it was when the run started.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Input {
    /// The file as the run resolved it: against the scenario file's folder, as the scenario
    /// file was named (relative to the folder the run started in, when it was given so).
    pub path: PathBuf,
    /// The lowercase hex SHA-256 of its bytes.
    pub sha256: String,
}

/// The files `sc` reads, each once in the order first read: none for a built-in robot and
/// generated poses, and none for a registration study, which reads no file.
pub fn files(sc: &AnyScenario) -> Result<Vec<PathBuf>> {
    let s = match sc {
        AnyScenario::MonteCarlo(s) => s,
        AnyScenario::Instruments(s) => return Ok(s.robot_file().into_iter().collect()),
        AnyScenario::Registration(_) => return Ok(Vec::new()),
    };
    let mut files: Vec<PathBuf> = Vec::new();
    for (_, plan) in s.sweep_plans()? {
        let poses = plan.calibration.strategies.iter().filter_map(|p| match p {
            PoseStrategy::File(f) => Some(f),
            _ => None,
        });
        let robot = match &plan.robot {
            RobotRef::File(f) => Some(f),
            RobotRef::Builtin(_) => None,
        };
        for f in robot.into_iter().chain(poses) {
            if !files.contains(f) {
                files.push(f.clone());
            }
        }
    }
    Ok(files)
}

/// The files `sc` reads, with their hashes now.
pub fn of(sc: &AnyScenario) -> Result<Vec<Input>> {
    files(sc)?
        .into_iter()
        .map(|path| {
            let sha256 = hash(&path).map_err(|e| Error::io(&path, e))?;
            Ok(Input { path, sha256 })
        })
        .collect()
}

/// The lowercase hex SHA-256 of the bytes of the file `path`.
fn hash(path: &Path) -> std::io::Result<String> {
    std::fs::read(path).map(|bytes| sha256_hex(&bytes))
}

/// Refuses, naming the key `inputs[k]` of `holder` (a `shard.json` or a `checkpoint.json`),
/// a file recorded there that cannot be read from here or whose bytes have changed since the
/// run started. Checked before the scenario as run is read, which reads them again.
pub fn unchanged(holder: &Path, recorded: &[Input]) -> Result<()> {
    for (k, was) in recorded.iter().enumerate() {
        let refuse = |msg: String| Err(Error::file(holder, format!("inputs[{k}]"), msg));
        let now = match hash(&was.path) {
            Ok(h) => h,
            Err(e) => {
                let hint = if was.path.is_relative() {
                    "; the path is relative to the folder the run started in: run this command \
                     from that folder"
                } else {
                    ""
                };
                return refuse(format!(
                    "{} cannot be read ({e}): the run read it{hint}",
                    was.path.display()
                ));
            }
        };
        if now != was.sha256 {
            return refuse(format!(
                "{} has changed since the run started (SHA-256 {} then, {now} now): its trials \
                 are not those of the file as it is; restore the file, or run again",
                was.path.display(),
                was.sha256
            ));
        }
    }
    Ok(())
}

/// Refuses, naming the key `inputs` of `holder`, a list of files that is not `now`, the
/// [`files`] the scenario as run reads (the file was altered).
pub fn as_run(holder: &Path, recorded: &[Input], now: &[PathBuf]) -> Result<()> {
    if recorded.iter().map(|i| &i.path).eq(now.iter()) {
        return Ok(());
    }
    let list = |p: Vec<&PathBuf>| {
        let names: Vec<String> = p.iter().map(|p| p.display().to_string()).collect();
        format!("[{}]", names.join(", "))
    };
    Err(Error::file(
        holder,
        "inputs",
        format!(
            "lists {} but the scenario as run reads {} (the file was altered)",
            list(recorded.iter().map(|i| &i.path).collect()),
            list(now.iter().collect())
        ),
    ))
}
