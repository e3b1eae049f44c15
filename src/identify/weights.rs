//! Robust point weights (Li 2018 §2.2, eqs. 15–18): the weight functions, the σ0 estimates
//! and the reweighting step of the robust ridge ([`super::robust`]); see there for the
//! formulas.

use nalgebra::DVector;

use crate::numeric::{median, Real};

/// The weight function of the robust iterations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WeightFn {
    /// IGG3 (Li 2018 eq. 18): normal, suspicious and rejected segments.
    Igg3,
    /// Huber's weights with threshold k0.
    Huber,
    /// Tukey's biweight with cut-off k1.
    Tukey,
}

/// How the unit-weight standard deviation σ0 is estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sigma0 {
    /// `sqrt(vᵀPv / (n − t))` (Li 2018 §2.2).
    Classical,
    /// `1.4826 · median |v_k|` over the residual rows.
    Mad,
}

/// What one robust weight belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Per {
    /// One weight per point, from the RMS of its residual rows.
    Point,
    /// One weight per residual row (x, y, z and, with full poses, the orientation rows),
    /// from that row alone, as Li 2018 weighs each observation (eq. 16).
    Coordinate,
}

/// The robust part of IGG3's options: its fields are the keys.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Robustness {
    /// Weight function. Default [`WeightFn::Igg3`].
    pub weight: WeightFn,
    /// Lower threshold k0 (IGG3, Huber). Default 1.5.
    pub k0: Real,
    /// Upper threshold k1 (IGG3) or Tukey's cut-off. Default 2.5.
    pub k1: Real,
    /// σ0 estimate. Default [`Sigma0::Classical`].
    pub sigma0: Sigma0,
    /// Whether a weight belongs to a point or to each of its residual rows. Default
    /// [`Per::Point`].
    pub per: Per,
}

impl Default for Robustness {
    fn default() -> Self {
        Robustness {
            weight: WeightFn::Igg3,
            k0: 1.5,
            k1: 2.5,
            sigma0: Sigma0::Classical,
            per: Per::Point,
        }
    }
}

impl Robustness {
    /// Checks the thresholds: positive, `k1 > k0`.
    pub fn check(&self) -> crate::Result<()> {
        crate::error::finite_positive("k0", self.k0)?;
        if !(self.k1.is_finite() && self.k1 > self.k0) {
            return Err(crate::Error::setting(
                "k1",
                format!(
                    "must be finite and exceed k0 ({}), got {}",
                    self.k0, self.k1
                ),
            ));
        }
        Ok(())
    }
}

impl WeightFn {
    /// The weight of a point with standardised residual `u ≥ 0`.
    pub fn weight(self, u: Real, k0: Real, k1: Real) -> Real {
        match self {
            WeightFn::Igg3 => {
                if u <= k0 {
                    1.0
                } else if u <= k1 {
                    let d = (k1 - u) / (k1 - k0);
                    k0 / u * d * d
                } else {
                    0.0
                }
            }
            WeightFn::Huber => {
                if u <= k0 {
                    1.0
                } else {
                    k0 / u
                }
            }
            WeightFn::Tukey => {
                if u < k1 {
                    let a = u / k1;
                    (1.0 - a * a) * (1.0 - a * a)
                } else {
                    0.0
                }
            }
        }
    }
}

/// What the reweighting found.
pub(crate) struct WeightStats {
    /// The MAD-based σ0, when that estimate is in use.
    pub mad: Option<Real>,
}

/// What the robust weights are computed from: the residuals at the current estimate and
/// the settings of the robust ridge.
pub(crate) struct Residuals<'a> {
    /// The residual vector, `rows` entries per point.
    pub r: &'a DVector<Real>,
    /// Residual rows per point.
    pub rows: usize,
    /// Unknowns.
    pub t: usize,
    /// The RMS point residual at the start (σ0 below `1e-9 rms0` means consistent data).
    pub rms0: Real,
    /// The σ0 of residuals that are only the rounding of the data
    /// ([`super::solver::LeastSquares::rounding_floor`] per row, at the mean prior weight):
    /// σ0 at or below it also means consistent data, as when the fit started at the truth.
    pub sigma_floor: Real,
    /// The problem's prior point weights; `None`: every point weighs 1.
    pub prior: Option<&'a [Real]>,
    /// The robust settings.
    pub o: &'a Robustness,
}

impl Residuals<'_> {
    /// `|v_i|²` of point `i`'s residual rows.
    fn point_norm2(&self, i: usize) -> Real {
        self.r.rows(i * self.rows, self.rows).norm_squared()
    }

    /// The classical σ0 with the weights `w`: `sqrt(Σ w_i |v_i|² / (rows Σ w_i − t))`; NaN
    /// when the weighted rows do not exceed the unknowns.
    fn classical_sigma0(&self, w: &[Real]) -> Real {
        let (mut s, mut n) = (0.0, 0.0);
        for (i, &wi) in w.iter().enumerate() {
            n += self.rows as Real * wi;
            s += wi * self.point_norm2(i);
        }
        if n > self.t as Real {
            (s / (n - self.t as Real)).sqrt()
        } else {
            Real::NAN
        }
    }

    /// Whether σ0 says nothing: not finite, or below `1e-9 rms0` or at the rounding floor
    /// (consistent data).
    fn uninformative(&self, sigma0: Real) -> bool {
        !sigma0.is_finite() || sigma0 <= 1e-9 * self.rms0 || sigma0 <= self.sigma_floor
    }

    /// Gives every point its prior weight (1 without priors).
    fn reset(&self, w: &mut [Real]) {
        match self.prior {
            None => w.fill(1.0),
            Some(p) => w.copy_from_slice(p),
        }
    }
}

