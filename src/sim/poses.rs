//! Joint configurations for measurement: in a region of joint space or of the workspace, or
//! from a pose-list file.

use std::collections::HashSet;
use std::path::Path;

use rand::Rng as _;

use super::settings::{Region, WorkspaceRegion};
use crate::error::{Error, Result};
use crate::numeric::rng::Rng;
use crate::numeric::{Real, Vec3};
use crate::robot::ik::{angle_deg, fixed_tool_axis, poses_in_workspace, WORKSPACE_TRIES_PER_POSE};
use crate::robot::sampling::{poses_in_box, reach_bound_mm, uniform_joint_poses};
use crate::robot::{Param, Robot};

/// Tries allowed per requested pose when sampling a box, on top of [`BOX_TRIES_MIN`].
pub const BOX_TRIES_PER_POSE: usize = 5_000;
/// Minimum number of tries when sampling a box.
pub const BOX_TRIES_MIN: usize = 200_000;

/// Refuses, naming `key`, a region that cannot give `n` poses, quickly and before any pose
/// is drawn (a scenario checks its regions when it is loaded):
///
/// - a `box` wholly beyond [`reach_bound_mm`] of the base origin: refused at once;
/// - a `box` in which not one of [`BOX_TRIES_MIN`] random joint configurations (a fixed
///   seed) puts the tool point: refused after that bounded search (the sampling itself gives
///   up after as many tries without a pose);
/// - a `grid` of fewer points than `n`.
pub fn check_region(robot: &Robot, region: &Region, n: usize, key: &str) -> Result<()> {
    region.check(key)?;
    match region {
        Region::Joint {} => Ok(()),
        Region::Grid { per_joint } => {
            let dof = robot.dof();
            let total = u32::try_from(dof)
                .ok()
                .and_then(|d| per_joint.checked_pow(d));
            match total {
                Some(g) if n > g => Err(Error::setting(
                    key,
                    format!(
                        "{n} poses asked for but the grid has only {per_joint}^{dof} = {g} points"
                    ),
                )),
                _ => Ok(()),
            }
        }
        Region::Workspace(w) => {
            beyond_reach(robot, &w.center_mm, &w.size_mm, key)?;
            let mut rng = crate::numeric::rng::stream(0, "reach");
            if !workspace(robot, w, 1, key, &mut rng)?.is_empty() {
                return Ok(());
            }
            if let Some(why) = untiltable(robot, w) {
                return Err(Error::setting(key, why));
            }
            let from = match &w.start {
                Some(s) => format!("its start {s:?}"),
                None => "the default start (zero joint values, clamped into the limits)".into(),
            };
            Err(Error::setting(
                key,
                format!(
                    "the workspace box centred at {:?} mm of size {:?} mm with the tool axis \
                     within {}° of {:?} is out of reach of robot \"{}\" from {from}: not one \
                     of {WORKSPACE_TRIES_PER_POSE} random targets is reached within the joint \
                     limits (the search stops there); every target's search starts there, so a \
                     `start` on the arm's branch that faces the region may reach it",
                    w.center_mm, w.size_mm, w.cone_deg, w.axis, robot.name
                ),
            ))
        }
        Region::Box { center_mm, size_mm } => {
            beyond_reach(robot, center_mm, size_mm, key)?;
            let mut rng = crate::numeric::rng::stream(0, "reach");
            let tries = (BOX_TRIES_MIN, BOX_TRIES_MIN);
            if !poses_in_box(robot, 1, *center_mm, *size_mm, tries, &mut rng).is_empty() {
                return Ok(());
            }
            Err(Error::setting(
                key,
                format!(
                    "the box centred at {center_mm:?} mm of size {size_mm:?} mm is out of \
                     reach of robot \"{}\": not one of {BOX_TRIES_MIN} random joint \
                     configurations within the limits puts the tool point in it (the search \
                     stops there)",
                    robot.name
                ),
            ))
        }
    }
}

