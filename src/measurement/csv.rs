//! The measurement CSV (docs/formats.md): a header `q1,…,qn,x,y,z` (full-pose data adds
//! `qw,qx,qy,qz`), then one row per pose: joint values in the robot file's units, the
//! measured point in mm in the instrument's frame and the unit quaternion of the measured
//! frame; optional columns `sigma_mm` (the point's standard deviation) and `payload_kg` (the
//! payload at the tool point during the measurement). A real tracker export in this shape
//! loads exactly like a simulated one.
//!
//! Reading accepts the columns in any order (matched by header name), blank lines and
//! `#` comment lines; it refuses a missing or unknown column, a row with the wrong number
//! of fields, a value that is not a finite number, a joint value that overflows in internal
//! units (mm, rad) or lies outside the limits, a measured coordinate beyond ±[`MAX_POINT_MM`],
//! a standard deviation outside [[`MIN_SIGMA_MM`], [`MAX_POINT_MM`]] and a quaternion that is
//! not of unit length (within 1e-3; it is then normalised), naming the file, the line and the
//! column. A measurement CSV with fewer than [`MIN_DISTINCT_POSES`] distinct poses is refused
//! too, naming its data lines: it can neither be registered nor identify anything.

mod checks;

use std::fmt::Write as _;
use std::path::Path;

use crate::error::{Error, Result};
use crate::measurement::rows::{at_line, number, Rows};
use crate::measurement::{JointSpace, Measurements};
use crate::numeric::{Real, Vec3};

pub(crate) use checks::{check_coordinate, check_joints, check_sigma, distinct_poses, user_limits};
use checks::{check_payload, unit_quaternion};
pub use checks::{joint_rows_from_arrays, measurements_from_arrays, ArrayKeys};

const QUAT: [&str; 4] = ["qw", "qx", "qy", "qz"];
const XYZ: [&str; 3] = ["x", "y", "z"];
/// The optional per-point standard deviation column (mm).
const SIGMA: &str = "sigma_mm";
/// The optional per-pose payload column (kg).
const PAYLOAD: &str = "payload_kg";

/// The largest measured coordinate (and standard deviation) read, in mm: 1 km, the bound of a
/// robot file's lengths. Beyond it a coordinate is an export error, and its square (in a
/// registration or a residual) could overflow.
pub const MAX_POINT_MM: Real = 1e6;

/// The smallest standard deviation read, in mm: the last decimal [`write_measurements`]
/// writes; below it the weight `1/σ²` of the point could overflow.
pub const MIN_SIGMA_MM: Real = 1e-9;

/// The fewest distinct poses (rows of distinct joint values) a measurement CSV may hold: the
/// instrument frame is registered on at least three points not on a line, and the poses of a
/// calibration must move the joints.
pub const MIN_DISTINCT_POSES: usize = 3;

/// Writes `m` as a measurement CSV. Numbers have a fixed format (joint values as finely as 9
/// decimals of a degree or a millimetre, 9 decimals for points, 12 for quaternions), so equal
/// measurements give identical bytes.
pub fn write_measurements(
    path: &Path,
    robot: &(impl JointSpace + ?Sized),
    m: &Measurements,
) -> Result<()> {
    let mut s = String::with_capacity(64 * (m.qs.len() + 1));
    let optional = (
        m.quats.is_some(),
        m.sigma_mm.is_some(),
        m.payload_kg.is_some(),
    );
    header(&mut s, robot.dof(), optional);
    for (i, q) in m.qs.iter().enumerate() {
        joint_cells(&mut s, robot, q);
        s.push(',');
        let p = of_pose(&m.points, i, m.qs.len(), "points")?;
        let _ = write!(s, "{},{},{}", fixed(p.x, 9), fixed(p.y, 9), fixed(p.z, 9));
        if let Some(qs) = &m.quats {
            for v in of_pose(qs, i, m.qs.len(), "quaternions")? {
                let _ = write!(s, ",{}", fixed(*v, 12));
            }
        }
        if let Some(sd) = &m.sigma_mm {
            let v = of_pose(sd, i, m.qs.len(), "standard deviations")?;
            let _ = write!(s, ",{}", fixed(*v, 9));
        }
        if let Some(pl) = &m.payload_kg {
            let v = of_pose(pl, i, m.qs.len(), "payloads")?;
            let _ = write!(s, ",{}", fixed(*v, 6));
        }
        s.push('\n');
    }
    std::fs::write(path, s).map_err(|e| Error::io(path, e))
}

