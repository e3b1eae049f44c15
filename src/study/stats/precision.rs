//! `calbench run --precision` (docs/formats.md "Stopping at a precision"): run trials until
//! every entry's headline interval is narrow enough. The headline interval is the 95 % t
//! interval of the mean validation error after compensation (`validation_after_mm.mean_ci95`),
//! its half-width compared with an absolute target in mm or with a share of the mean.
//!
//! The rule looks at the statistics only after whole blocks of [`BLOCK`] trials (trials
//! 0‥32, 0‥64, …) and at the trial cap, so where a run stops depends on the seed alone, never
//! on the thread count: the run that stops after N trials is the run of `--trials N`.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::study::metric::Metric;

/// Trials between two looks at the intervals.
pub const BLOCK: usize = 32;

/// How narrow the headline interval must be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// Half-width over |mean|, as a fraction (`0.5%` is 0.005).
    Relative(Real),
    /// Half-width in mm.
    Absolute(Real),
}

/// The headline metric a `--precision` target is put on (docs/formats.md "Stopping at a
/// precision").
pub const HEADLINE: Metric = Metric::ValidationAfterMean;

/// A `--precision` target, with the text it was given as.
#[derive(Clone, Debug, PartialEq)]
pub struct Precision {
    /// The metric whose interval must be narrow enough ([`HEADLINE`]).
    pub metric: Metric,
    /// The target.
    pub target: Target,
    /// As given (`0.5%`, `0.002mm`), for `summary.json` and the checkpoint.
    pub text: String,
}

impl Precision {
    /// Parses `0.5%` (half-width relative to the mean) or `0.002mm` (absolute); refuses
    /// anything else, a value that is not a positive finite number, and a relative target of
    /// 100 % or more, naming `--precision`.
    pub fn parse(text: &str) -> Result<Precision> {
        let t = text.trim();
        let bad = |why: &str| {
            Error::option(
                crate::error::Opt::Precision,
                format!(
                    "\"{text}\" {why}; give a relative half-width of the headline interval \
                     such as 0.5% or an absolute one such as 0.002mm"
                ),
            )
        };
        let (number, relative) = if let Some(n) = t.strip_suffix('%') {
            (n, true)
        } else if let Some(n) = t.strip_suffix("mm") {
            (n, false)
        } else {
            return Err(bad("has no unit (% or mm)"));
        };
        let v: Real = number
            .trim()
            .parse()
            .map_err(|_| bad("is not a number followed by % or mm"))?;
        if !v.is_finite() {
            return Err(bad("is not a finite number"));
        }
        if crate::error::underflow(number.trim(), v).is_some() {
            return Err(bad(
                "is below the smallest 64-bit number (about 4.9e-324) and would read as 0",
            ));
        }
        if v <= 0.0 {
            return Err(bad("must be positive"));
        }
        if relative && v >= 100.0 {
            return Err(bad("must be below 100%"));
        }
        let target = if relative {
            Target::Relative(v / 100.0)
        } else {
            Target::Absolute(v)
        };
        Ok(Precision {
            metric: HEADLINE,
            target,
            // Without a plus sign, which would be echoed as `±+5%`.
            text: t.strip_prefix('+').unwrap_or(t).to_string(),
        })
    }

    /// The width of an interval `ci` around `mean` in the target's unit: the half-width in
    /// mm, or over |mean|; `None` when there is no interval (under 2 usable trials) or it
    /// is not finite.
    pub fn width(&self, mean: Real, ci: Option<[Real; 2]>) -> Option<Real> {
        let [lo, hi] = ci?;
        let h = (hi - lo) / 2.0;
        let w = match self.target {
            Target::Absolute(_) => h,
            Target::Relative(_) => h / mean.abs(),
        };
        w.is_finite().then_some(w)
    }

    /// The target in the unit of [`Precision::width`].
    pub fn goal(&self) -> Real {
        match self.target {
            Target::Absolute(v) | Target::Relative(v) => v,
        }
    }

    /// Whether every interval of `headlines` ((mean, interval) per entry) is narrow enough.
    pub fn reached(&self, headlines: &[(Real, Option<[Real; 2]>)]) -> bool {
        !headlines.is_empty()
            && headlines
                .iter()
                .all(|&(m, ci)| self.width(m, ci).is_some_and(|w| w <= self.goal()))
    }

