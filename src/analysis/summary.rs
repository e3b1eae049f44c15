//! `Summary`: what the analysis of a run decided, typed; `summary.json` is its serialisation
//! (docs/formats.md "summary.json"), and every reader of a run (`check`, `compare`, the
//! results database, Python) deserialises it.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::claims::ClaimResult;
use super::comparisons::Differences;
use crate::error::{read_text, Error, Result};
use crate::numeric::Real;
use crate::study::metric::Metric;
pub use crate::study::stats::paired::Comparison;
use crate::study::stats::precision::Stopping;
use crate::study::stats::Entry;

/// The format of the summaries this calbench writes. Format 1 is the first and is written
/// without a `format` key (so its files keep their bytes); a later format writes its number.
pub const FORMAT: u32 = 1;

fn is_first(f: &u32) -> bool {
    *f == 1
}

fn first() -> u32 {
    1
}

/// An optimised pose set of the run (the same in every trial).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FixedPoseSet {
    /// Poses in the set.
    pub poses: usize,
    /// The optimiser's iterations.
    pub iterations: usize,
    /// The objective at the last iteration.
    pub final_objective: Option<Real>,
    /// The optimiser's scores of the set.
    pub scores: Option<Value>,
    /// The objective per iteration.
    pub trace: Vec<Real>,
    /// The iteration from which the objective stays within 0.1 % of its end.
    pub settled_iteration: Option<usize>,
}

/// One entry's performance profile over the sweep points (Dolan & Moré).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct EntryProfile {
    /// The method.
    pub method: String,
    /// The pose strategy.
    pub poses: String,
    /// Per sweep point, the metric over the point's best (`null` where not finite).
    pub ratio: Vec<Option<Real>>,
    /// Per τ, the share of sweep points within τ of the best.
    pub share: Vec<Real>,
}

/// The performance profile of a sweep.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Profile {
    /// The metric profiled.
    pub metric: Metric,
    /// The factors τ.
    pub tau: Vec<Real>,
    /// One per entry.
    pub profiles: Vec<EntryProfile>,
}

/// A run's summary (docs/formats.md "summary.json"). Keys written in sorted order, as
/// serde_json's map sorts them; read back, a key an older summary lacks takes its default
/// (only `scenario` and `results` are required).
#[serde_with::skip_serializing_none]
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary {
    /// The format ([`FORMAT`]); a summary of a later format is refused.
    #[serde(default = "first", skip_serializing_if = "is_first")]
    pub format: u32,
    /// The scenario's name.
    pub scenario: String,
    /// Its description.
    #[serde(default)]
    pub description: String,
    /// The robot.
    #[serde(default)]
    pub robot: String,
    /// Trials run.
    pub trials: Option<usize>,
    /// The seed.
    pub seed: Option<u64>,
    /// `pose` or `position` ([`Summary::MEASURES`]).
    #[serde(default)]
    pub measure: String,
    /// The registration.
    #[serde(default)]
    pub registration: String,
    /// The identified parameters.
    #[serde(default)]
    pub parameters: Vec<String>,
    /// The parameters with an injected error.
    #[serde(default)]
    pub error_parameters: Vec<String>,
    /// The optimised pose sets, by strategy.
    #[serde(default)]
    pub fixed_pose_sets: BTreeMap<String, FixedPoseSet>,
    /// The metaheuristics' best fitness per iteration in trial 0, by `method / poses`.
    #[serde(default)]
    pub fitness_trace_trial0: BTreeMap<String, Vec<Real>>,
    /// The timing file's name.
    #[serde(default)]
    pub timing: String,
    /// One entry per sweep point × strategy × method.
    pub results: Vec<Entry>,
    /// Every paired comparison, Holm-adjusted together.
    #[serde(default)]
    pub comparisons: Vec<Comparison>,
    /// The claims evaluated, with a claim per block.
    pub claims: Option<Vec<ClaimResult>>,
    /// A sweep's performance profile.
    pub performance_profile: Option<Profile>,
    /// Why a run with `--precision` stopped.
    pub stopping: Option<Stopping>,
    /// The ill-conditioned parameter separation.
    pub separation: Option<Value>,
    /// The simulated arm's compliances.
    pub true_compliance: Option<Value>,
    /// A one-axis sweep's key.
    pub sweep_key: Option<String>,
    /// … and its values.
    pub sweep_values: Option<Vec<Value>>,
    /// A sweep's keys.
    pub sweep_keys: Option<Vec<String>>,
    /// Whether the sweep's axes are zipped.
    pub sweep_zip: Option<bool>,
    /// The comparisons the reports show: each entry against its baseline (not written).
    #[serde(skip)]
    pub shown: Vec<Comparison>,
    /// The per-trial differences of the shown pairs of the first block (not written).
    #[serde(skip)]
    pub differences: Vec<Differences>,
}

impl Summary {
    /// The `measure` of a run of positions, and of one of full poses.
    pub const MEASURES: [&'static str; 2] = ["position", "pose"];

    /// The summary as a JSON value (object keys sorted).
    pub fn to_value(&self) -> Result<Value> {
        serde_json::to_value(self).map_err(|e| Error::Compute(e.to_string()))
    }

    /// `summary.json`'s text.
    pub fn to_json(&self) -> Result<String> {
        crate::error::json_text(&self.to_value()?)
    }

    /// Reads a summary from a JSON value (`path` names it in errors): a summary of a later
    /// format than [`FORMAT`], or one that is not a calbench summary, is refused.
    pub fn from_value(v: Value, path: &Path) -> Result<Summary> {
        let s: Summary = crate::error::read_typed(v, path, "summary.json")?;
        crate::error::newer_format(path, "summary", s.format, FORMAT)?;
        Ok(s)
    }

    /// Reads `summary.json` at `path`.
    pub fn read(path: &Path) -> Result<Summary> {
        let text = read_text(path)?;
        Summary::from_value(crate::error::json_value(path, &text)?, path)
    }
}
