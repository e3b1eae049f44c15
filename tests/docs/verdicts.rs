//! REPRODUCTION.md's verdict table and the claims of the paper scenarios (docs/formats.md
//! § 4.17): the table regenerated from the committed summaries, one row per paper claim under
//! the family-wise rule, and the bands and verdicts issue 51 requires.

use super::{common, root};

/// The runs of REPRODUCTION.md's verdict table: the committed summary (under
/// `results/reproduction/`) and the scenario that states the paper's claims.
const CLAIM_PAPERS: [(&str, &str); 14] = [
    ("li2018/summary.json", "scenarios/li2018-irb2600.toml"),
    (
        "li2018/summary-unmodelled.json",
        "scenarios/li2018-irb2600-unmodelled.toml",
    ),
    ("ban/summary.json", "scenarios/ban-irb2600.toml"),
    (
        "ban/summary-unmodelled.json",
        "scenarios/ban-irb2600-unmodelled.toml",
    ),
    ("ban/summary-fig3.json", "scenarios/ban-fig3.toml"),
    ("guo2024/summary.json", "scenarios/guo2024-3t2r.toml"),
    (
        "guo2024/summary-unmodelled.json",
        "scenarios/guo2024-3t2r-unmodelled.toml",
    ),
    ("qiao2021/summary.json", "scenarios/qiao2021-tx60.toml"),
    (
        "qiao2021/summary-errmodel.json",
        "scenarios/qiao2021-tx60-errmodel.toml",
    ),
    (
        "qiao2021/summary-unmodelled.json",
        "scenarios/qiao2021-tx60-unmodelled.toml",
    ),
    (
        "qiao2021/summary-constants.json",
        "scenarios/qiao2021-tx60-constants.toml",
    ),
    (
        "qiao2021/summary-population.json",
        "scenarios/qiao2021-tx60-population.toml",
    ),
    (
        "qiao2021/summary-fig4-evaluations.json",
        "scenarios/qiao2021-tx60-fig4-evaluations.toml",
    ),
    (
        "qiao2021/summary-fig4-iterations.json",
        "scenarios/qiao2021-tx60-fig4-iterations.toml",
    ),
];

/// The cells of a markdown table row.
fn row_cells(l: &str) -> Vec<String> {
    l.trim()
        .trim_matches('|')
        .split('|')
        .map(|c| c.trim().to_string())
        .collect()
}

/// The paper a committed summary belongs to (its folder under `results/reproduction/`).
fn paper_of(summary: &str) -> &str {
    summary.split('/').next().unwrap_or(summary)
}

