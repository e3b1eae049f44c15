//! JSON has no NaN: serde_json writes a non-finite number as `null`. These read such a `null`
//! back as NaN, so that a document deserialised and serialised again is the same bytes
//! (`#[serde(deserialize_with = "crate::numeric::nan::real")]`).

use std::collections::BTreeMap;

use serde::{Deserialize, Deserializer};

use super::Real;

/// A number, or `null` as NaN. Read as what the document holds (a format that writes NaN as
/// a number, as RON in `records.txt` does, gives it back unchanged).
pub fn real<'de, D: Deserializer<'de>>(d: D) -> Result<Real, D::Error> {
    struct Number;
    impl<'de> serde::de::Visitor<'de> for Number {
        type Value = Real;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a number or null")
        }
        fn visit_f64<E>(self, v: f64) -> Result<Real, E> {
            Ok(v)
        }
        fn visit_i64<E>(self, v: i64) -> Result<Real, E> {
            Ok(v as Real)
        }
        fn visit_u64<E>(self, v: u64) -> Result<Real, E> {
            Ok(v as Real)
        }
        fn visit_unit<E>(self) -> Result<Real, E> {
            Ok(Real::NAN)
        }
        fn visit_none<E>(self) -> Result<Real, E> {
            Ok(Real::NAN)
        }
        fn visit_some<S: Deserializer<'de>>(self, d: S) -> Result<Real, S::Error> {
            d.deserialize_any(Number)
        }
    }
    d.deserialize_any(Number)
}

/// A value whose numbers a document may write as `null` (NaN): a number, and lists, maps,
/// triples and options of such values ([`read`]).
pub trait Nullable: Sized {
    /// Reads the value, each `null` number as NaN.
    fn read<'de, D: Deserializer<'de>>(d: D) -> Result<Self, D::Error>;
}

/// One item of a list or map, read as [`Nullable`].
struct Item<T>(T);

impl<'de, T: Nullable> Deserialize<'de> for Item<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        T::read(d).map(Item)
    }
}

impl Nullable for Real {
    fn read<'de, D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        real(d)
    }
}

impl<T: Nullable> Nullable for Vec<T> {
    fn read<'de, D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Vec::<Item<T>>::deserialize(d)?;
        Ok(v.into_iter().map(|i| i.0).collect())
    }
}

impl<T: Nullable> Nullable for BTreeMap<String, T> {
    fn read<'de, D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let m = BTreeMap::<String, Item<T>>::deserialize(d)?;
        Ok(m.into_iter().map(|(k, i)| (k, i.0)).collect())
    }
}

impl<T: Nullable> Nullable for [T; 3] {
    fn read<'de, D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(<[Item<T>; 3]>::deserialize(d)?.map(|i| i.0))
    }
}

/// An optional value that is there (a key written only when it has a value, with
/// `#[serde(default)]`): its `null` is NaN, not `None`.
impl<T: Nullable> Nullable for Option<T> {
    fn read<'de, D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        T::read(d).map(Some)
    }
}

/// A [`Nullable`] value: lists, maps and triples of numbers, each `null` as NaN
/// (`#[serde(deserialize_with = "crate::numeric::nan::read")]`).
pub fn read<'de, D: Deserializer<'de>, T: Nullable>(d: D) -> Result<T, D::Error> {
    T::read(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize, serde::Serialize)]
    struct T {
        #[serde(deserialize_with = "real")]
        x: Real,
        #[serde(deserialize_with = "read")]
        m: BTreeMap<String, Real>,
        #[serde(
            default,
            deserialize_with = "read",
            skip_serializing_if = "Option::is_none"
        )]
        o: Option<Vec<[Real; 3]>>,
    }

    #[test]
    fn null_is_nan_both_ways() {
        let text = r#"{"x":null,"m":{"a":1.5,"b":null},"o":[[1.0,null,2.0]]}"#;
        let t: T = serde_json::from_str(text).unwrap();
        assert!(t.x.is_nan() && t.m["b"].is_nan() && t.m["a"] == 1.5);
        assert!(t.o.as_ref().unwrap()[0][1].is_nan());
        assert_eq!(serde_json::to_string(&t).unwrap(), text);
        let t: T = serde_json::from_str(r#"{"x":1.0,"m":{}}"#).unwrap();
        assert_eq!(t.o, None);
    }
}
