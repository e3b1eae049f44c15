//! The numerical ground floor: scalar and small fixed-size types, rigid frames and rotations
//! (lengths in millimetres and angles in radians everywhere inside the library), named random
//! streams, and the dense kernels the identification and the pose selection spend their time
//! in.
//!
//! - `frames`: [`Real`], [`Vec3`], [`Mat3`], [`Frame`], elementary rotations, roll-pitch-yaw
//!   angles, rotation vectors and quaternions (re-exported here).
//! - `trig`: [`sin_cos_slice`], the sines and cosines of all joint angles of a pose at once,
//!   and [`sin_cos`], the same bits for one angle.
//! - [`gp`]: Gaussian-process regression (ARD squared-exponential kernel, marginal likelihood).
//! - [`linalg`]: the Cholesky factorisation and solve of the normal equations.
//! - [`symeig`]: eigenvalues of small symmetric matrices, several matrices at once.
//! - `gram`: the normal equations `JᵀPJ`, `JᵀPr` of the Gauss–Newton methods.
//! - [`normal`]: the same normal equations summed over blocks of rows (streaming).
//! - [`rng`]: the portable, named random streams.
//!
//! The kernels run on vector instructions where the processor has them (AVX2 and FMA on
//! x86-64) and on portable code elsewhere, chosen at run time in one place (`simd`), with the
//! same bits either way; nothing outside this module chooses an instruction set. The environment
//! variable [`SIMD_VARIABLE`] (`CALBENCH_SIMD=scalar`) forces the portable code.

pub mod dist;
mod frames;
pub mod gp;
pub(crate) mod gram;
pub mod linalg;
pub mod nan;
pub mod normal;
pub mod options;
pub mod rng;
pub(crate) mod simd;
pub mod symeig;
mod trig;

pub use frames::{
    matrix_rpy, median, nearest_turn, quaternion, quaternion_matrix, rot_x, rot_y, rot_z,
    rotation_vector, rpy_matrix, skew, so3_right_jacobian_inverse, Frame, Mat3, Real, Vec3,
};
pub use simd::{simd_forced_scalar, SIMD_VARIABLE};
pub use trig::{sin_cos, sin_cos_slice};
