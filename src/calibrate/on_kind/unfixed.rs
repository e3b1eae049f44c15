//! Refusals of kind-file readings that cannot fix what a fit needs: given parameters they do
//! not determine, too few readings, an instrument's unknowns left free, rows repeated
//! (docs/formats.md § 8.5).

use std::path::Path;

use super::{first_guess, prepared, IdentifyRequest};
use crate::calibrate::verdict::allowing;
use crate::error::{Error, Opt, Result, Said};
use crate::measurement::kind::{Instrument, Kind, KindData};
use crate::measurement::kind_csv::KindFile;
use crate::robot::identifiability::Identifiability;
use crate::robot::Param;

/// Refuses a file of rows that repeat earlier ones ([`KindFile::repeated_rows`]), as a
/// tracker's are refused: a copy counts one reading twice.
pub(super) fn repeated(q: &IdentifyRequest, file: &KindFile) -> Result<()> {
    let repeated = file.repeated_rows();
    if repeated.is_empty() {
        return Ok(());
    }
    let same = match file.data.instrument.kind() {
        Kind::Distance => "the same joint values and length",
        Kind::Plane => "the same joint values, plane and offset",
        Kind::Sphere => "the same joint values, sphere and offset",
        Kind::Socket => "the same joint values and socket",
        _ => "the same joint values and measured points",
    };
    let why = crate::measurement::repeated_rows_named(
        &repeated,
        same,
        file.rows_numbered(),
        &|r| file.row_named(r),
        crate::measurement::REPEATED_CALIBRATION,
    );
    Err(Error::file(&q.source, "data", why))
}

/// Refuses a socket file whose `socket_distance_mm` the nominal robot's tool points put at
/// another scale ([`crate::calibrate::task::socket::misplaced_socket`], as a socket task's
/// `sockets.distances_mm` is refused), at the first row of that socket: the rows that cannot
/// reach a socket so far were dropped, and the file had been refused as "socket 2 has no
/// pose" although it has.
pub(super) fn misplaced_sockets(q: &IdentifyRequest, file: &KindFile) -> Result<()> {
    let Instrument::Sockets(distances) = &file.data.instrument else {
        return Ok(());
    };
    let group = &file.data.group;
    let Some(m) =
        crate::calibrate::task::socket::misplaced_socket(&q.robot, &file.qs, group, distances)
    else {
        return Ok(());
    };
    let row = group.iter().position(|&g| g == m.socket).unwrap_or(0);
    let line = file.lines.get(row).copied().unwrap_or(0);
    let msg = m.said("its rows", "the file's distances");
    let place = format!("line {line}, column socket_distance_mm");
    Err(Error::file(&q.source, place, msg))
}

/// The refusal of given parameters that `data` cannot determine (`count` given).
pub(super) fn undetermined(
    source: &Path,
    data: &KindData,
    a: &Identifiability,
    count: usize,
) -> Error {
    let (names, groups) = crate::calibrate::verdict::names_and_groups(a);
    let msg = format!(
        "{} readings on these poses determine only {} of the {count} parameters (undetermined: \
         {names}; dependent groups: {groups}), with the instrument's own unknowns ({}); nothing \
         was written. Leave the undetermined ones out of ",
        data.instrument.kind().as_str(),
        a.rank,
        data.instrument.nuisance_names().join(" "),
    );
    let msg = Said::from(msg).name(Opt::Params).text(", or pass ");
    Error::file(source, "data", msg.on(Opt::AllowRankDeficient))
}

/// Refuses the readings of `file` when they are too few for what its instrument (at its first
/// guess) determines of `among` on poses spread over the workspace
/// ([`crate::identify::kind::generic_rank`])
/// and its own unknowns together: a fit of as many unknowns as readings matches them
/// exactly, whatever the robot, and leaves none to check it. Says how many poses would give
/// more readings than unknowns.
pub(super) fn too_few(
    q: &IdentifyRequest,
    file: &KindFile,
    among: &[Param],
    register: bool,
) -> Result<()> {
    let inst = &file.data.instrument;
    let readings = |poses: usize| inst.observations(poses) * inst.rows_per_observation();
    // Readings whose first guess cannot be made, or does not place the instrument where
    // the arm reaches it, are refused by the identification.
    let generic = prepared(&q.robot, file, register)
        .and_then(|(d, _, p)| first_guess(&d, &p))
        .and_then(|lay| crate::identify::kind::generic_rank(&q.robot, among, &lay));
    let Ok(robot) = generic else {
        return Ok(());
    };
    let own = inst.nuisance_names();
    let unknowns = robot + own.len();
    let poses = file.qs.len();
    if readings(poses) > unknowns {
        return Ok(());
    }
    let least = (poses..).find(|&m| readings(m) > unknowns).unwrap_or(poses);
    let own = match own.is_empty() {
        true => String::new(),
        false => format!(
            " and the instrument's own {} ({})",
            own.len(),
            own.join(" ")
        ),
    };
    let msg = format!(
        "{poses} poses give {} {} readings for {unknowns} unknowns: the {robot} robot \
         parameters these readings determine on poses spread over the workspace{own}; a fit \
         would match every reading and leave none to check it, so nothing was written. \
         Measure at least {least} poses, or pass ",
        readings(poses),
        inst.kind().as_str(),
    );
    Err(Error::file(
        &q.source,
        "data",
        allowing(msg, Opt::AllowRankDeficient),
    ))
}

/// The refusal of readings that leave the instrument's own unknowns `free` (the solve ends
/// singular whatever the robot), naming them and the layout that leaves them so.
pub(super) fn unknowns_free(q: &IdentifyRequest, kind: Kind, free: &[String]) -> Error {
    let why = match kind {
        Kind::Plane => {
            "a plane's points on one line or at one point leave its tilt free: touch each \
             plane at points spread over it"
        }
        Kind::Sphere => {
            "a sphere's points on one great circle or at one point leave its centre free: \
             touch each sphere at points spread over it"
        }
        _ => "the poses leave them free: measure poses spread about the instrument",
    };
    let msg = format!(
        "the {} readings do not determine the instrument's own unknowns {} on these poses \
         ({why}); nothing was written. Measure again, or pass ",
        kind.as_str(),
        free.join(" "),
    );
    Error::file(&q.source, "data", allowing(msg, Opt::AllowRankDeficient))
}