/// The verdict table REPRODUCTION.md leads with, generated from the committed summaries'
/// `claims` (docs/formats.md § 4.17): one row per paper claim
/// (`calbench::analysis::claims::paper_rows` over each paper's summaries: the claims of one
/// family are one row, its verdict at the paper's setting after Holm's rule over the paper's
/// judged claims, with the settings it holds under). A summary's claim whose relation,
/// family or `about` is not its scenario's gives "stale committed run", a claim its summary
/// lacks "no committed run", each naming the summary to regenerate. The last column, why a claim does not reproduce, is written by hand (`why`, by
/// claim id).
fn verdict_table(why: &std::collections::BTreeMap<String, String>) -> String {
    use calbench::analysis::claims::{paper_rows, ClaimResult};
    use calbench::report::markdown::fmt_num;
    let mut s = String::from(
        "| paper | claim | statement | paper's value | relation (metric) | test | calbench: estimate [95 % CI] (trials) | verdict (Holm over the paper's claims) | settings | why |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut papers: Vec<&str> = Vec::new();
    for (summary, _) in CLAIM_PAPERS {
        if !papers.contains(&paper_of(summary)) {
            papers.push(paper_of(summary));
        }
    }
    for paper in papers {
        let mut claims: Vec<ClaimResult> = Vec::new();
        let mut missing = Vec::new();
        for (summary, scenario) in CLAIM_PAPERS.iter().filter(|(s, _)| paper_of(s) == paper) {
            let file = root().join(format!("results/reproduction/{summary}"));
            let v: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&file).expect("summary"))
                    .expect("json");
            let got: Vec<ClaimResult> = v["claims"]
                .as_array()
                .map(|a| {
                    a.iter()
                        .map(|c| serde_json::from_value(c.clone()).expect("a claim"))
                        .collect()
                })
                .unwrap_or_default();
            // A summary written before verdicts had tests has no `test` beside its verdicts.
            let before_tests = v["claims"]
                .as_array()
                .is_some_and(|a| a.iter().any(|c| c.get("test").is_none()));
            let mut fresh = Vec::new();
            for (c, metric) in common::scenario_claims(&root().join(scenario)) {
                let mine: Vec<&ClaimResult> = got.iter().filter(|g| g.id == c.id).collect();
                // A summary committed before its scenario's claim was written as it is now
                // is stale: its rows say so, with the command that regenerates it.
                let listed = |g: &ClaimResult| {
                    c.parameters.as_ref().is_none_or(|want| {
                        let got = g.parameters.iter().flatten().map(|p| &p.name);
                        got.eq(want.iter())
                    })
                };
                let stale = before_tests
                    || mine.iter().any(|g| {
                        (&g.relation, &g.family, g.about) != (&c.relation, &c.family, c.about)
                            || !listed(g)
                    });
                if mine.is_empty() || stale {
                    let why = if stale {
                        "stale committed run"
                    } else {
                        "no committed run"
                    };
                    missing.push((c, metric, why, *summary));
                } else {
                    fresh.extend(mine.into_iter().cloned());
                }
            }
            let got = fresh;
            claims.extend(got);
        }
        let num = |x: f64| fmt_num(x, 4);
        for r in paper_rows(&claims) {
            let c = &r.claim;
            let ci = c.ci95.map_or(String::new(), |[lo, hi]| {
                format!(" [{}, {}]", num(lo), num(hi))
            });
            let more = c.trials_to_resolve.map_or(String::new(), |t| {
                format!("; about {t} trials would resolve it")
            });
            let judged = match (c.margin, c.band) {
                (Some(m), _) => format!(", margin {}", fmt_num(m, 3)),
                (_, Some([lo, hi])) => format!(", band [{}, {}]", num(lo), num(hi)),
                _ => String::new(),
            };
            let each = c.parameters.as_ref().map_or(String::new(), |p| {
                let k = p
                    .iter()
                    .filter(|x| x.verdict == calbench::study::verdict::Verdict::Reproduces)
                    .count();
                let none = p.iter().filter(|x| x.n == 0).count();
                let none = match none {
                    0 => String::new(),
                    z => format!(", {z} determined in no trial"),
                };
                format!("; {k} of {} parameters reproduce{none}", p.len())
            });
            // A claim with no run at the paper's setting is outside the family: no verdict.
            let verdict = match r.p_holm {
                _ if !r.at_paper_setting => "no verdict".to_string(),
                Some(p) => format!("{} (Holm p {})", r.verdict.as_str(), fmt_num(p, 2)),
                None => r.verdict.as_str().to_string(),
            };
            let settings = match (r.at_paper_setting, r.holds) {
                (_, (_, 0)) | (true, (_, 1)) => String::new(),
                (true, (k, m)) => format!("holds under {k} of {m} settings"),
                (false, (k, m)) => {
                    format!("no run at the paper's setting; holds under {k} of {m} settings")
                }
            };
            let value = match &c.value {
                serde_json::Value::String(s) => s.clone(),
                v => v.to_string(),
            };
            s += &format!(
                "| {} | {} | {} | {value} | `{}` (`{}`) | {} ({}){judged} | {} {}{ci} ({}){more}{each} | {verdict} | {settings} | {} |\n",
                c.paper,
                c.id,
                c.statement,
                c.relation,
                c.metric,
                c.test.as_str(),
                c.about.as_str(),
                c.interval,
                num(c.estimate),
                c.n,
                why.get(&c.id).map_or("", String::as_str)
            );
        }
        for (c, metric, why_missing, summary) in missing {
            let value = match &c.value {
                toml::Value::String(s) => s.clone(),
                v => v.to_string(),
            };
            s += &format!(
                "| {} | {} | {} | {value} | `{}` (`{metric}`) |  | {why_missing} (`results/reproduction/{summary}`) | not evaluated |  | {} |\n",
                c.paper,
                c.id,
                c.statement,
                c.relation,
                why.get(&c.id).map_or("", String::as_str)
            );
        }
    }
    s
}

