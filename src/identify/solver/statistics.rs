//! The statistics of a solution ([`finish`]: the unit-weight standard deviation, the RMS
//! residual and the normal matrix of [`Identified`]) and the numerical rank and condition
//! number of the column-scaled Jacobian from its normal matrix ([`rank`], [`conditioning`]).

use nalgebra::{DMatrix, DVector};

use super::{weighted_cost, LeastSquares, Work};
use crate::identify::{Identified, Termination};
use crate::numeric::linalg;
use crate::numeric::symeig::symmetric_eigenvalues;
use crate::numeric::Real;

/// The statistics of the solution: evaluates at `x`, forms `JᵀPJ` and fills [`Identified`].
/// `sigma0` overrides the classical unit-weight standard deviation (the MAD option). With
/// `fresh`, `work` already holds the residual, Jacobian and normal equations at `x` with
/// `weights`, and is not evaluated again (the evaluation is then not counted twice either).
#[allow(clippy::too_many_arguments)]
pub(crate) fn finish(
    p: &dyn LeastSquares,
    work: &mut Work,
    x: DVector<Real>,
    weights: Vec<Real>,
    iterations: usize,
    termination: Termination,
    ridge_xi: Option<Real>,
    sigma0: Option<Real>,
    fresh: bool,
) -> Identified {
    let t = x.len();
    let rows = work.rows;
    let evaluations = work.evaluations;
    // The data's cost only (σ0 is the data's; a prior's term is not a residual).
    if !fresh {
        work.evaluate(p, &x, &weights);
        work.normal(p, &weights);
    }
    let cost = weighted_cost(&work.r, rows, &weights);
    let n_eff = rows as Real * weights.iter().sum::<Real>();
    let classical = if n_eff > t as Real && cost.is_finite() {
        (cost / (n_eff - t as Real)).sqrt()
    } else {
        Real::NAN
    };
    let sigma0 = sigma0.unwrap_or(classical);
    let m = weights.len() as Real;
    let rms_residual = (work.r.norm_squared() / m).sqrt();
    let rank = work.n.iter().all(|v| v.is_finite()).then(|| rank(&work.n));
    let termination = match (termination, rank) {
        (
            Termination::Converged | Termination::MaxIterations | Termination::NoProgress,
            Some(r),
        ) if r < t => Termination::RankDeficient,
        (other, _) => other,
    };
    Identified {
        x,
        iterations,
        termination,
        weights,
        row_weights: None,
        own_weights: true,
        normal: work.n.clone(),
        sigma0,
        rms_residual,
        ridge_xi,
        evaluations,
        trace: None,
        rank,
    }
}

/// How many Cramér–Rao standard deviations decide whether a parameter's value can be told
/// from zero (k = 3, fixed from first principles, not from the figures it selects): an
/// efficient estimate of a parameter whose value is x is x + N(0, σ²), and a two-sided test
/// of "x = 0" at the conventional 3σ level (0.27 %) does not reject |x| ≤ 3σ. A study's
/// injected error within it is not determinable (docs/formats.md § 7.1, `eta_not_determinable`);
/// a parameter `identify` left out at the nominal robot is re-admitted at the identified
/// robot only when its largest plausible value lies beyond it (§ 2.6.1, "Parameters
/// re-checked at the identified robot").
pub const DETERMINABLE_SIGMAS: Real = 3.0;

/// `n⁻¹`, whose diagonal holds each parameter's Cramér–Rao variance when `n = JᵀWJ` is the
/// normal matrix weighted by the inverse noise variances (Kay, *Fundamentals of Statistical
/// Signal Processing*, vol. 1, § 3.7, Gaussian noise). `None` where there is no bound: `n` of
/// numerical rank below its size ([`rank`]: a parameter the data do not determine, or two
/// that only their sum is; its rounded inverse would be noise), or a diagonal that is not
/// finite and non-negative.
pub fn bound_inverse(n: &DMatrix<Real>) -> Option<DMatrix<Real>> {
    if rank(n) < n.nrows() {
        return None;
    }
    let inv = n.clone().try_inverse()?;
    inv.diagonal()
        .iter()
        .all(|v| v.is_finite() && *v >= 0.0)
        .then_some(inv)
}

