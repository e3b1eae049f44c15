//! The guard on files edited by hand or cut (docs/formats.md § 2.4, § 2.13, § 8.4): a
//! baseline without `trials` leaves the changes it cannot judge unresolved rather than
//! regressed; a `trials.csv` row of an entry the summary lacks, and a baseline whose summary
//! lacks a figure its per-trial values give, are refused naming the file, the line and the key;
//! `compare` counts every metric B lacks and says how to read its page in `compare.md` too;
//! a tolerance below the smallest 64-bit number is refused.

use std::path::Path;

use serde_json::Value;

use crate::common::{calbench, calbench_ok, load_json, path_arg, read, root, tmp_dir};
use crate::guard::{check, run, three_trials_and_baseline};

/// `doc` written to `dir/NAME` as a pretty JSON file; its text.
fn written(dir: &Path, name: &str, doc: &Value) -> String {
    let text = serde_json::to_string_pretty(doc).unwrap() + "\n";
    std::fs::write(dir.join(name), &text).unwrap();
    text
}

#[test]
fn a_baseline_without_trials_leaves_changes_unresolved_not_regressed() {
    let dir = tmp_dir("cli-guard-edits-no-trials");
    let (a, base) = three_trials_and_baseline(&dir);
    let mut doc = load_json(&base);
    doc.as_object_mut().unwrap().remove("trials");
    written(&dir, "no-trials.json", &doc);
    let cut = dir.join("no-trials.json");
    // Another seed: every metric from the summaries, whose intervals no longer say over how
    // many trials they were taken. Their noise is not known; a change is not a regression
    // (it had been taken as exact: 27 regressions with p = 0 of an unchanged program).
    let b = dir.join("b");
    let sc = root().join("scenarios/ci-guard.toml");
    run(&sc, &b, &["--trials", "3", "--seed", "6"]);
    let (ok, said) = check(&b, &cut, &[]);
    assert!(ok, "{said}");
    assert!(!said.contains("regression:"), "{said}");
    assert!(
        said.contains("unresolved: ") && said.contains("with no interval"),
        "{said}"
    );
    // The baseline's own seed: each entry pairs by the trials its values hold, and the
    // comparison does not claim to be unpaired for the trials it does not say.
    let (ok, said) = check(&a, &cut, &[]);
    assert!(ok, "{said}");
    assert!(!said.contains("differ in their trials"), "{said}");
    assert!(!said.contains("(0 paired)"), "{said}");
    // A baseline without its `seed`: the run that would pair is the baseline scenario's, not
    // a run "with --seed none".
    doc.as_object_mut().unwrap().remove("seed");
    written(&dir, "no-seed.json", &doc);
    let (_, said) = check(&b, &dir.join("no-seed.json"), &[]);
    assert!(
        said.contains("a run of the baseline's scenario") && !said.contains("--seed none"),
        "{said}"
    );
}

