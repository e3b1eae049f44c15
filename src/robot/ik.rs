//! Inverse kinematics by Gauss–Newton with a finite-difference joint Jacobian: the joints at
//! which a robot reaches a full pose (joint-command compensation, Li 2018 §3), or a point with
//! its flange z axis along a given direction (pose planning in the workspace).

use nalgebra::{DMatrix, DVector};

use crate::numeric::rng::Rng;
use crate::numeric::{rotation_vector, Frame, Real, Vec3};
use crate::robot::loaded::LoadedFk;
use crate::robot::Robot;
use rand::Rng as _;

/// mm per rad: the orientation rows' weight in the Newton step (an arm of about one metre).
const K_MM_PER_RAD: Real = 1000.0;
/// Newton iterations at most.
const MAX_ITERATIONS: usize = 50;
/// Singular values of the full-pose Jacobian below this share of the largest count as zero:
/// the central differences leave rounding in every entry, so at a singular pose (the wrist's
/// axes 4 and 6 in line) the direction that does not move the tool keeps a small singular
/// value instead of zero, and a step divided by it turned joints 4 and 6 by 10⁷ rad in
/// opposite senses (a compensated program row at q5 = 0), where the minimum-norm step leaves
/// them.
const POSE_SINGULAR: Real = 1e-8;
/// Convergence: position (mm) and orientation (rad) errors below these.
const TOL_MM: Real = 1e-10;
const TOL_RAD: Real = 1e-12;

/// The position error `dp` (mm) and the rotation `dr` (rad, mm-weighted) as one 6-vector.
fn stack(dp: Vec3, dr: Vec3) -> [Real; 6] {
    let r = K_MM_PER_RAD * dr;
    [dp.x, dp.y, dp.z, r.x, r.y, r.z]
}

/// The 6-vector pose error of `f` against `target` (mm, then mm-weighted rad).
fn pose_error(target: &Frame, f: &Frame) -> [Real; 6] {
    stack(
        target.pos - f.pos,
        rotation_vector(&(target.rot * f.rot.transpose())),
    )
}

/// The point-and-axis error of `f`: the position error, then `z_f × axis` (the small
/// rotation that turns the flange z axis onto `axis`), mm-weighted. The rotation about the
/// axis is free, so the rows have rank 5 at most.
fn axis_error(point: &Vec3, axis: &Vec3, f: &Frame) -> [Real; 6] {
    stack(point - f.pos, f.rot.column(2).cross(axis))
}

/// Gauss–Newton on the first `rows` rows of `error(pose(q))` (the others count as zero)
/// from `q0`: central-difference Jacobian, minimum-norm
/// steps (SVD; singular values below `singular` times the largest, and below 1e-12, count as
/// zero), until the position error is below [`TOL_MM`] and the rotation below
/// [`TOL_RAD`] or after [`MAX_ITERATIONS`]. Returns the iterate that reached, else the one of
/// least error, `q0` included: steps that diverge (from a singular start) are not kept.
fn gauss_newton(
    q0: &[Real],
    pose: impl Fn(&[Real]) -> crate::Result<Frame>,
    error: impl Fn(&Frame) -> [Real; 6],
    (rows, singular): (usize, Real),
) -> crate::Result<Vec<Real>> {
    let n = q0.len();
    let mut q = q0.to_vec();
    let mut qh = q.clone();
    let mut jac = DMatrix::<Real>::zeros(rows, n);
    // The iterate of least squared error so far, and that error.
    let (mut best, mut least) = (q.clone(), Real::INFINITY);
    let squared = |e: &[Real; 6]| e[..rows].iter().map(|v| v * v).sum::<Real>();
    for _ in 0..MAX_ITERATIONS {
        let f = pose(&q)?;
        let mut e = error(&f);
        e[rows..].fill(0.0);
        let pos = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
        let rot = (e[3] * e[3] + e[4] * e[4] + e[5] * e[5]).sqrt() / K_MM_PER_RAD;
        if pos < TOL_MM && rot < TOL_RAD {
            return Ok(q);
        }
        let size = squared(&e);
        if size < least {
            least = size;
            best.copy_from_slice(&q);
        }
        // Central differences: J = −∂e/∂q (the pose's derivative); the step solves J·Δq = e.
        let h = 1e-6;
        for j in 0..n {
            qh.copy_from_slice(&q);
            qh[j] += h;
            let ep = error(&pose(&qh)?);
            qh[j] -= 2.0 * h;
            let em = error(&pose(&qh)?);
            for r in 0..rows {
                jac[(r, j)] = -(ep[r] - em[r]) / (2.0 * h);
            }
        }
        // A non-finite error or Jacobian (a target so far away that its squares overflow) ends
        // the iteration: the SVD does not converge on such a matrix.
        if !(e.iter().all(|v| v.is_finite()) && jac.iter().all(|v| v.is_finite())) {
            break;
        }
        let rhs = DVector::from_row_slice(&e[..rows]);
        let Some(Ok(step)) = crate::numeric::linalg::svd(jac.clone(), true, true).map(|s| {
            let cut = (singular * s.singular_values.max()).max(1e-12);
            s.solve(&rhs, cut)
        }) else {
            break;
        };
        for j in 0..n {
            q[j] += step[j];
        }
    }
    // The last iterate unless an earlier one came closer (or it is not finite).
    let last = squared(&error(&pose(&q)?));
    Ok(if last <= least { q } else { best })
}

