//! The regression rule of `calbench check`, `compare` and `history`: the guard on
//! identification accuracy (docs/formats.md § 8.4).
//!
//! A summary is compared with a baseline entry by entry — entries are matched by method,
//! pose strategy and swept value — on the metrics that say how well the calibration worked.
//! Timing is not compared: it depends on the machine.
//!
//! Both sides are typed summaries ([`Summary`], read by serde: a file that is not one is
//! refused naming the file and the key, [`check_summary`]) of the same scenario that share
//! at least one metric ([`comparable`]); otherwise there is nothing to guard and `check`
//! refuses them, naming the file. A metric regresses when it is worse by the tolerance or
//! more — a change of exactly the tolerance counts — and the change is not Monte-Carlo
//! noise: its Holm-adjusted interval excludes zero ([`noise`]); worse beyond the tolerance
//! within the noise is *unresolved* ([`compare_with`]). A baseline file carries the per-trial
//! values that pairing needs ([`baseline`]).

pub mod baseline;
pub mod noise;
mod read;
pub mod tolerance;
pub mod trials_csv;

use std::fmt;
use std::path::Path;

use crate::analysis::summary::Summary;
use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::study::stats::Entry;
pub use baseline::{
    a_shard, baseline_document, trials_of, unpaired_because, unpaired_entries, Side, Unpaired,
    Which,
};
use noise::Change;
pub use noise::{pairable, Status, Trials};
pub use read::{check_summary, check_summary_for, read_json, read_summary};
use tolerance::regressed;
pub use tolerance::{checked_tolerance, MAX_TOLERANCE};

use crate::study::metric::{Better, Metric};

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
const METRICS: [Metric; 8] = [
    Metric::EtaMean,
    Metric::EtaMedian,
    Metric::ValidationAfterMean,
    Metric::ValidationAfterRms,
    Metric::ValidationAfterMax,
    Metric::DegAfterMean,
    Metric::DegAfterRms,
    Metric::Failures,
];

/// The finite figure of `path` in entry `e` (`None` when it lacks it or holds `null`).
fn lookup(e: &Entry, path: &str) -> Option<Real> {
    e.figure(path).map(|f| f.0).filter(|v| !v.is_nan())
}

/// The metrics compared for one baseline entry: [`METRICS`] and its `param_rmse` names.
fn entry_metrics(b: &Entry) -> Vec<(String, Better)> {
    let mut metrics: Vec<(String, Better)> =
        METRICS.iter().map(|m| (m.key(), m.spec().better)).collect();
    let rmse = Metric::ParamRmse;
    metrics.extend(
        b.param_rmse
            .keys()
            .map(|k| (rmse.of_parameter(k), rmse.spec().better)),
    );
    metrics
}

/// Compares `summary` with `baseline` and returns every regression. A metric regresses when it
/// is worse than the baseline by the tolerance or more: by at least `tolerance` times the
/// baseline's magnitude (a change of exactly the tolerance is a regression) and by more than
/// 1e-9, so a zero baseline tolerates rounding only. A baseline entry or metric missing from
/// the summary is a regression; a non-finite value is one too.
///
/// This compares two values as they are; `calbench check` first refuses them unless they are
/// [`comparable`].
pub fn compare(summary: &Summary, baseline: &Summary, tolerance: Real) -> Vec<Regression> {
    compare_all(summary, baseline, tolerance)
        .into_iter()
        .filter(|c| c.regressed)
        .map(|c| c.metric)
        .collect()
}

/// One compared metric: the values, and whether it is a regression by [`compare`]'s rules.
#[derive(Clone, Debug, PartialEq)]
pub struct Compared {
    /// The entry, the metric and both values (`value` NaN when the summary lacks it).
    pub metric: Regression,
    /// Whether the summary's value is worse than the baseline's by the tolerance or more,
    /// missing or non-finite.
    pub regressed: bool,
    /// Whether a higher value of the metric is better (η) or a lower one (errors).
    pub higher_is_better: bool,
    /// What the metric did ([`Status`]); `regressed` is `status == Regression`.
    pub status: Status,
    /// The interval of the change B − A at the Holm-adjusted level of this metric
    /// ([`ALPHA`] / its Holm step), in the metric's units; `None` for a missing metric.
    /// Unpaired it is the t (Welch) interval, which excludes zero exactly when the step
    /// rejects; paired it is the interval of the test the report's comparison of the pair
    /// uses ([`Change::interval`]): of the mean (t), or of the median (sign) — `median`. A
    /// change is resolved ([`Status`]) when the step rejects and this interval excludes zero.
    /// (Paired, the step's rank test can reject where it does not.)
    pub diff_ci: Option<[Real; 2]>,
    /// The two-sided p-value of "no change" (NaN for a missing metric).
    pub p_value: Real,
    /// … Holm-adjusted over the metrics compared.
    pub p_holm: Real,
    /// Whether the change was computed trial by trial (from both runs' `trials.csv`).
    pub paired: bool,
    /// Whether both runs' per-trial values of the metric pair but were set aside: over the
    /// trials usable in both they do not give the summaries' figures (a trial, or a
    /// parameter's η, counted in one run only), so the change is the summaries' (unpaired).
    pub not_the_figures: bool,
    /// Whether `diff_ci` is the interval of the median change (paired, where the report's
    /// comparison of the pair locates the median: the sign test's), not the t interval of
    /// the mean.
    pub median: bool,
    /// For an unresolved metric: the trials per run that would detect a change of exactly
    /// the tolerance with 80 % power at the Bonferroni level [`ALPHA`] / m.
    pub trials_needed: Option<usize>,
}

