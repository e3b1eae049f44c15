//! Allocation-free dense Cholesky factorisation, solve and inverse: the one factor of the
//! library, for the normal equations and the Gaussian process's kernel matrix.
//!
//! The kernels are plain Rust run through the numeric kernels' one dispatch: compiled for
//! AVX2 and FMA where the processor has them, with the same bits either way (every update
//! is an explicit fused multiply-add in a fixed order).

use nalgebra::linalg::SVD;
use nalgebra::{DMatrix, DVector, Dyn};

use super::simd;
use super::Real;

/// The most iterations [`svd`] lets nalgebra's SVD take: orders of magnitude more than a
/// finite matrix of calbench's needs (a few per singular value).
pub const SVD_MAX_ITERATIONS: usize = 100_000;

/// The singular value decomposition of `m` (`u`, `v`: whether to compute U and Vᵀ), as
/// nalgebra's `svd` computes it (the same tolerance, so the same bits), but bounded: `None`
/// for an empty matrix, a matrix with a non-finite entry (on which nalgebra's iteration never
/// ends) or one not converged after [`SVD_MAX_ITERATIONS`]. The one SVD of a dynamic matrix
/// in the library.
pub fn svd(m: DMatrix<Real>, u: bool, v: bool) -> Option<SVD<Real, Dyn, Dyn>> {
    if m.is_empty() || !m.iter().all(|x| x.is_finite()) {
        return None;
    }
    SVD::try_new(m, u, v, Real::EPSILON * 5.0, SVD_MAX_ITERATIONS)
}

/// Relative pivot below which a normal matrix counts as singular.
pub(crate) const PIVOT_TOL: Real = 1e-12;

/// Factorises the symmetric matrix `a = L Lᵀ` in place by [`factor`] with the pivot test
/// [`PIVOT_TOL`]: false when `a` is numerically singular or not finite.
pub(crate) fn cholesky_in_place(a: &mut DMatrix<Real>) -> bool {
    let n = a.nrows();
    factor(a.as_mut_slice(), n, PIVOT_TOL)
}

/// Factorises the symmetric `n × n` matrix `s = L Lᵀ` in place: the one Cholesky factor of
/// the library (the normal equations through [`cholesky_in_place`], the Gaussian process's
/// kernel matrix in `numeric::gp`). `s` is column-major and only its lower triangle is
/// read. On return L is in the lower triangle and mirrored into the upper one, so that `s`
/// holds L both column-major (column j of L contiguous, `s[j n + i]`, i ≥ j) and row-major
/// (row i of L contiguous, `s[i n + j]`, j ≤ i). Returns false when a pivot is not positive
/// or falls below `tol` times its own diagonal entry before the updates (with `tol` > 0 the
/// test is numerical singularity, invariant to column scaling, so mm and rad columns compare;
/// with `tol` = 0 it is positive definiteness), or when a diagonal entry is not finite.
pub(crate) fn factor(s: &mut [Real], n: usize, tol: Real) -> bool {
    let mut dmax: Real = 0.0;
    for i in 0..n {
        let d = s[i * n + i];
        if !d.is_finite() {
            return false;
        }
        dmax = dmax.max(d.abs());
    }
    if dmax == 0.0 {
        return n == 0;
    }
    simd::dispatch(
        #[inline(always)]
        |_| factor_columns(s, n, tol),
    )
}

