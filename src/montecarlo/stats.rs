//! Monte-Carlo statistics: identification accuracy η (Guo 2024 eq. 29), validation errors
//! averaged over trials, parameter RMSE and its ratio to the Cramér–Rao bound (SPEC §6).

use serde::Serialize;
use std::collections::BTreeMap;

use super::trial::{Outcome, TrialResult};
use crate::calibrate::ErrorStats;
use crate::identify::Termination;
use crate::math::Real;

/// Mean, median and standard deviation of η for one parameter, over trials (%).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct EtaStats {
    /// Mean η (%).
    pub mean: Real,
    /// Median η (%).
    pub median: Real,
    /// Standard deviation of η (%).
    pub std: Real,
}

/// One `results` entry of `summary.json` (FORMATS.md "summary.json").
#[derive(Clone, Debug, Serialize)]
pub struct Entry {
    /// The method's label.
    pub method: String,
    /// The calibration pose strategy.
    pub poses: String,
    /// The swept value, for sweeps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sweep_value: Option<serde_json::Value>,
    /// Mean over parameters of the mean η (%).
    pub eta_mean_pct: Real,
    /// Mean over parameters of the median η (%): with random errors a draw near zero makes
    /// one trial's η hugely negative, which the mean follows and the median does not.
    pub eta_median_pct: Real,
    /// η per parameter with a non-zero injected error.
    pub eta: BTreeMap<String, EtaStats>,
    /// Validation position errors before compensation (mm), each statistic averaged over
    /// trials.
    pub validation_before_mm: ErrorStats,
    /// … after compensation.
    pub validation_after_mm: ErrorStats,
    /// Orientation errors (deg, rotation angle) before, for full-pose data.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub validation_before_deg: Option<ErrorStats>,
    /// … after.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub validation_after_deg: Option<ErrorStats>,
    /// Qiao's attitude errors (deg) before, for full-pose data (Qiao's ACAE is the mean).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub validation_before_attitude_deg: Option<ErrorStats>,
    /// … after.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub validation_after_attitude_deg: Option<ErrorStats>,
    /// Improvement of the mean validation error, % ((before − after) / before).
    pub improvement_pct: Real,
    /// RMSE over trials of each identified parameter error (mm, rad); the base parameters,
    /// which absorb the registration's error, are left out.
    pub param_rmse: BTreeMap<String, Real>,
    /// Trace of the empirical covariance of the estimates over the mean Cramér–Rao trace
    /// σ²(JᵀWJ)⁻¹ (`null` without tracker noise or with fewer than 2 trials).
    pub crb_ratio: Option<Real>,
    /// Identifications that gave no usable result (diverged, singular, invalid, non-finite).
    pub failures: usize,
    /// How the identifications ended, by termination reason.
    pub terminations: BTreeMap<String, usize>,
    /// Mean iterations.
    pub iterations_mean: Real,
    /// Mean evaluations of the model per identification (residuals for the Jacobian
    /// methods, fitness for BAS, PSO and BAS-PSO): the budget a method spent.
    pub evaluations_mean: Real,
    /// Mean wall time of one registration + identification (s). Machine-dependent, so it
    /// is written as `null` in `summary.json` (which must be the same bytes for a seed
    /// whatever the thread count) and with its value in `timing.json` and `report.md`.
    #[serde(serialize_with = "as_null")]
    pub seconds_per_identification: Real,
}

fn as_null<S: serde::Serializer>(_: &Real, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_none()
}

fn mean(v: &[Real]) -> Real {
    if v.is_empty() {
        Real::NAN
    } else {
        v.iter().sum::<Real>() / v.len() as Real
    }
}

fn std(v: &[Real]) -> Real {
    let m = mean(v);
    if v.is_empty() {
        return Real::NAN;
    }
    (v.iter().map(|x| (x - m) * (x - m)).sum::<Real>() / v.len() as Real).sqrt()
}

fn median(v: &[Real]) -> Real {
    crate::math::median(&mut v.to_vec())
}

/// η_i = (1 − |x_i − x̂_i| / |x_i|) · 100 % (Guo 2024 eq. 29); `None` where x_i = 0.
pub fn eta(truth: Real, identified: Real) -> Option<Real> {
    (truth != 0.0).then(|| (1.0 - (truth - identified).abs() / truth.abs()) * 100.0)
}

fn average_stats(v: &[ErrorStats]) -> ErrorStats {
    let f = |g: fn(&ErrorStats) -> Real| mean(&v.iter().map(g).collect::<Vec<_>>());
    ErrorStats {
        mean: f(|s| s.mean),
        rms: f(|s| s.rms),
        max: f(|s| s.max),
        std: f(|s| s.std),
    }
}

