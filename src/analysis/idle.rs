//! Sweep points that changed nothing: two points whose entries hold the same figures to the
//! bit ran the same study, so the swept key had no effect between them with the scenario's
//! other settings (an outlier magnitude swept with no outliers, a method's option swept for a
//! method the run does not have). The trials of every point share their draws, so such points
//! are equal exactly; the run warns, and its files are those of the sweep as given.

use crate::analysis::summary::Summary;
use crate::error::{Error, Result};
use crate::study::reporter::Reporter;
use crate::study::stats::Entry;
use crate::study::RunResult;

/// Each sweep point of `s` whose entries are those of an earlier point, as `(earlier, later)`,
/// each point written as its swept keys and values (`outliers.magnitude_mm = [0.5, 1.0]`).
pub fn idle_points(s: &Summary) -> Result<Vec<(String, String)>> {
    let mut points: Vec<(String, Vec<serde_json::Value>)> = Vec::new();
    for e in &s.results {
        let Some(sweep) = &e.sweep else {
            return Ok(Vec::new());
        };
        let point: Vec<String> = sweep.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        let point = point.join(", ");
        let figures = figures(e)?;
        match points.last_mut() {
            Some((p, entries)) if *p == point => entries.push(figures),
            _ => points.push((point, vec![figures])),
        }
    }
    let mut idle = Vec::new();
    for (j, (later, entries)) in points.iter().enumerate() {
        if let Some((earlier, _)) = points[..j].iter().find(|(_, e)| e == entries) {
            idle.push((earlier.clone(), later.clone()));
        }
    }
    Ok(idle)
}

/// What `e` says of its study: every field but its sweep point's.
fn figures(e: &Entry) -> Result<serde_json::Value> {
    let mut v = serde_json::to_value(e)
        .map_err(|err| Error::Compute(format!("cannot read an entry's figures: {err}")))?;
    if let Some(m) = v.as_object_mut() {
        m.remove("sweep");
        m.remove("sweep_value");
    }
    Ok(v)
}

/// The summary of `r` ([`super::analyse::analyse`]), warning through `reporter` of each sweep
/// point that changed nothing ([`idle_points`]): what a run, a resume and a merge each do once.
pub fn analyse_warning(r: &RunResult, reporter: &dyn Reporter) -> Result<Summary> {
    let summary = super::analyse::analyse(r)?;
    warn(&summary, reporter)?;
    Ok(summary)
}

/// Warns through `reporter` of each sweep point of `s` that changed nothing ([`idle_points`]).
fn warn(s: &Summary, reporter: &dyn Reporter) -> Result<()> {
    for (earlier, later) in idle_points(s)? {
        reporter.warning(&format!(
            "sweep point {later} gave every entry the figures of {earlier}, to the bit: the \
             swept key has no effect between them with the scenario's other settings"
        ));
    }
    Ok(())
}
