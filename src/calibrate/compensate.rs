//! Joint-command compensation (Li 2018 §3): for a controller whose kinematic table is locked,
//! the identified model is used offline to correct the joint commands. A program computed with
//! the nominal model asks for the pose `T_nom(q)`; the corrected command `q'` is the solution of
//! `T_id(q') = T_nom(q)` (position and orientation), found by Gauss–Newton from `q' = q` on the
//! 6-vector error `[Δp (mm); k·log(R_targetR(q')ᵀ) (rad)]`, with a finite-difference joint
//! Jacobian (the error itself is exact, so the fixed point is exact).

use crate::calibrate::validation::rotation_angle_deg;
use crate::numeric::{Frame, Real};
use crate::robot::loaded::{loaded_fk, LoadedFk};
use crate::robot::{Convention, Param, Robot};

/// What a corrected row must reach to be flagged `ok`: residual_mm and residual_deg.
pub const ACCEPT_MM: Real = 1e-6;
/// See [`ACCEPT_MM`].
pub const ACCEPT_DEG: Real = 1e-6;

/// The corrected command of one program row.
#[derive(Clone, Debug, PartialEq)]
pub struct Corrected {
    /// Joint values (internal units: rad, mm).
    pub q: Vec<Real>,
    /// Position error of the identified robot at `q` against the nominal pose (mm).
    pub residual_mm: Real,
    /// Orientation error, rotation angle (deg).
    pub residual_deg: Real,
    /// `ok`, `limits` (the solution leaves the joint limits) or `failed` (the pose is not
    /// reached within [`ACCEPT_MM`] / [`ACCEPT_DEG`]: out of reach, or a singularity).
    pub flag: &'static str,
}

/// What makes `identified` no calibration of `nominal`, in words (empty when it can be one):
/// a joint of another kind, or a parameter both robots have moved beyond the bounds of
/// "Physical plausibility" ([`super::plausibility::moves`]; the gravity basis's deflections
/// at the program's poses `qs`). A program corrected with another robot's model (a file given
/// for another), or with one that cannot be physically right, would send the arm far from
/// every pose it was written for. The parameters are compared in the nominal robot's DH form
/// ([`Robot::normals_as`]): a link whose common normal the identified robot's file points the
/// other way is the same link. Parameters beyond their bounds whose robot does what a
/// calibration's would (its tool points within a link's length bound of the nominal's: the
/// same arm in other parameters, coincident axes traded, a URDF's own frames) are no refusal;
/// robots of the two DH families, which name other quantities alike, are compared by that
/// alone.
pub fn not_a_calibration_of(nominal: &Robot, identified: &Robot, qs: &[Vec<Real>]) -> Vec<String> {
    // A URDF read back can turn a link's common normal over: the same robot, θ moved by π.
    let identified = &identified.normals_as(nominal);
    let kinds: Vec<String> = nominal
        .joints
        .iter()
        .zip(&identified.joints)
        .enumerate()
        .filter(|(_, (n, i))| n.kind != i.kind)
        .map(|(j, (n, i))| {
            let (n, i): (&str, &str) = (n.kind.into(), i.kind.into());
            format!("joint {} is {i}, the nominal robot's {n}", j + 1)
        })
        .collect();
    if !kinds.is_empty() {
        return kinds;
    }
    // Modified and standard DH name other quantities by the same names: compared by what the
    // robots do.
    let modified = |r: &Robot| r.convention == Convention::Mdh;
    if modified(identified) != modified(nominal) {
        return tool_points_apart(nominal, identified, qs, true);
    }
    let theirs = identified.params();
    let mut shared: Vec<Param> = nominal
        .params()
        .into_iter()
        .filter(|p| theirs.contains(p))
        .collect();
    shared.extend(crate::robot::gravity_basis::params(identified));
    let found = super::plausibility::moves(nominal, identified, &shared, qs);
    if found.is_empty() || tool_points_apart(nominal, identified, qs, false).is_empty() {
        return Vec::new();
    }
    found
}

