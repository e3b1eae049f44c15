//! Levenberg–Marquardt (Guo 2024 eq. 8; Ban, LM with adaptive damping).
//!
//! Each iteration solves `(JᵀJ + μ M) Δx = Jᵀ ΔP` with `ΔP = measured − model(x)` and
//! `M = I`, or `M = diag(JᵀJ)` with Marquardt's scaling ([`LmOptions::marquardt`]).
//!
//! - Fixed damping (Guo 2024 eq. 8, `μ = 1`): every step is taken; stop when `max |Δx| < ε`
//!   and the damping alone did not hold the step small (`converged_step`); the statistics
//!   then come from the last evaluation, `Work::take_step_in_residual`.
//!   With `M = I` it converges linearly: per iteration the error along an eigenvector of
//!   `JᵀJ` with eigenvalue σ² shrinks by `μ / (σ² + μ)`, slowly where σ² is small against μ
//!   (docs/formats.md `lm`: weakly seen lengths of arms with parallel joints 2 and 3).
//! - Adaptive damping (Ban: `λ0 = 0.01`, `ε = 1e-5`, `kmax = 50`): a step is accepted when it
//!   lowers `|ΔP|²`, and λ is then divided by the factor (10); otherwise λ is multiplied by it
//!   and the step is solved again. Stop when an accepted step has `max |Δx| < ε` as above
//!   ([`super::Termination::Converged`], also when a step that small no longer lowers the
//!   cost), after `kmax` iterations, or when λ exceeds 1e16 without a lower cost
//!   ([`super::Termination::NoProgress`]).

use nalgebra::DVector;
use serde::Deserialize;

use super::solver::{
    at_rounding_floor, check_stop, finish, max_abs, start_weights, LeastSquares, Solver, Work,
    DIVERGENCE_FACTOR,
};
use super::{Identified, Termination};
use crate::error::{finite_non_negative, finite_positive, Error, Result};
use crate::numeric::linalg::{cholesky_in_place, cholesky_solve};
use crate::numeric::Real;

/// Options of `lm` (docs/formats.md `[[methods]]`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LmOptions {
    /// Fixed damping μ (Guo 2024 eq. 8). Default 1.
    pub mu: Real,
    /// Adaptive damping (Ban) instead of the fixed μ. Default false.
    pub adaptive: bool,
    /// Initial λ of the adaptive form. Default 0.01 (Ban).
    pub lambda0: Real,
    /// Factor by which λ falls after a good step and grows after a bad one. Default 10.
    pub lambda_factor: Real,
    /// Marquardt's scaling `M = diag(JᵀJ)` instead of `I`. Default false.
    pub marquardt: bool,
    /// Stop when `max |Δx| < eps` (mm or rad). Default 1e-5 (Ban's ε).
    pub eps: Real,
    /// Iteration limit kmax. Default 50 (Ban).
    pub max_iter: usize,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            mu: 1.0,
            adaptive: false,
            lambda0: 0.01,
            lambda_factor: 10.0,
            marquardt: false,
            eps: 1e-5,
            max_iter: 50,
        }
    }
}

/// Solves the damped normal equations `(N + damping · M) Δx = g` for `work.dx`, with `N`
/// and `g` from `work` (left unchanged: the damped matrix is formed in the factorisation
/// buffer) and `M = I` or, with Marquardt's scaling, `diag(N)`. Returns false when the damped
/// matrix is numerically singular.
fn solve_damped(work: &mut Work, damping: Real, marquardt: bool) -> bool {
    work.a.copy_from(&work.n);
    for k in 0..work.n.nrows() {
        work.a[(k, k)] += damping * damping_scale(work, k, marquardt);
    }
    if !cholesky_in_place(&mut work.a) {
        return false;
    }
    work.dx.copy_from(&work.g);
    cholesky_solve(&work.a, &mut work.dx);
    work.dx.iter().all(|v| v.is_finite())
}

