//! Scalar and small fixed-size types, rigid frames, elementary rotations and quaternions.
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

/// The angle `t` (rad) less the whole turns nearest it: the same direction, within [−π, π].
pub fn nearest_turn(t: Real) -> Real {
    t - std::f64::consts::TAU * (t / std::f64::consts::TAU).round()
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
    // Near gimbal lock (|cos pitch| < 0.014) the entries below scale with cos pitch and
    // `asin` loses digits; there pitch and roll are read, after the yaw, from entries of size
    // 1 ([`near_lock_rpy`]), unless the first column is exactly ±z.
    let column = r[(0, 0)] != 0.0 || r[(1, 0)] != 0.0;
    if r[(2, 0)].abs() >= 1.0 - 1e-4 && column {
        return near_lock_rpy(r);
    }
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

/// [`matrix_rpy`] near gimbal lock: the yaw from the first column, then `Ry(pitch) Rx(roll) =
/// Rz(yaw)ᵀ r`, whose entries (1, 1), (1, 2) and (0, 0), (2, 0) give roll and pitch to full
/// precision however the yaw fell: the three angles give back `r` to rounding, where reading
/// roll from entries of size cos pitch moved a URDF's tool by 1e-4 mm.
fn near_lock_rpy(r: &Mat3) -> [Real; 3] {
    let yaw = r[(1, 0)].atan2(r[(0, 0)]);
    let rest = rot_z(yaw).transpose() * r;
    [
        (-rest[(1, 2)]).atan2(rest[(1, 1)]),
        (-rest[(2, 0)]).atan2(rest[(0, 0)]),
        yaw,
    ]
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

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

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

    #[test]
    fn rpy_round_trip() {
        let rpy = [0.3, -0.7, 2.1];
        let back = matrix_rpy(&rpy_matrix(rpy));
        for i in 0..3 {
            assert_relative_eq!(rpy[i], back[i], epsilon = 1e-12);
        }
    }

    /// Near gimbal lock the angles give back the matrix to rounding: pitches from 1e-3 to
    /// 1e-16 rad off ±90° (the exported URDF origin of a joint with `rpy="-1.5708 -1.5708 0"`
    /// moved its tool by 1e-4 mm).
    #[test]
    fn rpy_near_gimbal_lock_gives_back_the_matrix() {
        let half = std::f64::consts::FRAC_PI_2;
        for (off, roll, yaw) in [
            (7.9e-8, -half + 4.9e-12, 0.0),
            (1e-3, 0.4, -2.0),
            (3e-6, 2.5, 1.0),
            (1e-12, -0.3, 0.2),
            (0.0, 0.7, -0.1),
        ] {
            for sign in [1.0, -1.0] {
                let r = rpy_matrix([roll, sign * (half - off), yaw]);
                let back = rpy_matrix(matrix_rpy(&r));
                let gap = (back - r).abs().max();
                assert!(gap < 1e-15, "pitch off by {off}: {gap}");
            }
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
