//! `[report] baseline = "NAME"` (docs/formats.md § 4.16): the reports' paired comparisons
//! show each method against the named one; `summary.json` keeps every pair as it was; a name
//! that is not a method's label is refused naming the file, the key and the accepted labels.

use std::path::Path;

use calbench::report::fmt_num;
use serde_json::Value;

use crate::common::{
    calbench, calbench_ok, load_json, path_arg, read, root, tmp_dir, write_scenario,
};

/// `scenarios/ci-guard.toml` with `extra` appended, as `DIR/NAME.toml`.
fn scenario(dir: &Path, name: &str, extra: &str) -> std::path::PathBuf {
    let text = read(&root().join("scenarios/ci-guard.toml"));
    write_scenario(dir, name, &format!("{text}\n{extra}"))
}

fn run(scenario: &Path, out: &Path) {
    calbench_ok(&[
        "run",
        path_arg(scenario),
        "--trials",
        "12",
        "--out",
        path_arg(out),
        "--threads",
        "2",
    ]);
}

/// The rows (cells) of report.md's "Paired comparisons" table.
fn comparison_rows(md: &str) -> Vec<Vec<String>> {
    let section = md
        .split("## Paired comparisons")
        .nth(1)
        .unwrap_or_else(|| panic!("no paired comparisons in report.md:\n{md}"));
    section
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2)
        .map(|l| {
            l.trim_matches('|')
                .split('|')
                .map(|c| c.trim().to_string())
                .collect()
        })
        .collect()
}

/// The comparison of `a` and `b` on `metric` in summary.json's `comparisons`.
fn pair<'s>(summary: &'s Value, a: &str, b: &str, metric: &str) -> &'s Value {
    summary["comparisons"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["a"] == a && c["b"] == b && c["metric"] == metric)
        .unwrap_or_else(|| panic!("no comparison {a} → {b} of {metric}"))
}

#[test]
fn the_reports_compare_against_the_named_baseline_and_the_summary_keeps_every_pair() {
    let dir = tmp_dir("cli-report-baseline");
    let (plain, based) = (dir.join("plain"), dir.join("based"));
    run(&scenario(&dir, "plain", ""), &plain);
    run(
        &scenario(&dir, "based", "[report]\nbaseline = \"lm\"\n"),
        &based,
    );
    // summary.json and trials.csv do not depend on how the reports present the study.
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&plain.join(f)), read(&based.join(f)), "{f}");
    }
    let summary = load_json(&based.join("summary.json"));
    assert_eq!(summary["comparisons"].as_array().unwrap().len(), 6);

    // Without the key: each method against ls, the first one.
    let rows = comparison_rows(&read(&plain.join("report.md")));
    let shown: Vec<(&str, &str)> = rows.iter().map(|r| (&*r[0], &*r[1])).collect();
    assert_eq!(rows.len(), 4, "{rows:?}");
    assert!(shown.iter().all(|(a, _)| *a == "ls / random"), "{shown:?}");

    // With baseline = "lm": ls and igg3 against lm, which comes last in `results`.
    let rows = comparison_rows(&read(&based.join("report.md")));
    let shown: Vec<(&str, &str, &str)> = rows.iter().map(|r| (&*r[0], &*r[1], &*r[2])).collect();
    assert_eq!(
        shown,
        [
            ("lm / random", "ls / random", "validation_after_mm.rms"),
            ("lm / random", "ls / random", "eta_mean_pct"),
            ("lm / random", "igg3 / random", "validation_after_mm.rms"),
            ("lm / random", "igg3 / random", "eta_mean_pct"),
        ]
    );
    // Each row is the summary's pair the other way round: the same test, its estimate
    // negated and its interval mirrored (the mean's t interval, or the median's sign-test
    // interval: the one the verdict is judged on), the same Wilcoxon p-value and Holm
    // adjustment.
    for r in &rows {
        let c = pair(&summary, &r[1], &r[0], &r[2]);
        let f = |k: &str| c[k].as_f64().unwrap();
        let ci = |i: usize| c["ci95"][i].as_f64().unwrap();
        assert_eq!(r[3], c["n"].to_string());
        let test = match c["test"].as_str().unwrap() {
            "t" => "mean (t)",
            "sign" => "median (sign)",
            t => panic!("test {t}"),
        };
        assert_eq!(r[4], test, "{r:?} vs {c}");
        assert_eq!(r[5], fmt_num(-f("estimate"), 4), "{r:?} vs {c}");
        assert_eq!(
            r[6],
            format!("[{}, {}]", fmt_num(-ci(1), 4), fmt_num(-ci(0), 4)),
            "{r:?} vs {c}"
        );
        assert_eq!(r[9], fmt_num(f("p_value"), 3), "{r:?} vs {c}");
        assert_eq!(r[10], fmt_num(f("p_holm"), 3), "{r:?} vs {c}");
        if r[2].starts_with("validation") {
            assert_eq!(r[7], fmt_num(1.0 / f("ratio"), 4), "{r:?} vs {c}");
        }
    }
    let html = read(&based.join("report.html"));
    assert!(
        html.contains("<td class=\"t\">lm / random</td><td class=\"t\">igg3 / random</td>"),
        "report.html"
    );
    assert!(
        !html.contains("<td class=\"t\">ls / random</td><td class=\"t\">igg3 / random</td>"),
        "report.html"
    );
}

#[test]
fn a_baseline_that_is_not_a_method_is_refused_naming_the_file_key_and_labels() {
    let dir = tmp_dir("cli-report-baseline-bad");
    let file = scenario(&dir, "bad", "[report]\nbaseline = \"lsq\"\n");
    let out = dir.join("out");
    let o = calbench(&[
        "run",
        path_arg(&file),
        "--trials",
        "2",
        "--out",
        path_arg(&out),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    let line = read(&file)
        .lines()
        .position(|l| l.starts_with("baseline"))
        .unwrap()
        + 1;
    assert!(err.contains(path_arg(&file)), "{err}");
    assert!(
        err.contains(&format!(
            "line {line}, report.baseline: \"lsq\" is not a method of the scenario; accepted: \
             ls, igg3, lm"
        )),
        "{err}"
    );
    assert!(!out.exists(), "a refused run wrote {}", out.display());
    // An unknown key of the section is refused too.
    let file = scenario(&dir, "typo", "[report]\nbasline = \"lm\"\n");
    let o = calbench(&[
        "run",
        path_arg(&file),
        "--trials",
        "2",
        "--out",
        path_arg(&out),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("basline"));
}
