//! `record` stores only what calbench writes (docs/formats.md § 2.15): an `identified.json`
//! whose figures no identification writes (an error or residual below 0, a mean above its RMS,
//! a rank above the unknowns, a method calbench does not have, an error of a parameter it did
//! not identify, a robot no robot file may be named) is refused naming the file, the line and
//! the key, by the rule a summary's figures are refused by, and nothing is stored. A summary that lacks an entry's validation
//! errors, or whose terminations are no run's, is refused too (by `check` as well), and so is
//! one whose error statistics are out of order (a mean above the RMS), by `record`.

use std::path::Path;

use crate::common::{calbench_ok, path_arg, read, refused, root, tmp_dir};

/// `calbench simulate` of ci-guard and `identify` of its readings into `dir/id`, as a user
/// runs them.
fn identified(dir: &Path) -> std::path::PathBuf {
    let sim = dir.join("sim");
    let sc = root().join("scenarios/ci-guard.toml");
    calbench_ok(&["simulate", path_arg(&sc), "--out", path_arg(&sim)]);
    let out = dir.join("id");
    calbench_ok(&[
        "identify",
        "--robot",
        "irb2600",
        "--data",
        path_arg(&sim.join("measurements.csv")),
        "--method",
        "lm",
        "--validate",
        path_arg(&sim.join("validation.csv")),
        "--out",
        path_arg(&out),
    ]);
    out
}

#[test]
fn an_identification_with_figures_no_identification_writes_is_refused_naming_the_key() {
    let dir = tmp_dir("record-figures-identify");
    let out = identified(&dir);
    let file = out.join("identified.json");
    let written = read(&file);
    let v: serde_json::Value = serde_json::from_str(&written).unwrap();
    let after = &v["validation_after_mm"];
    let params = v["parameters"].as_array().unwrap().len();
    let db = dir.join("calbench.sqlite");
    // Each edit of one key, with what the refusal must say.
    let set = |key: &[&str], to: serde_json::Value| {
        let mut e = v.clone();
        let mut at = &mut e;
        for k in key {
            at = &mut at[*k];
        }
        *at = to;
        e
    };
    let mut extra = v.clone();
    extra["errors"]["zz9"] = serde_json::json!(1.0);
    let edits = [
        (
            set(&["validation_after_mm", "mean"], (-1.0).into()),
            "validation_after_mm.mean: is -1: this figure is never negative".to_string(),
        ),
        (
            set(&["rms_residual_mm"], (-1.0).into()),
            "rms_residual_mm: is -1".to_string(),
        ),
        (set(&["sigma0"], (-1.0).into()), "sigma0: is -1".to_string()),
        (
            set(&["condition_number"], (-5.0).into()),
            "condition_number: is -5".to_string(),
        ),
        (
            set(&["validation_after_mm", "mean"], 1e300.into()),
            format!(
                "validation_after_mm.mean: is 1e300, above the RMS {} of the same errors",
                after["rms"]
            ),
        ),
        (
            set(&["rank"], 999.into()),
            format!("rank: is 999, above the {params} unknowns solved for"),
        ),
        (
            set(&["method"], "zzz".into()),
            "method: is \"zzz\", which is no identification method (ls,".to_string(),
        ),
        (
            extra,
            format!("errors.zz9: is not one of the {params} parameters identified"),
        ),
        (
            set(&["robot"], "".into()),
            "robot: is \"\": an identification names its robot".to_string(),
        ),
        (
            set(&["robot"], "a\u{7}b".into()),
            "robot: is \"a\\u{7}b\": an identification names its robot".to_string(),
        ),
    ];
    for (edited, want) in edits {
        let text = serde_json::to_string_pretty(&edited).unwrap() + "\n";
        std::fs::write(&file, text).unwrap();
        let o = crate::common::calbench(&["record", path_arg(&out), "--db", path_arg(&db)]);
        let err = refused(&o, &["id/identified.json: line ", &want]);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(!db.exists(), "{want}: stored");
    }
    std::fs::write(&file, &written).unwrap();
    calbench_ok(&["record", path_arg(&out), "--db", path_arg(&db)]);
}

