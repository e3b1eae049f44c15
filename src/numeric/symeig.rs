//! Eigenvalues of a small dense symmetric matrix, allocation-free: for every pose-selection
//! objective (Guo 2024 §3.2: DETMAX's scans evaluate the objective of JᵀJ ± BᵀB for each
//! candidate block B, IDE's generations that of each trial set, through the singular values
//! sqrt(eig(JᵀJ))) and for the rank and condition number of every identification
//! ([`crate::identify::solver::conditioning`]).
//!
//! Householder reduction to tridiagonal form (eigenvalues only: Wilkinson & Reinsch, routine
//! `tred2` without the accumulation of transforms), then the implicit QL iteration with
//! Wilkinson shifts (`tqli` without vectors). Both are backward stable: each eigenvalue is
//! exact for a matrix within a few ε·‖A‖ of the input, as for nalgebra's `symmetric_eigen`.
//! Written on a flat row-major slice so the inner loops are plain slices (nalgebra's generic
//! version spends most of its time outside the arithmetic at k ≈ 26), and for several
//! matrices at once ([`symmetric_eigenvalues_lanes`]): one entry holds the same entry of each
//! matrix, every operation runs across them, and each matrix gets the bits it would get alone.

use super::simd;
use super::Real;

/// Overwrites `d` (length n) with the eigenvalues (unordered) of the symmetric n × n matrix
/// whose **lower triangle** is stored row-major in `a` (`a[i·n + j]`, j ≤ i; the upper
/// triangle is neither read nor written); the lower triangle is destroyed and `e` (length n)
/// is scratch. Returns false when the QL iteration does not converge in 30·n sweeps (d then
/// holds NaN) or when the lower triangle is not finite.
pub fn symmetric_eigenvalues(a: &mut [Real], n: usize, d: &mut [Real], e: &mut [Real]) -> bool {
    symmetric_eigenvalues_lanes(one_lane(a), n, one_lane(d), one_lane(e)) == [true]
}

/// `x` as one-lane entries.
fn one_lane(x: &mut [Real]) -> &mut [[Real; 1]] {
    // SAFETY: `[Real; 1]` has the size and alignment of `Real`, so the same memory holds as
    // many one-lane entries as values; the borrow is carried over.
    unsafe { std::slice::from_raw_parts_mut(x.as_mut_ptr().cast(), x.len()) }
}

/// [`symmetric_eigenvalues`] of `L` matrices at once, lane `t` of every entry belonging to
/// matrix `t` (`a[i·n + j][t]`): each lane goes through exactly the arithmetic of the one-matrix
/// call, in the same order, so its eigenvalues are the same bits; the lanes share the
/// instructions (SIMD, AVX2 when the processor has it) and hide each other's latency in the QL
/// sweeps. Returns, per lane, whether it converged (a lane that did not holds NaN in `d`).
pub fn symmetric_eigenvalues_lanes<const L: usize>(
    a: &mut [[Real; L]],
    n: usize,
    d: &mut [[Real; L]],
    e: &mut [[Real; L]],
) -> [bool; L] {
    simd::dispatch(
        #[inline(always)]
        |_| {
            let mut ok = [true; L];
            if n == 0 {
                return ok;
            }
            for i in 0..n {
                for x in &a[i * n..i * n + i + 1] {
                    for t in 0..L {
                        ok[t] &= x[t].is_finite();
                    }
                }
            }
            if ok.iter().any(|&o| o) {
                tridiagonalise(a, n, d, e);
                ql_implicit(d, e, n, &mut ok);
            }
            for (t, &o) in ok.iter().enumerate() {
                if !o {
                    for x in &mut d[..n] {
                        x[t] = Real::NAN;
                    }
                }
            }
            ok
        },
    )
}

/// Lane-wise `f(x, y)`.
#[inline(always)]
fn zip<const L: usize>(x: [Real; L], y: [Real; L], f: impl Fn(Real, Real) -> Real) -> [Real; L] {
    std::array::from_fn(|t| f(x[t], y[t]))
}

