//! Scalar and small fixed-size types, rigid frames and elementary rotations.
//!
//! Lengths are in millimetres and angles in radians everywhere inside the library.

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

/// Beyond this |x| (rad) [`sin_cos4`] hands a lane to the library's `sin_cos`: its
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

/// `(sin x, cos x)` of four values at once: `x = q·π/2 + r` with `q` the nearest integer to
/// `x·2/π` and `r` from two fused multiply-adds (π/2 as a double and its remainder, so `r`
/// carries about an ulp for |x| ≤ 1e5), then the Taylor series of sin and cos on |r| ≤ π/4 to
/// the terms in r¹⁷ and r¹⁸ (the first terms left out are below 1e-19) by Horner's rule in
/// fused multiply-adds, and the quadrant `q mod 4` swapping and signing them. Within an ulp
/// of the correctly rounded values (tested against the library's), and the same bits on every
/// machine: AVX2 and FMA instructions where the processor has them, otherwise the same
/// operations one value at a time (the fused multiply-add is the correctly rounded IEEE
/// operation everywhere). A value with |x| > 1e5 or not finite gets the library's `sin_cos`.
pub fn sin_cos4(x: [Real; 4]) -> ([Real; 4], [Real; 4]) {
    #[cfg(target_arch = "x86_64")]
    let (mut sin, mut cos) = if has_avx2_fma() {
        // SAFETY: the processor has AVX2 and FMA (checked just above).
        unsafe { sin_cos4_avx2(x) }
    } else {
        sin_cos4_portable(x)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let (mut sin, mut cos) = sin_cos4_portable(x);
    for l in 0..4 {
        if !x[l].is_finite() || x[l].abs() > SIN_COS_LIMIT {
            (sin[l], cos[l]) = x[l].sin_cos();
        }
    }
    (sin, cos)
}

/// [`sin_cos4`]'s arithmetic one value at a time (before the library's values for large or
/// non-finite arguments).
fn sin_cos4_portable(x: [Real; 4]) -> ([Real; 4], [Real; 4]) {
    use std::f64::consts::{FRAC_2_PI, FRAC_PI_2};
    let mut sin = [0.0; 4];
    let mut cos = [0.0; 4];
    for l in 0..4 {
        let m = x[l].mul_add(FRAC_2_PI, ROUND);
        let q = m - ROUND;
        let r = (-q).mul_add(PIO2_LO, (-q).mul_add(FRAC_PI_2, x[l]));
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
        sin[l] = if quadrant & 2 == 0 { s } else { -s };
        cos[l] = if (quadrant + 1) & 2 == 0 { c } else { -c };
    }
    (sin, cos)
}

/// [`sin_cos4_portable`] in AVX2 vectors: the same operations in the same order.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn sin_cos4_avx2(x: [Real; 4]) -> ([Real; 4], [Real; 4]) {
    use std::arch::x86_64::*;
    use std::f64::consts::{FRAC_2_PI, FRAC_PI_2};
    let sign = _mm256_set1_pd(-0.0);
    // SAFETY: `x` holds four values.
    let xv = unsafe { _mm256_loadu_pd(x.as_ptr()) };
    let m = _mm256_fmadd_pd(xv, _mm256_set1_pd(FRAC_2_PI), _mm256_set1_pd(ROUND));
    let q = _mm256_sub_pd(m, _mm256_set1_pd(ROUND));
    let nq = _mm256_xor_pd(q, sign);
    let r = _mm256_fmadd_pd(nq, _mm256_set1_pd(FRAC_PI_2), xv);
    let r = _mm256_fmadd_pd(nq, _mm256_set1_pd(PIO2_LO), r);
    let z = _mm256_mul_pd(r, r);
    let mut ps = _mm256_set1_pd(SIN[7]);
    for &c in SIN[..7].iter().rev() {
        ps = _mm256_fmadd_pd(ps, z, _mm256_set1_pd(c));
    }
    let mut pc = _mm256_set1_pd(COS[8]);
    for &c in COS[..8].iter().rev() {
        pc = _mm256_fmadd_pd(pc, z, _mm256_set1_pd(c));
    }
    let s = _mm256_fmadd_pd(_mm256_mul_pd(r, z), ps, r);
    let s = _mm256_or_pd(_mm256_andnot_pd(sign, s), _mm256_and_pd(sign, r));
    let c = _mm256_fmadd_pd(z, pc, _mm256_set1_pd(1.0));
    let bits = _mm256_castpd_si256(m);
    let one = _mm256_set1_epi64x(1);
    let two = _mm256_set1_epi64x(2);
    let swap = _mm256_castsi256_pd(_mm256_sub_epi64(
        _mm256_setzero_si256(),
        _mm256_and_si256(bits, one),
    ));
    let (s, c) = (_mm256_blendv_pd(s, c, swap), _mm256_blendv_pd(c, s, swap));
    let flip_s = _mm256_slli_epi64::<62>(_mm256_and_si256(bits, two));
    let flip_c = _mm256_slli_epi64::<62>(_mm256_and_si256(_mm256_add_epi64(bits, one), two));
    let mut sin = [0.0; 4];
    let mut cos = [0.0; 4];
    // SAFETY: `sin` and `cos` hold four values each.
    unsafe {
        _mm256_storeu_pd(
            sin.as_mut_ptr(),
            _mm256_xor_pd(s, _mm256_castsi256_pd(flip_s)),
        );
        _mm256_storeu_pd(
            cos.as_mut_ptr(),
            _mm256_xor_pd(c, _mm256_castsi256_pd(flip_c)),
        );
    }
    (sin, cos)
}

