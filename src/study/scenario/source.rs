//! The text a scenario was read from ([`Source`]): where its refused keys stand.

/// The text a scenario was read from, for the lines of refused keys, and the keys set since
/// (by an override or a sweep point), whose values are not the text's: they get no line.
#[derive(Clone)]
pub(super) struct Source {
    pub(super) text: std::sync::Arc<str>,
    pub(super) edited: Vec<String>,
}

impl std::fmt::Debug for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Source")
            .field("lines", &self.text.lines().count())
            .field("edited", &self.edited)
            .finish()
    }
}

impl Source {
    /// The line of `key` in the text, unless `key` was edited (or lies in, or holds, an
    /// edited key).
    pub(super) fn line(&self, key: &str) -> Option<usize> {
        let within = |a: &str, b: &str| {
            a == b || a.strip_prefix(b).is_some_and(|r| r.starts_with(['.', '[']))
        };
        if self.edited.iter().any(|e| within(key, e) || within(e, key)) {
            return None;
        }
        crate::error::toml_key_line(&self.text, key)
    }

    /// `source` with `keys` edited too. A method's key (`methods.<label>.<key>`) counts as
    /// an edit of every method: refusals name methods by index.
    pub(super) fn edit(
        source: &Option<Source>,
        keys: impl IntoIterator<Item = String>,
    ) -> Option<Source> {
        source.as_ref().map(|s| {
            let mut s = s.clone();
            s.edited.extend(keys.into_iter().map(|k| {
                if k.starts_with("methods.") {
                    "methods".to_string()
                } else {
                    k
                }
            }));
            s
        })
    }
}
