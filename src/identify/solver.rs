//! The nonlinear least-squares engine under the Jacobian-based methods: the
//! [`LeastSquares`] problem trait, the shared buffers and normal equations (in the module
//! `work`), the Gauss–Newton iteration of LS, ridge and the robust ridge (Li 2018 eqs. 13–14,
//! §2.2), and the statistics of a solution (`finish`, with [`rank`] and [`conditioning`], in
//! the module `statistics`).
//!
//! A solver is any [`Solver`]: it runs on a [`LeastSquares`] problem from a start `x0` and
//! returns an [`Identified`]. [`solve`] checks the problem and the options first, so a
//! solver never sees inconsistent sizes, a non-finite start or fewer rows than unknowns.

mod statistics;
mod work;

use nalgebra::{DMatrix, DVector};

use super::weights::{point_weights, redecide_inliers, Residuals, Robustness, Sigma0};
use super::xi::{choose_xi, RidgeStep, XiRule};
use super::{Identified, Termination};
use crate::error::Result;
use crate::numeric::linalg::solve_spd;
use crate::numeric::Real;

pub(crate) use statistics::finish;
pub use statistics::{
    bound_inverse, conditioning, inverse_diagonal, rank, DETERMINABLE_SIGMAS, RANK_TOLERANCE,
};
pub(crate) use work::Work;

/// A column vector of the problems (unknowns, residual).
pub type Column = DVector<Real>;

/// A matrix of the problems (Jacobian, normal equations).
pub type Matrix = DMatrix<Real>;

/// The size of a [`LeastSquares`] problem.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    /// Number of unknowns `t`.
    pub params: usize,
    /// Number of measured points (each carries one weight in the robust methods).
    pub points: usize,
    /// Rows of the residual per point (3 for positions, 6 for full poses).
    pub rows_per_point: usize,
}

impl Size {
    /// `params` unknowns, `points` measured points of `rows_per_point` rows each.
    pub fn new(params: usize, points: usize, rows_per_point: usize) -> Size {
        Size {
            params,
            points,
            rows_per_point,
        }
    }

    /// Rows of the residual, `points · rows_per_point`.
    pub fn rows(&self) -> usize {
        self.points * self.rows_per_point
    }
}

/// A nonlinear least-squares problem: residuals of `points` points with `rows_per_point`
/// rows each, over `params` unknowns ([`Size`]).
pub trait LeastSquares {
    /// The problem's size.
    fn size(&self) -> Size;
    /// Prior weight of each point (`P` of the normal equations before any robust
    /// reweighting); `None`: every point weighs 1.
    fn prior(&self) -> Option<&[Real]> {
        None
    }
    /// r = measured − model(x) (length `size().rows()`), j = ∂model/∂x
    /// (`size().rows() × size().params`). Both buffers come with the right sizes.
    fn evaluate(&self, x: &DVector<Real>, r: &mut DVector<Real>, j: &mut DMatrix<Real>);
    /// Tikhonov precision `λ_k` of each unknown (a prior `x_k ~ N(0, 1/λ_k)` in the units of
    /// the weighted cost; 0: none): the MAP estimate minimises `rᵀPr + Σ λ_k x_k²`. `None`:
    /// no priors.
    fn tikhonov(&self) -> Option<&[Real]> {
        None
    }
    /// The squared norm of one point's residual that is only the rounding of the data and of
    /// the model's evaluation. Weighed by the points' weights, it is the cost at or below
    /// which a step is that rounding amplified by the normal equations: a fit there that its
    /// next step cannot lower by more has converged. 0 (the default): no floor is known, and
    /// only the step rule stops the solvers.
    fn rounding_floor(&self) -> Real {
        0.0
    }
    /// Whether the problem is large enough that the solvers should evaluate it block by block
    /// ([`LeastSquares::evaluate_points`]) and accumulate the normal equations
    /// ([`crate::numeric::normal::NormalEquations`]) instead of holding the whole Jacobian:
    /// `Some` with the points per block. `None` (the default): [`LeastSquares::evaluate`],
    /// whole.
    fn block_points(&self) -> Option<usize> {
        None
    }
    /// [`LeastSquares::evaluate`] of the points `i..i + count` only, `count` the
    /// points `r` has room for: `r` holds their rows and `j` their Jacobian rows, in the
    /// order of the whole problem. The default evaluates the whole problem and copies the
    /// block (correct, not economical: a problem that returns [`LeastSquares::block_points`]
    /// overrides it).
    fn evaluate_points(&self, x: &Column, i: usize, r: &mut Column, j: &mut Matrix) {
        let size = self.size();
        let mut rw = DVector::zeros(size.rows());
        let mut jw = DMatrix::zeros(size.rows(), size.params);
        self.evaluate(x, &mut rw, &mut jw);
        let row0 = i * size.rows_per_point;
        r.copy_from(&rw.rows(row0, r.len()));
        j.copy_from(&jw.rows(row0, r.len()));
    }
}