#[test]
fn per_trial_values_of_an_entry_or_figure_the_summary_lacks_are_refused() {
    let dir = tmp_dir("cli-guard-edits-ghost");
    let (a, base) = three_trials_and_baseline(&dir);
    // A trials.csv row of an entry the summary has no result of: `check` had passed over it,
    // `baseline` carried it into a file `check` then refused.
    let ghost = dir.join("ghost");
    std::fs::create_dir(&ghost).unwrap();
    for f in ["summary.json", "scenario.toml"] {
        std::fs::copy(a.join(f), ghost.join(f)).unwrap();
    }
    let csv = read(&a.join("trials.csv"));
    let row = csv.lines().nth(1).unwrap().replacen(",ls,", ",ghost,", 1);
    assert!(row.contains(",ghost,"), "{row}");
    std::fs::write(ghost.join("trials.csv"), format!("{csv}{row}\n")).unwrap();
    let line = csv.lines().count() + 1;
    let want = format!(
        "ghost/trials.csv: line {line}, column method: ghost / random is not an entry of the \
         summary's results"
    );
    let (ok, said) = check(&ghost, &base, &[]);
    assert!(!ok && said.contains(&want), "{want}: {said}");
    let out = dir.join("ghost-base.json");
    let o = calbench(&["baseline", path_arg(&ghost), "--out", path_arg(&out)]);
    let said = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && said.contains(&want), "{said}");
    assert!(!out.exists(), "nothing is written");
    // A baseline whose summary lost a figure its per-trial values give: the metric had gone
    // unguarded without a word.
    let mut doc = load_json(&base);
    let entry = doc["per_trial"]["entries"]
        .as_object()
        .unwrap()
        .keys()
        .find(|k| k.starts_with("ls /"))
        .unwrap()
        .clone();
    let results = doc["results"].as_array_mut().unwrap();
    let at = results.iter().position(|e| e["method"] == "ls").unwrap();
    results[at]
        .as_object_mut()
        .unwrap()
        .remove("validation_after_mm");
    let text = written(&dir, "lost.json", &doc);
    let key = format!("per_trial.entries.{entry}.values.validation_after_mm.mean");
    let (ok, said) = check(&a, &dir.join("lost.json"), &[]);
    // The line of the key: the metric's values under the entry under `per_trial`.
    let lines: Vec<&str> = text.lines().collect();
    let after = |from: usize, key: &str| {
        from + lines[from..]
            .iter()
            .position(|l| l.trim_start().starts_with(&format!("\"{key}\"")))
            .unwrap()
    };
    let line = after(
        after(after(0, "per_trial"), &entry),
        "validation_after_mm.mean",
    ) + 1;
    let want = format!("lost.json: line {line}, {key}: its 3 values give");
    assert!(!ok && said.contains(&want), "{want}: {said}");
    assert!(said.contains("where the summary has none"), "{said}");
    // So is η, whose figure its per-trial values do not give (it is over each parameter's
    // determinable trials), when the summary lacks it: by `check` and by `baseline` of a run
    // folder whose summary.json lost it.
    let mut doc = load_json(&base);
    let results = doc["results"].as_array_mut().unwrap();
    let at = results.iter().position(|e| e["method"] == "ls").unwrap();
    results[at].as_object_mut().unwrap().remove("eta_mean_pct");
    written(&dir, "no-eta.json", &doc);
    let (ok, said) = check(&a, &dir.join("no-eta.json"), &[]);
    let want = format!("per_trial.entries.{entry}.values.eta_mean_pct: its 3 finite values");
    assert!(!ok && said.contains(&want), "{want}: {said}");
    let run = dir.join("no-eta-run");
    std::fs::create_dir_all(&run).unwrap();
    for f in ["summary.json", "trials.csv", "scenario.toml"] {
        std::fs::copy(a.join(f), run.join(f)).unwrap();
    }
    let mut doc = load_json(&run.join("summary.json"));
    let results = doc["results"].as_array_mut().unwrap();
    let at = results.iter().position(|e| e["method"] == "ls").unwrap();
    results[at].as_object_mut().unwrap().remove("eta_mean_pct");
    std::fs::write(run.join("summary.json"), doc.to_string()).unwrap();
    let out = dir.join("no-eta-base.json");
    let o = calbench(&["baseline", path_arg(&run), "--out", path_arg(&out)]);
    let said = String::from_utf8_lossy(&o.stderr);
    let want = "trials.csv: column eta_mean_pct";
    assert!(!o.status.success() && said.contains(want), "{want}: {said}");
    assert!(said.contains("where the summary has none"), "{said}");
    assert!(!out.exists(), "nothing is written");
}

#[test]
fn compare_counts_every_metric_b_lacks_and_says_how_to_read_it_in_markdown() {
    let dir = tmp_dir("cli-guard-edits-compare");
    let (a, _) = three_trials_and_baseline(&dir);
    let mut doc = load_json(&a.join("summary.json"));
    doc["results"][0]["validation_after_mm"]["mean"] = Value::Null;
    written(&dir, "null-mean.json", &doc);
    let out = dir.join("cmp");
    let o = calbench_ok(&[
        "compare",
        path_arg(&a.join("summary.json")),
        path_arg(&dir.join("null-mean.json")),
        "--out",
        path_arg(&out),
    ]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        said.contains("1 regressed (1 of them missing in B)"),
        "{said}"
    );
    let md = read(&out.join("compare.md"));
    assert!(md.contains("regression: missing in B"), "{md}");
    let how = md
        .split("## How to read this page\n\n")
        .nth(1)
        .unwrap_or("");
    assert!(
        how.contains("A metric regresses when B is worse than A"),
        "{md}"
    );
}

#[test]
fn a_tolerance_below_the_smallest_number_is_refused() {
    let base = root().join("results/baselines/ci-guard.json");
    let o = calbench(&[
        "check",
        path_arg(&base),
        "--baseline",
        path_arg(&base),
        "--tolerance",
        "1e-400",
    ]);
    let said = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{said}");
    assert!(
        said.contains("\"1e-400\" is below the smallest 64-bit number"),
        "{said}"
    );
}

