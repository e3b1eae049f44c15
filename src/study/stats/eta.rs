//! The identification efficiency η of a parameter (Guo 2024 eq. 29) and a trial's mean η, as
//! `summary.json`, `trials.csv` and the comparisons on them count it (docs/formats.md § 7.1,
//! "Determinable parameters").

use crate::numeric::Real;

/// η_i = (1 − |x_i − x̂_i| / |x_i|) · 100 % (Guo 2024 eq. 29); `None` where x_i = 0.
pub fn eta(truth: Real, identified: Real) -> Option<Real> {
    (truth != 0.0).then(|| (1.0 - (truth - identified).abs() / truth.abs()) * 100.0)
}

/// One outcome's mean η in its trial: over the study parameters `names` but the base's
/// (which absorb the registration's error), those with an η whose injected error is
/// determinable (not in `below`, the trial's [`super::TrialResult`] `not_determinable` of the
/// outcome's strategy), in parameter order; NaN when none is.
pub fn trial_eta_mean(
    names: &[String],
    (truth, identified): (&[Real], &[Real]),
    below: &[usize],
) -> Real {
    let (mut sum, mut n) = (-0.0, 0usize);
    for (k, name) in names.iter().enumerate() {
        if name.starts_with("base.") || below.contains(&k) {
            continue;
        }
        if let Some(e) = eta(truth[k], identified[k]) {
            sum += e;
            n += 1;
        }
    }
    if n == 0 {
        Real::NAN
    } else {
        sum / n as Real
    }
}
