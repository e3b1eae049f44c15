//! Drawing joint configurations: uniformly within the joint limits, or with the tool point
//! in a box of the workspace.

use rand::Rng as _;

use crate::numeric::rng::Rng;
use crate::numeric::Real;
use crate::robot::Robot;

/// One joint vector drawn uniformly within the joint limits into `q` (internal units): one
/// uniform draw per joint, in joint order. Every uniform joint draw of calbench is this one.
pub fn uniform_joint_pose(robot: &Robot, rng: &mut Rng, q: &mut [Real]) {
    for (v, j) in q.iter_mut().zip(&robot.joints) {
        *v = j.limits.0 + (j.limits.1 - j.limits.0) * rng.random::<Real>();
    }
}

/// `n` joint vectors drawn uniformly within the joint limits (internal units).
pub fn uniform_joint_poses(robot: &Robot, n: usize, rng: &mut Rng) -> Vec<Vec<Real>> {
    (0..n)
        .map(|_| {
            let mut q = vec![0.0; robot.dof()];
            uniform_joint_pose(robot, rng, &mut q);
            q
        })
        .collect()
}

/// Joint vectors whose tool point (forward kinematics of `robot`) lies in the axis-aligned
/// box centred at `centre_mm` with edges `size_mm`, by rejection sampling: uniform joint
/// vectors ([`uniform_joint_pose`]) are drawn until `n` fall in the box or `max_tries` have
/// been drawn, or `give_up` have been drawn without one in the box. Returns those found, in
/// the order drawn: fewer than `n` when the box is (nearly) out of reach, which the caller
/// reports.
pub fn poses_in_box(
    robot: &Robot,
    n: usize,
    centre_mm: [Real; 3],
    size_mm: [Real; 3],
    (max_tries, give_up): (usize, usize),
    rng: &mut Rng,
) -> Vec<Vec<Real>> {
    let chain = robot.chain();
    let mut out = Vec::with_capacity(n);
    let mut q = vec![0.0; robot.dof()];
    let mut tries = 0;
    while out.len() < n && tries < max_tries {
        if tries == give_up && out.is_empty() {
            break; // hopeless: not one pose so far
        }
        tries += 1;
        uniform_joint_pose(robot, rng, &mut q);
        let p = chain.fk(&q).pos;
        if (0..3).all(|k| (p[k] - centre_mm[k]).abs() <= size_mm[k] / 2.0) {
            out.push(q.clone());
        }
    }
    out
}

/// Tries per requested pose of [`poses_in_workspace`] before it gives up.
pub const WORKSPACE_TRIES_PER_POSE: usize = 200;

/// The workspace region (`kind = "workspace"`): `n` joint vectors whose tool point is drawn
/// uniformly in the axis-aligned box centred at `centre_mm` with edges `size_mm`, with the
/// tool z axis drawn uniformly (in solid angle) within `cone_deg` of `axis` (normalised here).
/// The joints are solved by inverse kinematics on `robot` ([`crate::robot::ik`]) from one
/// start, `start` (internal units) or else zero clamped into each joint's range (one elbow and wrist branch, as a measurement
/// program keeps), except the last joint, whose start is drawn uniformly in its range (the
/// turn about the tool axis); a target not reached within the joint limits is drawn again.
/// Per try the draws are: the point (x, y, z), the cone (cos of the angle, then the
/// azimuth), the last joint's start. Stops after `WORKSPACE_TRIES_PER_POSE · n` tries and
/// returns those found, in order: fewer than `n` when the region is (nearly) out of reach,
/// which the caller reports.
pub fn poses_in_workspace(
    robot: &Robot,
    n: usize,
    (centre_mm, size_mm): ([Real; 3], [Real; 3]),
    (axis, cone_deg): ([Real; 3], Real),
    start: Option<&[Real]>,
    rng: &mut Rng,
) -> Vec<Vec<Real>> {
    use crate::numeric::Vec3;
    let a = Vec3::from(axis).normalize();
    // Two unit vectors perpendicular to the axis.
    let helper = if a.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let u = a.cross(&helper).normalize();
    let v = a.cross(&u);
    let cos_max = cone_deg.to_radians().cos();
    let mut out = Vec::with_capacity(n);
    // One start for every target, so that every pose is of the same branch (elbow, wrist)
    // as a measurement program keeps: zero clamped into each joint's range; the last joint's
    // start is drawn uniformly in its range (the free turn about the tool axis).
    let mut q0: Vec<Real> = match start {
        Some(s) => s.to_vec(),
        None => robot
            .joints
            .iter()
            .map(|j| 0.0f64.clamp(j.limits.0, j.limits.1))
            .collect(),
    };
    let mut tries = 0;
    while out.len() < n && tries < WORKSPACE_TRIES_PER_POSE * n.max(1) {
        tries += 1;
        let p = Vec3::from_fn(|k, _| centre_mm[k] + size_mm[k] * (rng.random::<Real>() - 0.5));
        let c = 1.0 - (1.0 - cos_max) * rng.random::<Real>();
        let s = (1.0 - c * c).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * rng.random::<Real>();
        let dir = c * a + s * (phi.cos() * u + phi.sin() * v);
        if let (Some(last), Some(j)) = (q0.last_mut(), robot.joints.last()) {
            *last = j.limits.0 + (j.limits.1 - j.limits.0) * rng.random::<Real>();
        }
        if let Some(q) = crate::robot::ik::solve_point_axis(robot, &p, &dir, &q0, (1e-6, 1e-6)) {
            out.push(q);
        }
    }
    out
}
