//! A claim judged on a block's trials (docs/formats.md "claims", "Tests and margins").
//!
//! What is estimated, and its interval ([`crate::study::stats::location`] chooses the test):
//!
//! - `"a" op "b"`: the paired difference a − b over trials: its mean with the t interval, or
//!   its median with the sign test's interval;
//! - `"a" / "b" op x`: the ratio of the means of a and b by the delta method (R = ā / b̄ ±
//!   t₀.₉₇₅,ₙ₋₁ · s(aᵢ − R bᵢ) / (√n b̄), Cochran, *Sampling Techniques*, § 6.4), or the
//!   median of the per-trial ratios aᵢ / bᵢ with the sign test's interval;
//! - `"a" op x`: the mean (t) or median (sign) of a over trials.
//!
//! The verdict from the 95 % interval:
//!
//! - an ordering of two entries (`"a" < "b"`) reproduces when the interval lies wholly
//!   beyond the margin m on the claimed side (a − b < −m), and contradicts when it lies
//!   wholly on the other side of −m (no difference that matters in the claimed direction);
//! - a point value (`"a" ~ x`, band [x − h, x + h], h the tolerance at x) reproduces when the
//!   interval lies inside the band, contradicts when it lies wholly outside;
//! - a one-sided bound against a number (`"a" >= 90`) reproduces on the claimed side of the
//!   number and contradicts on the other;
//!
//! and `unresolved` otherwise. A `calibrated` claim is `calibrated` and a claim that is not
//! comparable on this arm `not comparable`, whatever the interval. Each verdict carries the
//! p-value of the boundary that decides it (the smallest α at which the 1 − α interval gives
//! a verdict), which the family-wise rule over a paper's claims adjusts.

use super::claims::{Bound, Claim, Op, Term};
use crate::numeric::Real;
use crate::study::stats::location::{choose, excess_kurtosis, Located, Test};

/// A claim's verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Verdict {
    /// The interval lies wholly on the claimed side (inside a point value's band).
    #[serde(rename = "reproduces")]
    Reproduces,
    /// The interval lies wholly on the other side (outside the band).
    #[serde(rename = "contradicts")]
    Contradicts,
    /// The interval straddles a boundary (or there is none).
    #[serde(rename = "unresolved")]
    Unresolved,
    /// A figure of the arm's error on an arm without error outside the kinematic model: a
    /// real robot's figure cannot be compared with it.
    #[serde(rename = "not comparable")]
    NotComparable,
    /// The figure was used to choose a setting of the scenario: never judged.
    #[serde(rename = "calibrated")]
    Calibrated,
}

impl Verdict {
    /// Its name in `summary.json` and the reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Reproduces => "reproduces",
            Verdict::Contradicts => "contradicts",
            Verdict::Unresolved => "unresolved",
            Verdict::NotComparable => "not comparable",
            Verdict::Calibrated => "calibrated",
        }
    }

    /// Whether it is a judgement (reproduces, contradicts or unresolved).
    pub fn is_judged(self) -> bool {
        matches!(
            self,
            Verdict::Reproduces | Verdict::Contradicts | Verdict::Unresolved
        )
    }
}

/// A claim evaluated on a block's trials.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// What was estimated: `difference`, `ratio` or `mean` (`median` for a median of
    /// values; a median difference or ratio keeps its name, [`Evaluation::test`] says).
    pub interval: &'static str,
    /// The bound the estimate is compared with (0 for a difference, the value of a band).
    pub bound: Real,
    /// Trials usable in every entry the claim names.
    pub n: usize,
    /// The estimate.
    pub estimate: Real,
    /// Its 95 % interval (`None` under 2 trials, or 6 for the sign test).
    pub ci95: Option<[Real; 2]>,
    /// The test that decided.
    pub test: Test,
    /// The sample excess kurtosis of what the test was chosen on (NaN under 4 trials).
    pub kurtosis: Real,
    /// An ordering's margin m, in the metric's unit.
    pub margin: Option<Real>,
    /// A point value's band.
    pub band: Option<[Real; 2]>,
    /// The two-sided p-value of the deciding boundary (NaN without one).
    pub p_value: Real,
    /// The verdict.
    pub verdict: Verdict,
    /// For an unresolved claim (or a calibrated one that would be unresolved), the trials at
    /// which an interval as wide per trial would clear the nearer boundary:
    /// n · (half-width / distance)², rounded up.
    pub trials_to_resolve: Option<u64>,
}

