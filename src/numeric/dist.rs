//! The distributions the intervals and tests need: the normal and Student's t (cumulative
//! distribution and quantile), by the regularised incomplete beta function (Numerical
//! Recipes, 3rd ed., § 6.4, Lentz's continued fraction) and the complementary error function
//! (W. J. Cody's rational approximations through `erfc = 1 − erf` for |x| < 0.5, and the
//! continued fraction of Numerical Recipes § 6.2 otherwise). Pure functions of their
//! arguments, so an interval is the same bits on every machine with IEEE-754 arithmetic.

// The published coefficients, as printed.
#![allow(clippy::excessive_precision)]

use crate::numeric::Real;

/// ln Γ(x) for x > 0 (Lanczos, g = 7, n = 9; relative error below 1e-15).
pub fn ln_gamma(x: Real) -> Real {
    const G: Real = 7.0;
    const C: [Real; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x)Γ(1 − x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as Real);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The smallest magnitude the modified Lentz method lets a partial denominator take.
const TINY: Real = 1e-300;

/// `v`, or [`TINY`] where `v` is smaller in magnitude.
fn away_from_zero(v: Real) -> Real {
    if v.abs() < TINY {
        TINY
    } else {
        v
    }
}

/// One step of the modified Lentz method with the partial numerator `aa`: updates `c` and `d`
/// and returns the factor by which the continued fraction's value changes.
fn lentz_step(aa: Real, c: &mut Real, d: &mut Real) -> Real {
    *d = 1.0 / away_from_zero(1.0 + aa * *d);
    *c = away_from_zero(1.0 + aa / *c);
    *d * *c
}

/// The continued fraction of the incomplete beta function (modified Lentz).
fn beta_cf(a: Real, b: Real, x: Real) -> Real {
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 / away_from_zero(1.0 - qab * x / qap);
    let mut h = d;
    for m in 1..10_000 {
        let m = m as Real;
        let m2 = 2.0 * m;
        h *= lentz_step(m * (b - m) * x / ((qam + m2) * (a + m2)), &mut c, &mut d);
        let del = lentz_step(
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
            &mut c,
            &mut d,
        );
        h *= del;
        if (del - 1.0).abs() < 1e-16 {
            break;
        }
    }
    h
}

/// The regularised incomplete beta function I_x(a, b).
pub fn beta_inc(a: Real, b: Real, x: Real) -> Real {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    let front = ln_front.exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, 1.0 - x) / b
    }
}

/// P(T > t) for Student's t with `df` degrees of freedom (`df` infinite: the normal).
pub fn t_sf(t: Real, df: Real) -> Real {
    if df.is_infinite() {
        return normal_sf(t);
    }
    let tail = 0.5 * beta_inc(0.5 * df, 0.5, df / (df + t * t));
    if t >= 0.0 {
        tail
    } else {
        1.0 - tail
    }
}

/// The two-sided p-value of a t statistic: P(|T| ≥ |t|).
pub fn t_two_sided(t: Real, df: Real) -> Real {
    if t.is_nan() {
        return Real::NAN;
    }
    (2.0 * t_sf(t.abs(), df)).min(1.0)
}

/// Most quantiles [`t_quantile`] keeps per thread.
const T_QUANTILES_KEPT: usize = 64;

