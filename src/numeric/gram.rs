//! The normal equations of the Gauss–Newton methods, `N = (PJ)ᵀ J` and `g = (PJ)ᵀ r`, from
//! the column-major Jacobian `J` and weighted Jacobian `PJ`: the kernel under every
//! identification's iterations (Li 2018 eq. 13).

use super::simd::{self, Isa};
use super::Real;

/// `N = (PJ)ᵀ J` (t × t, column-major, exactly symmetric) and `g = (PJ)ᵀ r` (length t) from
/// the column-major m × t `J` (`js`) and `PJ` (`pjs`) and the residual `r` (length m): t is
/// the length of `g`, m that of `r`.
/// Every entry is one dot product in a fixed order ([`dots`]): the same bits whatever the
/// processor and whichever of the block shapes computes it.
pub(crate) fn normal_equations(
    js: &[Real],
    pjs: &[Real],
    r: &[Real],
    n: &mut [Real],
    g: &mut [Real],
) {
    let (m, t) = (r.len(), g.len());
    assert!(js.len() == m * t && pjs.len() == m * t && n.len() == t * t);
    simd::dispatch(
        #[inline(always)]
        |isa| gram(isa, js, pjs, r, n, g),
    );
}

/// `N = (PJ)ᵀ J` (t × t, column-major, exactly symmetric: the lower triangle mirrored) and
/// `g = (PJ)ᵀ r` from the column-major m × t `J` and `PJ` (m the length of `r`, t that of
/// `g`). Two columns of `PJ` at a time against four (or two) of `J`, so that every loaded
/// value serves several products and eight independent sums hide the latency of the
/// additions; each entry's sum runs as in [`dots`], whatever the block and the instruction
/// set.
#[inline(always)]
fn gram(isa: Isa, js: &[Real], pjs: &[Real], r: &[Real], n: &mut [Real], g: &mut [Real]) {
    let (m, t) = (r.len(), g.len());
    let mut a = 0;
    while a < t {
        if a + 1 < t {
            let ca = [col(pjs, m, a), col(pjs, m, a + 1)];
            let mut b = 0;
            // Four columns of J while all lie left of column a + 2, then two: when a is two
            // more than a multiple of four, the last block of four ends with the diagonal
            // pair (its entry (a, a + 1) is computed both ways, and the one put last,
            // (PJ)_{a+1}·J_a, is the one the 2 × 2 block gives), so that eight sums run
            // side by side instead of four.
            while b + 4 <= a + 2 {
                let cb = [
                    col(js, m, b),
                    col(js, m, b + 1),
                    col(js, m, b + 2),
                    col(js, m, b + 3),
                ];
                put(n, t, a, b, dots::<2, 4>(isa, ca, cb));
                b += 4;
            }
            while b <= a {
                put(
                    n,
                    t,
                    a,
                    b,
                    dots::<2, 2>(isa, ca, [col(js, m, b), col(js, m, b + 1)]),
                );
                b += 2;
            }
        } else {
            for b in 0..=a {
                put(
                    n,
                    t,
                    a,
                    b,
                    dots::<1, 1>(isa, [col(pjs, m, a)], [col(js, m, b)]),
                );
            }
        }
        a += 2;
    }
    // g four entries at a time: four independent sums instead of one latency-bound chain.
    let mut k = 0;
    while k + 4 <= t {
        let cols = [
            col(pjs, m, k),
            col(pjs, m, k + 1),
            col(pjs, m, k + 2),
            col(pjs, m, k + 3),
        ];
        for (p, v) in dots::<4, 1>(isa, cols, [r]).iter().enumerate() {
            g[k + p] = v[0];
        }
        k += 4;
    }
    for (k, gk) in g.iter_mut().enumerate().take(t).skip(k) {
        *gk = dots::<1, 1>(isa, [col(pjs, m, k)], [r])[0][0];
    }
}

/// Writes the block `v` of entries `(a + p, b + q)` of the t × t `n` and their mirror images.
#[inline(always)]
fn put<const P: usize, const Q: usize>(
    n: &mut [Real],
    t: usize,
    a: usize,
    b: usize,
    v: [[Real; Q]; P],
) {
    for (p, row) in v.iter().enumerate() {
        for (q, &x) in row.iter().enumerate() {
            n[(b + q) * t + a + p] = x;
            n[(a + p) * t + b + q] = x;
        }
    }
}

/// Column `k` of a column-major matrix with `m` rows.
#[inline(always)]
fn col(s: &[Real], m: usize, k: usize) -> &[Real] {
    &s[k * m..(k + 1) * m]
}

/// The `P × Q` dot products `x_p · y_q` of slices of one length, each in four interleaved
/// partial sums (`s_k ← fma(x_i, y_i, s_k)` over the indices `i ≡ k mod 4`, one rounding per
/// term) combined as `(s0 + s2) + (s1 + s3)`: a fixed order, so every product is the same
/// whichever block computes it, whichever kernel, and on every machine (the fused
/// multiply-add is the correctly rounded IEEE operation everywhere: an instruction where the
/// processor has one, a library call where not). `isa` picks the portable or the AVX2 code.
#[inline(always)]
fn dots<const P: usize, const Q: usize>(
    isa: Isa,
    x: [&[Real]; P],
    y: [&[Real]; Q],
) -> [[Real; Q]; P] {
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the token proves the processor has AVX2 and FMA.
        Isa::Avx2Fma(_) => unsafe { dots_avx2(x, y) },
        Isa::Portable => dots_portable(x, y),
    }
}

