//! A task's canonical text and its hash (docs/formats.md § 9.3): the task file's values, one
//! `key = value` line each, then the SHA-256 of every file it fixes.

use std::path::Path;

use super::sha256::sha256_hex;
use crate::error::{Error, Result};

/// The task's hash: SHA-256 (hex) of the canonical text of its table and of one
/// `KEY.sha256 = "…"` line per file it fixes (`fixed`, each with its key), keys sorted.
pub(super) fn task_hash(table: &toml::Table, mut fixed: Vec<(&str, &Path)>) -> Result<String> {
    let mut canonical = canonical_text(&toml::Value::Table(table.clone()));
    fixed.sort_by_key(|(k, _)| *k);
    for (key, p) in fixed {
        let bytes = std::fs::read(p).map_err(|e| Error::io(p, e))?;
        canonical.push_str(&format!("{key}.sha256 = \"{}\"\n", sha256_hex(&bytes)));
    }
    Ok(sha256_hex(canonical.as_bytes()))
}

/// `key = value` lines of every leaf of `v`, keys sorted and dotted (arrays of tables
/// indexed): a task's text without its comments and layout.
pub(super) fn canonical_text(v: &toml::Value) -> String {
    fn walk(prefix: &str, v: &toml::Value, out: &mut String) {
        match v {
            toml::Value::Table(t) => {
                let mut keys: Vec<&String> = t.keys().collect();
                keys.sort();
                for k in keys {
                    let p = if prefix.is_empty() {
                        k.clone()
                    } else {
                        format!("{prefix}.{k}")
                    };
                    walk(&p, &t[k], out);
                }
            }
            toml::Value::Array(a) if a.iter().all(toml::Value::is_table) && !a.is_empty() => {
                for (i, x) in a.iter().enumerate() {
                    walk(&format!("{prefix}[{i}]"), x, out);
                }
            }
            leaf => out.push_str(&format!("{prefix} = {leaf}\n")),
        }
    }
    let mut out = String::new();
    walk("", v, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn canonical_text_ignores_comments_and_order() {
        let a: toml::Value = toml::from_str("# x\nb = 1\na = \"s\"\n[[p]]\nv = 2.5\n").unwrap();
        let b: toml::Value = toml::from_str("a = \"s\" # y\nb = 1\n\n[[p]]\nv = 2.5").unwrap();
        assert_eq!(canonical_text(&a), canonical_text(&b));
        assert_eq!(canonical_text(&a), "a = \"s\"\nb = 1\np[0].v = 2.5\n");
    }
}
