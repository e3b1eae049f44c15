//! `task.json` (docs/formats.md § 9.3), typed: what `calbench task` writes for an entry and
//! `record` reads back. Written through a JSON tree, so its keys are in byte order whatever
//! the order of the fields here.

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::{Division, Metric, Published, TASK_FORMAT};
use crate::calibrate::cv::RepeatedChoice;
use crate::error::{Error, Result};
use crate::numeric::nan;
use crate::numeric::Real;

/// An entry's `task.json`. A key an older file lacks takes its default (none, an empty list);
/// a key every file has had (`chosen_by`, `entrant`) is required, and a key this calbench
/// does not know is refused, naming it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskRecord {
    /// [`TASK_FORMAT`]; a file of another format is refused.
    pub format: String,
    /// The task's name.
    pub task: String,
    /// The task's hash (docs/formats.md § 9.1).
    pub task_hash: String,
    /// The task's metric.
    pub metric: Metric,
    /// The entry's figure (mm; `null` when not finite).
    #[serde(deserialize_with = "nan::real")]
    pub value: Real,
    /// Its 95 % interval.
    pub ci95: Option<[Real; 2]>,
    /// The division.
    pub division: Division,
    /// The method.
    pub method: String,
    /// The model terms identified.
    #[serde(default)]
    pub models: Vec<String>,
    /// `cv` (chosen among several candidates) or `given`.
    pub chosen_by: String,
    /// The candidate models considered.
    #[serde(default)]
    pub candidates: Vec<String>,
    /// What fixed them: `task`, `command line`, `default` or `caller`.
    pub candidates_fixed_by: Option<String>,
    /// The repeated K-fold choice among the candidates.
    pub cv_choice: Option<RepeatedChoice>,
    /// Who ran it: `calbench` or `python:NAME`.
    pub entrant: String,
    /// The calbench version that ran it.
    pub calbench_version: Option<String>,
    /// The commit it ran at.
    pub git_commit: Option<String>,
    /// The data's authors' figures, from the task file.
    #[serde(default)]
    pub published: Vec<Published>,
    /// The position error of each validation row, in the task's order (mm): what the figure
    /// and its interval are computed from ([`TaskRecord::recomputed`]); empty in a file
    /// written before calbench recorded them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub validation_errors_mm: Vec<Real>,
    /// A socket task's figures of every model on both placements (docs/formats.md § 9.4);
    /// absent for a tracker's task.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub socket: Option<SocketScores>,
}

/// The authors' figures of a model on one placement (docs/formats.md § 9.4, [`super::socket`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SocketFigures {
    /// Per socket, the RMS distance of its tool points from their mean (mm): the square
    /// root of the sum of the per-axis variances.
    pub spread_per_socket_mm: Vec<Real>,
    /// Every socket's tool points pooled: the RMS distance of each from its socket's mean
    /// (mm), the authors' `std_dev_fk`.
    pub spread_mm: Real,
    /// The error of the distance between the sockets' mean points against the known one
    /// (mm; the RMS over sockets 2, 3, … of each one's distance from socket 1).
    pub distance_error_mm: Real,
}

/// A model's figures on the calibration and the validation placement.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Placements {
    /// On the calibration placement.
    pub calibration: SocketFigures,
    /// On the validation placement.
    pub validation: SocketFigures,
}

/// `task.json`'s `socket`: every model scored on both placements, and the authors' own
/// figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SocketScores {
    /// The placements' folder names, calibration then validation.
    pub placements: [String; 2],
    /// calbench's identified robot.
    pub calbench: Placements,
    /// The nominal robot.
    pub nominal: Placements,
    /// The authors' calibrated model, scored by calbench.
    pub authors_model: Option<Placements>,
    /// The authors' own figures on the calibration placement, from their `kpis.yaml`.
    pub authors_kpis: Option<SocketFigures>,
}

/// The name of the task file as an entry's folder carries it.
pub const TASK_FILE: &str = "task.toml";

/// The files a tracker task's entry folder holds (docs/formats.md § 9), which its output guard
/// keeps an input from being written over, for the command line and Python alike.
pub const OUTPUTS: [&str; 7] = [
    crate::calibrate::kernel::KERNEL_FILE,
    "identified.json",
    "residuals.csv",
    "robot.toml",
    "report.md",
    "task.json",
    TASK_FILE,
];