/// Why no target of the workspace region `w` is reached when `robot` cannot tilt its tool
/// ([`fixed_tool_axis`]) and `w` asks for another axis than the one it keeps, or a cone
/// about it (whose targets' axes are drawn, so almost never that one): `None` otherwise.
fn untiltable(robot: &Robot, w: &WorkspaceRegion) -> Option<String> {
    let z = fixed_tool_axis(robot)?;
    let axis = Vec3::from(w.axis).normalize();
    let off_deg = angle_deg(&z, &axis);
    if w.cone_deg == 0.0 && off_deg <= 1e-6 {
        return None;
    }
    let shown = |v: Vec3| {
        let c = v.map(|x| (x * 1e6).round() / 1e6 + 0.0);
        format!("[{}, {}, {}]", c.x, c.y, c.z)
    };
    let asked = if off_deg > w.cone_deg {
        format!("{off_deg:.1}° from the region's axis {:?}", w.axis)
    } else {
        format!(
            "and the targets' axes are drawn within {}° of {:?}, so almost none is along it",
            w.cone_deg, w.axis
        )
    };
    Some(format!(
        "robot \"{}\" cannot tilt its tool: its flange z axis is along {} at every joint \
         configuration, {asked}; a workspace region of this robot takes axis = {} and \
         cone_deg = 0",
        robot.name,
        shown(z),
        shown(z)
    ))
}

/// Up to `n` poses of the workspace region `w` ([`poses_in_workspace`]); its `start` is
/// refused, naming `key`, when it does not give one value per joint or leaves the limits.
fn workspace(
    robot: &Robot,
    w: &WorkspaceRegion,
    n: usize,
    key: &str,
    rng: &mut Rng,
) -> Result<Vec<Vec<Real>>> {
    let start = match &w.start {
        None => None,
        Some(s) if s.len() != robot.dof() => {
            return Err(Error::setting(
                key,
                format!(
                    "start has {} values but robot \"{}\" has {} joints",
                    s.len(),
                    robot.name,
                    robot.dof()
                ),
            ))
        }
        Some(s) => {
            let q = robot.q_from_user(s);
            if !robot.within_limits(&q) {
                return Err(Error::setting(
                    key,
                    format!(
                        "start {s:?} leaves the joint limits of robot \"{}\"",
                        robot.name
                    ),
                ));
            }
            Some(q)
        }
    };
    Ok(poses_in_workspace(
        robot,
        n,
        (w.center_mm, w.size_mm),
        (w.axis, w.cone_deg),
        start.as_deref(),
        rng,
    ))
}

/// Refuses, naming `key`, a box wholly beyond [`reach_bound_mm`] of the base origin.
fn beyond_reach(
    robot: &Robot,
    center_mm: &[Real; 3],
    size_mm: &[Real; 3],
    key: &str,
) -> Result<()> {
    let c = Vec3::from(*center_mm);
    let h = Vec3::from(*size_mm) / 2.0;
    let base = Vec3::new(
        robot.get(Param::Base(0)),
        robot.get(Param::Base(1)),
        robot.get(Param::Base(2)),
    );
    let nearest = Vec3::from_fn(|k, _| base[k].clamp(c[k] - h[k], c[k] + h[k]));
    let gap = (nearest - base).norm();
    let reach = reach_bound_mm(robot);
    let out_of_reach = |how: String| {
        Error::setting(
            key,
            format!(
                "the box centred at {center_mm:?} mm of size {size_mm:?} mm is out of \
                         reach of robot \"{}\": {how}",
                robot.name
            ),
        )
    };
    if gap > reach * (1.0 + 1e-9) + 1e-6 {
        return Err(out_of_reach(format!(
            "its nearest point is {gap:.1} mm from the base origin, and no tool point \
                     is farther than {reach:.1} mm (the sum of the link lengths, travels and \
                     tool offset)"
        )));
    }
    Ok(())
}

/// `n` joint configurations (internal units) in `region`, errors keyed `calibration.region`.
/// See [`sample_region_keyed`].
pub fn sample_region(
    robot: &Robot,
    region: &Region,
    n: usize,
    rng: &mut Rng,
) -> Result<Vec<Vec<Real>>> {
    sample_region_keyed(robot, region, n, "calibration.region", rng)
}