    /// The widest interval of `headlines` in the target's unit (`None` when an entry has
    /// none).
    pub fn widest(&self, headlines: &[(Real, Option<[Real; 2]>)]) -> Option<Real> {
        headlines
            .iter()
            .map(|&(m, ci)| self.width(m, ci))
            .try_fold(0.0, |acc: Real, w| w.map(|w| acc.max(w)))
    }
}

/// Why a run with `--precision` stopped: `summary.json`'s `stopping`.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Stopping {
    /// `precision`.
    pub rule: String,
    /// The target as given (`0.5%`, `0.002mm`).
    pub target: String,
    /// Whether every entry's headline interval is within it at the stop (false: the run
    /// stopped at its trial cap with one wider).
    pub reached: bool,
    /// The trials run, the run's `trials`.
    pub trials: usize,
    /// The cap (`--trials`, or the scenario's `trials`).
    pub max_trials: usize,
    /// Trials between two looks ([`BLOCK`]).
    pub block: usize,
    /// The widest headline interval at the stop, in the target's unit: a half-width in mm,
    /// or the half-width over the mean (a fraction, 0.005 for 0.5 %); `null` when an entry
    /// had no interval.
    pub widest: Option<Real>,
    /// When the target was not reached: the entry with the widest interval
    /// (`method / poses`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub widest_entry: Option<String>,
    /// When the target was not reached: the trials the widest interval would need, its
    /// half-width shrinking as 1/√trials, rounded up to a whole [`BLOCK`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trials_needed: Option<usize>,
}

impl Stopping {
    /// The shortfall in words when the run stopped at its cap short of the target (naming
    /// the widest entry, its half-width and the trials it would need); `None` when it
    /// reached the target.
    pub fn shortfall(&self) -> Option<String> {
        if self.reached {
            return None;
        }
        let width = self.widest.map_or("without an interval".to_string(), |w| {
            if self.target.trim_end().ends_with('%') {
                format!("at ±{:.3} %", w * 100.0)
            } else {
                format!("at ±{w:.4} mm")
            }
        });
        let entry = self.widest_entry.as_deref().unwrap_or("an entry");
        let most = crate::study::scenario::MAX_TRIALS;
        let needed = self
            .trials_needed
            .map_or(String::new(), |n| match n > most {
                true => format!("; more than {most} trials, the most a run takes, would reach it"),
                false => format!("; about {n} trials would reach it"),
            });
        Some(format!(
            "precision ±{} not reached: stopped at the cap of {} with {entry}'s mean \
             validation error after calibration {width}{needed}",
            self.target.trim_start_matches(['±', '+']),
            crate::error::counted(self.trials, "trial", "trials"),
        ))
    }
}

