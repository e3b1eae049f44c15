//! Robot files (docs/formats.md, "Robot file"): reading with every value checked, and writing.

use std::fmt::Write as _;
use std::path::Path;

use serde::Deserialize;

use super::{
    joint_place, to_internal, value_count, AngleUnit, Convention, Coupling, Joint, JointType,
    LengthUnit, Param, Quantity, Robot, Units, GRAVITY_POINTS, HARMONIC_TERMS, MAX_JOINTS,
};
use crate::error::{read_text, Error, Result};
use crate::numeric::Real;

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
    beta_joints: Option<Vec<i64>>,
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
    /// Mass of the link this joint moves, kg (all joints or none).
    mass_kg: Option<Real>,
    /// Joint compliance, rad/(N·m) whatever the file's units (default 0: rigid).
    compliance: Option<Real>,
    /// Joint-angle harmonic coefficients `[a, b]` or `[a, b, c, d]`, rad whatever the file's
    /// units: `Δq = a sin q + b cos q + c sin 2q + d cos 2q` (default none).
    harmonics: Option<Vec<Real>>,
    /// Coefficients of the mass-free gravity basis (elbow, wrist centre, tool point), rad per
    /// N·m of a 1 N weight ([`crate::robot::gravity_basis`]).
    gravity: Option<Vec<Real>>,
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
/// unknown convention, unit or joint type, `limits` that are not two numbers, a non-zero
/// `beta` in a `dh` robot, and every value that is not finite or out of range *after* its
/// conversion to mm and rad (see [`Robot::check`]: a length of `1e308` m is infinite in mm
/// and refused), including limits whose lower value is not below the upper one.
///
/// A refusal of a value names its line too (`line 14, joint 2 (joints[1]), key \`a\``) where
/// the file writes the key, else of its joint's table (a key missing on one joint); TOML
/// errors carry their own line and column.
pub fn parse_robot_file(text: &str, path: &Path) -> Result<Robot> {
    parse_robot_text(text, path).map_err(|e| match e {
        Error::File { file, place, msg } if !place.starts_with("line ") => {
            let key = key_of_place(&place);
            let joint = key.rsplit_once('.').filter(|(j, _)| j.ends_with(']'));
            let line = crate::error::toml_key_line(text, &key)
                .or_else(|| crate::error::toml_key_line(text, joint?.0));
            Error::file(file, crate::error::at_line(line, place), msg)
        }
        other => other,
    })
}

/// The dotted key of a place as robot-file messages name it: `joint 2 (joints[1]), key \`a\``
/// is `joints[1].a`; `base.xyz`, `coupling.l1` and other keys are themselves.
fn key_of_place(place: &str) -> String {
    let joint = place
        .split_once(" (")
        .and_then(|(_, rest)| rest.split_once("), key `"))
        .and_then(|(at, key)| Some(format!("{at}.{}", key.strip_suffix('`')?)));
    joint.unwrap_or_else(|| place.to_string())
}