/// The files a socket task's entry folder holds (docs/formats.md § 9.4).
pub const SOCKET_OUTPUTS: [&str; 4] = ["identified.json", "robot.toml", "task.json", TASK_FILE];

/// The `[[published]]` rows of the task file `text` (read from `path`).
fn published_of(text: &str, path: &Path) -> Result<Vec<Published>> {
    #[derive(Deserialize)]
    struct Rows {
        #[serde(default)]
        published: Vec<Published>,
    }
    let rows: Rows = toml::from_str(text)
        .map_err(|e| Error::file(path, "published", e.message().trim_end().to_string()))?;
    Ok(rows.published)
}

/// The 1-based line of `task.json`'s text where the `i`-th published row starts (its
/// `{` after the `published` key), for a message.
fn published_line(json: &str, i: usize) -> Option<usize> {
    let start = json.find("\"published\"")?;
    let mut depth = 0usize;
    let mut row = 0usize;
    for (k, c) in json[start..].char_indices() {
        match c {
            '{' if depth == 1 => {
                if row == i {
                    return Some(json[..start + k].matches('\n').count() + 1);
                }
                row += 1;
                depth += 1;
            }
            '[' | '{' => depth += 1,
            ']' | '}' => {
                depth = depth.saturating_sub(1);
                if depth == 0 {
                    return None;
                }
            }
            _ => {}
        }
    }
    None
}

impl TaskRecord {
    /// Refuses, naming `json_path` and the line and key of the row, a published row of this
    /// record (whose text is `json`) that is not a `[[published]]` row of the task file the
    /// folder carries (`task_text`, read from `task_path`), and a `[[published]]` row of that
    /// file the record lacks: the data's authors' figures are the task file's, all of them.
    pub fn check_published(
        &self,
        (json, json_path): (&str, &Path),
        (task_text, task_path): (&str, &Path),
    ) -> Result<()> {
        let rows = published_of(task_text, task_path)?;
        for (i, p) in self.published.iter().enumerate() {
            if !rows.contains(p) {
                let place = match published_line(json, i) {
                    Some(l) => format!("line {l}, published[{i}]"),
                    None => format!("published[{i}]"),
                };
                return Err(Error::file(
                    json_path,
                    place,
                    format!(
                        "\"{}\" ({} mm, {}) is not a [[published]] row of {}, the task file \
                         this entry ran: published figures come from the task file only",
                        p.label,
                        p.value,
                        p.source,
                        task_path.display()
                    ),
                ));
            }
        }
        if let Some(p) = rows.iter().find(|p| !self.published.contains(p)) {
            return Err(Error::file(
                json_path,
                "published",
                format!(
                    "lacks \"{}\" ({} mm, {}), a [[published]] row of {}, the task file this \
                     entry ran: every published figure of the task file is kept beside the entry",
                    p.label,
                    p.value,
                    p.source,
                    task_path.display()
                ),
            ));
        }
        Ok(())
    }
}

/// A figure with its 95 % interval.
pub type Figure = (Real, Option<[Real; 2]>);

/// Whether two figures and their intervals are the same bit for bit (a NaN equals a NaN).
pub fn same_figure((a, a_ci): Figure, (b, b_ci): Figure) -> bool {
    let same = |a: Real, b: Real| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
    same(a, b)
        && match (a_ci, b_ci) {
            (Some(a), Some(b)) => same(a[0], b[0]) && same(a[1], b[1]),
            (a, b) => a.is_none() && b.is_none(),
        }
}

/// A figure and its interval as a refusal shows them.
pub fn shown((value, ci): Figure) -> String {
    let ci = ci.map_or("(no interval)".into(), |[lo, hi]| format!("({lo} – {hi})"));
    format!("{value} {ci}")
}