/// The index of the widest interval of `headlines` in the target's unit of `p`, and the
/// trials it would need to reach the target after `n` ([`Stopping::trials_needed`]).
pub fn widest_and_needed(
    p: &Precision,
    headlines: &[(Real, Option<[Real; 2]>)],
    n: usize,
) -> (Option<usize>, Option<usize>) {
    let widths: Vec<Option<Real>> = headlines.iter().map(|&(m, ci)| p.width(m, ci)).collect();
    // The first of the widest (entries without an interval the widest of all).
    let i = (0..widths.len()).rev().max_by(|&a, &b| {
        let key = |w: Option<Real>| w.unwrap_or(Real::INFINITY);
        key(widths[a]).total_cmp(&key(widths[b]))
    });
    let needed = i.and_then(|i| widths[i]).map(|w| {
        let raw = (n as Real * (w / p.goal()).powi(2)).ceil();
        let blocks = (raw / BLOCK as Real).ceil().max(1.0);
        (blocks as usize).saturating_mul(BLOCK)
    });
    (i, needed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_parse_and_bad_ones_name_the_flag() {
        assert_eq!(Precision::parse(" +5%").unwrap().text, "5%");
        assert_eq!(
            Precision::parse("0.5%").unwrap().target,
            Target::Relative(0.005)
        );
        assert_eq!(
            Precision::parse("0.002mm").unwrap().target,
            Target::Absolute(0.002)
        );
        assert_eq!(
            Precision::parse(" 1 % ").unwrap().target,
            Target::Relative(0.01)
        );
        for bad in ["5", "-1%", "0mm", "nan%", "inf mm", "%", "x%", "100%", ""] {
            let e = Precision::parse(bad).unwrap_err();
            assert_eq!(e.key(), Some("precision"), "{bad}: {e}");
        }
        // Each refused with its own reason: not "must be positive" for an infinity or a NaN.
        for (bad, why) in [
            ("infmm", "is not a finite number"),
            ("nan%", "is not a finite number"),
            ("-1%", "must be positive"),
            // Below the smallest number: not "must be positive", as it was written so.
            (
                "1e-400mm",
                "is below the smallest 64-bit number (about 4.9e-324) and would read as 0",
            ),
            ("0mm", "must be positive"),
        ] {
            let e = Precision::parse(bad).unwrap_err().to_string();
            assert!(e.contains(&format!("\"{bad}\" {why};")), "{bad}: {e}");
        }
    }

    #[test]
    fn reached_when_every_half_width_is_within_the_goal() {
        let p = Precision::parse("1%").unwrap();
        let ok = (1.0, Some([0.995, 1.005]));
        let wide = (1.0, Some([0.98, 1.02]));
        assert!(p.reached(&[ok, ok]));
        assert!(!p.reached(&[ok, wide]));
        assert!(!p.reached(&[ok, (1.0, None)]));
        assert!(!p.reached(&[]));
        assert!((p.widest(&[ok, wide]).unwrap() - 0.02).abs() < 1e-12);
        assert_eq!(p.widest(&[ok, (1.0, None)]), None);
        let a = Precision::parse("0.01mm").unwrap();
        assert!(a.reached(&[(5.0, Some([4.99, 5.01]))]));
    }

    /// `--precision 1e-300mm` printed the saturated count 18446744073709551615 as trials.
    #[test]
    fn a_shortfall_beyond_any_run_says_so() {
        let p = Precision::parse("1e-300mm").unwrap();
        let (i, needed) = widest_and_needed(&p, &[(1.0, Some([0.9, 1.1]))], 3);
        assert_eq!((i, needed), (Some(0), Some(usize::MAX)));
        let st = Stopping {
            rule: "precision".into(),
            target: "1e-300mm".into(),
            reached: false,
            trials: 3,
            max_trials: 3,
            block: BLOCK,
            widest: Some(0.1),
            widest_entry: None,
            trials_needed: needed,
        };
        let text = st.shortfall().unwrap();
        assert!(
            text.ends_with("; more than 1000000000 trials, the most a run takes, would reach it"),
            "{text}"
        );
        let st = Stopping {
            trials_needed: Some(500),
            ..st
        };
        assert!(st
            .shortfall()
            .unwrap()
            .ends_with("; about 500 trials would reach it"));
    }

    /// Of equal widths the first entry is named (it was the last, so that a run of one trial,
    /// where no entry has an interval, named the last entry), and a missing interval is said
    /// so (the message read "at no interval").
    #[test]
    fn the_first_widest_entry_is_named_and_a_missing_interval_said() {
        let p = Precision::parse("1%").unwrap();
        let wide = (1.0, Some([0.98, 1.02]));
        let ok = (1.0, Some([0.995, 1.005]));
        assert_eq!(widest_and_needed(&p, &[ok, wide, wide], 10).0, Some(1));
        let (i, needed) = widest_and_needed(&p, &[(1.0, None), (2.0, None)], 1);
        assert_eq!((i, needed), (Some(0), None));
        let st = Stopping {
            rule: "precision".into(),
            target: "1%".into(),
            reached: false,
            trials: 1,
            max_trials: 1,
            block: BLOCK,
            widest: None,
            widest_entry: Some("ls / random".into()),
            trials_needed: None,
        };
        assert_eq!(
            st.shortfall().unwrap(),
            "precision ±1% not reached: stopped at the cap of 1 trial with ls / random's mean \
             validation error after calibration without an interval"
        );
    }
}
