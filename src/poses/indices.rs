//! Observability indices O1–O6, the entropy-weighted composite index and the GCN
//! (Guo 2024 eqs. 9–15).
//!
//! All indices are functions of the singular values σ1 ≥ … ≥ σk of the stacked identification
//! Jacobian J over m poses (k = number of parameters):
//!
//! - O1 = (σ1 ⋯ σk)^(1/k) / √m (eq. 9, D-optimal),
//! - O2 = σk / σ1, O3 = σk, O4 = σk² / σ1 (the classical indices Guo cites),
//! - O5 = 1 / Σ 1/σi (eq. 10),
//! - O6 = ((1/k) Σ 1/σi²)^(−1/2) (eq. 11, A-optimal, Φ_p with p = 2),
//! - composite f = (2/π) Σ_j arctan O_j^w (eq. 15) over the entropy-weighted O1, O5, O6
//!   (eqs. 12–13, see [`composite`]),
//! - GCN = cond(J) / m (eq. 14).
//!
//! A rank-deficient J (a zero singular value, or fewer rows than parameters) gives zero for
//! every index and the composite, and an infinite condition number and GCN.
//!
//! The indices depend on the units of the columns (mm per mm against mm per rad): scaling the
//! columns is the caller's choice, made in the [`super::PoseModel`] it passes.

use std::f64::consts::PI;

use nalgebra::DMatrix;
use serde::Serialize;

use super::{Objective, PoseModel};
use crate::numeric::Real;

/// The observability indices of one pose set (Guo 2024 eqs. 9–15).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Scores {
    /// O1 = (σ1 ⋯ σk)^(1/k) / √m (eq. 9).
    pub o1: Real,
    /// O2 = σk / σ1 (inverse condition number).
    pub o2: Real,
    /// O3 = σk (minimum singular value).
    pub o3: Real,
    /// O4 = σk² / σ1 (noise amplification index).
    pub o4: Real,
    /// O5 = 1 / Σ 1/σi (eq. 10).
    pub o5: Real,
    /// O6 = ((1/k) Σ 1/σi²)^(−1/2) (eq. 11).
    pub o6: Real,
    /// The entropy-weighted composite f = (2/π) Σ arctan O_j^w (eqs. 12–15).
    pub composite: Real,
    /// GCN = cond(J) / m (eq. 14).
    pub gcn: Real,
    /// cond(J) = σ1 / σk.
    pub condition_number: Real,
}

/// Whether a singular-value list is usable (every value finite and positive).
fn full_rank(sv: &[Real]) -> bool {
    !sv.is_empty() && sv.iter().all(|&s| s.is_finite() && s > 0.0)
}

fn max_min(sv: &[Real]) -> (Real, Real) {
    sv.iter().fold((0.0 as Real, Real::INFINITY), |(a, b), &s| {
        (a.max(s), b.min(s))
    })
}

/// O1 (eq. 9), computed through logarithms so that large k does not overflow.
pub fn o1(sv: &[Real], m: usize) -> Real {
    if !full_rank(sv) || m == 0 {
        return 0.0;
    }
    let k = sv.len() as Real;
    (sv.iter().map(|s| s.ln()).sum::<Real>() / k).exp() / (m as Real).sqrt()
}

/// O5 = 1 / Σ 1/σi (eq. 10).
pub fn o5(sv: &[Real]) -> Real {
    if !full_rank(sv) {
        return 0.0;
    }
    1.0 / sv.iter().map(|s| 1.0 / s).sum::<Real>()
}

/// O6 = ((1/k) Σ 1/σi²)^(−1/2) (eq. 11).
pub fn o6(sv: &[Real]) -> Real {
    if !full_rank(sv) {
        return 0.0;
    }
    let k = sv.len() as Real;
    (sv.iter().map(|s| 1.0 / (s * s)).sum::<Real>() / k).powf(-0.5)
}

/// Normalised entropy S = −(1/ln k) Σ p ln p of a positive feature column, p = x / Σ x
/// (eq. 12; the paper writes lg, the ratio is the same for any base).
fn entropy(values: impl Iterator<Item = Real> + Clone, k: usize) -> Real {
    let total: Real = values.clone().sum();
    entropy_with_total(values, total, k)
}

