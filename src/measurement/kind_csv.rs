//! The measurement CSV of the kinds beyond the tracker (docs/formats.md § 5.3): the joint
//! columns `q1…qn` and, per kind, the reading that names it:
//!
//! | kind | columns besides `q1…qn` |
//! |---|---|
//! | `distance` from a pivot | `length_mm` |
//! | `distance` between consecutive poses | `step_mm` (empty on the first row) |
//! | `plane` | `plane` (1, 2, …), optional `offset_mm` |
//! | `sphere` | `sphere` (1, 2, …), `radius_mm`, optional `offset_mm` |
//! | `socket` | `socket` (1, 2, …), `socket_distance_mm` (the socket's distance from socket 1) |
//! | `multi-target` | `target` (1, 2, …), `x`, `y`, `z`, `target_x_mm`, `target_y_mm`, `target_z_mm`: one row per target and pose |
//!
//! and, but for targets, optionally `sigma_mm`, the reading's standard deviation. A file
//! without any of these columns is the tracker's ([`super::csv`]). Reading refuses what the
//! tracker's reader refuses (unknown, missing or repeated columns, rows of another length,
//! values that are not finite numbers, joints outside their limits, fewer than three distinct
//! poses) and what is wrong with a reading: a negative length, a plane, sphere or target
//! number that is not 1, 2, …, a numbering with gaps, a radius that is not positive or
//! changes within a sphere, a target offset that changes, a pose without every target,
//! naming the file, the line and the column.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::csv::{
    check_coordinate, check_joints, check_sigma, distinct_poses, fixed, joint_cells, joint_header,
    user_limits, MAX_POINT_MM,
};
use super::kind::{Instrument, Kind, KindData};
use super::rows::{at_line, number, Rows};
use super::JointSpace;
use crate::error::{shown, Error, Result};
use crate::numeric::{Real, Vec3};

mod named;

/// The length from the pivot (`distance`).
const LENGTH: &str = "length_mm";
/// The length from the previous row's tool point (`distance` between consecutive poses).
const STEP: &str = "step_mm";
/// The plane a row touches.
const PLANE: &str = "plane";
/// The sphere a row touches.
const SPHERE: &str = "sphere";
/// The sphere's radius.
const RADIUS: &str = "radius_mm";
/// The probe's reading at contact (0 for a touch trigger).
const OFFSET: &str = "offset_mm";
/// The reading's standard deviation.
const SIGMA: &str = "sigma_mm";
/// The socket a row's tool point is held in.
const SOCKET: &str = "socket";
/// The socket's known distance from socket 1.
const SOCKET_DISTANCE: &str = "socket_distance_mm";
/// The target a row measures (multi-target).
const TARGET: &str = "target";
/// The measured point of a target, in the tracker's frame.
const XYZ: [&str; 3] = ["x", "y", "z"];
/// A target's offset in the tool frame.
const OFFSETS: [&str; 3] = ["target_x_mm", "target_y_mm", "target_z_mm"];

/// The most planes or spheres of one file.
pub const MAX_GROUPS: usize = 1000;

/// The columns that make a file one of a kind, with its kind and whether lengths are from a
/// pivot.
const KIND_COLUMNS: [(&str, Kind); 6] = [
    (LENGTH, Kind::Distance),
    (STEP, Kind::Distance),
    (PLANE, Kind::Plane),
    (SPHERE, Kind::Sphere),
    (SOCKET, Kind::Socket),
    (TARGET, Kind::MultiTarget),
];