/// Problems of more points than this are evaluated block by block when they can be
/// ([`LeastSquares::block_points`]): a study's few hundred poses, and any file below this size,
/// keep the whole-Jacobian path, whose bits the studies' outputs are fixed by.
pub const STREAM_MIN_POINTS: usize = 4096;

/// Points per block of a streamed problem: a block's Jacobian (1536 × 30 values for
/// positions and thirty parameters, 370 kB) stays in the processor's cache.
pub const BLOCK_POINTS: usize = 512;

/// Calls `f(points, r, j)` for each block of up to [`BLOCK_POINTS`] points of `p` at `x`, in
/// order, with the block's residual rows and Jacobian ([`LeastSquares::evaluate_points`]) in
/// buffers made for the first block and again only for a shorter last one: memory stays
/// bounded for files of millions of rows. The solvers' own passes over a streamed problem
/// keep their buffers from one iteration to the next instead.
pub fn by_blocks(
    p: &dyn LeastSquares,
    x: &DVector<Real>,
    mut f: impl FnMut(std::ops::Range<usize>, &DVector<Real>, &DMatrix<Real>),
) {
    let size = p.size();
    let rows = size.rows_per_point;
    let (mut r, mut j) = (DVector::zeros(0), DMatrix::zeros(0, 0));
    for first in (0..size.points).step_by(BLOCK_POINTS) {
        let k = BLOCK_POINTS.min(size.points - first);
        if r.len() != k * rows {
            r = DVector::zeros(k * rows);
            j = DMatrix::zeros(k * rows, size.params);
        }
        p.evaluate_points(x, first, &mut r, &mut j);
        f(first..first + k, &r, &j);
    }
}

/// Whether a problem of `points` points is streamed ([`STREAM_MIN_POINTS`]).
pub fn streams(points: usize) -> bool {
    points > STREAM_MIN_POINTS
}

/// A Jacobian-based method: it solves any [`LeastSquares`] problem. Every solver is a
/// [`super::Method`]: on a calibration problem it solves the kinematic least squares
/// ([`super::robot::identify_robot`]).
pub trait Solver: std::fmt::Debug + Send + Sync {
    /// Checks the option values; an error names the offending key.
    fn check(&self) -> Result<()>;
    /// Runs from `x0` on a problem [`solve`] has checked.
    fn run(&self, p: &dyn LeastSquares, x0: &DVector<Real>) -> Identified;
    /// Runs from `start` of `(x0, start)` on a problem [`solve_from`] has checked; `x0` stays
    /// the point a ridge penalises towards. A method without one runs from `start`.
    fn run_from(&self, p: &dyn LeastSquares, (_, start): (&Column, &Column)) -> Identified {
        self.run(p, start)
    }
    /// See [`super::Method::tolerates_rank_deficiency`].
    fn tolerates_rank_deficiency(&self) -> bool {
        false
    }
}

/// The weights the iterations start from: the problem's prior weights, or 1.
pub(crate) fn start_weights(p: &dyn LeastSquares) -> Vec<Real> {
    p.prior()
        .map_or_else(|| vec![1.0; p.size().points], <[Real]>::to_vec)
}

/// Checks the stopping rule of the Gauss–Newton methods: `eps` finite and positive,
/// `max_iter` at least 1.
pub(crate) fn check_stop(eps: Real, max_iter: usize) -> Result<()> {
    crate::error::finite_positive("eps", eps)?;
    crate::error::check_count("max_iter", max_iter)
}

