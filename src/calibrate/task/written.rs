//! What `calbench task` writes of an entry's model and entrant in `task.json` (docs/formats.md
//! § 9.3), checked when it is recorded: an edit the command cannot write would file the entry
//! in another division, or as chosen by a comparison that never ran.

use serde_json::Value;
use std::path::Path;

use super::{Division, TaskRecord};
use crate::error::{Error, Result};

/// What fixed an entry's candidate models: the task file's `[models]`, `--models`, neither,
/// or the `models` of Python's `calbench.task`.
const FIXED_BY: [&str; 4] = ["task", "command line", "default", "caller"];

impl TaskRecord {
    /// Refuses, naming `path` (this record's file, whose JSON is `raw`) and the key, what
    /// `calbench task` cannot write: an `entrant` neither `calbench` nor `python:NAME`; no
    /// `models`, or models that do not start with `kinematic`; a `division` other than the
    /// one the model and entrant give (`closed` for calbench's kinematic models, `open` for
    /// the rest); `candidates` given empty; a `chosen_by` `cv` without two candidates to
    /// compare, or `given` with several; a `candidates_fixed_by` of another name.
    pub fn check_written(&self, path: &Path, raw: &Value) -> Result<()> {
        let bad = |key: &str, msg: String| Err(Error::file(path, key, msg).at_json_key_line());
        let name = self.entrant.strip_prefix("python:");
        let named = name.is_some_and(|n| {
            !n.trim().is_empty() && crate::identify::registry::hidden_label(n).is_none()
        });
        if self.entrant != "calbench" && !named {
            return bad(
                "entrant",
                format!(
                    "is {:?}: an entry is calbench's (\"calbench\") or a Python method's \
                     (\"python:NAME\", its name)",
                    self.entrant
                ),
            );
        }
        if self.models.first().map(String::as_str) != Some("kinematic") {
            return bad(
                "models",
                format!(
                    "are {:?}: the terms of the model identified are `kinematic`, then each \
                     term added",
                    self.models
                ),
            );
        }
        let terms = self.terms();
        let kinematic = terms
            .parse::<crate::calibrate::cv::Model>()
            .is_ok_and(|m| m.is_kinematic());
        let closed = kinematic && self.entrant == "calbench";
        if closed != (self.division == Division::Closed) {
            let msg = match closed {
                false => format!(
                    "\"closed\" is for calbench's kinematic models (DH, β, tool, base); \
                     models `{terms}` of entrant `{}` are in the open division",
                    self.entrant
                ),
                true => format!(
                    "\"open\" is for a model beyond the kinematic one or an entrant not \
                     calbench's; models `{terms}` of entrant `calbench` are in the closed \
                     division"
                ),
            };
            return bad("division", msg);
        }
        let given_empty = raw
            .get("candidates")
            .and_then(Value::as_array)
            .is_some_and(Vec::is_empty);
        if given_empty {
            return bad(
                "candidates",
                "is empty: an entry names the candidate models it considered, one at least \
                 ([\"kinematic\"] by default)"
                    .into(),
            );
        }
        let n = self.candidates.len();
        // A file written before entries named their candidates has none to compare with.
        let compared = n > 1;
        if n > 0 && compared != (self.chosen_by == "cv") {
            let msg = match compared {
                false => format!(
                    "is \"cv\", but the entry considered {n} candidate model ({:?}): a model is \
                     chosen by cross-validation among two or more, else it is \"given\"",
                    self.candidates
                ),
                true => format!(
                    "is {:?}, but the entry compared {n} candidate models ({:?}): the model \
                     chosen among them is chosen by cross-validation, \"cv\"",
                    self.chosen_by, self.candidates
                ),
            };
            return bad("chosen_by", msg);
        }
        // The one model considered is the one identified.
        if let [one] = self.candidates.as_slice() {
            let model = |t: &str| t.parse::<crate::calibrate::cv::Model>().ok();
            if model(one).is_some_and(|m| model(&terms) != Some(m)) {
                return bad(
                    "models",
                    format!("are `{terms}`, but the one candidate model was `{one}` (candidates)"),
                );
            }
        }
        if let Some(by) = self
            .candidates_fixed_by
            .as_deref()
            .filter(|b| !FIXED_BY.contains(b))
        {
            return bad(
                "candidates_fixed_by",
                format!(
                    "is {by:?}: the candidates are fixed by \"task\" (the task file's \
                     [models]), \"command line\" (the command's models), \"default\" or \"caller\" \
                     (Python's models)"
                ),
            );
        }
        Ok(())
    }

    /// Refuses, naming `path` (this record's file) and `candidates_fixed_by`, candidates said to
    /// be fixed by what did not fix them, by the task file the entry ran (`task_path`, whose
    /// `[models]` candidates are `models`): `task` where the task file has no `[models]` or
    /// other candidates than the entry's, `default` where it has one (its candidates are then
    /// the task's) or where the entry considered other candidates than `kinematic`.
    pub(super) fn check_fixed_by(
        &self,
        path: &Path,
        (task_path, models): (&Path, Option<&[String]>),
    ) -> Result<()> {
        let given = self.candidates.as_slice();
        let why = match (self.candidates_fixed_by.as_deref(), models) {
            (Some("task"), None) => format!(
                "is \"task\", but the task file the entry ran ({}) has no [models]",
                task_path.display()
            ),
            (Some("task"), Some(m)) if !given.is_empty() && given != m => format!(
                "is \"task\", but the entry considered {given:?} (candidates) and the task \
                 file it ran ({}) names {m:?} in [models]",
                task_path.display()
            ),
            (Some("default"), Some(m)) => format!(
                "is \"default\", but the task file the entry ran ({}) names its candidates \
                 {m:?} in [models]: without the command's models they fix the candidates \
                 (\"task\")",
                task_path.display()
            ),
            (Some("default"), None) if !given.is_empty() && given != ["kinematic"] => format!(
                "is \"default\", but the entry considered {given:?} (candidates): the \
                 default candidate is [\"kinematic\"] alone"
            ),
            _ => return Ok(()),
        };
        Err(Error::file(path, "candidates_fixed_by", why).at_json_key_line())
    }
}
