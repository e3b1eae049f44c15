//! Summaries no run can have written, as a user makes them by hand: more failures than
//! trials, η above 100 % (docs/formats.md § 2.4, § 2.15). `check` (on either side) and
//! `record` refuse them naming the file, the line and the key, where they had compared or
//! stored them.

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use crate::common::{calbench, calbench_ok, load_json, path_arg, refused, root, tmp_dir};
use crate::guard::{check, three_trials};

/// A run of `scenarios/ci-guard.toml` with 2 trials into `dir/good`.
pub fn good_run(dir: &Path) -> PathBuf {
    let out = dir.join("good");
    let sc = root().join("scenarios/ci-guard.toml");
    let args = ["--trials", "2", "--threads", "1", "--out", path_arg(&out)];
    calbench_ok(&[&["run", path_arg(&sc)][..], &args].concat());
    out
}

/// A copy at `to` of the files of the run folder `from` (its sub-folders left out), its
/// `summary.json` replaced by `text`.
pub fn copy_with_summary(from: &Path, to: &Path, text: &str) -> PathBuf {
    std::fs::create_dir_all(to).unwrap();
    for f in std::fs::read_dir(from).unwrap() {
        let f = f.unwrap().path();
        if f.is_file() {
            std::fs::copy(&f, to.join(f.file_name().unwrap())).unwrap();
        }
    }
    std::fs::write(to.join("summary.json"), text).unwrap();
    to.to_path_buf()
}

/// The 1-based line of the first `"key"` after `"results"` in `text`.
fn line_in_results(text: &str, key: &str) -> usize {
    let from = text.find("\"results\"").unwrap();
    let at = from + text[from..].find(&format!("\"{key}\"")).unwrap();
    text[..at].matches('\n').count() + 1
}

/// `record` stores what a run wrote: a summary of no entry (its `trials.csv` holding rows),
/// or naming a method with a control or bidirectional character (which a scenario refuses,
/// and `check` shows escaped), is refused at its line; it had been stored.
#[test]
fn record_refuses_a_summary_of_no_entry_or_of_a_hidden_character() {
    let dir = tmp_dir("cli-impossible-record");
    let good = good_run(&dir);
    let doc = load_json(&good.join("summary.json"));
    let db = dir.join("x.sqlite");
    type Edit<'a> = (&'a str, &'a str, &'a dyn Fn(&mut Value));
    let edits: [Edit; 2] = [
        ("empty", "results: holds no entry", &|d| {
            d["results"] = json!([])
        }),
        (
            "hidden",
            "results[0]: names its method or strategy with a control",
            &|d| {
                d["results"][0]["method"] = "ls\u{1b}[31m\u{202e}".into();
            },
        ),
    ];
    for (name, words, edit) in edits {
        let mut d = doc.clone();
        edit(&mut d);
        let text = serde_json::to_string_pretty(&d).unwrap();
        let folder = copy_with_summary(&good, &dir.join(name), &text);
        let o = calbench(&["record", path_arg(&folder), "--db", path_arg(&db)]);
        let said = refused(&o, &[words]);
        assert!(
            said.contains(&format!("{name}/summary.json: line ")),
            "{said}"
        );
    }
}

