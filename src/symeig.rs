//! Eigenvalues of a small dense symmetric matrix, allocation-free: for the DETMAX candidate
//! scans (Guo 2024 §3.2: every scan evaluates the objective of JᵀJ ± BᵀB, through the
//! singular values sqrt(eig(JᵀJ)), for each candidate block B) and for the rank and
//! condition number of every identification ([`crate::identify::solver::conditioning`]).
//!
//! Householder reduction to tridiagonal form (eigenvalues only: Wilkinson & Reinsch, routine
//! `tred2` without the accumulation of transforms), then the implicit QL iteration with
//! Wilkinson shifts (`tqli` without vectors). Both are backward stable: each eigenvalue is
//! exact for a matrix within a few ε·‖A‖ of the input, as for nalgebra's `symmetric_eigen`.
//! Written on a flat row-major slice so the inner loops are plain slices (nalgebra's generic
//! version spends most of its time outside the arithmetic at k ≈ 26).

use crate::math::Real;

/// Overwrites `d` (length n) with the eigenvalues (unordered) of the symmetric n × n matrix
/// whose **lower triangle** is stored row-major in `a` (`a[i·n + j]`, j ≤ i; the upper
/// triangle is ignored); `a` is destroyed and `e` (length n) is scratch. Returns false when
/// the QL iteration does not converge in 30·n sweeps (d then holds NaN) or when the input is
/// not finite.
pub fn symmetric_eigenvalues(a: &mut [Real], n: usize, d: &mut [Real], e: &mut [Real]) -> bool {
    if n == 0 {
        return true;
    }
    if a[..n * n].iter().any(|x| !x.is_finite()) {
        d[..n].fill(Real::NAN);
        return false;
    }
    tridiagonalise(a, n, d, e);
    if !ql_implicit(d, e, n) {
        d[..n].fill(Real::NAN);
        return false;
    }
    true
}

/// Householder tridiagonalisation of the lower triangle (`tred2`, eigenvalues only): the
/// diagonal into `d`, the sub-diagonal into `e[1..n]` (`e[0] = 0`).
fn tridiagonalise(a: &mut [Real], n: usize, d: &mut [Real], e: &mut [Real]) {
    for i in (1..n).rev() {
        let l = i - 1;
        if l > 0 {
            let (head, row_i) = a.split_at_mut(i * n);
            let ri = &mut row_i[..=l];
            let scale: Real = ri.iter().map(|x| x.abs()).sum();
            if scale == 0.0 {
                e[i] = ri[l];
            } else {
                let mut h = 0.0;
                let inv = 1.0 / scale;
                for x in ri.iter_mut() {
                    *x *= inv;
                    h += *x * *x;
                }
                let f = ri[l];
                let g = if f >= 0.0 { -h.sqrt() } else { h.sqrt() };
                e[i] = scale * g;
                h -= f * g;
                ri[l] = f - g;
                let mut f = 0.0;
                for j in 0..=l {
                    // g = (A u)_j over the lower triangle: row j up to j, then column j below.
                    let mut g = 0.0;
                    let rj = &head[j * n..j * n + j + 1];
                    for (x, u) in rj.iter().zip(&ri[..=j]) {
                        g += x * u;
                    }
                    for kk in (j + 1)..=l {
                        g += head[kk * n + j] * ri[kk];
                    }
                    e[j] = g / h;
                    f += e[j] * ri[j];
                }
                let hh = f / (h + h);
                for j in 0..=l {
                    let f = ri[j];
                    let g = e[j] - hh * f;
                    e[j] = g;
                    let rj = &mut head[j * n..j * n + j + 1];
                    for ((x, ek), uk) in rj.iter_mut().zip(&e[..=j]).zip(&ri[..=j]) {
                        *x -= f * ek + g * uk;
                    }
                }
            }
        } else {
            e[i] = a[i * n + l];
        }
    }
    e[0] = 0.0;
    for i in 0..n {
        d[i] = a[i * n + i];
    }
}