/// `M`'s diagonal entry `k`: 1, or with Marquardt's scaling `N`'s (at least the smallest
/// positive number, so that a column of zeros is still damped).
fn damping_scale(work: &Work, k: usize, marquardt: bool) -> Real {
    if marquardt {
        work.n[(k, k)].max(Real::MIN_POSITIVE)
    } else {
        1.0
    }
}

/// Whether a step `work.dx` solved from `work`'s normal equations with `damping` ends the
/// solve at `x` (the step taken; `x0` the start): below `eps` (max |Δx|), and not held small
/// by the damping alone. After the step the linearised gradient is `damping · M Δx`; its ratio
/// `r` to the gradient before the step is the step's contraction (per direction
/// `μ / (σ² + μ)`), so the steps still to come add up to about `max |Δx| · r / (1 − r)`. A
/// solve whose remaining way is longer than the way it has come, `max |x − x0|`, has not
/// converged however small its step: a damping far above `JᵀJ` (`mu = 1e12`) makes every step
/// tiny while the cost barely moves, and would otherwise end `converged` at its start.
fn converged_step(
    work: &Work,
    (damping, marquardt): (Real, bool),
    eps: Real,
    x: &DVector<Real>,
    x0: &DVector<Real>,
) -> bool {
    let step = max_abs(&work.dx);
    if step >= eps {
        return false;
    }
    let (mut after, mut before) = (0.0, 0.0);
    for k in 0..work.dx.len() {
        let m = damping_scale(work, k, marquardt);
        after = Real::max(after, (damping * m * work.dx[k]).abs());
        before = Real::max(before, work.g[k].abs());
    }
    let r = if before > 0.0 { after / before } else { 0.0 };
    let come = x
        .iter()
        .zip(x0)
        .fold(0.0, |m: Real, (a, b)| m.max((a - b).abs()));
    r < 1.0 && step * r <= come * (1.0 - r)
}

/// The keys of the two dampings: the fixed one's, and the adaptive one's.
const MU: &str = "mu";
const LAMBDA0: &str = "lambda0";
const LAMBDA_FACTOR: &str = "lambda_factor";

/// Refuses, as (key, message), a damping key of the entry `t` (as written) that the form it
/// chooses does not read: `mu` with `adaptive = true`, `lambda0` or `lambda_factor` without.
pub(crate) fn refuse_unread(t: &toml::Table) -> std::result::Result<(), (String, String)> {
    let adaptive = t.get("adaptive").and_then(toml::Value::as_bool) == Some(true);
    let (unread, why) = match adaptive {
        true => (
            &[MU][..],
            "the adaptive damping starts at lambda0 (drop mu)",
        ),
        false => (
            &[LAMBDA0, LAMBDA_FACTOR][..],
            "the fixed damping is mu (set adaptive = true, or drop it)",
        ),
    };
    match unread.iter().find(|k| t.contains_key(**k)) {
        Some(k) => Err((
            k.to_string(),
            format!("is not read with adaptive = {adaptive}: {why}"),
        )),
        None => Ok(()),
    }
}

impl Solver for LmOptions {
    fn tolerates_rank_deficiency(&self) -> bool {
        // μ I (or the adaptive λ) keeps JᵀJ + μI invertible; μ = 0 without adaptation is
        // Gauss–Newton.
        self.adaptive || self.mu > 0.0
    }

    fn check(&self) -> Result<()> {
        check_stop(self.eps, self.max_iter)?;
        finite_non_negative(MU, self.mu)?;
        finite_positive(LAMBDA0, self.lambda0)?;
        if !(self.lambda_factor.is_finite() && self.lambda_factor > 1.0) {
            return Err(Error::setting(
                LAMBDA_FACTOR,
                format!("must be finite and above 1, got {}", self.lambda_factor),
            ));
        }
        Ok(())
    }