#[test]
fn more_failures_than_trials_or_eta_above_100_is_refused_by_check_and_record() {
    let dir = tmp_dir("cli-impossible-figures");
    let good = good_run(&dir);
    let summary = good.join("summary.json");
    let doc = load_json(&summary);
    type Edit<'a> = (&'a str, &'a str, &'a str, &'a dyn Fn(&mut Value));
    let edits: [Edit; 4] = [
        (
            "failures",
            "failures",
            "is 999, more than the 2 trials",
            &|d| {
                d["results"][0]["failures"] = 999.into();
            },
        ),
        ("eta-mean", "eta_mean_pct", "is 1e300 %: η = 100", &|d| {
            d["results"][0]["eta_mean_pct"] = 1e300.into();
            d["results"][0]["eta_mean_pct_ci95"] = json!([0.0, 1e301]);
        }),
        ("eta-median", "eta_median_pct", "is 150 %", &|d| {
            d["results"][0]["eta_median_pct"] = 150.into();
            d["results"][0]["eta_median_pct_ci95"] = json!([0.0, 200.0]);
        }),
        (
            "eta-median-ci",
            "eta_median_pct",
            "[90, 100.5], above 100 %",
            &|d| {
                d["results"][0]["eta_median_pct"] = 95.into();
                d["results"][0]["eta_median_pct_ci95"] = json!([90.0, 100.5]);
            },
        ),
    ];
    let db = dir.join("x.sqlite");
    for (name, key, words, edit) in edits {
        let mut d = doc.clone();
        edit(&mut d);
        let text = serde_json::to_string_pretty(&d).unwrap();
        let line = line_in_results(&text, key);
        let place = format!("line {line}, results (ls / random), {key}: ");
        let bad = dir.join(format!("{name}.json"));
        std::fs::write(&bad, &text).unwrap();
        for (s, b) in [(&bad, &summary), (&summary, &bad)] {
            let o = calbench(&["check", path_arg(s), "--baseline", path_arg(b)]);
            let file = format!("{}: {place}", bad.display());
            refused(&o, &[&file, words]);
        }
        let folder = copy_with_summary(&good, &dir.join(name), &text);
        let o = calbench(&["record", path_arg(&folder), "--db", path_arg(&db)]);
        let file = format!("{}: {place}", folder.join("summary.json").display());
        refused(&o, &[&file, words]);
    }
    // A t interval of a mean η can reach above 100 %: it is no refusal.
    let mut d = doc.clone();
    d["results"][0]["eta_mean_pct_ci95"] = json!([90.0, 100.5]);
    let wide = dir.join("wide.json");
    std::fs::write(&wide, d.to_string()).unwrap();
    calbench_ok(&["check", path_arg(&wide), "--baseline", path_arg(&summary)]);
    let o = calbench(&["record", path_arg(&good), "--db", path_arg(&db)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A summary no run can have written — 0 trials, an entry without its strategy, a
/// key no summary has, an interval with its ends reversed, a negative RMS — is refused by `check` (as the run and as the baseline) and by `compare`,
/// naming the file and the key, as `record` refuses it; they had compared it. A figure scaled
/// by hand beyond its interval (a "what if") is compared, and found a regression.
#[test]
fn a_summary_no_run_can_have_written_is_refused_by_check_and_compare() {
    let dir = tmp_dir("cli-guard-impossible");
    let a = three_trials(&dir);
    let good = a.join("summary.json");
    let doc = load_json(&good);
    type Edit<'a> = (&'a str, &'a str, &'a dyn Fn(&mut serde_json::Value));
    let mut outside = doc.clone();
    outside["results"][0]["validation_after_mm"]["mean"] = 99.0.into();
    let worse = dir.join("outside.json");
    std::fs::write(&worse, outside.to_string()).unwrap();
    let (ok, text) = check(&worse, &good, &[]);
    assert!(
        !ok && text.contains("regression: ") && text.contains("validation_after_mm.mean"),
        "{text}"
    );
    let edits: [Edit; 5] = [
        // An entry without its strategy: read as another entry, every figure missing.
        (
            "no-poses",
            "results[0]: is an entry without its `poses`",
            &|d| {
                d["results"][0].as_object_mut().unwrap().remove("poses");
            },
        ),
        ("zero", "trials", &|d| d["trials"] = 0.into()),
        // A misspelt key: passed over, it had left the trials unknown.
        (
            "misspelt",
            "trails: is not a key of a calbench summary",
            &|d| {
                let n = d.as_object_mut().unwrap().remove("trials").unwrap();
                d["trails"] = n;
            },
        ),
        ("reversed", "validation_after_mm.rms", &|d| {
            let ci = &mut d["results"][0]["validation_after_mm"]["rms_ci95"];
            *ci = serde_json::json!([ci[1], ci[0]]);
        }),
        ("negative", "validation_after_mm.rms", &|d| {
            d["results"][0]["validation_after_mm"]["rms"] = (-0.5).into();
            d["results"][0]["validation_after_mm"]["rms_ci95"] = serde_json::json!([-0.6, -0.4]);
        }),
    ];
    for (name, key, edit) in edits {
        let mut d = doc.clone();
        edit(&mut d);
        let bad = dir.join(format!("{name}.json"));
        std::fs::write(&bad, serde_json::to_string_pretty(&d).unwrap()).unwrap();
        for (summary, base) in [(&bad, &good), (&good, &bad)] {
            let (ok, text) = check(summary, base, &[]);
            // Each at its line (`trials` 0 had been named without one).
            assert!(
                !ok && text.contains(&format!("{name}.json: line ")) && text.contains(key),
                "check {name}: {text}"
            );
        }
        let o = calbench(&[
            "compare",
            path_arg(&good),
            path_arg(&bad),
            "--out",
            path_arg(&dir.join(format!("cmp-{name}"))),
        ]);
        let text = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && text.contains(&format!("{name}.json")) && text.contains(key),
            "compare {name}: {text}"
        );
        assert!(!dir.join(format!("cmp-{name}")).exists());
    }
}
