//! Iterated Gauss–Newton least squares (Li 2018 eq. 13), and the Gauss–Newton engine shared
//! with ridge and the robust ridge.
//!
//! Each iteration solves `(JᵀPJ) δx = JᵀP E` with `E = measured − model(x)` and updates
//! `x ← x + δx` until `max |δx| < ε` (mm or rad) or the iteration limit. `P` is the identity
//! here (all points weight 1).

use nalgebra::DVector;

use super::linalg::solve_spd;
use super::ridge::{choose_xi, XiRule};
use super::robust::{point_weights, RobustOptions};
use super::{finish, max_abs, Identified, Problem, Termination, Work, DIVERGENCE_FACTOR};
use crate::math::Real;

/// Settings of [`super::Method::Ls`].
#[derive(Clone, Debug)]
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

pub(crate) fn run(p: &dyn Problem, x0: &DVector<Real>, o: &LsOptions) -> Identified {
    gauss_newton(p, x0, o.eps, o.max_iter, None, None)
}

/// Ridge settings as the engine sees them.
pub(crate) struct RidgeCfg<'a> {
    pub xi: &'a XiRule,
    pub scale: bool,
}

/// The Gauss–Newton engine: plain (Li eq. 13), ridge-penalised towards `x0` (eq. 14) and
/// iteratively reweighted (§2.2).
///
/// With a ridge, iteration k solves `(JᵀPJ + ξ_k D) δx = JᵀP E − ξ_k D (x − x0)`: the
/// Gauss–Newton step of `EᵀPE + ξ (x − x0)ᵀ D (x − x0)`. From `x = x0` this is exactly Li's
/// eq. 14; the penalty on the total `x − x0` (rather than on each increment) keeps the
/// shrinkage when the iterations converge, instead of relaxing to the least-squares answer.
/// `D = diag(JᵀPJ)` at `x0` (column scaling, so ξ is relative to unit-norm columns) or `I`.
///
/// With robust weights, the points first all weigh 1 until the step falls below ε; from
/// then on each iteration reweighs every point from the residuals at the current `x` and
/// stops when a reweighted step falls below ε.
pub(crate) fn gauss_newton(
    p: &dyn Problem,
    x0: &DVector<Real>,
    eps: Real,
    max_iter: usize,
    ridge: Option<RidgeCfg>,
    robust: Option<&RobustOptions>,
) -> Identified {
    let t = x0.len();
    let mut work = Work::new(p);
    let mut w = vec![1.0; p.n_points()];
    let mut x = x0.clone();
    let mut d = DVector::from_element(t, 1.0);
    let mut dev = DVector::zeros(t);
    let mut sort_buf: Vec<Real> = Vec::with_capacity(work.r.len());
    let mut reweighting = false;
    let mut cost0 = Real::NAN;
    let mut rms0 = Real::NAN;
    let mut xi_used = None;
    let mut termination = Termination::MaxIterations;
    let mut iterations = 0;
    let mut sigma_mad = None;
    for it in 0..max_iter {
        let cost = work.evaluate(p, &x, &w);
        if !cost.is_finite() {
            termination = Termination::Diverged;
            break;
        }
        if it == 0 {
            cost0 = cost;
            rms0 = (work.r.norm_squared() / w.len() as Real).sqrt();
        } else if cost > DIVERGENCE_FACTOR * cost0.max(Real::MIN_POSITIVE) {
            termination = Termination::Diverged;
            break;
        }
        if let (true, Some(ro)) = (reweighting, robust) {
            let s = point_weights(&work.r, work.rows, t, ro, rms0, &mut w, &mut sort_buf);
            sigma_mad = s.mad;
        }
        work.normal(&w);
        if let Some(rc) = &ridge {
            if it == 0 && rc.scale {
                for k in 0..t {
                    let v = work.n[(k, k)];
                    d[k] = if v > 0.0 && v.is_finite() { v } else { 1.0 };
                }
            }
            dev.copy_from(&x);
            dev -= x0;
            let cost_now = super::weighted_cost(&work.r, work.rows, &w);
            let n_rows = work.rows * w.iter().filter(|&&v| v > 0.0).count();
            let xi = choose_xi(rc.xi, &work.n, &work.g, cost_now, &dev, &d, n_rows);
            xi_used = Some(xi);
            for k in 0..t {
                work.n[(k, k)] += xi * d[k];
                work.g[k] -= xi * d[k] * dev[k];
            }
        }
        if !solve_spd(&work.n, &work.g, &mut work.a, &mut work.dx) {
            termination = Termination::Singular;
            break;
        }
        x += &work.dx;
        iterations = it + 1;
        if max_abs(&work.dx) < eps {
            if robust.is_some() && !reweighting {
                reweighting = true;
                continue;
            }
            termination = Termination::Converged;
            break;
        }
    }
    let sigma0 = match robust {
        Some(ro) if ro.sigma0 == super::Sigma0::Mad => sigma_mad,
        _ => None,
    };
    finish(p, &mut work, x, w, iterations, termination, xi_used, sigma0)
}