/// Entry `i` of a per-pose column `v` (`what`, plural) of a measurement of `poses` poses;
/// an error when the column is shorter.
fn of_pose<'a, T>(v: &'a [T], i: usize, poses: usize, what: &str) -> Result<&'a T> {
    v.get(i).ok_or_else(|| {
        Error::Compute(format!(
            "measurement has {poses} poses but {} {what}",
            v.len()
        ))
    })
}

/// Writes a pose list (the measurement CSV without the measured columns): `q1..qn` in the
/// robot's units, in the same fixed format as [`write_measurements`], so the poses a
/// measurement of this list records are the very values of the list.
pub fn write_pose_list(
    path: &Path,
    robot: &(impl JointSpace + ?Sized),
    qs: &[Vec<Real>],
) -> Result<()> {
    let mut s = String::with_capacity(16 * robot.dof() * (qs.len() + 1));
    joint_header(&mut s, robot.dof());
    s.push('\n');
    for q in qs {
        joint_cells(&mut s, robot, q);
        s.push('\n');
    }
    std::fs::write(path, s).map_err(|e| Error::io(path, e))
}

/// The header line of a measurement file (docs/formats.md § 5): `q1…qN,x,y,z`, then those of
/// the optional columns that are present: `(qw,qx,qy,qz, sigma_mm, payload_kg)`.
pub(crate) fn header(s: &mut String, dof: usize, (quats, sigma, payload): (bool, bool, bool)) {
    joint_header(s, dof);
    s.push_str(",x,y,z");
    for (present, columns) in [
        (quats, ",qw,qx,qy,qz"),
        (sigma, ",sigma_mm"),
        (payload, ",payload_kg"),
    ] {
        if present {
            s.push_str(columns);
        }
    }
    s.push('\n');
}

pub(crate) fn joint_header(s: &mut String, dof: usize) {
    let names: Vec<String> = (1..=dof).map(|j| format!("q{j}")).collect();
    s.push_str(&names.join(","));
}

/// The joint values `q` (internal units) as the file writes them: in the robot's units, each
/// as finely as 9 decimals of a degree or a millimetre ([`JointSpace::decimals`]: 11 in
/// radians, 12 in metres), where 9 decimals of a radian held a point of a 1 m arm to 5e-7 mm.
pub(crate) fn joint_cells(s: &mut String, robot: &(impl JointSpace + ?Sized), q: &[Real]) {
    let cells: Vec<String> = robot
        .q_to_user(q)
        .iter()
        .enumerate()
        .map(|(j, &v)| fixed(v, robot.decimals(j)))
        .collect();
    s.push_str(&cells.join(","));
}

/// `v` with `d` decimals, negative zero written as zero.
pub fn fixed(v: Real, d: usize) -> String {
    let t = format!("{v:.d$}");
    if t.starts_with('-') && t[1..].bytes().all(|b| b == b'0' || b == b'.') {
        t[1..].to_string()
    } else {
        t
    }
}

/// Reads a measurement CSV for `robot` (see the module docs for what is refused).
pub fn read_measurements(path: &Path, robot: &(impl JointSpace + ?Sized)) -> Result<Measurements> {
    read_table(path, robot, true, true).map(|(m, _)| m)
}

