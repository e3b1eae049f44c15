//! The scenario's claims evaluated on the run (docs/formats.md "claims"): `summary.json`'s
//! `claims`, which the claims tables of `report.md` and `report.html` show.

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::numeric::{nan, Real};
use crate::study::claims::{Bound, Claim, Term};
use crate::study::metric::Metric;
use crate::study::stats::location::{About, Test};
use crate::study::stats::paired::holm;
use crate::study::verdict::{evaluate, evaluate_every, Evaluation, ParameterVerdict, Verdict};
use crate::study::{toml_to_json, RunResult};

/// One claim evaluated on one block's trials, as `summary.json`'s `claims` holds it.
#[serde_with::skip_serializing_none]
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
    #[serialize_always]
    pub ci95: Option<[Real; 2]>,
    /// The verdict.
    pub verdict: Verdict,
    /// For an unresolved claim, the trials that would resolve it.
    #[serialize_always]
    pub trials_to_resolve: Option<u64>,
    /// With a sweep: the block's swept value.
    pub sweep_value: Option<Value>,
    /// Whether the claim is about the mean or the median (older summaries: the mean).
    #[serde(default)]
    pub about: About,
    /// The test that decided (older summaries: t).
    #[serde(default)]
    pub test: Test,
    /// The sample excess kurtosis the test was chosen on (`null`: under 4 trials).
    pub kurtosis: Option<Real>,
    /// An ordering's margin, in the metric's unit.
    pub margin: Option<Real>,
    /// A point value's tolerance band.
    pub band: Option<[Real; 2]>,
    /// The two-sided p-value of the boundary that decides the verdict.
    pub p_value: Option<Real>,
    /// The id of the paper's claim this one tests under another setting.
    pub family: Option<String>,
    /// The other setting, in words (`null`: the paper's setting).
    pub setting: Option<String>,
    /// A claim "for every parameter": each parameter's verdict.
    pub parameters: Option<Vec<ParameterVerdict>>,
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
            setting: match (&sweep_value, &c.paper_point) {
                (Some(p), Some(pp)) if *p == toml_to_json(pp) => c.setting.clone(),
                (Some(p), _) => Some(match &c.setting {
                    Some(s) => format!("{s}, sweep value {p}"),
                    None => format!("sweep value {p}"),
                }),
                (None, _) => c.setting.clone(),
            },
            sweep_value,
            about: c.about,
            test: e.test,
            kurtosis: e.kurtosis.is_finite().then_some(e.kurtosis),
            margin: e.margin,
            band: e.band,
            p_value: e.p_value.is_finite().then_some(e.p_value),
            family: c.family.clone(),
            parameters: None,
        }
    }
}

/// Every claim evaluated on every block, in claim order then block order, with the block's
/// swept value: each entry's per-trial values of the claim's metric, paired by trial, read
/// from the study's scratch file for one claim and block at a time (fails only when that
/// file cannot be read).
pub fn evaluations(r: &RunResult) -> crate::error::Result<Vec<ClaimResult>> {
    let mut out = Vec::new();
    for c in &r.scenario.claims {
        for b in &r.blocks {
            let n = b.info.methods.len();
            let entry = |(mi, si): (usize, usize)| &b.entries[si * n + mi];
            let sweep_value = b.entries.first().and_then(|e| e.sweep_value.clone());
            if c.every_parameter {
                let (Term::One(ka), Bound::Entry(kb)) = (&c.term, &c.bound) else {
                    continue;
                };
                let (ea, eb) = (entry(*ka), entry(*kb));
                // The claim's own parameters, in its order (one without an η in either entry
                // is judged on no trials), else every parameter with an η in both; only
                // those are read from the scratch file.
                let (ka, kb) = (&ea.eta_per_trial, &eb.eta_per_trial);
                let names: Vec<&String> = match &c.parameters {
                    Some(listed) => listed.iter().collect(),
                    None => ka.keys().filter(|k| kb.contains_key(*k)).collect(),
                };
                let mut read = Vec::new();
                for name in names {
                    let (a, b) = match (ka.get(name), kb.get(name)) {
                        (Some(a), Some(b)) => (a.values()?, b.values()?),
                        _ => (Vec::new(), Vec::new()),
                    };
                    read.push((name.clone(), a, b));
                }
                let params: Vec<(String, &[Real], &[Real])> = read
                    .iter()
                    .map(|(name, a, b)| (name.clone(), a.as_slice(), b.as_slice()))
                    .collect();
                let (e, each) = evaluate_every(c, &params);
                let mut r = ClaimResult::new(c, &e, sweep_value);
                r.parameters = Some(each);
                out.push(r);
            } else {
                let values = b
                    .entries
                    .iter()
                    .map(|e| e.per_trial.values(c.metric))
                    .collect::<crate::error::Result<Vec<_>>>()?;
                let e = evaluate(c, |(mi, si)| &values[si * n + mi]);
                out.push(ClaimResult::new(c, &e, sweep_value));
            }
        }
    }
    Ok(out)
}