/// The column loop of [`factor`] on the column-major `s` (n × n).
///
/// Left-looking: column j from row j down, `a_ij ← fma(−L[i,k], L[j,k], a_ij)` for k = 0, 1,
/// … in turn (one rounding per term), then scaled by the reciprocal of its pivot's square
/// root. Columns go in pairs: the terms k < j of columns j and j + 1 together
/// ([`update_columns`]: each loaded value of L serves both, and the two columns' sums run
/// side by side), then column j is finished, then column j + 1 takes its term k = j and is
/// finished: every entry's terms in the same order as one column at a time.
#[inline(always)]
fn factor_columns(s: &mut [Real], n: usize, tol: Real) -> bool {
    let mut j = 0;
    while j < n {
        let pair = j + 1 < n;
        let first = s[j * n + j];
        let second = if pair { s[(j + 1) * n + j + 1] } else { 0.0 };
        if j > 0 {
            let (left, right) = s.split_at_mut(j * n);
            if pair {
                update::<2>(left, &mut right[..2 * n], n, j);
            } else {
                update::<1>(left, &mut right[..n], n, j);
            }
        }
        if !finish_column(s, n, j, first, tol) {
            return false;
        }
        if pair {
            let (left, right) = s.split_at_mut((j + 1) * n);
            let (lj, col) = (&left[j * n..], &mut right[..n]);
            let l = -lj[j + 1];
            for (a, &y) in col[j + 1..].iter_mut().zip(&lj[j + 1..]) {
                *a = y.mul_add(l, *a);
            }
            if !finish_column(s, n, j + 1, second, tol) {
                return false;
            }
        }
        j += 2;
    }
    true
}

/// Checks column j's pivot against `tol` times its diagonal entry before the updates (`ajj`), then
/// replaces the pivot by its square root and scales the rows below by the root's reciprocal,
/// mirroring them into row j of the upper triangle. False when the pivot fails the check.
#[inline(always)]
fn finish_column(s: &mut [Real], n: usize, j: usize, ajj: Real, tol: Real) -> bool {
    let d = s[j * n + j];
    if d.is_nan() || d <= tol * ajj {
        return false;
    }
    let l = d.sqrt();
    let inverse = 1.0 / l;
    s[j * n + j] = l;
    for i in j + 1..n {
        let v = s[j * n + i] * inverse;
        s[j * n + i] = v;
        s[i * n + j] = v;
    }
    true
}

/// [`update_columns`] with the widest register block that the rows left (n − j) and the
/// matrix (n) allow.
#[inline(always)]
fn update<const C: usize>(left: &[Real], cols: &mut [Real], n: usize, j: usize) {
    let rows = n - j;
    if n >= 16 && rows > 8 {
        update_columns::<C, 16>(left, cols, n, j);
    } else if n >= 8 && rows > 4 {
        update_columns::<C, 8>(left, cols, n, j);
    } else if n >= 4 {
        update_columns::<C, 4>(left, cols, n, j);
    } else {
        update_columns::<C, 1>(left, cols, n, j);
    }
}

/// The `C` (1 or 2) columns j, j + 1 (`cols`, column-major with n rows, n ≥ `B`) updated by the
/// j columns of L to their left (`left`): rows j.. (column j + c from row j + c) `B` at a
/// time, kept in registers across the k's. A block that would run past the last row is moved
/// up to end there: its first rows (above the column's diagonal, or already updated) are
/// computed and not stored, so that every block is a whole register block and every stored
/// entry gets the same fused updates in the same order.
#[inline(always)]
fn update_columns<const C: usize, const B: usize>(
    left: &[Real],
    cols: &mut [Real],
    n: usize,
    j: usize,
) {
    let mut r0 = j;
    while r0 < n {
        let b0 = r0.min(n - B);
        let mut acc0: [Real; B] = cols[b0..b0 + B].try_into().expect("B values");
        let mut acc1: [Real; B] = if C == 2 {
            cols[n + b0..n + b0 + B].try_into().expect("B values")
        } else {
            [0.0; B]
        };
        for k in 0..j {
            let lk = &left[k * n..(k + 1) * n];
            let y: &[Real; B] = lk[b0..b0 + B].try_into().expect("B values");
            let l0 = -lk[j];
            for (a, &y) in acc0.iter_mut().zip(y) {
                *a = y.mul_add(l0, *a);
            }
            if C == 2 {
                let l1 = -lk[j + 1];
                for (a, &y) in acc1.iter_mut().zip(y) {
                    *a = y.mul_add(l1, *a);
                }
            }
        }
        cols[r0..b0 + B].copy_from_slice(&acc0[r0 - b0..]);
        if C == 2 {
            let from = r0.max(j + 1);
            cols[n + from..n + b0 + B].copy_from_slice(&acc1[from - b0..]);
        }
        r0 = b0 + B;
    }
}

