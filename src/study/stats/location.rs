//! The one test of a location that the claims, the paired comparisons, `check` and `compare`
//! use (docs/formats.md "Tests and margins"): what a set of per-trial values (or paired
//! differences) says about its mean or its median, with a 95 % interval, the p-value of any
//! boundary, and the verdict of a paired comparison against a margin of practical relevance.
//!
//! The test is chosen by a rule fixed before any verdict is seen ([`choose`]): a statement
//! about the median is tested with the sign test (the distribution-free interval of the
//! median, Conover, *Practical Nonparametric Statistics*, § 3.2); a statement about the mean
//! with the t interval, unless the values are heavy-tailed ([`heavy_tailed`]: sample excess
//! kurtosis above [`HEAVY_KURTOSIS`]), where the t interval of the mean does not keep its
//! level, and the sign test of the median decides instead.

use serde::{Deserialize, Serialize};

use super::{dist, median_ranks};
use crate::numeric::Real;
pub use crate::study::margin::Margin;

/// What a statement is about.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum About {
    /// The mean over trials.
    #[default]
    Mean,
    /// The median over trials.
    Median,
}

impl About {
    /// Its name in scenarios and `summary.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            About::Mean => "mean",
            About::Median => "median",
        }
    }
}

/// The test that decided.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Test {
    /// Student's t interval of the mean.
    #[default]
    T,
    /// The sign test: the order-statistic interval of the median.
    Sign,
}

impl Test {
    /// Its name in `summary.json` and the reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Test::T => "t",
            Test::Sign => "sign",
        }
    }
}

/// The sample excess kurtosis above which values count as heavy-tailed: 3, the Laplace
/// (double-exponential) distribution's, the textbook boundary between the tails under which
/// the t interval of the mean keeps its level at the trial counts of a study and those under
/// which a few extreme trials decide it (Wilcox, *Introduction to Robust Estimation*, § 4.1).
pub const HEAVY_KURTOSIS: Real = 3.0;

/// The sample excess kurtosis g₂ = m₄ / m₂² − 3 (moments about the mean, divisor n); NaN
/// under 4 values or without spread.
pub fn excess_kurtosis(v: &[Real]) -> Real {
    let n = v.len();
    if n < 4 {
        return Real::NAN;
    }
    let nf = n as Real;
    let m = v.iter().sum::<Real>() / nf;
    let m2 = v.iter().map(|x| (x - m).powi(2)).sum::<Real>() / nf;
    let m4 = v.iter().map(|x| (x - m).powi(4)).sum::<Real>() / nf;
    if m2 <= 0.0 {
        return Real::NAN;
    }
    m4 / (m2 * m2) - 3.0
}

/// Whether `v` is heavy-tailed: its sample excess kurtosis exceeds [`HEAVY_KURTOSIS`].
pub fn heavy_tailed(v: &[Real]) -> bool {
    excess_kurtosis(v) > HEAVY_KURTOSIS
}

/// The test of a statement `about` the values `v`: the sign test for the median, and for the
/// mean the t test unless `v` is heavy-tailed.
pub fn choose(about: About, v: &[Real]) -> Test {
    match about {
        About::Median => Test::Sign,
        About::Mean if heavy_tailed(v) => Test::Sign,
        About::Mean => Test::T,
    }
}

/// A location estimate with its 95 % interval and the p-values of boundaries.
#[derive(Clone, Debug)]
pub struct Located {
    /// The test.
    pub test: Test,
    /// Values behind it.
    pub n: usize,
    /// The mean (t) or median (sign).
    pub estimate: Real,
    /// Its 95 % interval (`None`: too few values).
    pub ci95: Option<[Real; 2]>,
    /// The t test's standard error.
    se: Real,
    /// The sign test's values, sorted.
    sorted: Vec<Real>,
}

impl Located {
    /// The location of `v` by `test`.
    pub fn of(v: &[Real], test: Test) -> Located {
        match test {
            Test::T => Located::mean(v),
            Test::Sign => Located::median(v),
        }
    }

