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

/// A map of numbers, each `null` as NaN.
pub fn map<'de, D: Deserializer<'de>>(d: D) -> Result<BTreeMap<String, Real>, D::Error> {
    let m = BTreeMap::<String, Option<Real>>::deserialize(d)?;
    Ok(m.into_iter()
        .map(|(k, v)| (k, v.unwrap_or(Real::NAN)))
        .collect())
}

/// A list of numbers, each `null` as NaN.
pub fn list<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Real>, D::Error> {
    let v = Vec::<Option<Real>>::deserialize(d)?;
    Ok(v.into_iter().map(|x| x.unwrap_or(Real::NAN)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize, serde::Serialize)]
    struct T {
        #[serde(deserialize_with = "real")]
        x: Real,
        #[serde(deserialize_with = "map")]
        m: BTreeMap<String, Real>,
    }

    #[test]
    fn null_is_nan_both_ways() {
        let text = r#"{"x":null,"m":{"a":1.5,"b":null}}"#;
        let t: T = serde_json::from_str(text).unwrap();
        assert!(t.x.is_nan() && t.m["b"].is_nan() && t.m["a"] == 1.5);
        assert_eq!(serde_json::to_string(&t).unwrap(), text);
    }
}