/// Solves `L Lᵀ x = b` in place with the factor from [`cholesky_in_place`] (by [`solve`]).
pub(crate) fn cholesky_solve(l: &DMatrix<Real>, b: &mut DVector<Real>) {
    solve(l.as_slice(), l.nrows(), b.as_mut_slice());
}

/// Solves `L Lᵀ x = b` in place with the factor `l` (n × n) from [`factor`]: the forward
/// sweep down the contiguous columns of L, the backward one down those of Lᵀ (the mirrored
/// upper triangle), each as column updates `b_i ← fma(−l_i, x_k, b_i)` with
/// `x_k = b_k · (1/l_kk)`.
pub(crate) fn solve(l: &[Real], n: usize, b: &mut [Real]) {
    simd::dispatch(
        #[inline(always)]
        |_| {
            forward(l, b, n, 0);
            backward(l, b, n);
        },
    );
}

/// The forward sweep of [`solve`] from row `from` on (the rows above hold zeros: `L⁻¹ b` for
/// a `b` that vanishes above `from`).
#[inline(always)]
fn forward(ls: &[Real], bs: &mut [Real], n: usize, from: usize) {
    for k in from..n {
        let col = &ls[k * n..(k + 1) * n];
        let v = bs[k] * (1.0 / col[k]);
        bs[k] = v;
        for (bi, li) in bs[k + 1..].iter_mut().zip(&col[k + 1..]) {
            *bi = li.mul_add(-v, *bi);
        }
    }
}

/// The backward sweep of [`solve`].
#[inline(always)]
fn backward(ls: &[Real], bs: &mut [Real], n: usize) {
    for i in (0..n).rev() {
        // Column i of the upper triangle: L[i, 0..i].
        let row = &ls[i * n..i * n + i];
        let v = bs[i] * (1.0 / ls[i * n + i]);
        bs[i] = v;
        for (bk, lk) in bs[..i].iter_mut().zip(row) {
            *bk = lk.mul_add(-v, *bk);
        }
    }
}

/// `A⁻¹` from the factor `l` (n × n) of [`factor`], into the lower triangle of `l` read
/// row-major (`l[i n + j]`, j ≤ i; the rest of `l` is left undefined): first `U = L⁻ᵀ` into
/// `u` (row j of `u`, from column j on, is column j of L⁻¹, by [`solve`]'s forward sweep on
/// the unit vector e_j), then `(A⁻¹)_ij = Σ_{k ≥ i} U_ik U_jk` (i ≥ j) as a fused dot product
/// in four partial sums, `(s0 + s1) + (s2 + s3)` then the remainder.
pub(crate) fn inverse(l: &mut [Real], u: &mut [Real], n: usize) {
    simd::dispatch(
        #[inline(always)]
        |_| {
            for j in 0..n {
                let row = &mut u[j * n..(j + 1) * n];
                row[j..].fill(0.0);
                row[j] = 1.0;
                forward(l, row, n, j);
            }
            for i in 0..n {
                let ui = &u[i * n + i..(i + 1) * n];
                for j in 0..=i {
                    l[i * n + j] = fused_dot(ui, &u[j * n + i..(j + 1) * n]);
                }
            }
        },
    );
}