/// [`read_measurements`], with the line of the file each data row was read from (`#` comment
/// and blank lines counted), by which a refusal names a reading.
pub fn read_measurements_at_lines(
    path: &Path,
    robot: &(impl JointSpace + ?Sized),
) -> Result<(Measurements, Vec<u64>)> {
    read_table(path, robot, true, true)
}

/// Reads `text`, a measurement CSV for `robot` held in memory (an export as its mapping
/// reads it, [`super::import::import_text`]), as [`read_measurements`] reads a file; refusals
/// name `path`.
pub fn read_measurements_text(
    path: &Path,
    text: String,
    robot: &(impl JointSpace + ?Sized),
) -> Result<Measurements> {
    let rows = Rows::of_text(path, text, "q1,…,qn,x,y,z")?;
    table_of(rows, path, robot, true, true).map(|(m, _)| m)
}

/// Cartesian targets have no joints.
struct NoJoints;

impl JointSpace for NoJoints {
    fn name(&self) -> &str {
        "targets"
    }
    fn dof(&self) -> usize {
        0
    }
    fn q_to_user(&self, q: &[Real]) -> Vec<Real> {
        q.to_vec()
    }
    fn q_from_user(&self, q: &[Real]) -> Vec<Real> {
        q.to_vec()
    }
    fn limits(&self, _: usize) -> (Real, Real) {
        (0.0, 0.0)
    }
}

/// Reads a CSV of Cartesian tool targets (`compensate --targets`): the measurement CSV's
/// columns without the joints, `x,y,z` (mm) and optionally `qw,qx,qy,qz`, in the robot's base
/// frame. Refused like a measurement file (unknown or missing columns, bad values, by line).
pub fn read_targets(path: &Path) -> Result<Measurements> {
    read_table(path, &NoJoints, true, true).map(|(m, _)| m)
}

/// Reads a measurement CSV (`measured`) or a pose list (measured columns optional and
/// ignored), refusing with `distinct` fewer than [`MIN_DISTINCT_POSES`] distinct poses; with
/// the line of each row.
pub(crate) fn read_table(
    path: &Path,
    robot: &(impl JointSpace + ?Sized),
    measured: bool,
    distinct: bool,
) -> Result<(Measurements, Vec<u64>)> {
    // The header an empty file lacks: a pose list's joints, a target list's point.
    let expected = match (robot.dof(), measured) {
        (0, _) => "x,y,z",
        (_, true) => "q1,…,qn,x,y,z",
        (_, false) => "q1,…,qn",
    };
    table_of(Rows::open(path, expected)?, path, robot, measured, distinct)
}