fn parse_robot_text(text: &str, path: &Path) -> Result<Robot> {
    let f: RobotFile = crate::error::toml_keys(path, text)?;
    let err = |place: String, msg: String| Error::file(path, place, msg);
    if f.name.trim().is_empty() {
        let msg = "is empty: it names the robot in reports, and `identify` names the \
                   compensated robot `<name>-calibrated`";
        return Err(err("name".into(), msg.into()));
    }
    if f.name.chars().any(crate::error::is_hidden) {
        let msg = "must be a name without control characters (bidirectional overrides \
                   included): it names the robot in reports, on the terminal and in a URDF";
        return Err(err("name".into(), msg.into()));
    }
    use crate::robot::names::parse_in;
    let convention: Convention = parse_in(path, "convention", &f.convention)?;
    let length: LengthUnit = parse_in(path, "length_unit", &f.length_unit)?;
    let angle: AngleUnit = parse_in(path, "angle_unit", &f.angle_unit)?;
    let units = Units { length, angle };
    let (lu, au) = (units.length_to_mm(), units.angle_to_rad());
    let (lname, aname) = (units.length_name(), units.angle_name());
    // Every number goes through here: converted to mm / rad, then checked.
    let conv = |place: &dyn Fn() -> String, quantity: Quantity, raw: Real| -> Result<Real> {
        let (factor, unit) = match quantity {
            Quantity::Length => (lu, lname),
            Quantity::Angle | Quantity::JointAngle => (au, aname),
        };
        to_internal(quantity, raw, factor, unit).map_err(|m| err(place(), m))
    };
    if f.joints.is_empty() {
        return Err(err(
            "joints".into(),
            "a robot needs at least one [[joints]] entry".into(),
        ));
    }
    if f.joints.len() > MAX_JOINTS {
        return Err(err(
            "joints".into(),
            format!("at most {MAX_JOINTS} joints are supported"),
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
            let l1 = conv(&|| "coupling.l1".into(), Quantity::Length, c.l1)?;
            if l1 <= 0.0 {
                return Err(err(
                    "coupling.l1".into(),
                    format!("must be a length > 0, got {:?} {lname}", c.l1),
                ));
            }
            Some(Coupling::Differential { l1_mm: l1 })
        }
    };
    let n = f.joints.len();
    let mut values = vec![0.0; value_count(n)];
    let mut joints = Vec::with_capacity(n);
    for (j, e) in f.joints.iter().enumerate() {
        let kind: JointType = parse_in(path, &joint_place(j, "type"), &e.kind)?;
        let beta = e.beta.unwrap_or(0.0);
        for (key, p, quantity, raw) in [
            ("alpha", Param::Alpha(j), Quantity::Angle, e.alpha),
            ("a", Param::A(j), Quantity::Length, e.a),
            ("d", Param::D(j), Quantity::Length, e.d),
            ("theta", Param::Theta(j), Quantity::Angle, e.theta),
            ("beta", Param::Beta(j), Quantity::Angle, beta),
        ] {
            values[p.index(n)] = conv(&|| joint_place(j, key), quantity, raw)?;
        }
        if convention == Convention::Dh && beta != 0.0 {
            return Err(err(
                joint_place(j, "beta"),
                "convention \"dh\" has no β; use \"dh_beta\" or \"mdh\"".into(),
            ));
        }
        if e.limits.len() != 2 {
            return Err(err(
                joint_place(j, "limits"),
                format!("must be [lower, upper], got {} values", e.limits.len()),
            ));
        }
        let coupled = coupling.is_some() && j < 2;
        let (quantity, unit) = if coupled || kind == JointType::Prismatic {
            (Quantity::Length, lname)
        } else {
            (Quantity::JointAngle, aname)
        };
        let place = || joint_place(j, "limits");
        let lo = conv(&place, quantity, e.limits[0])?;
        let hi = conv(&place, quantity, e.limits[1])?;
        if lo >= hi {
            return Err(err(
                place(),
                format!(
                    "lower limit {:?} {unit} must be below upper limit {:?} {unit}",
                    e.limits[0], e.limits[1]
                ),
            ));
        }
        joints.push(Joint {
            kind,
            limits: (lo, hi),
        });
        // A prismatic joint is rigid and takes no angle: the three keys of a joint's rotation
        // are refused on it even at zero, as they are refused at any other value.
        let revolute_only = [
            ("compliance", e.compliance.is_some()),
            ("harmonics", e.harmonics.is_some()),
            ("gravity", e.gravity.is_some()),
        ];
        let given = (revolute_only.iter().find(|(_, given)| *given))
            .filter(|_| kind == JointType::Prismatic);
        if let Some((key, _)) = given {
            let msg = format!(
                "is for a revolute joint, and joint {} is prismatic (it translates rigidly: no \
                 compliance, no joint-angle harmonics, no gravity basis)",
                j + 1
            );
            return Err(err(joint_place(j, key), msg));
        }
        values[Param::Compliance(j).index(n)] = e.compliance.unwrap_or(0.0);
        if let Some(h) = &e.harmonics {
            if h.is_empty() || h.len() % 2 != 0 || h.len() > HARMONIC_TERMS {
                return Err(err(
                    joint_place(j, "harmonics"),
                    format!(
                        "must be [a1, b1, a2, b2, …] (rad): sine and cosine of each order from \
                         1, at most order {}, got {} values",
                        HARMONIC_TERMS / 2,
                        h.len()
                    ),
                ));
            }
            for (k, v) in h.iter().enumerate() {
                values[Param::Harmonic(j, k).index(n)] = *v;
            }
        }
        if let Some(g) = &e.gravity {
            if g.len() != GRAVITY_POINTS {
                return Err(err(
                    joint_place(j, "gravity"),
                    format!(
                        "must be [elbow, wrist, tool] (rad per N·m), got {} values",
                        g.len()
                    ),
                ));
            }
            for (l, v) in g.iter().enumerate() {
                values[Param::Gravity(j, l).index(n)] = *v;
            }
        }
    }
    let link_mass_kg = match f.joints.iter().filter(|e| e.mass_kg.is_some()).count() {
        0 => None,
        k if k == n => Some(f.joints.iter().filter_map(|e| e.mass_kg).collect()),
        _ => {
            let j = f
                .joints
                .iter()
                .position(|e| e.mass_kg.is_none())
                .unwrap_or(0);
            return Err(err(
                joint_place(j, "mass_kg"),
                "give `mass_kg` on every joint or on none".into(),
            ));
        }
    };
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
        for (key, vals, quantity, offset) in [
            ("xyz", &part.xyz, Quantity::Length, 0),
            ("rpy", &part.rpy, Quantity::Angle, 3),
        ] {
            let Some(vals) = vals else { continue };
            let place = || format!("{name}.{key}");
            if vals.len() != 3 {
                return Err(err(
                    place(),
                    format!("must be three numbers, got {} values", vals.len()),
                ));
            }
            for (c, &v) in vals.iter().enumerate() {
                values[make(offset + c).index(n)] = conv(&place, quantity, v)?;
            }
        }
    }
    let beta_joints = match &f.beta_joints {
        None => None,
        Some(list) => {
            if !convention.has_beta() {
                return Err(err(
                    "beta_joints".into(),
                    "convention \"dh\" has no β; use \"dh_beta\" or \"mdh\"".into(),
                ));
            }
            let mut out: Vec<usize> = Vec::with_capacity(list.len());
            for &j in list {
                let within = j >= 1 && (j as usize) <= n;
                if !within || out.contains(&(j as usize - 1)) {
                    let msg = match within {
                        true => format!("lists joint {j} twice: each joint carries β once"),
                        false => format!("must list joint numbers from 1 to {n}, got {j}"),
                    };
                    return Err(err("beta_joints".into(), msg));
                }
                out.push(j as usize - 1);
            }
            for (j, e) in f.joints.iter().enumerate() {
                if !out.contains(&j) && e.beta.is_some_and(|b| b != 0.0) {
                    return Err(err(
                        joint_place(j, "beta"),
                        format!("joint {} is not in `beta_joints` and carries no β", j + 1),
                    ));
                }
            }
            Some(out)
        }
    };
    let robot = Robot {
        name: f.name,
        convention,
        joints,
        values,
        units,
        coupling,
        beta_joints,
        link_mass_kg,
    };
    // Everything above was checked value by value in the file's units; this is the same
    // check on the assembled model, so the two cannot drift apart.
    robot.check().map_err(|i| err(i.place, i.msg))?;
    Ok(robot)
}