/// Joint vectors drawn (a fixed stream) where a comparison of two robots has no program rows.
const DRAWN_POSES: usize = 64;

/// The tool points of `identified` and `nominal` at the program's poses `qs` and at
/// [`DRAWN_POSES`] joint vectors drawn within the limits further apart than a calibration
/// moves them, in words (empty when they are not): by more than a link's length may move in
/// "Physical plausibility", the larger of [`super::plausibility::LENGTH_SHARE`] of the reach
/// and [`super::plausibility::LENGTH_FLOOR_MM`]. A calibration moves a tool point by
/// millimetres; another arm's model (a KR 16's against an IRB 2600's) by hundreds. `families`:
/// the robots are of the two DH families, and the words say why they are compared so.
fn tool_points_apart(
    nominal: &Robot,
    identified: &Robot,
    qs: &[Vec<Real>],
    families: bool,
) -> Vec<String> {
    use super::plausibility::{LENGTH_FLOOR_MM, LENGTH_SHARE};
    let mut rng = crate::numeric::rng::stream(0, "compared poses");
    let drawn = crate::robot::sampling::uniform_joint_poses(nominal, DRAWN_POSES, &mut rng);
    let reach = crate::robot::sampling::reach_bound_mm(nominal);
    let bound = (LENGTH_SHARE * reach).max(LENGTH_FLOOR_MM);
    let gap = qs
        .iter()
        .chain(&drawn)
        .map(|q| (identified.fk(q).pos - nominal.fk(q).pos).norm())
        .fold(0.0, Real::max);
    if gap <= bound {
        return Vec::new();
    }
    let why = match families {
        true => format!(
            "; the robots' conventions, {} and {}, name other quantities alike, so they are \
             compared by their tool points",
            identified.convention.as_str(),
            nominal.convention.as_str(),
        ),
        false => String::new(),
    };
    vec![format!(
        "its tool point is {gap:.0} mm from the nominal robot's at a pose (bound {bound:.0} mm: \
         the larger of {:.0} % of the robot's reach, {reach:.0} mm, and {LENGTH_FLOOR_MM:.0} mm, \
         as a link's length{why})",
        LENGTH_SHARE * 100.0,
    )]
}

/// The flag of a written command `q` with its residuals ([`Corrected::flag`]).
fn flag(identified: &Robot, q: &[Real], residual_mm: Real, residual_deg: Real) -> &'static str {
    if !(residual_mm <= ACCEPT_MM && residual_deg <= ACCEPT_DEG) {
        "failed"
    } else if !identified.within_limits(q) {
        "limits"
    } else {
        "ok"
    }
}

/// Corrects one program row `q_nominal` (internal units): the joints at which `identified`
/// reaches the pose `nominal` gives at `q_nominal` (its position, for an arm of fewer than six
/// joints: its orientation residual is written, not judged by the flag), each revolute joint
/// turned by whole turns to the value nearest the row's (`nearest_turns`) and judged against
/// the limits there: a solution just past a limit is flagged `limits`, not turned into the
/// limits a whole turn from the row's. `round` maps joint values to what is written (the
/// output's decimals), so the residuals are those of the written command. The
/// identified robot carries `payload_kg` at the tool (its sag, when it has compliances; the
/// nominal robot of a locked controller knows no sag).
pub fn compensate_row(
    nominal: &Robot,
    identified: &Robot,
    q_nominal: &[Real],
    payload_kg: Real,
    round: impl Fn(&[Real]) -> Vec<Real>,
) -> crate::Result<Corrected> {
    let target = nominal.fk(q_nominal);
    let (mut q, judged) = reach(identified, &target, q_nominal, payload_kg, false)?;
    nearest_turns(identified, &mut q, q_nominal);
    let q = round(&q);
    let f = loaded_fk(identified, &identified.chain(), &q, payload_kg)?;
    let residual_mm = (f.pos - target.pos).norm();
    let residual_deg = rotation_angle_deg(&f, &target);
    let flag = flag(
        identified,
        &q,
        residual_mm,
        if judged { residual_deg } else { 0.0 },
    );
    Ok(Corrected {
        q,
        residual_mm,
        residual_deg,
        flag,
    })
}