/// Runs `solver` on `p` from `x0`.
///
/// Never panics on bad input: inconsistent sizes, a non-finite start or invalid options give
/// [`Termination::InvalidInput`] with `x = x0`. Fewer residual rows than unknowns give
/// [`Termination::RankDeficient`] with `x = x0` and the rows as `rank`, refused as any.
pub fn solve(solver: &dyn Solver, p: &dyn LeastSquares, x0: &DVector<Real>) -> Identified {
    solve_from(solver, p, (x0, x0))
}

/// [`solve`] from `start` of `(x0, start)` ([`Solver::run_from`]): a second fit started where
/// its parameters are determined, `x0` (the nominal robot) staying the ridge's point.
pub fn solve_from(
    solver: &dyn Solver,
    p: &dyn LeastSquares,
    from: (&Column, &Column),
) -> Identified {
    let (x0, start) = from;
    if check_problem(p, x0).or(check_problem(p, start)).is_some() || solver.check().is_err() {
        return unsolved(p, x0, Termination::InvalidInput, None);
    }
    let rows = p.size().rows();
    if rows < x0.len() {
        return unsolved(p, x0, Termination::RankDeficient, Some(rows));
    }
    solver.run_from(p, from)
}

fn check_problem(p: &dyn LeastSquares, x0: &DVector<Real>) -> Option<&'static str> {
    let size = p.size();
    let t = size.params;
    if t == 0 || size.rows_per_point == 0 || size.points == 0 {
        return Some("empty problem");
    }
    if x0.len() != t {
        return Some("x0 has the wrong length");
    }
    if x0.iter().any(|v| !v.is_finite()) {
        return Some("x0 is not finite");
    }
    None
}

/// The result of a problem not solved: `x0`, ending `termination` before any iteration.
fn unsolved(
    p: &dyn LeastSquares,
    x0: &DVector<Real>,
    termination: Termination,
    rank: Option<usize>,
) -> Identified {
    let t = x0.len();
    Identified {
        x: x0.clone(),
        iterations: 0,
        termination,
        weights: start_weights(p),
        row_weights: None,
        own_weights: true,
        normal: DMatrix::from_element(t, t, Real::NAN),
        sigma0: Real::NAN,
        rms_residual: Real::NAN,
        ridge_xi: None,
        evaluations: 0,
        trace: None,
        rank,
    }
}

/// `Σ_i w_i |r_i|²` over points.
pub(crate) fn weighted_cost(r: &DVector<Real>, rows: usize, w: &[Real]) -> Real {
    let mut c = 0.0;
    for (i, &wi) in w.iter().enumerate() {
        let mut s = 0.0;
        for k in 0..rows {
            s += r[i * rows + k] * r[i * rows + k];
        }
        c += wi * s;
    }
    c
}

/// Whether a reweighting round has settled: the rejected points (weight 0) are the ones of
/// the round before. Only that set reaches the estimate (the final refit keeps the others
/// with their prior weights), so the down-weighted band need not settle too: waiting for
/// every weight to stop moving cost two to four more rounds on clean data, and the refit's
/// accuracy came out the same or better without them.
fn settled(w: &[Real], before: &[Real]) -> bool {
    w.iter()
        .zip(before)
        .all(|(&a, &b)| (a == 0.0) == (b == 0.0))
}

/// `max |v_i|`.
pub(crate) fn max_abs(v: &DVector<Real>) -> Real {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Whether the fit stands at the rounding floor of its data: its cost and the decrease that
/// the step `dx` solved from the gradient `g` promises (`g·dx`, the Gauss–Newton model's
/// decrease of the objective, the ridge's pull included) both at or below the point weights
/// `w` times [`LeastSquares::rounding_floor`]. On exact data from poses that determine some
/// parameter weakly, the step there is rounding noise of 1e-8 or more, which a step rule of
/// 1e-9 alone ends only by chance.
pub(crate) fn at_rounding_floor(
    p: &dyn LeastSquares,
    w: &[Real],
    cost: Real,
    (g, dx): (&DVector<Real>, &DVector<Real>),
) -> bool {
    let floor = p.rounding_floor() * w.iter().sum::<Real>();
    floor > 0.0 && cost <= floor && g.dot(dx) <= floor
}

/// Cost growth beyond which an iteration counts as diverged.
pub(crate) const DIVERGENCE_FACTOR: Real = 1e12;

/// Ridge settings as the engine sees them.
pub(crate) struct RidgeCfg<'a> {
    pub xi: &'a XiRule,
    pub scale: bool,
}