/// `value` (mm, rad or kg inside calbench) in a file unit of `factor` mm or rad per unit,
/// as a robot file writes it. It is rounded to 12 decimals, which takes away the last bits
/// of a unit conversion (`89.99999999999999` is written `90.0`), only where the rounded
/// number reads back as the same `value`; elsewhere every digit is written. So tidying never
/// changes the robot: −π/2 rad is written `-1.5707963267948966`, a compliance of 1e-7 with
/// all its digits.
fn num(value: Real, factor: Real) -> String {
    // Where the division rounded, a neighbour of the quotient may be the number that reads
    // back as `value` (`raw * factor`, as [`to_internal`] reads it).
    let q = value / factor;
    let exact = [q, q.next_down(), q.next_up()]
        .into_iter()
        .find(|v| v * factor == value)
        .unwrap_or(q);
    let rounded = (exact * 1e12).round() / 1e12;
    let v = if rounded * factor == exact * factor {
        rounded
    } else {
        exact
    };
    let s = format!("{v:?}");
    if s == "-0.0" {
        "0.0".into()
    } else {
        s
    }
}

/// `text` as a TOML basic string, quoted and escaped, so any name reads back as itself.
fn toml_string(text: &str) -> String {
    let mut s = String::with_capacity(text.len() + 2);
    s.push('"');
    for c in text.chars() {
        match c {
            '"' => s.push_str("\\\""),
            '\\' => s.push_str("\\\\"),
            '\n' => s.push_str("\\n"),
            '\t' => s.push_str("\\t"),
            '\r' => s.push_str("\\r"),
            c if c.is_control() => {
                let _ = write!(s, "\\u{:04X}", c as u32);
            }
            c => s.push(c),
        }
    }
    s.push('"');
    s
}