/// Lane-wise `acc + x·u` (a multiplication and an addition: no fused multiply-add).
#[inline(always)]
fn mul_add<const L: usize>(acc: [Real; L], x: [Real; L], u: [Real; L]) -> [Real; L] {
    std::array::from_fn(|t| acc[t] + x[t] * u[t])
}

/// Householder tridiagonalisation of the lower triangle (`tred2`, eigenvalues only): the
/// diagonal into `d`, the sub-diagonal into `e[1..n]` (`e[0] = 0`). A lane whose row to reduce
/// is zero (`scale == 0`) keeps its matrix: its transform is computed with unit scale and a
/// zero vector, and not applied.
#[inline(always)]
fn tridiagonalise<const L: usize>(
    a: &mut [[Real; L]],
    n: usize,
    d: &mut [[Real; L]],
    e: &mut [[Real; L]],
) {
    for i in (1..n).rev() {
        let l = i - 1;
        if l > 0 {
            let (head, row_i) = a.split_at_mut(i * n);
            let ri = &mut row_i[..=l];
            let mut scale = [0.0; L];
            for x in ri.iter() {
                scale = zip(scale, *x, |s, x| s + x.abs());
            }
            let skip: Mask<L> = mask(|t| scale[t] == 0.0);
            let inv = zip(scale, [1.0; L], |s, one| {
                one / if s == 0.0 { one } else { s }
            });
            let mut h = [0.0; L];
            for x in ri.iter_mut() {
                *x = zip(*x, inv, |x, inv| x * inv);
                h = zip(h, *x, |h, x| h + x * x);
            }
            let f = ri[l];
            let g = zip(f, h, |f, h| if f >= 0.0 { -h.sqrt() } else { h.sqrt() });
            e[i] = blend(skip, f, zip(scale, g, |s, g| s * g));
            let h = zip(h, zip(f, g, |f, g| f * g), |h, fg| h - fg);
            let h = blend(skip, [1.0; L], h);
            ri[l] = zip(f, g, |f, g| f - g);
            // g = (A u)_j over the lower triangle (row j up to j, then column j below), two
            // rows at a time: two independent sums sharing the loads of u, each in the order
            // of its row alone.
            let mut f = [0.0; L];
            let mut j = 0;
            while j <= l {
                let pair = j < l;
                let (mut g0, mut g1) = ([0.0; L], [0.0; L]);
                if pair {
                    let r0 = &head[j * n..j * n + j + 1];
                    let r1 = &head[(j + 1) * n..(j + 1) * n + j + 2];
                    for ((x0, x1), u) in r0.iter().zip(r1).zip(&ri[..=j]) {
                        g0 = mul_add(g0, *x0, *u);
                        g1 = mul_add(g1, *x1, *u);
                    }
                    g1 = mul_add(g1, r1[j + 1], ri[j + 1]);
                    g0 = mul_add(g0, r1[j], ri[j + 1]);
                    for kk in (j + 2)..=l {
                        g0 = mul_add(g0, head[kk * n + j], ri[kk]);
                        g1 = mul_add(g1, head[kk * n + j + 1], ri[kk]);
                    }
                } else {
                    for (x, u) in head[j * n..j * n + j + 1].iter().zip(&ri[..=j]) {
                        g0 = mul_add(g0, *x, *u);
                    }
                }
                for (jj, g) in [(j, g0), (j + 1, g1)].into_iter().take(1 + pair as usize) {
                    e[jj] = zip(g, h, |g, h| g / h);
                    f = mul_add(f, e[jj], ri[jj]);
                }
                j += 1 + pair as usize;
            }
            let hh = zip(f, h, |f, h| f / (h + h));
            // Row j less f_j e + g_j u over its first j + 1 entries, with g_j = e_j − hh f_j
            // (into e_j) and f_j = u_j; two rows at a time, sharing the loads of e and u. A
            // lane that skips keeps its entries: without one (almost always) no selection.
            let any_skip = skip.iter().any(|&s| s != 0);
            let step =
                |f: &[Real; L], g: &[Real; L], ek: &[Real; L], uk: &[Real; L]| -> [Real; L] {
                    std::array::from_fn(|t| f[t] * ek[t] + g[t] * uk[t])
                };
            let sub = |x: Real, s: Real| x - s;
            let mut j = 0;
            while j <= l {
                let f0 = ri[j];
                let g0 = zip(e[j], zip(hh, f0, |hh, f| hh * f), |e, hf| e - hf);
                e[j] = g0;
                if any_skip || j == l {
                    let updates = head[j * n..j * n + j + 1]
                        .iter_mut()
                        .zip(&e[..=j])
                        .zip(&ri[..=j]);
                    for ((x, ek), uk) in updates {
                        let new = zip(*x, step(&f0, &g0, ek, uk), sub);
                        *x = if any_skip { blend(skip, *x, new) } else { new };
                    }
                    j += 1;
                    continue;
                }
                let f1 = ri[j + 1];
                let g1 = zip(e[j + 1], zip(hh, f1, |hh, f| hh * f), |e, hf| e - hf);
                e[j + 1] = g1;
                let (r0, r1) = head[j * n..(j + 2) * n].split_at_mut(n);
                let rows = r0[..=j].iter_mut().zip(&mut r1[..=j]);
                for (((x0, x1), ek), uk) in rows.zip(&e[..=j]).zip(&ri[..=j]) {
                    *x0 = zip(*x0, step(&f0, &g0, ek, uk), sub);
                    *x1 = zip(*x1, step(&f1, &g1, ek, uk), sub);
                }
                r1[j + 1] = zip(r1[j + 1], step(&f1, &g1, &e[j + 1], &ri[j + 1]), sub);
                j += 2;
            }
        } else {
            e[i] = a[i * n + l];
        }
    }
    e[0] = [0.0; L];
    for i in 0..n {
        d[i] = a[i * n + i];
    }
}