/// The joints (internal units) at which `robot` reaches `target` on the first `rows` rows of
/// the error (6 for the pose; 3 for the position only, the orientation free and the step the
/// least-norm one) under a payload of `payload_kg` (its gravity sag, when the robot has joint
/// compliances), starting from `q0`; the iterate that came closest, `q0` included, when the
/// pose is out of reach (the caller checks the residual). Fails when the robot has compliances
/// but no link masses.
pub fn solve_pose_rows(
    robot: &Robot,
    target: &Frame,
    q0: &[Real],
    payload_kg: Real,
    rows: usize,
) -> crate::Result<Vec<Real>> {
    let fk = LoadedFk::new(robot);
    gauss_newton(
        q0,
        |q| fk.at(q, payload_kg),
        |f| pose_error(target, f),
        (rows, POSE_SINGULAR),
    )
}

/// The joints (internal units) at which the rigid `robot` puts its tool point at `point`
/// (mm, base frame) with its flange z axis along the unit vector `axis`, starting from `q0`,
/// or `None` when the iteration does not reach them within `tol_mm` and `tol_deg` or leaves
/// the joint limits. The rotation about the axis is left where the iteration ends.
pub fn solve_point_axis(
    robot: &Robot,
    point: &Vec3,
    axis: &Vec3,
    q0: &[Real],
    (tol_mm, tol_deg): (Real, Real),
) -> Option<Vec<Real>> {
    let chain = robot.chain();
    // Singular values cut at 1e-12 alone: the turn about the axis is free (rank 5), and the
    // workspace region's poses are drawn with the turn the iteration leaves.
    let free = (6, 0.0);
    let q = gauss_newton(
        q0,
        |q| Ok(chain.fk(q)),
        |f| axis_error(point, axis, f),
        free,
    )
    .ok()?;
    let f = chain.fk(&q);
    let angle = angle_deg(&f.rot.column(2).into_owned(), axis);
    let reached = (f.pos - point).norm() <= tol_mm && angle <= tol_deg;
    (reached && q.iter().all(|v| v.is_finite()) && robot.within_limits(&q)).then_some(q)
}

/// The angle between the directions `a` and `b` (deg), from both its sine and cosine: `acos`
/// of the dot product alone cannot tell angles below about 1e-6° apart (acos(1 − ε) ≈ √(2ε)).
pub fn angle_deg(a: &Vec3, b: &Vec3) -> Real {
    a.cross(b).norm().atan2(a.dot(b)).to_degrees()
}

