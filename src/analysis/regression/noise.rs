//! Telling a change from Monte-Carlo noise (docs/formats.md § 8.4): each compared metric gets
//! the interval of its change and a p-value, Holm-adjusted over the metrics compared, and one
//! of the statuses of [`Status`].
//!
//! Paired when both sides hold per-trial values (a run's `trials.csv`, or the `per_trial` of a
//! baseline file, [`super::baseline`]) and share the scenario, the seed, the sweep and the
//! trials (a sweep's entries point by point): the p-value is that of the Wilcoxon signed-rank
//! test of the per-trial differences, the one test the report's comparisons of two entries
//! use ([`crate::study::stats::paired::compare`]), and the interval shown is the t interval of
//! their mean on n − 1 degrees of freedom. Otherwise unpaired, from the summaries: Welch's
//! interval from each side's 95 % interval of the figure (its half-width over t₀.₉₇₅ is the
//! standard error); a side without intervals (a summary from before they were written) borrows
//! the other's spread over trials, as does a side of a single usable trial, which has none;
//! with neither, the change is taken as exact, as the plain rule of the tolerance always did,
//! unless the summaries write intervals and lack only this figure's (a median's under the
//! trials its interval needs) or a side has a single usable trial: its noise is then not
//! known, and the change is never resolved. A change within the rounding of the numbers
//! (1e-12 of their size, per trial or in the summaries) is no change.

use std::collections::{BTreeMap, BTreeSet};

use serde_json::Value;

use crate::analysis::summary::Summary;
use crate::numeric::dist;
use crate::numeric::Real;
use crate::study::metric::Metric;
use crate::study::stats::location::Test;
use crate::study::stats::paired::compare;
use crate::study::stats::{median_ranks, same_json, Entry};

/// What a compared metric did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Worse by the tolerance or more, and the (Holm-adjusted) interval of the change
    /// excludes zero; or missing, or not finite. `check` fails.
    Regression,
    /// Worse by the tolerance or more, but the interval includes zero: more trials would
    /// tell. `check --strict` fails.
    Unresolved,
    /// Within the tolerance, and the interval excludes zero: a real change, allowed.
    Changed,
    /// Better by the tolerance or more, and the interval excludes zero.
    Improved,
    /// Anything else.
    NoChange,
}

impl Status {
    /// The status as the reports write it.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Regression => "regression",
            Status::Unresolved => "unresolved",
            Status::Changed => "changed, within tolerance",
            Status::Improved => "improved",
            Status::NoChange => "no change",
        }
    }
}

/// The statistics of one change: B − A, its standard error and degrees of freedom, or that
/// it is exact.
#[derive(Clone, Debug)]
pub struct Change {
    /// Standard error of the change (0: exact).
    pub se: Real,
    /// Degrees of freedom of the t distribution (infinite: normal).
    pub df: Real,
    /// Trials behind it (per run).
    pub n: usize,
    /// Whether it came from per-trial differences.
    pub paired: bool,
    /// For `param_rmse`, compared as mean squared errors: A's mean squared error, so that
    /// an interval of the squared error maps back to one of the RMSE.
    pub mse_a: Option<Real>,
    /// The change in the tested scale (B − A; squared errors for `param_rmse`).
    pub diff: Real,
    /// Paired: the means over the paired trials of A's and B's values (for `param_rmse`
    /// the root of the mean squared error), which must be the summaries' figures for the
    /// per-trial values to be those of the summaries ([`Change::matches`]).
    pub means: Option<[Real; 2]>,
    /// Paired: the two-sided p-value of the Wilcoxon signed-rank test of the per-trial
    /// differences (1 when every difference is within rounding), which decides; `None`
    /// unpaired (the t or z test of `diff` over `se`).
    pub p_test: Option<Real>,
    /// Paired, when the location rule of the report's comparison of the pair picks the sign
    /// test (heavy-tailed differences, docs/formats.md "Tests and margins"): the per-trial
    /// differences in the tested scale, sorted, whose median and its distribution-free
    /// interval are the change's interval ([`Change::interval`]); `None`: the t interval.
    pub sorted: Option<Vec<Real>>,
}

