//! Reading a summary for `check`, `compare`, `baseline` and `record`: by serde
//! ([`Summary`]), refusing what no run can have written, naming the file, the key and its line.

use std::path::Path;

use serde_json::Value;

use super::baseline;
use crate::analysis::figures;
use crate::analysis::summary::Summary;
use crate::error::{read_text, Error, Result};

/// Reads the JSON `value` of the file `path` as a calbench summary ([`Summary`], by serde),
/// refusing, naming the file and the key (with its line where the file writes it), what is
/// not one: not an object with a `scenario` name and `results`, a list of entries each naming
/// its `method`; a figure of the wrong type; a later format; figures no run writes
/// ([`figures::check_figures`] for [`figures::Reader::Compare`]).
pub fn check_summary(value: Value, path: &Path) -> Result<Summary> {
    check_summary_for(value, path, figures::Reader::Compare).map(|(s, _)| s)
}

/// [`check_summary`] with its figures checked for `reader`, returned with the summary
/// ([`figures::of_summary`]).
pub fn check_summary_for(
    value: Value,
    path: &Path,
    reader: figures::Reader,
) -> Result<(Summary, Vec<figures::Figure>)> {
    // A study of cells writes its `kind` and `cells` where a Monte-Carlo study writes
    // `results`: a calbench summary, of another kind.
    if let (Some(kind), None) = (
        value.get("kind").and_then(Value::as_str),
        value.get("results"),
    ) {
        let msg = format!(
            "is \"{kind}\": the summary of a study of cells, which `check`, `compare` and \
             `baseline` do not compare (they compare the `results` of a Monte-Carlo study's \
             summary); `record` and `history` follow such a study cell by cell"
        );
        return Err(Error::file(path, "kind", msg).at_json_key_line());
    }
    let what = "so this is not a calbench summary (summary.json from `calbench run`: an object \
                with a `scenario` name and `results`, a list of entries with `method`, `poses` \
                and metrics)";
    // Every run writes the validation errors of each entry; a block deleted reads as NaN.
    let lacking = written_blocks(&value);
    let keys: Vec<String> = value
        .as_object()
        .map(|m| {
            m.iter()
                .filter(|(_, v)| !v.is_null())
                .map(|(k, _)| k.clone())
                .collect()
        })
        .unwrap_or_default();
    let s = Summary::from_value(value, path).map_err(|e| {
        match e {
            Error::File { file, place, msg } if place != "format" => {
                Error::file(file, place, format!("{msg}, {what}"))
            }
            e => e,
        }
        .at_json_key_line()
    })?;
    unknown_key(&s, &keys, path)?;
    named_values(&s, path)?;
    // `check` and `compare` name every baseline entry an empty summary lacks; none is stored.
    if reader == figures::Reader::Record && s.results.is_empty() {
        let why = "holds no entry: every run writes one per method and pose strategy";
        return Err(Error::file(path, "results", why).at_json_key_line());
    }
    // Entries are paired by their key: a second one of a key would be paired or passed over
    // by where it stands.
    for (i, e) in s.results.iter().enumerate() {
        let first = s.results[..i].iter().position(|f| f.key() == e.key());
        let why = match first {
            _ if e.method.is_empty() => format!("is an entry without a `method` name, {what}"),
            _ if e.poses.is_empty() => format!("is an entry without its `poses` strategy, {what}"),
            // A scenario refuses such a label; `check` shows one escaped, but none is stored.
            _ if reader == figures::Reader::Record
                && e.method
                    .chars()
                    .chain(e.poses.chars())
                    .any(crate::error::is_hidden) =>
            {
                "names its method or strategy with a control character (bidirectional \
                 overrides included), which no run writes"
                    .to_string()
            }
            Some(j) => format!(
                "is a second entry of {} (the first is results[{j}]): a summary has one entry \
                 per method, poses and sweep value",
                e.key()
            ),
            None => continue,
        };
        return Err(Error::file(path, format!("results[{i}]"), why).at_json_key_line());
    }
    if let Some((i, block)) = lacking.filter(|_| reader == figures::Reader::Record) {
        let why = format!(
            "lacks `{block}`, which every run writes for each entry: the summary was edited"
        );
        return Err(Error::file(path, format!("results[{i}]"), why).at_json_key_line());
    }
    let figures = figures::of_summary(&s)?;
    let at = |entry: &str| {
        let i = s.results.iter().position(|e| e.key() == entry)?;
        Some(format!("results[{i}]"))
    };
    figures::check_figures(path, s.trials, &figures, reader, &at)?;
    check_terminations(&s, path)?;
    Ok((s, figures))
}

