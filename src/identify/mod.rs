//! Identification methods (SPEC §4): least squares, ridge, IGG3 robust ridge and
//! Levenberg–Marquardt over a generic nonlinear least-squares [`Problem`].
//!
//! | method | normal equations per iteration | source |
//! |---|---|---|
//! | [`Method::Ls`] | `(JᵀPJ) δx = JᵀP E` | Li 2018 eq. 13 |
//! | [`Method::Ridge`] | `(JᵀPJ + ξD) δx = JᵀP E − ξD(x − x0)` | Li 2018 eq. 14 |
//! | [`Method::Igg3`] | the ridge equations with IGG3 (Huber, Tukey) weights | Li 2018 §2.2, eqs. 15–18 |
//! | [`Method::Lm`] | `(JᵀJ + μI) Δx = JᵀΔP`, μ fixed or adaptive | Guo 2024 eq. 8; Ban (LM) |
//!
//! `E = measured − model(x)` is the residual the [`Problem`] returns and `J = ∂model/∂x`.
//! Every method is one call, [`identify`]; failing to converge is a [`Termination`] in the
//! result, never an error or a panic, so a Monte-Carlo run can count failures.
//!
//! The solvers allocate their buffers once per call; the iterations reuse them (the ridge
//! parameter rules decompose one `t × t` matrix per iteration, which allocates).

mod linalg;
pub mod lm;
pub mod ls;
pub mod ridge;
pub mod robot;
pub mod robust;

use nalgebra::{DMatrix, DMatrixView, DVector};

use crate::math::Real;

pub use lm::LmOptions;
pub use ls::LsOptions;
pub use ridge::{RidgeOptions, XiRule};
pub use robot::{RobotData, RobotProblem};
pub use robust::{RobustOptions, Sigma0, WeightFn};

/// A nonlinear least-squares problem: residuals of `n_points` points with `rows_per_point`
/// rows each, over `n_params` unknowns.
pub trait Problem {
    /// Number of unknowns `t`.
    fn n_params(&self) -> usize;
    /// Number of measured points (each carries one weight in the robust methods).
    fn n_points(&self) -> usize;
    /// Rows of the residual per point (3 for positions, 6 for full poses).
    fn rows_per_point(&self) -> usize;
    /// r = measured − model(x) (length n_points·rows), j = ∂model/∂x
    /// (`n_points·rows × n_params`). Both buffers come with the right sizes.
    fn evaluate(&self, x: &DVector<Real>, r: &mut DVector<Real>, j: &mut DMatrix<Real>);
}

/// An identification method with its settings.
#[derive(Clone, Debug)]
pub enum Method {
    /// Iterated Gauss–Newton least squares (Li 2018 eq. 13).
    Ls(LsOptions),
    /// Ridge (Tikhonov) estimation (Li 2018 eq. 14).
    Ridge(RidgeOptions),
    /// IGG3 robust ridge estimation (Li 2018 §2.2), also with Huber or Tukey weights.
    Igg3(RobustOptions),
    /// Levenberg–Marquardt (Guo 2024 eq. 8, fixed μ; Ban, adaptive λ).
    Lm(LmOptions),
}

impl Method {
    /// The method's name in scenarios and reports: `ls`, `ridge`, `igg3`, `lm`.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Ls(_) => "ls",
            Method::Ridge(_) => "ridge",
            Method::Igg3(_) => "igg3",
            Method::Lm(_) => "lm",
        }
    }
}

/// Why an identification stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Termination {
    /// The step fell below the tolerance (`max |dx| < ε`).
    Converged,
    /// The iteration limit was reached first.
    MaxIterations,
    /// The residual became non-finite or grew without bound.
    Diverged,
    /// The normal matrix could not be factorised (rank-deficient parameters).
    Singular,
    /// Levenberg–Marquardt could not find a step that lowers the cost.
    NoProgress,
    /// The problem or the settings are inconsistent (sizes, non-finite start, bad options).
    InvalidInput,
}

impl Termination {
    /// The name used in reports: `converged`, `max-iterations`, `diverged`, `singular`,
    /// `no-progress`, `invalid-input`.
    pub fn as_str(self) -> &'static str {
        match self {
            Termination::Converged => "converged",
            Termination::MaxIterations => "max-iterations",
            Termination::Diverged => "diverged",
            Termination::Singular => "singular",
            Termination::NoProgress => "no-progress",
            Termination::InvalidInput => "invalid-input",
        }
    }
}