/// The direction the flange z axis keeps at every joint configuration of `robot`, where it
/// keeps one: a SCARA or a gantry cannot tilt its tool, so a workspace target whose axis is
/// not that one is never reached. `None` when the axis turns: within 1e-9 rad over 32 uniform
/// joint vectors of a fixed stream, and at zero.
pub fn fixed_tool_axis(robot: &Robot) -> Option<Vec3> {
    let mut rng = crate::numeric::rng::stream(0, "tool axis");
    let mut q = vec![0.0; robot.dof()];
    let z0 = robot.fk(&q).rot.column(2).into_owned();
    (0..32)
        .all(|_| {
            crate::robot::sampling::uniform_joint_pose(robot, &mut rng, &mut q);
            let z = robot.fk(&q).rot.column(2).into_owned();
            angle_deg(&z, &z0) <= 1e-9_f64.to_degrees()
        })
        .then_some(z0)
}

/// Tries per requested pose of [`poses_in_workspace`] before it gives up.
pub const WORKSPACE_TRIES_PER_POSE: usize = 200;

/// The workspace region (`kind = "workspace"`): `n` joint vectors whose tool point is drawn
/// uniformly in the axis-aligned box centred at `centre_mm` with edges `size_mm`, with the
/// tool z axis drawn uniformly (in solid angle) within `cone_deg` of `axis` (normalised here).
/// The joints are solved by inverse kinematics on `robot` ([`solve_point_axis`]) from one
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
        if let Some(q) = solve_point_axis(robot, &p, &dir, &q0, (1e-6, 1e-6)) {
            out.push(q);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::stream;
    use crate::robot::sampling::uniform_joint_pose;

    /// Independent truth: the point and axis of a random pose are reached again from another
    /// start, to the tolerance, and the solution is a pose of the robot with that point/axis.
    #[test]
    fn reaches_the_point_and_axis_of_a_known_pose() {
        let r = crate::robot::builtin::irb2600();
        let mut rng = stream(7, "ik");
        let mut hits = 0;
        for _ in 0..20 {
            let mut q = vec![0.0; 6];
            uniform_joint_pose(&r, &mut rng, &mut q);
            let f = r.fk(&q);
            let axis = f.rot.column(2).into_owned();
            let start: Vec<Real> = q.iter().map(|v| v + 0.2).collect();
            if let Some(s) = solve_point_axis(&r, &f.pos, &axis, &start, (1e-6, 1e-6)) {
                let g = r.fk(&s);
                assert!((g.pos - f.pos).norm() < 1e-6);
                assert!(g.rot.column(2).dot(&axis) > 1.0 - 1e-12);
                hits += 1;
            }
        }
        assert!(hits >= 15, "only {hits} of 20 reached");
    }

    /// A six-axis arm turns its tool axis, so it keeps none (the SCARA, which keeps one, is
    /// tests/cli/refusals.rs's).
    #[test]
    fn a_six_axis_arm_keeps_no_tool_axis() {
        assert_eq!(fixed_tool_axis(&crate::robot::builtin::irb2600()), None);
    }

    /// An unreachable point (beyond the arm's reach) gives `None`, not a wrong pose.
    #[test]
    fn an_unreachable_point_is_refused() {
        let r = crate::robot::builtin::irb2600();
        let p = Vec3::new(5000.0, 0.0, 500.0);
        let q0 = vec![0.0; 6];
        assert!(solve_point_axis(&r, &p, &Vec3::x(), &q0, (1e-3, 1e-3)).is_none());
    }

    /// A target so far away that the error's squares overflow ends the iteration (the SVD does
    /// not converge on a non-finite Jacobian; found by the scenario fuzzer, which hung here).
    #[test]
    fn an_overflowing_target_ends_the_iteration() {
        let r = crate::robot::builtin::irb2600();
        let q0 = vec![0.0; 6];
        for x in [1e200, 8.9e307, -8.9e307] {
            let p = Vec3::new(x, 0.0, 500.0);
            assert!(solve_point_axis(&r, &p, &Vec3::x(), &q0, (1e-3, 1e-3)).is_none());
        }
    }
}