/// The joints at which `identified` (carrying `payload_kg`) reaches `target`, solved from
/// `q0`, and whether its orientation is judged: the whole pose; the position alone for
/// `position_only`; and for an arm of fewer than six joints, which cannot take every pose a
/// changed model asks for (five joints against six coordinates), the position, solved both
/// from `q0` and from the joints that come closest to the whole pose ([`nearest_pose`]).
fn reach(
    identified: &Robot,
    target: &Frame,
    q0: &[Real],
    payload_kg: Real,
    position_only: bool,
) -> crate::Result<(Vec<Real>, bool)> {
    let solve = |q0: &[Real], rows| {
        crate::robot::ik::solve_pose_rows(identified, target, q0, payload_kg, rows)
    };
    if position_only {
        return Ok((solve(q0, 3)?, false));
    }
    let q = solve(q0, 6)?;
    if identified.dof() >= 6 {
        return Ok((q, true));
    }
    let candidates = [solve(q0, 3)?, solve(&q, 3)?];
    Ok((
        nearest_pose(identified, target, q0, payload_kg, candidates)?,
        false,
    ))
}

/// How much further (a share of the joint's range) a later solution of an arm of fewer than
/// six joints may move a joint and still be kept for turning the tool nearer the target's
/// orientation: 1 %. With none, a slide 0.001 mm further (of a 180 mm travel) had kept a
/// SCARA's yaw 2.7° off where 0.27° was reachable; a joint turned tens of degrees for a
/// tenth of a degree is still refused.
const MOVE_SLACK: Real = 0.01;

/// Of an arm's joint vectors that reach a target's position (`candidates`: from the start
/// `q0`, then from the joints closest to the whole pose), the one to keep: the position
/// reached ([`ACCEPT_MM`]) first, then within the limits (each revolute joint nearest `q0`'s
/// by whole turns); of two alike, a later one only where it turns the tool nearer the
/// target's orientation and moves no joint further from `q0` (by the share of its range,
/// beyond [`MOVE_SLACK`]).
/// The whole pose's solve of an arm of fewer than six joints minimises position and
/// orientation together, with no pose to reach exactly, and can end on another branch: on a
/// five-joint arm with a sliding joint it had sent the slide to 1401 mm past its 300 mm limit,
/// turned a tool 4.9° from the pose where the row's own position solve left it 0.6° away, and
/// moved joints by 50° to gain 0.1°.
fn nearest_pose<const N: usize>(
    robot: &Robot,
    target: &Frame,
    q0: &[Real],
    payload_kg: Real,
    candidates: [Vec<Real>; N],
) -> crate::Result<Vec<Real>> {
    let fk = LoadedFk::new(robot);
    // The kept one's failures (position, limits), tool turn (deg) and largest move.
    let mut best: Option<((bool, bool), Real, Real)> = None;
    let mut kept = q0.to_vec();
    for q in candidates {
        let f = fk.at(&q, payload_kg)?;
        let mut turned = q.clone();
        nearest_turns(robot, &mut turned, q0);
        let fails = (
            (f.pos - target.pos).norm() > ACCEPT_MM,
            !robot.within_limits(&turned),
        );
        let turn = rotation_angle_deg(&f, target);
        let moved = (turned.iter().zip(q0).zip(&robot.joints))
            .map(|((v, r), j)| (v - r).abs() / (j.limits.1 - j.limits.0))
            .fold(0.0, Real::max);
        let better = best.is_none_or(|(b_fails, b_turn, b_moved)| {
            fails < b_fails || (fails == b_fails && turn < b_turn && moved <= b_moved + MOVE_SLACK)
        });
        if better {
            best = Some((fails, turn, moved));
            kept = q;
        }
    }
    Ok(kept)
}

