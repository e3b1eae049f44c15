//! An entry's figures read by metric, by field (docs/formats.md "summary.json"): what
//! `check`, `compare`, history and the results database read of a summary's entries.

use super::{Entry, Figures};
use crate::numeric::Real;
use crate::study::metric::Metric;

impl Entry {
    /// The figure of `key` — a metric's key ([`Metric::key`]) or a parameter's RMSE
    /// (`param_rmse.NAME`) — with its 95 % interval when the summary has one; `None` when
    /// the entry has no such figure (a parameter it does not list, an optional statistic its
    /// study lacks, a metric an entry does not carry). A figure written as `null`, or lacking
    /// from an older file, is NaN.
    pub fn figure(&self, key: &str) -> Option<(Real, Option<[Real; 2]>)> {
        if let Some(name) = Metric::ParamRmse.parameter_of(key) {
            let v = *self.param_rmse.get(name)?;
            return Some((v, self.param_rmse_ci95.get(name).copied().flatten()));
        }
        let m = Metric::from_key(key)?;
        let figures: &Figures = match m {
            Metric::EtaMean => return Some((self.eta_mean_pct, self.eta_mean_pct_ci95)),
            Metric::EtaMedian => return Some((self.eta_median_pct, self.eta_median_pct_ci95)),
            Metric::Failures => return Some((self.failures as Real, None)),
            Metric::Improvement => return Some((self.improvement_pct, None)),
            Metric::FinalFitness => return self.final_fitness.map(|f| (f.mean, f.mean_ci95)),
            Metric::ValidationAfterMean
            | Metric::ValidationAfterRms
            | Metric::ValidationAfterMax => &self.validation_after_mm,
            Metric::ValidationBeforeMean | Metric::ValidationBeforeRms => {
                &self.validation_before_mm
            }
            Metric::CalibrationAfterMean | Metric::CalibrationAfterRms => {
                &self.calibration_after_mm
            }
            _ => self.optional.get(m.spec().field)?,
        };
        figures.stat(m)
    }

    /// Whether `other` (an entry of another run) is this entry: the same method, poses and
    /// sweep value, numbers compared by value (`15` and `15.0` are one point, as a
    /// scenario's settings are compared by what they set, docs/formats.md § 2.4).
    pub fn same_entry(&self, other: &Entry) -> bool {
        self.method == other.method
            && self.poses == other.poses
            && match (&self.sweep_value, &other.sweep_value) {
                (Some(a), Some(b)) => same_json(a, b),
                (a, b) => a.is_none() && b.is_none(),
            }
    }

    /// The entry's name in `check` and the results database: `method / poses`, and
    /// ` / VALUE` at a sweep point (a string value as itself, another as JSON writes it).
    pub fn key(&self) -> String {
        match &self.sweep_value {
            Some(serde_json::Value::String(v)) => format!("{} / {} / {v}", self.method, self.poses),
            Some(v) => format!("{} / {} / {v}", self.method, self.poses),
            None => format!("{} / {}", self.method, self.poses),
        }
    }
}

/// Whether two JSON values of a sweep say the same: numbers by value (`15` and `15.0`),
/// arrays and tables element by element, anything else as written.
pub fn same_json(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.as_f64() == y.as_f64(),
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(a, b)| same_json(a, b))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .all(|(k, v)| y.get(k).is_some_and(|w| same_json(v, w)))
        }
        _ => a == b,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_are_read_by_field_and_a_lacking_one_is_nan() {
        let e: Entry = serde_json::from_value(serde_json::json!({
            "method": "ls", "poses": "random", "eta_mean_pct": 91.5,
            "eta_mean_pct_ci95": [90.0, 93.0],
            "validation_after_mm": {"mean": 0.1, "rms": 0.2, "max": 0.4, "std": null,
                                    "rms_ci95": [0.15, 0.25]},
            "validation_after_deg": {"mean": 0.01, "rms": 0.02, "max": 0.04, "std": 0.0},
            "param_rmse": {"a2": 0.5}, "param_rmse_ci95": {"a2": [0.4, 0.6]}, "failures": 2,
            "sweep_value": 0.5
        }))
        .unwrap();
        assert_eq!(e.figure("eta_mean_pct"), Some((91.5, Some([90.0, 93.0]))));
        assert_eq!(
            e.figure("validation_after_mm.rms"),
            Some((0.2, Some([0.15, 0.25])))
        );
        assert_eq!(e.figure("validation_after_mm.max"), Some((0.4, None)));
        assert_eq!(e.figure("validation_after_deg.rms"), Some((0.02, None)));
        assert_eq!(e.figure("param_rmse.a2"), Some((0.5, Some([0.4, 0.6]))));
        assert_eq!(e.figure("param_rmse.d1"), None);
        assert_eq!(e.figure("failures"), Some((2.0, None)));
        assert_eq!(e.figure("no_such_metric"), None);
        // Lacking from the file: NaN, never a value a reader could take for one.
        assert!(e.figure("eta_median_pct").unwrap().0.is_nan());
        assert!(e.figure("validation_before_mm.mean").unwrap().0.is_nan());
        assert_eq!(e.figure("validation_after_attitude_deg.mean"), None);
        assert_eq!(e.key(), "ls / random / 0.5");
    }

    #[test]
    fn an_integer_and_a_float_of_one_value_are_one_sweep_point() {
        let entry = |v: serde_json::Value| -> Entry {
            serde_json::from_value(serde_json::json!({
                "method": "ls", "poses": "random", "sweep_value": v
            }))
            .unwrap()
        };
        let json = |t: &str| serde_json::from_str::<serde_json::Value>(t).unwrap();
        assert!(entry(json("15")).same_entry(&entry(json("15.0"))));
        assert!(entry(json("[1, {\"a\": 2.0}]")).same_entry(&entry(json("[1.0, {\"a\": 2}]"))));
        assert!(!entry(json("15")).same_entry(&entry(json("15.5"))));
        assert!(!entry(json("\"15\"")).same_entry(&entry(json("15"))));
        assert!(!entry(json("[1, 2]")).same_entry(&entry(json("[1]"))));
    }
}