/// [`dots`] in plain Rust (the compiler vectorises the four lanes as the target allows).
#[inline(always)]
fn dots_portable<const P: usize, const Q: usize>(
    x: [&[Real]; P],
    y: [&[Real]; Q],
) -> [[Real; Q]; P] {
    let n = x[0].len();
    let mut acc = [[[0.0; 4]; Q]; P];
    let whole = n - n % 4;
    let mut i = 0;
    while i < whole {
        let xs: [[Real; 4]; P] = std::array::from_fn(|p| x[p][i..i + 4].try_into().unwrap());
        let ys: [[Real; 4]; Q] = std::array::from_fn(|q| y[q][i..i + 4].try_into().unwrap());
        for p in 0..P {
            for q in 0..Q {
                for k in 0..4 {
                    acc[p][q][k] = xs[p][k].mul_add(ys[q][k], acc[p][q][k]);
                }
            }
        }
        i += 4;
    }
    combine(x, y, whole, acc)
}

/// Adds the last `n mod 4` products to the first partial sums and combines each entry's four.
#[inline(always)]
fn combine<const P: usize, const Q: usize>(
    x: [&[Real]; P],
    y: [&[Real]; Q],
    whole: usize,
    mut acc: [[[Real; 4]; Q]; P],
) -> [[Real; Q]; P] {
    for (k, i) in (whole..x[0].len()).enumerate() {
        for p in 0..P {
            for q in 0..Q {
                acc[p][q][k] = x[p][i].mul_add(y[q][i], acc[p][q][k]);
            }
        }
    }
    acc.map(|row| row.map(|s| (s[0] + s[2]) + (s[1] + s[3])))
}

/// [`dots`] in AVX2 vectors with fused multiply-adds, one vector per partial-sum quadruple:
/// the same bits as [`dots_portable`].
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn dots_avx2<const P: usize, const Q: usize>(
    x: [&[Real]; P],
    y: [&[Real]; Q],
) -> [[Real; Q]; P] {
    use std::arch::x86_64::{__m256d, _mm256_fmadd_pd, _mm256_loadu_pd};
    use std::arch::x86_64::{_mm256_setzero_pd, _mm256_storeu_pd};
    let n = x[0].len();
    assert!(x.iter().all(|v| v.len() == n) && y.iter().all(|v| v.len() == n));
    let whole = n - n % 4;
    let mut acc: [[__m256d; Q]; P] = [[_mm256_setzero_pd(); Q]; P];
    let mut i = 0;
    while i < whole {
        let mut xs = [_mm256_setzero_pd(); P];
        for p in 0..P {
            // SAFETY: i + 4 ≤ n, the length of every slice (asserted above).
            xs[p] = unsafe { _mm256_loadu_pd(x[p].as_ptr().add(i)) };
        }
        for q in 0..Q {
            // SAFETY: as above.
            let yq = unsafe { _mm256_loadu_pd(y[q].as_ptr().add(i)) };
            for p in 0..P {
                acc[p][q] = _mm256_fmadd_pd(xs[p], yq, acc[p][q]);
            }
        }
        i += 4;
    }
    let mut sums = [[[0.0; 4]; Q]; P];
    for p in 0..P {
        for q in 0..Q {
            // SAFETY: `sums[p][q]` holds four values.
            unsafe { _mm256_storeu_pd(sums[p][q].as_mut_ptr(), acc[p][q]) };
        }
    }
    combine(x, y, whole, sums)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// The normal equations of every kernel and block shape are one set of bits, N and g each
    /// entry that of its plain dot product: sizes with odd column counts and row counts that
    /// are not a multiple of four.
    #[test]
    fn the_gram_kernels_agree_to_the_bit() {
        let mut g = crate::numeric::rng::from_seed(3);
        for (m, t) in [(150, 24), (57, 7), (6, 1), (13, 20), (300, 33)] {
            let j = DMatrix::from_fn(m, t, |_, _| rand::Rng::random_range(&mut g, -1.0..1.0));
            let pj = DMatrix::from_fn(m, t, |i, k| j[(i, k)] * (1.0 + (i % 3) as Real));
            let r: Vec<Real> = (0..m).map(|i| (i as Real).sin()).collect();
            let run = |kernel: &dyn Fn(&mut [Real], &mut [Real])| {
                let (mut n, mut gv) = (vec![Real::NAN; t * t], vec![Real::NAN; t]);
                kernel(&mut n, &mut gv);
                (n, gv)
            };
            let (js, pjs) = (j.as_slice(), pj.as_slice());
            let portable = run(&|n, gv| gram(Isa::Portable, js, pjs, &r, n, gv));
            // Against the plain definition: each entry one dot product in the fixed order.
            for a in 0..t {
                for b in 0..=a {
                    let x = dots_portable::<1, 1>([col(pjs, m, a)], [col(js, m, b)])[0][0];
                    assert_eq!(portable.0[b * t + a].to_bits(), x.to_bits(), "({a}, {b})");
                    assert_eq!(portable.0[a * t + b].to_bits(), x.to_bits(), "({b}, {a})");
                }
                let x = dots_portable::<1, 1>([col(pjs, m, a)], [&r])[0][0];
                assert_eq!(portable.1[a].to_bits(), x.to_bits(), "g[{a}]");
            }
            // Every path of the dispatch, through the entry point, gives those bits.
            let bits = |v: &[Real]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            for isa in simd::available() {
                let path = run(&|n, gv| simd::forced(isa, || normal_equations(js, pjs, &r, n, gv)));
                assert_eq!(bits(&portable.0), bits(&path.0), "N, {m} × {t}, {isa:?}");
                assert_eq!(bits(&portable.1), bits(&path.1), "g, {m} × {t}, {isa:?}");
            }
        }
    }
}
