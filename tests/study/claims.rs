//! A paper's claims as `[[claims]]` (docs/formats.md § 4.16): evaluated on the paired trials
//! the same bytes whatever the threads and shards, checked against trials.csv, shown at the
//! top of the reports, refused before any trial when they name what the study lacks; and
//! every paper's scenario states its claims.

use std::path::PathBuf;

use crate::common::{
    calbench, calbench_ok, load_json, path_arg, read, root, scenario_claims, tmp_dir,
    write_scenario, PAPER_SCENARIOS, SMALL_STUDY as SMALL,
};

/// [`SMALL`] with outliers (IGG3, labelled `rob`, against LS) and four claims.
fn study() -> String {
    SMALL.replace("count = 0\n", "count = 4\n")
        + r#"
[[claims]]
id = "robust-better"
statement = "IGG3 ends below LS with outliers"
paper = "§ 3, table 3"
value = [0.42, 0.61]
metric = "validation_after_mm.rms"
relation = '"rob" < "ls"'

[[claims]]
id = "robust-ratio"
statement = "IGG3 at most half the error of LS"
paper = "§ 3"
value = "≤ 50 %"
metric = "validation_after_mm.mean"
relation = '"rob / random" / "ls / random" <= 0.5'

[[claims]]
id = "ls-improves"
statement = "calibration improves"
paper = "§ 3"
value = 70.0
metric = "improvement_pct"
relation = '"ls" > 0'

[[claims]]
id = "ls-worsens"
statement = "a claim the run contradicts"
paper = "nowhere"
value = 0
metric = "improvement_pct"
relation = '"ls" < 0'
"#
}

/// The column `name` of trials.csv for rows of `method`, in trial order.
fn column(csv: &str, method: &str, name: &str) -> Vec<f64> {
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let (m, k) = (
        head.iter().position(|h| *h == "method").unwrap(),
        head.iter().position(|h| *h == name).unwrap(),
    );
    lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|c| c[m] == method)
        .map(|c| c[k].parse().unwrap())
        .collect()
}

