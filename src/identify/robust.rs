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
use serde::Deserialize;

use super::solver::{gauss_newton, LeastSquares, RidgeCfg, Solver};
use super::weights::{RobustCfg, Sigma0, WeightFn};
use super::xi::XiRule;
use super::Identified;
use crate::error::{check_count, finite_positive, Error, Result};
use crate::math::Real;

/// Options of `igg3` (FORMATS.md `[[methods]]`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
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

impl Solver for RobustOptions {
    fn name(&self) -> &'static str {
        "igg3"
    }

    fn check(&self) -> Result<()> {
        finite_positive("k0", self.k0)?;
        finite_positive("k1", self.k1)?;
        if self.k1 <= self.k0 {
            return Err(Error::setting(
                "k1",
                format!("must exceed k0 ({}), got {}", self.k0, self.k1),
            ));
        }
        self.xi.check("xi")?;
        finite_positive("eps", self.eps)?;
        check_count("max_iter", self.max_iter)
    }

    fn run(&self, p: &dyn LeastSquares, x0: &DVector<Real>) -> Identified {
        let cfg = RidgeCfg {
            xi: &self.xi,
            scale: self.scale,
        };
        let robust = RobustCfg {
            weight: self.weight,
            k0: self.k0,
            k1: self.k1,
            sigma0: self.sigma0,
        };
        gauss_newton(p, x0, self.eps, self.max_iter, Some(cfg), Some(&robust))
    }
}