/// `Σ a_k b_k` over the shorter length, in four fused partial sums.
#[inline(always)]
fn fused_dot(a: &[Real], b: &[Real]) -> Real {
    let n = a.len().min(b.len());
    let mut s = [0.0 as Real; 4];
    let (ac, bc) = (a[..n].chunks_exact(4), b[..n].chunks_exact(4));
    let (ar, br) = (ac.remainder(), bc.remainder());
    for (x, y) in ac.zip(bc) {
        for t in 0..4 {
            s[t] = x[t].mul_add(y[t], s[t]);
        }
    }
    let mut r = (s[0] + s[1]) + (s[2] + s[3]);
    for (x, y) in ar.iter().zip(br) {
        r = x.mul_add(*y, r);
    }
    r
}

/// `trace (L Lᵀ)⁻¹ = ‖L⁻¹‖²_F` from the factor `l` of [`cholesky_in_place`]: the squared
/// entries of L⁻¹ summed column by column. Four columns of L⁻¹ at a time, by forward
/// substitution on the unit vectors e_c side by side; each of the four partial sums takes
/// its own column's squares, combined as `(s0 + s2) + (s1 + s3)`.
pub(crate) fn cholesky_inverse_trace(l: &DMatrix<Real>) -> Real {
    // Four columns of L⁻¹ at a time (forward substitution on e_c for c = c0…c0+3 side by
    // side, down the contiguous columns of L; a column c > k has v_k = 0 and takes no update).
    let t = l.nrows();
    let inverse: Vec<Real> = (0..t).map(|k| 1.0 / l[(k, k)]).collect();
    let l = l.as_slice();
    let mut v = vec![[0.0 as Real; 4]; t];
    simd::dispatch(
        #[inline(always)]
        |_| {
            let mut sums = [0.0 as Real; 4];
            for c0 in (0..t).step_by(4) {
                for (i, vi) in v.iter_mut().enumerate().skip(c0) {
                    *vi = std::array::from_fn(|c| if i == c0 + c { 1.0 } else { 0.0 });
                }
                for k in c0..t {
                    let x: [Real; 4] = std::array::from_fn(|c| v[k][c] * inverse[k]);
                    for c in 0..4 {
                        sums[c] += x[c] * x[c];
                    }
                    for (vi, &lik) in v[k + 1..].iter_mut().zip(&l[k * t + k + 1..(k + 1) * t]) {
                        for c in 0..4 {
                            vi[c] -= lik * x[c];
                        }
                    }
                }
            }
            (sums[0] + sums[2]) + (sums[1] + sums[3])
        },
    )
}

