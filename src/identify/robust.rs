//! IGG3 robust ridge estimation (Li 2018 §2.2, eqs. 15–18), with Huber and Tukey weights as
//! comparisons.
//!
//! Iteratively reweighted ridge: the ridge iterations of [`super::ridge`] first run with all
//! points at weight 1 until the step falls below ε (Li: "第 1 次求解时 P 为单位权"); from then
//! on every iteration gives each point the equivalent weight `p̄_i = p_i ψ(v_i)/v_i` (eq. 16,
//! prior `p_i = 1`) from its residual `v_i` at the current estimate (eq. 15), and the
//! iterations stop when a reweighted step has `max |dx| < ε`.
//!
//! The weight of a point follows from its standardised residual `u_i = |v_i| / (σ0 √r)`:
//! `|v_i|` is the norm of its r = 3 (or 6) residual rows, so `u_i` is the RMS of the point's
//! rows in units of σ0 (about 1 for a normal point). σ0 is either
//! - [`Sigma0::Classical`]: Li's `σ0 = sqrt(vᵀPv / (n − t))` with the weights of the
//!   previous iteration, where n counts each row with its weight, `n = r Σ_i p̄_i` (with n
//!   the plain row count, down-weighted points keep their share of the redundancy while
//!   their residuals leave `vᵀPv`, and σ0 shrinks from one reweighting to the next until
//!   good points are rejected too); or
//! - [`Sigma0::Mad`]: `1.4826 · median |v_k|` over all residual rows (zero-centred MAD).
//!
//! When σ0 falls below `1e-9` times the RMS point residual at the start (consistent,
//! noise-free data), every point keeps weight 1.
//!
//! Weight functions ([`WeightFn`]):
//! - IGG3 (Li eq. 18): `1` for `u ≤ k0`; `(k0/u)·((k1 − u)/(k1 − k0))²` for `k0 < u ≤ k1`;
//!   `0` for `u > k1`. The paper's text gives `k0 = 1.5`, `k1 = 2.4` (garbled); the defaults
//!   are `k0 = 1.5`, `k1 = 2.5` (SPEC §4), both settable.
//! - Huber: `1` for `u ≤ k0`, `k0/u` beyond.
//! - Tukey's biweight with cut-off `c = k1`: `(1 − (u/c)²)²` for `u < c`, `0` beyond.

use nalgebra::DVector;

use super::ls::{gauss_newton, RidgeCfg};
use super::ridge::XiRule;
use super::{Identified, Problem};
use crate::math::Real;

/// The weight function of the robust iterations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WeightFn {
    /// IGG3 (Li 2018 eq. 18): normal, suspicious and rejected segments.
    Igg3,
    /// Huber's weights with threshold k0.
    Huber,
    /// Tukey's biweight with cut-off k1.
    Tukey,
}

/// How the unit-weight standard deviation σ0 is estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sigma0 {
    /// `sqrt(vᵀPv / (n − t))` (Li 2018 §2.2).
    Classical,
    /// `1.4826 · median |v_k|` over the residual rows.
    Mad,
}

/// Settings of [`super::Method::Igg3`].
#[derive(Clone, Debug)]
pub struct RobustOptions {
    /// Weight function. Default [`WeightFn::Igg3`].
    pub weight: WeightFn,
    /// Lower threshold k0 (IGG3, Huber). Default 1.5.
    pub k0: Real,
    /// Upper threshold k1 (IGG3) or Tukey's cut-off. Default 2.5.
    pub k1: Real,
    /// σ0 estimate. Default [`Sigma0::Classical`].
    pub sigma0: Sigma0,
    /// Ridge parameter rule. Default [`XiRule::DoubleH`].
    pub xi: XiRule,
    /// Column scaling of the ridge (see [`super::RidgeOptions::scale`]). Default true.
    pub scale: bool,
    /// Stop when `max |δx| < eps` (mm or rad). Default 1e-9.
    pub eps: Real,
    /// Iteration limit (all phases). Default 200.
    pub max_iter: usize,
}

impl Default for RobustOptions {
    fn default() -> Self {
        RobustOptions {
            weight: WeightFn::Igg3,
            k0: 1.5,
            k1: 2.5,
            sigma0: Sigma0::Classical,
            xi: XiRule::DoubleH,
            scale: true,
            eps: 1e-9,
            max_iter: 200,
        }
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

pub(crate) fn run(p: &dyn Problem, x0: &DVector<Real>, o: &RobustOptions) -> Identified {
    let cfg = RidgeCfg {
        xi: &o.xi,
        scale: o.scale,
    };
    gauss_newton(p, x0, o.eps, o.max_iter, Some(cfg), Some(o))
}

/// What the reweighting found.
pub(crate) struct WeightStats {
    /// The MAD-based σ0, when that estimate is in use.
    pub mad: Option<Real>,
}

/// Recomputes the point weights `w` from the residuals `r` (`rows` per point, `t` unknowns).
/// `rms0` is the RMS point residual at the start. Allocation-free once `buf` has capacity.
pub(crate) fn point_weights(
    r: &DVector<Real>,
    rows: usize,
    t: usize,
    o: &RobustOptions,
    rms0: Real,
    w: &mut [Real],
    buf: &mut Vec<Real>,
) -> WeightStats {
    let sigma0 = match o.sigma0 {
        Sigma0::Classical => {
            let mut s = 0.0;
            let mut n = 0.0;
            for (i, &wi) in w.iter().enumerate() {
                n += rows as Real * wi;
                let e2: Real = (0..rows).map(|k| r[i * rows + k].powi(2)).sum();
                s += wi * e2;
            }
            if n > t as Real {
                (s / (n - t as Real)).sqrt()
            } else {
                Real::NAN
            }
        }
        Sigma0::Mad => {
            buf.clear();
            buf.extend(r.iter().map(|v| v.abs()));
            1.4826 * median(buf)
        }
    };
    let mad = (o.sigma0 == Sigma0::Mad).then_some(sigma0);
    if !sigma0.is_finite() || sigma0 <= 1e-9 * rms0 {
        w.fill(1.0);
        return WeightStats { mad };
    }
    let scale = sigma0 * (rows as Real).sqrt();
    for (i, wi) in w.iter_mut().enumerate() {
        let e: Real = (0..rows)
            .map(|k| r[i * rows + k].powi(2))
            .sum::<Real>()
            .sqrt();
        *wi = o.weight.weight(e / scale, o.k0, o.k1);
    }
    WeightStats { mad }
}

/// Median of `v` (reorders it); NaN when empty.
fn median(v: &mut [Real]) -> Real {
    if v.is_empty() {
        return Real::NAN;
    }
    v.sort_unstable_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
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
