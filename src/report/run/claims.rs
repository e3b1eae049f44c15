//! The scenario's claims evaluated on the run (docs/formats.md "claims"): `summary.json`'s
//! `claims` and the claims table at the top of `report.md` and `report.html`.

use serde_json::{json, Value};

use crate::report::markdown::fmt_num;
use crate::study::claims::{evaluate, Claim, Evaluation, METRICS};
use crate::study::{toml_to_json, RunResult};

use super::fmt_ci;

/// Every claim evaluated on every block, in claim order then block order, with the block's
/// swept value.
pub fn evaluations(r: &RunResult) -> Vec<(&Claim, Option<Value>, Evaluation)> {
    let mut out = Vec::new();
    for c in &r.scenario.claims {
        for b in &r.blocks {
            let n = b.info.methods.len();
            let e = evaluate(c, |(mi, si)| &b.entries[si * n + mi].per_trial[c.metric]);
            let sweep_value = b.entries.first().and_then(|e| e.sweep_value.clone());
            out.push((c, sweep_value, e));
        }
    }
    out
}

/// `summary.json`'s `claims`.
pub fn summary(r: &RunResult) -> Value {
    Value::Array(
        evaluations(r)
            .into_iter()
            .map(|(c, sweep_value, e)| {
                let mut v = claim_json(c, METRICS[c.metric].0, &e);
                if let Some(s) = sweep_value {
                    v["sweep_value"] = s;
                }
                v
            })
            .collect(),
    )
}

/// One evaluated claim as `summary.json` holds it; `metric`: the name of its metric.
pub fn claim_json(c: &Claim, metric: &str, e: &Evaluation) -> Value {
    json!({
        "id": c.id,
        "statement": c.statement,
        "paper": c.paper,
        "value": toml_to_json(&c.value),
        "metric": metric,
        "relation": c.relation,
        "interval": e.interval,
        "bound": e.bound,
        "n": e.n,
        "estimate": e.estimate,
        "ci95": e.ci95,
        "verdict": e.verdict.as_str(),
        "trials_to_resolve": e.trials_to_resolve,
    })
}

/// The paper's value as the tables print it: a string as written, anything else as JSON.
pub fn paper_value(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => toml_to_json(other).to_string(),
    }
}

/// The reports' claims table: headers and one row per claim (and sweep point).
pub fn table(r: &RunResult) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let sweep = r.scenario.sweep.is_some();
    let rows = evaluations(r)
        .into_iter()
        .map(|(c, sweep_value, e)| {
            let swept = sweep.then(|| sweep_value.map_or(String::new(), |v| v.to_string()));
            row(c, METRICS[c.metric].0, swept, &e)
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
        "trials",
        "estimate",
        "95 % CI",
        "verdict",
        "trials to resolve",
    ]);
    h
}

/// One row of the claims table ([`headers`]); `sweep_value`: the cell of a sweep's column.
pub fn row(c: &Claim, metric: &str, sweep_value: Option<String>, e: &Evaluation) -> Vec<String> {
    let mut row = vec![
        c.id.clone(),
        c.paper.clone(),
        c.statement.clone(),
        paper_value(&c.value),
    ];
    row.extend(sweep_value);
    row.extend([
        c.relation.clone(),
        format!("{metric} ({})", e.interval),
        e.n.to_string(),
        fmt_num(e.estimate, 4),
        fmt_ci(e.ci95, 4),
        e.verdict.as_str().to_string(),
        e.trials_to_resolve.map_or(String::new(), |t| t.to_string()),
    ]);
    row
}

/// What the claims table says, for the reports.
pub const NOTE: &str = "Each claim of the paper is a relation between the entries' per-trial \
    values of a metric, evaluated on the same trials: `\"a\" < \"b\"` by the mean of the \
    paired difference a − b and its 95 % t interval (compared with 0); `\"a\" / \"b\" <= x` \
    by the ratio of the means and its paired 95 % interval (delta method); `\"a\" < x` by the \
    mean of a and its t interval. The claim reproduces when the interval lies wholly on the \
    claimed side, contradicts when wholly on the other, and is unresolved otherwise, with the \
    trials at which an interval as wide per trial would exclude the bound.";