/// Solves `a x = b` for symmetric positive definite `a` (copied into `work`); the answer goes
/// to `x`. Returns false when `a` is numerically singular.
pub(crate) fn solve_spd(
    a: &DMatrix<Real>,
    b: &DVector<Real>,
    work: &mut DMatrix<Real>,
    x: &mut DVector<Real>,
) -> bool {
    work.copy_from(a);
    if !cholesky_in_place(work) {
        return false;
    }
    x.copy_from(b);
    cholesky_solve(work, x);
    x.iter().all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Numbers in [−0.5, 0.5) from a linear congruential generator seeded with `seed`.
    fn uniform(mut seed: u64) -> impl FnMut() -> Real {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as Real / (1u64 << 53) as Real - 0.5
        }
    }

    #[test]
    fn solves_a_known_spd_system() {
        // A = [[4,2,0],[2,5,1],[0,1,3]], x = [1,-2,3] → b = A x = [0,-5,7].
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 2.0, 0.0, 2.0, 5.0, 1.0, 0.0, 1.0, 3.0]);
        let b = DVector::from_vec(vec![0.0, -5.0, 7.0]);
        let mut w = DMatrix::zeros(3, 3);
        let mut x = DVector::zeros(3);
        assert!(solve_spd(&a, &b, &mut w, &mut x));
        assert_relative_eq!(x, DVector::from_vec(vec![1.0, -2.0, 3.0]), epsilon = 1e-12);
    }

    /// The register blocks of [`factor_columns`] give the bits of the plain left-looking
    /// loop (each entry's fused updates over k in ascending order, the column scaled by the
    /// pivot's reciprocal), for sizes under, at and over the block and with columns of very
    /// different scales; the upper triangle mirrors L.
    #[test]
    fn blocked_factor_is_the_plain_loop_to_the_bit() {
        let mut next = uniform(7u64);
        for n in [1, 2, 5, 7, 8, 9, 14, 15, 16, 17, 20, 31, 33, 47] {
            let m = n + 30;
            let j = DMatrix::from_fn(m, n, |_, c| next() * [1.0, 1e3, 1e-2][c % 3]);
            let a = j.transpose() * &j;
            let mut plain = a.clone();
            for c in 0..n {
                for k in 0..c {
                    let lck = plain[(c, k)];
                    for i in c..n {
                        plain[(i, c)] = plain[(i, k)].mul_add(-lck, plain[(i, c)]);
                    }
                }
                let l = plain[(c, c)].sqrt();
                plain[(c, c)] = l;
                for i in c + 1..n {
                    plain[(i, c)] *= 1.0 / l;
                }
            }
            let mut blocked = a.clone();
            assert!(cholesky_in_place(&mut blocked), "n {n}");
            for c in 0..n {
                for i in c..n {
                    assert_eq!(
                        blocked[(i, c)].to_bits(),
                        plain[(i, c)].to_bits(),
                        "n {n}, ({i}, {c})"
                    );
                    assert_eq!(blocked[(c, i)].to_bits(), blocked[(i, c)].to_bits());
                }
            }
        }
    }

    /// The factorisation, the solve, the inverse and its trace give the same bits on every
    /// instruction set the processor offers.
    #[test]
    fn every_path_gives_the_same_bits() {
        let mut next = uniform(11u64);
        for n in [1, 3, 8, 17, 26, 40] {
            let j = DMatrix::from_fn(n + 20, n, |_, c| next() * [1.0, 1e3, 1e-2][c % 3]);
            let a = j.transpose() * &j;
            let b = DVector::from_fn(n, |i, _| (i as Real).cos());
            let run = || {
                let mut l = a.clone();
                assert!(cholesky_in_place(&mut l), "n {n}");
                let mut x = b.clone();
                cholesky_solve(&l, &mut x);
                let trace = cholesky_inverse_trace(&l);
                let mut inv = l.as_slice().to_vec();
                let mut u = vec![0.0; n * n];
                inverse(&mut inv, &mut u, n);
                let mut bits: Vec<u64> = l.iter().chain(x.iter()).map(|v| v.to_bits()).collect();
                bits.push(trace.to_bits());
                bits.extend(
                    (0..n)
                        .flat_map(|i| (0..=i).map(move |c| (i, c)))
                        .map(|(i, c)| inv[i * n + c].to_bits()),
                );
                bits
            };
            let portable = simd::forced(simd::Isa::Portable, run);
            for isa in simd::available() {
                assert_eq!(simd::forced(isa, run), portable, "n {n}, {isa:?}");
            }
            // The trace is that of the inverse.
            let want = a.clone().try_inverse().expect("invertible").trace();
            let got = f64::from_bits(portable[n * n + n]);
            assert!((got - want).abs() <= 1e-8 * want, "n {n}: {got} vs {want}");
        }
    }

    /// The factor of a 2 × 2 matrix in closed form, to the bit: A = [[4, 2], [2, 5]] has
    /// L = [[2, 0], [1, 2]] and A⁻¹ = [[5, −2], [−2, 4]] / 16; the solve of A x = (8, 9)
    /// gives x = (1.375, 1.25).
    #[test]
    fn two_by_two_in_closed_form() {
        let mut s = vec![4.0, 2.0, 2.0, 5.0];
        assert!(factor(&mut s, 2, PIVOT_TOL));
        assert_eq!(s, [2.0, 1.0, 1.0, 2.0]);
        let mut b = vec![8.0, 9.0];
        solve(&s, 2, &mut b);
        assert_relative_eq!(b[0], 1.375, epsilon = 1e-15);
        assert_relative_eq!(b[1], 1.25, epsilon = 1e-15);
        let mut u = vec![0.0; 4];
        inverse(&mut s, &mut u, 2);
        assert_eq!((s[0], s[2], s[3]), (5.0 / 16.0, -2.0 / 16.0, 4.0 / 16.0));
    }

    /// On random symmetric positive definite matrices (sizes under, at and over the register
    /// blocks, columns of very different scales): L Lᵀ rebuilds A, L is mirrored into the
    /// upper triangle, the solve gives back a known x, and A A⁻¹ is the identity.
    #[test]
    fn factor_solve_and_inverse_against_a_rebuilt_a() {
        let mut next = uniform(3u64);
        for n in [1, 2, 5, 9, 16, 17, 45] {
            let j = DMatrix::from_fn(n + 10, n, |_, c| next() * [1.0, 1e3, 1e-2][c % 3]);
            let a = j.transpose() * &j;
            let mut s = a.as_slice().to_vec();
            assert!(factor(&mut s, n, PIVOT_TOL), "n {n}");
            let l = DMatrix::from_fn(n, n, |i, c| if i >= c { s[c * n + i] } else { 0.0 });
            for i in 0..n {
                for c in 0..=i {
                    assert_eq!(s[i * n + c].to_bits(), s[c * n + i].to_bits(), "mirror");
                }
            }
            let rebuilt = &l * l.transpose();
            for i in 0..n {
                for c in 0..n {
                    let scale = (a[(i, i)] * a[(c, c)]).sqrt();
                    assert!(
                        (rebuilt[(i, c)] - a[(i, c)]).abs() <= 1e-13 * scale,
                        "n {n}"
                    );
                }
            }
            let x = DVector::from_fn(n, |i, _| 1.0 + i as Real);
            let mut b = (&a * &x).as_slice().to_vec();
            solve(&s, n, &mut b);
            for (got, want) in b.iter().zip(x.iter()) {
                assert!((got - want).abs() <= 1e-6 * want, "n {n}: {got} vs {want}");
            }
            let mut u = vec![0.0; n * n];
            inverse(&mut s, &mut u, n);
            let inv = DMatrix::from_fn(n, n, |i, c| s[i.max(c) * n + i.min(c)]);
            let eye = &a * inv;
            for i in 0..n {
                for c in 0..n {
                    let want = if i == c { 1.0 } else { 0.0 };
                    // A's columns differ in scale by 1e5: the residual in each column of A A⁻¹
                    // scales with its condition.
                    let tol = 1e-9 * (a[(i, i)] / a[(c, c)]).sqrt().max(1.0);
                    assert!((eye[(i, c)] - want).abs() <= tol, "n {n}: ({i}, {c})");
                }
            }
        }
    }

    /// Tolerance 0 tests positive definiteness, a positive tolerance numerical singularity:
    /// a pivot of 1e-14 relative to its diagonal entry passes the first and fails the second.
    #[test]
    fn the_tolerance_separates_singular_from_indefinite() {
        let a = [1.0, 1.0, 1.0, 1.0 + 1e-14];
        let mut s = a.to_vec();
        assert!(factor(&mut s, 2, 0.0));
        let mut s = a.to_vec();
        assert!(!factor(&mut s, 2, PIVOT_TOL));
        let mut s = vec![1.0, 2.0, 2.0, 1.0];
        assert!(!factor(&mut s, 2, 0.0));
        let mut s = vec![Real::NAN, 0.0, 0.0, 1.0];
        assert!(!factor(&mut s, 2, 0.0));
    }

    #[test]
    fn reports_a_singular_matrix() {
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]);
        let mut w = DMatrix::zeros(2, 2);
        assert!(!cholesky_in_place(&mut {
            w.copy_from(&a);
            w
        }));
    }
}
