//! serde's words in a refusal said as a file's reader would say them: the key of a TOML
//! value's error, the unknown field, and Rust's type names after `expected `.

/// A serde error of a TOML value read from a table rather than a text (so without a line):
/// its message, and the dotted key it is about, which toml writes on a line of its own after
/// the message (`in `tracker.mpe_a_um``). A refusal shows the key as its place. toml's
/// message for a name given as another type (`kind = 3`), which speaks of serde's "unit
/// variant", is said as the file should read.
pub fn toml_value_error(e: &toml::de::Error) -> (String, Option<String>) {
    let text = e.to_string();
    let text = text.trim_end().replace(
        NOT_A_NAME,
        "must be a name in double quotes (a TOML string)",
    );
    match text.rsplit_once("\nin `") {
        Some((msg, key)) => (msg.to_string(), Some(key.trim_end_matches('`').to_string())),
        None => (text.to_string(), None),
    }
}

/// [`toml_value_error`] of a scenario's value, with the place its refusal names: the key, a
/// key missing from the scenario itself by its own name (`name`), else `scenario`.
pub fn scenario_value_error(e: &toml::de::Error) -> (String, String) {
    let (msg, key) = toml_value_error(e);
    let missing = missing_field(&msg).map(String::from);
    let place = key.or(missing).unwrap_or_else(|| "scenario".into());
    (msg, place)
}

/// The key serde's refusal of a missing field names (`missing field `name``); `None` for any
/// other refusal.
pub(super) fn missing_field(msg: &str) -> Option<&str> {
    msg.strip_prefix("missing field `")?
        .split_once('`')
        .map(|(field, _)| field)
}

/// The key serde's refusal of an unknown field names (`unknown field `foo`, expected one of
/// …`), and the rest of the message after it; `None` for any other refusal.
pub fn unknown_field(msg: &str) -> Option<(&str, &str)> {
    msg.strip_prefix("unknown field `")?.split_once('`')
}

/// toml's message (0.9) when a value of any other type stands where a named choice is read.
const NOT_A_NAME: &str = "invalid type: unit variant, expected string only";

/// serde's names of the number types a file's value is read as, and what a message says
/// instead: `expected usize` is `expected a whole number ≥ 0`.
const NUMBER_TYPES: [(&str, &str); 12] = [
    ("usize", "a whole number ≥ 0"),
    ("u64", "a whole number ≥ 0"),
    ("u32", "a whole number from 0 to 4294967295"),
    ("u16", "a whole number from 0 to 65535"),
    ("u8", "a whole number from 0 to 255"),
    ("isize", "a whole number"),
    ("i64", "a whole number"),
    ("i32", "a whole number from -2147483648 to 2147483647"),
    ("i16", "a whole number from -32768 to 32767"),
    ("i8", "a whole number from -128 to 127"),
    ("f64", "a number"),
    ("f32", "a number"),
];

/// `text` with serde's Rust type names after `expected ` (`invalid type: string "a",
/// expected usize`, from a file's or a dict's value) said in words ([`NUMBER_TYPES`], and
/// `struct NAME` as `a table of keys`); any other text as it is.
pub(super) fn plain_types(text: String) -> String {
    const EXPECTED: &str = "expected ";
    if let Some(said) = beyond_toml(&text) {
        return said;
    }
    if !text.contains(EXPECTED) {
        return text;
    }
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(i) = rest.find(EXPECTED) {
        let after = &rest[i + EXPECTED.len()..];
        out.push_str(&rest[..i + EXPECTED.len()]);
        rest = after;
        let ends = |name: &str| {
            after
                .strip_prefix(name)
                .is_some_and(|tail| !tail.starts_with(|c: char| c.is_alphanumeric() || c == '_'))
        };
        if let Some((name, words)) = NUMBER_TYPES.iter().find(|(name, _)| ends(name)) {
            out.push_str(words);
            rest = &after[name.len()..];
        } else if let Some(tail) = after.strip_prefix("struct ") {
            // serde's `expected struct RobotSection`: the section's Rust type.
            let name = tail.find(|c: char| !c.is_alphanumeric() && c != '_');
            out.push_str("a table of keys");
            rest = &tail[name.unwrap_or(tail.len())..];
        }
    }
    out.push_str(rest);
    out
}

/// toml's refusals of a whole number beyond the 64-bit integers TOML has (`u64 value was too
/// large`; `invalid type: integer `N` as i128, expected any valid TOML value`, or `expected a
/// number` where a robot file's length is read), said with the range; `None` for any other
/// text.
fn beyond_toml(text: &str) -> Option<String> {
    const RANGE: &str = "beyond TOML's whole numbers, -9223372036854775808 to \
                         9223372036854775807 (2^63 − 1)";
    if text == "u64 value was too large" {
        return Some(format!("the whole number is {RANGE}"));
    }
    // Whatever the key expected (any value, a number): the number is none of TOML's.
    let (head, expected) = text.split_once(" as i128, expected ")?;
    let tail = expected.find('\n').map_or("", |i| &expected[i..]);
    let n = head.strip_prefix("invalid type: integer ")?;
    Some(format!("{n} is {RANGE}{tail}"))
}

#[cfg(test)]
mod tests {
    use crate::error::Said;

    #[test]
    fn serde_number_types_are_said_in_words() {
        let said = |t: &str| Said::from(t).to_string();
        assert_eq!(
            said("invalid type: string \"a\", expected usize"),
            "invalid type: string \"a\", expected a whole number ≥ 0"
        );
        assert_eq!(
            said("invalid type: floating point `6.5`, expected u64\nin `seed`"),
            "invalid type: floating point `6.5`, expected a whole number ≥ 0\nin `seed`"
        );
        assert_eq!(
            said("u64 value was too large"),
            "the whole number is beyond TOML's whole numbers, -9223372036854775808 to 9223372036854775807 \
             (2^63 − 1)"
        );
        assert_eq!(
            said("invalid type: integer `99999999999999999999` as i128, expected any valid TOML value"),
            "`99999999999999999999` is beyond TOML's whole numbers, -9223372036854775808 to \
             9223372036854775807 (2^63 − 1)"
        );
        // A robot file's number: the same words, not the parser's type.
        assert_eq!(
            said("invalid type: integer `99999999999999999999` as i128, expected a number\nin `a`"),
            "`99999999999999999999` is beyond TOML's whole numbers, -9223372036854775808 to \
             9223372036854775807 (2^63 − 1)\nin `a`"
        );
        assert_eq!(
            said("invalid value: integer `300`, expected u8"),
            "invalid value: integer `300`, expected a whole number from 0 to 255"
        );
        assert_eq!(
            said("expected f64, expected i64"),
            "expected a number, expected a whole number"
        );
        // A section given as a value: serde names its Rust type.
        assert_eq!(
            said("invalid type: string \"irb2600\", expected struct RobotSection"),
            "invalid type: string \"irb2600\", expected a table of keys"
        );
        // Other words after `expected`, and type names inside longer words, stay.
        for kept in [
            "invalid length 2, expected an array of length 6",
            "expected u64x",
            "expected f64_pair",
            "unknown field `a`, expected one of `usize`",
            "expected",
        ] {
            assert_eq!(said(kept), kept);
        }
    }
}
