//! The one parse of calbench's JSON files (summaries, baselines, `identified.json`,
//! `task.json`, `shard.json`, `checkpoint.json`) that refuses a key written twice in one
//! object and a number below the smallest 64-bit one (`1e-400`), naming the file, the line
//! and the key path, as a TOML file's are refused: serde_json keeps the last value of a key,
//! reads such a number as 0, and a reader would use either without a word.

use std::cell::RefCell;
use std::fmt;
use std::path::Path;

use serde::de::{DeserializeSeed, Deserializer, Error as _, MapAccess, SeqAccess, Visitor};
use serde_json::{Map, Number, Value};

use super::{Error, Result};

/// What [`Unique`] saw that serde_json does not say: a key written twice (its key path and
/// the key), the key paths of the floats that read as 0 in the text's order, and the key path
/// of the value being read (where serde_json's own refusal of a number stands).
#[derive(Default)]
struct Found {
    duplicate: Option<(String, String)>,
    zeros: Vec<String>,
    reading: String,
}

/// Builds a [`Value`] as serde_json does, refusing a key written twice in one object; the key
/// path of the value is `path` (`results[0]`), what it finds is kept in `found`.
struct Unique<'a> {
    path: String,
    found: &'a RefCell<Found>,
}

impl<'a> Unique<'a> {
    fn at(&self, path: String) -> Unique<'a> {
        self.found.borrow_mut().reading.clone_from(&path);
        Unique {
            path,
            found: self.found,
        }
    }
}

impl<'de> DeserializeSeed<'de> for Unique<'_> {
    type Value = Value;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Unique<'_> {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> std::result::Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> std::result::Result<Value, E> {
        Ok(Value::Number(v.into()))
    }
    fn visit_u64<E>(self, v: u64) -> std::result::Result<Value, E> {
        Ok(Value::Number(v.into()))
    }
    fn visit_f64<E>(self, v: f64) -> std::result::Result<Value, E> {
        if v == 0.0 {
            self.found.borrow_mut().zeros.push(self.path);
        }
        Ok(Number::from_f64(v).map_or(Value::Null, Value::Number))
    }
    fn visit_str<E>(self, v: &str) -> std::result::Result<Value, E> {
        Ok(Value::String(v.to_string()))
    }
    fn visit_string<E>(self, v: String) -> std::result::Result<Value, E> {
        Ok(Value::String(v))
    }
    fn visit_unit<E>(self) -> std::result::Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> std::result::Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<Value, A::Error> {
        let mut out = Vec::new();
        while let Some(v) =
            seq.next_element_seed(self.at(format!("{}[{}]", self.path, out.len())))?
        {
            out.push(v);
        }
        Ok(Value::Array(out))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<Value, A::Error> {
        let mut out = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            let path = match self.path.as_str() {
                "" => key.clone(),
                p => format!("{p}.{key}"),
            };
            if out.contains_key(&key) {
                self.found.borrow_mut().duplicate = Some((path, key));
                return Err(A::Error::custom("duplicate key"));
            }
            let v = map.next_value_seed(self.at(path))?;
            out.insert(key, v);
        }
        Ok(Value::Object(out))
    }
}

/// The JSON `text` of the file `path` as a value: text that is not JSON is refused at its line
/// (`line 3: expected value at line 3 column 5`), and a key written twice in one object at
/// the line of its second writing, naming its key path (`line 57, results[0].eta_mean_pct:
/// duplicate key …`).
pub fn json_value(path: &Path, text: &str) -> Result<Value> {
    parse(path, text).map_err(|(e, _)| e)
}

/// Refuses, as [`json_value`] does, a key written twice in one object of the JSON `text` of
/// the file `path`, for a reader that parses the text into its own types (and says itself
/// what is not JSON).
pub fn unique_keys(path: &Path, text: &str) -> Result<()> {
    match parse(path, text) {
        Err((e, true)) => Err(e),
        _ => Ok(()),
    }
}

/// The calbench file `what` (`shard.json`, `checkpoint.json`) at `path`, whose text `text`
/// [`json_value`] read as `v`, as `T`: a key missing, unknown or of the wrong type is refused
/// naming the file, the key's line and the key path ([`super::read_typed`]).
pub fn json_typed<T: serde::de::DeserializeOwned>(
    v: &Value,
    path: &Path,
    text: &str,
    what: &str,
) -> Result<T> {
    super::read_typed(v, path, what)
        .map_err(|e| e.at_line_of(|key| super::json_key_line(text, key)))
}

/// The refusal `e` of a reader that parses the JSON `text` of the file `path` into its own
/// types, at its line as [`json_value`] places one (`line 3: missing field …`).
pub fn json_refusal(path: &Path, text: &str, e: &serde_json::Error) -> Error {
    Error::file(path, format!("line {}", e.line()), not_json(text, e))
}

/// The number literals of the JSON `text` outside its strings, with their byte offsets.
fn numbers(text: &str) -> Vec<(usize, &str)> {
    let (bytes, mut out, mut i) = (text.as_bytes(), Vec::new(), 0);
    while i < bytes.len() {
        match bytes[i] {
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
                i += 1;
            }
            b'-' | b'0'..=b'9' => {
                let len = bytes[i..]
                    .iter()
                    .take_while(|b| matches!(b, b'0'..=b'9' | b'-' | b'+' | b'.' | b'e' | b'E'))
                    .count();
                out.push((i, &text[i..i + len]));
                i += len;
            }
            _ => i += 1,
        }
    }
    out
}