/// [`entropy`] of a column whose sum `total` is known.
fn entropy_of(values: &[Real], total: Real, k: usize) -> Real {
    entropy_with_total(values.iter().copied(), total, k)
}

/// [`entropy`] with the column's sum given.
fn entropy_with_total(values: impl Iterator<Item = Real>, total: Real, k: usize) -> Real {
    let s: Real = values
        .map(|x| {
            let p = x / total;
            if p > 0.0 {
                p * p.ln()
            } else {
                0.0
            }
        })
        .sum();
    -s / (k as Real).ln()
}

/// The entropy weights (w1, w5, w6) of the feature columns {σi}, {1/σi}, {1/σi²}
/// (Guo 2024 eqs. 12–13): w_j = (1 − S_j) / Σ (1 − S). Where the weights are undefined
/// (k < 2, or all singular values equal so every S_j = 1) they are equal, 1/3 each.
pub fn entropy_weights(sv: &[Real]) -> [Real; 3] {
    let k = sv.len();
    if k < 2 || !full_rank(sv) {
        return [1.0 / 3.0; 3];
    }
    let s1 = entropy(sv.iter().copied(), k);
    let s5 = entropy(sv.iter().map(|s| 1.0 / s), k);
    let s6 = entropy(sv.iter().map(|s| 1.0 / (s * s)), k);
    weights_of_entropies(s1, s5, s6)
}

/// The weights (1 − S_j) / Σ (1 − S) of three entropies, equal where undefined.
fn weights_of_entropies(s1: Real, s5: Real, s6: Real) -> [Real; 3] {
    let d = [1.0 - s1, 1.0 - s5, 1.0 - s6];
    let total: Real = d.iter().sum();
    if total.is_nan() || total <= 1e-300 || !total.is_finite() {
        return [1.0 / 3.0; 3];
    }
    [d[0] / total, d[1] / total, d[2] / total]
}

/// The composite index (Guo 2024 eqs. 12–15).
///
/// The evaluation matrix X (k × 3) holds the feature columns {σi}, {1/σi}, {1/σi²} of O1, O5
/// and O6; each column is multiplied by its entropy weight (eq. 13) and the weighted column is
/// substituted into its own index formula, read as a function of its feature values:
/// O1^w = (Π w1 σi)^(1/k) / √m = w1 · O1, O5^w = 1 / Σ (w5 / σi) = O5 / w5 and
/// O6^w = ((1/k) Σ w6 / σi²)^(−1/2) = O6 / √w6. The objective is
/// f = (2/π) (arctan O1^w + arctan O5^w + arctan O6^w) (eq. 15), in [0, 3).
///
/// The feature columns {1/σi} and {1/σi²} and their sums are formed once and serve both the
/// entropies and O5, O6: the same arithmetic in the same order as [`entropy_weights`],
/// [`o5`] and [`o6`] each on their own, so the same bits.
pub fn composite(sv: &[Real], m: usize) -> Real {
    if !full_rank(sv) || m == 0 {
        return 0.0;
    }
    const ON_STACK: usize = 64;
    let k = sv.len();
    if k > ON_STACK {
        let inv: Vec<Real> = sv.iter().map(|s| 1.0 / s).collect();
        let inv2: Vec<Real> = sv.iter().map(|s| 1.0 / (s * s)).collect();
        return composite_of_columns(sv, &inv, &inv2, m);
    }
    let (mut inv, mut inv2) = ([0.0; ON_STACK], [0.0; ON_STACK]);
    for ((s, a), b) in sv.iter().zip(&mut inv).zip(&mut inv2) {
        *a = 1.0 / s;
        *b = 1.0 / (s * s);
    }
    composite_of_columns(sv, &inv[..k], &inv2[..k], m)
}

/// [`composite`] from the feature columns σ, 1/σ and 1/σ² of a full-rank list.
fn composite_of_columns(sv: &[Real], inv: &[Real], inv2: &[Real], m: usize) -> Real {
    let k = sv.len();
    let (t5, t6): (Real, Real) = (inv.iter().sum(), inv2.iter().sum());
    let [w1, w5, w6] = if k < 2 {
        [1.0 / 3.0; 3]
    } else {
        let s1 = entropy_of(sv, sv.iter().sum(), k);
        let s5 = entropy_of(inv, t5, k);
        let s6 = entropy_of(inv2, t6, k);
        weights_of_entropies(s1, s5, s6)
    };
    let a = (w1 * o1(sv, m)).atan();
    let b = if w5 > 0.0 {
        (1.0 / t5 / w5).atan()
    } else {
        PI / 2.0
    };
    let c = if w6 > 0.0 {
        ((t6 / k as Real).powf(-0.5) / w6.sqrt()).atan()
    } else {
        PI / 2.0
    };
    2.0 / PI * (a + b + c)
}