/// Recomputes the point weights `w` from the residuals. Allocation-free once `buf` has
/// capacity.
pub(crate) fn point_weights(res: &Residuals, w: &mut [Real], buf: &mut Vec<Real>) -> WeightStats {
    let (r, rows, o, prior) = (res.r, res.rows, res.o, res.prior);
    let sigma0 = match o.sigma0 {
        Sigma0::Classical => res.classical_sigma0(w),
        Sigma0::Mad => {
            buf.clear();
            match prior {
                None => buf.extend(r.iter().map(|v| v.abs())),
                Some(p) => buf.extend(
                    r.iter()
                        .enumerate()
                        .map(|(k, v)| p[k / rows].sqrt() * v.abs()),
                ),
            }
            1.4826 * median(buf)
        }
    };
    let mad = (o.sigma0 == Sigma0::Mad).then_some(sigma0);
    if res.uninformative(sigma0) {
        // The weighted points fit exactly (noise-free data): the weights stay as they are,
        // the prior ones in the first round. (Giving a rejected point its weight back here
        // made the rounds alternate between the two sets until the iteration limit.)
        return WeightStats { mad };
    }
    let scale = sigma0 * (rows as Real).sqrt();
    for (i, wi) in w.iter_mut().enumerate() {
        let e = res.point_norm2(i).sqrt();
        // Eq. 16 with prior weight p_i: p̄_i = p_i ψ(u_i)/u_i, u_i the standardised residual.
        *wi = match prior {
            None => o.weight.weight(e / scale, o.k0, o.k1),
            Some(p) => p[i] * o.weight.weight(p[i].sqrt() * e / scale, o.k0, o.k1),
        };
    }
    WeightStats { mad }
}

/// The rejection rule of the robust ridge's final refit, on the residuals `r` at the current
/// estimate: starting from every point at its prior weight, σ0 is the classical estimate over
/// the kept points (`sqrt(Σ p_i |v_i|² / (r Σ p_i − t))`), every point with standardised
/// residual `u_i = √p_i |v_i| / (σ0 √r)` above `k1` is rejected (weight 0), and the two repeat
/// until no more points go. σ0 thus comes down from above (the gross errors inflate it at
/// first) and never rests on a set truncated by a too-small σ0, as the σ0 of the down-weighted
/// rounds would. Returns whether the kept set differs from the one `w` held (kept: `w > 0`).
/// Keeps every point when σ0 is not defined (too few rows), below `1e-9 rms0` or at the
/// rounding floor (consistent data).
pub(crate) fn redecide_inliers(res: &Residuals, w: &mut [Real], before: &mut Vec<bool>) -> bool {
    before.clear();
    before.extend(w.iter().map(|&v| v > 0.0));
    res.reset(w);
    loop {
        let sigma0 = res.classical_sigma0(w);
        if res.uninformative(sigma0) {
            break;
        }
        let scale = sigma0 * (res.rows as Real).sqrt();
        let mut rejected = false;
        for (i, wi) in w.iter_mut().enumerate() {
            if *wi > 0.0 && wi.sqrt() * res.point_norm2(i).sqrt() / scale > res.o.k1 {
                *wi = 0.0;
                rejected = true;
            }
        }
        if !rejected {
            break;
        }
    }
    w.iter().zip(before.iter()).any(|(&v, &b)| (v > 0.0) != b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn igg3_weights_match_the_three_segments() {
        let f = WeightFn::Igg3;
        assert_relative_eq!(f.weight(1.0, 1.5, 2.5), 1.0);
        assert_relative_eq!(f.weight(1.5, 1.5, 2.5), 1.0);
        // u = 2: (1.5/2)·((2.5 − 2)/(1))² = 0.75 · 0.25.
        assert_relative_eq!(f.weight(2.0, 1.5, 2.5), 0.1875, epsilon = 1e-15);
        assert_relative_eq!(f.weight(2.5, 1.5, 2.5), 0.0);
        assert_relative_eq!(f.weight(3.0, 1.5, 2.5), 0.0);
    }

    #[test]
    fn huber_and_tukey_weights_by_hand() {
        assert_relative_eq!(WeightFn::Huber.weight(1.0, 1.5, 2.5), 1.0);
        assert_relative_eq!(WeightFn::Huber.weight(3.0, 1.5, 2.5), 0.5);
        // Tukey, c = 2.5, u = 1.25: (1 − 0.25)² = 0.5625.
        assert_relative_eq!(WeightFn::Tukey.weight(1.25, 1.5, 2.5), 0.5625);
        assert_relative_eq!(WeightFn::Tukey.weight(2.6, 1.5, 2.5), 0.0);
    }

    #[test]
    fn median_of_even_and_odd_lists() {
        assert_relative_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_relative_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
    }
}
