//! Scalar and small fixed-size types, rigid frames and elementary rotations.
//!
//! Lengths are in millimetres and angles in radians everywhere inside the library.

pub mod linalg;
pub mod rng;
pub mod symeig;

use nalgebra::{Matrix3, Vector3};

/// The scalar type.
pub type Real = f64;
/// A 3-vector (mm for points and translations, rad for small rotations).
pub type Vec3 = Vector3<Real>;
/// A 3×3 matrix.
pub type Mat3 = Matrix3<Real>;

/// A rigid transform: `x ↦ rot · x + pos`. Equivalent to a 4×4 homogeneous matrix
/// `[rot pos; 0 1]`, kept as a rotation matrix and a translation for speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Rotation matrix (columns are the frame's axes in the parent frame).
    pub rot: Mat3,
    /// Origin of the frame in the parent frame, mm.
    pub pos: Vec3,
}

impl Default for Frame {
    fn default() -> Self {
        Self::identity()
    }
}

impl Frame {
    /// The identity transform.
    pub fn identity() -> Self {
        Frame {
            rot: Mat3::identity(),
            pos: Vec3::zeros(),
        }
    }

    /// A frame from a translation (mm) and fixed X-Y-Z roll-pitch-yaw angles (rad):
    /// `Trans(xyz) · Rz(rz) · Ry(ry) · Rx(rx)`, the form used by robot files and scenarios.
    pub fn from_xyz_rpy(xyz: [Real; 3], rpy: [Real; 3]) -> Self {
        Frame {
            rot: rpy_matrix(rpy),
            pos: Vec3::new(xyz[0], xyz[1], xyz[2]),
        }
    }

    /// Composition `self · other`.
    #[inline]
    pub fn compose(&self, other: &Frame) -> Frame {
        Frame {
            rot: self.rot * other.rot,
            pos: self.rot * other.pos + self.pos,
        }
    }

    /// The inverse transform.
    #[inline]
    pub fn inverse(&self) -> Frame {
        let rt = self.rot.transpose();
        Frame {
            rot: rt,
            pos: -(rt * self.pos),
        }
    }

    /// Maps a point of this frame into the parent frame.
    #[inline]
    pub fn apply(&self, p: &Vec3) -> Vec3 {
        self.rot * p + self.pos
    }

    /// Maps a point of the parent frame into this frame.
    #[inline]
    pub fn apply_inverse(&self, p: &Vec3) -> Vec3 {
        self.rot.tr_mul(&(p - self.pos))
    }

    /// Translation (mm) and fixed X-Y-Z angles (rad) of this frame, the inverse of
    /// [`Frame::from_xyz_rpy`].
    pub fn to_xyz_rpy(&self) -> ([Real; 3], [Real; 3]) {
        ([self.pos.x, self.pos.y, self.pos.z], matrix_rpy(&self.rot))
    }
}