impl TaskRecord {
    /// The figure and its interval computed again from the recorded per-row errors by the
    /// task's metric; `None` when the record holds no per-row errors. A negative error (a
    /// row's error is a distance) is refused, naming `path` (this record's file) and the row.
    pub fn recomputed(&self, path: &Path) -> Result<Option<Figure>> {
        let errors = &self.validation_errors_mm;
        if let Some(i) = errors.iter().position(|e| *e < 0.0) {
            return Err(Error::file(
                path,
                format!("validation_errors_mm[{i}]"),
                format!(
                    "is {}: a validation row's error is a distance (mm), ≥ 0",
                    errors[i]
                ),
            ));
        }
        Ok((!errors.is_empty()).then(|| self.metric.of(errors)))
    }

    /// Refuses, naming `path` (this record's file) and `value`, a figure and interval that
    /// are not, bit for bit, what the recorded per-row errors give ([`TaskRecord::recomputed`]):
    /// an edited figure. A record without per-row errors passes.
    pub fn check_figure(&self, path: &Path) -> Result<()> {
        let Some(again) = self.recomputed(path)? else {
            return Ok(());
        };
        let stated = (self.value, self.ci95);
        if same_figure(stated, again) {
            return Ok(());
        }
        Err(Error::file(
            path,
            "value",
            format!(
                "states the figure {}, but its {} validation errors \
                 (validation_errors_mm) give {} by {}: the figure was edited",
                shown(stated),
                self.validation_errors_mm.len(),
                shown(again),
                self.metric.as_str()
            ),
        ))
    }

    /// Refuses, naming `path` (this record's file) and `value`, a tracker task's figure that
    /// is not, bit for bit, the validation figure (`after`, its `mean` or `rms` by the
    /// metric) of the identification written beside it (`file`): a figure edited with its
    /// per-row errors removed, which [`TaskRecord::check_figure`] cannot recompute.
    pub fn check_identified_figure(
        &self,
        path: &Path,
        file: &Path,
        after: Option<crate::calibrate::ErrorStats>,
    ) -> Result<()> {
        let Some(after) = after else {
            return Ok(());
        };
        let (there, key) = match self.metric {
            Metric::ValidationMeanMm => (after.mean, "mean"),
            Metric::ValidationRmsMm => (after.rms, "rms"),
            Metric::SocketSpreadMm => return Ok(()),
        };
        if same_figure((self.value, None), (there, None)) {
            return Ok(());
        }
        let msg = format!(
            "states the figure {}, but {} beside it gives the validation {key} {}: the figure \
             was edited",
            shown((self.value, self.ci95)),
            file.display(),
            there
        );
        Err(Error::file(path, "value", msg))
    }

    /// Refuses, naming `path` (this record's file) and the key, a record that is not of the
    /// task file it ran (`task_text`, read from `task_path`), copied from the task file
    /// `file`: its `task` not `file`'s name (its stem), its hash not that of the task with
    /// the files it fixes read beside `file` as they are now (the task, its data, split,
    /// mapping or robot changed since the entry ran), or its `metric` not the task's.
    pub fn check_ran(
        &self,
        path: &Path,
        (task_text, task_path): (&str, &Path),
        file: &Path,
    ) -> Result<()> {
        let stem = file.file_stem().map(|s| s.to_string_lossy());
        if stem.as_deref() != Some(self.task.as_str()) {
            let msg = format!(
                "is \"{}\", but the task file given is {}: an entry is recorded under the \
                 task it ran",
                self.task,
                file.display()
            );
            return Err(Error::file(path, "task", msg));
        }
        let dir = file.parent().unwrap_or(Path::new("."));
        let (head, metric, models) = super::head_of(task_text, task_path, dir)?;
        let (fixed, hash) = (head.fixed_shown(), head.hash);
        if hash == self.task_hash {
            // The hash binds the task file, and with it the metric the entry must have.
            if metric != self.metric {
                let msg = format!(
                    "is {}, but the task file the entry ran ({}) ranks by {}",
                    self.metric.as_str(),
                    task_path.display(),
                    metric.as_str()
                );
                return Err(Error::file(path, "metric", msg));
            }
            self.check_fixed_by(path, (task_path, models.as_deref()))?;
            return self.check_named(path, (task_text, task_path), file);
        }
        Err(Error::file(
            path,
            "task_hash",
            format!(
                "is {}, but the task file the entry ran ({}) with the files it fixes as they \
                 are now ({}) has the hash {}: the task file or one of its files changed \
                 since the entry ran; run the entry again",
                self.task_hash,
                task_path.display(),
                fixed.join(", "),
                hash
            ),
        ))
    }

