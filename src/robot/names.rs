//! Names of the settings' enums, from serde alone: an enum derives `Serialize` /
//! `Deserialize` with its `rename_all` rule, and [`static_name`] and [`parse`] give the name
//! of a value and the value of a name (command-line options, reports), so no enum carries a
//! hand-written `as_str` / `FromStr` pair. [`take_keys`] splits one options table between
//! two structs.

use serde::de::value::{Error as ValueError, StrDeserializer};
use serde::de::{DeserializeOwned, Deserializer, Error as _, IntoDeserializer, Visitor};
use serde::Serialize;

use crate::error::{Error, Result};

/// The serde name of a unit variant (`Termination::MaxIterations` → `"max-iterations"`): the
/// entry of the enum's variant list (as its `Deserialize` declares it) that equals the value
/// serialised.
///
/// # Panics
/// If `v` is not a unit variant of a field-less enum (a programming error).
pub fn static_name<T: Serialize + DeserializeOwned>(v: &T) -> &'static str {
    let name = serde_json::to_value(v).ok();
    let probe = VariantList::default();
    let _ = T::deserialize(&probe);
    probe
        .0
        .get()
        .iter()
        .find(|n| name.as_ref().and_then(|v| v.as_str()) == Some(**n))
        .copied()
        .unwrap_or_else(|| panic!("static_name on a value that is not a unit variant: {name:?}"))
}

/// Parses `s` as the serde name of a `T` (a field-less enum); the error names `key` and the
/// allowed names.
pub fn parse<T: DeserializeOwned>(key: &str, s: &str) -> Result<T> {
    let d: StrDeserializer<'_, ValueError> = s.into_deserializer();
    T::deserialize(d).map_err(|e| Error::setting(key, e.to_string()))
}

/// [`parse`] of a value read from `file` at `place` (a key path): the error names the file,
/// the place, the value and the allowed names.
pub fn parse_in<T: DeserializeOwned>(file: &std::path::Path, place: &str, s: &str) -> Result<T> {
    parse(place, s).map_err(|e| match e {
        Error::Setting { msg, .. } => Error::file(file, place, msg),
        other => other,
    })
}

/// Removes the entries of `keys` from `table` and returns them as a table of their own: for
/// options read from one table into two structs (each refusing keys it does not know).
pub fn take_keys(table: &mut toml::Table, keys: &[&str]) -> toml::Table {
    keys.iter()
        .filter_map(|k| table.remove(*k).map(|v| (k.to_string(), v)))
        .collect()
}

/// A deserializer that only records the variant names an enum asks for.
#[derive(Default)]
struct VariantList(std::cell::Cell<&'static [&'static str]>);

impl<'de> Deserializer<'de> for &VariantList {
    type Error = ValueError;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> std::result::Result<V::Value, ValueError> {
        Err(ValueError::custom("not an enum"))
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _: &'static str,
        variants: &'static [&'static str],
        _: V,
    ) -> std::result::Result<V::Value, ValueError> {
        self.0.set(variants);
        Err(ValueError::custom("variant names recorded"))
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map struct identifier
        ignored_any
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
    #[serde(rename_all = "kebab-case")]
    enum Colour {
        DeepRed,
        Blue,
    }

    #[test]
    fn names_round_trip_and_unknown_names_list_the_allowed_ones() {
        assert_eq!(static_name(&Colour::DeepRed), "deep-red");
        assert_eq!(parse::<Colour>("colour", "blue").unwrap(), Colour::Blue);
        let e = parse::<Colour>("colour", "green").unwrap_err().to_string();
        assert!(
            e.contains("colour") && e.contains("deep-red") && e.contains("green"),
            "{e}"
        );
    }
}
