//! Sine and cosine of many values at once: [`sin_cos_slice`], sixteen values at a time in
//! AVX2 vectors where the processor has them, with a portable twin of the same bits.

use super::simd::{self, Isa};
use super::Real;

/// Beyond this |x| (rad) [`sin_cos_slice`] hands a value to the library's `sin_cos`: its
/// two-constant reduction by π/2 keeps the reduced argument to about an ulp up to here.
const SIN_COS_LIMIT: Real = 1e5;

/// π/2 − `FRAC_PI_2`, rounded.
const PIO2_LO: Real = 6.123_233_995_736_766e-17;

/// Adding and subtracting 1.5·2⁵² rounds |y| < 2⁵¹ to the nearest integer (ties to even),
/// which is left in the low bits of the sum.
const ROUND: Real = 6_755_399_441_055_744.0;

/// (−1)ᵏ/(2k+1)! for k = 1…8.
const SIN: [Real; 8] = [
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
    -1.0 / 1_307_674_368_000.0,
    1.0 / 355_687_428_096_000.0,
];

/// (−1)ᵏ/(2k)! for k = 1…9.
const COS: [Real; 9] = [
    -1.0 / 2.0,
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
    1.0 / 479_001_600.0,
    -1.0 / 87_178_291_200.0,
    1.0 / 20_922_789_888_000.0,
    -1.0 / 6_402_373_705_728_000.0,
];

/// `(sin x, cos x)` of every value of `x`, into `out`: `x = q·π/2 + r` with `q` the nearest
/// integer to `x·2/π` and `r` from two fused multiply-adds (π/2 as a double and its
/// remainder, so `r` carries about an ulp for |x| ≤ 1e5), then the Taylor series of sin and
/// cos on |r| ≤ π/4 to the terms in r¹⁷ and r¹⁸ (the first terms left out are below 1e-19) by
/// Horner's rule in fused multiply-adds, and the quadrant `q mod 4` swapping and signing them.
/// Within an ulp of the correctly rounded values (tested against the library's), and the same
/// bits on every machine and for every length and position in `x`: sixteen values at a time
/// as four AVX2 vectors side by side (their chains of dependent multiply-adds overlap) where
/// the processor has AVX2 and FMA, otherwise the same operations one value at a time (the
/// fused multiply-add is the correctly rounded IEEE operation everywhere; the choice is the
/// numeric kernels' one run-time dispatch). A value with
/// |x| > 1e5 or not finite gets the library's `sin_cos`.
///
/// # Panics
/// If `x` and `out` differ in length.
pub fn sin_cos_slice(x: &[Real], out: &mut [(Real, Real)]) {
    assert_eq!(x.len(), out.len(), "one (sin, cos) per value");
    simd::dispatch(
        #[inline(always)]
        |isa| match isa {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2Fma(_) => in_sixteens(
                x,
                out,
                #[inline(always)]
                // SAFETY: the token proves the processor has AVX2 and FMA.
                |v| unsafe { sin_cos_avx2(v) },
            ),
            Isa::Portable => in_sixteens(x, out, sin_cos_portable),
        },
    );
    for (&x, o) in x.iter().zip(out.iter_mut()) {
        if !x.is_finite() || x.abs() > SIN_COS_LIMIT {
            *o = x.sin_cos();
        }
    }
}

/// Sines and cosines of four groups of four values, one per kernel call.
type Sixteen = ([[Real; 4]; 4], [[Real; 4]; 4]);

/// Runs `kernel` on `x` sixteen values at a time (the last group padded with zeros) and
/// writes its (sin, cos) pairs to `out`.
#[inline(always)]
fn in_sixteens(x: &[Real], out: &mut [(Real, Real)], kernel: impl Fn([[Real; 4]; 4]) -> Sixteen) {
    for (xs, os) in x.chunks(16).zip(out.chunks_mut(16)) {
        let mut v = [[0.0; 4]; 4];
        for (i, &xi) in xs.iter().enumerate() {
            v[i / 4][i % 4] = xi;
        }
        let (sin, cos) = kernel(v);
        for (i, o) in os.iter_mut().enumerate() {
            *o = (sin[i / 4][i % 4], cos[i / 4][i % 4]);
        }
    }
}

/// [`sin_cos_slice`]'s arithmetic one value at a time (before the library's values for large or
/// non-finite arguments).
fn sin_cos_portable(x: [[Real; 4]; 4]) -> Sixteen {
    let mut sin = [[0.0; 4]; 4];
    let mut cos = [[0.0; 4]; 4];
    for v in 0..4 {
        for l in 0..4 {
            (sin[v][l], cos[v][l]) = reduced_series(x[v][l]);
        }
    }
    (sin, cos)
}