/// The diagonal of [`bound_inverse`]: each parameter's Cramér–Rao variance.
pub fn inverse_diagonal(n: &DMatrix<Real>) -> Option<Vec<Real>> {
    bound_inverse(n).map(|inv| inv.diagonal().iter().copied().collect())
}

/// Directions whose scaled singular value is below this fraction of the largest are
/// undetermined by the data (relative eigenvalue of the scaled normal matrix below its
/// square, 1e-14: a few hundred times the rounding of `JᵀPJ`). The identifiability analysis's
/// own tolerance, so that the parameters it finds identifiable are of full rank here.
pub const RANK_TOLERANCE: Real = crate::robot::identifiability::RANK_TOL;

/// The numerical rank of [`conditioning`] without its eigenvalues when the matrix is clearly
/// of full rank, as almost every calibration's is. With `S = D^-½ n D^-½` (unit diagonal),
/// `λ_max ≤ trace S = t` and `λ_min ≥ 1 / trace S⁻¹`, and `trace S⁻¹ = ‖L⁻¹‖²_F` from the
/// Cholesky factor `S = L Lᵀ`; when `t · trace S⁻¹` stays a hundred times below
/// `RANK_TOLERANCE⁻²`, every eigenvalue is above [`conditioning`]'s floor and the rank is `t`.
/// Otherwise (factorisation fails, or the bound is not conclusive) the eigenvalues decide.
pub fn rank(n: &DMatrix<Real>) -> usize {
    let t = n.nrows();
    let scaled = (0..t).all(|k| {
        let d = n[(k, k)];
        d > 0.0 && d.is_finite()
    });
    if scaled && full_rank_certified(n) {
        return t;
    }
    conditioning(n).0
}

/// The certificate of [`rank`] for a matrix with a positive, finite diagonal: whether
/// `t · trace S⁻¹` is conclusively small. A bound, not a rank: its rounding only moves the
/// point at which the eigenvalues are asked instead.
fn full_rank_certified(n: &DMatrix<Real>) -> bool {
    let t = n.nrows();
    let bound = scaled_inverse_trace(n).map_or(Real::NAN, |trace| t as Real * trace);
    bound.is_finite() && bound < 1e-2 / (RANK_TOLERANCE * RANK_TOLERANCE)
}

/// `trace S⁻¹` of the scaled `S = D^-½ n D^-½` (`D = diag(n)`, positive and finite), from
/// its Cholesky factor; `None` when the factorisation fails.
fn scaled_inverse_trace(n: &DMatrix<Real>) -> Option<Real> {
    let t = n.nrows();
    let scale: Vec<Real> = (0..t).map(|k| 1.0 / n[(k, k)].sqrt()).collect();
    let mut s = DMatrix::zeros(t, t);
    // The lower triangle only: all the factorisation reads.
    for k in 0..t {
        for i in k..t {
            s[(i, k)] = n[(i, k)] * scale[i] * scale[k];
        }
    }
    if !linalg::cholesky_in_place(&mut s) {
        return None;
    }
    Some(linalg::cholesky_inverse_trace(&s))
}