/// The significance level of the guard, before the Holm adjustment: the familywise error of
/// one comparison of two summaries. Chosen in advance at 1 %, the guard's target false-alarm
/// rate (docs/guard.md): Holm's adjustment holds the chance that any of the metrics compared
/// is flagged on unchanged code at or below it, whatever the dependence between the metrics
/// (Holm 1979), and the tolerance only lowers it further. At 0.05 a change of the code that
/// moves every draw of `scenarios/ci-guard.toml` was flagged in 2 of 100 unchanged pairs.
pub const ALPHA: Real = 0.01;

/// Every metric [`compare`] looks at, entry by entry in the baseline's order, each with
/// both values and its status, from the summaries only (unpaired): [`compare_with`]
/// without per-trial values.
pub fn compare_all(summary: &Summary, baseline: &Summary, tolerance: Real) -> Vec<Compared> {
    compare_with(summary, baseline, tolerance, None)
}

/// Every metric [`compare`] looks at, entry by entry in the baseline's order, each with both
/// values, the interval of its change and its [`Status`]. `trials` holds the per-trial
/// values of the baseline's run and of the summary's (their `trials.csv`): when the two runs
/// are [`pairable`] and an entry has the same trials in both, its metrics are compared trial
/// by trial; otherwise from the summaries ([`noise::unpaired`]).
pub fn compare_with(
    summary: &Summary,
    baseline: &Summary,
    tolerance: Real,
    trials: Option<(&Trials, &Trials)>,
) -> Vec<Compared> {
    let new = &summary.results;
    let counts = [baseline.trials, summary.trials];
    let trials = trials.filter(|_| pairable(baseline, summary));
    let mut out = Vec::new();
    let mut changes = Vec::new();
    for b in &baseline.results {
        let key = b.key();
        let found = new.iter().find(|e| e.same_entry(b));
        for (metric, dir) in entry_metrics(b) {
            let Some(base) = lookup(b, &metric) else {
                continue;
            };
            let value = found.and_then(|e| lookup(e, &metric)).unwrap_or(Real::NAN);
            let mut not_the_figures = false;
            let change = found.filter(|_| value.is_finite()).map(|e| {
                let paired = trials.and_then(|(ta, tb)| {
                    let keys = (
                        noise::trials_key(b, baseline),
                        noise::trials_key(e, summary),
                    );
                    noise::paired(ta, tb, (&keys.0, &keys.1), &metric)
                });
                not_the_figures = paired.as_ref().is_some_and(|c| !c.matches(base, value));
                paired
                    .filter(|c| c.matches(base, value))
                    .unwrap_or_else(|| noise::unpaired(b, e, &metric, (base, value), counts))
            });
            let located = change.as_ref().map(|c| c.sorted.is_some());
            changes.push(change);
            out.push(Compared {
                median: located == Some(true),
                higher_is_better: dir == Better::Higher,
                regressed: !value.is_finite(),
                status: Status::Regression,
                diff_ci: None,
                p_value: Real::NAN,
                p_holm: Real::NAN,
                paired: changes
                    .last()
                    .is_some_and(|c| c.as_ref().is_some_and(|c| c.paired)),
                not_the_figures,
                trials_needed: None,
                metric: Regression {
                    entry: key.clone(),
                    metric,
                    baseline: base,
                    value,
                },
            });
        }
    }
    let p: Vec<Real> = changes
        .iter()
        .map(|c| c.as_ref().map_or(Real::NAN, Change::p_value))
        .collect();
    let (p_holm, steps) = noise::holm(&p);
    let m = p.iter().filter(|p| !p.is_nan()).count().max(1);
    for (i, c) in out.iter_mut().enumerate() {
        let Some(change) = &changes[i] else {
            continue;
        };
        let dir = if c.higher_is_better {
            Better::Higher
        } else {
            Better::Lower
        };
        let (value, base) = (c.metric.value, c.metric.baseline);
        let worse = regressed(value, base, tolerance, dir);
        let better = regressed(
            base,
            value,
            tolerance * base.abs() / value.abs().max(Real::MIN_POSITIVE),
            dir,
        );
        // Rejected by the Holm step and shown so: the interval at the step's level leaves
        // zero out. The paired rank test may reject where the interval of the report's test
        // of the pair (the mean's t, or the median's) still holds zero; such a change is not
        // resolved.
        let interval = change.interval(ALPHA / steps[i] as Real);
        let excludes_zero = interval[0] > 0.0 || interval[1] < 0.0;
        let significant = p_holm[i] < ALPHA && excludes_zero;
        c.status = match (worse, better, significant) {
            (true, _, true) => Status::Regression,
            (true, _, false) => Status::Unresolved,
            (_, true, true) => Status::Improved,
            (_, _, true) => Status::Changed,
            _ => Status::NoChange,
        };
        c.regressed = c.status == Status::Regression;
        c.p_value = p[i];
        c.p_holm = p_holm[i];
        c.diff_ci = Some(interval);
        if c.status == Status::Unresolved {
            c.trials_needed = change.trials_needed(tolerance * base.abs(), ALPHA / m as Real);
        }
    }
    out
}

