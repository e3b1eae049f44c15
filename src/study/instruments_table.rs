//! The `[instruments_study]` table of an instruments study (docs/formats.md § 4.15): its keys,
//! moved to the top level where [`super::instruments::InstrumentsScenario`] reads them, and
//! the refusal of the layout before the table, saying how to migrate.

use std::path::Path;

use crate::error::{Error, Result};

/// The table that makes a scenario an instruments study.
pub const INSTRUMENTS_STUDY: &str = "instruments_study";

/// The keys of [`INSTRUMENTS_STUDY`].
pub const INSTRUMENTS_KEYS: [&str; 4] = ["poses", "strategies", "candidates", "validation"];

/// How a scenario written before [`INSTRUMENTS_STUDY`] existed is migrated.
pub const MIGRATE: &str = "an instruments study is declared by an [instruments_study] table \
    holding its poses, strategies, candidates and validation (CHANGELOG.md, docs/formats.md \
    § 4.15): add `[instruments_study]` and move those keys under it";

/// An instruments study's `table` with the keys of its `[instruments_study]` table moved to
/// the top level, where [`super::instruments::InstrumentsScenario`] reads them; `path` names the file in errors.
/// One of those keys at the top level (the layout before the table), a missing table and a
/// key the table does not take are refused, naming the key and saying how to migrate.
pub fn instruments_keys(mut table: toml::Table, path: &Path) -> Result<toml::Table> {
    let ferr = |place: &str, msg: String| Error::file(path, place, msg);
    if let Some(key) = INSTRUMENTS_KEYS.iter().find(|k| table.contains_key(**k)) {
        return Err(ferr(
            key,
            format!("{MIGRATE} (`{key}` is at the top level)"),
        ));
    }
    let study = match table.remove(INSTRUMENTS_STUDY) {
        Some(toml::Value::Table(t)) => t,
        Some(_) => return Err(ferr(INSTRUMENTS_STUDY, "must be a table".into())),
        None => return Err(ferr(INSTRUMENTS_STUDY, format!("is missing: {MIGRATE}"))),
    };
    for (k, v) in study {
        if !INSTRUMENTS_KEYS.contains(&k.as_str()) {
            return Err(ferr(
                &format!("{INSTRUMENTS_STUDY}.{k}"),
                format!(
                    "unknown key: [{INSTRUMENTS_STUDY}] takes {}",
                    INSTRUMENTS_KEYS.join(", ")
                ),
            ));
        }
        table.insert(k, v);
    }
    Ok(table)
}
