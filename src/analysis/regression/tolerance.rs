//! The tolerance of the regression rule: the relative worsening a metric may show before it
//! counts as worse (docs/formats.md § 2.4, `--tolerance`), the range it is accepted in, and
//! whether a change exceeds it.

use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::study::metric::Better;

/// The largest tolerance accepted: a worsening of 1000 % of the baseline's value. A larger
/// one would let every change pass and guard nothing.
pub const MAX_TOLERANCE: Real = 10.0;

/// `t` as the tolerance of the rule, given as the option or argument `key`: a number from 0
/// to [`MAX_TOLERANCE`]; a negative, larger or non-finite number is refused, naming `key` and
/// the range.
pub fn checked_tolerance(t: Real, key: &str) -> Result<Real> {
    if (0.0..=MAX_TOLERANCE).contains(&t) {
        Ok(t)
    } else {
        Err(Error::setting(
            key,
            format!(
                "must be a number from 0 to {MAX_TOLERANCE} (a relative worsening: 0.05 is \
                 5 %, {MAX_TOLERANCE} is 1000 %)"
            ),
        ))
    }
}

/// Whether `value` is worse than `base` by at least `tolerance` times the baseline's
/// magnitude, in direction `dir`. A change of exactly the tolerance counts: the comparison
/// allows 1e-12 of the magnitude for the rounding of decimal numbers. A change of 1e-9 or
/// less never counts, so equal values, and a zero baseline with rounding noise, pass.
pub(super) fn regressed(value: Real, base: Real, tolerance: Real, dir: Better) -> bool {
    let worse_by = match dir {
        Better::Higher => base - value,
        Better::Lower => value - base,
    };
    let rounding = 1e-12 * base.abs().max(value.abs());
    worse_by > 1e-9 && worse_by >= tolerance * base.abs() - rounding
}