    /// Refuses, naming `path` (this record's file) and `task`, a record whose task file by
    /// name (`file`) is not the task file it ran (`task_text`, read from `task_path`), value for
    /// value: the hash the entry states is that of the file it carries, so an entry filed under
    /// another task's name would be ranked on a board of a task it did not run.
    fn check_named(
        &self,
        path: &Path,
        (task_text, task_path): (&str, &Path),
        file: &Path,
    ) -> Result<()> {
        let canonical = |text: &str, p: &Path| -> Result<String> {
            let table: toml::Table = crate::error::toml_keys(p, text)?;
            Ok(super::canonical::canonical_text(&toml::Value::Table(table)))
        };
        let named = crate::error::read_text(file)?;
        if canonical(&named, file)? == canonical(task_text, task_path)? {
            return Ok(());
        }
        Err(Error::file(
            path,
            "task",
            format!(
                "is \"{}\", but the task file of that name, {}, is not the task file the entry \
                 ran ({}, which with the files it fixes has the task_hash the entry states): the \
                 entry ran another task, or the task file changed since it ran; an entry is \
                 recorded only under the task it ran",
                self.task,
                file.display(),
                task_path.display()
            ),
        ))
    }

    /// The file's JSON tree (keys in byte order).
    pub fn to_value(&self) -> Value {
        serde_json::to_value(self).unwrap_or(Value::Null)
    }

    /// Reads the `task.json` value `v` of the file `path`, refusing, naming the file and the
    /// key, a key of the wrong type, a missing or unknown one, and another format.
    pub fn from_value(v: Value, path: &Path) -> Result<TaskRecord> {
        if let Some(f) = v.get("format").filter(|f| f.as_str() != Some(TASK_FORMAT)) {
            // `calbench-task-N`: a later N is a later calbench's; anything else none of its.
            let n = f.as_str().and_then(|f| f.strip_prefix("calbench-task-"));
            match n.and_then(|n| n.parse::<u32>().ok()).filter(|&n| n > 1) {
                Some(n) => crate::error::newer_format(path, "task.json", n, 1)?,
                None => {
                    return Err(Error::file(
                        path,
                        "format",
                        format!("not a calbench task.json: {f}"),
                    ))
                }
            }
        }
        crate::error::read_typed(v, path, "task.json")
    }
}

impl TaskRecord {
    /// The model's terms joined by `+` (`kinematic+harmonics`); `kinematic` for a record
    /// that names none.
    pub fn terms(&self) -> String {
        match self.models.is_empty() {
            true => "kinematic".to_string(),
            false => self.models.join("+"),
        }
    }