/// [`json_value`], its refusal marked `true` for one serde_json does not make: a key written
/// twice, or a number below the smallest 64-bit one.
fn parse(path: &Path, text: &str) -> std::result::Result<Value, (Error, bool)> {
    let found = RefCell::new(Found::default());
    let mut de = serde_json::Deserializer::from_str(text);
    let parsed = Unique {
        path: String::new(),
        found: &found,
    }
    .deserialize(&mut de)
    .and_then(|v| de.end().map(|()| v));
    let found = found.into_inner();
    let parsed = parsed.map_err(|e| match found.duplicate {
        Some((key_path, key)) => {
            let msg = format!(
                "duplicate key `{key}`: it is written a second time in its object, and a \
                 reader would take one of the two values without a word; no calbench file \
                 writes a key twice"
            );
            (
                Error::file(path, format!("line {}, {key_path}", e.line()), msg),
                true,
            )
        }
        None if !found.reading.is_empty() && e.to_string().starts_with("number out of range") => (
            Error::file(
                path,
                format!("line {}, {}", e.line(), found.reading),
                not_json(text, &e),
            ),
            false,
        ),
        None => (json_refusal(path, text, &e), false),
    })?;
    // Every float that reads as 0 (serde_json reads `0` alone as an integer), in order: the
    // one whose text has a digit other than 0 was below the smallest 64-bit number.
    if found.zeros.is_empty() {
        return Ok(parsed);
    }
    let written = numbers(text)
        .into_iter()
        .filter(|(_, t)| *t != "0" && t.parse::<f64>() == Ok(0.0));
    for (key_path, (at, t)) in found.zeros.iter().zip(written) {
        if let Some(msg) = super::underflow(t, 0.0) {
            let line = text[..at].matches('\n').count() + 1;
            return Err((
                Error::file(path, format!("line {line}, {key_path}"), msg),
                true,
            ));
        }
    }
    Ok(parsed)
}

/// The parser's refusal `e` of `text`, with what a reader needs that it does not say: that the
/// file is empty, or that `NaN` and `Infinity` (which Python's `json` writes) are not JSON,
/// where calbench writes `null` for a figure it has none of.
fn not_json(text: &str, e: &serde_json::Error) -> String {
    let start = text.trim_start();
    if start.is_empty() {
        return "is empty, where a JSON document was expected".into();
    }
    // Another kind of file (a CSV, a TOML) given for a JSON one: say so, not the parser's
    // "expected ident".
    if !start.starts_with(['{', '[']) {
        let first = start.lines().next().unwrap_or("");
        let shown: String = first.chars().take(40).collect();
        let more = if shown.len() < first.len() { "…" } else { "" };
        return format!(
            "is not JSON: it begins `{}{more}`, where a JSON document begins with `{{` ({e})",
            shown.escape_debug()
        );
    }
    let line = text.lines().nth(e.line().saturating_sub(1)).unwrap_or("");
    // serde_json counts a line's columns in bytes.
    let at = line.get(e.column().saturating_sub(1)..).unwrap_or("");
    match ["NaN", "Infinity"].into_iter().find(|w| at.starts_with(w)) {
        Some(w) => format!(
            "{e}: `{w}` is not JSON (a file calbench writes holds `null` for a figure it has \
             none of)"
        ),
        None => e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_key_written_twice_is_refused_at_its_second_line() {
        let text = "{\n  \"a\": [\n    {\"b\": 1,\n     \"b\": 2}\n  ]\n}\n";
        let e = json_value(Path::new("s.json"), text)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("s.json: line 4, a[0].b: duplicate key `b`"),
            "{e}"
        );
        assert!(unique_keys(Path::new("s.json"), text).is_err());
        let same = "{\"a\": [{\"b\": 1.5, \"c\": null}], \"b\": {\"b\": true}}";
        let v = json_value(Path::new("s.json"), same).unwrap();
        assert_eq!(v, serde_json::from_str::<Value>(same).unwrap());
        let e = json_value(Path::new("s.json"), "{\n\"a\": }").unwrap_err();
        assert!(e.to_string().starts_with("s.json: line 2: "), "{e}");
        // Another kind of file is named as such, at its first line.
        let csv = "trial,strategy,method,validation_after_mean_mm_mean_over_the_trials\n0,random\n";
        let e = json_value(Path::new("s.json"), csv).unwrap_err();
        assert_eq!(
            e.to_string(),
            "s.json: line 1: is not JSON: it begins `trial,strategy,method,validation_after_m…`, \
             where a JSON document begins with `{` (expected ident at line 1 column 3)"
        );
        assert!(unique_keys(Path::new("s.json"), "{\n\"a\": }").is_ok());
    }

    #[test]
    fn a_number_below_the_smallest_double_is_refused_at_its_line_and_key() {
        // Strings, `0`, `-0`, `0.0` and `0e-400` read as 0 and are zero; a subnormal is kept.
        let text = "{\"s\": \"1e-400 \\\" 2e-999\", \"z\": [0, -0, 0.0, 0e-400, 4.9e-324],\n\
                    \"r\": [{\"a\": 1.5}, {\"b\": [2, 1e-400]}]}";
        let e = json_value(Path::new("s.json"), text).unwrap_err();
        assert_eq!(
            e.to_string(),
            "s.json: line 2, r[1].b[1]: \"1e-400\" is below the smallest 64-bit number (about \
             4.9e-324) and would read as 0"
        );
        assert!(unique_keys(Path::new("s.json"), text).is_err());
        let fine = text.replace("1e-400]", "1e-300]");
        assert!(json_value(Path::new("s.json"), &fine).is_ok());
        // A number beyond the largest is refused by the parser, at its key.
        let e = json_value(Path::new("s.json"), "{\"a\": {\"b\":\n 1e400}}").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("s.json: line 2, a.b: number out of range"),
            "{e}"
        );
    }
}