/// Turns each revolute joint ([`Robot::q_turns`]: not a coupling's screw travel) by whole
/// turns (the same pose) to the value nearest `near`'s, within half a turn of it, inside its
/// limits or not: the command a program row's arm moves least to. (Turned into the limits
/// instead, a row at 359° whose correction is +1° with limits of ±360° had been written
/// −359.96°, a turn and more away, and flagged `ok`.)
fn nearest_turns(robot: &Robot, q: &mut [Real], near: &[Real]) {
    let turn = 2.0 * std::f64::consts::PI;
    for (i, (v, r)) in q.iter_mut().zip(near).enumerate() {
        if robot.q_turns(i) {
            *v += ((r - *v) / turn).round() * turn;
        }
    }
}

/// Turns each revolute joint outside its limits by whole turns into them, where a turn
/// reaches (the same pose): to the lowest value within them (a Cartesian target has no
/// command to stay near).
fn wrap_into_limits(robot: &Robot, q: &mut [Real]) {
    let turn = 2.0 * std::f64::consts::PI;
    for (i, (v, j)) in q.iter_mut().zip(&robot.joints).enumerate() {
        let (lo, hi) = j.limits;
        if !robot.q_turns(i) || (lo..=hi).contains(v) {
            continue;
        }
        let lowest = *v + ((lo - *v) / turn).ceil() * turn;
        if lowest <= hi {
            *v = lowest;
        }
    }
}

/// Random starts tried for a Cartesian target after the previous solution and the middle of
/// the joint limits.
pub const TARGET_STARTS: usize = 40;

