//! Paired comparisons of the entries of a study that share their draws (docs/formats.md
//! "comparisons"): the per-trial differences of a headline metric between two entries run on
//! the same trials, their mean and t interval, the share of trials one wins, the Wilcoxon
//! signed-rank test computed as `scipy.stats.wilcoxon` does by default, and Holm's adjustment.

use serde::{Deserialize, Serialize};

use super::dist;
use super::location::{choose, paired_verdict, About, Located, Margin, Paired, Test};
use crate::numeric::nan;
use crate::numeric::Real;
use crate::study::metric::Metric;

/// One paired comparison of `summary.json`'s `comparisons`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Comparison {
    /// The first entry, `method / poses`.
    pub a: String,
    /// The second entry.
    pub b: String,
    /// With a sweep: the swept value of both.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sweep_value: Option<serde_json::Value>,
    /// The metric compared (its key in the entries).
    pub metric: Metric,
    /// Trials usable in both.
    pub n: usize,
    /// Mean over those trials of b − a.
    #[serde(deserialize_with = "nan::real")]
    pub diff_mean: Real,
    /// Its 95 % t interval (`null` under 2 trials).
    pub diff_ci95: Option<[Real; 2]>,
    /// Mean of b over mean of a, for a metric on a ratio scale (errors); `null` otherwise.
    pub ratio: Option<Real>,
    /// Share of the trials where b is strictly better than a.
    #[serde(deserialize_with = "nan::real")]
    pub win_rate: Real,
    /// Two-sided p-value of the Wilcoxon signed-rank test of b − a ([`wilcoxon`]).
    #[serde(deserialize_with = "nan::real")]
    pub p_value: Real,
    /// `p_value` Holm-adjusted over every comparison of the study.
    #[serde(deserialize_with = "nan::real")]
    pub p_holm: Real,
    /// The test of the verdict (docs/formats.md "Tests and margins"): `t` (the mean of
    /// b − a), or `sign` (its median) when the differences are heavy-tailed.
    #[serde(default)]
    pub test: Test,
    /// The test's estimate of b − a (`null` in summaries before verdicts).
    pub estimate: Option<Real>,
    /// Its 95 % interval.
    pub ci95: Option<[Real; 2]>,
    /// The margin m of practical relevance, in the metric's unit.
    pub margin: Option<Real>,
    /// `better`, `worse` (b against a, beyond ± m), `equivalent` (inside ± m) or
    /// `unresolved`.
    pub verdict: Option<Paired>,
    /// For an unresolved verdict, the trials at which an interval as wide per trial would
    /// resolve it.
    pub trials_to_resolve: Option<u64>,
}

/// The number of subsets of {1, …, n} by their sum: the null distribution of the signed-rank
/// statistic times 2ⁿ (exact in f64 for n ≤ 50).
fn signed_rank_counts(n: usize) -> Vec<Real> {
    let top = n * (n + 1) / 2;
    let mut c = vec![0.0; top + 1];
    c[0] = 1.0;
    for k in 1..=n {
        for s in (k..=k * (k + 1) / 2).rev() {
            c[s] += c[s - k];
        }
    }
    c
}

/// The two-sided p-value of the Wilcoxon signed-rank test that the differences `d` are
/// symmetric about zero, as `scipy.stats.wilcoxon(d)` computes it (scipy 1.17, defaults
/// `zero_method="wilcox"`, `correction=False`, `method="auto"`): zeros are dropped; with at
/// most 50 differences, no zero and no tie, the exact null distribution; otherwise the normal
/// approximation with the tie correction of the variance. scipy's permutation test for ties
/// among at most 13 differences is replaced by the normal approximation here. NaN without a
/// non-zero difference.
pub fn wilcoxon(d: &[Real]) -> Real {
    let zeros = d.iter().filter(|&&x| x == 0.0).count();
    let mut nz: Vec<Real> = d.iter().copied().filter(|&x| x != 0.0).collect();
    let n = nz.len();
    if n == 0 {
        return Real::NAN;
    }
    nz.sort_by(|x, y| x.abs().total_cmp(&y.abs()));
    // Average ranks of |d|, and the tie groups.
    let (mut r_plus, mut tie_correct, mut ties) = (0.0, 0.0, false);
    let mut i = 0;
    while i < n {
        let mut j = i;
        while j + 1 < n && nz[j + 1].abs() == nz[i].abs() {
            j += 1;
        }
        let rank = (i + j) as Real / 2.0 + 1.0;
        let t = (j - i + 1) as Real;
        if j > i {
            ties = true;
        }
        tie_correct += t * t * t - t;
        r_plus += nz[i..=j].iter().filter(|&&x| x > 0.0).count() as Real * rank;
        i = j + 1;
    }
    let nf = n as Real;
    let mean = nf * (nf + 1.0) * 0.25;
    if d.len() <= 50 && !ties && zeros == 0 {
        let counts = signed_rank_counts(n);
        let total = (2.0 as Real).powi(n as i32);
        let pmf: Vec<Real> = counts.iter().map(|c| c / total).collect();
        let cdf = |k: usize| -> Real {
            if (k as Real) <= mean {
                pmf[..=k].iter().sum()
            } else {
                1.0 - pmf[k + 1..].iter().sum::<Real>()
            }
        };
        let sf = |k: usize| -> Real {
            if (k as Real) <= mean {
                pmf[k..].iter().sum()
            } else {
                1.0 - pmf[..k].iter().sum::<Real>()
            }
        };
        let k = r_plus as usize;
        return (2.0 * sf(k).min(cdf(k))).clamp(0.0, 1.0);
    }
    let se = ((nf * (nf + 1.0) * (2.0 * nf + 1.0) - tie_correct / 2.0) / 24.0).sqrt();
    let z = (r_plus - mean) / se;
    (2.0 * dist::normal_sf(z.abs())).min(1.0)
}

