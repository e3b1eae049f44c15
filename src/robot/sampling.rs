//! Drawing joint configurations.

use rand::Rng as _;

use crate::numeric::rng::Rng;
use crate::numeric::Real;
use crate::robot::Robot;

/// `n` joint vectors drawn uniformly within the joint limits (internal units).
pub fn uniform_joint_poses(robot: &Robot, n: usize, rng: &mut Rng) -> Vec<Vec<Real>> {
    (0..n)
        .map(|_| {
            robot
                .joints
                .iter()
                .map(|j| j.limits.0 + (j.limits.1 - j.limits.0) * rng.random::<Real>())
                .collect()
        })
        .collect()
}
