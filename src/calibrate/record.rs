//! The identification record: what `identified.json` holds (docs/formats.md `identify`), built
//! here once from an [`IdentifyOutcome`](super::request::IdentifyOutcome) for every caller
//! (the `identify` command writes it, the Python module returns it as a dict).
//!
//! The tracker's record is serialised as it is written: the per-point vectors of the
//! diagnostics go from their slices to the file, never through a JSON tree. Keys are in byte
//! order at every level, as a `serde_json::Map` writes them.

use std::path::Path;

use serde_json::{json, Map, Value};

use super::cv::{CrossValidation, Holdout};
use super::diagnostics::Diagnostics;
use super::validation::{keys, FileValidation};
use super::{Calibrated, ErrorStats, Registration};
use crate::numeric::Real;
use crate::robot::{Param, Robot};

/// A prior's effect: the estimate without and with it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PriorMove {
    /// The parameter.
    pub parameter: String,
    /// The prior's σ (mm, rad).
    pub sigma: Real,
    /// The estimate without any prior.
    pub without_prior: Real,
    /// The MAP estimate.
    pub with_prior: Real,
}

/// The practice options' results of one identification on a tracker's file.
#[derive(Clone, Debug, Default)]
pub struct Practice {
    /// `--holdout`.
    pub holdout: Option<Holdout>,
    /// The cross-validation of the model identified.
    pub cv: Option<CrossValidation>,
    /// `--models`: every model's cross-validation and the index of the best.
    pub models: Option<(Vec<CrossValidation>, usize)>,
    /// `--fix`.
    pub fixed: Vec<Param>,
    /// `--prior`: how each moved its estimate.
    pub priors: Vec<PriorMove>,
    /// The convergence trace: what it holds, and its values.
    pub trace: Option<(&'static str, Vec<Real>)>,
    /// The diagnostics.
    pub diagnostics: Option<Diagnostics>,
}

fn to_value<T: serde::Serialize>(v: &T) -> Value {
    serde_json::to_value(v).unwrap_or(Value::Null)
}

/// Names as strings.
pub(crate) fn names(v: &[Param]) -> Vec<String> {
    v.iter().map(|p| p.to_string()).collect()
}

impl Practice {
    /// The keys the practice options add to `identified.json` (the diagnostics apart:
    /// [`IdentifiedJson`] writes them); nothing for an option not used.
    pub fn json(&self) -> Map<String, Value> {
        let mut j = Map::new();
        if let Some(h) = self.holdout {
            j.insert("holdout".into(), json!(format!("{}/{}", h.last, h.every)));
        }
        if let Some(cv) = &self.cv {
            j.insert("cv".into(), to_value(cv));
        }
        if let Some((cvs, best)) = &self.models {
            j.insert("cv_models".into(), to_value(cvs));
            j.insert("cv_best".into(), json!(cvs[*best].model));
        }
        if !self.fixed.is_empty() {
            j.insert("fixed".into(), json!(names(&self.fixed)));
        }
        if !self.priors.is_empty() {
            j.insert("priors".into(), to_value(&self.priors));
        }
        if let Some((what, values)) = &self.trace {
            j.insert(
                "convergence_trace".into(),
                json!({"values": what, "trace": values}),
            );
        }
        j
    }
}

fn stats_json(s: &ErrorStats) -> Value {
    json!({"mean": s.mean, "rms": s.rms, "max": s.max, "std": s.std})
}

/// What the base keys of a tracker's record are built from.
pub struct TrackerBase<'a> {
    /// The nominal robot (of the model identified).
    pub nominal: &'a Robot,
    /// The measurement file (its name in the record).
    pub source: &'a Path,
    /// The method's name.
    pub method: &'a str,
    /// The registration used.
    pub registration: Registration,
    /// The identified parameters.
    pub params: &'a [Param],
    /// The calibration.
    pub calibrated: &'a Calibrated,
    /// The validation on a separate file or the held-out rows, if any.
    pub validation: Option<&'a FileValidation>,
}