/// `n` joint configurations (internal units) in `region`:
///
/// - `joint`: uniform within the joint limits;
/// - `box`: rejection sampling ([`poses_in_box`]) of uniform joint configurations whose tool
///   point (forward kinematics of `robot`, the nominal model the planner knows) lies in the
///   axis-aligned box (Qiao 2021 §4's 1000 mm cube); at most
///   `BOX_TRIES_MIN + BOX_TRIES_PER_POSE · n` tries, and at most `BOX_TRIES_MIN` while no
///   pose is found, after which the box is refused as
///   (nearly) unreachable, naming `key`;
/// - `grid`: `per_joint` values per joint at the cell centres of each joint range, `n`
///   distinct grid points drawn at random and returned in grid order; more poses than grid
///   points are refused naming `key`.
pub fn sample_region_keyed(
    robot: &Robot,
    region: &Region,
    n: usize,
    key: &str,
    rng: &mut Rng,
) -> Result<Vec<Vec<Real>>> {
    region.check(key)?;
    match region {
        Region::Joint {} => Ok(uniform_joint_poses(robot, n, rng)),
        Region::Box { center_mm, size_mm } => {
            let tries = BOX_TRIES_MIN + BOX_TRIES_PER_POSE * n;
            let out = poses_in_box(robot, n, *center_mm, *size_mm, (tries, BOX_TRIES_MIN), rng);
            if out.len() < n {
                let t = if out.is_empty() { BOX_TRIES_MIN } else { tries };
                return Err(Error::setting(
                    key,
                    format!(
                        "only {} of {n} poses found with the tool point in the box centred at \
                         {center_mm:?} mm of size {size_mm:?} mm after {t} random tries (the \
                         search stops there): the box is (nearly) out of reach of robot \"{}\"",
                        out.len(),
                        robot.name
                    ),
                ));
            }
            Ok(out)
        }
        Region::Workspace(w) => {
            let out = workspace(robot, w, n, key, rng)?;
            if out.len() < n {
                return Err(Error::setting(
                    key,
                    format!(
                        "only {} of {n} poses found in the workspace box centred at {:?} mm of \
                         size {:?} mm with the tool axis within {}° of {:?} after {} random \
                         targets (the search stops there): the region is (nearly) out of reach \
                         of robot \"{}\"",
                        out.len(),
                        w.center_mm,
                        w.size_mm,
                        w.cone_deg,
                        w.axis,
                        WORKSPACE_TRIES_PER_POSE * n,
                        robot.name
                    ),
                ));
            }
            Ok(out)
        }
        Region::Grid { per_joint } => grid(robot, *per_joint, n, key, rng),
    }
}

fn grid(robot: &Robot, k: usize, n: usize, key: &str, rng: &mut Rng) -> Result<Vec<Vec<Real>>> {
    let dof = robot.dof();
    let total = u32::try_from(dof).ok().and_then(|d| k.checked_pow(d));
    if let Some(g) = total {
        if n > g {
            return Err(Error::setting(
                key,
                format!("{n} poses asked for but the grid has only {k}^{dof} = {g} points"),
            ));
        }
    }
    let value = |j: usize, i: usize| {
        let (lo, hi) = robot.joints[j].limits;
        lo + (hi - lo) * (i as Real + 0.5) / k as Real
    };
    // Grid points as per-joint index vectors.
    let mut picks: Vec<Vec<usize>> = match total {
        Some(g) if g <= 1_000_000 => rand::seq::index::sample(rng, g, n)
            .into_iter()
            .map(|mut idx| {
                (0..dof)
                    .map(|_| {
                        let i = idx % k;
                        idx /= k;
                        i
                    })
                    .collect()
            })
            .collect(),
        _ => {
            // A huge grid: draw indices per joint, reject repeats (rare, since n ≪ grid).
            let mut seen = HashSet::with_capacity(n);
            let mut v = Vec::with_capacity(n);
            while v.len() < n {
                let idx: Vec<usize> = (0..dof).map(|_| rng.random_range(0..k)).collect();
                if seen.insert(idx.clone()) {
                    v.push(idx);
                }
            }
            v
        }
    };
    picks.sort_unstable_by(|a, b| a.iter().rev().cmp(b.iter().rev()));
    Ok(picks
        .into_iter()
        .map(|idx| idx.iter().enumerate().map(|(j, &i)| value(j, i)).collect())
        .collect())
}

/// Reads a pose list (docs/formats.md: the measurement CSV without the measured columns): a
/// header with `q1 … qn` (measured columns `x,y,z,qw,qx,qy,qz` may follow and are ignored),
/// then one row per pose in the robot file's units. Returns internal units. A bad line, a
/// non-finite value or a value outside the joint limits is refused naming the file, the line
/// and the column.
pub fn read_pose_list(path: &Path, robot: &Robot) -> Result<Vec<Vec<Real>>> {
    let (table, _) = crate::measurement::csv::read_table(path, robot, false, false)?;
    Ok(table.qs)
}

