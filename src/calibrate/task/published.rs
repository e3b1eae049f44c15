//! The check of a task's `[[published]]` figures and its `unpublished` note (docs/formats.md
//! § 9.1), for a tracker's task and a socket task alike.

use super::Published;
use crate::error::{Error, Result};

/// Refuses a task without `[[published]]` figures and without the `unpublished` note, with
/// both, or with a figure that is not finite and ≥ 0 or lacks its label or source; `bad`
/// names the task file's key.
pub(super) fn check_published(
    published: &[Published],
    unpublished: &Option<String>,
    bad: &dyn Fn(&str, String) -> Error,
) -> Result<()> {
    match (published.is_empty(), unpublished) {
        (true, None) => {
            return Err(bad(
                "published",
                "missing: the data's authors' figures ([[published]] label, value, \
                 source, division), or `unpublished` saying why there are none"
                    .into(),
            ))
        }
        (false, Some(_)) => {
            return Err(bad(
                "unpublished",
                "given with [[published]] figures: one or the other".into(),
            ))
        }
        _ => {}
    }
    for (i, p) in published.iter().enumerate() {
        if !(p.value.is_finite() && p.value >= 0.0) {
            let key = format!("published[{i}].value");
            return Err(bad(
                &key,
                format!("{}: a figure in mm, finite and ≥ 0", p.value),
            ));
        }
        if p.source.trim().is_empty() || p.label.trim().is_empty() {
            let key = format!("published[{i}].source");
            return Err(bad(&key, "a figure needs its label and its source".into()));
        }
    }
    Ok(())
}
