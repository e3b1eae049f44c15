//! Joint configurations for measurement: in a region of joint space or of the workspace, or
//! from a pose-list file.

use std::collections::HashSet;
use std::path::Path;

use rand::Rng as _;

use super::settings::Region;
use crate::error::{Error, Result};
use crate::numeric::rng::Rng;
use crate::numeric::Real;
use crate::robot::sampling::{poses_in_box, uniform_joint_poses};
use crate::robot::Robot;

/// Tries allowed per requested pose when sampling a box, on top of [`BOX_TRIES_MIN`].
pub const BOX_TRIES_PER_POSE: usize = 5_000;
/// Minimum number of tries when sampling a box.
pub const BOX_TRIES_MIN: usize = 200_000;

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
///   `BOX_TRIES_MIN + BOX_TRIES_PER_POSE · n` tries, after which the box is refused as
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
        Region::Joint => Ok(uniform_joint_poses(robot, n, rng)),
        Region::Box { center_mm, size_mm } => {
            let tries = BOX_TRIES_MIN + BOX_TRIES_PER_POSE * n;
            let out = poses_in_box(robot, n, *center_mm, *size_mm, tries, rng);
            if out.len() < n {
                return Err(Error::setting(
                    key,
                    format!(
                        "only {} of {n} poses found with the tool point in the box centred at \
                         {center_mm:?} mm of size {size_mm:?} mm after {tries} random tries: the \
                         box is (nearly) out of reach of robot \"{}\"",
                        out.len(),
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
    let table = crate::measurement::csv::read_table(path, robot, false)?;
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
    fn joint_region_is_within_limits() {
        let r = crate::robot::builtin::irb2600();
        let qs = sample_region(&r, &Region::Joint, 100, &mut stream(2, "p")).unwrap();
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