/// The base keys of a tracker's `identified.json`: robot, data, method, registration, the
/// estimate with its covariance and statistics, and the validation.
pub fn tracker_base(r: &TrackerBase) -> Map<String, Value> {
    let id = &r.calibrated.identified;
    let names = names(r.params);
    let errors: Map<String, Value> = names
        .iter()
        .zip(id.x.iter())
        .map(|(n, x)| (n.clone(), json!(x)))
        .collect();
    let covariance = id.covariance();
    let cov: Vec<Vec<Real>> = (0..covariance.nrows())
        .map(|i| covariance.row(i).iter().copied().collect())
        .collect();
    let (xyz, rpy) = r.calibrated.frame.to_xyz_rpy();
    let mut j = json!({
        "robot": r.nominal.name,
        "data": r.source.display().to_string(),
        "method": r.method,
        "registration": r.registration.as_str(),
        "registration_frame": {"xyz_mm": xyz, "rpy_rad": rpy},
        "registration_rounds": r.calibrated.rounds.rounds,
        "registration_termination": r.calibrated.rounds.termination.as_str(),
        "registration_last_step_mm": r.calibrated.rounds.last_step_mm,
        "parameters": names,
        "errors": errors,
        "covariance": cov,
        "condition_number": id.condition_number(),
        "rank": id.rank,
        "sigma0": id.sigma0,
        "rms_residual_mm": id.rms_residual,
        "iterations": id.iterations,
        "evaluations": id.evaluations,
        "termination": id.termination.as_str(),
    });
    if let Some(v) = r.validation {
        j[keys::BEFORE_MM] = stats_json(&v.before_mm);
        j[keys::AFTER_MM] = stats_json(&v.after_mm);
        if let Some((b, a)) = &v.deg {
            j["validation_before_deg"] = stats_json(b);
            j[keys::AFTER_DEG] = stats_json(a);
        }
        if let Some((b, a)) = &v.attitude_deg {
            j["validation_before_attitude_deg"] = stats_json(b);
            j[keys::AFTER_ATTITUDE_DEG] = stats_json(a);
        }
    }
    let Value::Object(m) = j else {
        unreachable!("json! of an object")
    };
    m
}

/// The key of `identified.json` that lists why a result kept with `--allow-worse` is worse
/// than the nominal robot (docs/formats.md `identify`).
pub const ALLOWED_WORSE: &str = "allowed_worse";

/// A tracker's `identified.json`: the base keys, the `more` keys (the practice options',
/// [`ALLOWED_WORSE`]) and the diagnostics, serialised in key order.
pub struct IdentifiedJson<'a> {
    /// The base keys ([`tracker_base`]).
    pub base: &'a Map<String, Value>,
    /// Keys added to them.
    pub more: &'a Map<String, Value>,
    /// The diagnostics, written from their vectors as `diagnostics`.
    pub diagnostics: Option<&'a Diagnostics>,
}

/// A value of [`IdentifiedJson`]: a JSON tree, or the diagnostics.
enum Entry<'a> {
    Json(&'a Value),
    Diagnostics(&'a Diagnostics),
}

impl serde::Serialize for Entry<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap as _;
        let d = match self {
            Entry::Json(v) => return v.serialize(s),
            Entry::Diagnostics(d) => d,
        };
        // Everything but the per-point vectors as a (small) tree; those two in its key order.
        let small = Diagnostics {
            sigma: d.sigma.clone(),
            correlation: d.correlation.clone(),
            flagged_pairs: d.flagged_pairs.clone(),
            leverage: Vec::new(),
            cook_distance: Vec::new(),
            top_points: d.top_points.clone(),
            predicted: d.predicted.clone(),
        };
        let Ok(Value::Object(tree)) = serde_json::to_value(&small) else {
            return s.serialize_none();
        };
        let mut m = s.serialize_map(Some(tree.len()))?;
        for (k, v) in &tree {
            match k.as_str() {
                "leverage" => m.serialize_entry(k, &d.leverage)?,
                "cook_distance" => m.serialize_entry(k, &d.cook_distance)?,
                _ => m.serialize_entry(k, v)?,
            }
        }
        m.end()
    }
}

impl serde::Serialize for IdentifiedJson<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap as _;
        let mut keys: std::collections::BTreeMap<&str, Entry> = self
            .base
            .iter()
            .chain(self.more)
            .map(|(k, v)| (k.as_str(), Entry::Json(v)))
            .collect();
        if let Some(d) = self.diagnostics {
            keys.insert("diagnostics", Entry::Diagnostics(d));
        }
        let mut m = s.serialize_map(Some(keys.len()))?;
        for (k, v) in &keys {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}