/// The measurements (or poses, unless `measured`) of the rows `t` of `path`, of at least
/// [`MIN_DISTINCT_POSES`] distinct poses with `distinct`, and the line of each row.
fn table_of(
    mut t: Rows,
    path: &Path,
    robot: &(impl JointSpace + ?Sized),
    measured: bool,
    distinct: bool,
) -> Result<(Measurements, Vec<u64>)> {
    let (names, header_line) = (t.names.clone(), t.header_line);
    let bad = |line: u64, place: &str, msg: String| at_line(path, line, place, msg);
    let dof = robot.dof();
    let qnames: Vec<String> = (1..=dof).map(|j| format!("q{j}")).collect();
    let find = |n: &str| names.iter().position(|h| h == n);
    let known = |n: &str| {
        qnames.iter().any(|q| q == n)
            || XYZ.contains(&n)
            || QUAT.contains(&n)
            || n == SIGMA
            || n == PAYLOAD
    };
    // Targets (no joints) name only the Cartesian columns.
    let joints = if dof == 0 {
        String::new()
    } else {
        format!("q1…q{dof}, ")
    };
    let expected = format!("{joints}x, y, z and optionally qw, qx, qy, qz, sigma_mm, payload_kg");
    t.check_columns(known, &expected)?;
    let missing = |n: &str| {
        bad(
            header_line,
            "",
            match dof {
                // A target list: no robot's joints.
                0 => format!("missing column \"{n}\" (a target list has {expected})"),
                _ => format!(
                    "missing column \"{n}\" (robot \"{}\" has {dof} joints)",
                    robot.name()
                ),
            },
        )
    };
    let qcol: Vec<usize> = qnames
        .iter()
        .map(|n| find(n).ok_or_else(|| missing(n)))
        .collect::<Result<_>>()?;
    let (xcol, qtcol) = if measured {
        let x: Vec<usize> = XYZ
            .iter()
            .map(|n| find(n).ok_or_else(|| missing(n)))
            .collect::<Result<_>>()?;
        let present = QUAT.iter().filter(|n| find(n).is_some()).count();
        let q = match present {
            0 => None,
            4 => Some(QUAT.iter().filter_map(|n| find(n)).collect::<Vec<usize>>()),
            _ => {
                let n = QUAT
                    .iter()
                    .find(|n| find(n).is_none())
                    .copied()
                    .unwrap_or("qw");
                let msg = format!(
                    "missing column \"{n}\" (an orientation is the four columns qw, qx, qy, \
                     qz, or none of them)"
                );
                return Err(bad(header_line, "", msg));
            }
        };
        (x, q)
    } else {
        (Vec::new(), None)
    };
    let sigma_col = if measured { find(SIGMA) } else { None };
    let payload_col = find(PAYLOAD);
    let mut payload = Vec::new();
    let mut sigma = Vec::new();
    let mut qs = Vec::new();
    let mut lines = Vec::new();
    let mut points = Vec::new();
    let mut quats = Vec::new();
    let mut rec = ::csv::StringRecord::new();
    let mut quser = vec![0.0; dof];
    let (lim_lo, lim_hi) = user_limits(robot);
    while let Some(line) = t.next(&mut rec)? {
        let num = |c: usize| number(&rec, &names, c).map_err(|(p, m)| bad(line, &p, m));
        for (j, &c) in qcol.iter().enumerate() {
            quser[j] = num(c)?;
        }
        let q = check_joints(robot, &quser, (&lim_lo, &lim_hi))
            .map_err(|(j, msg)| bad(line, &format!(", column q{}", j + 1), msg))?;
        qs.push(q);
        lines.push(line);
        if measured {
            let mut p = [0.0; 3];
            for (k, &c) in xcol.iter().enumerate() {
                p[k] = num(c)?;
                check_coordinate(p[k])
                    .map_err(|msg| bad(line, &format!(", column {}", XYZ[k]), msg))?;
            }
            points.push(Vec3::from(p));
        }
        if let Some(qc) = &qtcol {
            let mut qq = [0.0; 4];
            for (k, &c) in qc.iter().enumerate() {
                qq[k] = num(c)?;
            }
            quats.push(unit_quaternion(qq).map_err(|msg| bad(line, ", column qw", msg))?);
        }
        if let Some(c) = sigma_col {
            let v = num(c)?;
            check_sigma(v).map_err(|msg| bad(line, &format!(", column {SIGMA}"), msg))?;
            sigma.push(v);
        }
        if let Some(c) = payload_col {
            let v = num(c)?;
            check_payload(v).map_err(|msg| bad(line, &format!(", column {PAYLOAD}"), msg))?;
            payload.push(v);
        }
    }
    if qs.is_empty() {
        return Err(bad(
            header_line,
            "",
            "the file has a header but no data rows".into(),
        ));
    }
    if distinct && dof > 0 {
        distinct_poses(&qs, &lines, dof).map_err(|(place, msg)| bad(place, "", msg))?;
    }
    let m = Measurements {
        qs,
        points,
        quats: qtcol.map(|_| quats),
        sigma_mm: sigma_col.map(|_| sigma),
        payload_kg: payload_col.map(|_| payload),
    };
    Ok((m, lines))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::stream;
    use crate::robot::sampling::uniform_joint_poses;
    use crate::robot::Robot;
    use crate::sim::{measure_poses, MeasureSetting, Tracker, TrackerSettings};
    use approx::assert_relative_eq;

    fn tmp(name: &str) -> std::path::PathBuf {
        let d = crate::test_dir("sim-csv");
        d.join(name)
    }

    fn measurement(pose: bool) -> (Robot, Measurements) {
        let r = crate::robot::builtin::tx60();
        let qs = uniform_joint_poses(&r, 12, &mut stream(1, "poses"));
        let t = Tracker::new(&TrackerSettings {
            measure: if pose {
                MeasureSetting::Pose
            } else {
                MeasureSetting::Position
            },
            angle_noise_deg: if pose { 0.01 } else { 0.0 },
            ..Default::default()
        })
        .unwrap();
        let m = measure_poses(&r, &qs, &t, None, None, None, &mut stream(1, "noise")).unwrap();
        (r, m.data)
    }

    #[test]
    fn write_read_roundtrip() {
        for pose in [false, true] {
            let (r, m) = measurement(pose);
            let p = tmp(&format!("rt-{pose}.csv"));
            write_measurements(&p, &r, &m).unwrap();
            let d = read_measurements(&p, &r).unwrap();
            assert_eq!(d.qs.len(), m.qs.len());
            for i in 0..m.qs.len() {
                for j in 0..6 {
                    // 1e-9 degree written.
                    assert_relative_eq!(d.qs[i][j], m.qs[i][j], epsilon = 1e-10);
                }
                assert_relative_eq!(d.points[i], m.points[i], epsilon = 1e-9);
            }
            assert_eq!(d.quats.is_some(), pose);
            if let (Some(a), Some(b)) = (&d.quats, &m.quats) {
                for (x, y) in a.iter().zip(b) {
                    for k in 0..4 {
                        assert_relative_eq!(x[k], y[k], epsilon = 1e-11);
                    }
                }
            }
            // Rewriting what was read gives the same bytes.
            let again = d.clone();
            let p2 = tmp(&format!("rt2-{pose}.csv"));
            write_measurements(&p2, &r, &again).unwrap();
            assert_eq!(std::fs::read(&p).unwrap(), std::fs::read(&p2).unwrap());
            // The pose list reader takes the same file.
            let ql = crate::sim::poses::read_pose_list(&p, &r).unwrap();
            assert_eq!(ql.len(), m.qs.len());
        }
        let (r, m) = measurement(false);
        let text = std::fs::read_to_string(tmp("rt-false.csv")).unwrap();
        assert!(text.starts_with("q1,q2,q3,q4,q5,q6,x,y,z\n"));
        assert_eq!(text.lines().count(), m.qs.len() + 1);
        let _ = r;
    }

    /// The error reading `text` from a file of its own (tests run in parallel threads of one
    /// process: a shared name let one test read another's file).
    fn read_err(text: impl AsRef<[u8]>) -> String {
        static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let name = format!(
            "bad-{}.csv",
            N.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
        );
        let p = tmp(&name);
        std::fs::write(&p, text).unwrap();
        let e = read_measurements(&p, &crate::robot::builtin::irb2600()).unwrap_err();
        let s = e.to_string();
        assert!(s.contains(&name), "{s}");
        s
    }

    #[test]
    fn standard_deviations_round_trip_and_must_be_positive() {
        let (r, mut m) = measurement(false);
        m.sigma_mm = Some((0..m.len()).map(|i| 0.01 + 0.001 * i as Real).collect());
        let p = tmp("sigma.csv");
        write_measurements(&p, &r, &m).unwrap();
        let d = read_measurements(&p, &r).unwrap();
        let (a, b) = (d.sigma_mm.unwrap(), m.sigma_mm.unwrap());
        for (x, y) in a.iter().zip(&b) {
            assert_relative_eq!(*x, *y, epsilon = 1e-12);
        }
        let h = "q1,q2,q3,q4,q5,q6,x,y,z,sigma_mm\n";
        let s = read_err(format!("{h}0,0,0,0,0,0,1,2,3,0.01\n0,0,0,0,0,0,1,2,3,-1\n"));
        assert!(s.contains("line 3") && s.contains("column sigma_mm"), "{s}");
    }

    #[test]
    fn bad_lines_are_named() {
        let h = "q1,q2,q3,q4,q5,q6,x,y,z\n";
        let ok = "0,0,0,0,0,0,1,2,3\n";
        let s = read_err(format!("{h}{ok}{ok}0,0,0,zero,0,0,1,2,3\n"));
        assert!(
            s.contains("line 4") && s.contains("column q4") && s.contains("zero"),
            "{s}"
        );
        let s = read_err(format!("{h}{ok}0,0,0,0,0,0,1,NaN,3\n"));
        assert!(s.contains("line 3") && s.contains("column y"), "{s}");
        let s = read_err(format!("{h}{ok}0,0,0,0,0,1,2,3\n"));
        assert!(s.contains("line 3") && s.contains("8 fields"), "{s}");
        let s = read_err("q1,q2,q3,q4,q5,x,y,z\n");
        assert!(s.contains("missing column \"q6\""), "{s}");
        let s = read_err("q1,q2,q3,q4,q5,q6,x,y,z,w\n");
        assert!(s.contains("unknown column \"w\""), "{s}");
        let s = read_err(format!("{h}0,400,0,0,0,0,1,2,3\n"));
        assert!(
            s.contains("line 2") && s.contains("column q2") && s.contains("limits"),
            "{s}"
        );
        let s = read_err("q1,q2,q3,q4,q5,q6,x,y,z,qw,qx,qy,qz\n0,0,0,0,0,0,1,2,3,1,1,0,0\n");
        assert!(s.contains("line 2") && s.contains("unit quaternion"), "{s}");
        let s = read_err("q1,q2,q3,q4,q5,q6,x,y,z,qw,qx\n");
        assert!(
            s.contains("missing column \"qy\" (an orientation is the four"),
            "{s}"
        );
        // A target list names what a target list has, not a robot of no joints.
        let targets =
            std::env::temp_dir().join(format!("calbench-targets-{}.csv", std::process::id()));
        std::fs::write(&targets, "x,y\n1,2\n").unwrap();
        let s = read_targets(&targets).unwrap_err().to_string();
        std::fs::remove_file(&targets).unwrap();
        assert!(
            s.contains("line 1: missing column \"z\" (a target list has x, y, z"),
            "{s}"
        );
        // A payload is a mass from 0 to 100 000 kg, as everywhere a mass is read.
        for kg in ["-1", "100001", "1e9"] {
            let s =
                read_err(format!("{h}0,0,0,0,0,0,1,2,3,{kg}\n").replace(",z\n", ",z,payload_kg\n"));
            assert!(
                s.contains("line 2, column payload_kg: must be a mass from 0 to 100000 kg"),
                "{s}"
            );
        }
        // A cell or a header name that is not UTF-8 (a Latin-1 export) is named by its column.
        let s = read_err(b"q1,q2,q3,q4,q5,q6,x,y,z\n0,0,\xe9,0,0,0,1,2,3\n");
        assert!(s.contains("line 2, column q3: not UTF-8 text"), "{s}");
        let s = read_err(b"# from the tracker\nq1,q2,q3,q4,q5,q\xe96,x,y,z\n");
        assert!(s.contains("line 2, column 6: not UTF-8 text"), "{s}");
        // One endless line is refused, not read into memory whole.
        let s = read_err(vec![b'0'; 3 << 20]);
        assert!(s.contains("line 1 is longer than 1 MiB"), "{s}");
    }

    #[test]
    fn columns_in_any_order_with_comments_and_blank_lines() {
        let p = tmp("order.csv");
        std::fs::write(
            &p,
            "# exported\nx,y,z,q1,q2,q3,q4,q5,q6\n\n1,2,3,10,20,30,40,50,60\n\
             # more\n1,2,3,11,20,30,40,50,60\n1,2,3,12,20,30,40,50,60\n",
        )
        .unwrap();
        let r = crate::robot::builtin::irb2600();
        let d = read_measurements(&p, &r).unwrap();
        assert_eq!(d.points, vec![Vec3::new(1.0, 2.0, 3.0); 3]);
        assert_relative_eq!(d.qs[0][5], 60f64.to_radians(), epsilon = 1e-15);
    }

    #[test]
    fn the_header_line_is_named_after_comments() {
        let s = read_err("# exported by the tracker\n\nq1,q2,q3,q4,q5,q6,x,y,z,w\n");
        assert!(s.contains("line 3, column 10"), "{s}");
    }

    #[test]
    fn too_few_distinct_poses_are_refused_naming_the_lines() {
        let h = "q1,q2,q3,q4,q5,q6,x,y,z\n";
        let row = |q1: u32| format!("{q1},10,20,30,40,50,1000,200,300\n");
        let s = read_err(format!("{h}{}{}# again\n{}", row(1), row(1), row(1)));
        assert!(
            s.contains("line 2: all 3 rows (lines 2 to 5) are the same pose"),
            "{s}"
        );
        assert!(s.contains("at least 3 distinct poses"), "{s}");
        let s = read_err(format!("{h}{}{}{}{}", row(1), row(2), row(1), row(2)));
        assert!(
            s.contains("line 2: the 4 rows (lines 2 to 5) hold only 2 distinct poses, first seen on lines 2 and 3"),
            "{s}"
        );
        let s = read_err(format!("{h}{}", row(1)));
        assert!(s.contains("line 2: the file has one row (line 2)"), "{s}");
        // Three distinct poses are enough, whatever repeats.
        let p = tmp("three.csv");
        std::fs::write(&p, format!("{h}{}{}{}{}", row(1), row(1), row(2), row(3))).unwrap();
        let d = read_measurements(&p, &crate::robot::builtin::irb2600()).unwrap();
        assert_eq!(d.len(), 4);
        // A pose list is a list of commands: repeats are allowed.
        let ql = crate::sim::poses::read_pose_list(&p, &crate::robot::builtin::irb2600());
        assert_eq!(ql.unwrap().len(), 4);
    }

    #[test]
    fn values_that_overflow_are_refused_naming_line_and_column() {
        let h = "q1,q2,q3,q4,q5,q6,x,y,z,sigma_mm\n";
        let ok = "0,0,0,0,0,0,1,2,3,0.01\n1,0,0,0,0,0,1,2,3,0.01\n2,0,0,0,0,0,1,2,3,0.01\n";
        for (row, column) in [
            ("3,0,0,0,0,0,1,1e400,3,0.01", "column y"),
            ("3,0,0,0,0,0,1,1e308,3,0.01", "column y"),
            ("3,0,0,0,0,0,-2e6,0,3,0.01", "column x"),
            ("3,0,0,0,0,0,1,2,3,1e-200", "column sigma_mm"),
            ("3,0,0,0,0,0,1,2,3,1e300", "column sigma_mm"),
            ("1e400,0,0,0,0,0,1,2,3,0.01", "column q1"),
        ] {
            let s = read_err(format!("{h}{ok}{row}\n"));
            assert!(s.contains(&format!("line 5, {column}")), "{row}: {s}");
        }
        // Joint values finite in metres overflow in mm.
        let mut r = crate::robot::builtin::guo_3t2r();
        r.units.length = crate::robot::LengthUnit::M;
        let p = tmp("metres.csv");
        std::fs::write(&p, "q1,q2,q3,q4,q5,x,y,z\n1e306,0,0,0,0,1,2,3\n").unwrap();
        let s = read_measurements(&p, &r).unwrap_err().to_string();
        assert!(
            s.contains("line 2, column q1") && s.contains("overflows"),
            "{s}"
        );
    }
}
