//! What every task file gives, a tracker's task (§ 9.1) or a socket task (§ 9.4) alike
//! (docs/formats.md): its name, text and hash, title, nominal robot, the files it fixes, and
//! the data's authors' `[[published]]` figures or the `unpublished` note; and the reading of
//! a task file that both kinds share (its table, its keys, the files it names).

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

use super::canonical::task_hash;
use super::{Division, Metric, Published, TaskRecord, TASK_FORMAT};
use crate::error::{Error, Result};
use crate::numeric::Real;

/// What every task file gives.
#[derive(Clone, Debug)]
pub struct TaskHead {
    /// The task's name: its file's stem.
    pub name: String,
    /// The task file.
    pub path: PathBuf,
    /// Its text as read (an entry's folder carries it as `task.toml`).
    pub text: String,
    /// SHA-256 of its canonical text and of the bytes of every file it fixes
    /// (docs/formats.md § 9.3), hex.
    pub hash: String,
    /// What the task is.
    pub title: String,
    /// The nominal robot file (a robot file or a URDF).
    pub robot: PathBuf,
    /// Every file the task fixes, with its key in the task file (`robot`, `mapping`,
    /// `data.file`, `sockets.calibration[0]`, …), the robot first.
    pub fixed: Vec<(String, PathBuf)>,
    /// The data's authors' figures.
    pub published: Vec<Published>,
    /// Why there is no published figure.
    pub unpublished: Option<String>,
}

impl TaskHead {
    /// Every file the task reads: the task file, then each file it fixes (what an output
    /// folder must not destroy, [`crate::report::guard`]).
    pub fn inputs(&self) -> Vec<&Path> {
        let fixed = self.fixed.iter().map(|(_, p)| p.as_path());
        std::iter::once(self.path.as_path()).chain(fixed).collect()
    }

    /// `task.json` of an entry of `method` whose validation rows have the errors `errors`
    /// (mm), its figure and interval `metric` of them: calbench's entry of the kinematic
    /// model, given, in the closed division (an entry that differs says so over it).
    pub fn record(&self, metric: Metric, method: &str, errors: Vec<Real>) -> TaskRecord {
        let (value, ci95) = metric.of(&errors);
        let kinematic = || vec!["kinematic".to_string()];
        TaskRecord {
            format: TASK_FORMAT.into(),
            task: self.name.clone(),
            task_hash: self.hash.clone(),
            metric,
            value,
            ci95,
            division: Division::Closed,
            method: method.into(),
            models: kinematic(),
            chosen_by: "given".into(),
            candidates: kinematic(),
            candidates_fixed_by: Some("default".into()),
            cv_choice: None,
            entrant: "calbench".into(),
            calbench_version: Some(env!("CARGO_PKG_VERSION").into()),
            git_commit: super::record::git_commit(self.path.parent().unwrap_or(Path::new("."))),
            published: self.published.clone(),
            validation_errors_mm: errors,
            socket: None,
        }
    }

    /// The files an entry's folder holds beside the identify outputs: `task.json` (the
    /// entry's `json`) and the task file it ran, as read ([`super::TASK_FILE`]), as a run
    /// folder holds the scenario it ran.
    pub fn files(&self, json: &serde_json::Value) -> Result<[(&'static str, String); 2]> {
        let text = crate::error::json_text(json)?;
        Ok([("task.json", text), (super::TASK_FILE, self.text.clone())])
    }

    /// [`TaskHead::files`] of a tracker entry whose identification is `o`, with the kernel
    /// residual's `kernel.json` when the chosen model has one: what the command line and
    /// Python write beside the identify outputs.
    pub fn entry_files(
        &self,
        json: &serde_json::Value,
        o: &crate::calibrate::pipeline::TrackerOutcome,
    ) -> Result<Vec<(&'static str, String)>> {
        let mut files = self.files(json)?.to_vec();
        if let Some(k) = &o.kernel {
            files.push((crate::calibrate::kernel::KERNEL_FILE, k.to_json()?));
        }
        Ok(files)
    }

    /// The files it fixes as a refusal lists them: `KEY PATH` each.
    pub fn fixed_shown(&self) -> Vec<String> {
        let shown = |(k, p): &(String, PathBuf)| format!("{k} {}", p.display());
        self.fixed.iter().map(shown).collect()
    }
}

/// A task file being read: its path, text and table, and the folder its files are named
/// relative to.
pub(super) struct TaskFile<'a> {
    pub(super) path: &'a Path,
    pub(super) text: String,
    pub(super) table: toml::Table,
    dir: &'a Path,
}