/// `(sin x, cos x)` of one value, the same bits as [`sin_cos_slice`] gives it (the portable
/// arithmetic, and the library's values beyond |x| = 1e5 or for non-finite `x`): for a walk
/// that needs one angle at a time. It runs on the numeric kernels' dispatch, so its
/// multiply-adds are instructions where the processor has FMA, not calls into the library's
/// software `fma`.
#[inline]
pub fn sin_cos(x: Real) -> (Real, Real) {
    if !x.is_finite() || x.abs() > SIN_COS_LIMIT {
        return x.sin_cos();
    }
    simd::dispatch(
        #[inline(always)]
        |_| reduced_series(x),
    )
}

/// The reduction by π/2, the two series and the quadrant of [`sin_cos_slice`] for one value.
#[inline(always)]
fn reduced_series(x: Real) -> (Real, Real) {
    use std::f64::consts::{FRAC_2_PI, FRAC_PI_2};
    let m = x.mul_add(FRAC_2_PI, ROUND);
    let q = m - ROUND;
    let r = (-q).mul_add(PIO2_LO, (-q).mul_add(FRAC_PI_2, x));
    let z = r * r;
    let mut ps = SIN[7];
    for &c in SIN[..7].iter().rev() {
        ps = ps.mul_add(z, c);
    }
    let mut pc = COS[8];
    for &c in COS[..8].iter().rev() {
        pc = pc.mul_add(z, c);
    }
    // |sin r| < |r| here, so the sign is r's; copying it keeps sin(−0) = −0.
    let s = (r * z).mul_add(ps, r).copysign(r);
    let c = z.mul_add(pc, 1.0);
    // Odd quadrants swap sin and cos, quadrants 2 and 3 negate sin, 1 and 2 negate cos.
    let quadrant = m.to_bits() & 3;
    let (s, c) = if quadrant & 1 == 0 { (s, c) } else { (c, s) };
    (
        if quadrant & 2 == 0 { s } else { -s },
        if (quadrant + 1) & 2 == 0 { c } else { -c },
    )
}

