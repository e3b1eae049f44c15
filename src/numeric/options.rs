//! Reading the methods' options structs: each method's options are one
//! `#[derive(Deserialize)]` struct (`deny_unknown_fields`, defaults), and its keys are the
//! struct's fields, nowhere else. When one `[[methods]]` table feeds two structs (the
//! robust ridge's ridge and weights, a search and its box), [`split`] hands each struct the
//! keys it declares, read from the struct itself ([`fields`]), so no list of keys is kept by
//! hand.

use serde::de::{self, DeserializeOwned, Visitor};
use serde::Serialize;

/// The keys of the derived `Deserialize` struct `T` (its fields under their serde names),
/// as serde's derive declares them; empty for a type that is not a derived struct.
pub fn fields<T: DeserializeOwned>() -> &'static [&'static str] {
    let mut out: &'static [&'static str] = &[];
    let _ = T::deserialize(Fields(&mut out));
    out
}

/// A deserializer that records the field list a derived struct asks for and reads nothing.
struct Fields<'a>(&'a mut &'static [&'static str]);

impl<'de> de::Deserializer<'de> for Fields<'_> {
    type Error = de::value::Error;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Self::Error> {
        Err(de::Error::custom("not a struct"))
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _: &'static str,
        fields: &'static [&'static str],
        _: V,
    ) -> Result<V::Value, Self::Error> {
        *self.0 = fields;
        Err(de::Error::custom("fields recorded"))
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map enum identifier
        ignored_any
    }
}

/// Deserialises `t`; on failure names the key as (key, message): serde's path to the value
/// that failed (an unknown key, a value of the wrong type or out of range, `box.lo` or
/// `weights[1]` inside a value), empty when the table itself fails (a required key missing).
pub fn read<T: DeserializeOwned>(t: &toml::Table) -> Result<T, (String, String)> {
    serde_path_to_error::deserialize(toml::Value::Table(t.clone())).map_err(|e| {
        let key = e
            .path()
            .iter()
            .next()
            .map_or(String::new(), |_| e.path().to_string());
        let (msg, named) = crate::error::toml_value_error(&e.into_inner());
        if !key.is_empty() {
            return (key, msg);
        }
        // Where the path stops at the table, toml's message still names the key: a value's
        // check ends in "in `key`", an unknown key starts "unknown field `key`".
        if let Some(k) = named {
            return (k, msg);
        }
        let unknown = crate::error::unknown_field(&msg).map(|(k, _)| k);
        (unknown.unwrap_or_default().to_string(), msg.clone())
    })
}

/// Checks options built in code the way a scenario's are read: `v` written as a table and
/// read back, so that checks declared on the fields (`deserialize_with`) apply; the error
/// names the key.
pub fn recheck<T: Serialize + DeserializeOwned>(v: &T) -> crate::Result<()> {
    let t = toml::Table::try_from(v).map_err(|e| crate::Error::setting("", e.to_string()))?;
    read::<T>(&t)
        .map(|_| ())
        .map_err(|(key, msg)| crate::Error::setting(key, msg))
}

/// [`recheck`] of the settings of the scenario section `section` (`tracker`): the error
/// names the key under it (`tracker.coverage`).
pub fn recheck_at<T: Serialize + DeserializeOwned>(section: &str, v: &T) -> crate::Result<()> {
    recheck(v).map_err(|e| match e {
        crate::Error::Setting { key, msg } => {
            crate::Error::setting(format!("{section}.{key}"), msg)
        }
        e => e,
    })
}

/// `v`, numbers, refused unless each is finite.
pub fn finite<'de, D, T>(d: D) -> Result<T, D::Error>
where
    D: serde::Deserializer<'de>,
    T: serde::Deserialize<'de> + AsRef<[crate::numeric::Real]>,
{
    let v = T::deserialize(d)?;
    let (n, bad) = (v.as_ref().len(), v.as_ref().iter().find(|x| !x.is_finite()));
    match bad {
        Some(x) => Err(de::Error::custom(format!(
            "must be {n} finite numbers, got {x}"
        ))),
        None => Ok(v),
    }
}

/// `v`, a range `[lo, hi]`, refused unless `0 ≤ lo ≤ hi` (finite).
pub fn range<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<[crate::numeric::Real; 2], D::Error> {
    let [lo, hi] = <[crate::numeric::Real; 2] as serde::Deserialize>::deserialize(d)?;
    if lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi {
        Ok([lo, hi])
    } else {
        Err(de::Error::custom(format!(
            "must be [lo, hi] with 0 ≤ lo ≤ hi, got [{lo}, {hi}]"
        )))
    }
}