/// A `trials.csv` cell that is not UTF-8 (a Latin-1 `°`) is named by its line and column, as a
/// measurement file's is; the CSV reader's own words had named a record and a byte.
#[test]
fn a_trials_csv_cell_that_is_not_utf8_is_named_at_its_line_and_column() {
    let dir = tmp_dir("cli-guard-edits-latin1");
    let (a, base) = three_trials_and_baseline(&dir);
    let csv = read(&a.join("trials.csv"));
    let second = csv.lines().nth(2).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let column = header.iter().position(|h| *h == "termination").unwrap();
    let cells: Vec<&str> = second.split(',').collect();
    let mut bytes = Vec::new();
    for (i, line) in csv.lines().enumerate() {
        if i == 2 {
            let mut row: Vec<Vec<u8>> = cells.iter().map(|c| c.as_bytes().to_vec()).collect();
            row[column].push(0xB0);
            bytes.extend(row.join(&b","[..]));
        } else {
            bytes.extend(line.as_bytes());
        }
        bytes.push(b'\n');
    }
    std::fs::write(a.join("trials.csv"), bytes).unwrap();
    let (ok, said) = check(&a, &base, &[]);
    let want = "a/trials.csv: line 3, column termination: not UTF-8 text; save the file as UTF-8";
    assert!(!ok && said.contains(want), "{said}");
}

/// A baseline holding `NaN` or `-Infinity` (as Python's `json` writes them) or nothing at all
/// is refused saying so; the parser's words alone had said "expected value" and "EOF".
#[test]
fn a_baseline_with_nan_or_nothing_says_what_is_not_json() {
    let dir = tmp_dir("cli-guard-edits-not-json");
    let base = root().join("results/baselines/ci-guard.json");
    let text = read(&base);
    let at = text.find("\"max\": ").unwrap() + "\"max\": ".len();
    let end = at + text[at..].find(',').unwrap();
    let line = text[..at].lines().count();
    for (name, word) in [("nan", "NaN"), ("inf", "-Infinity")] {
        let p = dir.join(format!("{name}.json"));
        std::fs::write(&p, format!("{}{word}{}", &text[..at], &text[end..])).unwrap();
        let (ok, said) = check(&base, &p, &[]);
        let want = format!("{name}.json: line {line}: ");
        let not = format!("`{}` is not JSON", word.trim_start_matches('-'));
        assert!(!ok && said.contains(&want) && said.contains(&not), "{said}");
    }
    let empty = dir.join("empty.json");
    std::fs::write(&empty, "").unwrap();
    let (ok, said) = check(&base, &empty, &[]);
    assert!(
        !ok && said.contains("empty.json: line 1: is empty"),
        "{said}"
    );
}

/// `baseline` writes nothing `check` would refuse: a summary of no entries, or one whose
/// `scenario` is not the scenario its `scenario.toml` ran, is refused naming the key and its
/// line; and `check` refuses a folder named `scenario.toml`, which it had taken for none.
#[test]
fn baseline_and_check_refuse_a_run_folder_edited_by_hand() {
    let dir = tmp_dir("cli-guard-edits-folder");
    let (a, _) = three_trials_and_baseline(&dir);
    let copy = |name: &str, edit: &dyn Fn(&mut Value)| {
        let run = dir.join(name);
        std::fs::create_dir_all(&run).unwrap();
        for f in ["trials.csv", "scenario.toml"] {
            std::fs::copy(a.join(f), run.join(f)).unwrap();
        }
        let mut doc = load_json(&a.join("summary.json"));
        edit(&mut doc);
        written(&run, "summary.json", &doc);
        run
    };
    let empty = copy("empty", &|d| d["results"] = Value::Array(Vec::new()));
    let other = copy("other", &|d| d["scenario"] = "other".into());
    for (run, want) in [
        (&empty, "results: is empty: the summary has no entries"),
        (&other, "scenario: is other, but "),
    ] {
        let out = dir.join("b.json");
        let o = calbench(&["baseline", path_arg(run), "--out", path_arg(&out)]);
        let said = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && said.contains(want), "{want}: {said}");
        assert!(said.contains("summary.json: line "), "{said}");
        let beside = "the summary is not of the run beside it";
        assert!(run == &empty || said.contains(beside), "{said}");
        assert!(!out.exists(), "nothing is written");
    }
    let folder = copy("folder", &|_| ());
    std::fs::remove_file(folder.join("scenario.toml")).unwrap();
    std::fs::create_dir(folder.join("scenario.toml")).unwrap();
    let (ok, said) = check(&folder, &a.join("summary.json"), &[]);
    assert!(
        !ok && said.contains("folder/scenario.toml: is a folder"),
        "{said}"
    );
}