/// Refuses a summary and a baseline (each read by [`check_summary`]) that cannot be compared,
/// naming the file, the key and its line: they are summaries of
/// different scenarios (their `scenario` names differ), or they share no
/// metric — no baseline entry has a compared metric that the summary's entry of the same
/// method, poses and swept value also has — so a comparison would guard nothing. Which file
/// is short is said: a baseline without entries; a summary without entries, or without any
/// of the baseline's (the missing entries are listed), or whose entries lack every metric the
/// baseline's have; a baseline whose entries have no compared metric.
pub fn comparable(
    summary: &Summary,
    summary_path: &Path,
    baseline: &Summary,
    baseline_path: &Path,
) -> Result<()> {
    let (s, b) = (&summary.scenario, &baseline.scenario);
    if s != b {
        return Err(Error::file(
            baseline_path,
            "scenario",
            format!(
                "is \"{b}\", but {} is a summary of scenario \"{s}\": a baseline must come \
                 from the same scenario",
                summary_path.display()
            ),
        )
        .at_json_key_line());
    }
    let (new, old) = (&summary.results, &baseline.results);
    let listed = |v: Vec<String>| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.join(", ")
        }
    };
    let keys = |v: &[Entry]| listed(v.iter().map(Entry::key).collect());
    let results = |path: &Path, msg: String| Error::file(path, "results", msg).at_json_key_line();
    if old.is_empty() {
        return Err(results(
            baseline_path,
            format!(
                "is empty: the baseline has no entries, so it shares no metric with {}: \
                 nothing to guard",
                summary_path.display()
            ),
        ));
    }
    if new.is_empty() {
        return Err(results(
            summary_path,
            format!(
                "is empty: the summary has no entries, so it shares no metric with {}: every \
                 baseline entry is missing ({})",
                baseline_path.display(),
                keys(old)
            ),
        ));
    }
    let matched: Vec<&Entry> = old
        .iter()
        .filter(|b| new.iter().any(|e| e.same_entry(b)))
        .collect();
    if matched.is_empty() {
        return Err(results(
            summary_path,
            format!(
                "shares no metric with {}: it has none of the baseline's entries (missing: {}; \
                 here: {}; entries are matched by method, poses and sweep value)",
                baseline_path.display(),
                keys(old),
                keys(new)
            ),
        ));
    }
    let has = |e: &Entry, b: &Entry| {
        entry_metrics(b)
            .iter()
            .any(|(m, _)| present(b, m) && present(e, m))
    };
    let shared = matched
        .iter()
        .any(|b| new.iter().filter(|e| e.same_entry(b)).any(|e| has(e, b)));
    if !shared {
        // The baseline's matched entries have metrics the summary's lack: the summary is short.
        let wanted: Vec<String> = matched
            .iter()
            .flat_map(|b| {
                entry_metrics(b)
                    .into_iter()
                    .filter(|(m, _)| present(b, m))
                    .map(|(m, _)| format!("{} {m}", b.key()))
                    .collect::<Vec<_>>()
            })
            .collect();
        if !wanted.is_empty() {
            return Err(results(
                summary_path,
                format!(
                    "shares no metric with {}: its entries lack every compared metric the \
                     baseline has (missing: {})",
                    baseline_path.display(),
                    listed(wanted)
                ),
            ));
        }
        return Err(results(
            baseline_path,
            format!(
                "shares no metric with {}: nothing to compare (baseline entries: {}; \
                 entries are matched by method, poses and sweep value)",
                summary_path.display(),
                keys(old)
            ),
        ));
    }
    Ok(())
}

