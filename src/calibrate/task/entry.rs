//! What an entry of a task compares and on which rows: the candidate models (the command
//! line's, or the task's own `[models]`, chosen by repeated K-fold cross-validation on the
//! calibration rows alone); the check that no validation row repeats a calibration row is
//! [`Measurements::shared_rows`] (docs/formats.md § 9.1).

use super::Task;
use crate::calibrate::cv::{choose_model_repeated, Model, RepeatedChoice};
use crate::calibrate::request::IdentifyRequest;
use crate::error::{Error, Result};
use crate::identify::MethodSpec;
use crate::measurement::Measurements;

/// The candidate models of an entry, where they come from, and the repeated choice among
/// them when the task fixes them.
pub struct EntryModels {
    /// The candidates considered.
    pub candidates: Vec<Model>,
    /// `task` (the task file's `[models]`), `command line` or `default` (`kinematic`); the
    /// Python entry names the candidates it is given `caller`.
    pub fixed_by: &'static str,
    /// The repeated K-fold choice among the task's candidates, when there are several.
    pub choice: Option<RepeatedChoice>,
}

impl Task {
    /// The request of an entry whose candidate models are `given` (the command line's), or
    /// when none are given the task's own (`[models]`): several of the task's are compared
    /// by repeated K-fold cross-validation on the calibration rows alone
    /// ([`choose_model_repeated`]) and the chosen one is identified; else `kinematic`.
    pub fn entry_request(
        &self,
        method: MethodSpec,
        given: &[Model],
    ) -> Result<(IdentifyRequest, Measurements, EntryModels)> {
        let robot = self.load_robot()?;
        let (cal, val, lines) = self.measurements(&robot)?;
        // The task's folds are checked against its calibration rows whether they are used or
        // not: a bad value in the task file is refused, as it enters `task_hash`.
        if let Some(tm) = self.models.as_ref().filter(|tm| tm.folds > cal.len()) {
            let h = &self.head;
            return Err(Error::toml_file(
                &h.path,
                &h.text,
                "models.folds",
                "models.folds",
                format!(
                    "{} folds but only {} calibration rows: at most one fold per row",
                    tm.folds,
                    cal.len()
                ),
            ));
        }
        if !given.is_empty() {
            let (q, val) = self.request((robot, cal, val, lines), method, given)?;
            let m = EntryModels {
                candidates: given.to_vec(),
                fixed_by: "command line",
                choice: None,
            };
            return Ok((q, val, m));
        }
        let Some(tm) = &self.models else {
            let (q, val) = self.request((robot, cal, val, lines), method, &[Model::KINEMATIC])?;
            let m = EntryModels {
                candidates: vec![Model::KINEMATIC],
                fixed_by: "default",
                choice: None,
            };
            return Ok((q, val, m));
        };
        // A candidate the robot cannot take (`h1q9` on six joints, `compliance` without link
        // masses) is the task file's, refused at its key, not the command line's.
        for (i, c) in tm.candidates.iter().enumerate() {
            let registration = crate::calibrate::Registration::Identify;
            if let Err(Error::Option { msg, .. }) =
                c.robot_and_params(&robot, &cal, registration, &[])
            {
                let h = &self.head;
                let place = format!("models.candidates[{i}]");
                return Err(Error::toml_file(
                    &h.path,
                    &h.text,
                    "models.candidates",
                    place,
                    msg,
                ));
            }
        }
        let choice = if tm.candidates.len() > 1 {
            let setup = crate::calibrate::cv::CvSetup {
                method: &method,
                registration: crate::calibrate::Registration::Identify,
                seed: 0,
                fold_seed: 0,
                fixed: &[],
                done: &[],
            };
            Some(choose_model_repeated(
                &robot,
                &tm.candidates,
                &cal,
                tm.folds,
                &tm.fold_seeds,
                &setup,
            )?)
        } else {
            None
        };
        let chosen = tm.candidates[choice.as_ref().map_or(0, |c| c.best)];
        let (mut q, val) = self.request((robot, cal, val, lines), method, &[chosen])?;
        // The identification cross-validates the chosen model: it takes the repeated
        // choice's cross-validation of it that ran on the same setup (the same key: model,
        // method and settings, registration, seeds, folds and rows), if one did, instead of
        // running it again.
        q.cross_validated = choice.as_ref().map(|c| c.chosen_cvs.clone());
        let m = EntryModels {
            candidates: tm.candidates.clone(),
            fixed_by: "task",
            choice,
        };
        Ok((q, val, m))
    }
}
