//! The commands behind the `calbench` binary, one function each. They print to stdout and
//! write files; `main.rs` only parses arguments and reports errors.

use serde_json::json;

use crate::error::{Error, Result};
use crate::identifiability::analyse;
use crate::jacobian::Measure;
use crate::kinematics::robot_to_toml;
use crate::math::Real;
use crate::robots::{self, BUILTINS};

/// `calbench robots [NAME]`.
pub fn robots(name: Option<&str>) -> Result<()> {
    match name {
        None => {
            for b in BUILTINS {
                println!("{:<12} {}", b.name, b.summary);
            }
            Ok(())
        }
        Some(n) => {
            let b = robots::builtin(n).ok_or_else(|| {
                let names: Vec<&str> = BUILTINS.iter().map(|b| b.name).collect();
                Error::setting(
                    "NAME",
                    format!("no built-in robot \"{n}\"; built-ins: {}", names.join(", ")),
                )
            })?;
            print!("# {}\n{}", b.summary, robot_to_toml(&(b.build)()));
            Ok(())
        }
    }
}

/// Parses a comma-separated list of numbers (joint values) for a robot with `dof` joints.
pub fn parse_q(text: &str, dof: usize) -> Result<Vec<Real>> {
    let q: Vec<Real> = text
        .split(',')
        .map(|s| {
            s.trim()
                .parse::<Real>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    Error::setting("--q", format!("\"{}\" is not a finite number", s.trim()))
                })
        })
        .collect::<Result<_>>()?;
    if q.len() != dof {
        return Err(Error::setting(
            "--q",
            format!(
                "the robot has {dof} joints but {} values were given",
                q.len()
            ),
        ));
    }
    Ok(q)
}

/// Parses `position` / `pose`.
pub fn parse_measure(text: &str) -> Result<Measure> {
    match text {
        "position" => Ok(Measure::Position),
        "pose" => Ok(Measure::Pose),
        other => Err(Error::setting(
            "--measure",
            format!("\"{other}\"; allowed: position, pose"),
        )),
    }
}

/// `calbench fk --robot R --q … [--json]`.
pub fn fk(robot: &str, q: &str, json: bool) -> Result<()> {
    let robot = robots::load(robot)?;
    let q = robot.q_from_user(&parse_q(q, robot.dof())?);
    let f = robot.fk(&q);
    let rot: Vec<[Real; 3]> = (0..3)
        .map(|i| [f.rot[(i, 0)], f.rot[(i, 1)], f.rot[(i, 2)]])
        .collect();
    if json {
        println!(
            "{}",
            json!({"position_mm": [f.pos.x, f.pos.y, f.pos.z], "rotation": rot})
        );
    } else {
        println!(
            "position (mm): {:.6} {:.6} {:.6}",
            f.pos.x, f.pos.y, f.pos.z
        );
        println!("rotation:");
        for r in rot {
            println!("  {:>10.6} {:>10.6} {:>10.6}", r[0], r[1], r[2]);
        }
    }
    if !robot.within_limits(&q) {
        eprintln!("warning: the joint values lie outside the robot's joint limits");
    }
    Ok(())
}

/// `calbench identifiability --robot R --measure M --poses N --seed S [--json]`.
pub fn identifiability(
    robot: &str,
    measure: &str,
    poses: usize,
    seed: u64,
    json: bool,
) -> Result<()> {
    let robot = robots::load(robot)?;
    let measure = parse_measure(measure)?;
    if poses == 0 {
        return Err(Error::setting("--poses", "must be at least 1"));
    }
    let mut rng = crate::rng::stream(seed, "identifiability");
    let qs = crate::sampling::uniform_joint_poses(&robot, poses, &mut rng);
    let a = analyse(&robot, &robot.params(), &qs, measure);
    let names =
        |v: &[crate::kinematics::Param]| v.iter().map(|p| p.to_string()).collect::<Vec<_>>();
    if json {
        let groups: Vec<Vec<String>> = a.groups.iter().map(|g| names(g)).collect();
        println!(
            "{}",
            json!({
                "rank": a.rank,
                "identifiable": names(&a.identifiable),
                "unidentifiable": names(&a.unidentifiable),
                "groups": groups,
                "condition_number": a.condition_number,
            })
        );
    } else {
        println!("robot {} ({} poses, {:?})", robot.name, poses, measure);
        println!("rank {} of {} parameters", a.rank, robot.params().len());
        println!("identifiable:   {}", names(&a.identifiable).join(" "));
        println!("unidentifiable: {}", names(&a.unidentifiable).join(" "));
        for g in &a.groups {
            println!("dependent group: {}", names(g).join(" "));
        }
        println!(
            "condition number (column-scaled): {:.4e}",
            a.condition_number
        );
    }
    Ok(())
}