/// A measurement-kind file as read: the joint values, the readings and the line of each row.
#[derive(Clone, Debug, PartialEq)]
pub struct KindFile {
    /// Joint values of each row (internal units).
    pub qs: Vec<Vec<Real>>,
    /// The readings. A plane file's planes are `p[z] = c₀ + c₁ p[x] + c₂ p[y]` until the
    /// identification chooses each plane's normal axis from its points
    /// ([`super::kind::choose_plane_axes`]).
    pub data: KindData,
    /// Standard deviation of each observation (mm), when the file has `sigma_mm`.
    pub sigma_mm: Option<Vec<Real>>,
    /// The file line of each row.
    pub lines: Vec<u64>,
    /// The files of the rows when they were read from several, each with its number of rows,
    /// in row order (a socket task's placement: one file per socket, each row's line in
    /// [`Self::lines`] a line of its own file); empty when they come from one file.
    pub files: Vec<(PathBuf, usize)>,
}

impl KindFile {
    /// The pairs (earlier row, row) of rows that hold the same reading: joint values within
    /// [`super::SAME_JOINT`], the same plane, sphere or socket, and readings within
    /// [`super::SAME_POINT_MM`] (a step file's first row has none), whatever σ they carry,
    /// as [`super::Measurements::repeated_rows`] tells a tracker's: each row that repeats an
    /// earlier one, with the first it repeats, in row order.
    pub fn repeated_rows(&self) -> Vec<(usize, usize)> {
        let (n, inst) = (self.qs.len(), &self.data.instrument);
        let per = inst.rows_per_observation();
        let unread = n - inst.observations(n);
        let reading = |r: usize| (r >= unread).then(|| (r - unread) * per);
        let values = &self.data.values;
        let same = |a: usize, b: usize| {
            self.data.group.get(a) == self.data.group.get(b)
                && super::within(&self.qs[a], &self.qs[b], super::SAME_JOINT)
                && match (reading(a), reading(b)) {
                    (Some(x), Some(y)) => super::within(
                        &values[x..x + per],
                        &values[y..y + per],
                        super::SAME_POINT_MM,
                    ),
                    _ => false,
                }
        };
        // Rows sorted by their first joint value: a row's repeats follow it within the
        // tolerance.
        let first_joint = |r: usize| self.qs[r].first().copied().unwrap_or(0.0);
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| first_joint(a).total_cmp(&first_joint(b)).then(a.cmp(&b)));
        let mut first: Vec<Option<usize>> = vec![None; n];
        for (k, &a) in order.iter().enumerate() {
            let within = |b: &&usize| first_joint(**b) - first_joint(a) <= super::SAME_JOINT;
            for &b in order[k + 1..].iter().take_while(within) {
                let (lo, hi) = (a.min(b), a.max(b));
                if same(a, b) && first[hi].is_none_or(|f| lo < f) {
                    first[hi] = Some(lo);
                }
            }
        }
        (0..n).filter_map(|r| first[r].map(|f| (f, r))).collect()
    }
}

/// The kind of the measurement file at `path` by its header: `Some` when it has one of the
/// kinds' columns (docs/formats.md § 5.3), `None` for the tracker's file, and for a file
/// without a readable header, which the tracker's reader then refuses with its own words.
pub fn file_kind(path: &Path) -> Option<Kind> {
    let rows = Rows::open(path, "q1,…,qn and the measured columns").ok()?;
    KIND_COLUMNS
        .iter()
        .find(|(c, _)| rows.names.iter().any(|n| n == c))
        .map(|(_, k)| *k)
}

/// The header a measurement-kind file is expected to have, as a refusal says it.
const KIND_HEADER: &str = "q1,…,qn and length_mm, step_mm, plane, sphere or socket";

/// Reads a measurement-kind file for `robot` (see the module docs for what is refused).
pub fn read_kind_file(path: &Path, robot: &(impl JointSpace + ?Sized)) -> Result<KindFile> {
    read_kind_rows(Rows::open(path, KIND_HEADER)?, path, robot)
}

/// Reads `text`, the rows of a measurement-kind file held in memory without a header line,
/// whose columns are `names`, for `robot`; refusals name `path` and the lines of `text` (a
/// socket task's joint file, docs/formats.md § 9.4, whose own lines a refusal names).
pub fn read_kind_headerless(
    path: &Path,
    text: String,
    names: Vec<String>,
    robot: &(impl JointSpace + ?Sized),
) -> Result<KindFile> {
    read_kind_rows(Rows::headerless(path, text, names), path, robot)
}

