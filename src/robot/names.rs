//! Names of the settings' enums. An enum derives `Serialize` / `Deserialize` with its
//! `rename_all` rule (the names of files and reports) and `strum`'s `IntoStaticStr`,
//! `EnumString`, `VariantNames` and `EnumIter` with the same rule (`serialize_all`): its
//! `as_str` is `self.into()`, the command line accepts and lists `VARIANTS`, and messages
//! list them, so no enum carries a hand-written name list or `as_str` / `FromStr` pair.
//! [`parse`] reads a name through serde, with serde's message naming the allowed names.

use serde::de::value::{Error as ValueError, StrDeserializer};
use serde::de::{DeserializeOwned, IntoDeserializer};

use crate::error::{Error, Result};

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

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, serde::Deserialize)]
    #[serde(rename_all = "kebab-case")]
    enum Colour {
        DeepRed,
        Blue,
    }

    #[test]
    fn unknown_names_list_the_allowed_ones() {
        assert_eq!(parse::<Colour>("colour", "blue").unwrap(), Colour::Blue);
        let e = parse::<Colour>("colour", "green").unwrap_err().to_string();
        assert!(
            e.contains("colour") && e.contains("deep-red") && e.contains("green"),
            "{e}"
        );
    }
}