impl<'a> TaskFile<'a> {
    /// The task file `path`, whose text is `text` and whose files are named from `dir`; its
    /// TOML refused naming the file and line.
    pub(super) fn new(text: String, path: &'a Path, dir: &'a Path) -> Result<TaskFile<'a>> {
        let table = crate::error::toml_keys(path, &text)?;
        Ok(TaskFile {
            path,
            text,
            table,
            dir,
        })
    }

    /// Its keys as `K` reads them (an unknown, missing or mistyped key refused naming the
    /// file, line and key path, `line 19, models.folds`).
    pub(super) fn keys<K: DeserializeOwned>(&self) -> Result<K> {
        crate::error::toml_keys(self.path, &self.text)
    }

    /// The refusal of the value of `key`, at its line.
    pub(super) fn bad(&self, key: &str, msg: String) -> Error {
        Error::toml_file(self.path, &self.text, key, key, msg)
    }

    /// The file `rel` that `key` names, relative to the task's folder; refused if it is not
    /// a file.
    pub(super) fn file(&self, key: &str, rel: &str) -> Result<PathBuf> {
        let p = self.dir.join(rel);
        // Why it is not, where the system says (a link that loops, a folder it may not read).
        match std::fs::metadata(&p) {
            Ok(m) if m.is_file() => Ok(p),
            Ok(_) => Err(self.bad(key, format!("{} is not a file", p.display()))),
            Err(e) => Err(self.bad(key, format!("{} is not a file ({e})", p.display()))),
        }
    }

    /// The head of the task: its name (the file's stem), the published figures checked
    /// ([`check_published`]) and the hash of its canonical text and of the files it fixes,
    /// the nominal `robot` and the `more` files.
    pub(super) fn head(
        self,
        title: String,
        robot: PathBuf,
        more: Vec<(String, PathBuf)>,
        (published, unpublished): (Vec<Published>, Option<String>),
    ) -> Result<TaskHead> {
        if title.trim().is_empty() {
            return Err(self.bad("title", "is blank: say what the task is".into()));
        }
        check_published(&published, &unpublished, &|k, m| self.bad(k, m))?;
        let mut fixed = vec![("robot".to_string(), robot.clone())];
        fixed.extend(more);
        let keyed = fixed
            .iter()
            .map(|(k, p)| (k.as_str(), p.as_path()))
            .collect();
        let hash = task_hash(&self.table, keyed)?;
        let name = self
            .path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("task");
        Ok(TaskHead {
            name: name.to_string(),
            path: self.path.to_path_buf(),
            text: self.text,
            hash,
            title,
            robot,
            fixed,
            published,
            unpublished,
        })
    }
}

/// Refuses a task without `[[published]]` figures and without the `unpublished` note, with
/// both, or with a figure that is not finite and ≥ 0 or lacks its label or source; `bad`
/// names the task file's key.
fn check_published(
    published: &[Published],
    unpublished: &Option<String>,
    bad: &dyn Fn(&str, String) -> Error,
) -> Result<()> {
    match (published.is_empty(), unpublished) {
        (true, None) => {
            return Err(bad(
                "published",
                "missing: the data's authors' figures ([[published]] label, value, \
                 source, division), or `unpublished` saying why there are none"
                    .into(),
            ))
        }
        (false, Some(_)) => {
            return Err(bad(
                "unpublished",
                "given with [[published]] figures: one or the other".into(),
            ))
        }
        _ => {}
    }
    for (i, p) in published.iter().enumerate() {
        if !(p.value.is_finite() && p.value >= 0.0) {
            let key = format!("published[{i}].value");
            return Err(bad(
                &key,
                format!("{}: a figure in mm, finite and ≥ 0", p.value),
            ));
        }
        for (field, text) in [("label", &p.label), ("source", &p.source)] {
            let key = format!("published[{i}].{field}");
            if text.trim().is_empty() {
                return Err(bad(
                    &key,
                    "is blank: a figure needs its label and its source".into(),
                ));
            }
            if text.chars().any(crate::error::is_hidden) {
                let msg = "must be text without control characters (bidirectional overrides \
                           included): the leaderboard shows it on the terminal and in its page";
                return Err(bad(&key, msg.into()));
            }
        }
        if let Some(k) = published[..i].iter().position(|q| q.label == p.label) {
            let key = format!("published[{i}].label");
            let msg = format!(
                "{:?} is the label of published[{k}] too: the leaderboard ranks each figure \
                 by its label",
                p.label
            );
            return Err(bad(&key, msg));
        }
    }
    if unpublished.as_ref().is_some_and(|u| u.trim().is_empty()) {
        return Err(bad(
            "unpublished",
            "is blank: say why the data's authors give no figure".into(),
        ));
    }
    Ok(())
}
