//! The checks of a measurement's values, shared by the measurement files (the tracker's and
//! the other kinds', [`super::read_measurements`], [`crate::measurement::kind_csv`]) and the
//! arrays of the Python module ([`measurements_from_arrays`]): joint values within their
//! limits, coordinates and standard deviations within range, unit quaternions, payloads
//! ≥ 0, and enough distinct poses.

use super::{MAX_POINT_MM, MIN_DISTINCT_POSES, MIN_SIGMA_MM, PAYLOAD, QUAT, SIGMA, XYZ};
use crate::error::{shown, shown_converted, Error, Result};

use crate::measurement::{JointSpace, Measurements};
use crate::numeric::{Real, Vec3};

/// Joint values `quser` (the robot's units) of one pose converted to internal units and
/// checked: finite after the conversion and within the limits (`lim`: the limits in the
/// robot's units, for the message). A refusal is (the joint's index, message).
pub(crate) fn check_joints(
    robot: &(impl JointSpace + ?Sized),
    quser: &[Real],
    lim: (&[Real], &[Real]),
) -> std::result::Result<Vec<Real>, (usize, String)> {
    let q = robot.q_from_user(quser);
    for (j, v) in q.iter().enumerate() {
        if !v.is_finite() {
            return Err((
                j,
                format!(
                    "{} overflows: it is {v} in internal units (mm or rad); the joint \
                     limits are [{}, {}]",
                    shown(quser[j]),
                    lim.0[j],
                    lim.1[j]
                ),
            ));
        }
        let (lo, hi) = robot.limits(j);
        if *v < lo - 1e-9 || *v > hi + 1e-9 {
            return Err((
                j,
                format!(
                    "{} is outside the joint limits [{}, {}]",
                    shown_converted(quser[j]),
                    lim.0[j],
                    lim.1[j]
                ),
            ));
        }
    }
    Ok(q)
}

/// A measured coordinate (mm) within ±[`MAX_POINT_MM`].
pub(crate) fn check_coordinate(v: Real) -> std::result::Result<(), String> {
    if v.abs() > MAX_POINT_MM {
        return Err(format!(
            "{} mm is out of range: a measured coordinate must be within \
             ±{MAX_POINT_MM} mm (1 km)",
            shown_converted(v)
        ));
    }
    Ok(())
}

/// A quaternion `[qw, qx, qy, qz]` of unit length within 1e-3, normalised.
pub(super) fn unit_quaternion(qq: [Real; 4]) -> std::result::Result<[Real; 4], String> {
    let n = qq.iter().map(|v| v * v).sum::<Real>().sqrt();
    if (n - 1.0).abs() > 1e-3 {
        return Err(format!(
            "the quaternion has length {}, expected a unit quaternion",
            shown(n)
        ));
    }
    Ok(qq.map(|v| v / n))
}

/// A standard deviation (mm) within [[`MIN_SIGMA_MM`], [`MAX_POINT_MM`]].
pub(crate) fn check_sigma(v: Real) -> std::result::Result<(), String> {
    if v <= 0.0 {
        return Err(format!("{} is not a positive standard deviation", shown(v)));
    }
    if !(MIN_SIGMA_MM..=MAX_POINT_MM).contains(&v) {
        return Err(format!(
            "{} mm is out of range: a standard deviation must be within \
             [{MIN_SIGMA_MM:e}, {MAX_POINT_MM}] mm (its weight 1/σ² must not overflow)",
            shown_converted(v)
        ));
    }
    Ok(())
}

/// A payload (kg): a mass from 0 to [`MAX_MASS_KG`](crate::error::MAX_MASS_KG), as
/// everywhere a mass is read ([`not_a_mass`](crate::error::not_a_mass)).
pub(super) fn check_payload(v: Real) -> std::result::Result<(), String> {
    crate::error::not_a_mass(v).map_or(Ok(()), Err)
}

/// The setting a refusal of [`measurements_from_arrays`] names: each array its own (`q`,
/// `points`, `rotations`, `sigma`, `payload`: the arguments that gave them), or each by its
/// place in the one setting that gave them all (a tuple given as one argument:
/// `validate.points`).
#[derive(Clone, Copy, Debug)]
pub enum ArrayKeys<'a> {
    /// Each array is named by its own name.
    Own,
    /// Every array is named by its place in this one setting (`KEY.points`).
    All(&'a str),
}