/// A `summary.json` whose entry lost its `validation_after_mm` block is refused by `record`
/// (as `check` refuses the folder); terminations of an unknown name, or that do not add up
/// to the trials, are refused by `check` and `record` alike, naming the key at its line.
#[test]
fn a_summary_without_its_validation_errors_or_with_unknown_terminations_is_refused() {
    let dir = tmp_dir("record-figures-summary");
    let out = dir.join("run");
    let sc = root().join("scenarios/ci-guard.toml");
    let args = [
        "run",
        path_arg(&sc),
        "--trials",
        "2",
        "--out",
        path_arg(&out),
    ];
    calbench_ok(&args);
    let file = out.join("summary.json");
    let written = read(&file);
    let baseline = dir.join("baseline.json");
    std::fs::write(&baseline, &written).unwrap();
    let v: serde_json::Value = serde_json::from_str(&written).unwrap();
    let db = dir.join("calbench.sqlite");
    let record = || crate::common::calbench(&["record", path_arg(&out), "--db", path_arg(&db)]);
    let check = || {
        let b = path_arg(&baseline);
        crate::common::calbench(&["check", path_arg(&file), "--baseline", b])
    };
    let write = |e: &serde_json::Value| {
        std::fs::write(&file, serde_json::to_string_pretty(e).unwrap() + "\n").unwrap()
    };
    let mut e = v.clone();
    e["results"][0]
        .as_object_mut()
        .unwrap()
        .remove("validation_after_mm");
    write(&e);
    refused(
        &record(),
        &[
            "run/summary.json: line ",
            ", results[0]: lacks `validation_after_mm`",
        ],
    );
    refused(&check(), &["validation_after_mm"]);
    let mut e = v.clone();
    e["results"][0]["terminations"] = serde_json::json!({"bogus": 2});
    write(&e);
    let want = [
        "run/summary.json: line ",
        "results[0].terminations.bogus: is not a termination",
    ];
    refused(&record(), &want);
    refused(&check(), &want);
    let mut e = v.clone();
    e["results"][0]["terminations"] = serde_json::json!({"converged": 1});
    write(&e);
    let want = ["results[0].terminations: add up to 1, but the run has 2 trials"];
    refused(&record(), &want);
    refused(&check(), &want);
    // A trial that diverged gave no result: `failures` edited below the count had been
    // stored.
    let mut e = v.clone();
    e["results"][0]["terminations"] = serde_json::json!({"converged": 1, "diverged": 1});
    e["results"][0]["failures"] = 0.into();
    write(&e);
    let want = [
        "run/summary.json: line ",
        "results[0].failures: is 0, but 1 trial ended diverged, singular or with invalid input",
    ];
    refused(&record(), &want);
    refused(&check(), &want);
    // A measure or a registration no run writes had been accepted by both.
    for (key, value) in [("measure", "posture"), ("registration", "best")] {
        let mut e = v.clone();
        e[key] = value.into();
        write(&e);
        let says = format!("{key}: is \"{value}\", which no run writes");
        let want = ["run/summary.json: line ", says.as_str()];
        refused(&record(), &want);
        refused(&check(), &want);
    }
    // Averaged over trials, a mean stays at most the RMS, and the RMS of errors never
    // negative at most the maximum: a summary edited otherwise had been stored.
    let after = &v["results"][0]["validation_after_mm"];
    let (rms, max) = (
        after["rms"].as_f64().unwrap(),
        after["max"].as_f64().unwrap(),
    );
    for (stat, value, says) in [
        (
            "max",
            rms / 2.0,
            format!("validation_after_mm.rms: is {rms}, above the maximum"),
        ),
        (
            "mean",
            2.0 * max,
            format!("validation_after_mm.mean: is {}, above the RMS", 2.0 * max),
        ),
    ] {
        let mut e = v.clone();
        let block = &mut e["results"][0]["validation_after_mm"];
        block[stat] = value.into();
        block[format!("{stat}_ci95")] = serde_json::json!([value, value]);
        write(&e);
        let want = ["run/summary.json: line ", "results (ls / random), ", &says];
        refused(&record(), &want);
    }
    // A trial's termination in trials.csv of no name an identification ends with: it had
    // been read as a usable trial.
    write(&v);
    let csv = out.join("trials.csv");
    let rows = read(&csv);
    let edited = rows.replacen(",converged,", ",bogus,", 1);
    assert_ne!(edited, rows);
    std::fs::write(&csv, &edited).unwrap();
    refused(
        &check(),
        &["run/trials.csv: line 2, termination: is \"bogus\", which is not a termination"],
    );
    std::fs::write(&csv, &rows).unwrap();
    // An improvement of errors ≥ 0 is at most 100 %: one of 1000 % had been stored.
    let mut e = v.clone();
    e["results"][0]["improvement_pct"] = 1000.0.into();
    write(&e);
    let want = [
        "run/summary.json: line ",
        "improvement_pct: is 1000 %: the improvement",
    ];
    refused(&record(), &want);
    refused(&check(), &want);
    assert!(!db.exists());
    std::fs::write(&file, &written).unwrap();
    calbench_ok(&["record", path_arg(&out), "--db", path_arg(&db)]);
}