/// Whether entry `e` carries the figure `path`: a listed parameter's RMSE, or a finite
/// figure. A `null` figure and one an older file lacks both read as NaN
/// (`study::stats::missing`); the count of failures, which every entry has (0 when the file
/// lacks it), does not by itself make an entry comparable, so an entry that names nothing but
/// its method and poses carries nothing. (An entry whose every trial failed still lists its
/// parameters.)
fn present(e: &Entry, path: &str) -> bool {
    Metric::from_key(path) != Some(Metric::Failures)
        && e.figure(path)
            .is_some_and(|(v, _)| !v.is_nan() || Metric::ParamRmse.parameter_of(path).is_some())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{json, Value};

    fn doc(eta: Real, rms: Real) -> Value {
        json!({"scenario": "s", "results": [{"method": "ls", "poses": "random", "eta_mean_pct": eta,
            "validation_after_mm": {"mean": rms, "rms": rms, "max": 2.0 * rms, "std": 0.1},
            "param_rmse": {"a2": 0.01}, "failures": 0}]})
    }

    fn typed(v: Value) -> Summary {
        check_summary(v, Path::new("t.json")).unwrap()
    }

    fn summary(eta: Real, rms: Real) -> Summary {
        typed(doc(eta, rms))
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
        let mut s = doc(90.0, 0.1);
        s["results"][0]["method"] = json!("lm");
        assert!(!compare(&typed(s), &summary(90.0, 0.1), 0.05).is_empty());
    }

    #[test]
    fn a_figure_the_summary_lacks_is_a_regression_not_a_zero() {
        let mut s = doc(90.0, 0.1);
        s["results"][0]
            .as_object_mut()
            .unwrap()
            .remove("validation_after_mm");
        let r = compare(&typed(s), &summary(90.0, 0.1), 0.05);
        assert!(
            r.iter()
                .any(|r| r.metric == "validation_after_mm.rms" && r.value.is_nan()),
            "{r:?}"
        );
    }

    #[test]
    fn a_change_of_exactly_the_tolerance_is_a_regression() {
        // 5 % worse, exactly: 0.1 → 0.105 mm, 90 → 85.5 %.
        let r = compare(&summary(85.5, 0.105), &summary(90.0, 0.1), 0.05);
        let names: Vec<&str> = r.iter().map(|r| r.metric.as_str()).collect();
        assert!(names.contains(&"eta_mean_pct"), "{names:?}");
        assert!(names.contains(&"validation_after_mm.rms"), "{names:?}");
        assert!(names.contains(&"validation_after_mm.max"), "{names:?}");
        // Exactly the tolerance on values whose decimal forms round differently.
        for (base, tol) in [(0.3, 0.05), (0.7, 0.1), (1.1, 0.02), (123.456, 0.03)] {
            let worse = base * (1.0 + tol);
            let r = compare(&summary(90.0, worse), &summary(90.0, base), tol);
            assert!(
                r.iter().any(|r| r.metric == "validation_after_mm.rms"),
                "{base} → {worse} at {tol}"
            );
        }
        // Just inside the tolerance, and equal values with a zero tolerance, pass.
        assert!(compare(&summary(85.6, 0.1049), &summary(90.0, 0.1), 0.05).is_empty());
        assert!(compare(&summary(90.0, 0.1), &summary(90.0, 0.1), 0.0).is_empty());
    }

    /// Reads both documents as `check` does and compares them: the error's text.
    fn read_and_compare(s: &Value, b: &Value) -> Result<()> {
        let (sp, bp) = (Path::new("new/summary.json"), Path::new("old/base.json"));
        let (s, b) = (check_summary(s.clone(), sp)?, check_summary(b.clone(), bp)?);
        comparable(&s, sp, &b, bp)
    }

    fn refused(s: &Value, b: &Value, file: &str, key: &str) {
        let e = read_and_compare(s, b).expect_err("accepted").to_string();
        assert!(
            e.contains(file) && e.contains(key),
            "`{e}` lacks {file} or {key}"
        );
    }

    #[test]
    fn files_that_are_not_summaries_are_refused_naming_the_file() {
        let good = doc(90.0, 0.1);
        read_and_compare(&good, &good).unwrap();
        for (bad, key) in [
            (json!({}), "results"),
            (json!({"results": []}), "scenario"),
            (json!({"scenario": "s"}), "results"),
            (json!({"scenario": "s", "results": 3}), "results"),
            (json!({"scenario": "s", "results": {"a": 1}}), "results"),
            (json!({"scenario": 7, "results": []}), "scenario"),
            (json!([1, 2]), "not a calbench summary"),
            (json!({"scenario": "s", "results": [1]}), "results[0]"),
            (
                json!({"scenario": "s", "results": [{"poses": "x"}]}),
                "method",
            ),
            // A figure of the wrong type, a key renamed to one that is not a figure's.
            (
                json!({"scenario": "s", "results": [{"method": "ls", "failures": "none"}]}),
                "results[0].failures",
            ),
            (
                json!({"scenario": "s", "results": [{"method": "ls",
                    "validation_after_mm": {"mean": 0.1, "rms": 0.1, "std": 0.1}}]}),
                "max",
            ),
            (
                json!({"scenario": "s", "results": [], "format": 2}),
                "format",
            ),
        ] {
            refused(&good, &bad, "old/base.json", key);
            refused(&bad, &good, "new/summary.json", key);
        }
    }

    #[test]
    fn a_summary_without_the_baselines_entries_says_what_is_missing() {
        let good = summary(90.0, 0.1);
        let (s, b) = (Path::new("new/summary.json"), Path::new("old/base.json"));
        // Summaries built in code: a file of no entry is refused when it is read.
        let empty = Summary::from_value(json!({"scenario": "s", "results": []}), s).unwrap();
        let e = comparable(&empty, s, &good, b).unwrap_err().to_string();
        assert!(
            e.starts_with("new/summary.json: results: is empty")
                && e.contains("every baseline entry is missing (ls / random)"),
            "{e}"
        );
        let e = comparable(&good, s, &empty, b).unwrap_err().to_string();
        assert!(e.starts_with("old/base.json: results: is empty"), "{e}");
        let mut lm = good.clone();
        lm.results[0].method = "lm".into();
        let e = comparable(&lm, s, &good, b).unwrap_err().to_string();
        assert!(
            e.starts_with("new/summary.json: results: ")
                && e.contains("missing: ls / random; here: lm / random"),
            "{e}"
        );
        let bare =
            typed(json!({"scenario": "s", "results": [{"method": "ls", "poses": "random"}]}));
        let e = comparable(&bare, s, &good, b).unwrap_err().to_string();
        assert!(
            e.starts_with("new/summary.json: results: ") && e.contains("ls / random eta_mean_pct"),
            "{e}"
        );
    }

    #[test]
    fn the_line_of_results_is_named() {
        let dir = crate::test_dir("check");
        let path = dir.join("s.json");
        // Two keys before it that hold "results" as a key and as a text.
        let text = "{\n  \"separation\": {\"results\": 1},\n  \"description\": \"results\",\n  \
                    \"results\": []\n}\n";
        std::fs::write(&path, text).unwrap();
        assert_eq!(crate::error::json_key_line(text, "results"), Some(4));
        assert_eq!(crate::error::json_key_line(text, "scenario"), None);
        let mut v: Value = serde_json::from_str(text).unwrap();
        v["scenario"] = json!("s");
        let e = comparable(
            &Summary::from_value(v, &path).unwrap(),
            &path,
            &summary(90.0, 0.1),
            Path::new("b"),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("s.json: line 4, results: is empty"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn unrelated_baselines_are_refused() {
        let good = doc(90.0, 0.1);
        let mut other = good.clone();
        other["scenario"] = json!("another");
        refused(&good, &other, "old/base.json", "scenario");
        let empty = json!({"scenario": "s", "results": []});
        refused(&good, &empty, "old/base.json", "shares no metric");
        // Entries of other methods only, or entries without compared metrics.
        let mut lm = good.clone();
        lm["results"][0]["method"] = json!("lm");
        refused(&good, &lm, "new/summary.json", "shares no metric");
        let bare = json!({"scenario": "s", "results": [{"method": "ls", "poses": "random"}]});
        refused(&good, &bare, "old/base.json", "shares no metric");
        // One shared metric is enough; the rest missing are regressions.
        let mut two = good.clone();
        two["results"]
            .as_array_mut()
            .unwrap()
            .push(lm["results"][0].clone());
        read_and_compare(&good, &two).unwrap();
        assert!(!compare(&typed(good), &typed(two), 0.05).is_empty());
    }
}