/// Refuses, naming the file and the key at its line, a `measure` or a `registration` that no
/// run writes (a summary without them, written before the keys, reads them as empty).
fn named_values(s: &Summary, path: &Path) -> Result<()> {
    use crate::calibrate::Registration;
    use strum::VariantNames as _;
    let registrations = Registration::VARIANTS;
    for (key, value, names) in [
        ("measure", &s.measure, &Summary::MEASURES[..]),
        ("registration", &s.registration, registrations),
    ] {
        if !value.is_empty() && !names.contains(&value.as_str()) {
            let why = format!("is \"{value}\", which no run writes ({})", names.join(", "));
            return Err(Error::file(path, key, why).at_json_key_line());
        }
    }
    Ok(())
}

/// The first entry of the summary `value` (its index) without one of the blocks of validation
/// errors every run writes, and that block.
fn written_blocks(value: &Value) -> Option<(usize, &'static str)> {
    let entries = value.get("results")?.as_array()?;
    entries.iter().enumerate().find_map(|(i, e)| {
        let e = e.as_object()?;
        use crate::calibrate::validation::keys::{AFTER_MM, BEFORE_MM};
        [BEFORE_MM, AFTER_MM]
            .into_iter()
            .find(|k| !e.contains_key(*k))
            .map(|k| (i, k))
    })
}

/// Refuses, naming the file and the key at its line, an entry's `terminations` that no run
/// writes: a name that is not a termination ([`crate::identify::Termination`], as
/// `identified.json` names them), counts that do not add up to the summary's `trials`
/// (each trial's identification ends one way), or `failures` fewer than the trials that ended
/// with no result. A summary without them is not judged.
fn check_terminations(s: &Summary, path: &Path) -> Result<()> {
    use std::str::FromStr as _;
    for (i, e) in s.results.iter().enumerate() {
        let t = &e.terminations;
        if let Some(name) = t
            .keys()
            .find(|k| crate::identify::Termination::from_str(k).is_err())
        {
            let names = <crate::identify::Termination as strum::VariantNames>::VARIANTS;
            let why = format!(
                "is not a termination of an identification ({})",
                names.join(", ")
            );
            let key = format!("results[{i}].terminations.{name}");
            return Err(Error::file(path, key, why).at_json_key_line());
        }
        let sum: usize = t.values().sum();
        if let Some(n) = s.trials.filter(|&n| !t.is_empty() && sum != n) {
            let why = format!(
                "add up to {sum}, but the run has {n} trials: each trial's identification \
                 ends one way"
            );
            let key = format!("results[{i}].terminations");
            return Err(Error::file(path, key, why).at_json_key_line());
        }
        // A trial that diverged, was singular or had invalid input gave no result, so it is a
        // failure (one rank-deficient may still be used, and one of finite termination may not).
        let unusable: usize = (t.iter())
            .filter(|(k, _)| {
                crate::identify::Termination::from_str(k).is_ok_and(|t| t.gives_nothing())
            })
            .map(|(_, n)| n)
            .sum();
        if e.failures < unusable {
            let why = format!(
                "is {}, but {} ended diverged, singular or with invalid input (its \
                 `terminations`), and none of those gives a result: each is a failure",
                e.failures,
                crate::error::counted(unusable, "trial", "trials")
            );
            let key = format!("results[{i}].failures");
            return Err(Error::file(path, key, why).at_json_key_line());
        }
    }
    Ok(())
}

/// Refuses, naming the file, the key and its line, a top-level key of a summary (`keys`, those
/// it gives a value other than `null`) that no calbench summary has: read, it would be passed
/// over, and a misspelt figure (`"trails": 5`) read as absent. A summary writes every key it
/// holds a value of, and `format` only past the first; a baseline adds `per_trial`.
fn unknown_key(s: &Summary, keys: &[String], path: &Path) -> Result<()> {
    let written = s.to_value()?;
    let known = |k: &str| k == "format" || k == baseline::KEY || written.get(k).is_some();
    match keys.iter().find(|k| !known(k)) {
        Some(k) => Err(Error::file(
            path,
            k.as_str(),
            "is not a key of a calbench summary (docs/formats.md § 7.1): it would be passed \
             over, and a misspelt one read as absent",
        )
        .at_json_key_line()),
        None => Ok(()),
    }
}

/// Reads a JSON file.
pub fn read_json(path: &Path) -> Result<Value> {
    let text = read_text(path)?;
    crate::error::json_value(path, &text)
}

/// Reads the summary file `path` ([`check_summary`]).
pub fn read_summary(path: &Path) -> Result<Summary> {
    check_summary(read_json(path)?, path)
}