/// Aggregates the outcomes of `(strategy, method)` over `trials`.
pub fn aggregate(
    trials: &[TrialResult],
    strategy: usize,
    method: usize,
    names: &[String],
    labels: (&str, &str),
    sweep_value: Option<serde_json::Value>,
) -> Entry {
    let outs: Vec<(&TrialResult, &Outcome)> = trials
        .iter()
        .filter_map(|t| {
            t.outcomes
                .iter()
                .find(|o| o.strategy == strategy && o.method == method)
                .map(|o| (t, o))
        })
        .collect();
    let usable = |o: &Outcome| {
        !matches!(
            o.termination,
            Termination::Diverged
                | Termination::Singular
                | Termination::RankDeficient
                | Termination::InvalidInput
        ) && o.identified.iter().all(|x| x.is_finite())
            && o.after_mm.rms.is_finite()
    };
    let ok: Vec<_> = outs.iter().filter(|(_, o)| usable(o)).collect();
    let failures = outs.len() - ok.len();

    let mut eta_map = BTreeMap::new();
    let mut rmse = BTreeMap::new();
    let mut emp_trace = 0.0;
    for (k, name) in names.iter().enumerate() {
        // Base parameters absorb the registration's error: nuisance, not compared.
        if name.starts_with("base.") {
            continue;
        }
        let errs: Vec<Real> = ok
            .iter()
            .map(|(t, o)| o.identified[k] - t.truth[k])
            .collect();
        rmse.insert(
            name.clone(),
            (mean(&errs.iter().map(|e| e * e).collect::<Vec<_>>())).sqrt(),
        );
        emp_trace += std(&errs).powi(2);
        let etas: Vec<Real> = ok
            .iter()
            .filter_map(|(t, o)| eta(t.truth[k], o.identified[k]))
            .collect();
        if !etas.is_empty() {
            eta_map.insert(
                name.clone(),
                EtaStats {
                    mean: mean(&etas),
                    median: median(&etas),
                    std: std(&etas),
                },
            );
        }
    }
    let eta_mean_pct = mean(&eta_map.values().map(|e| e.mean).collect::<Vec<_>>());
    let eta_median_pct = mean(&eta_map.values().map(|e| e.median).collect::<Vec<_>>());
    let crbs: Vec<Real> = ok
        .iter()
        .filter_map(|(t, _)| t.crb_trace[strategy])
        .collect();
    let crb_ratio = (ok.len() >= 2 && crbs.len() == ok.len())
        .then(|| emp_trace * ok.len() as Real / (ok.len() - 1) as Real / mean(&crbs));
    let before = average_stats(&ok.iter().map(|(_, o)| o.before_mm).collect::<Vec<_>>());
    let after = average_stats(&ok.iter().map(|(_, o)| o.after_mm).collect::<Vec<_>>());
    let deg = |f: fn(&Outcome) -> Option<ErrorStats>| {
        let v: Vec<ErrorStats> = ok.iter().filter_map(|(_, o)| f(o)).collect();
        (!v.is_empty()).then(|| average_stats(&v))
    };
    let mut terminations = BTreeMap::new();
    for (_, o) in &outs {
        *terminations
            .entry(o.termination.as_str().to_string())
            .or_insert(0) += 1;
    }
    Entry {
        method: labels.0.to_string(),
        poses: labels.1.to_string(),
        sweep_value,
        eta_mean_pct,
        eta_median_pct,
        eta: eta_map,
        validation_before_mm: before,
        validation_after_mm: after,
        validation_before_deg: deg(|o| o.before_deg),
        validation_after_deg: deg(|o| o.after_deg),
        validation_before_attitude_deg: deg(|o| o.before_attitude_deg),
        validation_after_attitude_deg: deg(|o| o.after_attitude_deg),
        improvement_pct: (before.mean - after.mean) / before.mean * 100.0,
        param_rmse: rmse,
        crb_ratio,
        failures,
        terminations,
        iterations_mean: mean(
            &ok.iter()
                .map(|(_, o)| o.iterations as Real)
                .collect::<Vec<_>>(),
        ),
        evaluations_mean: mean(
            &ok.iter()
                .map(|(_, o)| o.evaluations as Real)
                .collect::<Vec<_>>(),
        ),
        seconds_per_identification: mean(&outs.iter().map(|(_, o)| o.seconds).collect::<Vec<_>>()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eta_is_guo_eq_29() {
        assert_eq!(eta(0.5, 0.5), Some(100.0));
        assert!((eta(0.5, 0.4).unwrap() - 80.0).abs() < 1e-12);
        assert!((eta(-0.05, -0.06).unwrap() - 80.0).abs() < 1e-12);
        assert_eq!(eta(0.0, 0.1), None);
    }

    #[test]
    fn median_and_std_by_hand() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!((std(&[1.0, 3.0]) - 1.0).abs() < 1e-12);
    }
}
