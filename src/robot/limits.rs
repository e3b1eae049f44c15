//! Joint limits: whether joint values lie within them, and the first joint that does not in
//! the robot's units (`calbench fk`'s warning).

use super::Robot;
use crate::numeric::Real;

impl Robot {
    /// Whether `q` (internal units) lies within the joint limits (with a tolerance of 1e-9);
    /// `fk` warns [`OUTSIDE_LIMITS`](super::OUTSIDE_LIMITS) when it does not.
    pub fn within_limits(&self, q: &[Real]) -> bool {
        self.first_outside(q).is_none()
    }

    /// The first joint whose value in `q` (internal units) lies outside its limits, in the
    /// robot's units to 12 digits (`joint 1 is 500 deg, outside its limits [-180, 180]`);
    /// `None` when `q` is [`within_limits`](Robot::within_limits).
    pub fn outside_limits(&self, q: &[Real]) -> Option<String> {
        let i = self.first_outside(q)?;
        let kind = self.joints[i].kind;
        let unit = if self.q_is_length(i, kind) {
            self.units.length_name()
        } else {
            self.units.angle_name()
        };
        let user = |v: Real| crate::error::shown_converted(v / self.q_factor(i, kind));
        let (lo, hi) = self.joints[i].limits;
        Some(format!(
            "joint {} is {} {unit}, outside its limits [{}, {}]",
            i + 1,
            user(q[i]),
            user(lo),
            user(hi)
        ))
    }

    /// The index of the first joint outside its limits (tolerance 1e-9).
    fn first_outside(&self, q: &[Real]) -> Option<usize> {
        q.iter()
            .zip(&self.joints)
            .position(|(v, j)| *v < j.limits.0 - 1e-9 || *v > j.limits.1 + 1e-9)
    }
}