/// Solves Cartesian tool targets (`compensate --targets`): per target, the joints at which
/// `identified` reaches it (position only when `position_only`, else the whole pose, and
/// for an arm of fewer than six joints its position, `reach`).
/// Targets carry no joints, so each is solved from the previous target's solution, then the
/// middle of the joint limits, then [`TARGET_STARTS`] seeded random poses, until a start
/// gives a solution within the joint limits to [`ACCEPT_MM`] / [`ACCEPT_DEG`] (for the whole
/// pose of an arm of fewer than six joints every start, the nearest orientation kept);
/// otherwise the closest one is returned, flagged. `round` as in [`compensate_row`].
pub fn compensate_targets(
    identified: &Robot,
    targets: &[Frame],
    position_only: bool,
    payload_kg: Real,
    round: impl Fn(&[Real]) -> Vec<Real>,
) -> crate::Result<Vec<Corrected>> {
    let n = identified.dof();
    let middle: Vec<Real> = (0..n)
        .map(|j| 0.5 * (identified.joints[j].limits.0 + identified.joints[j].limits.1))
        .collect();
    let mut g = crate::numeric::rng::stream(0, "compensate-targets");
    let randoms = crate::robot::sampling::uniform_joint_poses(identified, TARGET_STARTS, &mut g);
    let fk = LoadedFk::new(identified);
    let mut out: Vec<Corrected> = Vec::with_capacity(targets.len());
    for target in targets {
        let previous = out.last().map(|c| c.q.clone());
        let starts = previous
            .iter()
            .chain(std::iter::once(&middle))
            .chain(&randoms);
        let mut best: Option<Corrected> = None;
        for q0 in starts {
            let (mut q, judged) = reach(identified, target, q0, payload_kg, position_only)?;
            wrap_into_limits(identified, &mut q);
            let q = round(&q);
            let f = fk.at(&q, payload_kg)?;
            let residual_mm = (f.pos - target.pos).norm();
            let residual_deg = if position_only {
                0.0
            } else {
                rotation_angle_deg(&f, target)
            };
            let judged_deg = if judged { residual_deg } else { 0.0 };
            let flag = flag(identified, &q, residual_mm, judged_deg);
            let c = Corrected {
                q,
                residual_mm,
                residual_deg,
                flag,
            };
            // An arm of fewer than six joints reaches a whole pose's position from most
            // starts, with an orientation that depends on the start (another branch turns
            // the tool by 100°): every start is tried, and of the `ok` ones the nearest
            // orientation kept.
            let nearest_turn = !position_only && !judged;
            let rank = |c: &Corrected| {
                let at = ["ok", "limits", "failed"].iter().position(|g| *g == c.flag);
                let ok = c.flag == "ok" && nearest_turn;
                (at, if ok { c.residual_deg } else { c.residual_mm })
            };
            let better = best.as_ref().is_none_or(|b| rank(&c) < rank(b));
            let done = c.flag == "ok" && !nearest_turn;
            if better {
                best = Some(c);
            }
            if done {
                break;
            }
        }
        out.extend(best);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::numeric::rng::stream;
    use crate::robot::sampling::uniform_joint_poses;
    use crate::robot::Param;

    /// A whole turn leaves an angle's pose and moves a screw travel: Guo's arm's joints 1 and
    /// 2 (screw travels, mm) are never turned, whatever their drift, and its angles are, to
    /// the value nearest the command.
    #[test]
    fn only_angles_are_turned() {
        let guo = crate::robot::builtin::load("guo-3t2r").unwrap();
        let turn = 2.0 * std::f64::consts::PI;
        let near = vec![0.0; guo.dof()];
        let mut q: Vec<Real> = (0..guo.dof()).map(|_| 4.0).collect();
        nearest_turns(&guo, &mut q, &near);
        for (i, v) in q.iter().enumerate() {
            let want = if guo.q_turns(i) { 4.0 - turn } else { 4.0 };
            assert_eq!(*v, want, "joint {}", i + 1);
        }
        assert!(!guo.q_turns(0) && !guo.q_turns(1) && guo.q_turns(2));
        // Screw travels a little past their limits stay there (they had been moved 2π mm).
        let mut q: Vec<Real> = guo.joints.iter().map(|j| j.limits.1 + 1.0).collect();
        let before = q.clone();
        wrap_into_limits(&guo, &mut q);
        assert_eq!(q[..2], before[..2]);
    }

    /// Simulation: a true robot (nominal + errors) identified exactly reaches, at the corrected
    /// joints, the poses the nominal model promised; the nominal joints miss them by the error.
    #[test]
    fn corrected_joints_reach_the_nominal_pose_on_the_true_robot() {
        let nominal = crate::robot::builtin::load("irb2600").unwrap();
        let errors: Vec<(Param, Real)> = nominal
            .params()
            .into_iter()
            .enumerate()
            .map(|(i, p)| {
                let e = if matches!(p, Param::Theta(_) | Param::Alpha(_) | Param::Beta(_)) {
                    1e-3
                } else {
                    0.5
                };
                (p, if i % 2 == 0 { e } else { -e })
            })
            .collect();
        let truth = nominal.with_errors(&errors);
        let mut g = stream(7, "compensate-test");
        let qs = uniform_joint_poses(&nominal, 30, &mut g);
        let mut ok = 0;
        for q in &qs {
            let c = compensate_row(&nominal, &truth, q, 0.0, |q| q.to_vec()).unwrap();
            let target = nominal.fk(q);
            let before = (truth.fk(q).pos - target.pos).norm();
            assert!(before > 0.1, "the errors move the tool ({before} mm)");
            if c.flag == "failed" {
                continue;
            }
            let f = truth.fk(&c.q);
            assert!((f.pos - target.pos).norm() < 1e-8);
            assert!(rotation_angle_deg(&f, &target) < 1e-8);
            ok += 1;
        }
        assert!(ok >= 25, "only {ok} of 30 rows solved");
    }

    /// A program row at a wrist singularity (q5 = 0: axes 4 and 6 in line) is corrected
    /// within the limits, every joint less than half a turn from the row's and joints 4 and 6
    /// together turning the tool about their common axis as the row does, where the step
    /// along the direction that does not move the tool turned them by 10⁷ rad in opposite
    /// senses. (The wrist tilt the errors call for sets joint 4 apart from the row's: near the
    /// singularity a small tilt needs joint 4 turned towards its direction.)
    #[test]
    fn a_row_at_a_wrist_singularity_keeps_its_wrist() {
        let nominal = crate::robot::builtin::load("irb2600").unwrap();
        let truth = nominal.with_errors(&[(Param::A(1), 0.5), (Param::D(3), -0.3)]);
        for q in [
            [0.3, -0.4, 0.5, 1.2, 0.0, 2.5],
            [1.2, -0.35, 0.6, -1.0, 0.0, 2.6],
            [-0.7, 0.2, -0.1, 0.0, 0.0, 0.0],
        ] {
            let c = compensate_row(&nominal, &truth, &q, 0.0, |q| q.to_vec()).unwrap();
            assert_eq!(c.flag, "ok", "{q:?}: {:?}", c.q);
            assert!(
                (0..6).all(|j| (c.q[j] - q[j]).abs() < std::f64::consts::PI),
                "{q:?}: {:?}",
                c.q
            );
            let turn = (c.q[3] + c.q[5]) - (q[3] + q[5]);
            assert!(c.q[4].abs() < 0.01 && turn.abs() < 0.01, "{q:?}: {:?}", c.q);
            let (f, target) = (truth.fk(&c.q), nominal.fk(&q));
            assert!((f.pos - target.pos).norm() < 1e-8, "{q:?}");
            assert!(rotation_angle_deg(&f, &target) < 1e-8, "{q:?}");
        }
    }

    /// Cartesian targets of the nominal robot (positions, then full poses) are reached by the
    /// identified robot; an unreachable one is flagged.
    #[test]
    fn cartesian_targets_are_reached_on_the_identified_robot() {
        let nominal = crate::robot::builtin::irb2600();
        let qs = uniform_joint_poses(&nominal, 12, &mut stream(9, "targets-test"));
        let truth = nominal.with_errors(&[(Param::A(1), 0.7), (Param::Theta(2), 2e-3)]);
        let mut targets: Vec<Frame> = qs.iter().map(|q| nominal.fk(q)).collect();
        for only in [true, false] {
            let c = compensate_targets(&truth, &targets, only, 0.0, |q| q.to_vec()).unwrap();
            for (t, c) in targets.iter().zip(&c) {
                assert_eq!(c.flag, "ok", "{c:?}");
                let f = truth.fk(&c.q);
                assert!((f.pos - t.pos).norm() < 1e-8);
                if !only {
                    assert!(rotation_angle_deg(&f, t) < 1e-7);
                }
            }
        }
        targets[0].pos *= 10.0;
        let c = compensate_targets(&truth, &targets[..1], true, 0.0, |q| q.to_vec()).unwrap();
        assert_eq!(c[0].flag, "failed");
    }

    /// The residual is that of the written (rounded) command, and a bad solve is flagged.
    #[test]
    fn rounding_shows_in_the_residual_and_failures_are_flagged() {
        let nominal = crate::robot::builtin::load("irb2600").unwrap();
        let q = vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
        let coarse = compensate_row(&nominal, &nominal, &q, 0.0, |q| {
            q.iter().map(|v| v + 1e-3).collect()
        })
        .unwrap();
        assert!(coarse.residual_mm > 1e-3);
        assert_eq!(coarse.flag, "failed");
        let exact = compensate_row(&nominal, &nominal, &q, 0.0, |q| q.to_vec()).unwrap();
        assert_eq!(exact.flag, "ok");
        assert!(exact.residual_mm < 1e-12);
    }

    /// A robot with joint compliances: the corrected commands reach the nominal pose with the
    /// arm sagging under the payload (the elasto-geometric model's own forward kinematics), and
    /// the sag is what the uncorrected commands miss by.
    #[test]
    fn compliant_robot_commands_include_the_sag_at_the_payload() {
        let nominal = crate::robot::builtin::load("irb2600").unwrap();
        let mut soft = nominal.clone();
        soft.set(Param::Compliance(1), 1.0 / 3.5e6);
        soft.set(Param::Compliance(2), 1.0 / 2.5e6);
        let chain = soft.chain();
        let q = vec![0.3, 0.4, -0.2, 0.5, 0.6, 0.1];
        let target = nominal.fk(&q);
        let sagged = loaded_fk(&soft, &chain, &q, 20.0).unwrap();
        let sag = (sagged.pos - target.pos).norm();
        assert!(sag > 0.05, "20 kg sag the arm by {sag} mm");
        let c = compensate_row(&nominal, &soft, &q, 20.0, |q| q.to_vec()).unwrap();
        assert_eq!(c.flag, "ok");
        let f = loaded_fk(&soft, &chain, &c.q, 20.0).unwrap();
        assert!((f.pos - target.pos).norm() < 1e-8);
        // Without a payload the rigid and the compliant arm differ by the links' own sag only.
        let light = compensate_row(&nominal, &soft, &q, 0.0, |q| q.to_vec()).unwrap();
        assert!(light.q != c.q);
    }

    /// Full-pose targets of a five-joint arm: it reaches each target's position (the
    /// orientation a changed model asks for is out of its reach, and not judged), as a
    /// program row does. It had solved all six coordinates by least squares, missed the
    /// position by millimetres and written joint 1 turns outside its limits.
    #[test]
    fn a_five_joint_arm_reaches_the_position_of_full_pose_targets() {
        let joint = |alpha: f64, a: f64, d: f64, theta: f64, lim: [f64; 2]| {
            format!(
                "[[joints]]\ntype = \"revolute\"\nalpha = {alpha}\na = {a}\nd = {d}\n\
                 theta = {theta}\nlimits = [{}, {}]\n",
                lim[0], lim[1]
            )
        };
        let text = [
            "name = \"arm5\"\nconvention = \"dh\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n"
                .to_string(),
            joint(90.0, 33.0, 147.0, 0.0, [-169.0, 169.0]),
            joint(0.0, 155.0, 0.0, 90.0, [-65.0, 90.0]),
            joint(0.0, 135.0, 0.0, 0.0, [-150.0, 146.0]),
            joint(90.0, 0.0, 0.0, 90.0, [-102.0, 102.0]),
            joint(0.0, 0.0, 218.0, 0.0, [-167.0, 167.0]),
            "[tool]\nxyz = [0.0, 15.0, 40.0]\nrpy = [0.0, 0.0, 0.0]\n".to_string(),
        ]
        .concat();
        let nominal = crate::robot::parse_robot_file(&text, "arm5.toml".as_ref()).unwrap();
        let errors: Vec<(Param, Real)> = (0..5)
            .flat_map(|j| [(Param::A(j), 0.5), (Param::Theta(j), 0.01)])
            .collect();
        let identified = nominal.with_errors(&errors);
        let deg = std::f64::consts::PI / 180.0;
        let qs = [
            [10.0, 20.0, -30.0, 40.0, 50.0],
            [-60.0, 5.0, 70.0, -20.0, 100.0],
        ];
        let targets: Vec<Frame> = qs.iter().map(|q| nominal.fk(&q.map(|v| v * deg))).collect();
        let out = compensate_targets(&identified, &targets, false, 0.0, |q| q.to_vec()).unwrap();
        for (c, t) in out.iter().zip(&targets) {
            assert_eq!(c.flag, "ok", "{c:?}");
            assert!(c.residual_mm < 1e-6, "{c:?}");
            assert!(c.residual_deg > 0.0 && c.residual_deg < 5.0, "{c:?}");
            assert!(identified.within_limits(&c.q), "{c:?}");
            let f = identified.fk(&c.q);
            assert!((f.pos - t.pos).norm() < 1e-6);
        }
    }
}
