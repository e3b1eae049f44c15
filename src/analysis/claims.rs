//! The scenario's claims evaluated on the run (docs/formats.md "claims"): `summary.json`'s
//! `claims`, which the claims tables of `report.md` and `report.html` show.

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::numeric::{nan, Real};
use crate::study::claims::{evaluate, Claim, Evaluation, Verdict};
use crate::study::metric::Metric;
use crate::study::{toml_to_json, RunResult};

/// One claim evaluated on one block's trials, as `summary.json`'s `claims` holds it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ClaimResult {
    /// The claim's id.
    pub id: String,
    /// The paper's claim in words.
    pub statement: String,
    /// Where the paper makes it.
    pub paper: String,
    /// The paper's figure(s), as written.
    pub value: Value,
    /// The metric compared.
    pub metric: Metric,
    /// The relation as written.
    pub relation: String,
    /// What was estimated: `difference`, `ratio` or `mean`.
    pub interval: String,
    /// The bound the estimate is compared with.
    #[serde(deserialize_with = "nan::real")]
    pub bound: Real,
    /// Trials usable in every entry the claim names.
    pub n: usize,
    /// The estimate.
    #[serde(deserialize_with = "nan::real")]
    pub estimate: Real,
    /// Its 95 % interval.
    pub ci95: Option<[Real; 2]>,
    /// The verdict.
    pub verdict: Verdict,
    /// For an unresolved claim, the trials that would resolve it.
    pub trials_to_resolve: Option<u64>,
    /// With a sweep: the block's swept value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweep_value: Option<Value>,
}

impl ClaimResult {
    /// Claim `c` with its evaluation `e` (on the block swept to `sweep_value`).
    pub fn new(c: &Claim, e: &Evaluation, sweep_value: Option<Value>) -> ClaimResult {
        ClaimResult {
            id: c.id.clone(),
            statement: c.statement.clone(),
            paper: c.paper.clone(),
            value: toml_to_json(&c.value),
            metric: c.metric,
            relation: c.relation.clone(),
            interval: e.interval.to_string(),
            bound: e.bound,
            n: e.n,
            estimate: e.estimate,
            ci95: e.ci95,
            verdict: e.verdict,
            trials_to_resolve: e.trials_to_resolve,
            sweep_value,
        }
    }
}

/// Every claim evaluated on every block, in claim order then block order, with the block's
/// swept value: each entry's per-trial values of the claim's metric, paired by trial.
pub fn evaluations(r: &RunResult) -> Vec<ClaimResult> {
    let mut out = Vec::new();
    for c in &r.scenario.claims {
        for b in &r.blocks {
            let n = b.info.methods.len();
            let entry = |(mi, si): (usize, usize)| &b.entries[si * n + mi];
            let e = evaluate(c, |k| &entry(k).per_trial[c.metric]);
            let sweep_value = b.entries.first().and_then(|e| e.sweep_value.clone());
            out.push(ClaimResult::new(c, &e, sweep_value));
        }
    }
    out
}
