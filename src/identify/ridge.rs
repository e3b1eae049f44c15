//! Ridge estimation (Li 2018 eq. 14).
//!
//! Iteration k solves `(JᵀPJ + ξ_k D) δx = JᵀP E − ξ_k D (x − x0)` (the Gauss–Newton step of
//! the ridge objective `EᵀPE + ξ (x − x0)ᵀ D (x − x0)`; from `x0` it is Li's eq. 14). With
//! [`RidgeOptions::scale`] `D = diag(JᵀPJ)` at the start (`x0`, or a second fit's start:
//! [`super::solver::solve_from`]), i.e. ξ acts on the column-scaled problem
//! `A = P^½ J D^-½` whose columns have unit norm, so one ξ means the same for mm and rad
//! columns; without it `D = I` (Li's literal form, ξ in the units of `JᵀPJ`). ξ is fixed or
//! chosen anew at every iteration by one of the rules of [`super::xi`].

use nalgebra::DVector;
use serde::{Deserialize, Serialize};

use super::solver::{check_stop, gauss_newton, Column, LeastSquares, RidgeCfg, Solver};
use super::xi::XiRule;
use super::Identified;
use crate::error::Result;
use crate::numeric::Real;

/// Options of `ridge` (docs/formats.md `[[methods]]`).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RidgeOptions {
    /// The ξ rule. Default [`XiRule::DoubleH`].
    pub xi: XiRule,
    /// Column scaling `D = diag(JᵀPJ)` at the start (see the module docs). Default true.
    pub scale: bool,
    /// Stop when `max |δx| < eps` (mm or rad). Default 1e-9.
    pub eps: Real,
    /// Iteration limit. Default 100.
    pub max_iter: usize,
}

impl Default for RidgeOptions {
    fn default() -> Self {
        RidgeOptions {
            xi: XiRule::DoubleH,
            scale: true,
            eps: 1e-9,
            max_iter: 100,
        }
    }
}

impl RidgeOptions {
    /// The ridge settings as the Gauss–Newton engine takes them.
    pub(crate) fn cfg(&self) -> RidgeCfg<'_> {
        RidgeCfg {
            xi: &self.xi,
            scale: self.scale,
        }
    }
}

impl Solver for RidgeOptions {
    fn tolerates_rank_deficiency(&self) -> bool {
        true
    }

    fn check(&self) -> Result<()> {
        self.xi.check("xi")?;
        check_stop(self.eps, self.max_iter)
    }

    fn run(&self, p: &dyn LeastSquares, x0: &DVector<Real>) -> Identified {
        self.run_from(p, (x0, x0))
    }

    fn run_from(&self, p: &dyn LeastSquares, from: (&Column, &Column)) -> Identified {
        gauss_newton(p, from, self.eps, self.max_iter, Some(self.cfg()), None)
    }
}
