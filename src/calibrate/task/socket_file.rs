//! One joint file of a socket task (docs/formats.md § 9.4): header-less CSV, each line the
//! robot's joint values at one hold of the ball in the file's socket. It is read as a
//! measurement-kind file (§ 5.8) under a header calbench adds, and every refusal names the
//! user's file, its own line and its own counts: a line of too few or too many values, a cell
//! that is not a number, and whatever the kind reader refuses, its line moved back by the
//! header's.

use std::path::Path;

use crate::error::{read_text, Error, Result};
use crate::measurement::kind_csv::{read_kind_text, KindFile};
use crate::measurement::rows::quoted;
use crate::numeric::Real;
use crate::robot::Robot;

/// The rows of the socket file `f` for `robot`: its lines read under the header
/// `q1,…,qN,socket,socket_distance_mm`, each with `1,0` added (the caller groups the rows by
/// file).
pub(super) fn read_socket_file(f: &Path, robot: &Robot) -> Result<KindFile> {
    let raw = read_text(f)?;
    let dof = robot.dof();
    check_values(f, &raw, dof)?;
    let header: Vec<String> = (1..=dof)
        .map(|j| format!("q{j}"))
        .chain(["socket".into(), "socket_distance_mm".into()])
        .collect();
    let mut text = header.join(",") + "\n";
    for line in raw.lines() {
        let line = line.trim_end();
        if !line.is_empty() && !line.starts_with('#') {
            text.push_str(line);
            text.push_str(",1,0");
        }
        text.push('\n');
    }
    let mut one = read_kind_text(f, text, robot).map_err(|e| own_line(e, f))?;
    for l in &mut one.lines {
        *l -= 1;
    }
    Ok(one)
}

/// Refuses a line of `raw` (the text of `f`) with another number of values than the robot's
/// `dof` joints, or a value that is not a finite number, at the file's own line and column.
/// Blank lines and `#` comment lines are skipped, as in a measurement file.
fn check_values(f: &Path, raw: &str, dof: usize) -> Result<()> {
    let mut rd = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(::csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(raw.as_bytes());
    for rec in rd.records() {
        let rec = rec.map_err(|e| {
            let line = e.position().map_or(0, ::csv::Position::line);
            Error::file(f, format!("line {line}"), format!("unreadable line ({e})"))
        })?;
        let line = rec.position().map_or(0, ::csv::Position::line);
        if rec.iter().all(str::is_empty) {
            continue;
        }
        if rec.len() != dof {
            return Err(Error::file(
                f,
                format!("line {line}"),
                format!("{} values, expected {dof} (the robot's joints)", rec.len()),
            ));
        }
        for (j, t) in rec.iter().enumerate() {
            if !t.parse::<Real>().is_ok_and(Real::is_finite) {
                return Err(Error::file(
                    f,
                    format!("line {line}, column q{}", j + 1),
                    format!("{} is not a finite number", quoted(t)),
                ));
            }
        }
    }
    Ok(())
}

/// A refusal `e` of the kind reader about `f` read under one header line, placed at `f`'s own
/// line (`line N` becomes `line N - 1`); any other error as it is.
fn own_line(e: Error, f: &Path) -> Error {
    match e {
        Error::File { file, place, msg } if file == f => {
            let moved = place
                .strip_prefix("line ")
                .and_then(|rest| {
                    let digits =
                        rest.len() - rest.trim_start_matches(|c: char| c.is_ascii_digit()).len();
                    let n: u64 = rest[..digits].parse().ok()?;
                    Some(format!("line {}{}", n.saturating_sub(1), &rest[digits..]))
                })
                .unwrap_or(place);
            Error::File {
                file,
                place: moved,
                msg,
            }
        }
        e => e,
    }
}
