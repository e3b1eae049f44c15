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
