//! JSON has no NaN: serde_json writes a non-finite number as `null`. These read such a `null`
//! back as NaN, so that a document deserialised and serialised again is the same bytes
//! (`#[serde(deserialize_with = "crate::numeric::nan::real")]`).

use std::collections::BTreeMap;

use serde::{Deserialize, Deserializer};

use super::Real;

/// A number, or `null` as NaN.
pub fn real<'de, D: Deserializer<'de>>(d: D) -> Result<Real, D::Error> {
    Ok(Option::<Real>::deserialize(d)?.unwrap_or(Real::NAN))
}

/// A map of numbers, each `null` as NaN.
pub fn map<'de, D: Deserializer<'de>>(d: D) -> Result<BTreeMap<String, Real>, D::Error> {
    let m = BTreeMap::<String, Option<Real>>::deserialize(d)?;
    Ok(m.into_iter()
        .map(|(k, v)| (k, v.unwrap_or(Real::NAN)))
        .collect())
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