/// Whether `a` and `b` differ by no more than the rounding of decimal numbers (1e-12 of the
/// larger): such a change is no change.
pub fn within_rounding(a: Real, b: Real) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
}

/// The per-trial values of a run's `trials.csv`, by entry key (`method / poses`) and metric
/// key, each a map from trial index to value (only trials whose identification is usable).
#[derive(Debug, Default)]
pub struct Trials {
    /// (entry, metric) → trial → value.
    pub values: BTreeMap<(String, String), BTreeMap<usize, Real>>,
    /// Every trial index of each entry, usable or not.
    pub trials: BTreeMap<String, BTreeSet<usize>>,
    /// The line of a `trials.csv` where each entry's first row stands (empty for a
    /// baseline's own values), for a refusal of the entry.
    pub first_line: BTreeMap<String, usize>,
}

/// Whether two runs can be compared trial by trial: [`differs`] finds nothing.
pub fn pairable(a: &Summary, b: &Summary) -> bool {
    differs(a, b).is_none()
}

/// The first key in which two runs differ that keeps them from being compared trial by
/// trial, with `a`'s value and `b`'s as each summary writes it (`null`: not written): the
/// scenario, the seed (which `a` must give), the trial count when both give it, the swept
/// keys and their values (compared by value). `None`: they pair, each entry by the trials it
/// holds on both sides.
pub fn differs(a: &Summary, b: &Summary) -> Option<(&'static str, Value, Value)> {
    let agree = |s: &Summary| -> [(&'static str, Value); 5] {
        let json = |v: serde_json::Result<Value>| v.unwrap_or(Value::Null);
        [
            ("scenario", Value::String(s.scenario.clone())),
            ("seed", json(serde_json::to_value(s.seed))),
            ("trials", json(serde_json::to_value(s.trials))),
            ("sweep_keys", json(serde_json::to_value(&s.sweep_keys))),
            ("sweep_values", json(serde_json::to_value(&s.sweep_values))),
        ]
    };
    agree(a)
        .into_iter()
        .zip(agree(b))
        .find(|((key, x), (_, y))| {
            let missing_seed = *key == "seed" && x.is_null();
            // A summary that does not say its trials pairs entry by entry.
            let unsaid_trials = *key == "trials" && (x.is_null() || y.is_null());
            (!same_json(x, y) || missing_seed) && !unsaid_trials
        })
        .map(|((key, x), (_, y))| (key, x, y))
}

/// The key of summary entry `e` of `summary` in its run's [`Trials`]: `method / poses`, and
/// in a sweep ` @ k`, k the place of the entry's `sweep_value` among the summary's distinct
/// sweep values in `results` order (the order in which `trials.csv` holds the points).
pub fn trials_key(e: &Entry, summary: &Summary) -> String {
    let plain = format!("{} / {}", e.method, e.poses);
    let Some(v) = &e.sweep_value else {
        return plain;
    };
    let mut seen: Vec<&serde_json::Value> = Vec::new();
    for x in summary
        .results
        .iter()
        .filter_map(|r| r.sweep_value.as_ref())
    {
        if !seen.contains(&x) {
            seen.push(x);
        }
    }
    match seen.iter().position(|x| *x == v) {
        Some(k) => format!("{plain} @ {k}"),
        None => plain,
    }
}

/// The paired change of `metric` from entry `ka` of `a` to entry `kb` of `b` (their
/// [`trials_key`]s), when both hold the same trials of the entry and at least 2 are usable
/// in both.
pub fn paired(a: &Trials, b: &Trials, (ka, kb): (&str, &str), metric: &str) -> Option<Change> {
    if a.trials.get(ka)? != b.trials.get(kb)? {
        return None;
    }
    let (va, vb) = (
        a.values.get(&(ka.to_string(), metric.to_string()))?,
        b.values.get(&(kb.to_string(), metric.to_string()))?,
    );
    let pairs: Vec<(Real, Real)> = va
        .iter()
        .filter_map(|(i, x)| {
            let y = *vb.get(i)?;
            // A difference within rounding is none: the test sees a zero.
            Some((*x, if within_rounding(*x, y) { *x } else { y }))
        })
        .collect();
    let n = pairs.len();
    if n < 2 {
        return None;
    }
    let (xa, xb): (Vec<Real>, Vec<Real>) = pairs.iter().copied().unzip();
    // The report's paired comparison of two entries, on the same per-trial values: its
    // Wilcoxon p-value decides, its mean difference is the change.
    let m = Metric::from_key(metric).unwrap_or(Metric::ParamRmse);
    let test = compare((ka, kb), m, (&xa, &xb));
    let mean = test.diff_mean;
    let d: Vec<Real> = pairs.iter().map(|(x, y)| y - x).collect();
    let means = Some([
        figure_of(pairs.iter().map(|p| p.0), metric),
        figure_of(pairs.iter().map(|p| p.1), metric),
    ]);
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<Real>() / (n - 1) as Real;
    // The report's test of the pair: where it locates the median, so does the interval.
    let sorted = (test.test == Test::Sign).then(|| {
        let mut v = d.clone();
        v.sort_by(Real::total_cmp);
        v
    });
    Some(Change {
        se: (var / n as Real).sqrt(),
        df: (n - 1) as Real,
        n,
        paired: true,
        mse_a: is_rmse(metric).then(|| pairs.iter().map(|p| p.0).sum::<Real>() / n as Real),
        diff: mean,
        means,
        p_test: Some(if test.p_value.is_nan() {
            1.0
        } else {
            test.p_value
        }),
        sorted,
    })
}

/// The figure of `metric` that per-trial `values` give, as a summary writes it: their mean,
/// or for a parameter's RMSE (whose per-trial values are squared errors) the root of it.
pub fn figure_of(values: impl Iterator<Item = Real>, metric: &str) -> Real {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    let m = sum / n as Real;
    if is_rmse(metric) {
        m.sqrt()
    } else {
        m
    }
}

/// Whether a figure computed from per-trial values is the summary's `b` (to 1e-9 relative:
/// the summary sums in another order).
pub fn same_figure(a: Real, b: Real) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

/// Whether `metric` is a parameter's RMSE (`param_rmse.NAME`).
pub(super) fn is_rmse(metric: &str) -> bool {
    Metric::ParamRmse.parameter_of(metric).is_some()
}

/// Whether summary entry `e` is of a summary that writes intervals (its validation error's):
/// one written before them has none.
fn writes_intervals(e: &Entry) -> bool {
    e.validation_after_mm.mean_ci95.is_some() || e.eta_mean_pct_ci95.is_some()
}

/// The usable trials of summary entry `e`: `trials` − `failures`.
fn usable_trials(e: &Entry, trials: Option<usize>) -> Option<usize> {
    trials?.checked_sub(e.failures)
}

/// The standard error of a summary's figure at `path` of entry `e` over its `n` usable
/// trials, from its 95 % interval ([`Entry::figure`]: `<path>_ci95`, or
/// `param_rmse_ci95.<name>` for an RMSE, whose interval is compared on the squared scale).
fn summary_se(e: &Entry, path: &str, n: usize) -> Option<Real> {
    if n < 2 {
        return None;
    }
    let [lo, hi] = e.figure(path)?.1?;
    let (lo, hi) = if is_rmse(path) {
        (lo * lo, hi * hi)
    } else {
        (lo, hi)
    };
    let q = if Metric::from_key(path) == Some(Metric::EtaMedian) {
        // Not a t interval: its half-width taken as 1.96 standard errors.
        dist::normal_quantile(0.975)
    } else {
        dist::t_quantile(0.975, (n - 1) as Real)
    };
    Some((hi - lo) / (2.0 * q))
}

/// The unpaired change of `metric` from the baseline entry `a` (value `va`) to `b` (`vb`),
/// with `trials` the `trials` of each summary: Welch from the two standard errors; a side
/// without one borrows the other's; exact when neither has one and neither writes intervals
/// nor is of a single usable trial, else of unknown noise (never resolved). Failures are
/// compared as proportions of the trials (pooled two-proportion z).
pub fn unpaired(
    a: &Entry,
    b: &Entry,
    metric: &str,
    (va, vb): (Real, Real),
    trials: [Option<usize>; 2],
) -> Change {
    // A change within rounding is none.
    let vb = if within_rounding(va, vb) { va } else { vb };
    let exact = Change {
        se: 0.0,
        df: Real::INFINITY,
        n: trials[1].unwrap_or(0),
        paired: false,
        mse_a: None,
        diff: vb - va,
        means: None,
        p_test: None,
        sorted: None,
    };
    if Metric::from_key(metric) == Some(Metric::Failures) {
        let (Some(na), Some(nb)) = (trials[0], trials[1]) else {
            return exact;
        };
        if na == 0 || nb == 0 {
            return exact;
        }
        let pooled = (va + vb) / (na + nb) as Real;
        // The change in counts at B's trial count.
        let se =
            (pooled * (1.0 - pooled) * (1.0 / na as Real + 1.0 / nb as Real)).sqrt() * nb as Real;
        return Change {
            se,
            diff: vb / nb as Real * nb as Real - va / na as Real * nb as Real,
            ..exact
        };
    }
    // Summaries that write intervals but not of this figure at these trials (too few for a
    // median's), or not the trials their intervals were taken over (a `trials` deleted): its
    // noise is not known, and the change is not resolved.
    let unknown = Change {
        se: Real::INFINITY,
        ..exact.clone()
    };
    let intervals = writes_intervals(a) || writes_intervals(b);
    let (Some(na), Some(nb)) = (usable_trials(a, trials[0]), usable_trials(b, trials[1])) else {
        return if intervals { unknown } else { exact };
    };
    // A single usable trial (or none) says nothing of the figure's spread, in a summary of
    // any format: it had been taken as exact, so that two one-trial runs of other seeds gave
    // certain regressions.
    let single = na < 2 || nb < 2;
    if na == 0 || nb == 0 {
        return unknown;
    }
    // A side without an interval borrows the other's spread over trials, scaled to its own
    // number of trials; of a single trial, with the degrees of freedom of the spread it
    // borrows.
    let (se_a, se_b) = match (summary_se(a, metric, na), summary_se(b, metric, nb)) {
        (Some(x), Some(y)) => (x, y),
        (Some(x), None) => (x, x * (na as Real / nb as Real).sqrt()),
        (None, Some(y)) => (y * (nb as Real / na as Real).sqrt(), y),
        (None, None) if intervals || single => return unknown,
        (None, None) => return exact,
    };
    let (df_a, df_b) = match (na - 1, nb - 1) {
        (0, d) | (d, 0) => (d, d),
        dfs => dfs,
    };
    let se2 = se_a * se_a + se_b * se_b;
    let den = se_a.powi(4) / df_a as Real + se_b.powi(4) / df_b as Real;
    let rmse = is_rmse(metric);
    Change {
        se: se2.sqrt(),
        df: if den > 0.0 {
            se2 * se2 / den
        } else {
            Real::INFINITY
        },
        n: nb,
        paired: false,
        mse_a: rmse.then_some(va * va),
        diff: if rmse { vb * vb - va * va } else { vb - va },
        means: None,
        p_test: None,
        sorted: None,
    }
}

impl Change {
    /// Whether a paired change's per-trial values are those behind the figures `a` and `b`
    /// of the summaries (their means agree to 1e-9 relative): not so for two summaries of
    /// different trials in one folder, an edited summary, or trials whose usability the
    /// file cannot tell; those are compared unpaired.
    pub fn matches(&self, a: Real, b: Real) -> bool {
        self.means
            .is_none_or(|[ma, mb]| same_figure(ma, a) && same_figure(mb, b))
    }

    /// The two-sided p-value of "no change": paired, the Wilcoxon signed-rank test's;
    /// unpaired, the t (z) test's of the change over its standard error, and for an exact
    /// change 0, or 1 when it is within rounding; 1 for a change whose noise is not known
    /// (an infinite standard error).
    pub fn p_value(&self) -> Real {
        if let Some(p) = self.p_test {
            return p;
        }
        if self.se == Real::INFINITY {
            return 1.0;
        }
        if self.se == 0.0 || !self.se.is_finite() {
            return if self.diff == 0.0 || self.diff.is_nan() {
                1.0
            } else {
                0.0
            };
        }
        dist::t_two_sided(self.diff / self.se, self.df)
    }

    /// The interval of the change at level 1 − `alpha`, in the metric's units (for an RMSE,
    /// mapped back from the squared errors around A's RMSE): the test's of the report's
    /// comparison of the pair — the t interval of the mean, or, where the report locates
    /// the median ([`Change::sorted`]), the distribution-free interval of the median
    /// (order statistics of ranks [`median_ranks`] at that level; the extreme differences
    /// when even they do not reach it).
    pub fn interval(&self, alpha: Real) -> [Real; 2] {
        let (lo, hi) = match &self.sorted {
            Some(v) if !v.is_empty() => {
                let (l, u) = median_ranks(v.len(), alpha).unwrap_or((0, v.len() - 1));
                (v[l], v[u])
            }
            _ => {
                let h = if self.se == 0.0 {
                    0.0
                } else {
                    dist::t_quantile(1.0 - alpha / 2.0, self.df) * self.se
                };
                (self.diff - h, self.diff + h)
            }
        };
        match self.mse_a {
            Some(m) => {
                let r = m.sqrt();
                [(m + lo).max(0.0).sqrt() - r, (m + hi).max(0.0).sqrt() - r]
            }
            None => [lo, hi],
        }
    }

    /// The trials per run that would detect a change of `effect` (in the metric's units,
    /// positive) with 80 % power at level `alpha` (two-sided): (z₁₋α/₂ + z₀.₈)² σ² /
    /// effect², σ² the per-trial variance behind the standard error. For an RMSE the effect
    /// is taken on the squared scale at A's RMSE, `(√m + e)² − m = e (2√m + e)` (written so
    /// that an effect of 0 stays 0, where the difference left a rounding error). Paired, at
    /// least the trials whose smallest Wilcoxon p-value (every difference of one sign,
    /// 2 / 2ⁿ) is below `alpha`. `None` for an effect of 0, and for a count beyond any whole
    /// number of trials (≥ 2⁶⁴), which had been shown as 18446744073709551615.
    pub fn trials_needed(&self, effect: Real, alpha: Real) -> Option<usize> {
        let effect = match self.mse_a {
            Some(m) => effect * (2.0 * m.sqrt() + effect),
            None => effect,
        };
        if effect.is_nan() || effect <= 0.0 || self.se == 0.0 || self.n == 0 {
            return None;
        }
        let z = dist::normal_quantile(1.0 - alpha / 2.0) + dist::normal_quantile(0.8);
        let var = self.se * self.se * self.n as Real;
        let need = (z * z * var / (effect * effect)).ceil();
        if need.is_nan() || need >= usize::MAX as Real {
            return None;
        }
        let by_power = need as usize;
        let floor = if self.paired {
            (2.0 / alpha).log2().floor() as usize + 1
        } else {
            0
        };
        Some(by_power.max(floor))
    }
}

pub use crate::study::stats::paired::holm;

#[cfg(test)]
mod tests {
    use super::*;

    /// Two runs' per-trial values of one entry: a, and b = a + `d` trial by trial.
    fn runs(a: &[Real], d: &[Real]) -> (Trials, Trials) {
        let key = (
            "ls / random".to_string(),
            "validation_after_mm.rms".to_string(),
        );
        let side = |v: Vec<Real>| {
            let mut t = Trials::default();
            t.values
                .insert(key.clone(), v.into_iter().enumerate().collect());
            t.trials
                .insert(key.0.clone(), (0..a.len()).collect::<BTreeSet<_>>());
            t
        };
        let b = a.iter().zip(d).map(|(x, y)| x + y).collect();
        (side(a.to_vec()), side(b))
    }

    #[test]
    fn a_paired_change_has_the_interval_of_the_reports_test_of_the_pair() {
        let a: Vec<Real> = (0..40).map(|i| 1.0 + 0.01 * i as Real).collect();
        // Heavy-tailed differences (a few stalls): the report's comparison locates the
        // median, and so does the change's interval — at 95 % the report's interval itself.
        let heavy: Vec<Real> = (0..40)
            .map(|i| {
                if i % 13 == 0 {
                    0.75
                } else {
                    -0.01 + 1e-4 * i as Real
                }
            })
            .collect();
        // Light-tailed differences: the t interval of the mean, as the report's.
        let light: Vec<Real> = (0..40)
            .map(|i| 0.01 * ((i * 7 % 11) as Real - 5.0))
            .collect();
        let k = "ls / random";
        for (d, test) in [(&heavy, Test::Sign), (&light, Test::T)] {
            let (ta, tb) = runs(&a, d);
            let c = paired(&ta, &tb, (k, k), "validation_after_mm.rms").unwrap();
            let b: Vec<Real> = a.iter().zip(d).map(|(x, y)| x + y).collect();
            let report = compare((k, k), Metric::ValidationAfterRms, (&a, &b));
            assert_eq!(report.test, test);
            assert_eq!(c.sorted.is_some(), test == Test::Sign);
            let [lo, hi] = c.interval(0.05);
            let [rlo, rhi] = report.ci95.unwrap();
            assert!(
                (lo - rlo).abs() < 1e-12 && (hi - rhi).abs() < 1e-12,
                "{lo} {hi} {rlo} {rhi}"
            );
            if test == Test::Sign {
                // The t interval of the mean would hold the stalls' pull: far wider.
                let mean = Change {
                    sorted: None,
                    ..c.clone()
                }
                .interval(0.05);
                assert!(
                    mean[1] - mean[0] > 3.0 * (hi - lo),
                    "{mean:?} against [{lo}, {hi}]"
                );
            }
        }
    }

    #[test]
    fn an_exact_change_is_significant_unless_zero() {
        let c = Change {
            se: 0.0,
            df: Real::INFINITY,
            n: 8,
            paired: false,
            mse_a: None,
            diff: 0.1,
            means: None,
            p_test: None,
            sorted: None,
        };
        assert_eq!(c.p_value(), 0.0);
        assert_eq!(
            Change {
                diff: 0.0,
                ..c.clone()
            }
            .p_value(),
            1.0
        );
    }

    #[test]
    fn trials_needed_grow_with_the_noise() {
        let c = Change {
            se: 0.01,
            df: 99.0,
            n: 100,
            paired: true,
            mse_a: None,
            diff: 0.01,
            means: None,
            p_test: None,
            sorted: None,
        };
        // σ = 0.1, effect 0.02 at α = 0.05: (1.96 + 0.8416)² · 0.01 / 0.0004 = 196.2.
        assert_eq!(c.trials_needed(0.02, 0.05), Some(197));
        // An RMSE (mean squared error 0.0382² at A): a tolerance of 0 resolves nothing, as
        // for any other metric, where (√m + 0)² − m left a rounding error and a count of
        // 2⁶⁴ − 1; e = 0.001 is (2 · 0.0382 + 0.001) · 0.001 = 7.74e-5 on the squared scale.
        let rmse = Change {
            mse_a: Some(0.0382 * 0.0382),
            ..c.clone()
        };
        assert_eq!(rmse.trials_needed(0.0, 0.05), None);
        let e2 = 0.001 * (2.0 * 0.0382 + 0.001);
        let want = (2.8016_f64.powi(2) * 0.01 / (e2 * e2)).ceil();
        let got = rmse.trials_needed(0.001, 0.05).unwrap() as f64;
        assert!((got - want).abs() <= want * 1e-3, "{got} {want}");
        // A count beyond any whole number of trials is none, not 2⁶⁴ − 1.
        let wide = Change { se: 1e9, ..c };
        assert_eq!(wide.trials_needed(1e-9, 0.05), None);
    }
}
