//! `summary.json` is the serialisation of the typed `Summary` the analysis builds once
//! (docs/architecture.md, `src/analysis/`): its bytes are those of the `json!` document the
//! writer assembled before the analysis was typed, every committed run summary reads back
//! and writes again as the same bytes, and an old summary without intervals still loads.

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use calbench::analysis::comparisons::comparisons;
use calbench::analysis::summary::{Summary, FORMAT};
use calbench::report::run::json_text;
use calbench::runner::run::InMemoryRun;
use calbench::study::scenario::Scenario;
use calbench::study::{toml_to_json, RunOptions, RunResult};

use crate::common::{read, root, tmp_dir};

/// `summary.json` as the writer assembled it with `json!` before the analysis was typed (the
/// builder of `report/run.rs`, kept here as the reference the typed summary must match).
fn json_builder(r: &RunResult) -> Value {
    let sc = &r.scenario;
    let first = &r.blocks[0].info;
    let mut optimised = serde_json::Map::new();
    for (si, s) in first.strategies.iter().enumerate() {
        if let Some(set) = &first.fixed[si] {
            let settled = calbench::analysis::analyse::settled_iteration(&set.trace, 1e-3);
            optimised.insert(
                s.clone(),
                json!({"poses": set.poses, "iterations": set.trace.len(),
                       "final_objective": set.trace.last(), "scores": set.scores,
                       "trace": set.trace, "settled_iteration": settled}),
            );
        }
    }
    let results: Vec<Value> = r
        .blocks
        .iter()
        .flat_map(|b| b.entries.iter().map(|e| serde_json::to_value(e).unwrap()))
        .collect();
    let mut convergence = serde_json::Map::new();
    let b0 = &r.blocks[0];
    for (si, mi, trace) in b0.trial0.iter().flat_map(|t| &t.traces) {
        let label = format!("{} / {}", first.methods[*mi], first.strategies[*si]);
        convergence.insert(label, json!(trace));
    }
    let (all, _, _) = comparisons(r).unwrap();
    let mut s = json!({
        "scenario": sc.name, "description": sc.description, "robot": first.robot,
        "trials": sc.trials, "seed": sc.seed,
        "measure": if first.full_pose { "pose" } else { "position" },
        "registration": sc.registration.as_str(), "parameters": first.params,
        "error_parameters": first.error_params, "fixed_pose_sets": optimised,
        "fitness_trace_trial0": convergence, "timing": "timing.json", "results": results,
        "comparisons": all,
    });
    if !sc.claims.is_empty() {
        let mut claims = Vec::new();
        for c in &sc.claims {
            for b in &r.blocks {
                use calbench::study::claims::{Bound, Term};
                let n = b.info.methods.len();
                let entry = |(mi, si): (usize, usize)| &b.entries[si * n + mi];
                let (e, each) = match (&c.term, &c.bound) {
                    (Term::One(ka), Bound::Entry(kb)) if c.every_parameter => {
                        let (ea, eb) = (entry(*ka), entry(*kb));
                        let mut read: Vec<(String, Vec<f64>, Vec<f64>)> = ea
                            .eta_per_trial
                            .iter()
                            .filter_map(|(k, a)| {
                                let b = eb.eta_per_trial.get(k)?.values().unwrap();
                                Some((k.clone(), a.values().unwrap(), b))
                            })
                            .collect();
                        // The claim's listed parameters only, one without an η on no trials.
                        if let Some(listed) = &c.parameters {
                            read = listed
                                .iter()
                                .map(|n| match read.iter().find(|(k, ..)| k == n) {
                                    Some(r) => r.clone(),
                                    None => (n.clone(), vec![], vec![]),
                                })
                                .collect();
                        }
                        let params: Vec<(String, &[f64], &[f64])> = read
                            .iter()
                            .map(|(k, a, b)| (k.clone(), a.as_slice(), b.as_slice()))
                            .collect();
                        let (e, each) = calbench::study::verdict::evaluate_every(c, &params);
                        (e, Some(each))
                    }
                    _ => {
                        let values: Vec<Vec<f64>> = b
                            .entries
                            .iter()
                            .map(|e| e.per_trial.values(c.metric).unwrap())
                            .collect();
                        let e =
                            calbench::study::verdict::evaluate(c, |(mi, si)| &values[si * n + mi]);
                        (e, None)
                    }
                };
                let mut v = json!({
                    "id": c.id, "statement": c.statement, "paper": c.paper,
                    "value": toml_to_json(&c.value), "metric": c.metric.key(),
                    "relation": c.relation, "interval": e.interval, "bound": e.bound,
                    "n": e.n, "estimate": e.estimate, "ci95": e.ci95,
                    "verdict": e.verdict.as_str(), "trials_to_resolve": e.trials_to_resolve,
                    "about": c.about.as_str(), "test": e.test.as_str(),
                });
                if e.kurtosis.is_finite() {
                    v["kurtosis"] = json!(e.kurtosis);
                }
                if e.p_value.is_finite() {
                    v["p_value"] = json!(e.p_value);
                }
                for (k, x) in [("margin", json!(e.margin)), ("band", json!(e.band))] {
                    if !x.is_null() {
                        v[k] = x;
                    }
                }
                if let Some(f) = &c.family {
                    v["family"] = json!(f);
                }
                if let Some(each) = each {
                    v["parameters"] = json!(each);
                }
                let sweep_value = b.entries.first().and_then(|e| e.sweep_value.clone());
                let setting = match (&sweep_value, &c.paper_point) {
                    (Some(p), Some(pp)) if *p == toml_to_json(pp) => c.setting.clone(),
                    (Some(p), _) => Some(match &c.setting {
                        Some(s) => format!("{s}, sweep value {p}"),
                        None => format!("sweep value {p}"),
                    }),
                    (None, _) => c.setting.clone(),
                };
                if let Some(st) = setting {
                    v["setting"] = json!(st);
                }
                if let Some(sv) = sweep_value {
                    v["sweep_value"] = sv;
                }
                claims.push(v);
            }
        }
        s["claims"] = Value::Array(claims);
    }
    if let Some(p) = calbench::analysis::analyse::performance_profile(r) {
        s["performance_profile"] = serde_json::to_value(p).unwrap();
    }
    if let Some(st) = &r.stopping {
        s["stopping"] = json!(st);
    }
    if let Some(sep) = &first.separation {
        s["separation"] = sep.clone();
    }
    if let Some(c) = r
        .blocks
        .iter()
        .find_map(|b| b.info.true_compliance.as_ref())
    {
        s["true_compliance"] = c.clone();
    }
    if let Some(sw) = &sc.sweep {
        if let [axis] = sw.axes.as_slice() {
            s["sweep_key"] = json!(axis.key);
            s["sweep_values"] = Value::Array(axis.values.iter().map(toml_to_json).collect());
        }
        s["sweep_keys"] = json!(sw.keys());
        s["sweep_zip"] = json!(sw.zip);
    }
    s
}

