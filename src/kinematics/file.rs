//! Robot files (FORMATS.md, "Robot file"): reading with every value checked, and writing.

use std::fmt::Write as _;
use std::path::Path;

use serde::Deserialize;

use super::{AngleUnit, Convention, Coupling, Joint, JointType, LengthUnit, Param, Robot, Units};
use crate::error::{Error, Result};
use crate::math::Real;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotFile {
    name: String,
    convention: String,
    length_unit: String,
    angle_unit: String,
    joints: Vec<JointEntry>,
    base: Option<PartEntry>,
    tool: Option<PartEntry>,
    coupling: Option<CouplingEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JointEntry {
    #[serde(rename = "type")]
    kind: String,
    alpha: Real,
    a: Real,
    d: Real,
    theta: Real,
    beta: Option<Real>,
    limits: Vec<Real>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PartEntry {
    xyz: Option<Vec<Real>>,
    rpy: Option<Vec<Real>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CouplingEntry {
    kind: String,
    l1: Real,
}

/// Parses and checks a robot file's text. `path` is used in messages only.
///
/// Refuses, naming the file, the joint and the key: TOML errors, missing and unknown keys, an
/// unknown convention, unit or joint type, non-finite numbers, `limits` that are not two
/// increasing numbers, and a non-zero `beta` in a `dh` robot.
pub fn parse_robot_file(text: &str, path: &Path) -> Result<Robot> {
    let f: RobotFile =
        toml::from_str(text).map_err(|e| Error::file(path, "TOML", e.to_string().trim_end()))?;
    let err = |place: String, msg: String| Error::file(path, place, msg);
    let convention = match f.convention.as_str() {
        "dh" => Convention::Dh,
        "dh_beta" => Convention::DhBeta,
        "mdh" => Convention::Mdh,
        other => {
            return Err(err(
                "convention".into(),
                format!("unknown convention \"{other}\"; allowed: \"dh\", \"dh_beta\", \"mdh\""),
            ))
        }
    };
    let length = match f.length_unit.as_str() {
        "mm" => LengthUnit::Mm,
        "m" => LengthUnit::M,
        other => {
            return Err(err(
                "length_unit".into(),
                format!("unknown unit \"{other}\"; allowed: \"mm\", \"m\""),
            ))
        }
    };
    let angle = match f.angle_unit.as_str() {
        "deg" => AngleUnit::Deg,
        "rad" => AngleUnit::Rad,
        other => {
            return Err(err(
                "angle_unit".into(),
                format!("unknown unit \"{other}\"; allowed: \"deg\", \"rad\""),
            ))
        }
    };
    let units = Units { length, angle };
    let (lu, au) = (units.length_to_mm(), units.angle_to_rad());
    if f.joints.is_empty() {
        return Err(err(
            "joints".into(),
            "a robot needs at least one [[joints]] entry".into(),
        ));
    }
    if f.joints.len() > 16 {
        return Err(err(
            "joints".into(),
            "at most 16 joints are supported".into(),
        ));
    }
    let coupling = match &f.coupling {
        None => None,
        Some(c) => {
            if c.kind != "differential" {
                return Err(err(
                    "coupling.kind".into(),
                    format!("unknown coupling \"{}\"; allowed: \"differential\"", c.kind),
                ));
            }
            if !(c.l1.is_finite() && c.l1 > 0.0) {
                return Err(err(
                    "coupling.l1".into(),
                    format!("must be a finite length > 0, got {}", c.l1),
                ));
            }
            Some(Coupling::Differential { l1_mm: c.l1 * lu })
        }
    };
    let n = f.joints.len();
    let mut values = vec![0.0; 5 * n + 12];
    let mut joints = Vec::with_capacity(n);
    for (j, e) in f.joints.iter().enumerate() {
        let place = |key: &str| format!("joint {} (joints[{j}]), key `{key}`", j + 1);
        let kind = match e.kind.as_str() {
            "revolute" => JointType::Revolute,
            "prismatic" => JointType::Prismatic,
            other => {
                return Err(err(
                    place("type"),
                    format!("unknown joint type \"{other}\"; allowed: \"revolute\", \"prismatic\""),
                ))
            }
        };
        for (key, v) in [
            ("alpha", e.alpha),
            ("a", e.a),
            ("d", e.d),
            ("theta", e.theta),
        ]
        .into_iter()
        .chain(e.beta.map(|b| ("beta", b)))
        {
            if !v.is_finite() {
                return Err(err(place(key), format!("must be a finite number, got {v}")));
            }
        }
        let beta = e.beta.unwrap_or(0.0);
        if convention == Convention::Dh && beta != 0.0 {
            return Err(err(
                place("beta"),
                "convention \"dh\" has no β; use \"dh_beta\" or \"mdh\"".into(),
            ));
        }
        if e.limits.len() != 2 {
            return Err(err(
                place("limits"),
                format!("must be [lower, upper], got {} values", e.limits.len()),
            ));
        }
        let (lo, hi) = (e.limits[0], e.limits[1]);
        if !(lo.is_finite() && hi.is_finite()) {
            return Err(err(place("limits"), "limits must be finite numbers".into()));
        }
        if lo >= hi {
            return Err(err(
                place("limits"),
                format!("lower limit {lo} must be below upper limit {hi}"),
            ));
        }
        let coupled = coupling.is_some() && j < 2;
        let qf = if coupled || kind == JointType::Prismatic {
            lu
        } else {
            au
        };
        joints.push(Joint {
            kind,
            limits: (lo * qf, hi * qf),
        });
        values[Param::Theta(j).index(n)] = e.theta * au;
        values[Param::D(j).index(n)] = e.d * lu;
        values[Param::A(j).index(n)] = e.a * lu;
        values[Param::Alpha(j).index(n)] = e.alpha * au;
        values[Param::Beta(j).index(n)] = beta * au;
    }
    if let Some(Coupling::Differential { .. }) = coupling {
        if n < 2 || joints[0].kind != JointType::Revolute || joints[1].kind != JointType::Prismatic
        {
            return Err(err(
                "coupling".into(),
                "a differential coupling drives a revolute joint 1 and a prismatic joint 2".into(),
            ));
        }
    }
    for (name, part, make) in [
        ("base", &f.base, Param::Base as fn(usize) -> Param),
        ("tool", &f.tool, Param::Tool),
    ] {
        let Some(part) = part else { continue };
        for (key, vals, factor, offset) in [("xyz", &part.xyz, lu, 0), ("rpy", &part.rpy, au, 3)] {
            let Some(vals) = vals else { continue };
            if vals.len() != 3 || vals.iter().any(|v| !v.is_finite()) {
                return Err(err(
                    format!("{name}.{key}"),
                    format!("must be three finite numbers, got {vals:?}"),
                ));
            }
            for (c, v) in vals.iter().enumerate() {
                values[make(offset + c).index(n)] = v * factor;
            }
        }
    }
    Ok(Robot {
        name: f.name,
        convention,
        joints,
        values,
        units,
        coupling,
    })
}

/// Rounds away the last bits of unit conversions (deg → rad → deg) for printing.
fn tidy(v: Real) -> Real {
    let r = (v * 1e12).round() / 1e12;
    if (r - v).abs() <= 1e-9 * v.abs().max(1.0) {
        r
    } else {
        v
    }
}

fn num(v: Real) -> String {
    let v = tidy(v);
    let s = format!("{v:?}");
    if s == "-0.0" {
        "0.0".into()
    } else {
        s
    }
}

/// Writes a robot as a robot file in its own units; [`parse_robot_file`] reads it back.
pub fn robot_to_toml(robot: &Robot) -> String {
    let n = robot.dof();
    let (lu, au) = (robot.units.length_to_mm(), robot.units.angle_to_rad());
    let mut s = String::new();
    let _ = writeln!(s, "name = \"{}\"", robot.name);
    let _ = writeln!(s, "convention = \"{}\"", robot.convention.as_str());
    let _ = writeln!(
        s,
        "length_unit = \"{}\"",
        if robot.units.length == LengthUnit::Mm {
            "mm"
        } else {
            "m"
        }
    );
    let _ = writeln!(
        s,
        "angle_unit = \"{}\"",
        if robot.units.angle == AngleUnit::Deg {
            "deg"
        } else {
            "rad"
        }
    );
    if let Some(Coupling::Differential { l1_mm }) = robot.coupling {
        let _ = writeln!(
            s,
            "\n# Joints 1 and 2 take the travels of two differential screws (length unit):\n\
             # joint 1 turns by atan((q1 - q2) / l1), joint 2 moves by (q1 + q2) / 2.\n\
             [coupling]\nkind = \"differential\"\nl1 = {}",
            num(l1_mm / lu)
        );
    }
    for (j, joint) in robot.joints.iter().enumerate() {
        let g = |p: Param| robot.values[p.index(n)];
        let coupled = robot.coupling.is_some() && j < 2;
        let qf = if coupled || joint.kind == JointType::Prismatic {
            lu
        } else {
            au
        };
        let _ = writeln!(s, "\n[[joints]]");
        let _ = writeln!(
            s,
            "type = \"{}\"",
            if joint.kind == JointType::Revolute {
                "revolute"
            } else {
                "prismatic"
            }
        );
        let _ = writeln!(s, "alpha = {}", num(g(Param::Alpha(j)) / au));
        let _ = writeln!(s, "a = {}", num(g(Param::A(j)) / lu));
        let _ = writeln!(s, "d = {}", num(g(Param::D(j)) / lu));
        let _ = writeln!(s, "theta = {}", num(g(Param::Theta(j)) / au));
        if robot.convention.has_beta() {
            let _ = writeln!(s, "beta = {}", num(g(Param::Beta(j)) / au));
        }
        let _ = writeln!(
            s,
            "limits = [{}, {}]",
            num(joint.limits.0 / qf),
            num(joint.limits.1 / qf)
        );
    }
    for (name, make) in [
        ("base", Param::Base as fn(usize) -> Param),
        ("tool", Param::Tool),
    ] {
        let v: Vec<Real> = (0..6).map(|c| robot.values[make(c).index(n)]).collect();
        let _ = writeln!(
            s,
            "\n[{name}]\nxyz = [{}, {}, {}]\nrpy = [{}, {}, {}]",
            num(v[0] / lu),
            num(v[1] / lu),
            num(v[2] / lu),
            num(v[3] / au),
            num(v[4] / au),
            num(v[5] / au)
        );
    }
    s
}

/// Reads and checks a robot file.
pub fn read_robot_file(path: &Path) -> Result<Robot> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_robot_file(&text, path)
}