/// Evaluates `claim` on per-trial values: `values(method, strategy)` is the claim's metric of
/// that entry, one value per trial in trial order (NaN where the trial failed).
pub fn evaluate<'a>(claim: &Claim, values: impl Fn((usize, usize)) -> &'a [Real]) -> Evaluation {
    let (a, b) = match (&claim.term, &claim.bound) {
        (Term::One(a), Bound::Entry(b)) | (Term::Ratio(a, b), _) => (values(*a), Some(values(*b))),
        (Term::One(a), Bound::Number(_)) => (values(*a), None),
    };
    let rows: Vec<(Real, Real)> = match b {
        Some(b) => a
            .iter()
            .zip(b)
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(&x, &y)| (x, y))
            .collect(),
        None => a
            .iter()
            .filter(|x| x.is_finite())
            .map(|&x| (x, 0.0))
            .collect(),
    };
    judge(claim, &rows)
}

/// One parameter's verdict of a claim "for every parameter".
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ParameterVerdict {
    /// The parameter.
    pub name: String,
    /// Trials usable in both entries.
    pub n: usize,
    /// The estimate (`null`, read as NaN, without trials).
    #[serde(deserialize_with = "crate::numeric::nan::real")]
    pub estimate: Real,
    /// Its 95 % interval.
    pub ci95: Option<[Real; 2]>,
    /// The test that decided.
    pub test: Test,
    /// The verdict.
    pub verdict: Verdict,
}

/// Evaluates a claim "for every parameter" on each parameter's per-trial η of the two
/// entries (`(name, a, b)`, aligned by trial): each parameter judged as an ordering, the
/// claim's verdict `reproduces` when every parameter reproduces (an intersection–union test:
/// no adjustment), `contradicts` when one contradicts at the Bonferroni level 0.05 / p (its
/// p-value below it), `unresolved` otherwise. The estimate is the smallest parameter
/// estimate on the claimed side, the p-value the largest (all must hold) or the smallest
/// times p (one contradicts). A parameter without trials (a claim's listed parameter that no
/// trial determines) is `unresolved`, and so is the claim, with no count of trials that
/// would resolve it.
pub fn evaluate_every(
    claim: &Claim,
    params: &[(String, &[Real], &[Real])],
) -> (Evaluation, Vec<ParameterVerdict>) {
    let mut each = Vec::new();
    let mut evals = Vec::new();
    for (name, a, b) in params {
        let rows: Vec<(Real, Real)> = a
            .iter()
            .zip(*b)
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(&x, &y)| (x, y))
            .collect();
        let e = judge(claim, &rows);
        each.push(ParameterVerdict {
            name: name.clone(),
            n: e.n,
            estimate: e.estimate,
            ci95: e.ci95,
            test: e.test,
            verdict: e.verdict,
        });
        evals.push(e);
    }
    let p = evals.len().max(1) as Real;
    let claimed_down = matches!(claim.op, Op::Lt | Op::Le);
    // The parameter nearest to failing the claim: the smallest estimate on the claimed side,
    // among those with trials.
    let worst = evals.iter().filter(|e| e.n > 0).min_by(|x, y| {
        let (x, y) = if claimed_down {
            (-x.estimate, -y.estimate)
        } else {
            (x.estimate, y.estimate)
        };
        x.total_cmp(&y)
    });
    let Some(worst) = worst.cloned() else {
        return (judge(claim, &[]), each);
    };
    let all = evals.iter().all(|e| e.verdict == Verdict::Reproduces);
    let contra: Vec<&Evaluation> = evals
        .iter()
        .filter(|e| e.verdict == Verdict::Contradicts && e.p_value * p < 0.05)
        .collect();
    let (verdict, p_value) = if all {
        let pmax = evals.iter().map(|e| e.p_value).fold(0.0, Real::max);
        (Verdict::Reproduces, pmax)
    } else if let Some(pmin) = contra.iter().map(|e| e.p_value).reduce(Real::min) {
        (Verdict::Contradicts, (pmin * p).min(1.0))
    } else {
        (Verdict::Unresolved, Real::NAN)
    };
    let e = Evaluation {
        verdict: overridden(claim, verdict),
        p_value,
        // No count of trials resolves a parameter that no trial determines.
        trials_to_resolve: (verdict == Verdict::Unresolved && evals.iter().all(|e| e.n > 0))
            .then(|| evals.iter().filter_map(|e| e.trials_to_resolve).max())
            .flatten(),
        ..worst
    };
    (e, each)
}