/// The outcome of an identification.
#[derive(Clone, Debug)]
pub struct Identified {
    /// The estimate (for a [`RobotProblem`]: the parameter errors, mm / rad).
    pub x: DVector<Real>,
    /// Iterations (steps solved) carried out.
    pub iterations: usize,
    /// Why the iterations stopped.
    pub termination: Termination,
    /// Final weight of each point (1 for the non-robust methods).
    pub weights: Vec<Real>,
    /// Condition number `λmax/λmin` of `JᵀPJ` at the solution (Li 2018 eq. 17), unscaled;
    /// infinite when singular, NaN when not computed (invalid input).
    pub condition_number: Real,
    /// `σ0² (JᵀPJ)⁻¹` at the solution; NaN entries when `JᵀPJ` is singular or there is no
    /// redundancy.
    pub covariance: DMatrix<Real>,
    /// Unit-weight standard deviation `sqrt(vᵀPv / (n − t))` at the solution, n counting each
    /// row with its point's weight (for [`Method::Igg3`] with [`Sigma0::Mad`], the
    /// MAD-based value); NaN when `n ≤ t`.
    pub sigma0: Real,
    /// Root mean square over points of the residual norm per point, `sqrt(Σ|v_i|² / m)`,
    /// unweighted, at the solution.
    pub rms_residual: Real,
    /// The ridge parameter used in the last iteration (ridge and IGG3 only), in the units of
    /// the (scaled) normal matrix, see [`RidgeOptions`].
    pub ridge_xi: Option<Real>,
}

/// Runs method `m` on problem `p` from the start `x0`.
///
/// Never panics on bad input: inconsistent sizes, a non-finite start or invalid options give
/// [`Termination::InvalidInput`] with `x = x0`.
pub fn identify(p: &dyn Problem, x0: &DVector<Real>, m: &Method) -> Identified {
    if check_problem(p, x0).or_else(|| check_method(m)).is_some() {
        return invalid(p, x0);
    }
    match m {
        Method::Ls(o) => ls::run(p, x0, o),
        Method::Ridge(o) => ridge::run(p, x0, o),
        Method::Igg3(o) => robust::run(p, x0, o),
        Method::Lm(o) => lm::run(p, x0, o),
    }
}

fn check_problem(p: &dyn Problem, x0: &DVector<Real>) -> Option<&'static str> {
    let t = p.n_params();
    if t == 0 || p.rows_per_point() == 0 || p.n_points() == 0 {
        return Some("empty problem");
    }
    if x0.len() != t {
        return Some("x0 has the wrong length");
    }
    if x0.iter().any(|v| !v.is_finite()) {
        return Some("x0 is not finite");
    }
    if p.n_points() * p.rows_per_point() < t {
        return Some("fewer residual rows than unknowns");
    }
    None
}

fn check_method(m: &Method) -> Option<&'static str> {
    let pos = |v: Real| v.is_finite() && v > 0.0;
    let nonneg = |v: Real| v.is_finite() && v >= 0.0;
    let xi_ok = |x: &XiRule| match x {
        XiRule::Fixed(v) => nonneg(*v),
        _ => true,
    };
    let ok = match m {
        Method::Ls(o) => pos(o.eps),
        Method::Ridge(o) => pos(o.eps) && xi_ok(&o.xi),
        Method::Igg3(o) => {
            pos(o.eps) && xi_ok(&o.xi) && pos(o.k0) && o.k1.is_finite() && o.k1 > o.k0
        }
        Method::Lm(o) => {
            pos(o.eps)
                && nonneg(o.mu)
                && pos(o.lambda0)
                && o.lambda_factor.is_finite()
                && o.lambda_factor > 1.0
        }
    };
    (!ok).then_some("invalid options")
}

fn invalid(p: &dyn Problem, x0: &DVector<Real>) -> Identified {
    let t = x0.len();
    Identified {
        x: x0.clone(),
        iterations: 0,
        termination: Termination::InvalidInput,
        weights: vec![1.0; p.n_points()],
        condition_number: Real::NAN,
        covariance: DMatrix::from_element(t, t, Real::NAN),
        sigma0: Real::NAN,
        rms_residual: Real::NAN,
        ridge_xi: None,
    }
}

/// Buffers shared by the solvers: residual, Jacobian, weighted Jacobian, normal equations.
pub(crate) struct Work {
    pub rows: usize,
    pub r: DVector<Real>,
    pub j: DMatrix<Real>,
    /// `P J` (rows scaled by their point's weight).
    pub pj: DMatrix<Real>,
    /// `JᵀPJ`.
    pub n: DMatrix<Real>,
    /// `JᵀP r`.
    pub g: DVector<Real>,
    /// Factorisation buffer.
    pub a: DMatrix<Real>,
    /// Step.
    pub dx: DVector<Real>,
}

impl Work {
    pub fn new(p: &dyn Problem) -> Work {
        let (m, t) = (p.n_points() * p.rows_per_point(), p.n_params());
        Work {
            rows: p.rows_per_point(),
            r: DVector::zeros(m),
            j: DMatrix::zeros(m, t),
            pj: DMatrix::zeros(m, t),
            n: DMatrix::zeros(t, t),
            g: DVector::zeros(t),
            a: DMatrix::zeros(t, t),
            dx: DVector::zeros(t),
        }
    }