/// [`read_kind_file`] of the rows `t`, read from `path`.
fn read_kind_rows(
    mut t: Rows,
    path: &Path,
    robot: &(impl JointSpace + ?Sized),
) -> Result<KindFile> {
    let names = t.names.clone();
    let find = |n: &str| names.iter().position(|h| h == n);
    let bad = |line: u64, column: &str, msg: String| {
        at_line(path, line, &format!(", column {column}"), msg)
    };
    let mut present = KIND_COLUMNS.iter().filter(|(c, _)| find(c).is_some());
    let Some(&(reading, kind)) = present.next() else {
        return Err(t.bad(
            t.header_line,
            "",
            "no column length_mm, step_mm, plane, sphere or socket: not a measurement-kind \
             file"
                .into(),
        ));
    };
    if let Some((other, _)) = present.next() {
        return Err(bad(
            t.header_line,
            other,
            format!("a file holds one kind of reading, and column \"{reading}\" is there too"),
        ));
    }
    if kind == Kind::MultiTarget {
        return read_targets(t, robot, path);
    }
    let dof = robot.dof();
    let qnames: Vec<String> = (1..=dof).map(|j| format!("q{j}")).collect();
    let extra: &[&str] = match reading {
        PLANE => &[OFFSET],
        SPHERE => &[RADIUS, OFFSET],
        SOCKET => &[SOCKET_DISTANCE],
        _ => &[],
    };
    let known = |n: &str| qnames.iter().any(|q| q == n) || n == reading || n == SIGMA;
    let known = |n: &str| known(n) || extra.contains(&n);
    let optional: Vec<&str> = extra
        .iter()
        .copied()
        .filter(|c| *c != RADIUS && *c != SOCKET_DISTANCE)
        .collect();
    let mut expected = format!("q1…q{dof}, {reading}");
    if reading == SPHERE {
        expected += ", radius_mm";
    }
    if reading == SOCKET {
        expected += ", socket_distance_mm";
    }
    for c in optional.iter().chain(&[SIGMA]) {
        let _ = write!(expected, ", optionally {c}");
    }
    t.check_columns(known, &expected)?;
    let required = qnames
        .iter()
        .map(String::as_str)
        .chain((reading == SPHERE).then_some(RADIUS))
        .chain((reading == SOCKET).then_some(SOCKET_DISTANCE));
    let mut qcol = Vec::with_capacity(dof);
    for n in required {
        let c = find(n).ok_or_else(|| {
            t.bad(
                t.header_line,
                "",
                format!(
                    "missing column \"{n}\" (robot \"{}\" has {dof} joints; a {reading} file \
                     has {expected})",
                    robot.name()
                ),
            )
        })?;
        if n != RADIUS && n != SOCKET_DISTANCE {
            qcol.push(c);
        }
    }
    let (read_col, sigma_col) = (find(reading), find(SIGMA));
    let (radius_col, offset_col) = (find(RADIUS), find(OFFSET));
    let radius_col = radius_col.or(find(SOCKET_DISTANCE));
    let (lim_lo, lim_hi) = user_limits(robot);
    let chain = reading == STEP;
    let mut out = KindFile {
        qs: Vec::new(),
        data: KindData {
            instrument: Instrument::Distance { pivot: true },
            group: Vec::new(),
            values: Vec::new(),
        },
        sigma_mm: sigma_col.map(|_| Vec::new()),
        lines: Vec::new(),
        files: Vec::new(),
    };
    // Per plane or sphere: its radius and the line that gave it.
    let mut radii: Vec<Option<(Real, u64)>> = Vec::new();
    let mut group_line: Vec<Option<u64>> = Vec::new();
    let mut rec = ::csv::StringRecord::new();
    let lim = (&lim_lo[..], &lim_hi[..]);
    while let Some(line) = t.next(&mut rec)? {
        let num = |c: usize| number(&rec, &names, c).map_err(|(p, m)| t.bad(line, &p, m));
        let q = row_joints(robot, (&rec, &names), &qcol, lim, (path, line))?;
        let first = out.qs.is_empty();
        out.qs.push(q);
        out.lines.push(line);
        // The first row of consecutive lengths has no reading: its cells are empty.
        let blank = |c: usize| rec.get(c).is_some_and(str::is_empty);
        if chain && first {
            for c in read_col.iter().chain(&sigma_col) {
                if !blank(*c) {
                    let msg = format!(
                        "\"{}\": the first row has no pose before it, so its step_mm and \
                         sigma_mm are empty",
                        &rec[*c]
                    );
                    return Err(bad(line, &names[*c], msg));
                }
            }
            continue;
        }
        let c = read_col.unwrap_or(0);
        match reading {
            LENGTH | STEP => {
                let v = num(c)?;
                if !(0.0..=MAX_POINT_MM).contains(&v) {
                    let msg = format!("{} is not a length within [0, {MAX_POINT_MM}] mm", shown(v));
                    return Err(bad(line, reading, msg));
                }
                out.data.values.push(v);
            }
            _ => {
                let text = &rec[c];
                let g = text
                    .parse::<usize>()
                    .ok()
                    .filter(|g| (1..=MAX_GROUPS).contains(g))
                    .ok_or_else(|| {
                        let msg =
                            format!("\"{text}\" is not a {reading} number 1, 2, …, {MAX_GROUPS}");
                        bad(line, reading, msg)
                    })?;
                if group_line.len() < g {
                    group_line.resize(g, None);
                    radii.resize(g, None);
                }
                group_line[g - 1].get_or_insert(line);
                out.data.group.push(g - 1);
                let offset = match offset_col {
                    Some(c) => num(c)?,
                    None => 0.0,
                };
                if offset.abs() > MAX_POINT_MM {
                    let msg = format!("{} mm is beyond ±{MAX_POINT_MM} mm", shown(offset));
                    return Err(bad(line, OFFSET, msg));
                }
                if reading == SOCKET {
                    // The tool point is at the socket's centre: three zero readings.
                    out.data.values.extend([0.0; 3]);
                } else {
                    out.data.values.push(offset);
                }
                if let Some(rc) = radius_col {
                    let r = num(rc)?;
                    let (col, what) = if reading == SOCKET {
                        (SOCKET_DISTANCE, "socket distance")
                    } else {
                        (RADIUS, "radius")
                    };
                    let ok = if reading == SOCKET && g == 1 {
                        r == 0.0
                    } else {
                        r > 0.0 && r <= MAX_POINT_MM
                    };
                    if !ok {
                        let msg = if reading == SOCKET && g == 1 {
                            format!("{}: socket 1 is at distance 0 from itself", shown(r))
                        } else {
                            format!("{} is not a {what} within (0, {MAX_POINT_MM}] mm", shown(r))
                        };
                        return Err(bad(line, col, msg));
                    }
                    match radii[g - 1] {
                        Some((r0, l0)) if r0 != r => {
                            let msg = format!(
                                "{} mm, but {reading} {g} has {what} {} mm on line {l0}: one \
                                 {reading} has one {what}",
                                shown(r),
                                shown(r0)
                            );
                            return Err(bad(line, col, msg));
                        }
                        _ => radii[g - 1] = Some((r, line)),
                    }
                }
            }
        }
        if let (Some(c), Some(s)) = (sigma_col, out.sigma_mm.as_mut()) {
            let v = num(c)?;
            check_sigma(v).map_err(|msg| bad(line, SIGMA, msg))?;
            s.push(v);
        }
    }
    if out.qs.is_empty() {
        let msg = "the file has a header but no data rows".to_string();
        return Err(t.bad(t.header_line, "", msg));
    }
    distinct_poses(&out.qs, &out.lines, dof).map_err(|(l, msg)| t.bad(l, "", msg))?;
    if let Some(gap) = group_line.iter().position(Option::is_none) {
        let last = group_line.len();
        let line = group_line[last - 1].unwrap_or(t.header_line);
        let msg = format!(
            "{reading} {last} but no row of {reading} {}: {reading}s are numbered 1, 2, … \
             without gaps",
            gap + 1
        );
        return Err(bad(line, reading, msg));
    }
    let m = out.qs.len();
    out.data.instrument = match reading {
        LENGTH => Instrument::Distance { pivot: true },
        STEP => Instrument::Distance { pivot: false },
        PLANE => Instrument::Planes(vec![2; group_line.len()]),
        SOCKET => Instrument::Sockets(radii.iter().map(|r| r.map_or(0.0, |r| r.0)).collect()),
        _ => Instrument::Spheres(radii.iter().map(|r| r.map_or(0.0, |r| r.0)).collect()),
    };
    if out.data.group.is_empty() {
        out.data.group = vec![0; m];
    }
    out.data
        .check(m)
        .map_err(|e| t.bad(t.header_line, "", e.to_string()))?;
    Ok(out)
}

