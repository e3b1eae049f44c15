//! Numbers written with a nonzero digit but below the smallest 64-bit one (`1e-400`), which
//! every parser reads as 0: refused where they are written, as nothing is silently clamped.

use std::path::Path;

use super::{at_line, line_of, quoted, Error, Result};

/// The refusal of the number written `t` and read as `v` when it is below the smallest 64-bit
/// number and so reads as 0 (`1e-400`): not the value written. `None` for any other.
pub fn underflow(t: &str, v: f64) -> Option<String> {
    let mantissa = t.split(['e', 'E']).next().unwrap_or("");
    (v == 0.0 && mantissa.bytes().any(|b| (b'1'..=b'9').contains(&b))).then(|| {
        format!(
            "{} is below the smallest 64-bit number (about 4.9e-324) and would read as 0",
            quoted(t)
        )
    })
}

/// The first float of the TOML `text`, in the text's order, that [`underflow`] refuses: its
/// line, its key path (`joints[1].d`, `tracker.mpe_a_um`) and the refusal. `None` when there is
/// none or the text does not parse (its parser's refusal then stands).
pub fn toml_underflow(text: &str) -> Option<(usize, String, String)> {
    use toml::de::{DeTable, DeValue};
    use toml::Spanned;
    fn walk(v: &Spanned<DeValue>, key: String, found: &mut Vec<(usize, String, String)>) {
        match v.get_ref() {
            DeValue::Float(f) => {
                let t = f.as_str();
                if let Some(msg) = t.parse::<f64>().ok().and_then(|x| underflow(t, x)) {
                    found.push((v.span().start, key, msg));
                }
            }
            DeValue::Array(a) => {
                for (i, e) in a.iter().enumerate() {
                    walk(e, format!("{key}[{i}]"), found);
                }
            }
            DeValue::Table(t) => table(t, &key, found),
            _ => {}
        }
    }
    fn table(t: &DeTable, prefix: &str, found: &mut Vec<(usize, String, String)>) {
        for (k, v) in t {
            let key = match prefix {
                "" => k.get_ref().to_string(),
                p => format!("{p}.{}", k.get_ref()),
            };
            walk(v, key, found);
        }
    }
    let doc = DeTable::parse(text).ok()?;
    let mut found = Vec::new();
    table(doc.get_ref(), "", &mut found);
    let (at, key, msg) = found.into_iter().min_by_key(|f| f.0)?;
    Some((line_of(text, at), key, msg))
}

/// [`toml_underflow`] of the TOML file `path` whose text is `text`, refused naming the file,
/// line and key.
pub fn refuse_toml_underflow(path: &Path, text: &str) -> Result<()> {
    match toml_underflow(text) {
        Some((line, key, msg)) => Err(Error::file(path, at_line(Some(line), key), msg)),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_float_below_the_smallest_double_is_found_at_its_line_and_key() {
        let text = "a = 0.0\nb = 1e-320\n[[j]]\nd = 0e-400\n[[j]]\nd = [1.0, 2.5e-400]\n\
                    [t]\nx = 1e-400\n";
        let (line, key, msg) = toml_underflow(text).unwrap();
        assert_eq!((line, key.as_str()), (6, "j[1].d[1]"), "{msg}");
        assert!(msg.contains("\"2.5e-400\" is below the smallest"), "{msg}");
        // Zero written as zero, a subnormal, strings and comments are left alone.
        let fine = "a = 0.0\nb = 1e-320\nc = \"1e-400\" # 1e-400\nd = -0e-999\n";
        assert_eq!(toml_underflow(fine), None);
    }
}