thread_local! {
    /// This thread's quantiles computed last, by the bits of `p` and `df`: a run's summary
    /// asks for the same one (0.975 at n − 1 degrees of freedom) for each of its hundreds of
    /// intervals, and each costs a bisection of some hundred incomplete beta functions.
    static T_QUANTILES: std::cell::RefCell<Vec<((u64, u64), Real)>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// The quantile of Student's t: the t with P(T ≤ t) = p (bisection on [`t_sf`] to machine
/// precision, from a bracket that doubles). The last 64 are kept per thread, so a repeated
/// call gives the same bits without the bisection.
pub fn t_quantile(p: Real, df: Real) -> Real {
    let key = (p.to_bits(), df.to_bits());
    let kept = T_QUANTILES.with(|k| k.borrow().iter().find(|e| e.0 == key).map(|e| e.1));
    if let Some(t) = kept {
        return t;
    }
    let t = t_quantile_bisected(p, df);
    T_QUANTILES.with(|k| {
        let mut k = k.borrow_mut();
        if k.len() >= T_QUANTILES_KEPT {
            k.remove(0);
        }
        k.push((key, t));
    });
    t
}

/// [`t_quantile`] computed.
fn t_quantile_bisected(p: Real, df: Real) -> Real {
    if df.is_infinite() {
        return normal_quantile(p);
    }
    if p == 0.5 {
        return 0.0;
    }
    if p < 0.5 {
        return -t_quantile(1.0 - p, df);
    }
    let q = 1.0 - p;
    let mut hi = 1.0;
    while t_sf(hi, df) > q {
        hi *= 2.0;
        if hi > 1e300 {
            return Real::INFINITY;
        }
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if t_sf(mid, df) > q {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The complementary error function erfc(x).
pub fn erfc(x: Real) -> Real {
    // Numerical Recipes' erfccheb (§ 6.2.2): Chebyshev fit, relative error < 1.2e-16.
    const COF: [Real; 28] = [
        -1.3026537197817094,
        6.4196979235649026e-1,
        1.9476473204185836e-2,
        -9.561514786808631e-3,
        -9.46595344482036e-4,
        3.66839497852761e-4,
        4.2523324806907e-5,
        -2.0278578112534e-5,
        -1.624290004647e-6,
        1.303655835580e-6,
        1.5626441722e-8,
        -8.5238095915e-8,
        6.529054439e-9,
        5.059343495e-9,
        -9.91364156e-10,
        -2.27365122e-10,
        9.6467911e-11,
        2.394038e-12,
        -6.886027e-12,
        8.94487e-13,
        3.13092e-13,
        -1.12708e-13,
        3.81e-16,
        7.106e-15,
        -1.523e-15,
        -9.4e-17,
        1.21e-16,
        -2.8e-17,
    ];
    if x < 0.0 {
        return 2.0 - erfc(-x);
    }
    let t = 2.0 / (2.0 + x);
    let ty = 4.0 * t - 2.0;
    let (mut d, mut dd) = (0.0, 0.0);
    for &c in COF[1..].iter().rev() {
        let tmp = d;
        d = ty * d - dd + c;
        dd = tmp;
    }
    t * (-x * x + 0.5 * (COF[0] + ty * d) - dd).exp()
}

/// P(Z > z) for the standard normal.
pub fn normal_sf(z: Real) -> Real {
    0.5 * erfc(z / std::f64::consts::SQRT_2)
}

/// The standard normal's quantile (Acklam's rational approximation refined by one Halley
/// step on [`erfc`]: full double precision).
pub fn normal_quantile(p: Real) -> Real {
    if p <= 0.0 {
        return Real::NEG_INFINITY;
    }
    if p >= 1.0 {
        return Real::INFINITY;
    }
    const A: [Real; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.383577518672690e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [Real; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [Real; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [Real; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    let pl = 0.02425;
    let x = if p < pl {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - pl {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        let q = (-2.0 * (1.0 - p).ln()).sqrt();
        -(((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    // One Halley step.
    let e = 0.5 * erfc(-x / std::f64::consts::SQRT_2) - p;
    let u = e * (2.0 * std::f64::consts::PI).sqrt() * (x * x / 2.0).exp();
    x - u / (1.0 + x * u / 2.0)
}

/// The 95 % t interval of a mean: `mean ± t(0.975, n − 1) · sd / √n` with `sd` the sample
/// standard deviation (divisor n − 1); `None` with fewer than 2 values or a non-finite input.
pub fn t_interval(mean: Real, sd: Real, n: usize) -> Option<[Real; 2]> {
    if n < 2 || !mean.is_finite() || !sd.is_finite() {
        return None;
    }
    let h = t_quantile(0.975, (n - 1) as Real) * sd / (n as Real).sqrt();
    Some([mean - h, mean + h])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Real, b: Real, rel: Real) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    #[test]
    fn a_kept_quantile_is_the_bisections_bits_for_its_own_p_and_df() {
        // More pairs than are kept, asked in turn and then again in another order, with p on
        // both sides of ½: every answer is the bisection's for its own (p, df).
        let pairs: Vec<(Real, Real)> = (0..90)
            .map(|i| {
                (
                    0.02 + 0.96 * ((i * 37) % 90) as Real / 90.0,
                    (1 + i % 13) as Real,
                )
            })
            .collect();
        for round in 0..3 {
            for k in 0..pairs.len() {
                let (p, df) = pairs[(k * (round + 1)) % pairs.len()];
                let want = t_quantile_bisected(p, df);
                assert_eq!(t_quantile(p, df).to_bits(), want.to_bits(), "{p} {df}");
                assert_eq!(t_quantile(p, df).to_bits(), want.to_bits(), "{p} {df}");
            }
        }
    }

    #[test]
    fn quantiles_match_the_tables() {
        // scipy.stats.t.ppf(0.975, df) and norm.ppf(0.975).
        for (df, q) in [
            (1.0, 12.706204736174698),
            (4.0, 2.7764451051977934),
            (49.0, 2.0095752371292392),
            (199.0, 1.9719565442517533),
        ] {
            assert!(close(t_quantile(0.975, df), q, 1e-10), "{df}");
        }
        assert!(close(normal_quantile(0.975), 1.959963984540054, 1e-13));
        assert!(close(normal_quantile(1e-10), -6.361340902404056, 1e-10));
        // scipy.stats.t.sf(2.0, 10), norm.sf(3.0).
        assert!(close(t_sf(2.0, 10.0), 0.03669401738537018, 1e-10));
        assert!(close(normal_sf(3.0), 0.0013498980316300933, 1e-12));
        assert!(close(normal_sf(-1.0), 0.8413447460685429, 1e-14));
    }
}