/// Rotation about x by `t` rad.
#[inline]
pub fn rot_x(t: Real) -> Mat3 {
    let (s, c) = t.sin_cos();
    Mat3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

/// Rotation about y by `t` rad.
#[inline]
pub fn rot_y(t: Real) -> Mat3 {
    let (s, c) = t.sin_cos();
    Mat3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// Rotation about z by `t` rad.
#[inline]
pub fn rot_z(t: Real) -> Mat3 {
    let (s, c) = t.sin_cos();
    Mat3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// Fixed X-Y-Z roll-pitch-yaw: `Rz(rpy[2]) · Ry(rpy[1]) · Rx(rpy[0])`.
pub fn rpy_matrix(rpy: [Real; 3]) -> Mat3 {
    rot_z(rpy[2]) * rot_y(rpy[1]) * rot_x(rpy[0])
}

/// The fixed X-Y-Z angles of a rotation matrix (pitch in [−π/2, π/2]).
pub fn matrix_rpy(r: &Mat3) -> [Real; 3] {
    let pitch = (-r[(2, 0)]).clamp(-1.0, 1.0).asin();
    if r[(2, 0)].abs() < 1.0 - 1e-12 {
        [
            r[(2, 1)].atan2(r[(2, 2)]),
            pitch,
            r[(1, 0)].atan2(r[(0, 0)]),
        ]
    } else {
        // Gimbal lock: put the whole rotation about z into yaw.
        [0.0, pitch, (-r[(0, 1)]).atan2(r[(1, 1)])]
    }
}

/// The rotation vector (axis · angle, rad) of a rotation matrix: the matrix logarithm.
///
/// The angle comes from `atan2(|v|, (tr R − 1)/2)` with `v` the axial vector of the skew
/// part, which stays finite and accurate near the identity (where `acos` of a rounded trace
/// slightly above 3 would give NaN); near π the quaternion route of nalgebra is used.
pub fn rotation_vector(r: &Mat3) -> Vec3 {
    let v = 0.5
        * Vec3::new(
            r[(2, 1)] - r[(1, 2)],
            r[(0, 2)] - r[(2, 0)],
            r[(1, 0)] - r[(0, 1)],
        );
    let s = v.norm();
    let c = 0.5 * (r.trace() - 1.0);
    if c > -0.9 {
        let angle = s.atan2(c);
        if s < 1e-300 {
            return Vec3::zeros();
        }
        return v * (angle / s);
    }
    nalgebra::Rotation3::from_matrix_unchecked(*r).scaled_axis()
}

/// The inverse right Jacobian of SO(3) at the rotation vector `phi`:
/// `log(exp([φ]×) exp([δ]×)) = φ + J_r⁻¹(φ) δ + O(δ²)`, with
/// `J_r⁻¹(φ) = I + ½[φ]× + (1/θ² − (1 + cos θ)/(2θ sin θ))[φ]×²`, θ = |φ|
/// (series `1/12 + θ²/720` near 0).
pub fn so3_right_jacobian_inverse(phi: &Vec3) -> Mat3 {
    let th = phi.norm();
    let c = if th < 1e-4 {
        1.0 / 12.0 + th * th / 720.0
    } else {
        1.0 / (th * th) - (1.0 + th.cos()) / (2.0 * th * th.sin())
    };
    let k = skew(phi);
    Mat3::identity() + k * 0.5 + k * k * c
}

/// The skew-symmetric matrix `[v]×` with `[v]× w = v × w`.
#[inline]
pub fn skew(v: &Vec3) -> Mat3 {
    Mat3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// The unit quaternion `[qw, qx, qy, qz]` of a rotation matrix, with qw ≥ 0.
pub fn quaternion(r: &Mat3) -> [Real; 4] {
    let q = nalgebra::UnitQuaternion::from_rotation_matrix(
        &nalgebra::Rotation3::from_matrix_unchecked(*r),
    );
    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
    [s * q.w, s * q.i, s * q.j, s * q.k]
}

/// The rotation matrix of a unit quaternion `[qw, qx, qy, qz]` (normalised first).
pub fn quaternion_matrix(q: &[Real; 4]) -> Mat3 {
    nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]))
        .to_rotation_matrix()
        .into_inner()
}

/// Median of `v` (reorders it); NaN when empty.
pub fn median(v: &mut [Real]) -> Real {
    if v.is_empty() {
        return Real::NAN;
    }
    v.sort_unstable_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

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
/// fused multiply-add is the correctly rounded IEEE operation everywhere). A value with
/// |x| > 1e5 or not finite gets the library's `sin_cos`.
///
/// # Panics
/// If `x` and `out` differ in length.
pub fn sin_cos_slice(x: &[Real], out: &mut [(Real, Real)]) {
    assert_eq!(x.len(), out.len(), "one (sin, cos) per value");
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the processor has AVX2 and FMA (checked just above).
        unsafe { sin_cos_slice_avx2(x, out) };
    } else {
        in_sixteens(x, out, sin_cos_portable);
    }
    #[cfg(not(target_arch = "x86_64"))]
    in_sixteens(x, out, sin_cos_portable);
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

/// [`in_sixteens`] of [`sin_cos_avx2`], the whole loop compiled with AVX2 and FMA.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn sin_cos_slice_avx2(x: &[Real], out: &mut [(Real, Real)]) {
    in_sixteens(
        x,
        out,
        #[inline(always)]
        // SAFETY: this function runs only where the processor has AVX2 and FMA.
        |v| unsafe { sin_cos_avx2(v) },
    );
}

/// [`sin_cos_slice`]'s arithmetic one value at a time (before the library's values for large or
/// non-finite arguments).
fn sin_cos_portable(x: [[Real; 4]; 4]) -> Sixteen {
    use std::f64::consts::{FRAC_2_PI, FRAC_PI_2};
    let mut sin = [[0.0; 4]; 4];
    let mut cos = [[0.0; 4]; 4];
    for v in 0..4 {
        for l in 0..4 {
            let x = x[v][l];
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
            // Odd quadrants swap sin and cos, quadrants 2 and 3 negate sin, 1 and 2 negate
            // cos.
            let quadrant = m.to_bits() & 3;
            let (s, c) = if quadrant & 1 == 0 { (s, c) } else { (c, s) };
            sin[v][l] = if quadrant & 2 == 0 { s } else { -s };
            cos[v][l] = if (quadrant + 1) & 2 == 0 { c } else { -c };
        }
    }
    (sin, cos)
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

/// Whether the processor has AVX2 and FMA, the instructions of every run-time-selected
/// kernel that uses fused multiply-adds ([`with_avx2_fma`], [`sin_cos_slice`], the identification's
/// Gram kernel).
#[cfg(target_arch = "x86_64")]
pub(crate) fn has_avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// `f()`, compiled for AVX2 and FMA when the processor has both (checked at run time): `f`
/// and what it calls with `#[inline(always)]` are inlined into a function built with those
/// target features, so that loops over small arrays of lanes become four-wide vector
/// instructions and `mul_add` one instruction. The results are the same bits either way: Rust
/// never fuses a multiplication and an addition on its own, and `mul_add` is the correctly
/// rounded fused operation on every machine (a library call where there is no instruction).
#[inline(always)]
pub fn with_avx2_fma<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        #[target_feature(enable = "avx2,fma")]
        unsafe fn run<R>(f: impl FnOnce() -> R) -> R {
            f()
        }
        // SAFETY: the processor has AVX2 and FMA (checked just above).
        return unsafe { run(f) };
    }
    f()
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
        // The portable arithmetic, to the bit.
        let mut portable = vec![(0.0, 0.0); xs.len()];
        in_sixteens(&xs, &mut portable, sin_cos_portable);
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

    #[test]
    fn rotation_vector_near_identity_and_pi() {
        for w in [
            Vec3::new(1e-12, -2e-12, 3e-13),
            Vec3::new(0.3, -0.2, 0.5),
            Vec3::new(0.0, 3.1, 0.0),
            Vec3::new(1e-9, 0.0, 0.0),
        ] {
            let r = nalgebra::Rotation3::from_scaled_axis(w).into_inner();
            let back = rotation_vector(&r);
            assert!(
                (back - w).norm() < 1e-9 * (1.0 + w.norm()),
                "{w:?} -> {back:?}"
            );
        }
        // A rounded identity with trace just above 3 gives zero, not NaN.
        let mut r = Mat3::identity();
        r[(0, 0)] = 1.0 + 1e-16;
        assert!(rotation_vector(&r).iter().all(|x| x.is_finite()));
    }
    use approx::assert_relative_eq;

    #[test]
    fn rpy_round_trip() {
        let rpy = [0.3, -0.7, 2.1];
        let back = matrix_rpy(&rpy_matrix(rpy));
        for i in 0..3 {
            assert_relative_eq!(rpy[i], back[i], epsilon = 1e-12);
        }
    }

    #[test]
    fn frame_inverse_composes_to_identity() {
        let f = Frame::from_xyz_rpy([10.0, -20.0, 30.0], [0.1, 0.2, 0.3]);
        let i = f.compose(&f.inverse());
        assert_relative_eq!(i.rot, Mat3::identity(), epsilon = 1e-12);
        assert_relative_eq!(i.pos, Vec3::zeros(), epsilon = 1e-12);
        let p = Vec3::new(1.0, 2.0, 3.0);
        assert_relative_eq!(f.apply_inverse(&f.apply(&p)), p, epsilon = 1e-12);
    }
}