/// [`sin_cos_portable`] in AVX2 vectors, one per group of four, each step applied to every
/// vector before the next step: the same operations in the same order for every value.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
unsafe fn sin_cos_avx2(x: [[Real; 4]; 4]) -> Sixteen {
    use std::arch::x86_64::*;
    use std::f64::consts::{FRAC_2_PI, FRAC_PI_2};
    const V: usize = 4;
    let sign = _mm256_set1_pd(-0.0);
    let (mut m, mut r, mut z) = ([sign; V], [sign; V], [sign; V]);
    for v in 0..V {
        // SAFETY: `x[v]` holds four values.
        let xv = unsafe { _mm256_loadu_pd(x[v].as_ptr()) };
        m[v] = _mm256_fmadd_pd(xv, _mm256_set1_pd(FRAC_2_PI), _mm256_set1_pd(ROUND));
        let nq = _mm256_xor_pd(_mm256_sub_pd(m[v], _mm256_set1_pd(ROUND)), sign);
        let rv = _mm256_fmadd_pd(nq, _mm256_set1_pd(FRAC_PI_2), xv);
        r[v] = _mm256_fmadd_pd(nq, _mm256_set1_pd(PIO2_LO), rv);
        z[v] = _mm256_mul_pd(r[v], r[v]);
    }
    let mut ps = [_mm256_set1_pd(SIN[7]); V];
    for &c in SIN[..7].iter().rev() {
        for v in 0..V {
            ps[v] = _mm256_fmadd_pd(ps[v], z[v], _mm256_set1_pd(c));
        }
    }
    let mut pc = [_mm256_set1_pd(COS[8]); V];
    for &c in COS[..8].iter().rev() {
        for v in 0..V {
            pc[v] = _mm256_fmadd_pd(pc[v], z[v], _mm256_set1_pd(c));
        }
    }
    let mut sin = [[0.0; 4]; V];
    let mut cos = [[0.0; 4]; V];
    for v in 0..V {
        let s = _mm256_fmadd_pd(_mm256_mul_pd(r[v], z[v]), ps[v], r[v]);
        let s = _mm256_or_pd(_mm256_andnot_pd(sign, s), _mm256_and_pd(sign, r[v]));
        let c = _mm256_fmadd_pd(z[v], pc[v], _mm256_set1_pd(1.0));
        let bits = _mm256_castpd_si256(m[v]);
        let one = _mm256_set1_epi64x(1);
        let two = _mm256_set1_epi64x(2);
        let swap = _mm256_castsi256_pd(_mm256_sub_epi64(
            _mm256_setzero_si256(),
            _mm256_and_si256(bits, one),
        ));
        let (s, c) = (_mm256_blendv_pd(s, c, swap), _mm256_blendv_pd(c, s, swap));
        let flip_s = _mm256_slli_epi64::<62>(_mm256_and_si256(bits, two));
        let flip_c = _mm256_slli_epi64::<62>(_mm256_and_si256(_mm256_add_epi64(bits, one), two));
        // SAFETY: `sin[v]` and `cos[v]` hold four values each.
        unsafe {
            _mm256_storeu_pd(
                sin[v].as_mut_ptr(),
                _mm256_xor_pd(s, _mm256_castsi256_pd(flip_s)),
            );
            _mm256_storeu_pd(
                cos[v].as_mut_ptr(),
                _mm256_xor_pd(c, _mm256_castsi256_pd(flip_c)),
            );
        }
    }
    (sin, cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`sin_cos_slice`] against the library's `sin_cos` (correctly rounded nearly always):
    /// within two ulps over joint-sized and larger arguments, near the multiples of π/4 where
    /// the quadrant and the series change, at tiny and zero arguments, and the library's values
    /// beyond the reduction's range or for non-finite input.
    #[test]
    fn sin_cos_slice_agrees_with_the_library() {
        let ulps = |a: Real, b: Real| -> Real {
            if a == b {
                return 0.0;
            }
            let ulp = Real::EPSILON * b.abs().max(Real::MIN_POSITIVE);
            ((a - b) / ulp).abs()
        };
        let mut xs: Vec<Real> = Vec::new();
        let mut seed = 5u64;
        for k in 0..20_000 {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (seed >> 11) as Real / (1u64 << 53) as Real - 0.5;
            xs.push(u * [20.0, 200.0, 2e5, 1e-3][k % 4]);
        }
        for k in -200..=200 {
            let a = k as Real * std::f64::consts::FRAC_PI_4;
            xs.extend([a, a.next_up(), a.next_down(), a + 1e-9, a - 1e-9]);
        }
        xs.extend([0.0, -0.0, 1e-300, -1e-300, 1e-8, 99_999.9, 100_000.1, 1e300]);
        xs.extend([Real::NAN, Real::INFINITY, Real::NEG_INFINITY]);
        let mut out = vec![(0.0, 0.0); xs.len()];
        sin_cos_slice(&xs, &mut out);
        // Every path the processor offers gives the portable arithmetic, to the bit.
        let mut portable = vec![(0.0, 0.0); xs.len()];
        in_sixteens(&xs, &mut portable, sin_cos_portable);
        for isa in simd::available() {
            let mut path = vec![(0.0, 0.0); xs.len()];
            simd::forced(isa, || sin_cos_slice(&xs, &mut path));
            for (k, (a, b)) in path.iter().zip(&out).enumerate() {
                assert_eq!(a.0.to_bits(), b.0.to_bits(), "{isa:?}: sin {:e}", xs[k]);
                assert_eq!(a.1.to_bits(), b.1.to_bits(), "{isa:?}: cos {:e}", xs[k]);
            }
        }
        let mut worst: Real = 0.0;
        for (k, &x) in xs.iter().enumerate() {
            let (s, c) = out[k];
            if x.is_finite() && x.abs() <= SIN_COS_LIMIT {
                assert_eq!(s.to_bits(), portable[k].0.to_bits(), "sin {x:e}");
                assert_eq!(c.to_bits(), portable[k].1.to_bits(), "cos {x:e}");
            }
            let (ws, wc) = x.sin_cos();
            if !x.is_finite() {
                assert!(s.is_nan() && c.is_nan(), "{x}");
                continue;
            }
            // Near a zero of sin or cos the value is the reduced argument's, whose absolute
            // error is an ulp of π/2 times the quadrant count's rounding.
            let e = ulps(s, ws).min((s - ws).abs() / 1e-16 * 0.5);
            let f = ulps(c, wc).min((c - wc).abs() / 1e-16 * 0.5);
            worst = worst.max(e).max(f);
            assert!(e <= 2.0 && f <= 2.0, "x {x:e}: sin {e} ulp, cos {f} ulp");
        }
        assert!(worst > 0.0, "the check compares something");
        let mut zero = [(0.0, 0.0)];
        sin_cos_slice(&[-0.0], &mut zero);
        assert_eq!(zero[0].0.to_bits(), (-0.0 as Real).to_bits());
        // One value at a time, the same bits.
        for (k, &x) in xs.iter().enumerate() {
            let (s, c) = sin_cos(x);
            assert_eq!(s.to_bits(), out[k].0.to_bits(), "sin {x:e}");
            assert_eq!(c.to_bits(), out[k].1.to_bits(), "cos {x:e}");
        }
        // The same bits whatever a value's neighbours and place in a group of sixteen.
        for start in [0, 1, 7, 15, 16, 33] {
            for len in [1, 5, 16, 17, 35] {
                let mut part = vec![(0.0, 0.0); len];
                sin_cos_slice(&xs[start..start + len], &mut part);
                for (k, &(s, c)) in part.iter().enumerate() {
                    assert_eq!(s.to_bits(), out[start + k].0.to_bits());
                    assert_eq!(c.to_bits(), out[start + k].1.to_bits());
                }
            }
        }
    }
}