#[test]
fn claims_are_the_same_bytes_across_threads_and_shards_and_match_the_trials() {
    let dir = tmp_dir("study-claims");
    let sc = write_scenario(&dir, "claims", &study());
    let sc = path_arg(&sc);
    let run = |name: &str, extra: &[&str]| -> PathBuf {
        let out = dir.join(name);
        let mut args = vec!["run", sc, "--out", path_arg(&out)];
        args.extend(extra);
        calbench_ok(&args);
        out
    };
    let one = run("t1", &["--threads", "1"]);
    let two = run("t2", &["--threads", "2"]);
    let shards: Vec<PathBuf> = (0..3)
        .map(|i| run(&format!("s{i}"), &["--shard", &format!("{i}/3")]))
        .collect();
    let merged = dir.join("merged");
    let mut args = vec!["merge"];
    args.extend(shards.iter().map(|d| path_arg(d)));
    args.extend(["--out", path_arg(&merged)]);
    calbench_ok(&args);
    let summary = read(&one.join("summary.json"));
    for other in [&two, &merged] {
        assert_eq!(
            summary,
            read(&other.join("summary.json")),
            "{}",
            other.display()
        );
    }

    let s = load_json(&one.join("summary.json"));
    let claims = s["claims"].as_array().expect("claims");
    let ids: Vec<&str> = claims.iter().map(|c| c["id"].as_str().unwrap()).collect();
    assert_eq!(
        ids,
        ["robust-better", "robust-ratio", "ls-improves", "ls-worsens"]
    );
    let by = |id: &str| claims.iter().find(|c| c["id"] == id).unwrap();
    // The paired difference, recomputed from trials.csv.
    let csv = read(&one.join("trials.csv"));
    let (rob, ls) = (
        column(&csv, "rob", "after_rms_mm"),
        column(&csv, "ls", "after_rms_mm"),
    );
    let d: Vec<f64> = rob.iter().zip(&ls).map(|(a, b)| a - b).collect();
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    let c = by("robust-better");
    assert_eq!(c["interval"], "difference");
    assert_eq!(c["n"], 5);
    assert!((c["estimate"].as_f64().unwrap() - mean).abs() < 1e-12 * mean.abs().max(1e-3));
    let ci: Vec<f64> = c["ci95"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(ci[0] < mean && mean < ci[1]);
    // An ordering is judged beyond its margin m: 1 % of LS's mean RMS, at least 1 µm.
    let ls_mean = ls.iter().sum::<f64>() / ls.len() as f64;
    let m = (0.01 * ls_mean).max(1e-3);
    assert!((c["margin"].as_f64().unwrap() - m).abs() < 1e-15, "{c}");
    assert_eq!(c["test"], "t");
    let want = if ci[1] < -m {
        "reproduces"
    } else if ci[0] >= -m {
        "contradicts"
    } else {
        "unresolved"
    };
    assert_eq!(c["verdict"], want);
    assert_eq!(c["trials_to_resolve"].is_null(), want != "unresolved");
    assert_eq!(c["value"], serde_json::json!([0.42, 0.61]));
    // The ratio of the mean errors.
    let (rm, lm) = (
        column(&csv, "rob", "after_mean_mm"),
        column(&csv, "ls", "after_mean_mm"),
    );
    let ratio = rm.iter().sum::<f64>() / lm.iter().sum::<f64>();
    let c = by("robust-ratio");
    assert_eq!(
        (c["interval"].as_str(), c["bound"].as_f64()),
        (Some("ratio"), Some(0.5))
    );
    assert!((c["estimate"].as_f64().unwrap() - ratio).abs() < 1e-12);
    // Calibration improves in every trial: one claim holds, its opposite does not.
    assert_eq!(by("ls-improves")["verdict"], "reproduces");
    assert_eq!(by("ls-worsens")["verdict"], "contradicts");
    assert_eq!(by("ls-worsens")["interval"], "mean");

    // The reports lead with the claims table.
    let md = read(&one.join("report.md"));
    let (claims_at, results_at) = (
        md.find("## The paper's claims").expect("claims section"),
        md.find("## Validation errors").expect("results section"),
    );
    assert!(claims_at < results_at);
    let row: Vec<String> = md
        .lines()
        .find(|l| l.starts_with("| ls-worsens "))
        .expect("the claim's row")
        .split('|')
        .map(|c| c.trim().to_string())
        .collect();
    assert_eq!(
        row[1..5],
        ["ls-worsens", "nowhere", "a claim the run contradicts", "0"]
    );
    assert_eq!(row[row.len() - 3], "contradicts");
    let html = read(&one.join("report.html"));
    let (claims_at, settings_at) = (
        html.find("The paper&apos;s claims")
            .or_else(|| html.find("The paper's claims")),
        html.find("Settings"),
    );
    assert!(claims_at.expect("claims in html") < settings_at.expect("settings"));
}

#[test]
fn bad_claims_are_refused_before_any_trial() {
    let dir = tmp_dir("study-claims-refused");
    for (from, to, key, says) in [
        (
            "metric = \"improvement_pct\"\nrelation = '\"ls\" < 0'",
            "metric = \"speed\"\nrelation = '\"ls\" < 0'",
            "claims[3].metric",
            "unknown metric \"speed\"",
        ),
        (
            "relation = '\"ls\" < 0'",
            "relation = '\"lm\" < 0'",
            "claims[3].relation",
            "no entry \"lm\"",
        ),
        (
            "relation = '\"ls\" < 0'",
            "relation = '\"ls\" = 0'",
            "claims[3].relation",
            "neither a quoted entry",
        ),
        (
            "relation = '\"ls\" < 0'",
            "relation = '\"ls\" < 0'\nmetric = \"validation_after_axis_mm.rms\"",
            "claims[3]",
            "duplicate key",
        ),
        (
            "metric = \"improvement_pct\"\nrelation = '\"ls\" < 0'",
            "metric = \"validation_after_deg.mean\"\nrelation = '\"ls\" < 0'",
            "claims[3].metric",
            "needs tracker.measure = \"pose\"",
        ),
    ] {
        let text = study();
        assert!(text.contains(from), "{from}");
        let bad = text.replacen(from, to, 1);
        let sc = write_scenario(&dir, "bad", &bad);
        let out = dir.join("out");
        let o = calbench(&["run", path_arg(&sc), "--out", path_arg(&out)]);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(!o.status.success(), "{to}");
        assert!(err.contains("bad.toml"), "{err}");
        assert!(err.contains(says), "{err}");
        if key != "claims[3]" {
            // TOML itself refuses a duplicate key, at its line.
            assert!(err.contains(key), "{err}");
            assert!(err.contains("claim \"ls-worsens\""), "{err}");
            // The line of the refused key (1-based).
            let field = key.rsplit('.').next().unwrap();
            let line = bad
                .lines()
                .enumerate()
                .filter(|(_, l)| l.starts_with(&format!("{field} =")))
                .nth(3)
                .map(|(i, _)| i + 1)
                .unwrap();
            assert!(err.contains(&format!("line {line}")), "{err}");
        }
        assert!(!out.exists(), "nothing is written for a refused scenario");
    }
}

/// The scenarios named after a paper (calibration studies and Ban fig. 3's registration
/// study).
fn paper_scenarios() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("scenarios"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy().to_string();
            PAPER_SCENARIOS.iter().any(|s| n.starts_with(s))
        })
        .collect();
    v.sort();
    v
}

#[test]
fn every_paper_scenario_states_at_least_two_claims() {
    let files = paper_scenarios();
    assert!(files.len() >= 4, "{files:?}");
    for f in files {
        let claims: Vec<_> = scenario_claims(&f).into_iter().map(|(c, _)| c).collect();
        assert!(
            claims.len() >= 2,
            "{}: {} claims",
            f.display(),
            claims.len()
        );
        for c in &claims {
            assert!(!c.statement.is_empty() && !c.paper.is_empty(), "{}", c.id);
        }
    }
}