/// Rounds of reweighting needed before the robust iterations may stop reweighting.
const MIN_ROUNDS: usize = 2;

/// The robust ridge starts reweighting after a step below this (mm or rad): the next
/// estimate is then within about its square of the unweighted solution (0.01 mm), closer than
/// the weights need: the rounds that follow re-solve anyway. (At 1e-2 the switch came one
/// Gauss–Newton step later with the same results.)
const SWITCH_STEP: Real = 1e-1;

/// Steps of the refit at which the rejected set may still be re-decided; after them it is
/// fixed, so the refit always ends.
const REDECISIONS: usize = 4;

/// The phase of the Gauss–Newton engine.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// The prior weights (every method; the robust ridge's first solution).
    Prior,
    /// The robust ridge's reweighting rounds.
    Reweight,
    /// The robust ridge's final refit on the points it kept.
    Refit,
}

/// The Gauss–Newton engine: plain (Li eq. 13), ridge-penalised towards `x0` (eq. 14) and
/// iteratively reweighted (§2.2).
///
/// With a ridge, iteration k solves `(JᵀPJ + ξ_k D) δx = JᵀP E − ξ_k D (x − x0)`: the
/// Gauss–Newton step of `EᵀPE + ξ (x − x0)ᵀ D (x − x0)`. From `x = x0` this is exactly Li's
/// eq. 14; the penalty on the total `x − x0` (rather than on each increment) keeps the
/// shrinkage when the iterations converge, instead of relaxing to the least-squares answer.
/// `D = diag(JᵀPJ)` at `start` (column scaling, so ξ is relative to unit-norm columns) or `I`.
/// The iterations start at `start`, `x0` but for a re-admission's fit (docs/formats.md § 2.6.1).
///
/// With robust weights the iterations run in three phases, all in one loop:
/// 1. the points keep their prior weights until the step falls below [`SWITCH_STEP`] (the
///    residuals are then as close to those of the unweighted solution as the weights need);
/// 2. every iteration reweighs every point from the residuals at the current `x` (one
///    reweighting round) and takes one step; the rounds stop when the weights have settled
///    ([`settled`]): at least [`MIN_ROUNDS`] rounds, and the set of rejected points (weight 0)
///    unchanged;
/// 3. a final refit gives the kept points their prior weights and the rejected ones 0, and
///    iterates until the step falls below ε ([`Termination::Converged`]). The rejected set
///    is decided from the residuals at the robust estimate, and anew at each of the refit's
///    first [`REDECISIONS`] steps, by rejection of `u > k1` with σ0 the classical estimate
///    over the kept points, coming down from all points
///    ([`super::weights::redecide_inliers`]); the refit only ends on a step that left the set
///    unchanged. (The rounds' σ0 comes from down-weighted residuals and is biased low: their
///    own zero weights would also drop good points.)
///
/// The refit is the "reweighted then re-estimated" form of robust estimation: the
/// redescending weights only decide which points are gross errors, and the estimate is the
/// efficient least-squares one on the others — Hampel, Ronchetti, Rousseeuw & Stahel,
/// *Robust Statistics* (1986) §1.4 (rejection followed by least squares); Rousseeuw & Leroy,
/// *Robust Regression and Outlier Detection* (1987) ch. 1 §2, the reweighted least squares
/// after a robust fit. IGG3's down-weighting of the suspicious band `k0 < u ≤ k1` alone costs
/// about 8 % in efficiency on clean data (a tenth of the points of a normal sample fall in
/// it); the refit gives that back while the gross errors (u > k1) stay out.
pub(crate) fn gauss_newton(
    p: &dyn LeastSquares,
    (x0, start): (&DVector<Real>, &DVector<Real>),
    eps: Real,
    max_iter: usize,
    ridge: Option<RidgeCfg>,
    robust: Option<&Robustness>,
) -> Identified {
    let t = x0.len();
    let mut work = Work::new(p);
    let mut w = start_weights(p);
    let mut w_prev = w.clone();
    let mut x = start.clone();
    let mut d = DVector::from_element(t, 1.0);
    let mut dev = DVector::zeros(t);
    let mut sort_buf: Vec<Real> = Vec::with_capacity(work.r.len());
    let mut phase = Phase::Prior;
    let mut rounds = 0;
    let mut redecisions = 0;
    let mut set_changed = false;
    let mut kept: Vec<bool> = Vec::with_capacity(w.len());
    let mut cost0 = Real::NAN;
    let mut rms0 = Real::NAN;
    let mut xi_used = None;
    let mut termination = Termination::MaxIterations;
    let mut iterations = 0;
    let mut sigma_mad = None;
    let switch = if robust.is_some() {
        SWITCH_STEP.max(eps)
    } else {
        eps
    };
    // The σ0 per row of residuals that are only rounding, at the mean prior weight.
    let mean_prior = p
        .prior()
        .map_or(1.0, |q| q.iter().sum::<Real>() / q.len().max(1) as Real);
    let sigma_floor = (p.rounding_floor() * mean_prior / work.rows as Real).sqrt();
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
        if let Some(o) = robust {
            let res = Residuals {
                r: &work.r,
                rows: work.rows,
                t,
                rms0,
                sigma_floor,
                prior: p.prior(),
                o,
            };
            match phase {
                Phase::Refit if redecisions < REDECISIONS => {
                    set_changed = redecide_inliers(&res, &mut w, &mut kept);
                    redecisions += 1;
                }
                Phase::Refit => set_changed = false,
                Phase::Reweight => {
                    w_prev.copy_from_slice(&w);
                    sigma_mad = point_weights(&res, &mut w, &mut sort_buf).mad;
                    rounds += 1;
                    if rounds >= MIN_ROUNDS && settled(&w, &w_prev) {
                        redecide_inliers(&res, &mut w, &mut kept);
                        phase = Phase::Refit;
                    }
                }
                Phase::Prior => {}
            }
        }
        work.normal(p, &w);
        if let Some(rc) = &ridge {
            if it == 0 && rc.scale {
                for k in 0..t {
                    let v = work.n[(k, k)];
                    d[k] = if v > 0.0 && v.is_finite() { v } else { 1.0 };
                }
            }
            dev.copy_from(&x);
            dev -= x0;
            let cost_now = weighted_cost(&work.r, work.rows, &w);
            let n_rows = work.rows * w.iter().filter(|&&v| v > 0.0).count();
            let step = RidgeStep {
                n: &work.n,
                g: &work.g,
                cost: cost_now,
                dev: &dev,
                d: &d,
                n_rows,
            };
            let xi = choose_xi(rc.xi, &step, &mut work.a, &mut work.dx);
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
        iterations = it + 1;
        let step = max_abs(&work.dx);
        let floor = at_rounding_floor(p, &w, cost, (&work.g, &work.dx));
        let converged = match phase {
            Phase::Prior if robust.is_some() => {
                if step < switch || floor {
                    phase = Phase::Reweight;
                }
                false
            }
            Phase::Reweight => false,
            Phase::Prior | Phase::Refit => (step < eps || floor) && !set_changed,
        };
        x += &work.dx;
        if converged {
            termination = Termination::Converged;
            work.take_step_in_residual(p);
            break;
        }
    }
    let sigma0 = match robust {
        Some(ro) if ro.sigma0 == Sigma0::Mad => sigma_mad,
        _ => None,
    };
    let fresh = termination == Termination::Converged;
    if fresh && ridge.is_some() {
        // The ridge term was added to the normal equations in place: form them again.
        work.normal(p, &w);
    }
    finish(
        p,
        &mut work,
        x,
        w,
        iterations,
        termination,
        xi_used,
        sigma0,
        fresh,
    )
}
