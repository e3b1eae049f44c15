//! [`super::bounds`] against independent truth: a closed form, a rank-deficient Jacobian
//! whose estimable parameters are known by construction, and the pseudo-inverse of the
//! column-scaled normal matrix computed apart (nalgebra's SVD and symmetric eigendecomposition).

use super::bounds;
use crate::numeric::{rng, Real};
use nalgebra::{DMatrix, DVector};
use rand::Rng;

#[test]
fn two_parameters_whose_sum_only_is_determined_are_undetermined() {
    // Columns c1, c2 = c1 and c3: y = c1 (x1 + x2) + c3 x3. Neither x1 nor x2 is estimable:
    // the null direction (1, −1, 0)/√2 of the scaled columns moves each by 1/√2 per unit
    // step, over its column norm √5. x3 is, with the variance of the model in u = x1 + x2
    // and x3: [cᵀc] = [[5, 1], [1, 10]], whose inverse has 5 / 49 at (2, 2).
    let j = DMatrix::from_row_slice(3, 3, &[1.0, 1.0, 1.0, 2.0, 2.0, 0.0, 0.0, 0.0, 3.0]);
    let got = bounds(&(j.transpose() * &j)).expect("a bound");
    assert!(!got.full_rank);
    for k in [0, 1] {
        let want = std::f64::consts::FRAC_1_SQRT_2 / 5.0_f64.sqrt();
        let u = got.undetermined[k];
        assert!((u - want).abs() <= 1e-14, "{u} against {want}");
    }
    assert!(got.undetermined[2] <= 1e-15, "{got:?}");
    let v = got.variances[2];
    assert!((v - 5.0 / 49.0).abs() <= 1e-14, "{v}");
}

#[test]
fn a_full_rank_normal_matrix_keeps_the_diagonal_of_its_inverse_bit_for_bit() {
    let mut g = rng::from_seed(3);
    let j = DMatrix::from_fn(20, 5, |_, _| g.random_range(-1.0..1.0));
    let n = j.transpose() * &j;
    let want = crate::identify::solver::inverse_diagonal(&n).expect("regular");
    let got = bounds(&n).expect("a bound");
    assert!(got.full_rank && got.undetermined.iter().all(|&u| u == 0.0));
    for (w, g) in want.iter().zip(&got.variances) {
        assert_eq!(w.to_bits(), g.to_bits());
    }
}

/// A weighted Jacobian `W^½ A P D⁻¹` over 7 parameters: A random of full column rank, P the
/// projector off the null directions `u` (on parameters 1, 2) and `v` (on 4, 5, 6), D
/// parameter scales from 1e-3 to 1e3 (mm against rad). The null space of J is D span{u, v},
/// so exactly parameters 0 and 3 are estimable. Returns J and the orthonormal basis of its
/// row space, D⁻¹ · range(P) orthonormalised.
fn projected(seed: u64) -> (DMatrix<Real>, DMatrix<Real>) {
    let mut g = rng::from_seed(seed);
    let p = 7;
    let mut u = DVector::zeros(p);
    let mut v = DVector::zeros(p);
    for k in [1, 2] {
        u[k] = g.random_range(0.5..1.5);
    }
    for k in [4, 5, 6] {
        v[k] = g.random_range(0.5..1.5) * if k == 5 { -1.0 } else { 1.0 };
    }
    let (u, v) = (u.normalize(), v.normalize());
    let proj = DMatrix::identity(p, p) - &u * u.transpose() - &v * v.transpose();
    let scales = [1.0, 1e3, 1e-3, 10.0, 1e-2, 1.0, 1e2];
    let d = DMatrix::from_diagonal(&DVector::from_row_slice(&scales));
    let a = DMatrix::from_fn(60, p, |_, _| g.random_range(-1.0..1.0));
    let w = DMatrix::from_diagonal(&DVector::from_fn(60, |_, _| g.random_range(0.2..5.0)));
    let j = w * a * &proj * d.try_inverse().expect("regular");
    // range(P): the eigenvectors of P with eigenvalue 1; the row space of J = range(Jᵀ) =
    // D⁻¹ range(P).
    let eig = proj.symmetric_eigen();
    let cols: Vec<DVector<Real>> = (0..p)
        .filter(|&k| eig.eigenvalues[k] > 0.5)
        .map(|k| {
            let e = eig.eigenvectors.column(k).into_owned();
            DVector::from_fn(p, |i, _| e[i] / scales[i])
        })
        .collect();
    assert_eq!(cols.len(), p - 2);
    let basis = DMatrix::from_columns(&cols).qr().q();
    (j, basis)
}

#[test]
fn a_projected_jacobian_gives_the_estimable_set_of_its_construction() {
    for seed in 0..20 {
        let (j, _) = projected(seed);
        let got = bounds(&(j.transpose() * &j)).expect("a bound");
        // Undetermined shares in scaled units: 0 to rounding for the estimable parameters,
        // at least the smallest weight of u and v (≈ 0.3) for the others.
        let share: Vec<Real> = (0..7)
            .map(|k| got.undetermined[k] * got.column_norms[k])
            .collect();
        let estimable: Vec<usize> = (0..7).filter(|&k| share[k] < 1e-9).collect();
        assert_eq!(estimable, vec![0, 3], "seed {seed}: {share:?}");
        assert!(
            share.iter().all(|s| !(1e-9..=0.1).contains(s)),
            "seed {seed}: {share:?}"
        );
    }
}

#[test]
fn the_variances_and_shares_are_those_of_the_scaled_pseudo_inverse() {
    for seed in 0..20 {
        let (j, r) = projected(seed);
        let n = j.transpose() * &j;
        let got = bounds(&n).expect("a bound");
        // Apart: the column-scaled S = D⁻¹ n D⁻¹, its pseudo-inverse by SVD (singular values
        // below 1e-9 of the largest dropped), and the projector I − S S⁺ onto its null space.
        let d: Vec<Real> = (0..7).map(|k| n[(k, k)].sqrt()).collect();
        let s = DMatrix::from_fn(7, 7, |i, k| n[(i, k)] / (d[i] * d[k]));
        let pinv = s.clone().pseudo_inverse(1e-9 * s.norm()).expect("an SVD");
        let null = DMatrix::<Real>::identity(7, 7) - &s * &pinv;
        for i in 0..7 {
            let want = pinv[(i, i)] / (d[i] * d[i]);
            let v = got.variances[i];
            assert!(
                (v - want).abs() <= 1e-8 * want,
                "seed {seed}: parameter {i}: {v} against {want}"
            );
            // Squared shares: (I − S S⁺)ᵢᵢ = ‖P ẽᵢ‖², compared where rounding is linear.
            let (u, share) = (got.undetermined[i] * d[i], null[(i, i)]);
            assert!(
                (u * u - share).abs() <= 1e-10,
                "seed {seed}: parameter {i}: share² {} against {share}",
                u * u
            );
        }
        // And an estimable parameter's variance is that of the pseudo-inverse of n itself
        // on the row space (Searle, Linear Models § 5.4): the same for every g-inverse.
        let m = r.transpose() * &n * &r;
        let row = &r * m.try_inverse().expect("regular on the row space") * r.transpose();
        for i in [0, 3] {
            let (v, want) = (got.variances[i], row[(i, i)]);
            assert!(
                (v - want).abs() <= 1e-8 * want,
                "seed {seed}: {v} against {want}"
            );
        }
    }
}