/// Writes a robot as a robot file in its own units; [`parse_robot_file`] reads it back as
/// the same robot, value for value: numbers are tidied only where tidying changes nothing
/// read (`num`).
pub fn robot_to_toml(robot: &Robot) -> String {
    let n = robot.dof();
    let (lu, au) = (robot.units.length_to_mm(), robot.units.angle_to_rad());
    let mut s = String::new();
    let _ = writeln!(s, "name = {}", toml_string(&robot.name));
    let _ = writeln!(s, "convention = \"{}\"", robot.convention.as_str());
    let _ = writeln!(s, "length_unit = \"{}\"", robot.units.length_name());
    let _ = writeln!(s, "angle_unit = \"{}\"", robot.units.angle_name());
    if let (true, Some(bj)) = (robot.convention.has_beta(), &robot.beta_joints) {
        let list: Vec<String> = bj.iter().map(|j| (j + 1).to_string()).collect();
        let _ = writeln!(s, "beta_joints = [{}]", list.join(", "));
    }
    if let Some(Coupling::Differential { l1_mm }) = robot.coupling {
        let _ = writeln!(
            s,
            "\n# Joints 1 and 2 take the travels of two differential screws (length unit):\n\
             # joint 1 turns by atan((q1 - q2) / l1), joint 2 moves by (q1 + q2) / 2.\n\
             [coupling]\nkind = \"differential\"\nl1 = {}",
            num(l1_mm, lu)
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
        let _ = writeln!(s, "type = \"{}\"", <&str>::from(joint.kind));
        let _ = writeln!(s, "alpha = {}", num(g(Param::Alpha(j)), au));
        let _ = writeln!(s, "a = {}", num(g(Param::A(j)), lu));
        let _ = writeln!(s, "d = {}", num(g(Param::D(j)), lu));
        let _ = writeln!(s, "theta = {}", num(g(Param::Theta(j)), au));
        if robot.carries_beta(j) {
            let _ = writeln!(s, "beta = {}", num(g(Param::Beta(j)), au));
        }
        let _ = writeln!(
            s,
            "limits = [{}, {}]",
            num(joint.limits.0, qf),
            num(joint.limits.1, qf)
        );
        if let Some(m) = &robot.link_mass_kg {
            let _ = writeln!(s, "mass_kg = {}", num(m[j], 1.0));
        }
        let c = g(Param::Compliance(j));
        if c != 0.0 {
            let _ = writeln!(s, "compliance = {}", num(c, 1.0));
        }
        // Harmonic coefficients: every order up to the highest non-zero one.
        let h: Vec<Real> = (0..HARMONIC_TERMS)
            .map(|k| g(Param::Harmonic(j, k)))
            .collect();
        let used = h
            .iter()
            .rposition(|v| *v != 0.0)
            .map_or(0, |k| 2 * (k / 2 + 1));
        if used > 0 {
            let list: Vec<String> = h[..used].iter().map(|v| num(*v, 1.0)).collect();
            let _ = writeln!(s, "harmonics = [{}]", list.join(", "));
        }
        let k: Vec<Real> = (0..GRAVITY_POINTS)
            .map(|l| g(Param::Gravity(j, l)))
            .collect();
        if k.iter().any(|v| *v != 0.0) {
            let list: Vec<String> = k.iter().map(|v| num(*v, 1.0)).collect();
            let _ = writeln!(s, "gravity = [{}]", list.join(", "));
        }
    }
    for (name, make) in [
        ("base", Param::Base as fn(usize) -> Param),
        ("tool", Param::Tool),
    ] {
        let v: Vec<Real> = (0..6).map(|c| robot.values[make(c).index(n)]).collect();
        let _ = writeln!(
            s,
            "\n[{name}]\nxyz = [{}, {}, {}]\nrpy = [{}, {}, {}]",
            num(v[0], lu),
            num(v[1], lu),
            num(v[2], lu),
            num(v[3], au),
            num(v[4], au),
            num(v[5], au)
        );
    }
    s
}

/// Reads and checks a robot file.
pub fn read_robot_file(path: &Path) -> Result<Robot> {
    let text = read_text(path)?;
    parse_robot_file(&text, path)
}

impl Robot {
    /// The decimals that write joint `j`'s value in the file's unit as finely as 9 decimals of
    /// a degree (revolute) or a millimetre (prismatic) do: 9 in degrees and millimetres, 11 in
    /// radians, 12 in metres.
    pub fn q_decimals(&self, j: usize) -> usize {
        let kind = self.joints[j].kind;
        let per_unit = self.q_factor(j, kind);
        let finest = if self.q_is_length(j, kind) {
            1.0
        } else {
            1.0_f64.to_radians()
        };
        // A decimal more per factor of ten between the unit and the finest one, within the
        // rounding of the conversion factors (no library logarithm: docs/architecture.md).
        let (mut size, mut decimals) = (per_unit / finest, 9);
        while size > 1.0 + 1e-9 {
            size /= 10.0;
            decimals += 1;
        }
        decimals
    }
}

#[cfg(test)]
mod tests;