/// A study's calibration pose list (`calibration.poses_file`): [`read_pose_list`], refusing
/// at its lines, as a measurement CSV is refused, fewer than
/// [`crate::measurement::csv::MIN_DISTINCT_POSES`] distinct poses, which every trial would
/// measure and no registration could place.
pub fn read_calibration_poses(path: &Path, robot: &Robot) -> Result<Vec<Vec<Real>>> {
    let (table, _) = crate::measurement::csv::read_table(path, robot, false, true)?;
    Ok(table.qs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::stream;

    fn key_of(e: &Error) -> &str {
        match e {
            Error::Setting { key, .. } => key,
            _ => "",
        }
    }

    /// A cube of edge `edge_mm` centred at `center_mm`.
    fn cube(center_mm: [Real; 3], edge_mm: Real) -> Region {
        Region::Box {
            center_mm,
            size_mm: [edge_mm; 3],
        }
    }

    /// The workspace region: every pose's tool point (forward kinematics, independent of the
    /// inverse kinematics that found it) lies in the box, its tool z axis within the cone, its
    /// joints within the limits; the same seed gives the same poses.
    #[test]
    fn workspace_poses_lie_in_the_box_and_the_cone() {
        let r = crate::robot::builtin::irb2600();
        let region = Region::Workspace(WorkspaceRegion {
            center_mm: [1200.0, 0.0, 900.0],
            size_mm: [1000.0, 1000.0, 800.0],
            axis: [2.0, 0.0, 0.0],
            cone_deg: 30.0,
            start: None,
        });
        check_region(&r, &region, 40, "validation.region").unwrap();
        let qs = sample_region(&r, &region, 40, &mut stream(3, "poses")).unwrap();
        assert_eq!(qs.len(), 40);
        for q in &qs {
            assert!(r.within_limits(q));
            let f = r.fk(q);
            let d = f.pos - Vec3::new(1200.0, 0.0, 900.0);
            assert!(
                d.x.abs() <= 500.0 + 1e-6 && d.y.abs() <= 500.0 + 1e-6,
                "{d:?}"
            );
            assert!(d.z.abs() <= 400.0 + 1e-6, "{d:?}");
            let angle = f.rot.column(2).dot(&Vec3::x()).clamp(-1.0, 1.0).acos();
            assert!(angle.to_degrees() <= 30.0 + 1e-6, "{}", angle.to_degrees());
        }
        let again = sample_region(&r, &region, 40, &mut stream(3, "poses")).unwrap();
        assert_eq!(qs, again);
        // Out of reach, a zero axis, a start of the wrong length: refused naming the key.
        let far = Region::Workspace(WorkspaceRegion {
            center_mm: [9000.0, 0.0, 900.0],
            size_mm: [100.0; 3],
            axis: [1.0, 0.0, 0.0],
            cone_deg: 30.0,
            start: None,
        });
        let e = check_region(&r, &far, 5, "calibration.region").unwrap_err();
        assert_eq!(key_of(&e), "calibration.region");
        // Within the reach bound but not reached from the start every search starts from: the
        // message names that start and `start`.
        let inside = Region::Workspace(WorkspaceRegion {
            center_mm: [0.0; 3],
            size_mm: [1.0; 3],
            axis: [0.0, 0.0, -1.0],
            cone_deg: 10.0,
            start: None,
        });
        let e = check_region(&r, &inside, 5, "calibration.region")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("from the default start") && e.contains("`start`"),
            "{e}"
        );
        let zero = Region::Workspace(WorkspaceRegion {
            center_mm: [1200.0, 0.0, 900.0],
            size_mm: [100.0; 3],
            axis: [0.0; 3],
            cone_deg: 30.0,
            start: None,
        });
        assert!(check_region(&r, &zero, 5, "k").is_err());
        let short = Region::Workspace(WorkspaceRegion {
            center_mm: [1200.0, 0.0, 900.0],
            size_mm: [100.0; 3],
            axis: [1.0, 0.0, 0.0],
            cone_deg: 30.0,
            start: Some(vec![0.0; 3]),
        });
        assert!(check_region(&r, &short, 5, "k").is_err());
    }

    /// Qiao 2021 §4: 50 calibration points in a 1000 mm cube centred at (550, 0, 550) mm.
    #[test]
    fn box_sampling_finds_points_in_qiaos_cube() {
        let r = crate::robot::builtin::tx60();
        let region = cube([550.0, 0.0, 550.0], 1000.0);
        let qs = sample_region(&r, &region, 50, &mut stream(1, "poses")).unwrap();
        assert_eq!(qs.len(), 50);
        for q in &qs {
            assert!(r.within_limits(q));
            let p = r.fk(q).pos;
            for k in 0..3 {
                let c = [550.0, 0.0, 550.0][k];
                assert!((p[k] - c).abs() <= 500.0, "{p}");
            }
        }
    }

    #[test]
    fn unreachable_box_is_refused_naming_the_key() {
        let r = crate::robot::builtin::tx60();
        let region = cube([5000.0, 0.0, 0.0], 100.0);
        let e = sample_region_keyed(&r, &region, 10, "validation.region", &mut stream(1, "p"))
            .unwrap_err();
        assert_eq!(key_of(&e), "validation.region");
        assert!(e.to_string().contains("out of reach"), "{e}");
        let e = sample_region(&r, &region, 10, &mut stream(1, "p")).unwrap_err();
        assert_eq!(key_of(&e), "calibration.region");
    }

    #[test]
    fn no_tool_point_lies_beyond_the_reach_bound() {
        for b in crate::robot::builtin::BUILTINS {
            let r = (b.build)();
            let base = Vec3::new(
                r.get(Param::Base(0)),
                r.get(Param::Base(1)),
                r.get(Param::Base(2)),
            );
            let reach = reach_bound_mm(&r);
            for q in uniform_joint_poses(&r, 2000, &mut stream(4, b.name)) {
                let d = (r.fk(&q).pos - base).norm();
                assert!(d <= reach, "{}: {d} mm beyond the bound {reach} mm", b.name);
            }
        }
    }

    #[test]
    fn regions_no_pose_reaches_are_refused_quickly() {
        let r = crate::robot::builtin::tx60();
        // Far beyond the reach: refused without a search.
        let far = cube([5000.0, 0.0, 550.0], 100.0);
        let t = std::time::Instant::now();
        let e = check_region(&r, &far, 50, "calibration.region").unwrap_err();
        assert!(t.elapsed().as_millis() < 50, "{:?}", t.elapsed());
        assert_eq!(key_of(&e), "calibration.region");
        assert!(
            e.to_string().contains("out of reach")
                && e.to_string().contains("no tool point is farther"),
            "{e}"
        );
        // Within reach, but too small to be hit by chance: the bounded search.
        let under = cube([300.0, 0.0, 300.0], 0.01);
        let e = check_region(&r, &under, 50, "validation.region").unwrap_err();
        assert_eq!(key_of(&e), "validation.region");
        assert!(
            e.to_string()
                .contains(&format!("not one of {BOX_TRIES_MIN}")),
            "{e}"
        );
        // The sampling gives up as soon, whatever the number of poses asked for.
        let e = sample_region(&r, &under, 100_000, &mut stream(1, "p")).unwrap_err();
        assert!(
            e.to_string()
                .contains(&format!("after {BOX_TRIES_MIN} random tries")),
            "{e}"
        );
        // Reachable regions pass; a grid of too few points does not.
        check_region(&r, &cube([550.0, 0.0, 550.0], 1000.0), 50, "k").unwrap();
        check_region(&r, &Region::Joint {}, 10, "k").unwrap();
        check_region(&r, &Region::Grid { per_joint: 2 }, 64, "k").unwrap();
        let e = check_region(&r, &Region::Grid { per_joint: 2 }, 65, "k").unwrap_err();
        assert!(e.to_string().contains("2^6 = 64 points"), "{e}");
    }

    #[test]
    fn joint_region_is_within_limits() {
        let r = crate::robot::builtin::irb2600();
        let qs = sample_region(&r, &Region::Joint {}, 100, &mut stream(2, "p")).unwrap();
        assert_eq!(qs.len(), 100);
        assert!(qs.iter().all(|q| r.within_limits(q)));
    }

    #[test]
    fn grid_points_are_distinct_cell_centres() {
        let r = crate::robot::builtin::irb2600();
        let qs =
            sample_region(&r, &Region::Grid { per_joint: 2 }, 64, &mut stream(3, "p")).unwrap();
        assert_eq!(qs.len(), 64); // the whole 2^6 grid
        for (j, joint) in r.joints.iter().enumerate() {
            let (lo, hi) = joint.limits;
            let quarter = lo + 0.25 * (hi - lo);
            let three = lo + 0.75 * (hi - lo);
            assert_eq!(
                qs.iter().filter(|q| (q[j] - quarter).abs() < 1e-12).count(),
                32
            );
            assert_eq!(
                qs.iter().filter(|q| (q[j] - three).abs() < 1e-12).count(),
                32
            );
        }
        let e =
            sample_region(&r, &Region::Grid { per_joint: 2 }, 65, &mut stream(3, "p")).unwrap_err();
        assert_eq!(key_of(&e), "calibration.region");
        // A huge grid still gives distinct points.
        let qs =
            sample_region(&r, &Region::Grid { per_joint: 50 }, 30, &mut stream(3, "p")).unwrap();
        assert_eq!(qs.len(), 30);
    }
}
