//! [`super::estimable_variances`] against independent truth: a closed form, a rank-deficient
//! Jacobian whose estimable parameters are known by construction, and the pseudo-inverse on
//! the estimable subspace computed apart (nalgebra's SVD and symmetric eigendecomposition).

use super::estimable_variances;
use crate::numeric::{rng, Real};
use nalgebra::{DMatrix, DVector};
use rand::Rng;

#[test]
fn two_parameters_whose_sum_only_is_determined_are_not_estimable() {
    // Columns c1, c2 = c1 and c3: y = c1 (x1 + x2) + c3 x3. Neither x1 nor x2 is estimable;
    // x3 is, with the variance of the model in u = x1 + x2 and x3: [cᵀc] = [[5, 1], [1, 10]],
    // whose inverse has 5 / 49 at (2, 2).
    let j = DMatrix::from_row_slice(3, 3, &[1.0, 1.0, 1.0, 2.0, 2.0, 0.0, 0.0, 0.0, 3.0]);
    let got = estimable_variances(&(j.transpose() * &j)).expect("a bound");
    assert_eq!(got[0], None);
    assert_eq!(got[1], None);
    let v = got[2].expect("x3 estimable");
    assert!((v - 5.0 / 49.0).abs() <= 1e-14, "{v}");
}

#[test]
fn a_full_rank_normal_matrix_keeps_the_diagonal_of_its_inverse_bit_for_bit() {
    let mut g = rng::from_seed(3);
    let j = DMatrix::from_fn(20, 5, |_, _| g.random_range(-1.0..1.0));
    let n = j.transpose() * &j;
    let want = crate::identify::solver::inverse_diagonal(&n).expect("regular");
    let got = estimable_variances(&n).expect("a bound");
    for (w, g) in want.iter().zip(&got) {
        assert_eq!(Some(w.to_bits()), g.map(Real::to_bits));
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
        let got = estimable_variances(&(j.transpose() * &j)).expect("a bound");
        let estimable: Vec<usize> = (0..7).filter(|&k| got[k].is_some()).collect();
        assert_eq!(estimable, vec![0, 3], "seed {seed}: {got:?}");
    }
}

#[test]
fn the_estimable_variances_are_the_pseudo_inverse_on_the_row_space() {
    for seed in 0..20 {
        let (j, r) = projected(seed);
        let n = j.transpose() * &j;
        let got = estimable_variances(&n).expect("a bound");
        // N = R M Rᵀ with M = Rᵀ N R regular on the row space: N⁺ = R M⁻¹ Rᵀ.
        let m = r.transpose() * &n * &r;
        let pinv = &r * m.try_inverse().expect("regular on the row space") * r.transpose();
        // And eᵢ in the row space ⟺ N N⁺ eᵢ = eᵢ (Searle, Linear Models § 5.4).
        let nn = &n * &pinv;
        for i in 0..7 {
            let off = (nn.column(i) - DVector::from_fn(7, |k, _| Real::from(k == i))).norm();
            match got[i] {
                Some(v) => {
                    assert!(off < 1e-10, "seed {seed}: parameter {i} off by {off}");
                    let want = pinv[(i, i)];
                    assert!(
                        (v - want).abs() <= 1e-8 * want,
                        "seed {seed}: {v} against {want}"
                    );
                }
                // The null direction D u weighs parameter 2 by about 1e-6 of parameter 1 (their
                // scales 1e-3 and 1e3), so e₂ is that close to the row space, yet not in it.
                None => assert!(off > 1e-7, "seed {seed}: parameter {i} off by only {off}"),
            }
        }
    }
}
