//! `calbench check`: the regression guard on identification accuracy (FORMATS.md).
//!
//! A summary is compared with a baseline entry by entry — entries are matched by method,
//! pose strategy and swept value — on the metrics that say how well the calibration worked.
//! Timing is not compared: it depends on the machine.

use std::fmt;
use std::path::Path;

use serde_json::Value;

use crate::error::{Error, Result};
use crate::math::Real;

/// Which way a metric improves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Better {
    Higher,
    Lower,
}

/// One metric that got worse beyond the tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct Regression {
    /// The entry: `method / poses [/ sweep value]`.
    pub entry: String,
    /// The metric's key path, e.g. `validation_after_mm.rms`.
    pub metric: String,
    /// The baseline value.
    pub baseline: Real,
    /// The value in the summary (`NaN` when the entry or metric is missing).
    pub value: Real,
}

impl fmt::Display for Regression {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.value.is_nan() {
            write!(
                f,
                "{}: {} is missing (baseline {})",
                self.entry, self.metric, self.baseline
            )
        } else {
            write!(
                f,
                "{}: {} got worse: {} (baseline {})",
                self.entry, self.metric, self.value, self.baseline
            )
        }
    }
}

/// The compared metrics, with the direction each improves in. `param_rmse` is compared per
/// parameter name.
const METRICS: &[(&str, Better)] = &[
    ("eta_mean_pct", Better::Higher),
    ("eta_median_pct", Better::Higher),
    ("validation_after_mm.mean", Better::Lower),
    ("validation_after_mm.rms", Better::Lower),
    ("validation_after_mm.max", Better::Lower),
    ("validation_after_deg.mean", Better::Lower),
    ("validation_after_deg.rms", Better::Lower),
    ("failures", Better::Lower),
];

fn entry_key(e: &Value) -> String {
    let s = |k: &str| match e.get(k) {
        Some(Value::String(s)) => s.clone(),
        Some(v) => v.to_string(),
        None => String::new(),
    };
    match e.get("sweep_value") {
        Some(v) => format!("{} / {} / {}", s("method"), s("poses"), v),
        None => format!("{} / {}", s("method"), s("poses")),
    }
}

fn lookup(e: &Value, path: &str) -> Option<Real> {
    path.split('.')
        .try_fold(e, |v, k| v.get(k))
        .and_then(Value::as_f64)
}

/// Compares `summary` with `baseline` and returns every regression. A metric regresses when it
/// is worse than the baseline by more than `tolerance` times the baseline's magnitude (plus
/// 1e-9, so a zero baseline tolerates rounding only). A baseline entry or metric missing from
/// the summary is a regression; a non-finite value is one too.
pub fn compare(summary: &Value, baseline: &Value, tolerance: Real) -> Vec<Regression> {
    let empty = Vec::new();
    let entries = |v: &Value| {
        v.get("results")
            .and_then(Value::as_array)
            .unwrap_or(&empty)
            .clone()
    };
    let new = entries(summary);
    let mut out = Vec::new();
    for b in entries(baseline) {
        let key = entry_key(&b);
        let found = new.iter().find(|e| entry_key(e) == key);
        let mut metrics: Vec<(String, Better)> =
            METRICS.iter().map(|(m, d)| (m.to_string(), *d)).collect();
        if let Some(Value::Object(m)) = b.get("param_rmse") {
            metrics.extend(m.keys().map(|k| (format!("param_rmse.{k}"), Better::Lower)));
        }
        for (metric, dir) in metrics {
            let Some(base) = lookup(&b, &metric) else {
                continue;
            };
            let value = found.and_then(|e| lookup(e, &metric)).unwrap_or(Real::NAN);
            let margin = tolerance * base.abs() + 1e-9;
            let worse = match dir {
                Better::Higher => value < base - margin,
                Better::Lower => value > base + margin,
            };
            if worse || !value.is_finite() {
                out.push(Regression {
                    entry: key.clone(),
                    metric,
                    baseline: base,
                    value,
                });
            }
        }
    }
    out
}

/// Reads a JSON file.
pub fn read_json(path: &Path) -> Result<Value> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    serde_json::from_str(&text).map_err(|e| Error::file(path, "JSON", e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn summary(eta: Real, rms: Real) -> Value {
        json!({"results": [{"method": "ls", "poses": "random", "eta_mean_pct": eta,
            "validation_after_mm": {"mean": rms, "rms": rms, "max": 2.0 * rms, "std": 0.1},
            "param_rmse": {"a2": 0.01}, "failures": 0}]})
    }

    #[test]
    fn equal_summaries_pass() {
        assert!(compare(&summary(90.0, 0.1), &summary(90.0, 0.1), 0.05).is_empty());
    }

    #[test]
    fn worse_beyond_tolerance_is_named() {
        let r = compare(&summary(80.0, 0.2), &summary(90.0, 0.1), 0.05);
        let names: Vec<&str> = r.iter().map(|r| r.metric.as_str()).collect();
        assert!(names.contains(&"eta_mean_pct"));
        assert!(names.contains(&"validation_after_mm.rms"));
        assert!(!names.contains(&"failures"));
    }

    #[test]
    fn within_tolerance_and_better_pass() {
        assert!(compare(&summary(89.0, 0.104), &summary(90.0, 0.1), 0.05).is_empty());
        assert!(compare(&summary(99.0, 0.01), &summary(90.0, 0.1), 0.0).is_empty());
    }

    #[test]
    fn missing_entry_is_a_regression() {
        let mut s = summary(90.0, 0.1);
        s["results"][0]["method"] = json!("lm");
        assert!(!compare(&s, &summary(90.0, 0.1), 0.05).is_empty());
    }
}