/// Implicit QL with Wilkinson shifts on the tridiagonal (`d`, sub-diagonal `e[1..n]`)
/// (`tqli`, eigenvalues only).
fn ql_implicit(d: &mut [Real], e: &mut [Real], n: usize) -> bool {
    for i in 1..n {
        e[i - 1] = e[i];
    }
    e[n - 1] = 0.0;
    let eps = Real::EPSILON;
    for l in 0..n {
        let mut iter = 0;
        loop {
            let mut m = l;
            while m + 1 < n {
                let dd = d[m].abs() + d[m + 1].abs();
                if e[m].abs() <= eps * dd {
                    break;
                }
                m += 1;
            }
            if m == l {
                break;
            }
            iter += 1;
            if iter > 30 * n.max(1) {
                return false;
            }
            let mut g = (d[l + 1] - d[l]) / (2.0 * e[l]);
            let mut r = (g * g + 1.0).sqrt();
            g = d[m] - d[l] + e[l] / (g + r.copysign(g));
            let (mut s, mut c, mut p) = (1.0, 1.0, 0.0);
            let mut early = false;
            let mut i = m;
            while i > l {
                i -= 1;
                let f = s * e[i];
                let b = c * e[i];
                // sqrt(f² + g²) rather than hypot (half the time of the scan): Gram matrices
                // of Jacobians in mm and rad stay far from the over/underflow range.
                r = (f * f + g * g).sqrt();
                e[i + 1] = r;
                if r == 0.0 {
                    d[i + 1] -= p;
                    e[m] = 0.0;
                    early = true;
                    break;
                }
                s = f / r;
                c = g / r;
                g = d[i + 1] - p;
                r = (d[i] - g) * s + 2.0 * c * b;
                p = s * r;
                d[i + 1] = g + p;
                g = c * r - b;
            }
            if early {
                continue;
            }
            d[l] -= p;
            e[l] = g;
            e[m] = 0.0;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::from_seed;
    use nalgebra::DMatrix;
    use rand::Rng as _;
    use rand_distr::StandardNormal;

    /// Largest eigenvalue difference to nalgebra's, relative to the largest |eigenvalue|.
    fn rel_err(m: &DMatrix<Real>) -> Real {
        let n = m.nrows();
        let mut want: Vec<Real> = m.symmetric_eigenvalues().iter().copied().collect();
        want.sort_unstable_by(|a, b| a.total_cmp(b));
        // Row-major lower triangle; garbage in the upper triangle must be ignored.
        let mut a: Vec<Real> = (0..n * n)
            .map(|x| {
                let (i, j) = (x / n, x % n);
                if j <= i {
                    m[(i, j)]
                } else {
                    1e30
                }
            })
            .collect();
        let (mut d, mut e) = (vec![0.0; n], vec![0.0; n]);
        assert!(symmetric_eigenvalues(&mut a, n, &mut d, &mut e));
        d.sort_unstable_by(|a, b| a.total_cmp(b));
        let scale = want.iter().fold(1e-300 as Real, |a, &b| a.max(b.abs()));
        d.iter()
            .zip(&want)
            .map(|(g, w)| (g - w).abs() / scale)
            .fold(0.0, Real::max)
    }

    #[test]
    fn hand_cases() {
        // [[2, 1], [1, 4]] → 3 ± √2; 1 × 1; diagonal.
        let mut a = [2.0, 0.0, 1.0, 4.0];
        let (mut d, mut e) = ([0.0; 2], [0.0; 2]);
        assert!(symmetric_eigenvalues(&mut a, 2, &mut d, &mut e));
        d.sort_unstable_by(|a, b| a.total_cmp(b));
        assert!((d[0] - (3.0 - 2.0f64.sqrt())).abs() < 1e-14);
        assert!((d[1] - (3.0 + 2.0f64.sqrt())).abs() < 1e-14);
        let mut a = [5.0];
        let (mut d, mut e) = ([0.0], [0.0]);
        assert!(symmetric_eigenvalues(&mut a, 1, &mut d, &mut e));
        assert_eq!(d[0], 5.0);
        let mut a = [1.0, 0.0, 0.0, 0.0, 3.0, 0.0, 0.0, 0.0, 2.0];
        let (mut d, mut e) = ([0.0; 3], [0.0; 3]);
        assert!(symmetric_eigenvalues(&mut a, 3, &mut d, &mut e));
        d.sort_unstable_by(|a, b| a.total_cmp(b));
        assert_eq!(d, [1.0, 2.0, 3.0]);
        let mut a = [Real::NAN];
        assert!(!symmetric_eigenvalues(&mut a, 1, &mut [0.0], &mut [0.0]));
    }

    #[test]
    fn gram_plus_and_minus_rank3_match_nalgebra() {
        let mut rng = from_seed(5);
        let randn = |rng: &mut crate::rng::Rng, r: usize, c: usize| {
            DMatrix::from_fn(r, c, |_, _| rng.sample::<Real, _>(StandardNormal))
        };
        for trial in 0..200 {
            let k = [26, 26, 7, 36][trial % 4];
            let j = randn(&mut rng, 3 * 40, k);
            let mut g = j.transpose() * &j;
            let b = randn(&mut rng, 3, k) * 3.0;
            g.gemm_tr(1.0, &b, &b, 1.0);
            assert!(rel_err(&g) < 1e-13, "update {trial}");
            g.gemm_tr(-1.0, &b, &b, 1.0);
            g.gemm_tr(-1.0, &b, &b, 1.0);
            assert!(rel_err(&g) < 1e-13, "downdate {trial}");
        }
    }

    #[test]
    fn clustered_degenerate_and_rank_deficient_spectra() {
        let mut rng = from_seed(9);
        for trial in 0..200 {
            let k = 26;
            // Q diag(λ) Qᵀ with clusters of (nearly) equal eigenvalues and zeros.
            let lam: Vec<Real> = (0..k)
                .map(|i| {
                    let base = [0.0, 1.0, 1.0, 1e3, 1e-6][(i + trial) % 5];
                    base * (1.0 + 1e-12 * rng.random::<Real>() * (trial % 3) as Real)
                })
                .collect();
            let x = DMatrix::from_fn(k, k, |_, _| rng.sample::<Real, _>(StandardNormal));
            let q = x.qr().q();
            let m = &q * DMatrix::from_diagonal(&nalgebra::DVector::from_vec(lam)) * q.transpose();
            let m = (&m + m.transpose()) * 0.5;
            assert!(rel_err(&m) < 1e-13, "{trial}");
            // A rank-3 Gram matrix (k − 3 zero eigenvalues).
            let j = DMatrix::from_fn(3, k, |_, _| rng.sample::<Real, _>(StandardNormal));
            assert!(rel_err(&(j.transpose() * &j)) < 1e-13, "rank 3, {trial}");
        }
    }
}