    /// The mean of `v` with its t interval.
    pub fn mean(v: &[Real]) -> Located {
        let n = v.len();
        let nf = n as Real;
        let m = if n == 0 {
            Real::NAN
        } else {
            v.iter().sum::<Real>() / nf
        };
        let sd = if n < 2 {
            Real::NAN
        } else {
            (v.iter().map(|x| (x - m).powi(2)).sum::<Real>() / (nf - 1.0)).sqrt()
        };
        Located::with_se(m, sd / nf.sqrt(), n)
    }

    /// An estimate with a t standard error on n − 1 degrees of freedom (the delta method's
    /// ratio of means).
    pub fn with_se(estimate: Real, se: Real, n: usize) -> Located {
        Located {
            test: Test::T,
            n,
            estimate,
            ci95: dist::t_interval(estimate, se * (n as Real).sqrt(), n),
            se,
            sorted: Vec::new(),
        }
    }

    /// The median of `v` with its distribution-free 95 % interval ([`median_ranks`]).
    pub fn median(v: &[Real]) -> Located {
        let mut sorted = v.to_vec();
        sorted.sort_by(Real::total_cmp);
        let n = sorted.len();
        let estimate = match n {
            0 => Real::NAN,
            _ if n % 2 == 1 => sorted[n / 2],
            _ => 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]),
        };
        let ci95 = median_ranks(n, 0.05).map(|(l, u)| [sorted[l], sorted[u]]);
        Located {
            test: Test::Sign,
            n,
            estimate,
            ci95,
            se: Real::NAN,
            sorted,
        }
    }

    /// The two-sided p-value of "the location is `c`": the smallest α at which the 1 − α
    /// interval excludes `c` (t: the t test; sign: the two-sided binomial sign test, values
    /// equal to `c` dropped). NaN without values.
    pub fn p_at(&self, c: Real) -> Real {
        match self.test {
            Test::T => {
                if self.n < 2 || !self.estimate.is_finite() {
                    Real::NAN
                } else if self.se == 0.0 {
                    if self.estimate == c {
                        1.0
                    } else {
                        0.0
                    }
                } else {
                    dist::t_two_sided((self.estimate - c) / self.se, (self.n - 1) as Real)
                }
            }
            Test::Sign => {
                if self.sorted.is_empty() {
                    return Real::NAN;
                }
                let below = self.sorted.iter().filter(|&&x| x < c).count();
                let above = self.sorted.iter().filter(|&&x| x > c).count();
                sign_p(below.min(above), below + above)
            }
        }
    }

    /// The trials at which an interval as wide per trial would clear `gap` (the distance the
    /// interval's nearer end must move): n · (half-width / gap)², rounded up, at least n + 1.
    pub fn trials_to_clear(&self, gap: Real) -> Option<u64> {
        let [lo, hi] = self.ci95?;
        let half = (hi - lo) / 2.0;
        let nf = self.n as Real;
        (gap > 0.0 && half.is_finite())
            .then(|| (nf * (half / gap).powi(2)).ceil())
            .filter(|t| t.is_finite() && *t < 1e15)
            .map(|t| (t as u64).max(self.n as u64 + 1))
    }
}

/// The two-sided p-value of the sign test with `k` values on the rarer side of `n`:
/// min(1, 2 P(B ≤ k)), B ~ Binomial(n, ½); 1 for n = 0.
pub fn sign_p(k: usize, n: usize) -> Real {
    if n == 0 {
        return 1.0;
    }
    let nf = n as Real;
    let ln2n = nf * std::f64::consts::LN_2;
    let cdf: Real = (0..=k)
        .map(|j| {
            let ln_c = dist::ln_gamma(nf + 1.0)
                - dist::ln_gamma(j as Real + 1.0)
                - dist::ln_gamma(nf - j as Real + 1.0);
            (ln_c - ln2n).exp()
        })
        .sum();
    (2.0 * cdf).min(1.0)
}