    /// Refuses, naming `path` (this record's file) and the key, a record whose model is not
    /// the one its choice gives: `chosen_by` neither `cv` nor `given`; a `cv_choice` whose
    /// chosen candidate (`best`) is not `models`, whose candidates are not `candidates`, or
    /// beside `chosen_by` `given`; and, by the `identified.json` written beside it
    /// (`identified`, its path and document), another `method`, or a model chosen by
    /// cross-validation (`cv_best`) that is not `models` or beside `given`. An entry that
    /// states a kinematic model it did not identify would rank in the closed division.
    pub fn check_choice(&self, path: &Path, identified: Option<(&Path, &Value)>) -> Result<()> {
        use crate::calibrate::cv::Model;
        let bad = |key: &str, msg: String| Err(Error::file(path, key, msg));
        let cv = match self.chosen_by.as_str() {
            "cv" => true,
            "given" => false,
            other => {
                return bad(
                    "chosen_by",
                    format!("is \"{other}\": it is \"cv\" or \"given\""),
                )
            }
        };
        let terms = self.terms();
        // An entrant's own terms need not be calbench's: only calbench's are compared.
        let Ok(stated) = terms.parse::<Model>() else {
            return Ok(());
        };
        let differs = |chosen: &str| chosen.parse::<Model>() != Ok(stated);
        if let Some(c) = &self.cv_choice {
            let Some(best) = c.models.get(c.best) else {
                let n = c.models.len();
                return bad(
                    "cv_choice.best",
                    format!("is {}, of {n} candidates", c.best),
                );
            };
            if !cv {
                return bad("chosen_by", "is \"given\", beside a cv_choice".into());
            }
            if let Some((key, why)) = c.inconsistency() {
                return bad(
                    &format!("cv_choice.{key}"),
                    format!("{why}: the choice was edited"),
                );
            }
            if differs(&best.model) {
                let msg = format!(
                    "are `{terms}`, but cv_choice chose `{}` (candidate {})",
                    best.model, c.best
                );
                return bad("models", msg);
            }
            let names: Vec<&str> = c.models.iter().map(|m| m.model.as_str()).collect();
            if !self.candidates.is_empty() && self.candidates != names {
                let msg = format!(
                    "are {:?}, but cv_choice compared {names:?}",
                    self.candidates
                );
                return bad("candidates", msg);
            }
        }
        let Some((file, doc)) = identified else {
            return Ok(());
        };
        // A Python entrant's method is `external` in its identification, and only its.
        let external = crate::identify::external::EXTERNAL;
        let python = self.entrant.starts_with("python:");
        match doc.get("method").and_then(Value::as_str) {
            Some(m) if python != (m == external) => {
                let msg = match python {
                    true => format!(
                        "is \"{}\", a Python method's entry, but {} beside it was identified \
                         by calbench's method \"{m}\" (a Python method's identification is \
                         \"{external}\")",
                        self.entrant,
                        file.display()
                    ),
                    false => format!(
                        "is \"{}\", but {} beside it was identified by a method supplied from \
                         outside (\"{external}\"): a Python method's entry is \"python:NAME\"",
                        self.entrant,
                        file.display()
                    ),
                };
                return bad("entrant", msg);
            }
            Some(m) if !python && m != self.method => {
                let msg = format!(
                    "is \"{}\", but {} beside it was identified by \"{m}\"",
                    self.method,
                    file.display()
                );
                return bad("method", msg);
            }
            _ => {}
        }
        // A cross-validation of one candidate (`--models beta`) chose nothing: its model was
        // given.
        let compared = doc
            .get("cv_models")
            .and_then(Value::as_array)
            .map_or(0, Vec::len);
        match doc.get("cv_best").and_then(Value::as_str) {
            Some(_) if !cv && compared >= 2 => {
                let msg = format!(
                    "is \"given\", but {} beside it chose its model among {compared} by \
                     cross-validation (cv_best)",
                    file.display()
                );
                bad("chosen_by", msg)
            }
            Some(chosen) if differs(chosen) => {
                let msg = format!(
                    "are `{terms}`, but {} beside it identified `{chosen}` (cv_best)",
                    file.display()
                );
                bad("models", msg)
            }
            _ => Ok(()),
        }
    }
}

