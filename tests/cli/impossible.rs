//! Summaries no run can have written, as a user makes them by hand: more failures than
//! trials, η above 100 % (docs/formats.md § 2.4, § 2.15). `check` (on either side) and
//! `record` refuse them naming the file, the line and the key, where they had compared or
//! stored them.

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use crate::common::{calbench, calbench_ok, load_json, path_arg, refused, root, tmp_dir};

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
