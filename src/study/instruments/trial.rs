//! One trial's outcome as its record in `records.txt` holds it (docs/formats.md § 7.3), and
//! whether a trial read from a record can be a trial of its cell: the cell's results index its
//! identified values by the cell's parameters and its true errors by the first trial's.

use serde::{Deserialize, Serialize};

use super::CellPlan;
use crate::numeric::Real;
use crate::robot::Param;

/// One trial's outcome: the true errors, the identified values, the Cramér–Rao trace and the
/// validation RMS before and after (its serde form is its record in `records.txt`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Trial {
    pub(super) errors: Vec<(Param, Real)>,
    pub(super) x: Vec<Real>,
    pub(super) crb: Real,
    pub(super) before: Real,
    pub(super) after: Real,
}

impl Trial {
    /// Why this trial, read from a record whose checksum was made to match an edit, cannot be
    /// one of `plan`'s cell in a study whose true robots carry `errors` errors (`None`: not
    /// checked), if it cannot.
    pub fn misfit(&self, plan: &CellPlan, errors: Option<usize>) -> Option<String> {
        let (x, params) = (self.x.len(), plan.prepared.params.len());
        if x != params {
            return Some(format!(
                "{x} identified values, for a cell of {params} parameters"
            ));
        }
        let n = self.errors.len();
        errors
            .filter(|&e| e != n)
            .map(|e| format!("{n} true errors, for a study of {e}"))
    }
}
