//! Every TOML file calbench reads (robot, scenario, mapping, task, priors) read by one reader:
//! a syntax error refused at its line in the `file: line N: message` form of every other
//! refusal, a key of the wrong type, missing or unknown at its line and key path, and a number
//! that underflows to 0 refused where it is written ([`refuse_toml_underflow`]).

use std::path::Path;

use serde::de::DeserializeOwned;

use super::{at_line, line_of, refuse_toml_underflow, Error, Result};

/// `line N` of a TOML error, where it has a place; `TOML` where it has none.
fn toml_place(text: &str, e: &toml::de::Error) -> String {
    e.span().map_or("TOML".into(), |s| {
        format!("line {}", line_of(text, s.start))
    })
}

/// The refusal of the TOML `text` (the file `path`) that toml cannot read as TOML: at its line,
/// toml's message, a duplicate key named (toml names none; its span is the key's).
fn toml_syntax(path: &Path, text: &str, e: &toml::de::Error) -> Error {
    let msg = e.message().trim_end();
    let msg = match e.span().and_then(|s| text.get(s)) {
        Some(key) if msg == "duplicate key" => format!("duplicate key `{}`", key.trim()),
        _ => msg.to_string(),
    };
    Error::file(path, toml_place(text, e), msg)
}

/// The TOML `text` of the file `path` read as `K`: its syntax refused as `toml_syntax`; a
/// key of the wrong type, a missing or an unknown key refused naming the line and the key path
/// (`line 23, joints[2].a`; a missing or unknown key by its own path, `own_key`); a number
/// that reads as 0 refused at its key.
pub fn toml_keys<K: DeserializeOwned>(path: &Path, text: &str) -> Result<K> {
    let de = toml::Deserializer::parse(text).map_err(|e| toml_syntax(path, text, &e))?;
    let k = serde_path_to_error::deserialize(de).map_err(|e| {
        let key = e.path().to_string();
        let e = e.into_inner();
        let msg = e.message().trim_end();
        let line = toml_error_line(text, &e);
        let place = match own_key(key, msg) {
            key if key == "." => toml_place(text, &e),
            key => at_line(line, key),
        };
        Error::file(path, place, msg)
    })?;
    refuse_toml_underflow(path, text)?;
    Ok(k)
}

/// The line of a TOML refusal `e` of `text`; none for a key missing from the document
/// itself, which toml places at the empty span at its start (line 1 would name a line that
/// has nothing to do with it).
pub fn toml_error_line(text: &str, e: &toml::de::Error) -> Option<usize> {
    e.span()
        .filter(|s| !(s.is_empty() && s.start == 0))
        .map(|s| line_of(text, s.start))
}

/// The key path a serde refusal `msg` at the path `key` is about: a missing field's and an
/// unknown one's own (`chosen_by`, `joints[1].mas_kg`), not that of the table it is missing
/// from or written in; any other refusal's `key`.
pub(super) fn own_key(key: String, msg: &str) -> String {
    // serde_json says where after the message (`… at line 1 column 17`); the path of an
    // unknown field may end in it already (a JSON reader's does).
    let said = msg.split(" at line ").next().unwrap_or(msg);
    let field = super::serde_words::missing_field(said)
        .or_else(|| super::unknown_field(said).map(|(f, _)| f));
    let ends_in = |f: &str| key == f || key.ends_with(&format!(".{f}"));
    match field.filter(|f| !ends_in(f)) {
        Some(field) if key == "." => field.to_string(),
        Some(field) => format!("{key}.{field}"),
        None => key,
    }
}