/// The joint values of a row (`rec` under the header `names`, line `line` of `path`) from
/// the columns `qcol`, in internal units and checked against the limits `lim` (the robot's
/// units, for messages).
fn row_joints(
    robot: &(impl JointSpace + ?Sized),
    (rec, names): (&::csv::StringRecord, &[String]),
    qcol: &[usize],
    lim: (&[Real], &[Real]),
    (path, line): (&Path, u64),
) -> Result<Vec<Real>> {
    let mut quser = Vec::with_capacity(qcol.len());
    for &c in qcol {
        quser.push(number(rec, names, c).map_err(|(p, m)| at_line(path, line, &p, m))?);
    }
    check_joints(robot, &quser, lim)
        .map_err(|(j, msg)| at_line(path, line, &format!(", column q{}", j + 1), msg))
}

/// Reads a multi-target file from its rows `t` (header read): one row per target and pose,
/// the rows of a pose consecutive with the same joint values, every pose with every target
/// once; each target's offset the same on all its rows. The points stay in the tracker's
/// frame (the identification registers them).
fn read_targets(mut t: Rows, robot: &(impl JointSpace + ?Sized), path: &Path) -> Result<KindFile> {
    let names = t.names.clone();
    let find = |n: &str| names.iter().position(|h| h == n);
    let bad = |line: u64, column: &str, msg: String| {
        at_line(path, line, &format!(", column {column}"), msg)
    };
    let dof = robot.dof();
    let qnames: Vec<String> = (1..=dof).map(|j| format!("q{j}")).collect();
    let required: Vec<&str> = qnames
        .iter()
        .map(String::as_str)
        .chain([TARGET])
        .chain(XYZ)
        .chain(OFFSETS)
        .collect();
    let expected = format!("q1…q{dof}, target, x, y, z, target_x_mm, target_y_mm, target_z_mm");
    t.check_columns(|n| required.contains(&n), &expected)?;
    let cols: Vec<usize> = required
        .iter()
        .map(|n| {
            find(n).ok_or_else(|| {
                let msg = format!("missing column \"{n}\" (a multi-target file has {expected})");
                t.bad(t.header_line, "", msg)
            })
        })
        .collect::<Result<_>>()?;
    let (qcol, rest) = cols.split_at(dof);
    let (lim_lo, lim_hi) = user_limits(robot);
    let mut qs: Vec<Vec<Real>> = Vec::new();
    let mut lines: Vec<u64> = Vec::new();
    // Per pose, its targets' points by target number; per target, its offset and line.
    let mut points: Vec<Vec<Option<Vec3>>> = Vec::new();
    let mut offsets: Vec<Option<(Vec3, u64)>> = Vec::new();
    let mut rec = ::csv::StringRecord::new();
    let lim = (&lim_lo[..], &lim_hi[..]);
    let mut last = 0;
    while let Some(line) = t.next(&mut rec)? {
        let num = |c: usize| number(&rec, &names, c).map_err(|(p, m)| t.bad(line, &p, m));
        let q = row_joints(robot, (&rec, &names), qcol, lim, (path, line))?;
        let text = &rec[rest[0]];
        let g = text
            .parse::<usize>()
            .ok()
            .filter(|g| (1..=MAX_GROUPS).contains(g))
            .ok_or_else(|| {
                let msg = format!("\"{text}\" is not a target number 1, 2, …, {MAX_GROUPS}");
                bad(line, TARGET, msg)
            })?;
        let mut v = [[0.0; 3]; 2];
        for (k, &c) in rest[1..].iter().enumerate() {
            let x = num(c)?;
            check_coordinate(x).map_err(|msg| bad(line, &names[c], msg))?;
            v[k / 3][k % 3] = x;
        }
        let (p, o) = (Vec3::from(v[0]), Vec3::from(v[1]));
        if offsets.len() < g {
            offsets.resize(g, None);
        }
        match offsets[g - 1] {
            Some((o0, l0)) if o0 != o => {
                let msg = format!(
                    "target {g} is at [{}, {}, {}] mm in the tool frame on line {l0}: one \
                     target has one offset",
                    shown(o0.x),
                    shown(o0.y),
                    shown(o0.z)
                );
                return Err(bad(line, OFFSETS[0], msg));
            }
            _ => offsets[g - 1] = Some((o, line)),
        }
        let same_pose = qs
            .last()
            .is_some_and(|l: &Vec<Real>| l.iter().zip(&q).all(|(a, b)| a.to_bits() == b.to_bits()));
        if !same_pose {
            qs.push(q);
            lines.push(line);
            points.push(Vec::new());
        }
        let pose = points
            .last_mut()
            .unwrap_or_else(|| unreachable!("a pose was pushed"));
        if pose.len() < g {
            pose.resize(g, None);
        }
        if pose[g - 1].is_some() {
            let msg = format!(
                "target {g} twice in the pose that starts on line {}",
                lines[lines.len() - 1]
            );
            return Err(bad(line, TARGET, msg));
        }
        pose[g - 1] = Some(p);
        last = line;
    }
    if qs.is_empty() {
        let msg = "the file has a header but no data rows".to_string();
        return Err(t.bad(t.header_line, "", msg));
    }
    distinct_poses(&qs, &lines, dof).map_err(|(l, msg)| t.bad(l, "", msg))?;
    let count = offsets.len();
    if let Some(gap) = offsets.iter().position(Option::is_none) {
        let line = offsets[count - 1].map_or(last, |o| o.1);
        let msg = format!(
            "target {count} but no row of target {}: targets are numbered 1, 2, … without gaps",
            gap + 1
        );
        return Err(bad(line, TARGET, msg));
    }
    let mut values = Vec::with_capacity(3 * count * qs.len());
    for (i, pose) in points.iter().enumerate() {
        for g in 0..count {
            let p = pose.get(g).copied().flatten().ok_or_else(|| {
                let msg = format!(
                    "the pose that starts here has no row of target {}: every pose measures \
                     every target",
                    g + 1
                );
                t.bad(lines[i], "", msg)
            })?;
            values.extend(p.iter());
        }
    }
    let m = qs.len();
    let targets = offsets
        .iter()
        .map(|o| o.map_or(Vec3::zeros(), |o| o.0))
        .collect();
    let data = KindData {
        instrument: Instrument::Targets(targets),
        group: vec![0; m],
        values,
    };
    data.check(m)
        .map_err(|e| t.bad(t.header_line, "", e.to_string()))?;
    Ok(KindFile {
        qs,
        data,
        sigma_mm: None,
        lines,
        files: Vec::new(),
    })
}