/// `v`, an optional number, refused unless finite and in [0, 1].
pub fn share<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<crate::numeric::Real>, D::Error> {
    number(d, |v| (0.0..=1.0).contains(&v), "in [0, 1]").map(Some)
}

/// `v`, a number, refused unless finite and above 0.
pub fn positive<'de, D: serde::Deserializer<'de>>(d: D) -> Result<crate::numeric::Real, D::Error> {
    number(d, |v| v > 0.0, "positive")
}

/// `v`, a number, refused unless finite and at least 0.
pub fn non_negative<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<crate::numeric::Real, D::Error> {
    number(d, |v| v >= 0.0, "non-negative")
}

/// `v`, a number, refused unless finite and from 0 to `most`, given in `unit` (which may say
/// where the bound comes from).
pub fn within<'de, D: serde::Deserializer<'de>>(
    d: D,
    most: crate::numeric::Real,
    unit: &str,
) -> Result<crate::numeric::Real, D::Error> {
    number(
        d,
        |v| (0.0..=most).contains(&v),
        &format!("from 0 to {most} {unit}"),
    )
}

/// `v`, a number, refused unless in [0, 1).
pub fn fraction<'de, D: serde::Deserializer<'de>>(d: D) -> Result<crate::numeric::Real, D::Error> {
    number(d, |v| (0.0..1.0).contains(&v), "in [0, 1)")
}

/// `v`, a number, refused unless finite and `holds`, saying it must be `what`.
pub(crate) fn number<'de, D: serde::Deserializer<'de>>(
    d: D,
    holds: impl Fn(crate::numeric::Real) -> bool,
    what: &str,
) -> Result<crate::numeric::Real, D::Error> {
    let v = <crate::numeric::Real as serde::Deserialize>::deserialize(d)?;
    if v.is_finite() && holds(v) {
        Ok(v)
    } else {
        Err(de::Error::custom(format!(
            "must be finite and {what}, got {}",
            crate::error::shown(v)
        )))
    }
}

/// Removes the keys of the struct `T` from `table` and returns them as a table of their own.
pub fn split<T: DeserializeOwned>(table: &mut toml::Table) -> toml::Table {
    fields::<T>()
        .iter()
        .filter_map(|k| table.remove(*k).map(|v| (k.to_string(), v)))
        .collect()
}

/// The refusal `e` of the struct that read what [`split`] left of a table, with the keys split
/// off to the other structs (`taken`) among those an unknown key's refusal expects: they are
/// keys of the same table (igg3's `weight` beside the ridge's `xi`). Other refusals are `e`'s
/// words.
pub fn with_taken(e: impl std::fmt::Display, taken: &[&[&str]]) -> String {
    let msg = e.to_string();
    let Some((key, tail)) = crate::error::unknown_field(&msg) else {
        return msg;
    };
    // serde names the expected keys between backticks (`a`, `b` or `c`; none: no fields).
    let expected = tail.split('`').skip(1).step_by(2);
    let all: Vec<String> = expected
        .chain(taken.iter().flat_map(|t| t.iter().copied()))
        .map(|k| format!("`{k}`"))
        .collect();
    format!("unknown field `{key}`, expected one of {}", all.join(", "))
}

/// `T` read from `given` with the values of `defaults` for the keys `given` lacks: for a
/// struct whose defaults depend on the method that embeds it.
pub fn with_defaults<T: Serialize + DeserializeOwned>(
    defaults: &T,
    given: toml::Table,
) -> Result<T, toml::de::Error> {
    let mut t = toml::Table::try_from(defaults).map_err(de::Error::custom)?;
    t.extend(given);
    T::deserialize(toml::Value::Table(t))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, Serialize, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Two {
        a: f64,
        #[serde(rename = "b_key")]
        b: usize,
    }

    #[test]
    fn a_struct_names_its_keys() {
        assert_eq!(fields::<Two>(), ["a", "b_key"]);
        assert!(fields::<f64>().is_empty());
        let mut t: toml::Table = toml::from_str("a = 1.5\nb_key = 2\nc = 3").unwrap();
        let mine = split::<Two>(&mut t);
        assert_eq!(mine.len(), 2);
        assert_eq!(t.keys().collect::<Vec<_>>(), ["c"]);
        let mut only_b = toml::Table::new();
        only_b.insert("b_key".into(), toml::Value::Integer(7));
        let two = with_defaults(&Two { a: 0.5, b: 1 }, only_b).unwrap();
        assert_eq!(two, Two { a: 0.5, b: 7 });
    }
}