    /// Evaluates the problem at `x` and returns the weighted cost `rᵀPr` (non-finite when the
    /// model is).
    pub fn evaluate(&mut self, p: &dyn Problem, x: &DVector<Real>, w: &[Real]) -> Real {
        p.evaluate(x, &mut self.r, &mut self.j);
        weighted_cost(&self.r, self.rows, w)
    }

    /// Forms `N = JᵀPJ` and `g = JᵀP r` with per-point weights `w`. Allocation-free: `N` is
    /// one blocked matrix product (nalgebra's `gemm`, which hands dynamic sizes to
    /// `matrixmultiply`) of a transposed view of `J`, mirrored from its lower triangle so it is
    /// exactly symmetric; with all weights 1 `P J` is not formed.
    pub fn normal(&mut self, w: &[Real]) {
        let rows = self.rows;
        let unit = w.iter().all(|&wi| wi == 1.0);
        if !unit {
            self.pj.copy_from(&self.j);
            for (i, &wi) in w.iter().enumerate() {
                if wi != 1.0 {
                    self.pj.rows_mut(i * rows, rows).scale_mut(wi);
                }
            }
        }
        let pj = if unit { &self.j } else { &self.pj };
        let (m, t) = self.j.shape();
        if t > GEMM_MIN && m > GEMM_MIN {
            // Jᵀ as a t × m view of J's column-major storage (row stride m, column stride 1).
            let jt = DMatrixView::from_slice_with_strides(self.j.as_slice(), t, m, m, 1);
            self.n.gemm(1.0, &jt, pj, 0.0);
            for a in 0..t {
                for b in 0..a {
                    self.n[(b, a)] = self.n[(a, b)];
                }
            }
        } else {
            // Small problems: lower triangle by column dot products, mirrored.
            for a in 0..t {
                let ca = pj.column(a);
                for b in 0..=a {
                    let v = ca.dot(&self.j.column(b));
                    self.n[(a, b)] = v;
                    self.n[(b, a)] = v;
                }
            }
        }
        pj.tr_mul_to(&self.r, &mut self.g);
    }
}

/// Sizes above which nalgebra's `gemm` uses `matrixmultiply` (its `SMALL_DIM`); below, its
/// fallback does not accept the strided transposed view, so [`Work::normal`] uses dot products.
const GEMM_MIN: usize = 5;

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

/// `max |v_i|`.
pub(crate) fn max_abs(v: &DVector<Real>) -> Real {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// The statistics of the solution: evaluates at `x`, forms `JᵀPJ` and fills [`Identified`].
/// `sigma0` overrides the classical unit-weight standard deviation (the MAD option).
#[allow(clippy::too_many_arguments)]
pub(crate) fn finish(
    p: &dyn Problem,
    work: &mut Work,
    x: DVector<Real>,
    weights: Vec<Real>,
    iterations: usize,
    termination: Termination,
    ridge_xi: Option<Real>,
    sigma0: Option<Real>,
) -> Identified {
    let t = x.len();
    let rows = work.rows;
    let cost = work.evaluate(p, &x, &weights);
    work.normal(&weights);
    let n_eff = rows as Real * weights.iter().sum::<Real>();
    let classical = if n_eff > t as Real && cost.is_finite() {
        (cost / (n_eff - t as Real)).sqrt()
    } else {
        Real::NAN
    };
    let sigma0 = sigma0.unwrap_or(classical);
    let m = weights.len() as Real;
    let rms_residual = (work.r.norm_squared() / m).sqrt();
    let (condition_number, covariance) = if work.n.iter().all(|v| v.is_finite()) {
        // Eigenvalues only: the condition number needs no eigenvectors.
        let eigenvalues = work.n.symmetric_eigenvalues();
        let (mx, mn) = eigenvalues
            .iter()
            .fold((Real::NEG_INFINITY, Real::INFINITY), |(a, b), &e| {
                (a.max(e), b.min(e))
            });
        let cond = if mn > 0.0 && mn > mx * 1e-300 {
            mx / mn
        } else {
            Real::INFINITY
        };
        let mut cov = DMatrix::from_element(t, t, Real::NAN);
        if cond.is_finite() {
            work.a.copy_from(&work.n);
            if linalg::cholesky_in_place(&mut work.a) {
                for c in 0..t {
                    work.dx.fill(0.0);
                    work.dx[c] = 1.0;
                    linalg::cholesky_solve(&work.a, &mut work.dx);
                    for k in 0..t {
                        cov[(k, c)] = sigma0 * sigma0 * work.dx[k];
                    }
                }
            }
        }
        (cond, cov)
    } else {
        (Real::NAN, DMatrix::from_element(t, t, Real::NAN))
    };
    Identified {
        x,
        iterations,
        termination,
        weights,
        condition_number,
        covariance,
        sigma0,
        rms_residual,
        ridge_xi,
    }
}

/// Cost growth beyond which an iteration counts as diverged.
pub(crate) const DIVERGENCE_FACTOR: Real = 1e12;

#[cfg(test)]
mod tests;