/// REPRODUCTION.md's verdict table is the one the committed summaries give (regenerated here
/// and compared); every claim that does not reproduce says why, or "not known".
#[test]
fn reproduction_verdict_table_comes_from_the_committed_summaries() {
    let text = std::fs::read_to_string(root().join("REPRODUCTION.md")).expect("REPRODUCTION.md");
    let start = "<!-- verdicts: generated from results/reproduction/*/summary.json -->";
    let at = text.find(start).expect("the verdict table's marker");
    let table: Vec<&str> = text[at + start.len()..]
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .collect();
    let mut why = std::collections::BTreeMap::new();
    for l in table.iter().skip(2) {
        let c = row_cells(l);
        let reason = c.last().cloned().unwrap_or_default();
        let verdict = &c[c.len() - 3];
        assert!(
            verdict.starts_with("reproduces")
                || verdict == "calibrated"
                || verdict == "not comparable"
                || !reason.is_empty(),
            "claim {}: {verdict} without a reason (write \"not known\" when no run says why)",
            c[1]
        );
        why.insert(c[1].clone(), reason);
    }
    // Every paper scenario that states claims has its committed run in the table.
    for e in std::fs::read_dir(root().join("scenarios")).expect("scenarios") {
        let p = e.expect("scenario").path();
        let name = format!("scenarios/{}", p.file_name().unwrap().to_string_lossy());
        let paper = common::PAPER_SCENARIOS
            .iter()
            .any(|s| name.starts_with(&format!("scenarios/{s}")));
        let text = std::fs::read_to_string(&p).expect("scenario");
        if paper && text.contains("[[claims]]") {
            assert!(
                CLAIM_PAPERS.iter().any(|(_, s)| *s == name),
                "{name} states claims but has no committed summary in the verdict table"
            );
        }
    }
    let want = verdict_table(&why);
    let got = table.join("\n") + "\n";
    assert_eq!(
        got, want,
        "REPRODUCTION.md's verdict table differs from the committed summaries; it should read:\n{want}"
    );
}

/// Must hold (issue 51): no point-value claim of any scenario can reproduce when the estimate
/// is 2× (or ½×) off the paper's value: each band excludes both.
#[test]
fn no_point_value_band_admits_a_figure_two_times_off() {
    use calbench::study::claims::{Bound, Op};
    let mut bands = 0;
    for e in std::fs::read_dir(root().join("scenarios")).expect("scenarios") {
        let p = e.expect("scenario").path();
        if !std::fs::read_to_string(&p).unwrap().contains("[[claims]]") {
            continue;
        }
        for (c, _) in common::scenario_claims(&p) {
            let (Op::Near, Bound::Number(x), Some(t)) = (c.op, &c.bound, c.tolerance) else {
                continue;
            };
            let h = t.at(*x);
            for off in [2.0 * x, 0.5 * x] {
                assert!(
                    (off - x).abs() > h,
                    "{}: claim {}: the band {x} ± {h} admits {off}",
                    p.display(),
                    c.id
                );
            }
            bands += 1;
        }
    }
    assert!(bands >= 6, "{bands} point values");
}

/// Must hold (issue 51): Li's kinematic arm (0.017 mm against Li's 0.42 mm) and Ban's
/// (95.6 % against Ban's 65.10 %) do not "reproduce": on an arm without error outside the
/// model their figures are not comparable, in the committed summaries and on any values.
#[test]
fn kinematic_arm_figures_of_li_and_ban_do_not_reproduce() {
    use calbench::study::verdict::{evaluate, Verdict};
    for (scenario, summary, id, value) in [
        (
            "li2018-irb2600.toml",
            "li2018/summary.json",
            "li-rms-after",
            0.017,
        ),
        (
            "ban-irb2600.toml",
            "ban/summary.json",
            "ban-mae-reduction",
            95.6,
        ),
    ] {
        let claims = common::scenario_claims(&root().join("scenarios").join(scenario));
        let (c, _) = claims.iter().find(|(c, _)| c.id == id).expect(id);
        let v = vec![value; 50];
        let e = evaluate(c, |_| &v);
        assert_eq!(e.verdict, Verdict::NotComparable, "{id}");
        let s: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(root().join("results/reproduction").join(summary))
                .expect("summary"),
        )
        .expect("json");
        let got = s["claims"]
            .as_array()
            .and_then(|a| a.iter().find(|x| x["id"] == id))
            .expect("the committed claim");
        assert_eq!(got["verdict"], "not comparable", "{summary}: {got}");
    }
}