impl ArrayKeys<'_> {
    /// The setting that names `array`.
    pub fn of(self, array: &str) -> String {
        match self {
            ArrayKeys::Own => array.to_string(),
            ArrayKeys::All(key) => format!("{key}.{array}"),
        }
    }
}

/// The array a column of a measurement belongs to: the joint values, the point's
/// coordinates, the orientation's quaternion, the standard deviation or the payload.
fn array_of(column: &str) -> &'static str {
    if XYZ.contains(&column) {
        "points"
    } else if QUAT.contains(&column) {
        "rotations"
    } else if column == SIGMA {
        "sigma"
    } else if column == PAYLOAD {
        "payload"
    } else {
        "q"
    }
}

/// Measured poses given as arrays rather than a file (the Python module's `identify`):
/// joint values in the robot's units, points in mm, optional unit quaternions
/// `[qw, qx, qy, qz]`, standard deviations (mm) and payloads (kg), one per pose. Every value
/// is checked as a measurement CSV's ([`super::read_measurements`]), a refusal naming the
/// array's setting (`keys`), the row (0-based) and the column.
pub fn measurements_from_arrays(
    robot: &(impl JointSpace + ?Sized),
    keys: ArrayKeys<'_>,
    qs: &[Vec<Real>],
    points: &[[Real; 3]],
    quats: Option<&[[Real; 4]]>,
    sigma_mm: Option<&[Real]>,
    payload_kg: Option<&[Real]>,
) -> Result<Measurements> {
    let n = qs.len();
    let bad = |array: &str, msg: String| Error::setting(keys.of(array), msg);
    let lengths = [
        ("points", Some(points.len())),
        ("rotations", quats.map(<[_]>::len)),
        ("sigma", sigma_mm.map(<[_]>::len)),
        ("payload", payload_kg.map(<[_]>::len)),
    ];
    for (name, len) in lengths {
        if let Some(len) = len.filter(|&l| l != n) {
            return Err(bad(
                name,
                format!("{n} joint vectors but {len} rows of {name}"),
            ));
        }
    }
    if n == 0 {
        return Err(bad("q", "no poses".into()));
    }
    let dof = robot.dof();
    let (lim_lo, lim_hi) = user_limits(robot);
    // A one-dimensional array has no columns to name.
    let at = |i: usize, column: &str, msg: String| match array_of(column) {
        array @ ("sigma" | "payload") => bad(array, format!("row {i}: {msg}")),
        array => bad(array, format!("row {i}, column {column}: {msg}")),
    };
    let finite = |i: usize, column: &str, v: Real| {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(at(i, column, format!("{v} is not a finite number")))
        }
    };
    let mut m = Measurements {
        quats: quats.map(|_| Vec::with_capacity(n)),
        sigma_mm: sigma_mm.map(<[_]>::to_vec),
        payload_kg: payload_kg.map(<[_]>::to_vec),
        ..Measurements::default()
    };
    for (i, quser) in qs.iter().enumerate() {
        m.qs.push(joint_row(
            robot,
            &keys.of("q"),
            i,
            quser,
            (&lim_lo, &lim_hi),
        )?);
        for (k, &v) in points[i].iter().enumerate() {
            check_coordinate(finite(i, XYZ[k], v)?).map_err(|msg| at(i, XYZ[k], msg))?;
        }
        m.points.push(Vec3::from(points[i]));
        if let (Some(all), Some(out)) = (quats, m.quats.as_mut()) {
            for (k, &v) in all[i].iter().enumerate() {
                finite(i, QUAT[k], v)?;
            }
            out.push(unit_quaternion(all[i]).map_err(|msg| at(i, "qw", msg))?);
        }
        if let Some(s) = sigma_mm {
            check_sigma(finite(i, SIGMA, s[i])?).map_err(|msg| at(i, SIGMA, msg))?;
        }
        if let Some(p) = payload_kg {
            check_payload(finite(i, PAYLOAD, p[i])?).map_err(|msg| at(i, PAYLOAD, msg))?;
        }
    }
    let rows: Vec<u64> = (0..n as u64).collect();
    if distinct_poses(&m.qs, &rows, dof).is_err() {
        return Err(bad(
            "q",
            format!(
                "fewer than {MIN_DISTINCT_POSES} distinct poses among the {n} rows: the \
                 frame cannot be registered nor anything identified"
            ),
        ));
    }
    Ok(m)
}