/// The commit checked out in the repository holding `dir` (`git rev-parse HEAD`), if any.
pub(super) fn git_commit(dir: &Path) -> Option<String> {
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let o = std::process::Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(["rev-parse", "HEAD"])
        .output()
        .ok()?;
    let s = String::from_utf8(o.stdout).ok()?.trim().to_string();
    (o.status.success() && s.len() == 40).then_some(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn written() -> Value {
        serde_json::json!({
            "format": TASK_FORMAT, "task": "barrett-wam", "task_hash": "0f3c",
            "metric": "validation_mean_mm", "value": 3.1, "ci95": [2.9, 3.3],
            "division": "closed", "method": "lm", "models": ["kinematic"], "chosen_by": "given",
            "entrant": "calbench", "published": [{"label": "MDH", "value": 2.9,
                "source": "Jacobi 2025", "division": "open"}]
        })
    }

    #[test]
    fn a_task_record_reads_back_as_written() {
        let r = TaskRecord::from_value(written(), Path::new("t/task.json")).unwrap();
        assert_eq!(r.division, Division::Closed);
        assert_eq!(r.published[0].value, 2.9);
        let again = TaskRecord::from_value(r.to_value(), Path::new("t/task.json")).unwrap();
        assert_eq!(again, r);
    }

    /// An entry whose `models` are not what its choice chose would rank as another model
    /// (a kinematic one, in the closed division).
    #[test]
    fn a_model_that_is_not_the_one_its_choice_gives_is_refused() {
        let path = Path::new("t/task.json");
        let mut v = written();
        v["chosen_by"] = "cv".into();
        v["candidates"] = serde_json::json!(["kinematic", "harmonics"]);
        let cv = |model: &str, mean: f64, wins: usize| {
            serde_json::json!({"model": model, "parameters": 29, "rms": [mean], "mean": mean,
                "wins": wins})
        };
        v["cv_choice"] = serde_json::json!({"folds": 5, "fold_seeds": [0], "best": 1,
            "stability": 1.0, "models": [cv("kinematic", 2.3, 0), cv("harmonics", 2.1, 1)]});
        let refused = |v: &Value, identified: Option<&Value>, want: &str| {
            let r = TaskRecord::from_value(v.clone(), path).unwrap();
            let beside = identified.map(|d| (Path::new("t/identified.json"), d));
            let e = r.check_choice(path, beside).unwrap_err().to_string();
            assert!(
                e.starts_with("t/task.json: ") && e.contains(want),
                "{want}: {e}"
            );
        };
        refused(
            &v,
            None,
            "models: are `kinematic`, but cv_choice chose `harmonics`",
        );
        v["models"] = serde_json::json!(["kinematic", "harmonics"]);
        let r = TaskRecord::from_value(v.clone(), path).unwrap();
        let same = serde_json::json!({"method": "lm", "cv_best": "harmonics",
            "cv_models": [{"model": "kinematic"}, {"model": "harmonics"}]});
        let beside = Some((Path::new("t/identified.json"), &same));
        r.check_choice(path, beside).unwrap();
        let mut w = v.clone();
        w["candidates"] = serde_json::json!(["kinematic", "gravity"]);
        refused(&w, None, "candidates: are");
        let mut w = v.clone();
        w["chosen_by"] = "given".into();
        refused(&w, None, "chosen_by: is \"given\", beside a cv_choice");
        w["chosen_by"] = "guess".into();
        refused(&w, None, "chosen_by: is \"guess\"");
        let mut w = v.clone();
        w["cv_choice"]["best"] = 2.into();
        refused(&w, None, "cv_choice.best: is 2, of 2 candidates");
        // By the identified.json beside it: another method, another model chosen.
        let other = serde_json::json!({"method": "ls", "cv_best": "harmonics"});
        refused(&v, Some(&other), "method: is \"lm\", but t/identified.json");
        let other = serde_json::json!({"method": "lm", "cv_best": "gravity"});
        w = v.clone();
        w["cv_choice"] = Value::Null;
        refused(&w, Some(&other), "identified `gravity` (cv_best)");
        let mut g = written();
        g["chosen_by"] = "given".into();
        refused(
            &g,
            Some(&same),
            "chosen_by: is \"given\", but t/identified.json beside it chose its model among 2",
        );
        // A Python entrant's identification names its method `external`.
        g["entrant"] = "python:mine".into();
        g["method"] = "mine".into();
        let r = TaskRecord::from_value(g, path).unwrap();
        let external = serde_json::json!({"method": "external"});
        r.check_choice(path, Some((Path::new("t/identified.json"), &external)))
            .unwrap();
    }

    #[test]
    fn a_malformed_or_renamed_key_and_another_format_are_refused_naming_file_and_key() {
        let refused = |v: Value, key: &str| {
            let e = TaskRecord::from_value(v, Path::new("t/task.json"))
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("t/task.json: ") && e.contains(key),
                "{key}: {e}"
            );
        };
        let mut v = written();
        v["value"] = "three".into();
        refused(v, "value");
        let mut v = written();
        let m = v.as_object_mut().unwrap();
        let d = m.remove("division").unwrap();
        m.insert("divison".into(), d);
        refused(v, "divison");
        let mut v = written();
        v["published"][0]["value"] = "x".into();
        refused(v, "published[0].value");
        let mut v = written();
        v["format"] = "calbench-task-2".into();
        refused(v, "format");
        for key in ["chosen_by", "entrant"] {
            let mut v = written();
            v.as_object_mut().unwrap().remove(key);
            refused(v, key);
        }
    }
}
