//! A minimum effect of interest, or a tolerance band's half-width ([`Margin`]): what a claim's
//! band and a comparison's margin are made of (docs/formats.md "Tests and margins").

use serde::{Deserialize, Serialize};

use crate::numeric::Real;

/// A minimum effect of interest, or a tolerance band's half-width: relative to a reference
/// value, absolute in the metric's unit, the larger of the two counting (docs/formats.md
/// "Tests and margins").
#[serde_with::skip_serializing_none]
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table of `relative` (a fraction, 0.01 for 1 %) or `absolute` (in the \
                 metric's unit) or both, as `{ relative = 0.25 }`"
)]
pub struct Margin {
    /// A fraction of the reference (0.01: 1 %).
    pub relative: Option<Real>,
    /// In the metric's unit.
    pub absolute: Option<Real>,
}

impl Margin {
    /// The half-width at `reference`: max(relative · |reference|, absolute), each 0 when
    /// absent.
    pub fn at(&self, reference: Real) -> Real {
        let r = self.relative.map_or(0.0, |f| f * reference.abs());
        let a = self.absolute.unwrap_or(0.0);
        r.max(a)
    }

    /// Refuses a negative, non-finite or absent-everywhere margin: the message.
    pub fn check(&self) -> Result<(), String> {
        if self.relative.is_none() && self.absolute.is_none() {
            return Err(
                "give `relative` (a fraction, 0.01 for 1 %), `absolute` (in the \
                        metric's unit) or both"
                    .into(),
            );
        }
        for (k, v) in [("relative", self.relative), ("absolute", self.absolute)] {
            if let Some(v) = v {
                if !v.is_finite() || v < 0.0 {
                    return Err(format!("`{k}` must be a finite number ≥ 0, not {v}"));
                }
            }
        }
        Ok(())
    }
}
