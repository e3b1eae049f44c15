//! The scenario as run that a `shard.json` or a `checkpoint.json` holds (docs/formats.md
//! § 7.3, § 7.3.1): read back from its settings, its trial count checked against them, and
//! two such settings compared, as written and by what they set.

use std::path::Path;

use crate::error::{Error, Result};
use crate::study::kind::AnyScenario;

/// The scenario as run that `settings` holds, the key `settings` of `holder` (a `shard.json`
/// or a `checkpoint.json`), read from `scenario_file`. An error names `holder` and its key on
/// one line, not the scenario file: the text is the file's, not the user's scenario.
pub(crate) fn scenario_as_run(
    holder: &Path,
    settings: &str,
    scenario_file: Option<&Path>,
) -> Result<AnyScenario> {
    AnyScenario::parse(settings, scenario_file).map_err(|e| {
        let said = match &e {
            Error::File { place, msg, .. } => format!("{place}: {msg}"),
            e => e.to_string(),
        };
        let said: Vec<&str> = said
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect();
        Error::file(
            holder,
            "settings",
            format!(
                "the scenario as run cannot be read ({}): the file was altered",
                said.join(" ")
            ),
        )
    })
}

/// Refuses, naming the key `trials` of `holder` (a `shard.json` or a `checkpoint.json`), a
/// trial count that is not that of `scenario`, the scenario as run the same file holds.
pub(crate) fn trials_as_run(holder: &Path, trials: usize, scenario: &AnyScenario) -> Result<()> {
    if trials == scenario.trials() {
        return Ok(());
    }
    Err(Error::file(
        holder,
        "trials",
        format!(
            "{trials}, where its settings run {} trials: the file was altered",
            scenario.trials()
        ),
    ))
}

/// The first setting where the scenarios as run `a` and `b` (TOML texts, as `shard.json` and
/// `checkpoint.json` hold them) differ: its dotted key and its value in each.
pub(crate) fn settings_difference(a: &str, b: &str) -> Option<(String, String, String)> {
    let table = |t: &str| toml::from_str::<toml::Value>(t).ok();
    first_difference("", table(a).as_ref(), table(b).as_ref())
}

/// Whether the scenarios as run `a` and `b` (TOML texts) set the same, written otherwise
/// ([`crate::study::scenario::effect`]).
pub(crate) fn one_effect(a: &str, b: &str) -> bool {
    let effect = |t: &str| {
        let table: toml::Table = toml::from_str(t).ok()?;
        crate::study::scenario::effect(&table)
    };
    effect(a).is_some_and(|e| Some(e) == effect(b))
}

/// The first setting where two scenarios' settings differ: its dotted key and its values in
/// each, as TOML writes them (`not set` where one does not give it).
fn first_difference(
    key: &str,
    a: Option<&toml::Value>,
    b: Option<&toml::Value>,
) -> Option<(String, String, String)> {
    if a == b {
        return None;
    }
    if let (Some(toml::Value::Table(x)), Some(toml::Value::Table(y))) = (a, b) {
        let dotted = |k: &str| {
            if key.is_empty() {
                k.to_string()
            } else {
                format!("{key}.{k}")
            }
        };
        return x
            .keys()
            .chain(y.keys())
            .find_map(|k| first_difference(&dotted(k), x.get(k), y.get(k)));
    }
    let shown = |v: Option<&toml::Value>| v.map_or("not set".to_string(), |v| v.to_string());
    Some((key.to_string(), shown(a), shown(b)))
}