/// A calibrated or not comparable claim's verdict in place of the judgement.
fn overridden(claim: &Claim, judged: Verdict) -> Verdict {
    if claim.calibrated {
        Verdict::Calibrated
    } else if !claim.comparable {
        Verdict::NotComparable
    } else {
        judged
    }
}

/// The claim on paired rows (a, b); b is 0 for a claim against a number.
fn judge(claim: &Claim, rows: &[(Real, Real)]) -> Evaluation {
    let n = rows.len();
    let nf = n as Real;
    let mean = |f: &dyn Fn(&(Real, Real)) -> Real| rows.iter().map(f).sum::<Real>() / nf;
    let x = match &claim.bound {
        Bound::Number(x) => *x,
        Bound::Entry(_) => 0.0,
    };
    let (interval, sample, located) = match (&claim.term, &claim.bound) {
        (Term::One(_), Bound::Entry(_)) => {
            let d: Vec<Real> = rows.iter().map(|r| r.0 - r.1).collect();
            let test = choose(claim.about, &d);
            ("difference", d.clone(), Located::of(&d, test))
        }
        (Term::One(_), Bound::Number(_)) => {
            let v: Vec<Real> = rows.iter().map(|r| r.0).collect();
            let test = choose(claim.about, &v);
            let name = if test == Test::Sign { "median" } else { "mean" };
            (name, v.clone(), Located::of(&v, test))
        }
        (Term::Ratio(..), _) => {
            let (ma, mb) = (mean(&|r| r.0), mean(&|r| r.1));
            let ratio = ma / mb;
            let e: Vec<Real> = rows.iter().map(|r| r.0 - ratio * r.1).collect();
            let located = match choose(claim.about, &e) {
                Test::T => {
                    // The residuals' mean is 0 by construction of the ratio.
                    let sd = (e.iter().map(|x| x * x).sum::<Real>() / (nf - 1.0)).sqrt();
                    Located::with_se(ratio, sd / (mb.abs() * nf.sqrt()), n)
                }
                Test::Sign => {
                    let per: Vec<Real> = rows.iter().map(|r| r.0 / r.1).collect();
                    Located::median(&per)
                }
            };
            ("ratio", e, located)
        }
    };
    let kurtosis = excess_kurtosis(&sample);
    let reference = match claim.bound {
        Bound::Entry(_) => mean(&|r| r.1),
        Bound::Number(_) => x,
    };
    let margin = match claim.bound {
        Bound::Entry(_) => Some(
            claim
                .margin
                .unwrap_or_else(|| claim.metric.default_margin())
                .at(reference),
        ),
        Bound::Number(_) => None,
    };
    let band = claim.tolerance.filter(|_| claim.op == Op::Near).map(|t| {
        let h = t.at(x);
        [x - h, x + h]
    });
    let ci = located
        .ci95
        .filter(|[lo, hi]| lo.is_finite() && hi.is_finite());
    let est = located.estimate;
    // The boundaries: (reproduces, contradicts, the boundary that decides, its distance).
    let (verdict, p_value, gap) = match (ci, band) {
        (None, _) => (Verdict::Unresolved, Real::NAN, None),
        (Some([lo, hi]), Some([l, u])) => {
            let v = if lo > l && hi < u {
                Verdict::Reproduces
            } else if hi < l || lo > u {
                Verdict::Contradicts
            } else {
                Verdict::Unresolved
            };
            let (p, gap) = if est > l && est < u {
                (located.p_at(l).max(located.p_at(u)), (est - l).min(u - est))
            } else if est <= l {
                (located.p_at(l), l - est)
            } else {
                (located.p_at(u), est - u)
            };
            (v, p, Some(gap))
        }
        (Some([lo, hi]), None) => {
            // The boundary c: −m or +m for an ordering, x for a bound against a number.
            let m = margin.unwrap_or(0.0);
            let down = matches!(claim.op, Op::Lt | Op::Le);
            let c = match claim.bound {
                Bound::Entry(_) if down => -m,
                Bound::Entry(_) => m,
                Bound::Number(_) => x,
            };
            let strict = matches!(claim.op, Op::Lt | Op::Gt) || margin.is_some();
            let below = if strict { hi < c } else { hi <= c };
            let above = if strict { lo > c } else { lo >= c };
            let (claimed, other) = if down {
                (below, lo >= c && !below)
            } else {
                (above, hi <= c && !above)
            };
            let v = if claimed {
                Verdict::Reproduces
            } else if other {
                Verdict::Contradicts
            } else {
                Verdict::Unresolved
            };
            (v, located.p_at(c), Some((est - c).abs()))
        }
    };
    let trials_to_resolve = match (verdict, gap) {
        (Verdict::Unresolved, Some(g)) => located.trials_to_clear(g),
        _ => None,
    };
    Evaluation {
        interval,
        bound: x,
        n,
        estimate: if n == 0 { Real::NAN } else { est },
        ci95: located.ci95,
        test: located.test,
        kurtosis,
        margin,
        band,
        p_value,
        verdict: overridden(claim, verdict),
        trials_to_resolve,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Claim `rel` with the extra keys `more` on a study of ls, lm × random, detmax-ide.
    pub(crate) fn claim_with(rel: &str, more: &str, unmodelled: bool) -> Claim {
        parsed("validation_after_mm.rms", rel, more, unmodelled).expect("claim")
    }

    /// [`claim_with`] of `metric`, or why it is refused.
    fn parsed(
        metric: &str,
        rel: &str,
        more: &str,
        unmodelled: bool,
    ) -> std::result::Result<Claim, (String, String)> {
        crate::study::claims::tests::parsed(metric, rel, more, unmodelled, false)
    }

    #[test]
    fn orderings_by_hand() {
        let c = claim_with(r#""lm / random" < "ls / random""#, "", true);
        let a = [1.0, 2.0, 3.0, Real::NAN];
        let better = [2.0, 3.1, 3.9, 1.0];
        let e = evaluate(&c, |k| if k == (1, 0) { &a } else { &better });
        // Differences −1, −1.1, −0.9: mean −1, s 0.1, t₀.₉₇₅,₂ = 4.302652729749464; the
        // margin is 1 % of b's mean 3 = 0.03.
        assert_eq!((e.n, e.test, e.margin), (3, Test::T, Some(0.03)));
        assert!((e.estimate + 1.0).abs() < 1e-12);
        let h = 4.302652729749464 * 0.1 / 3f64.sqrt();
        let [lo, hi] = e.ci95.expect("ci");
        assert!((lo + 1.0 + h).abs() < 1e-9 && (hi + 1.0 - h).abs() < 1e-9);
        assert_eq!(
            (e.verdict, e.trials_to_resolve),
            (Verdict::Reproduces, None)
        );
        // p of the boundary −0.03: t = (−1 + 0.03) / (0.1 / √3).
        let t = 0.97 / (0.1 / 3f64.sqrt());
        assert!((e.p_value - crate::numeric::dist::t_two_sided(t, 2.0)).abs() < 1e-15);
        let e = evaluate(&c, |k| if k == (1, 0) { &better } else { &a });
        assert_eq!(e.verdict, Verdict::Contradicts);
        // A difference inside the margin contradicts a claimed ordering.
        let same = [1.0001, 2.0001, 3.0001, 0.0];
        let e = evaluate(&c, |k| if k == (1, 0) { &a } else { &same });
        assert_eq!(e.verdict, Verdict::Contradicts, "{e:?}");
        let noisy = [0.0, 4.0, 2.5, 1.0];
        let e = evaluate(&c, |k| if k == (1, 0) { &a } else { &noisy });
        assert_eq!(e.verdict, Verdict::Unresolved);
        // The ratio of means 2 / 3 against 0.5: the delta method's interval.
        let c = claim_with(r#""lm / random" / "ls / random" <= 0.5"#, "", true);
        let e = evaluate(&c, |k| if k == (1, 0) { &a } else { &better });
        assert!((e.estimate - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!((e.interval, e.bound), ("ratio", 0.5));
        let s = ((1.0 / 9.0 + 1.0 / 225.0 + 4.0 / 25.0) / 2.0 as Real).sqrt();
        let h = 4.302652729749464 * s / (3f64.sqrt() * 3.0);
        let [lo, hi] = e.ci95.expect("ci");
        assert!((lo - (2.0 / 3.0 - h)).abs() < 1e-9 && (hi - (2.0 / 3.0 + h)).abs() < 1e-9);
        assert_eq!(e.verdict, Verdict::Unresolved);
    }

    /// A claim "for every parameter" with the extra keys `more`.
    fn every(more: &str) -> std::result::Result<Claim, (String, String)> {
        let rel = r#""lm / detmax-ide" > "lm / random" for every parameter"#;
        parsed("eta", rel, more, false)
    }

    /// A listed parameter that no trial determines leaves the claim `unresolved`, whatever the
    /// others give, with no count of trials that would resolve it; the estimate is the others'.
    #[test]
    fn a_listed_parameter_without_trials_leaves_the_claim_unresolved() {
        let c = every("parameters = [\"alpha4\", \"d2\"]").expect("claim");
        assert_eq!(c.parameters, Some(vec!["alpha4".into(), "d2".into()]));
        let a: Vec<Real> = (0..20).map(|i| 0.99 + 1e-4 * (i % 3) as Real).collect();
        let b: Vec<Real> = (0..20).map(|i| 0.49 + 1e-3 * (i % 5) as Real).collect();
        let (e, each) = evaluate_every(&c, &[("alpha4".into(), &a, &b)]);
        assert_eq!(e.verdict, Verdict::Reproduces, "{e:?}");
        let (e, each2) = evaluate_every(&c, &[("alpha4".into(), &a, &b), ("d2".into(), &[], &[])]);
        assert_eq!(
            (e.verdict, e.trials_to_resolve),
            (Verdict::Unresolved, None)
        );
        assert_eq!((e.n, e.estimate), (each[0].n, each[0].estimate));
        assert_eq!((each2[1].n, each2[1].verdict), (0, Verdict::Unresolved));
        assert!(each2[1].estimate.is_nan() && each2[1].ci95.is_none());
        // `parameters` goes with "for every parameter", names each once, and names one.
        for (more, why) in [
            ("parameters = []", "at least one"),
            ("parameters = [\"d2\", \"d2\"]", "named twice"),
        ] {
            let (key, msg) = every(more).expect_err(more);
            assert_eq!(key, "claims[0].parameters");
            assert!(msg.contains(why), "{msg}");
        }
        let rel = r#""lm / random" < "ls / random""#;
        let (key, msg) = parsed(
            "validation_after_mm.rms",
            rel,
            "parameters = [\"d2\"]",
            false,
        )
        .expect_err("an ordering");
        assert_eq!(key, "claims[0].parameters", "{msg}");
    }

    /// Must hold (issue 51): no point-value claim reproduces when the estimate is 2× off.
    #[test]
    fn a_point_value_two_times_off_never_reproduces() {
        let c = claim_with(
            r#""ls / random" ~ 0.42"#,
            "tolerance = { relative = 0.25 }",
            true,
        );
        for scale in [2.0, 0.5] {
            for spread in [0.0, 1e-4, 1e-2, 0.3] {
                let v: Vec<Real> = (0..40)
                    .map(|i| 0.42 * scale + spread * ((i % 7) as Real - 3.0))
                    .collect();
                let e = evaluate(&c, |_| &v);
                assert_ne!(e.verdict, Verdict::Reproduces, "{scale} {spread}: {e:?}");
            }
        }
        let on: Vec<Real> = (0..40).map(|i| 0.42 + 1e-3 * (i % 3) as Real).collect();
        let e = evaluate(&c, |_| &on);
        assert_eq!(e.verdict, Verdict::Reproduces);
        assert_eq!(e.band, Some([0.42 - 0.105, 0.42 + 0.105]));
        let far: Vec<Real> = on.iter().map(|x| x * 2.0).collect();
        assert_eq!(evaluate(&c, |_| &far).verdict, Verdict::Contradicts);
    }

    /// Must hold (issue 51): a figure of the arm's error on an arm without error outside the
    /// model is not comparable (Li's 0.017 mm against 0.42 mm), and a calibrated figure is
    /// never judged.
    #[test]
    fn kinematic_arm_figures_are_not_comparable_and_calibrated_ones_not_judged() {
        let rel = r#""ls / random" ~ 0.42"#;
        let c = claim_with(rel, "tolerance = { relative = 0.25 }", false);
        let v = vec![0.017; 10];
        assert_eq!(evaluate(&c, |_| &v).verdict, Verdict::NotComparable);
        // An ordering stays judged on the kinematic arm.
        let c = claim_with(r#""lm / random" < "ls / random""#, "", false);
        assert!(c.comparable);
        let c = claim_with(
            rel,
            "tolerance = { relative = 0.25 }\ncalibrated = true",
            true,
        );
        let on = vec![0.42; 10];
        assert_eq!(evaluate(&c, |_| &on).verdict, Verdict::Calibrated);
    }

    /// A claim about the mean on heavy-tailed differences is decided by the sign test: a few
    /// stalls of b do not hide that a is worse in most trials.
    #[test]
    fn heavy_tails_switch_to_the_sign_test() {
        let c = claim_with(r#""lm / random" < "ls / random""#, "", true);
        let a: Vec<Real> = (0..20).map(|i| 0.05 + 0.001 * i as Real).collect();
        let mut b: Vec<Real> = a.iter().map(|x| x - 0.01).collect();
        b[3] = 0.7;
        b[11] = 0.75;
        let e = evaluate(&c, |k| if k == (1, 0) { &a } else { &b });
        assert_eq!(
            (e.test, e.verdict),
            (Test::Sign, Verdict::Contradicts),
            "{e:?}"
        );
        assert!(e.kurtosis > 3.0);
        let c = claim_with(
            r#""lm / random" < "ls / random""#,
            "about = \"median\"",
            true,
        );
        let b: Vec<Real> = a.iter().map(|x| x + 0.01).collect();
        let e = evaluate(&c, |k| if k == (1, 0) { &a } else { &b });
        assert_eq!((e.test, e.verdict), (Test::Sign, Verdict::Reproduces));
    }
}
