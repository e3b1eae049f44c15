//! An identify folder's `identified.json` checked before it is recorded (docs/formats.md
//! § 2.15): what is stored must be what an identification writes, beyond the types its reader
//! checks.

use std::collections::BTreeMap;
use std::path::Path;

use crate::analysis::figures::{check_figures, Figure, Reader};
use crate::calibrate::record::IdentifiedRecord;
use crate::error::{Error, Result};

/// Refuses, naming the file `path` and the key (at its line), a record `id` no identification
/// writes: a `robot` no robot file may be named (empty, or holding a control character); a
/// `method` that is neither one of calbench's ([`crate::identify::METHODS`]) nor a
/// method supplied from outside; an `errors` key that is not one of its `parameters`, or a
/// parameter without its error; a `rank` above the unknowns solved for (the parameters, with a
/// kind file's instrument unknowns); and a figure (`figures`) a run's summary may not hold
/// either ([`check_figures`]: an error, residual, σ₀ or condition number below 0, a block of
/// errors (`validation_after_mm`, …) whose mean is above its RMS or whose RMS is above its
/// maximum).
pub(super) fn check_identified(
    id: &IdentifiedRecord,
    path: &Path,
    figures: &[Figure],
) -> Result<()> {
    let bad = |key: &str, msg: String| Err(Error::file(path, key, msg).at_json_key_line());
    let external = crate::identify::external::EXTERNAL;
    let known = crate::identify::METHODS.iter().any(|m| m.name == id.method);
    if !known && id.method != external {
        return bad(
            "method",
            format!(
                "is \"{}\", which is no identification method ({}, or {external} for a method \
                 supplied from outside)",
                id.method,
                crate::identify::registry::method_names()
            ),
        );
    }
    if id.robot.trim().is_empty() || id.robot.chars().any(crate::error::is_hidden) {
        return bad(
            "robot",
            format!(
                "is {:?}: an identification names its robot by the robot file's `name`, which \
                 is not empty and holds no control character",
                id.robot
            ),
        );
    }
    let n = id.parameters.len();
    if let Some(k) = id.errors.keys().find(|k| !id.parameters.contains(k)) {
        let msg = format!("is not one of the {n} parameters identified (parameters)");
        return bad(&format!("errors.{k}"), msg);
    }
    if let Some(p) = id.parameters.iter().find(|p| !id.errors.contains_key(*p)) {
        return bad(
            "errors",
            format!("lacks `{p}`, a parameter identified (parameters)"),
        );
    }
    let instrument = id.instrument_unknowns.as_ref().map_or(0, BTreeMap::len);
    let unknowns = (n + instrument).max(id.standard_errors.as_ref().map_or(0, BTreeMap::len));
    if let Some(rank) = id.rank.filter(|&r| r > unknowns) {
        return bad(
            "rank",
            format!(
                "is {rank}, above the {unknowns} unknowns solved for: the rank of a solve is at \
                 most its unknowns"
            ),
        );
    }
    check_figures(
        path,
        None,
        figures,
        Reader::Record,
        &|_| Some(String::new()),
    )
}