/// The value of `objective` for singular values `sv` of a Jacobian over `m` poses.
pub fn objective_value(objective: Objective, sv: &[Real], m: usize) -> Real {
    match objective {
        Objective::Composite => composite(sv, m),
        Objective::O1 => o1(sv, m),
        Objective::O6 => o6(sv),
    }
}

/// Every index of [`Scores`] from the singular values of J over `m` poses. `sv` must hold k
/// values (pad with zeros when J has fewer rows than columns).
pub fn scores_from_singular_values(sv: &[Real], m: usize) -> Scores {
    let (mx, mn) = max_min(sv);
    if !full_rank(sv) || m == 0 {
        return Scores {
            o1: 0.0,
            o2: 0.0,
            o3: 0.0,
            o4: 0.0,
            o5: 0.0,
            o6: 0.0,
            composite: 0.0,
            gcn: Real::INFINITY,
            condition_number: Real::INFINITY,
        };
    }
    let cond = mx / mn;
    Scores {
        o1: o1(sv, m),
        o2: mn / mx,
        o3: mn,
        o4: mn * mn / mx,
        o5: o5(sv),
        o6: o6(sv),
        composite: composite(sv, m),
        gcn: cond / m as Real,
        condition_number: cond,
    }
}

/// The singular values of a matrix, padded with zeros to its column count.
pub fn singular_values(j: &DMatrix<Real>) -> Vec<Real> {
    let k = j.ncols();
    if k == 0 || j.nrows() == 0 {
        return vec![0.0; k];
    }
    let mut sv: Vec<Real> = j.singular_values().iter().copied().collect();
    sv.resize(k, 0.0);
    sv
}

/// GCN = cond(J) / m of a stacked Jacobian over `m` poses (Guo 2024 eq. 14); infinite when J
/// is rank-deficient.
pub fn gcn(j: &DMatrix<Real>, m: usize) -> Real {
    let sv = singular_values(j);
    let (mx, mn) = max_min(&sv);
    if sv.is_empty() || mn <= 0.0 || m == 0 {
        Real::INFINITY
    } else {
        mx / mn / m as Real
    }
}

/// Guo 2024's GCN of a pose sequence (eq. 14 as §4.1 applies it): cond(J_m)/m for the first
/// m = 1, 2, …, M poses of the sequence, averaged over m. J is the stacked Jacobian of the M
/// poses, `rows` rows per pose, J_m its first `rows · m` rows, and cond(J_m) = σ_1/σ_r over
/// its r = min(rows · m, k) singular values (a 3 × 5 block at m = 1 has three), the
/// convention of MATLAB's `cond`; infinite when σ_r is zero at any m. Guo averages over
/// m = 1…100 of one random set of 100 poses.
///
/// Each J_m's triangular factor is updated from J_(m−1)'s with the new rows (a QR of at most
/// k + `rows` rows), so the cost is M small factorisations, not M of the growing stack.
pub fn gcn_mean(j: &DMatrix<Real>, rows: usize) -> Real {
    let k = j.ncols();
    if k == 0 || rows == 0 || j.nrows() < rows {
        return Real::INFINITY;
    }
    let poses = j.nrows() / rows;
    let mut r = DMatrix::<Real>::zeros(0, k);
    let mut sum = 0.0;
    for m in 1..=poses {
        let mut stack = DMatrix::<Real>::zeros(r.nrows() + rows, k);
        stack.rows_mut(0, r.nrows()).copy_from(&r);
        stack
            .rows_mut(r.nrows(), rows)
            .copy_from(&j.rows(rows * (m - 1), rows));
        let n = stack.nrows().min(k);
        r = stack.qr().r().rows(0, n).into_owned();
        let sv = r.singular_values();
        let (mx, mn) = max_min(sv.as_slice());
        if mn <= 0.0 || !mn.is_finite() {
            return Real::INFINITY;
        }
        sum += mx / mn / m as Real;
    }
    sum / poses as Real
}