/// Writes the points `values` (3 per target and pose) of `targets` at joint values `qs` as a
/// multi-target file: one row per pose and target.
fn write_targets(
    path: &Path,
    robot: &(impl JointSpace + ?Sized),
    qs: &[Vec<Real>],
    targets: &[Vec3],
    values: &[Real],
) -> Result<()> {
    let mut s = String::with_capacity(16 * (robot.dof() + 7) * (targets.len() * qs.len() + 1));
    joint_header(&mut s, robot.dof());
    s.push_str(",target,x,y,z,target_x_mm,target_y_mm,target_z_mm\n");
    let cells =
        |v: &[Real]| -> String { v.iter().map(|x| fixed(*x, 9)).collect::<Vec<_>>().join(",") };
    for (i, q) in qs.iter().enumerate() {
        for (k, o) in targets.iter().enumerate() {
            joint_cells(&mut s, robot, q);
            let row = 3 * (targets.len() * i + k);
            let p = cells(&values[row..row + 3]);
            let _ = writeln!(s, ",{},{p},{}", k + 1, cells(o.as_slice()));
        }
    }
    std::fs::write(path, s).map_err(|e| Error::io(path, e))
}

/// Writes readings `data` at joint values `qs` of `robot` as a measurement-kind file, with
/// each observation's standard deviation `sigma_mm` when given (every one > 0; not for
/// targets). Numbers with 9 decimals, negative zero written as zero, so equal readings give
/// identical bytes.
pub fn write_kind_file(
    path: &Path,
    robot: &(impl JointSpace + ?Sized),
    qs: &[Vec<Real>],
    data: &KindData,
    sigma_mm: Option<&[Real]>,
) -> Result<()> {
    let inst = &data.instrument;
    data.check(qs.len())?;
    let columns = match inst {
        Instrument::Distance { pivot: true } => LENGTH,
        Instrument::Distance { pivot: false } => STEP,
        Instrument::Planes(_) => "plane,offset_mm",
        Instrument::Spheres(_) => "sphere,radius_mm,offset_mm",
        Instrument::Sockets(_) => "socket,socket_distance_mm",
        Instrument::Targets(targets) => {
            if sigma_mm.is_some() {
                return Err(Error::setting(
                    "sigma_mm",
                    "a multi-target file has no sigma_mm column",
                ));
            }
            return write_targets(path, robot, qs, targets, &data.values);
        }
    };
    let mut s = String::with_capacity(16 * (robot.dof() + 3) * (qs.len() + 1));
    joint_header(&mut s, robot.dof());
    let _ = write!(s, ",{columns}");
    if sigma_mm.is_some() {
        s.push_str(",sigma_mm");
    }
    s.push('\n');
    // Observation `k` of row `i`: consecutive lengths start on the second row.
    let skip = usize::from(matches!(inst, Instrument::Distance { pivot: false }));
    for (i, q) in qs.iter().enumerate() {
        joint_cells(&mut s, robot, q);
        let Some(k) = i.checked_sub(skip) else {
            s.push(',');
            if sigma_mm.is_some() {
                s.push(',');
            }
            s.push('\n');
            continue;
        };
        let v = fixed(data.values[k], 9);
        match inst {
            Instrument::Planes(_) => {
                let _ = write!(s, ",{},{v}", data.group[i] + 1);
            }
            Instrument::Spheres(r) => {
                let g = data.group[i];
                let _ = write!(s, ",{},{},{v}", g + 1, fixed(r[g], 9));
            }
            Instrument::Sockets(d) => {
                // The readings are the socket's zeros: the row names its socket.
                let g = data.group[i];
                let _ = write!(s, ",{},{}", g + 1, fixed(d[g], 9));
            }
            _ => {
                let _ = write!(s, ",{v}");
            }
        }
        if let Some(sd) = sigma_mm {
            let v = sd.get(k).ok_or_else(|| {
                Error::Compute(format!("{} observations but {} σ", k + 1, sd.len()))
            })?;
            let _ = write!(s, ",{}", fixed(*v, 9));
        }
        s.push('\n');
    }
    std::fs::write(path, s).map_err(|e| Error::io(path, e))
}