/// Numerical rank and condition number of the column-scaled Jacobian `J D^-½` from its normal
/// matrix `n = JᵀPJ` (docs/formats.md `condition_number`: σ_max/σ_min after scaling every column to
/// unit norm, points weighted): `sqrt(λ_max/λ_min)` of `D^-½ n D^-½`, `D = diag(n)`. A zero
/// column counts as an undetermined direction. The rank counts the scaled singular values
/// above [`RANK_TOLERANCE`] times the largest; the condition number is infinite below full
/// rank.
pub fn conditioning(n: &DMatrix<Real>) -> (usize, Real) {
    let t = n.nrows();
    let scale: Vec<Real> = (0..t)
        .map(|k| {
            let d = n[(k, k)];
            if d > 0.0 && d.is_finite() {
                1.0 / d.sqrt()
            } else {
                0.0
            }
        })
        .collect();
    // The scaled matrix is symmetric, so its column-major storage is also the row-major one
    // that [`symmetric_eigenvalues`] reads.
    let mut scaled: Vec<Real> = (0..t * t)
        .map(|ik| {
            let (i, k) = (ik % t, ik / t);
            n[(i, k)] * scale[i] * scale[k]
        })
        .collect();
    let mut eigenvalues = vec![0.0; t];
    let mut scratch = vec![0.0; t];
    if !symmetric_eigenvalues(&mut scaled, t, &mut eigenvalues, &mut scratch) {
        return (0, Real::INFINITY);
    }
    let max = eigenvalues.iter().fold(0.0 as Real, |a, &e| a.max(e));
    if !(max > 0.0 && max.is_finite()) {
        return (0, Real::INFINITY);
    }
    let floor = max * RANK_TOLERANCE * RANK_TOLERANCE;
    let rank = eigenvalues.iter().filter(|&&e| e > floor).count();
    let min = eigenvalues.iter().fold(Real::INFINITY, |a, &e| a.min(e));
    let cond = if rank == t {
        (max / min).sqrt()
    } else {
        Real::INFINITY
    };
    (rank, cond)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rank certificate's `trace S⁻¹` (four columns of L⁻¹ at a time) against the trace
    /// of the inverse of the scaled matrix formed by nalgebra, for sizes around the groups of
    /// four and columns of very different scales.
    /// One rank rule: the parameters the identifiability analysis finds identifiable are of
    /// full rank by [`rank`] on the same rows, down to pose sets that barely move the joints
    /// (near the tolerance, where the pivots' remaining norms had kept a column whose scaled
    /// singular value lay below it).
    #[test]
    fn what_identifiability_keeps_the_solve_finds_of_full_rank() {
        use crate::measurement::Measure;
        use crate::robot::identifiability::analyse;
        use crate::robot::jacobian::{jacobian, Columns};
        let mut checked = 0;
        for name in ["irb2600", "tx60", "guo-3t2r"] {
            let robot = crate::robot::builtin::load(name).expect("robot");
            let mut g = crate::numeric::rng::from_seed(3);
            let wide = crate::robot::sampling::uniform_joint_poses(&robot, 30, &mut g);
            for shrink in [1.0, 0.05, 0.02, 0.01, 0.007, 0.005, 0.003] {
                let qs: Vec<Vec<Real>> = wide
                    .iter()
                    .map(|q| q.iter().map(|v| v * shrink).collect())
                    .collect();
                for measure in [Measure::Position, Measure::Pose] {
                    let a = analyse(&robot, &robot.params(), &qs, measure);
                    let cols = Columns::new(&a.identifiable, robot.dof());
                    let j = jacobian(&robot, &cols, &qs, measure);
                    let n = j.transpose() * &j;
                    assert_eq!(rank(&n), a.rank, "{name} ×{shrink} {measure:?}");
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 42);
    }

    #[test]
    fn scaled_inverse_trace_is_the_trace_of_the_inverse() {
        let mut g = crate::numeric::rng::from_seed(5);
        for t in [1, 2, 3, 4, 5, 8, 9, 20, 23] {
            let j = DMatrix::from_fn(t + 10, t, |_, k| {
                rand::Rng::random_range(&mut g, -1.0..1.0) * [1.0, 1e3, 1e-3][k % 3]
            });
            let n = j.transpose() * &j;
            let d = DMatrix::from_diagonal(&n.map_diagonal(|v: Real| 1.0 / v.sqrt()));
            let want = (&d * &n * &d).try_inverse().expect("invertible").trace();
            let got = scaled_inverse_trace(&n).expect("positive definite");
            assert!((got - want).abs() <= 1e-9 * want, "t {t}: {got} vs {want}");
        }
        let singular = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        assert!(scaled_inverse_trace(&singular).is_none());
    }
}