fn in_memory(sc: Scenario) -> InMemoryRun {
    let opts = RunOptions {
        threads: Some(2),
        out: None,
        progress: false,
        shard: None,
        precision: None,
    };
    InMemoryRun::run(sc, &opts).unwrap()
}

/// Scenario `file` of `scenarios/` at `trials` trials.
fn scenario(file: &str, trials: usize) -> Scenario {
    Scenario::load(&root().join("scenarios").join(file))
        .unwrap()
        .with_run_overrides(Some(trials), None)
        .unwrap()
}

/// The typed summary of runs of committed scenarios (claims, optimised pose sets, outliers
/// and sag, a sweep with its performance profile) is the bytes of the `json!` builder, and
/// reads back and writes again as the same bytes.
#[test]
fn the_summary_is_the_bytes_of_the_json_builder() {
    let sweep = Scenario::parse(
        &(read(&root().join("scenarios/ci-guard.toml")).replace("trials = 8", "trials = 3")
            + "\n[sweep]\nkey = \"outliers.count\"\nvalues = [0, 2]\n"),
        None,
    )
    .unwrap();
    let runs = [
        scenario("ci-guard.toml", 3),
        scenario("li2018-irb2600.toml", 3),
        scenario("guo2024-3t2r.toml", 2),
        sweep,
    ];
    let mut seen = (false, false, false);
    for sc in runs {
        let name = sc.name.clone();
        let run = in_memory(sc);
        let text = run.summary.to_json().unwrap();
        assert_eq!(
            text,
            json_text(&json_builder(&run.result)).unwrap(),
            "{name}"
        );
        assert_eq!(run.summary_json().unwrap(), text, "{name}");
        let back: Summary = serde_json::from_str(&text).unwrap();
        assert_eq!(back.to_json().unwrap(), text, "{name}: read back");
        seen.0 |= back.claims.is_some();
        seen.1 |= back.performance_profile.is_some();
        seen.2 |= !back.fixed_pose_sets.is_empty() || back.true_compliance.is_some();
    }
    assert_eq!(
        seen,
        (true, true, true),
        "claims, a profile, pose sets or sag"
    );
}