/// Whether the processor has AVX2 and FMA, the instructions of every run-time-selected
/// kernel that uses fused multiply-adds ([`with_avx2_fma`], [`sin_cos4`], the identification's
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

    /// [`sin_cos4`] against the library's `sin_cos` (correctly rounded nearly always):
    /// within two ulps over joint-sized and larger arguments, near the multiples of π/4 where
    /// the quadrant and the series change, at tiny and zero arguments, and the library's values
    /// beyond the reduction's range or for non-finite input.
    #[test]
    fn sin_cos4_agrees_with_the_library() {
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
        let mut worst: Real = 0.0;
        for chunk in xs.chunks(4) {
            let mut x = [0.0; 4];
            x[..chunk.len()].copy_from_slice(chunk);
            let (s, c) = sin_cos4(x);
            // Both paths, to the bit.
            let (ps, pc) = sin_cos4_portable(x);
            for l in 0..chunk.len() {
                if x[l].is_finite() && x[l].abs() <= SIN_COS_LIMIT {
                    assert_eq!(s[l].to_bits(), ps[l].to_bits(), "sin {:e}", x[l]);
                    assert_eq!(c[l].to_bits(), pc[l].to_bits(), "cos {:e}", x[l]);
                }
            }
            for l in 0..chunk.len() {
                let (ws, wc) = x[l].sin_cos();
                if !x[l].is_finite() {
                    assert!(s[l].is_nan() && c[l].is_nan(), "{}", x[l]);
                    continue;
                }
                // Near a zero of sin or cos the value is the reduced argument's, whose
                // absolute error is an ulp of π/2 times the quadrant count's rounding.
                let e = ulps(s[l], ws).min((s[l] - ws).abs() / 1e-16 * 0.5);
                let f = ulps(c[l], wc).min((c[l] - wc).abs() / 1e-16 * 0.5);
                worst = worst.max(e).max(f);
                assert!(
                    e <= 2.0 && f <= 2.0,
                    "x {:e}: sin {e} ulp, cos {f} ulp",
                    x[l]
                );
            }
        }
        assert!(worst > 0.0, "the check compares something");
        assert_eq!(sin_cos4([-0.0; 4]).0[0].to_bits(), (-0.0 as Real).to_bits());
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
