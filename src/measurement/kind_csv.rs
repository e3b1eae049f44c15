//! The measurement CSV of the kinds beyond the tracker (docs/formats.md § 5.3): the joint
//! columns `q1…qn` and, per kind, the reading that names it:
//!
//! | kind | columns besides `q1…qn` |
//! |---|---|
//! | `distance` from a pivot | `length_mm` |
//! | `distance` between consecutive poses | `step_mm` (empty on the first row) |
//! | `plane` | `plane` (1, 2, …), optional `offset_mm` |
//! | `sphere` | `sphere` (1, 2, …), `radius_mm`, optional `offset_mm` |
//!
//! and optionally `sigma_mm`, the reading's standard deviation. A file without any of these
//! columns is the tracker's ([`super::csv`]). Reading refuses what the tracker's reader
//! refuses (unknown, missing or repeated columns, rows of another length, values that are not
//! finite numbers, joints outside their limits, fewer than three distinct poses) and what is
//! wrong with a reading: a negative length, a plane or sphere number that is not 1, 2, …, a
//! numbering with gaps, a radius that is not positive or changes within a sphere, naming the
//! file, the line and the column. Multi-target files (a `target` column) are refused: their
//! points are in the tracker's frame, which the kinds' identification does not register.

use std::fmt::Write as _;
use std::path::Path;

use super::csv::{
    check_joints, check_sigma, distinct_poses, fixed, joint_cells, joint_header, user_limits,
    MAX_POINT_MM,
};
use super::kind::{Instrument, Kind, KindData};
use super::rows::{at_line, number, Rows};
use super::JointSpace;
use crate::error::{Error, Result};
use crate::numeric::Real;

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
/// The column of a multi-target file (not read).
const TARGET: &str = "target";

/// The most planes or spheres of one file.
pub const MAX_GROUPS: usize = 1000;

/// The columns that make a file one of a kind, with its kind and whether lengths are from a
/// pivot.
const KIND_COLUMNS: [(&str, Kind); 5] = [
    (LENGTH, Kind::Distance),
    (STEP, Kind::Distance),
    (PLANE, Kind::Plane),
    (SPHERE, Kind::Sphere),
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

/// Reads a measurement-kind file for `robot` (see the module docs for what is refused).
pub fn read_kind_file(path: &Path, robot: &(impl JointSpace + ?Sized)) -> Result<KindFile> {
    let mut t = Rows::open(path, "q1,…,qn and length_mm, step_mm, plane or sphere")?;
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
            "no column length_mm, step_mm, plane or sphere: not a measurement-kind file".into(),
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
        return Err(bad(
            t.header_line,
            TARGET,
            "multi-target files are not read: their points are in the tracker's frame, which \
             the identification of the kinds does not register; identify each target's rows \
             as a tracker file (docs/formats.md § 5.1)"
                .into(),
        ));
    }
    let dof = robot.dof();
    let qnames: Vec<String> = (1..=dof).map(|j| format!("q{j}")).collect();
    let extra: &[&str] = match reading {
        PLANE => &[OFFSET],
        SPHERE => &[RADIUS, OFFSET],
        _ => &[],
    };
    let known = |n: &str| qnames.iter().any(|q| q == n) || n == reading || n == SIGMA;
    let known = |n: &str| known(n) || extra.contains(&n);
    let optional: Vec<&str> = extra.iter().copied().filter(|c| *c != RADIUS).collect();
    let mut expected = format!("q1…q{dof}, {reading}");
    if reading == SPHERE {
        expected += ", radius_mm";
    }
    for c in optional.iter().chain(&[SIGMA]) {
        let _ = write!(expected, ", optionally {c}");
    }
    t.check_columns(known, &expected)?;
    let required = qnames
        .iter()
        .map(String::as_str)
        .chain((reading == SPHERE).then_some(RADIUS));
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
        if n != RADIUS {
            qcol.push(c);
        }
    }
    let (read_col, sigma_col) = (find(reading), find(SIGMA));
    let (radius_col, offset_col) = (find(RADIUS), find(OFFSET));
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
    };
    // Per plane or sphere: its radius and the line that gave it.
    let mut radii: Vec<Option<(Real, u64)>> = Vec::new();
    let mut group_line: Vec<Option<u64>> = Vec::new();
    let mut rec = ::csv::StringRecord::new();
    let mut quser = vec![0.0; dof];
    while let Some(line) = t.next(&mut rec)? {
        let num = |c: usize| number(&rec, &names, c).map_err(|(p, m)| t.bad(line, &p, m));
        for (j, &c) in qcol.iter().enumerate() {
            quser[j] = num(c)?;
        }
        let q = check_joints(robot, &quser, (&lim_lo, &lim_hi))
            .map_err(|(c, msg)| bad(line, &c, msg))?;
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
                    let msg = format!("{v} is not a length within [0, {MAX_POINT_MM}] mm");
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
                    let msg = format!("{offset} mm is beyond ±{MAX_POINT_MM} mm");
                    return Err(bad(line, OFFSET, msg));
                }
                out.data.values.push(offset);
                if let Some(rc) = radius_col {
                    let r = num(rc)?;
                    if !(r > 0.0 && r <= MAX_POINT_MM) {
                        let msg = format!("{r} is not a radius within (0, {MAX_POINT_MM}] mm");
                        return Err(bad(line, RADIUS, msg));
                    }
                    match radii[g - 1] {
                        Some((r0, l0)) if r0 != r => {
                            let msg = format!(
                                "{r} mm, but sphere {g} has radius {r0} mm on line {l0}: one \
                                 sphere has one radius"
                            );
                            return Err(bad(line, RADIUS, msg));
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

/// Writes readings `data` at joint values `qs` of `robot` as a measurement-kind file, with
/// each observation's standard deviation `sigma_mm` when given (every one > 0). Numbers with 9
/// decimals, negative zero written as zero, so equal readings give identical bytes. Several
/// targets per pose are refused (their file is not defined).
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
        Instrument::Targets(_) => {
            return Err(Error::setting(
                "measurement.kind",
                format!(
                    "{} readings have no file of their own: position is the tracker's file, \
                     multi-target files are not defined",
                    inst.kind().as_str()
                ),
            ))
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
