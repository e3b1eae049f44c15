//! The claims table at the top of `report.md` and `report.html` (docs/formats.md "claims"):
//! the claims the analysis evaluated (`summary.json`'s `claims`).

use serde_json::Value;

use crate::analysis::claims::ClaimResult;
use crate::analysis::summary::Summary;
use crate::report::markdown::fmt_num;

use super::fmt_ci;

/// The paper's value as the tables print it: a string as written, anything else as JSON.
pub fn paper_value(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The reports' claims table: headers and one row per claim (and sweep point).
pub fn table(s: &Summary) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let sweep = s.sweep_keys.is_some();
    let rows = s
        .claims
        .iter()
        .flatten()
        .map(|c| {
            let swept = sweep.then(|| {
                c.sweep_value
                    .as_ref()
                    .map_or(String::new(), Value::to_string)
            });
            row(c, swept)
        })
        .collect();
    (headers(sweep), rows)
}

/// The claims table's headers, with a sweep-value column for a sweep.
pub fn headers(sweep: bool) -> Vec<&'static str> {
    let mut h = vec!["claim", "paper", "statement", "paper's value"];
    if sweep {
        h.push("sweep value");
    }
    h.extend([
        "relation",
        "metric",
        "test",
        "trials",
        "estimate",
        "95 % CI",
        "verdict",
        "trials to resolve",
    ]);
    h
}

/// One row of the claims table ([`headers`]); `sweep_value`: the cell of a sweep's column.
pub fn row(c: &ClaimResult, sweep_value: Option<String>) -> Vec<String> {
    let mut row = vec![
        c.id.clone(),
        c.paper.clone(),
        c.statement.clone(),
        paper_value(&c.value),
    ];
    row.extend(sweep_value);
    row.extend([
        c.relation.clone(),
        format!("{} ({})", c.metric, c.interval),
        bounds(c),
        c.n.to_string(),
        fmt_num(c.estimate, 4),
        fmt_ci(c.ci95, 4),
        c.verdict.as_str().to_string(),
        c.trials_to_resolve.map_or(String::new(), |t| t.to_string()),
    ]);
    row
}

/// The test, and the margin or band the verdict was judged against.
fn bounds(c: &ClaimResult) -> String {
    let mut s = format!("{} ({})", c.test.as_str(), c.about.as_str());
    if let Some(m) = c.margin {
        s += &format!(", margin {}", fmt_num(m, 3));
    }
    if let Some([lo, hi]) = c.band {
        s += &format!(", band [{}, {}]", fmt_num(lo, 4), fmt_num(hi, 4));
    }
    s
}

/// What the claims table says, for the reports.
pub const NOTE: &str = "Each claim of the paper is a relation between the entries' per-trial \
    values of a metric, evaluated on the same trials (docs/formats.md \"claims\"): an ordering \
    `\"a\" < \"b\"` by the paired difference a − b, judged beyond the metric's margin of \
    practical relevance; a point value `\"a\" ~ x` against its tolerance band; a ratio by the \
    ratio of the means (delta method). The test is the t interval of the mean, or the sign \
    test's interval of the median for a claim about the median or heavy-tailed values \
    (excess kurtosis above 3). A claim reproduces when the 95 % interval lies wholly on the \
    claimed side (inside the band), contradicts when wholly on the other (outside), and is \
    unresolved otherwise, with the trials at which an interval as wide per trial would \
    resolve it; a figure used to choose a setting is `calibrated` and not judged, a figure of \
    the arm's error on an arm without error outside the model `not comparable`.";