/// One row of a paper's verdict table: a paper's claim, with its verdict at the paper's
/// setting under the family-wise rule, and how many of the settings it was tested under
/// it holds in.
#[derive(Clone, Debug)]
pub struct PaperRow {
    /// The claim at the paper's setting (or, with none, the first setting).
    pub claim: ClaimResult,
    /// Whether `claim` is at the paper's setting.
    pub at_paper_setting: bool,
    /// The settings it reproduces under, and the settings it was tested under.
    pub holds: (usize, usize),
    /// Its p-value Holm-adjusted over the paper's judged claims.
    pub p_holm: Option<Real>,
    /// The verdict after the adjustment: a per-claim verdict whose adjusted p-value is not
    /// below 0.05 becomes `unresolved`.
    pub verdict: Verdict,
}

/// The level of the family-wise rule over a paper's claims.
pub const FAMILY_ALPHA: Real = 0.05;

/// A paper's claims (every summary's `claims` of the paper, in order) as one row per paper
/// claim: the claims of one family (a claim's `family`, else its id) are one row, whose
/// verdict is the one at the paper's setting (`setting` absent); Holm's step-down rule
/// (Holm 1979) over the rows' p-values at the paper's setting controls the family-wise error
/// of the paper's judged verdicts at 5 %. Rows not judged (`calibrated`, `not comparable`)
/// are outside the family.
pub fn paper_rows(claims: &[ClaimResult]) -> Vec<PaperRow> {
    let mut families: Vec<(String, Vec<&ClaimResult>)> = Vec::new();
    for c in claims {
        let key = c.family.clone().unwrap_or_else(|| c.id.clone());
        match families.iter_mut().find(|(k, _)| *k == key) {
            Some((_, v)) => v.push(c),
            None => families.push((key, vec![c])),
        }
    }
    let mut rows: Vec<PaperRow> = families
        .iter()
        .map(|(_, members)| {
            let paper = members.iter().find(|c| c.setting.is_none());
            let claim = (*paper.unwrap_or(&members[0])).clone();
            let judged: Vec<_> = members.iter().filter(|c| c.verdict.is_judged()).collect();
            let k = judged
                .iter()
                .filter(|c| c.verdict == Verdict::Reproduces)
                .count();
            PaperRow {
                verdict: claim.verdict,
                at_paper_setting: paper.is_some(),
                holds: (k, judged.len()),
                p_holm: None,
                claim,
            }
        })
        .collect();
    let p: Vec<Real> = rows
        .iter()
        .map(
            |r| match (r.at_paper_setting, r.claim.verdict.is_judged()) {
                // A judged claim without a p-value (an `unresolved` one whose test gives
                // none) is in the family all the same, with p = 1: left out, it would lower
                // every other claim's adjustment.
                (true, true) => r.claim.p_value.unwrap_or(1.0),
                _ => Real::NAN,
            },
        )
        .collect();
    let (adjusted, _) = holm(&p);
    for (r, a) in rows.iter_mut().zip(adjusted) {
        if a.is_nan() {
            if r.claim.verdict.is_judged() {
                r.verdict = Verdict::Unresolved;
            }
            continue;
        }
        r.p_holm = Some(a);
        if a >= FAMILY_ALPHA && r.verdict.is_judged() {
            r.verdict = Verdict::Unresolved;
            // The settings it holds under count the paper's setting as adjusted.
            if r.claim.verdict == Verdict::Reproduces {
                r.holds.0 -= 1;
            }
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(
        id: &str,
        family: Option<&str>,
        setting: Option<&str>,
        v: Verdict,
        p: Real,
    ) -> ClaimResult {
        ClaimResult {
            id: id.into(),
            statement: String::new(),
            paper: String::new(),
            value: Value::Null,
            metric: Metric::ValidationAfterMean,
            relation: String::new(),
            interval: "difference".into(),
            bound: 0.0,
            n: 20,
            estimate: 0.0,
            ci95: None,
            verdict: v,
            trials_to_resolve: None,
            sweep_value: None,
            about: About::Mean,
            test: Test::T,
            kurtosis: None,
            margin: None,
            band: None,
            p_value: Some(p),
            family: family.map(String::from),
            setting: setting.map(String::from),
            parameters: None,
        }
    }

    /// One row per paper claim, the verdict at the paper's setting after Holm, and
    /// "holds under k of m settings".
    #[test]
    fn one_row_per_paper_claim_under_holm() {
        use Verdict::*;
        let claims = [
            result("a", None, None, Reproduces, 0.001),
            result("a-c3", Some("a"), Some("c3 = 0.5"), Reproduces, 0.01),
            result("a-pop", Some("a"), Some("population = 20"), Unresolved, 0.3),
            result("b", None, None, Contradicts, 0.02),
            result("c", None, None, Reproduces, 0.04),
            result("d", None, None, Calibrated, 0.0),
        ];
        let rows = paper_rows(&claims);
        assert_eq!(rows.len(), 4);
        // Holm over a, b, c (d is not judged): 0.001 · 3, 0.02 · 2, 0.04 · 1.
        assert_eq!(rows[0].holds, (2, 3));
        assert_eq!(rows[0].verdict, Reproduces);
        assert!((rows[0].p_holm.unwrap() - 0.003).abs() < 1e-15);
        assert_eq!((rows[1].verdict, rows[1].p_holm), (Contradicts, Some(0.04)));
        assert_eq!((rows[2].verdict, rows[2].p_holm), (Reproduces, Some(0.04)));
        assert_eq!((rows[3].verdict, rows[3].p_holm), (Calibrated, None));
        // With one more claim at 0.03, b and c lose their verdicts.
        let mut more = claims.to_vec();
        more.push(result("e", None, None, Reproduces, 0.03));
        more.push(result(
            "c-pop",
            Some("c"),
            Some("population = 20"),
            Reproduces,
            0.01,
        ));
        let rows = paper_rows(&more);
        assert_eq!(rows[1].verdict, Unresolved);
        assert_eq!(rows[2].verdict, Unresolved);
        // c reproduces on its own at the paper's setting, not after the adjustment: it holds
        // under its other setting only.
        assert_eq!(rows[2].holds, (1, 2));
        // A judged claim without a p-value is in the family (p = 1): a's adjustment is over 4.
        let mut unsaid = claims.to_vec();
        let mut f = result("f", None, None, Unresolved, 0.0);
        f.p_value = None;
        unsaid.push(f);
        let rows = paper_rows(&unsaid);
        assert!((rows[0].p_holm.unwrap() - 0.004).abs() < 1e-15);
        assert_eq!((rows[4].verdict, rows[4].p_holm), (Unresolved, Some(1.0)));
    }
}
