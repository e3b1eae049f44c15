//! `scenario.toml` of a run or merge folder (docs/formats.md § 7.1), of every study kind: the scenario as the run
//! ran it — the file's table with `trials`, `seed` and every override applied, as TOML — under
//! one comment line giving the SHA-256 of that text, so that `calbench record` stores what
//! ran and refuses a scenario file that differs, and an edited copy is told by its hash.

use crate::calibrate::task::sha256::sha256_hex;
use crate::error::{Error, Result};
use crate::study::scenario::Scenario;

/// The file's name.
pub const NAME: &str = "scenario.toml";

/// The start of the first line, before the hash.
const HEAD: &str =
    "# The scenario as run (trials, seed and overrides applied); SHA-256 of the text below: ";

/// The canonical text of a scenario as run: its table as TOML.
pub fn canonical(sc: &Scenario) -> Result<String> {
    toml::to_string(sc.table())
        .map_err(|e| Error::Compute(format!("cannot write the scenario as TOML: {e}")))
}

/// The file's text for the scenario `sc`: the hash line, then [`canonical`].
pub fn text(sc: &Scenario) -> Result<String> {
    Ok(with_hash(&canonical(sc)?))
}

/// The file's text for a scenario whose canonical text (its table as run, as TOML) is `body`:
/// the hash line, then `body`.
pub fn with_hash(body: &str) -> String {
    format!("{HEAD}{}\n{body}", sha256_hex(body.as_bytes()))
}

/// The canonical text and its hash from the file's `text` read at `path`; refuses, naming
/// the file, a text without the hash line or whose text does not have the hash it states
/// (an edited copy).
pub fn read(text: &str, path: &std::path::Path) -> Result<(String, String)> {
    let (first, body) = text.split_once('\n').unwrap_or((text, ""));
    let Some(stated) = first.strip_prefix(HEAD) else {
        return Err(Error::file(
            path,
            "line 1",
            "is not the hash line calbench writes; this is not a run's scenario.toml",
        ));
    };
    let hash = sha256_hex(body.as_bytes());
    if stated.trim() != hash {
        return Err(Error::file(
            path,
            "line 1",
            format!(
                "states SHA-256 {} but the text below it has {hash}: the file was edited after \
                 the run",
                stated.trim()
            ),
        ));
    }
    Ok((body.to_string(), hash))
}
