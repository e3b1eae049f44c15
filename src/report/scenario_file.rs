//! `scenario.toml` of a run or merge folder (docs/formats.md § 7.1), of every study kind: the scenario as the run
//! ran it — the file's table with `trials`, `seed` and every override applied, as TOML — under
//! one comment line giving the SHA-256 of that text, so that `calbench record` stores what
//! ran and refuses a scenario file that differs, and an edited copy is told by its hash.

use crate::analysis::regression::Side;
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

/// The canonical text of the `scenario.toml` beside the summary file `summary` (hash line
/// checked, [`read`]); `None` when there is none (a baseline file, a summary copied alone).
pub fn beside(summary: &std::path::Path) -> Result<Option<String>> {
    let file = summary
        .parent()
        .unwrap_or(std::path::Path::new("."))
        .join(NAME);
    if !file.is_file() {
        return Ok(None);
    }
    let text = crate::error::read_text(&file)?;
    read(&text, &file).map(|(body, _)| Some(body))
}

/// The scenario the run of `side` ran (canonical text): the one its baseline file records
/// ([`Side::scenario`]), else the `scenario.toml` beside its summary ([`beside`]); `None`
/// when neither says.
pub fn ran(side: &Side) -> Result<Option<String>> {
    match &side.scenario {
        Some(s) => Ok(Some(s.clone())),
        None => beside(&side.path),
    }
}

/// What the runs of `a` and `b` ran differently ([`differences`] of [`ran`]); empty when
/// they ran one scenario or either does not say what it ran.
pub fn settings_apart(a: &Side, b: &Side) -> Result<Vec<String>> {
    Ok(match (ran(a)?, ran(b)?) {
        (Some(a), Some(b)) => differences(&a, &b),
        _ => Vec::new(),
    })
}

/// What two scenarios as run (canonical texts) set differently, other than the keys that
/// only choose the draws (`seed`, `trials`): each setting as `key: A → B` by its dotted key
/// (`calibration.count: 40 → 25`, `methods[1].name: "igg3" → "ridge"`, `(none)` where one
/// lacks it), in the tables' order; empty for one study. A text that is not TOML differs
/// from every other as a whole.
pub fn differences(a: &str, b: &str) -> Vec<String> {
    let table = |t: &str| -> Option<toml::Table> {
        let mut t: toml::Table = toml::from_str(t).ok()?;
        t.remove("seed");
        t.remove("trials");
        Some(t)
    };
    let mut out = Vec::new();
    match (table(a), table(b)) {
        (Some(a), Some(b)) => apart("", &a.into(), &b.into(), &mut out),
        _ => out.push("the scenario's text: it is not TOML".into()),
    }
    out
}

/// Adds to `out` each setting under the dotted `key` where `a` and `b` differ.
fn apart(key: &str, a: &toml::Value, b: &toml::Value, out: &mut Vec<String>) {
    use toml::Value::{Array, Table};
    let at = |k: &str| match key {
        "" => k.to_string(),
        _ => format!("{key}.{k}"),
    };
    match (a, b) {
        (Table(a), Table(b)) => {
            let keys = a.keys().chain(b.keys().filter(|k| !a.contains_key(*k)));
            for k in keys {
                match (a.get(k), b.get(k)) {
                    (Some(x), Some(y)) => apart(&at(k), x, y, out),
                    (x, y) => out.push(setting(&at(k), x, y)),
                }
            }
        }
        (Array(a), Array(b)) if a.len() == b.len() && a.iter().any(toml::Value::is_table) => {
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                apart(&format!("{key}[{i}]"), x, y, out);
            }
        }
        (a, b) if a != b => out.push(setting(key, Some(a), Some(b))),
        _ => {}
    }
}

/// One setting that differs, as `key: A → B`.
fn setting(key: &str, a: Option<&toml::Value>, b: Option<&toml::Value>) -> String {
    let show = |v: Option<&toml::Value>| v.map_or("(none)".into(), |v| v.to_string());
    format!("{key}: {} → {}", show(a), show(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differences_name_each_setting_but_the_draws() {
        let a = "name = \"g\"\nseed = 1\ntrials = 3\n[calibration]\ncount = 40\n\
                 [[methods]]\nname = \"ls\"\n[[methods]]\nname = \"igg3\"\n";
        let b = a
            .replace("seed = 1", "seed = 2")
            .replace("trials = 3", "trials = 9");
        assert!(
            differences(a, &b).is_empty(),
            "seed and trials only choose the draws"
        );
        let c = a
            .replace("count = 40", "count = 25")
            .replace("\"igg3\"", "\"ridge\"");
        assert_eq!(
            differences(a, &c),
            [
                "calibration.count: 40 → 25",
                "methods[1].name: \"igg3\" → \"ridge\""
            ]
        );
        let d = format!("{a}[outliers]\ncount = 2\n");
        assert_eq!(differences(a, &d), ["outliers: (none) → { count = 2 }"]);
        let e = a.replace("[[methods]]\nname = \"igg3\"\n", "");
        assert_eq!(
            differences(a, &e),
            ["methods: [{ name = \"ls\" }, { name = \"igg3\" }] → [{ name = \"ls\" }]"]
        );
        assert_eq!(
            differences(a, "not = toml = ["),
            ["the scenario's text: it is not TOML"]
        );
    }
}