/// Implicit QL with Wilkinson shifts on the tridiagonal (`d`, sub-diagonal `e[1..n]`)
/// (`tqli`, eigenvalues only). The lanes sweep in step: a lane whose block is already split
/// (or that failed, `ok` false) sits out a sweep, and a lane whose block is shorter than
/// another's joins the sweep at its own bottom row. A lane that does not converge in 30·n
/// sweeps of one eigenvalue gets `ok` false.
#[inline(always)]
fn ql_implicit<const L: usize>(
    d: &mut [[Real; L]],
    e: &mut [[Real; L]],
    n: usize,
    ok: &mut [bool; L],
) {
    for i in 1..n {
        e[i - 1] = e[i];
    }
    e[n - 1] = [0.0; L];
    let eps = Real::EPSILON;
    for l in 0..n {
        let mut iter = [0usize; L];
        loop {
            // The bottom row m of each lane's unreduced block starting at l, all lanes scanning
            // together: the first row mm whose sub-diagonal entry is negligible, else n − 1.
            let mut bottom = [n as u64 - 1; L];
            let mut open: Mask<L> = mask(|t| ok[t]);
            let mut mm = l;
            while mm + 1 < n && open.iter().any(|&o| o != 0) {
                let dd = zip(d[mm], d[mm + 1], |a, b| a.abs() + b.abs());
                let ends: Mask<L> =
                    std::array::from_fn(|t| open[t] & word(e[mm][t].abs() <= eps * dd[t]));
                bottom = std::array::from_fn(|t| (mm as u64 & ends[t]) | (bottom[t] & !ends[t]));
                open = std::array::from_fn(|t| open[t] & !ends[t]);
                mm += 1;
            }
            let mut m = [l; L];
            let mut active = [false; L];
            for t in 0..L {
                if !ok[t] {
                    continue;
                }
                let mm = bottom[t] as usize;
                if mm != l {
                    iter[t] += 1;
                    if iter[t] > 30 * n.max(1) {
                        ok[t] = false;
                        continue;
                    }
                    m[t] = mm;
                    active[t] = true;
                }
            }
            let Some(top) = (0..L).filter(|&t| active[t]).map(|t| m[t]).max() else {
                break;
            };
            let dm: [Real; L] = std::array::from_fn(|t| d[m[t]][t]);
            let g = zip(d[l + 1], d[l], |d1, d0| d1 - d0);
            let g = zip(g, e[l], |g, e| g / (2.0 * e));
            let r = zip(g, g, |g, _| (g * g + 1.0).sqrt());
            let shift = zip(e[l], zip(g, r, |g, r| g + r.copysign(g)), |e, x| e / x);
            let mut g = zip(zip(dm, d[l], |dm, dl| dm - dl), shift, |x, s| x + s);
            let (mut s, mut c, mut p) = ([1.0; L], [1.0; L], [0.0; L]);
            // Lanes still rotating in this sweep (a zero rotation radius ends one early), as
            // word masks: they vectorise as the comparisons they come from, where arrays of
            // bool cost a conversion per use.
            let mut live: Mask<L> = mask(|t| active[t]);
            let bottom: [i64; L] = std::array::from_fn(|t| m[t] as i64);
            let mut i = top;
            while i > l {
                i -= 1;
                let part: Mask<L> = std::array::from_fn(|t| live[t] & word(bottom[t] > i as i64));
                let f = zip(s, e[i], |s, e| s * e);
                let b = zip(c, e[i], |c, e| c * e);
                // sqrt(f² + g²) rather than hypot (half the time of the scan): Gram matrices
                // of Jacobians in mm and rad stay far from the over/underflow range.
                let r = zip(f, g, |f, g| (f * f + g * g).sqrt());
                e[i + 1] = blend(part, r, e[i + 1]);
                let early: Mask<L> = std::array::from_fn(|t| part[t] & word(r[t] == 0.0));
                if early.iter().any(|&x| x != 0) {
                    d[i + 1] = blend(early, zip(d[i + 1], p, |d, p| d - p), d[i + 1]);
                    for t in (0..L).filter(|&t| early[t] != 0) {
                        e[m[t]][t] = 0.0;
                        live[t] = 0;
                    }
                }
                let go: Mask<L> = std::array::from_fn(|t| part[t] & !early[t]);
                let s1 = zip(f, r, |f, r| f / r);
                let c1 = zip(g, r, |g, r| g / r);
                let g1 = zip(d[i + 1], p, |d, p| d - p);
                let r1: [Real; L] =
                    std::array::from_fn(|t| (d[i][t] - g1[t]) * s1[t] + 2.0 * c1[t] * b[t]);
                let p1 = zip(s1, r1, |s, r| s * r);
                d[i + 1] = blend(go, zip(g1, p1, |g, p| g + p), d[i + 1]);
                g = blend(go, zip(zip(c1, r1, |c, r| c * r), b, |cr, b| cr - b), g);
                s = blend(go, s1, s);
                c = blend(go, c1, c);
                p = blend(go, p1, p);
            }
            // Without branches on the lanes (which lanes finish a sweep is unpredictable):
            // a lane not live keeps its values, and m = l for a lane not active.
            d[l] = blend(live, zip(d[l], p, |d, p| d - p), d[l]);
            e[l] = blend(live, g, e[l]);
            for t in 0..L {
                let x = &mut e[m[t]][t];
                *x = if live[t] != 0 { 0.0 } else { *x };
            }
        }
    }
}