/// The run summaries committed under `results/`.
fn committed_summaries() -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![root().join("results")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "json") {
                let v: Value = serde_json::from_str(&read(&p)).unwrap();
                // A run's summary (not a registration study's, nor a score file).
                // A baseline carries its per-trial values beside the summary (`per_trial`).
                if v.get("results").is_some()
                    && v.get("comparisons").is_some()
                    && v.get("per_trial").is_none()
                {
                    out.push(p);
                }
            }
        }
    }
    out.sort();
    out
}

/// Every committed run summary deserialises into `Summary` and serialises back to its bytes.
#[test]
fn committed_summaries_read_back_to_their_bytes() {
    let all = committed_summaries();
    assert!(all.len() >= 8, "{all:?}");
    for p in all {
        let text = read(&p);
        let s = Summary::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        assert_eq!(s.to_json().unwrap(), text, "{}", p.display());
    }
}

/// A summary written before the intervals and comparisons (`tests/data/summary-before-intervals.json`,
/// the committed CI baseline as it was until the baselines carried per-trial values): it
/// loads, its figures as written and its missing intervals empty. A summary of a later format
/// is refused, naming the format.
#[test]
fn an_old_summary_loads_and_a_newer_format_is_refused() {
    let p = root().join("tests/data/summary-before-intervals.json");
    let v: Value = serde_json::from_str(&read(&p)).unwrap();
    assert!(v.get("comparisons").is_none() && v["results"][0].get("eta_mean_pct_ci95").is_none());
    let s = Summary::read(&p).unwrap();
    assert_eq!(s.results.len(), v["results"].as_array().unwrap().len());
    for (e, j) in s.results.iter().zip(v["results"].as_array().unwrap()) {
        assert_eq!(e.method, j["method"].as_str().unwrap());
        assert_eq!(
            Some(e.validation_after_mm.rms),
            j["validation_after_mm"]["rms"].as_f64()
        );
        assert_eq!(Some(e.eta_mean_pct), j["eta_mean_pct"].as_f64());
        assert!(e.eta_mean_pct_ci95.is_none() && e.validation_after_mm.rms_ci95.is_none());
    }
    assert!(s.comparisons.is_empty());
    let dir = tmp_dir("summary-format");
    let mut newer = v.clone();
    newer["format"] = json!(FORMAT + 1);
    let path: &Path = &dir.join("summary.json");
    std::fs::write(path, newer.to_string()).unwrap();
    let err = Summary::read(path).unwrap_err().to_string();
    assert!(
        err.contains("summary.json") && err.contains("format 2"),
        "{err}"
    );
}
