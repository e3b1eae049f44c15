//! One joint file of a socket task (docs/formats.md § 9.4): header-less CSV, each line the
//! robot's joint values at one hold of the ball in the file's socket. It is read as the rows
//! of a measurement-kind file (§ 5.8) of the columns `q1,…,qN,socket,socket_distance_mm`, and
//! every refusal names the user's file, its own line and its own counts: an empty file, a line
//! of too few or too many values, a cell that is not a number, and whatever the kind reader
//! refuses.

use std::path::Path;

use crate::error::{read_text, Error, Result};
use crate::measurement::kind_csv::{read_kind_headerless, KindFile};
use crate::measurement::rows::quoted;
use crate::numeric::Real;
use crate::robot::Robot;

/// The rows of the socket file `f` for `robot`: its lines read as the columns
/// `q1,…,qN,socket,socket_distance_mm`, each with `1,0` added (the caller groups the rows by
/// file).
pub(super) fn read_socket_file(f: &Path, robot: &Robot) -> Result<KindFile> {
    let raw = read_text(f)?;
    let dof = robot.dof();
    check_values(f, &raw, dof)?;
    let names: Vec<String> = (1..=dof)
        .map(|j| format!("q{j}"))
        .chain(["socket".into(), "socket_distance_mm".into()])
        .collect();
    // Each line keeps its place, a blank or comment line emptied, so that the kind reader
    // names the file's own lines.
    let mut text = String::with_capacity(raw.len() + raw.len() / 8);
    for line in raw.lines() {
        let line = line.trim_end();
        if !line.is_empty() && !line.starts_with('#') {
            text.push_str(line);
            text.push_str(",1,0");
        }
        text.push('\n');
    }
    read_kind_headerless(f, text, names, robot)
}

/// Refuses a line of `raw` (the text of `f`) with another number of values than the robot's
/// `dof` joints, or a value that is not a finite number, at the file's own line and column.
/// Blank lines and `#` comment lines are skipped, as in a measurement file; a file of none
/// but those is refused as empty.
fn check_values(f: &Path, raw: &str, dof: usize) -> Result<()> {
    let mut rd = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(::csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(raw.as_bytes());
    let mut rows = 0usize;
    for rec in rd.records() {
        let rec = rec.map_err(|e| {
            let line = e.position().map_or(0, ::csv::Position::line);
            Error::file(f, format!("line {line}"), format!("unreadable line ({e})"))
        })?;
        let line = rec.position().map_or(0, ::csv::Position::line);
        if rec.iter().all(str::is_empty) {
            continue;
        }
        rows += 1;
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
    if rows == 0 {
        let qs = format!("q1,…,q{dof}");
        return Err(Error::file(
            f,
            "line 1",
            format!("empty file: expected rows of joint values {qs}, one pose a line, no header"),
        ));
    }
    Ok(())
}