/// Holm's step-down adjustment of `p` (Holm 1979): the i-th smallest p times (m − i + 1),
/// made non-decreasing, at most 1; NaN stays NaN and does not count in m. Returns the
/// adjusted values and each one's step factor m − i + 1.
pub fn holm(p: &[Real]) -> (Vec<Real>, Vec<usize>) {
    let mut order: Vec<usize> = (0..p.len()).filter(|&i| !p[i].is_nan()).collect();
    order.sort_by(|&i, &j| p[i].total_cmp(&p[j]).then(i.cmp(&j)));
    let m = order.len();
    let mut out = vec![Real::NAN; p.len()];
    let mut steps = vec![1; p.len()];
    let mut running: Real = 0.0;
    for (rank, &i) in order.iter().enumerate() {
        running = running.max(((m - rank) as Real * p[i]).min(1.0));
        out[i] = running;
        steps[i] = m - rank;
    }
    (out, steps)
}

/// The paired comparison of `metric` between per-trial values `a` and `b` (aligned by trial,
/// NaN where a trial failed), the metric's direction saying which way wins, against the
/// metric's default margin; `p_holm` is left NaN for [`adjust`].
pub fn compare(labels: (&str, &str), metric: Metric, values: (&[Real], &[Real])) -> Comparison {
    compare_with(labels, metric, values, metric.default_margin())
}

/// [`compare`] against `margin` (relative to a's mean).
pub fn compare_with(
    labels: (&str, &str),
    metric: Metric,
    (a, b): (&[Real], &[Real]),
    margin: Margin,
) -> Comparison {
    let lower_is_better = metric.lower_is_better();
    let pairs: Vec<(Real, Real)> = a
        .iter()
        .zip(b)
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .map(|(&x, &y)| (x, y))
        .collect();
    let n = pairs.len();
    let d: Vec<Real> = pairs.iter().map(|(x, y)| y - x).collect();
    let mean = |v: &mut dyn Iterator<Item = Real>| -> Real {
        if n == 0 {
            Real::NAN
        } else {
            v.sum::<Real>() / n as Real
        }
    };
    let diff_mean = mean(&mut d.iter().copied());
    let sd = if n < 2 {
        Real::NAN
    } else {
        (d.iter().map(|x| (x - diff_mean).powi(2)).sum::<Real>() / (n - 1) as Real).sqrt()
    };
    let located = Located::of(&d, choose(About::Mean, &d));
    let m = margin.at(mean(&mut pairs.iter().map(|p| p.0)));
    let (verdict, trials_to_resolve) = paired_verdict(&located, m, lower_is_better);
    let wins = pairs
        .iter()
        .filter(|(x, y)| if lower_is_better { y < x } else { y > x })
        .count();
    Comparison {
        a: labels.0.to_string(),
        b: labels.1.to_string(),
        sweep_value: None,
        metric,
        n,
        diff_mean,
        diff_ci95: dist::t_interval(diff_mean, sd, n),
        ratio: lower_is_better
            .then(|| mean(&mut pairs.iter().map(|p| p.1)) / mean(&mut pairs.iter().map(|p| p.0)))
            .filter(|r| r.is_finite()),
        win_rate: if n == 0 {
            Real::NAN
        } else {
            wins as Real / n as Real
        },
        p_value: wilcoxon(&d),
        p_holm: Real::NAN,
        test: located.test,
        estimate: Some(located.estimate).filter(|e| e.is_finite()),
        ci95: located.ci95,
        margin: Some(m).filter(|m| m.is_finite()),
        verdict: Some(verdict),
        trials_to_resolve,
    }
}

/// Sets every comparison's `p_holm`: Holm over all of them.
pub fn adjust(c: &mut [Comparison]) {
    let p: Vec<Real> = c.iter().map(|c| c.p_value).collect();
    let (adj, _) = holm(&p);
    for (c, a) in c.iter_mut().zip(adj) {
        c.p_holm = a;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilcoxon_matches_scipy() {
        // scipy.stats.wilcoxon(d).pvalue, scipy 1.17.
        let exact = [0.5, -1.25, 2.0, 3.5, -0.25, 4.0, 1.5];
        assert!((wilcoxon(&exact) - 0.109375).abs() < 1e-15);
        // A tie (|0.5| twice) and a zero among 16: the normal approximation.
        let tied = [
            0.5, -0.5, 2.0, 3.5, 0.0, 4.0, 1.5, 2.5, -1.0, 3.0, 5.0, -2.25, 6.0, 7.0, 0.75, 8.0,
        ];
        let p = wilcoxon(&tied);
        assert!((p - 0.006968145590365646).abs() < 1e-9 * p, "{p}");
        assert_eq!(signed_rank_counts(3), [1.0, 1.0, 1.0, 2.0, 1.0, 1.0, 1.0]);
    }

    #[test]
    fn holm_by_hand() {
        // statsmodels' multipletests([0.01, 0.04, 0.03, 0.005], method="holm").
        let (p, s) = holm(&[0.01, 0.04, 0.03, 0.005, Real::NAN]);
        for (a, b) in p.iter().zip([0.03, 0.06, 0.06, 0.02]) {
            assert!((a - b).abs() < 1e-15, "{p:?}");
        }
        assert!(p[4].is_nan());
        assert_eq!(&s[..4], &[3, 1, 2, 4]);
    }
}
