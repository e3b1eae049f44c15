//! `calbench run --precision` (docs/formats.md § 2.2.1): trials in blocks of 32 until every
//! entry's headline interval is narrow enough; the run that stops after N trials is the run
//! of `--trials N`, whatever the thread count.

use serde_json::Value;

use crate::common::{calbench, calbench_ok, load_json, path_arg, read, root, tmp_dir};

/// `scenarios/ci-guard.toml` without IGG3 (LS and LM), written into `dir`.
fn guard(dir: &std::path::Path) -> std::path::PathBuf {
    let text =
        read(&root().join("scenarios/ci-guard.toml")).replace("[[methods]]\nname = \"igg3\"\n", "");
    crate::common::write_scenario(dir, "guard", &text)
}

/// The widest half-width over the mean of the entries' `validation_after_mm.mean_ci95`.
fn widest(summary: &Value) -> f64 {
    summary["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            let f = &e["validation_after_mm"];
            let ci = f["mean_ci95"].as_array().unwrap();
            let h = (ci[1].as_f64().unwrap() - ci[0].as_f64().unwrap()) / 2.0;
            h / f["mean"].as_f64().unwrap().abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn precision_stops_at_the_first_block_that_reaches_it_and_equals_trials_n() {
    let dir = tmp_dir("precision-stops");
    let sc = guard(&dir);
    let run = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec!["run", path_arg(&sc), "--out", path_arg(&out)];
        args.extend_from_slice(extra);
        calbench_ok(&args);
        out
    };
    let target = 0.025;
    let p1 = run(
        "p1",
        &["--precision", "2.5%", "--trials", "160", "--threads", "1"],
    );
    let p2 = run(
        "p2",
        &["--precision", "2.5%", "--trials", "160", "--threads", "2"],
    );
    let s1 = load_json(&p1.join("summary.json"));
    let stopping = &s1["stopping"];
    assert_eq!(stopping["rule"], "precision");
    assert_eq!(stopping["target"], "2.5%");
    assert_eq!(stopping["max_trials"], 160);
    assert_eq!(stopping["block"], 32);
    assert_eq!(stopping["reached"], true, "{stopping}");
    let n = stopping["trials"].as_u64().unwrap() as usize;
    assert!(n < 160 && n.is_multiple_of(32), "stopped after {n} trials");
    assert_eq!(s1["trials"], n);
    assert!(widest(&s1) <= target);
    assert!((stopping["widest"].as_f64().unwrap() - widest(&s1)).abs() < 1e-15);
    // The same bytes with 1 and 2 threads.
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&p1.join(f)), read(&p2.join(f)), "{f}");
    }
    // The same bytes as `--trials N` (`stopping` aside), which had not reached the target
    // one block earlier.
    let n_text = n.to_string();
    let fixed = run("fixed", &["--trials", &n_text, "--threads", "2"]);
    assert_eq!(
        read(&p1.join("trials.csv")),
        read(&fixed.join("trials.csv"))
    );
    let mut without: serde_json::Map<String, Value> =
        serde_json::from_str(&read(&p1.join("summary.json"))).unwrap();
    without.remove("stopping").unwrap();
    let text = serde_json::to_string_pretty(&Value::Object(without)).unwrap();
    let fixed_text = serde_json::to_string_pretty(&load_json(&fixed.join("summary.json"))).unwrap();
    assert_eq!(text, fixed_text);
    let earlier = (n - 32).to_string();
    let before = run("earlier", &["--trials", &earlier, "--threads", "2"]);
    assert!(widest(&load_json(&before.join("summary.json"))) > target);
    // A run without --precision has no `stopping`.
    assert!(load_json(&fixed.join("summary.json"))
        .get("stopping")
        .is_none());
}

#[test]
fn precision_at_the_cap_says_it_was_not_reached() {
    let dir = tmp_dir("precision-cap");
    let sc = guard(&dir);
    let out = dir.join("out");
    let args = [
        "run",
        path_arg(&sc),
        "--precision",
        "0.0001mm",
        "--trials",
        "40",
        "--out",
        path_arg(&out),
    ];
    calbench_ok(&args);
    let s = load_json(&out.join("summary.json"));
    assert_eq!(s["trials"], 40);
    assert_eq!(s["stopping"]["reached"], false);
    assert_eq!(s["stopping"]["trials"], 40);
    assert!(s["stopping"]["widest"].as_f64().unwrap() > 0.0001);
}

#[test]
fn bad_precisions_and_runs_it_cannot_stop_are_refused_naming_the_flag() {
    let dir = tmp_dir("precision-refused");
    let sc = guard(&dir);
    let out = dir.join("out");
    for bad in ["5", "-1%", "0mm", "abc%", "150%"] {
        let o = calbench(&[
            "run",
            path_arg(&sc),
            "--precision",
            bad,
            "--out",
            path_arg(&out),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains("--precision"),
            "{bad}: {err}"
        );
        assert!(!out.exists());
    }
    let text = read(&sc) + "\n[sweep]\nkey = \"outliers.count\"\nvalues = [0, 2]\n";
    let sweep = crate::common::write_scenario(&dir, "sweep", &text);
    let cases = [
        vec![
            "run",
            path_arg(&sc),
            "--precision",
            "1%",
            "--shard",
            "0/2",
            "--out",
            path_arg(&out),
        ],
        vec![
            "run",
            path_arg(&sweep),
            "--precision",
            "1%",
            "--out",
            path_arg(&out),
        ],
        vec!["run", "--resume", path_arg(&out), "--precision", "1%"],
    ];
    for args in cases {
        let o = calbench(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains("--precision"),
            "{args:?}: {err}"
        );
    }
    assert!(!out.exists());
}

/// `--precision 1% --trials 300` on `scenarios/ci-guard.toml` stops at the cap short of its
/// target and says so on stderr, in report.md and in report.html, naming the widest entry,
/// its half-width and the trials it would need (summary.json's `stopping`).
#[test]
fn a_precision_stop_short_of_its_target_explains_itself() {
    let dir = tmp_dir("precision-short");
    let out = dir.join("o");
    let sc = root().join("scenarios/ci-guard.toml");
    let o = calbench_ok(&[
        "run",
        path_arg(&sc),
        "--precision",
        "1%",
        "--trials",
        "300",
        "--out",
        path_arg(&out),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    let s = load_json(&out.join("summary.json"));
    let st = &s["stopping"];
    assert_eq!(st["reached"], false, "{st}");
    assert_eq!(st["trials"], 300);
    let entry = st["widest_entry"].as_str().unwrap();
    let needed = st["trials_needed"].as_u64().unwrap();
    let w = st["widest"].as_f64().unwrap();
    assert!(needed > 300 && needed.is_multiple_of(32), "{needed}");
    // The half-width shrinks as 1/√n: the trials needed bring it to the target.
    let expected = 300.0 * (w / 0.01).powi(2);
    assert!(
        (needed as f64) >= expected && (needed as f64) < expected + 32.0,
        "{needed} {expected}"
    );
    let half = format!("±{:.3} %", w * 100.0);
    for (place, text) in [
        ("stderr", err.to_string()),
        ("report.md", read(&out.join("report.md"))),
        ("report.html", read(&out.join("report.html"))),
    ] {
        assert!(
            text.contains("precision ±1% not reached"),
            "{place}: {text}"
        );
        assert!(text.contains(entry), "{place}: {entry}");
        assert!(text.contains(&half), "{place}: {half}");
        assert!(text.contains(&format!("about {needed} trials")), "{place}");
    }
}
