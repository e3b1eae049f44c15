//! Iterated Gauss–Newton least squares (Li 2018 eq. 13).
//!
//! Each iteration solves `(JᵀPJ) δx = JᵀP E` with `E = measured − model(x)` and updates
//! `x ← x + δx` until `max |δx| < ε` (mm or rad) or the iteration limit. `P` holds the
//! points' prior weights (1 without standard deviations). The statistics of the estimate (σ0, the
//! normal equations) come from the last evaluation, one step (< ε) before it, with the
//! residual moved by that step to first order: no further evaluation.

use nalgebra::DVector;
use serde::Deserialize;

use super::solver::{check_stop, gauss_newton, LeastSquares, Solver};
use super::Identified;
use crate::error::Result;
use crate::numeric::Real;

/// Options of `ls` (docs/formats.md `[[methods]]`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LsOptions {
    /// Stop when `max |δx| < eps` (mm or rad). Default 1e-9.
    pub eps: Real,
    /// Iteration limit. Default 100.
    pub max_iter: usize,
}

impl Default for LsOptions {
    fn default() -> Self {
        LsOptions {
            eps: 1e-9,
            max_iter: 100,
        }
    }
}

impl Solver for LsOptions {
    fn check(&self) -> Result<()> {
        check_stop(self.eps, self.max_iter)
    }

    fn run(&self, p: &dyn LeastSquares, x0: &DVector<Real>) -> Identified {
        gauss_newton(p, (x0, x0), self.eps, self.max_iter, None, None)
    }
}
