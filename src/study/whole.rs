//! What every study that runs whole (a registration study, an instruments study) begins with:
//! the `name`, `description`, `seed` and `trials` keys of its scenario file, read and checked
//! in one place, and the scenario's table as run (`--trials` and `--seed` applied), which the
//! checkpoint and a shard keep to read the study back.

use std::ops::RangeInclusive;
use std::path::Path;

use serde::Deserialize;

use crate::error::{Error, Result};

/// The scenario keys every study that runs whole takes.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Head {
    /// Name (the default output folder `results/<name>/`).
    pub name: String,
    /// What the study asks.
    #[serde(default)]
    pub description: String,
    /// Master seed; trial (draw) t uses `trial_seed(seed, t)`.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Trials (draws) per cell of the study; the study's default when absent.
    pub trials: usize,
    /// The scenario file's whole table, with the overrides of the run.
    #[serde(skip)]
    pub table: toml::Table,
    /// The file it was read from.
    #[serde(skip)]
    pub path: std::path::PathBuf,
}

fn default_seed() -> u64 {
    1
}

/// The keys of [`Head`].
pub(crate) const KEYS: [&str; 4] = ["name", "description", "seed", "trials"];

impl Head {
    /// Takes [`Head`]'s keys out of `table`, read from `path` (named in errors), and checks
    /// them: a name [`folder_name`] accepts, and `trials` (`default_trials` when absent)
    /// within `trials`.
    pub fn take(
        table: &mut toml::Table,
        path: &Path,
        default_trials: usize,
        trials: RangeInclusive<usize>,
    ) -> Result<Head> {
        let ferr = |place: &str, msg: String| Error::file(path, place, msg);
        let whole = table.clone();
        let mut keys: toml::Table = KEYS
            .iter()
            .filter_map(|k| table.remove(*k).map(|v| (k.to_string(), v)))
            .collect();
        let default_trials = i64::try_from(default_trials).unwrap_or(i64::MAX);
        keys.entry("trials")
            .or_insert(toml::Value::Integer(default_trials));
        let mut head: Head =
            toml::Value::Table(keys)
                .try_into()
                .map_err(|e: toml::de::Error| {
                    let (msg, place) = crate::error::scenario_value_error(&e);
                    ferr(&place, msg)
                })?;
        head.table = whole;
        head.path = path.to_path_buf();
        if let Err(msg) = folder_name(&head.name) {
            return Err(ferr("name", msg.into()));
        }
        let n = head.trials;
        if !trials.contains(&n) {
            let (lo, hi) = (trials.start(), trials.end());
            return Err(ferr(
                "trials",
                format!("must be between {lo} and {hi}, got {n}"),
            ));
        }
        head.set(head.trials, head.seed)?;
        Ok(head)
    }

    /// Sets `trials` and `seed`, in the table too (as the command line's overrides do).
    pub fn set(&mut self, trials: usize, seed: u64) -> Result<()> {
        let big = |key: &str| Error::setting(key, "must be below 2^63");
        let n = i64::try_from(trials).map_err(|_| big("trials"))?;
        let s = i64::try_from(seed).map_err(|_| big("seed"))?;
        self.table.insert("trials".into(), toml::Value::Integer(n));
        self.table.insert("seed".into(), toml::Value::Integer(s));
        (self.trials, self.seed) = (trials, seed);
        Ok(())
    }

    /// The scenario as run, TOML text: what a checkpoint and a shard keep.
    pub fn settings(&self) -> Result<String> {
        toml::to_string(&self.table)
            .map_err(|e| Error::Compute(format!("cannot write the scenario: {e}")))
    }
}

/// Reads a study's scenario from `table`, read from `path` (named in errors): its [`Head`]
/// ([`Head::take`], with `default_trials` and the range `trials`) and the rest as `T`, an
/// unknown key refused with the keys such a scenario takes (`takes`).
pub fn parse<T: serde::de::DeserializeOwned>(
    mut table: toml::Table,
    path: &Path,
    (default_trials, trials): (usize, RangeInclusive<usize>),
    takes: &str,
) -> Result<(Head, T)> {
    let head = Head::take(&mut table, path, default_trials, trials)?;
    let rest = toml::Value::Table(table)
        .try_into()
        .map_err(|e: toml::de::Error| {
            let (msg, place) = crate::error::scenario_value_error(&e);
            Error::file(path, place, format!("{msg} (a scenario {takes})"))
        })?;
    Ok((head, rest))
}

/// `e`, a refusal of a study's scenario file whose text is `text`, with the line of the key
/// its place names ([`Error::at_key_line`]); [`parse`]'s refusal of a key the study does not
/// take at the top level (place `scenario`, "unknown field \`methods\`") with that key's line.
pub fn at_key_line(e: Error, text: &str) -> Error {
    match e {
        Error::File { file, place, msg } if place == "scenario" => {
            let said = msg.to_string();
            let key = crate::error::unknown_field(&said);
            let line = key.and_then(|(k, _)| crate::error::toml_key_line(text, k));
            Error::file(file, crate::error::at_line(line, place), msg)
        }
        e => e.at_key_line(text),
    }
}

/// The longest study name, in bytes: a folder name may have 255 on the common file systems,
/// and the run's checkpoint and temporary folders beside `results/<name>/` add to it.
pub const MAX_NAME_BYTES: usize = 200;

/// Whether `name` can name a study's default output folder `results/<name>/`: not empty,
/// no slash, no control or bidirectional formatting character ([`crate::error::is_hidden`]),
/// not `.` or `..` (which would put the run beside or above `results/`), and at most
/// [`MAX_NAME_BYTES`] bytes. The refusal otherwise.
pub fn folder_name(name: &str) -> std::result::Result<(), &'static str> {
    if name.len() > MAX_NAME_BYTES {
        return Err("must be at most 200 bytes: it names the folder results/<name>/, and a longer name is refused by the file system");
    }
    let t = name.trim();
    if t.is_empty()
        || t == "."
        || t == ".."
        || name.contains(['/', '\\'])
        || name.chars().any(crate::error::is_hidden)
    {
        return Err("must be a non-empty name without slashes or control characters (bidirectional overrides included), and not `.` or `..`: it names the folder results/<name>/");
    }
    Ok(())
}