/// The stacked Jacobian of `model` over the poses `qs`.
pub fn stacked_jacobian(model: &dyn PoseModel, qs: &[Vec<Real>]) -> DMatrix<Real> {
    let r = model.rows_per_pose();
    let mut j = DMatrix::zeros(r * qs.len(), model.n_params());
    for (i, q) in qs.iter().enumerate() {
        let mut v = j.rows_mut(r * i, r);
        model.jacobian_block(q, &mut v);
    }
    j
}

/// The indices of the pose set `qs` under `model`, from an SVD of the stacked Jacobian
/// (independent of the eigenvalue path used inside the optimisers).
pub fn score(model: &dyn PoseModel, qs: &[Vec<Real>]) -> Scores {
    let j = stacked_jacobian(model, qs);
    scores_from_singular_values(&singular_values(&j), qs.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn composite_is_the_index_by_index_formula_to_the_bit() {
        // Eq. 15 from entropy_weights, o1, o5 and o6 each on their own, against composite's
        // shared columns; spreads of a few to ten decades, k from 1 to 80 (past the stack
        // buffer), ties and the k < 2 case.
        use rand::Rng as _;
        let mut rng = crate::numeric::rng::from_seed(8);
        for case in 0..400 {
            let k = [1, 2, 3, 20, 26, 64, 65, 80][case % 8];
            let decades = [2.0, 6.0, 10.0][case % 3];
            let mut sv: Vec<Real> = (0..k)
                .map(|_| (10.0 as Real).powf(rng.random::<Real>() * decades - 3.0))
                .collect();
            if case % 5 == 0 {
                sv.iter_mut().for_each(|s| *s = 1.5);
            }
            let m = 60;
            let [w1, w5, w6] = entropy_weights(&sv);
            let a = (w1 * o1(&sv, m)).atan();
            let b = if w5 > 0.0 {
                (o5(&sv) / w5).atan()
            } else {
                PI / 2.0
            };
            let c = if w6 > 0.0 {
                (o6(&sv) / w6.sqrt()).atan()
            } else {
                PI / 2.0
            };
            let want = 2.0 / PI * (a + b + c);
            assert_eq!(composite(&sv, m).to_bits(), want.to_bits(), "{sv:?}");
        }
    }

    #[test]
    fn indices_match_hand_computation_for_sv_3_2() {
        // σ = (3, 2), k = 2, m = 1.
        let sv = [3.0, 2.0];
        let s = scores_from_singular_values(&sv, 1);
        assert_relative_eq!(s.o1, 6.0f64.sqrt(), epsilon = 1e-12);
        assert_relative_eq!(s.o2, 2.0 / 3.0, epsilon = 1e-12);
        assert_relative_eq!(s.o3, 2.0, epsilon = 1e-12);
        assert_relative_eq!(s.o4, 4.0 / 3.0, epsilon = 1e-12);
        assert_relative_eq!(s.o5, 1.2, epsilon = 1e-12);
        // ((1/2)(1/9 + 1/4))^(-1/2) = (13/72)^(-1/2)
        assert_relative_eq!(s.o6, (72.0f64 / 13.0).sqrt(), epsilon = 1e-12);
        assert_relative_eq!(s.condition_number, 1.5, epsilon = 1e-12);
        assert_relative_eq!(s.gcn, 1.5, epsilon = 1e-12);
        // Same σ over m = 4 poses: O1 and GCN divide by √m and m.
        let s4 = scores_from_singular_values(&sv, 4);
        assert_relative_eq!(s4.o1, 6.0f64.sqrt() / 2.0, epsilon = 1e-12);
        assert_relative_eq!(s4.gcn, 0.375, epsilon = 1e-12);
    }

    #[test]
    fn composite_matches_hand_computation() {
        let sv = [3.0, 2.0];
        // Entropy of (p, 1-p) normalised by ln 2.
        let h = |p: f64| -(p * p.ln() + (1.0 - p) * (1.0 - p).ln()) / 2.0f64.ln();
        let s1 = h(3.0 / 5.0); // σ: 3, 2
        let s5 = h((1.0 / 3.0) / (1.0 / 3.0 + 0.5)); // 1/σ: 1/3, 1/2
        let s6 = h((1.0 / 9.0) / (1.0 / 9.0 + 0.25)); // 1/σ²
        let t = (1.0 - s1) + (1.0 - s5) + (1.0 - s6);
        let w = [(1.0 - s1) / t, (1.0 - s5) / t, (1.0 - s6) / t];
        let ws = entropy_weights(&sv);
        for i in 0..3 {
            assert_relative_eq!(ws[i], w[i], epsilon = 1e-12);
        }
        let o1w = w[0] * 6.0f64.sqrt();
        let o5w = 1.0 / (w[1] / 3.0 + w[1] / 2.0);
        let o6w = (0.5 * (w[2] / 9.0 + w[2] / 4.0)).powf(-0.5);
        let f = 2.0 / PI * (o1w.atan() + o5w.atan() + o6w.atan());
        assert_relative_eq!(composite(&sv, 1), f, epsilon = 1e-12);
        assert!(f > 0.0 && f < 3.0);
    }

    #[test]
    fn svd_of_a_rotated_diagonal_matrix_gives_the_hand_indices() {
        // J = R3 · [[3,0],[0,2],[0,0]] · R2ᵀ has singular values 3 and 2.
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let r3 = crate::numeric::rot_x(0.7) * crate::numeric::rot_z(-1.1);
        let d = DMatrix::from_row_slice(3, 2, &[3.0, 0.0, 0.0, 2.0, 0.0, 0.0]);
        let r2 = DMatrix::from_row_slice(2, 2, &[c, -s, s, c]);
        let r3d = DMatrix::from_iterator(3, 3, r3.iter().copied());
        let j = r3d * d * r2.transpose();
        let mut sv = singular_values(&j);
        sv.sort_by(|a, b| b.total_cmp(a));
        assert_relative_eq!(sv[0], 3.0, epsilon = 1e-12);
        assert_relative_eq!(sv[1], 2.0, epsilon = 1e-12);
        assert_relative_eq!(gcn(&j, 1), 1.5, epsilon = 1e-12);
    }

    #[test]
    fn rank_deficiency_gives_zero_indices_and_infinite_gcn() {
        let s = scores_from_singular_values(&[3.0, 0.0], 2);
        assert_eq!(s.o1, 0.0);
        assert_eq!(s.composite, 0.0);
        assert!(s.gcn.is_infinite());
        let j = DMatrix::from_row_slice(1, 2, &[1.0, 2.0]);
        assert!(gcn(&j, 1).is_infinite());
        assert_eq!(singular_values(&j).len(), 2);
    }

    #[test]
    fn equal_singular_values_give_equal_weights() {
        let w = entropy_weights(&[2.0, 2.0, 2.0]);
        for x in w {
            assert_relative_eq!(x, 1.0 / 3.0, epsilon = 1e-12);
        }
    }

    #[test]
    fn gcn_mean_is_the_average_over_pose_counts_of_each_prefix_cond() {
        // Against a direct SVD of every prefix of the stack, with MATLAB's convention of
        // min(rows, columns) singular values (the first prefixes have fewer rows than columns).
        use rand::Rng as _;
        let mut rng = crate::numeric::rng::from_seed(14);
        for (rows, k, poses) in [(3, 5, 40), (3, 21, 30), (6, 4, 10), (1, 3, 12)] {
            let j = DMatrix::<Real>::from_fn(rows * poses, k, |_, _| rng.random::<Real>() - 0.5);
            let mut sum = 0.0;
            for m in 1..=poses {
                let sv = j.rows(0, rows * m).singular_values();
                let (mx, mn) = max_min(sv.as_slice());
                sum += mx / mn / m as Real;
            }
            assert_relative_eq!(gcn_mean(&j, rows), sum / poses as Real, max_relative = 1e-9);
        }
        // A single column has cond 1 at every count: the mean of 1/m, H_M / M.
        let col = DMatrix::<Real>::from_fn(300, 1, |i, _| 1.0 + i as Real);
        let h100: Real = (1..=100).map(|m| 1.0 / m as Real).sum();
        assert_relative_eq!(gcn_mean(&col, 3), h100 / 100.0, epsilon = 1e-12);
        // Two equal columns: singular at every count.
        let twin = DMatrix::<Real>::from_fn(30, 2, |i, _| 1.0 + i as Real);
        assert!(gcn_mean(&twin, 3) > 1e12 || gcn_mean(&twin, 3).is_infinite());
    }
}