/// The verdict of a paired comparison b − a against a margin m.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Paired {
    /// The interval lies wholly beyond the margin on b's better side.
    Better,
    /// … on b's worse side.
    Worse,
    /// The interval lies inside ± m (two one-sided tests, each at 2.5 %).
    Equivalent,
    /// Anything else (or no interval).
    Unresolved,
}

impl Paired {
    /// Its name in `summary.json` and the reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Paired::Better => "better",
            Paired::Worse => "worse",
            Paired::Equivalent => "equivalent",
            Paired::Unresolved => "unresolved",
        }
    }
}

/// The verdict of the difference b − a located by `d` against the margin `m` (≥ 0), for a
/// metric that improves downwards (`lower_is_better`) or upwards; for an unresolved one,
/// the trials at which an interval as wide per trial would resolve it.
pub fn paired_verdict(d: &Located, m: Real, lower_is_better: bool) -> (Paired, Option<u64>) {
    let Some([lo, hi]) = d.ci95.filter(|[lo, hi]| lo.is_finite() && hi.is_finite()) else {
        return (Paired::Unresolved, None);
    };
    let (down, up) = if lower_is_better {
        (Paired::Better, Paired::Worse)
    } else {
        (Paired::Worse, Paired::Better)
    };
    if hi < -m {
        return (down, None);
    }
    if lo > m {
        return (up, None);
    }
    if lo > -m && hi < m {
        return (Paired::Equivalent, None);
    }
    let e = d.estimate.abs();
    (Paired::Unresolved, d.trials_to_clear((e - m).abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kurtosis_and_the_rule() {
        // scipy.stats.kurtosis([1, 2, 3, 4, 100]) (Fisher, biased).
        let g = excess_kurtosis(&[1.0, 2.0, 3.0, 4.0, 100.0]);
        assert!((g - 0.24671648930016365).abs() < 1e-12, "{g}");
        // 19 equal-spaced values and one far out: heavy.
        let mut v: Vec<Real> = (0..19).map(|i| i as Real * 0.01).collect();
        v.push(10.0);
        assert!(heavy_tailed(&v));
        assert_eq!(choose(About::Mean, &v), Test::Sign);
        let even: Vec<Real> = (0..20).map(|i| i as Real).collect();
        assert_eq!(choose(About::Mean, &even), Test::T);
        assert_eq!(choose(About::Median, &even), Test::Sign);
    }

    #[test]
    fn sign_test_by_hand() {
        // scipy.stats.binomtest(1, 10).pvalue = 0.021484375.
        assert!((sign_p(1, 10) - 0.021484375).abs() < 1e-12);
        assert_eq!(sign_p(5, 10), 1.0);
        let l = Located::median(&[3.0, 1.0, 2.0, 5.0, 4.0, 6.0, 7.0]);
        assert_eq!((l.estimate, l.ci95), (4.0, Some([1.0, 7.0])));
        // Every value above 0.5: 2 / 2⁷.
        assert!((l.p_at(0.5) - 2.0 / 128.0).abs() < 1e-12);
    }

    #[test]
    fn paired_verdicts_against_the_margin() {
        let tight = |m: Real| Located::with_se(m, 0.001, 100);
        assert_eq!(paired_verdict(&tight(-0.1), 0.01, true).0, Paired::Better);
        assert_eq!(paired_verdict(&tight(-0.1), 0.01, false).0, Paired::Worse);
        assert_eq!(
            paired_verdict(&tight(1e-7), 0.01, true).0,
            Paired::Equivalent
        );
        let (v, n) = paired_verdict(&Located::with_se(0.011, 0.002, 100), 0.01, true);
        assert_eq!(v, Paired::Unresolved);
        // Half-width t₀.₉₇₅,₉₉ · 0.002 = 0.003968; gap 0.001: 100 · 3.968² = 1575.
        assert_eq!(n, Some(1575));
        assert_eq!(Margin::default().at(2.0), 0.0);
        let m = Margin {
            relative: Some(0.01),
            absolute: Some(0.001),
        };
        assert_eq!((m.at(0.5), m.at(-0.05)), (0.005, 0.001));
    }
}