/// Joint values given as an array rather than a file (the Python module's
/// `identifiability`), in the robot's units: each row checked as a measurement CSV's
/// ([`super::read_measurements`]), a refusal naming the setting `what`, the row (0-based)
/// and the column. Returns internal units.
pub fn joint_rows_from_arrays(
    robot: &(impl JointSpace + ?Sized),
    what: &str,
    qs: &[Vec<Real>],
) -> Result<Vec<Vec<Real>>> {
    let (lim_lo, lim_hi) = user_limits(robot);
    qs.iter()
        .enumerate()
        .map(|(i, quser)| joint_row(robot, what, i, quser, (&lim_lo, &lim_hi)))
        .collect()
}

/// Row `i` of joint values `quser` (the robot's units) given as an array: as many as the
/// robot has joints, finite and within the limits (`lim`, the robot's units); returns
/// internal units, a refusal naming the setting `what`, the row and the column.
fn joint_row(
    robot: &(impl JointSpace + ?Sized),
    what: &str,
    i: usize,
    quser: &[Real],
    lim: (&[Real], &[Real]),
) -> Result<Vec<Real>> {
    let dof = robot.dof();
    if quser.len() != dof {
        return Err(Error::joint_count(
            what,
            format_args!("row {i}"),
            quser.len(),
            dof,
        ));
    }
    let at = |column: &str, msg: String| {
        Error::setting(what, format!("row {i}, column {column}: {msg}"))
    };
    if let Some(j) = quser.iter().position(|v| !v.is_finite()) {
        let v = quser[j];
        return Err(at(
            &format!("q{}", j + 1),
            format!("{v} is not a finite number"),
        ));
    }
    check_joints(robot, quser, lim).map_err(|(j, msg)| at(&format!("q{}", j + 1), msg))
}

/// The joint limits in the robot's units (for messages): (lower, upper), to 12 significant
/// digits, so that the trip through radians shows a limit of 120° as `120`, not
/// `119.99999999999999`.
pub(crate) fn user_limits(robot: &(impl JointSpace + ?Sized)) -> (Vec<Real>, Vec<Real>) {
    let dof = robot.dof();
    let shown = |v: Real| format!("{v:.11e}").parse::<Real>().unwrap_or(v);
    let side = |k: fn((Real, Real)) -> Real| {
        let user = robot.q_to_user(&(0..dof).map(|j| k(robot.limits(j))).collect::<Vec<_>>());
        user.into_iter().map(shown).collect::<Vec<_>>()
    };
    (side(|l| l.0), side(|l| l.1))
}

/// Refuses rows of fewer than [`MIN_DISTINCT_POSES`] distinct poses (`qs`, read from the
/// file's `lines`): (the first data line, message).
pub(crate) fn distinct_poses(
    qs: &[Vec<Real>],
    lines: &[u64],
    dof: usize,
) -> std::result::Result<(), (u64, String)> {
    let mut first: Vec<usize> = Vec::new();
    for (i, q) in qs.iter().enumerate() {
        let seen = first
            .iter()
            .any(|&k| qs[k].iter().zip(q).all(|(a, b)| a.to_bits() == b.to_bits()));
        if !seen {
            first.push(i);
            if first.len() >= MIN_DISTINCT_POSES {
                return Ok(());
            }
        }
    }
    let at = |i: usize| lines.get(i).copied().unwrap_or(0);
    let rows = qs.len();
    let span = format!("lines {} to {}", at(0), at(rows - 1));
    let what = if first.len() == 1 {
        if rows == 1 {
            format!("the file has one row (line {}), one pose", at(0))
        } else {
            format!(
                "all {rows} rows ({span}) are the same pose, the joint values of line {}",
                at(0)
            )
        }
    } else {
        let seen: Vec<String> = first.iter().map(|&i| at(i).to_string()).collect();
        format!(
            "the {rows} rows ({span}) hold only {} distinct poses, first seen on lines {}",
            first.len(),
            seen.join(" and ")
        )
    };
    Err((
        at(0),
        format!(
            "{what}: a measurement needs at least {MIN_DISTINCT_POSES} distinct poses (rows \
             of distinct q1…q{dof}): the instrument frame is registered on at least three \
             points not on a line, and the poses of a calibration must move the joints"
        ),
    ))
}