/// Qiao's fig. 4 under both readings of its horizontal axis (issue 51, deliverable 7): the
/// committed runs compare BAS, PSO and BAS-PSO on model 2 (the differential error model, as
/// Qiao §4.1 does), one at an equal budget of evaluations, one at equal iterations, each with
/// its runtime ECDFs, fixed-budget curves and attitude errors.
#[test]
fn qiao_fig4_is_run_on_model_2_at_equal_evaluations_and_at_equal_iterations() {
    for (reading, key, spread) in [
        ("evaluations", "evaluations_mean", 120.0),
        ("iterations", "iterations_mean", 0.0),
    ] {
        let scenario = root().join(format!("scenarios/qiao2021-tx60-fig4-{reading}.toml"));
        let sc: toml::Value =
            toml::from_str(&std::fs::read_to_string(&scenario).expect("scenario")).expect("toml");
        let methods = sc["methods"].as_array().expect("methods");
        let names: Vec<&str> = methods
            .iter()
            .map(|m| m["name"].as_str().unwrap())
            .collect();
        assert_eq!(names, ["bas-pso", "pso", "bas"], "{reading}");
        for m in methods {
            assert_eq!(
                m["error_model"].as_str(),
                Some("differential"),
                "{reading}: {m}"
            );
        }
        let file = root().join(format!(
            "results/reproduction/qiao2021/summary-fig4-{reading}.json"
        ));
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&file).expect("summary")).expect("json");
        assert_eq!(s["trials"], sc["trials"].as_integer().unwrap(), "{reading}");
        let results = s["results"].as_array().expect("results");
        assert_eq!(results.len(), 3, "{reading}");
        let counts: Vec<f64> = results
            .iter()
            .map(|r| r[key].as_f64().expect(key))
            .collect();
        let (lo, hi) = counts
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(l, h), &c| (l.min(c), h.max(c)));
        assert!(hi - lo <= spread, "{reading}: {key} {counts:?}");
        for r in results {
            let m = r["method"].as_str().unwrap();
            assert!(m.ends_with("-differential"), "{reading}: {m}");
            assert!(
                r["search_ecdf"]["all_targets"]
                    .as_array()
                    .is_some_and(|a| !a.is_empty()),
                "{reading}: {m}"
            );
            assert_eq!(
                r["fixed_budget"].as_array().map(Vec::len),
                Some(4),
                "{reading}: {m}"
            );
            assert!(
                r["validation_after_attitude_deg"]["mean"]
                    .as_f64()
                    .is_some(),
                "{reading}: {m}"
            );
        }
        // Fig. 4 itself is judged: BAS-PSO's final fitness against PSO's and BAS's, one
        // setting each of the paper's two fig. 4 claims (its axis is unnamed: neither reading
        // is the paper's setting).
        let claims = s["claims"].as_array().expect("claims");
        for other in ["pso", "bas"] {
            let id = format!("qiao-fig4-{reading}-final-below-{other}");
            let c = claims
                .iter()
                .find(|c| c["id"] == id.as_str())
                .unwrap_or_else(|| panic!("{id}"));
            assert_eq!(c["metric"], "final_fitness.mean", "{id}");
            assert_eq!(
                c["family"],
                format!("qiao-fig4-final-below-{other}"),
                "{id}"
            );
            assert!(c["setting"].as_str().is_some(), "{id}");
            assert!(["t", "sign"].contains(&c["test"].as_str().unwrap()), "{id}");
        }
        // Read as evaluations BAS-PSO spent the least, so its end is the fixed budget's full
        // share: the same mean, from the search's other record.
        if reading == "evaluations" {
            let bas_pso = &results[0];
            let full = &bas_pso["fixed_budget"][3];
            assert_eq!(full["n"], s["trials"], "{reading}");
            let (a, b) = (
                bas_pso["final_fitness"]["mean"]
                    .as_f64()
                    .expect("final_fitness"),
                full["fitness_mean"].as_f64().unwrap(),
            );
            assert!((a - b).abs() <= 1e-12 * b, "{a} {b}");
        }
    }
}