    fn run(&self, p: &dyn LeastSquares, x0: &DVector<Real>) -> Identified {
        levenberg_marquardt(p, x0, self)
    }
}

fn levenberg_marquardt(p: &dyn LeastSquares, x0: &DVector<Real>, o: &LmOptions) -> Identified {
    if o.adaptive {
        return adaptive(p, x0, o);
    }
    let mut work = Work::new(p);
    let w = start_weights(p);
    let mut x = x0.clone();
    let mut cost0 = Real::NAN;
    let mut termination = Termination::MaxIterations;
    let mut iterations = 0;
    for it in 0..o.max_iter {
        let cost = work.evaluate(p, &x, &w);
        if !cost.is_finite() || (it > 0 && cost > DIVERGENCE_FACTOR * cost0) {
            termination = Termination::Diverged;
            break;
        }
        if it == 0 {
            cost0 = cost.max(Real::MIN_POSITIVE);
        }
        work.normal(p, &w);
        if !solve_damped(&mut work, o.mu, o.marquardt) {
            termination = Termination::Singular;
            break;
        }
        x += &work.dx;
        iterations = it + 1;
        if converged_step(&work, (o.mu, o.marquardt), o.eps, &x, x0)
            || at_rounding_floor(p, &w, cost, (&work.g, &work.dx))
        {
            termination = Termination::Converged;
            work.take_step_in_residual(p);
            break;
        }
    }
    let fresh = termination == Termination::Converged;
    finish_lm(p, &mut work, x, w, iterations, termination, fresh)
}

fn adaptive(p: &dyn LeastSquares, x0: &DVector<Real>, o: &LmOptions) -> Identified {
    let mut work = Work::new(p);
    let w = start_weights(p);
    let mut x = x0.clone();
    let mut x_try = x0.clone();
    let mut cost = work.evaluate(p, &x, &w);
    // Whether the residual and Jacobian in `work` are those at `x`. A trial evaluation
    // overwrites them but leaves the normal equations of `x`, from which the next, more
    // damped step is solved; only an accepted trial forms new ones.
    let mut fresh = cost.is_finite();
    let mut termination = Termination::MaxIterations;
    let mut iterations = 0;
    let mut lambda = o.lambda0;
    if !cost.is_finite() {
        termination = Termination::Diverged;
    } else {
        work.normal(p, &w);
        'outer: for _ in 0..o.max_iter {
            loop {
                let ok = solve_damped(&mut work, lambda, o.marquardt);
                let step = max_abs(&work.dx);
                if ok {
                    x_try.copy_from(&x);
                    x_try += &work.dx;
                    let c = work.evaluate(p, &x_try, &w);
                    let done = converged_step(&work, (lambda, o.marquardt), o.eps, &x_try, x0);
                    if c.is_finite() && c < cost {
                        std::mem::swap(&mut x, &mut x_try);
                        cost = c;
                        lambda /= o.lambda_factor;
                        iterations += 1;
                        work.normal(p, &w);
                        fresh = true;
                        if done {
                            termination = Termination::Converged;
                            break 'outer;
                        }
                        break;
                    }
                    fresh = false;
                    if step < o.eps {
                        termination = Termination::Converged;
                        break 'outer;
                    }
                }
                lambda *= o.lambda_factor;
                if lambda > 1e16 {
                    termination = if ok {
                        Termination::NoProgress
                    } else {
                        Termination::Singular
                    };
                    break 'outer;
                }
            }
        }
    }
    finish_lm(p, &mut work, x, w, iterations, termination, fresh)
}

/// [`finish`] without a ridge parameter or a robust σ0 (LM reports neither).
fn finish_lm(
    p: &dyn LeastSquares,
    work: &mut Work,
    x: DVector<Real>,
    w: Vec<Real>,
    iterations: usize,
    termination: Termination,
    fresh: bool,
) -> Identified {
    finish(p, work, x, w, iterations, termination, None, None, fresh)
}
