//! The verdicts of a run as a user reads them in `summary.json` (docs/formats.md § 4.17,
//! "Tests and margins"): the paired comparisons judged against the metrics' margins, and the
//! claims' tests chosen from the data's shape.

use crate::common::{bin, path_arg, read, root, tmp_dir};

/// Runs `scenario` for `trials` trials and returns its `summary.json`.
fn run(scenario: &str, trials: &str, name: &str) -> serde_json::Value {
    let out = tmp_dir(name);
    let o = bin()
        .args([
            "run",
            path_arg(&root().join(scenario)),
            "--trials",
            trials,
            "--out",
            path_arg(&out),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_str(&read(&out.join("summary.json"))).unwrap()
}

/// The LS and LM comparisons of a summary (both metrics, every strategy) and their verdicts.
fn ls_lm(s: &serde_json::Value) -> Vec<(String, String)> {
    let rows: Vec<(String, String)> = s["comparisons"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| {
            let (a, b) = (c["a"].as_str().unwrap(), c["b"].as_str().unwrap());
            a.starts_with("ls / ") && b.starts_with("lm / ") && a[5..] == b[5..]
        })
        .map(|c| {
            (
                format!("{} vs {} ({})", c["a"], c["b"], c["metric"]),
                c["verdict"].as_str().unwrap_or("").to_string(),
            )
        })
        .collect();
    assert!(!rows.is_empty(), "no LS–LM comparison");
    rows
}

/// Must hold (issue 51): in the default study (`scenarios/default.toml`, what `calbench`
/// runs without arguments) the LS–LM comparisons read "equivalent": LM and LS reach the same
/// least-squares optimum, differing by 1e-8 mm, far inside the 1 µm margin.
#[test]
fn the_default_studys_ls_and_lm_are_equivalent() {
    let s = run("scenarios/default.toml", "12", "verdicts-default");
    for (pair, verdict) in ls_lm(&s) {
        assert_eq!(verdict, "equivalent", "{pair}");
    }
    // Every comparison carries its margin and test.
    for c in s["comparisons"].as_array().unwrap() {
        assert!(c["margin"].as_f64().is_some_and(|m| m > 0.0), "{c}");
        assert!(matches!(c["test"].as_str(), Some("t" | "sign")), "{c}");
    }
}

/// The same at the default study's own 1000 trials (minutes in a debug build).
#[test]
#[ignore]
fn the_default_studys_ls_and_lm_are_equivalent_at_its_trials() {
    let s = run("scenarios/default.toml", "1000", "verdicts-default-1000");
    for (pair, verdict) in ls_lm(&s) {
        assert_eq!(verdict, "equivalent", "{pair}");
    }
}

/// Must hold (issue 51): `scenarios/qiao2021-tx60.toml` at 20 trials: BAS-PSO against PSO at
/// equal evaluations reads "contradicts", by the test the differences' kurtosis picks (t, or
/// the sign test where PSO's rare stalls make them heavy-tailed), recorded beside the verdict;
/// the committed run of the same design, `summary-fig4-evaluations.json`, has kurtosis 0.48
/// and t. About 20 s in a release build, minutes in a debug one.
#[test]
#[ignore]
fn qiao_bas_pso_against_pso_at_equal_evaluations_contradicts_at_20_trials() {
    let s = run("scenarios/qiao2021-tx60.toml", "20", "verdicts-qiao");
    let c = s["claims"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["id"] == "qiao-bas-pso-below-pso")
        .expect("the claim");
    assert_eq!(c["verdict"], "contradicts", "{c}");
    assert!(matches!(c["test"].as_str(), Some("t" | "sign")), "{c}");
}