/// Lane masks as words, all ones (true) or zero (false).
type Mask<const L: usize> = [u64; L];

/// The word of a mask lane.
#[inline(always)]
fn word(b: bool) -> u64 {
    if b {
        u64::MAX
    } else {
        0
    }
}

/// The mask of `f(t)` per lane.
#[inline(always)]
fn mask<const L: usize>(f: impl Fn(usize) -> bool) -> Mask<L> {
    std::array::from_fn(|t| word(f(t)))
}

/// Lane-wise `if mask { new } else { old }`, by the bits.
#[inline(always)]
fn blend<const L: usize>(m: Mask<L>, new: [Real; L], old: [Real; L]) -> [Real; L] {
    std::array::from_fn(|t| Real::from_bits((new[t].to_bits() & m[t]) | (old[t].to_bits() & !m[t])))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::from_seed;
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

    /// Each lane of [`symmetric_eigenvalues_lanes`], on every instruction set the processor
    /// offers, gets the bits of its matrix alone on the portable path.
    #[test]
    fn eight_matrices_at_once_are_the_matrices_one_by_one_to_the_bit() {
        let mut rng = from_seed(21);
        for trial in 0..60 {
            let n = [26, 7, 36, 2, 1, 3][trial % 6];
            let mats: Vec<DMatrix<Real>> = (0..8)
                .map(|t| {
                    let j =
                        DMatrix::from_fn(n + t, n, |_, _| rng.sample::<Real, _>(StandardNormal));
                    let mut m = j.transpose() * &j;
                    // Decoupled rows and columns: Householder steps with nothing to reduce.
                    for i in (0..n).filter(|i| (i + t + trial) % 3 == 0) {
                        for c in (0..n).filter(|&c| c != i) {
                            m[(i, c)] = 0.0;
                            m[(c, i)] = 0.0;
                        }
                    }
                    if t == 5 && trial % 2 == 0 {
                        m[(n - 1, 0)] = Real::NAN;
                    }
                    if t == 6 {
                        m *= 1e-9;
                    }
                    m
                })
                .collect();
            // The eight lanes on every path of the dispatch, each matrix alone on the portable
            // one.
            for isa in simd::available() {
                let mut a = vec![[0.0; 8]; n * n];
                for (t, m) in mats.iter().enumerate() {
                    for (x, v) in a.iter_mut().zip(m.transpose().iter()) {
                        x[t] = *v;
                    }
                }
                let (mut d, mut e) = (vec![[0.0; 8]; n], vec![[0.0; 8]; n]);
                let ok = simd::forced(isa, || {
                    symmetric_eigenvalues_lanes(&mut a, n, &mut d, &mut e)
                });
                for (t, m) in mats.iter().enumerate() {
                    let mut one: Vec<Real> = m.transpose().iter().copied().collect();
                    let (mut d1, mut e1) = (vec![0.0; n], vec![0.0; n]);
                    let ok1 = simd::forced(simd::Isa::Portable, || {
                        symmetric_eigenvalues(&mut one, n, &mut d1, &mut e1)
                    });
                    let at = format!("trial {trial}, lane {t}, {isa:?}");
                    assert_eq!(ok[t], ok1, "{at}");
                    assert_eq!(ok1, !(t == 5 && trial % 2 == 0), "{at}");
                    for (x, y) in d.iter().zip(&d1) {
                        assert_eq!(x[t].to_bits(), y.to_bits(), "{at}");
                    }
                }
            }
        }
    }

    #[test]
    fn hand_cases() {
        // [[2, 1], [1, 4]] → 3 ± √2 (the upper triangle, here NaN, is neither read nor
        // written); 1 × 1; diagonal.
        let mut a = [2.0, Real::NAN, 1.0, 4.0];
        let (mut d, mut e) = ([0.0; 2], [0.0; 2]);
        assert!(symmetric_eigenvalues(&mut a, 2, &mut d, &mut e));
        assert!(a[1].is_nan());
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
        let randn = |rng: &mut crate::numeric::rng::Rng, r: usize, c: usize| {
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
