//! The regression guard against the committed baseline (docs/guard.md, docs/formats.md
//! § 8.4): `results/baselines/ci-guard.json` carries the per-trial values of its run, so a
//! run of `scenarios/ci-guard.toml` on the baseline's seed is compared with it trial by trial
//! — the tracker ten times noisier is caught, naming validation_after_mm — while a run of
//! another seed is compared from the summaries and passes; `calbench baseline` writes such a
//! file, and `check` says why a comparison is unpaired and what would pair it.

use std::path::{Path, PathBuf};

use crate::common::{
    as_another_version, calbench, calbench_ok, load_json, path_arg, read, root, tmp_dir,
    write_scenario,
};

fn committed() -> PathBuf {
    root().join("results/baselines/ci-guard.json")
}

/// `calbench check SUMMARY --baseline BASE`: (success, stdout + stderr).
pub(crate) fn check(summary: &Path, base: &Path, extra: &[&str]) -> (bool, String) {
    let mut args = vec!["check", path_arg(summary), "--baseline", path_arg(base)];
    args.extend(extra);
    let o = calbench(&args);
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    (o.status.success(), text)
}

pub(crate) fn run(scenario: &Path, out: &Path, extra: &[&str]) {
    let mut args = vec!["run", path_arg(scenario), "--out", path_arg(out)];
    args.extend(extra);
    calbench_ok(&args);
}

/// A run of `scenarios/ci-guard.toml` with 3 trials and seed 5 into `dir/a`.
pub(crate) fn three_trials(dir: &Path) -> PathBuf {
    let a = dir.join("a");
    run(
        &root().join("scenarios/ci-guard.toml"),
        &a,
        &["--trials", "3", "--seed", "5"],
    );
    a
}

/// [`three_trials`] and its `calbench baseline` file `dir/base.json`.
pub(crate) fn three_trials_and_baseline(dir: &Path) -> (PathBuf, PathBuf) {
    let a = three_trials(dir);
    let base = dir.join("base.json");
    calbench_ok(&["baseline", path_arg(&a), "--out", path_arg(&base)]);
    (a, base)
}

#[test]
fn the_tracker_ten_times_noisier_on_the_baselines_seed_fails_against_the_committed_baseline() {
    let dir = tmp_dir("cli-guard-noisy");
    let noisy = read(&root().join("scenarios/ci-guard.toml")).replace(
        "[tracker]\n",
        "[tracker]\nmpe_a_um = 150.0\nmpe_b_um_per_m = 60.0\n",
    );
    let noisy = write_scenario(&dir, "noisy", &noisy);
    let out = dir.join("bad");
    run(&noisy, &out, &["--threads", "2"]);
    // The committed baseline records its scenario: the edited one stands for another
    // version of the program.
    as_another_version(&out);
    let base = load_json(&committed());
    assert_eq!(
        load_json(&out.join("summary.json"))["seed"],
        base["seed"],
        "the run is on the baseline's seed"
    );
    let (ok, text) = check(&out.join("summary.json"), &committed(), &[]);
    assert!(!ok, "{text}");
    let named: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("regression: ") && l.contains(": validation_after_mm."))
        .collect();
    assert!(!named.is_empty(), "{text}");
    assert!(named.iter().all(|l| l.contains("paired")), "{text}");
    // Paired but for η's mean: ten times the noise leaves some parameters' η not
    // determinable in some trials, which the summary's figure does not count, and check
    // says so (it had compared it from the summaries without a word).
    let unpaired: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("unpaired: "))
        .collect();
    assert!(
        unpaired
            .iter()
            .all(|l| l.contains("/ random: eta_mean_pct: over the trials usable in both runs")),
        "{text}"
    );
}

/// Trials that fail in one run only: the entry's metrics pair, but over the trials usable in
/// both their per-trial values are not the summaries' figures, and are compared from the
/// summaries; `check` names them (it had said nothing), and at tolerance 0 gives no count of
/// trials that would resolve them (it gave 18446744073709551615).
#[test]
fn metrics_whose_trials_fail_in_one_run_only_are_named_as_compared_unpaired() {
    let dir = tmp_dir("cli-guard-failures");
    let with = |angle: &str| {
        let text = read(&root().join("scenarios/ci-guard.toml"))
            .replace(
                "kind = \"paper\"",
                &format!("kind = \"uniform\"\nangle_rad = {angle}\nlength_mm = 100.0"),
            )
            .replace("[[methods]]\nname = \"igg3\"\n\n", "")
            .replace("[[methods]]\nname = \"lm\"\n", "");
        write_scenario(&dir, &format!("big{angle}"), &text)
    };
    let (a, b) = (dir.join("a"), dir.join("b"));
    run(&with("1.0"), &a, &[]);
    run(&with("2.0"), &b, &[]);
    as_another_version(&b);
    let failures = load_json(&b.join("summary.json"))["results"][0]["failures"].clone();
    assert!(
        failures.as_u64().unwrap() > 0,
        "no trial failed: {failures}"
    );
    for tolerance in ["0.02", "0"] {
        let (_, text) = check(
            &b.join("summary.json"),
            &a.join("summary.json"),
            &["--tolerance", tolerance],
        );
        assert!(
            text.contains("unpaired: ls / random: eta_mean_pct, validation_after_mm.mean, ")
                && text.contains("over the trials usable in both runs their per-trial values do not give the summaries' figures"),
            "{text}"
        );
        assert!(!text.contains("18446744073709551615"), "{text}");
    }
}

#[test]
fn the_unchanged_scenario_at_another_seed_passes_against_the_committed_baseline() {
    let dir = tmp_dir("cli-guard-seed");
    let out = dir.join("other");
    let sc = root().join("scenarios/ci-guard.toml");
    run(&sc, &out, &["--seed", "7", "--threads", "2"]);
    let (ok, text) = check(&out.join("summary.json"), &committed(), &[]);
    assert!(ok, "{text}");
    assert!(text.contains("no regression beyond tolerance"), "{text}");
    // Unpaired, and check says why and what would pair it.
    assert!(
        text.contains("unpaired: the runs differ in their seed (baseline 42, this run 7)")
            && text.contains("--seed 42"),
        "{text}"
    );
    // The same seed as the baseline: every metric paired, and no change at all.
    let same = dir.join("same");
    run(&sc, &same, &["--threads", "1"]);
    let (ok, text) = check(&same.join("summary.json"), &committed(), &["--strict"]);
    assert!(ok, "{text}");
    assert!(!text.contains("unpaired"), "{text}");
    let tally = text
        .lines()
        .find(|l| l.contains("metrics compared"))
        .unwrap_or_default();
    // failures and eta_median_pct have no per-trial values: compared from the summaries.
    let (m, rest) = tally.split_once(" metrics compared (").unwrap();
    let paired: usize = rest.split(' ').next().unwrap().parse().unwrap();
    let m: usize = m.parse().unwrap();
    assert!(paired > m / 2, "{tally}");
    assert!(tally.ends_with(&format!("{m} no change")), "{tally}");
}

#[test]
fn calbench_baseline_writes_a_baseline_that_pairs_and_refuses_a_lone_summary() {
    let dir = tmp_dir("cli-guard-baseline");
    let sc = root().join("scenarios/ci-guard.toml");
    let a = dir.join("a");
    run(&sc, &a, &["--trials", "3", "--seed", "5"]);
    let base = dir.join("base.json");
    let o = calbench_ok(&["baseline", path_arg(&a), "--out", path_arg(&base)]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("wrote"));
    // The summary as it is, with the per-trial values beside it.
    let (doc, summary) = (load_json(&base), load_json(&a.join("summary.json")));
    let mut without = doc.clone();
    let per_trial = without
        .as_object_mut()
        .unwrap()
        .remove("per_trial")
        .unwrap();
    assert_eq!(without, summary);
    assert_eq!(per_trial["format"], "calbench-per-trial-1");
    let ls = &per_trial["entries"]["ls / random"];
    assert_eq!(ls["trials"], serde_json::json!([0, 1, 2]));
    assert_eq!(
        ls["values"]["validation_after_mm.rms"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
    // The same run against it: paired; the baseline file alone carries the trials.
    let (ok, text) = check(&a.join("summary.json"), &base, &["--strict"]);
    assert!(ok && !text.contains("unpaired"), "{text}");
    // A summary without its trials.csv is no baseline that pairs, and against a lone
    // summary check says what pairing would take.
    let lone = dir.join("lone.json");
    std::fs::copy(a.join("summary.json"), &lone).unwrap();
    let o = calbench(&[
        "baseline",
        path_arg(&lone),
        "--out",
        path_arg(&dir.join("x.json")),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("lone.json") && err.contains("trials.csv"),
        "{err}"
    );
    assert!(!dir.join("x.json").exists());
    // Into a folder that does not exist: the file asked for is named, not the temporary one.
    let nowhere = dir.join("nowhere/b.json");
    let o = calbench(&["baseline", path_arg(&a), "--out", path_arg(&nowhere)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.starts_with(&format!("error: {}: its folder ", nowhere.display()))
            && err.contains("does not exist")
            && !err.contains("partial"),
        "{err}"
    );
    // Not over the run's own files: its scenario.toml (which `check` reads) or its report
    // had been replaced, and the run could no longer be checked or recorded.
    for name in ["scenario.toml", "report.md", "timing.json", "summary.json"] {
        let file = a.join(name);
        let before = std::fs::read(&file).unwrap();
        let o = calbench(&["baseline", path_arg(&a), "--out", path_arg(&file)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains("is an input of this command"),
            "{name}: {err}"
        );
        assert_eq!(std::fs::read(&file).unwrap(), before, "{name}");
    }
    let (ok, text) = check(&a.join("summary.json"), &lone, &[]);
    assert!(ok, "{text}");
    assert!(
        text.contains("unpaired: ") && text.contains("calbench baseline RUN --out FILE"),
        "{text}"
    );
    // Per-trial values that disagree with their summary are refused naming the key.
    let mut bad = doc.clone();
    bad["per_trial"]["entries"]["ls / random"]["values"]["validation_after_mm.rms"] =
        serde_json::json!([1.0]);
    let badp = dir.join("bad.json");
    std::fs::write(&badp, serde_json::to_string_pretty(&bad).unwrap()).unwrap();
    let (ok, text) = check(&a.join("summary.json"), &badp, &[]);
    assert!(
        !ok && text.contains("bad.json") && text.contains("validation_after_mm.rms"),
        "{text}"
    );
}

/// docs/guard.md's figures come from `scripts/guard-calibration.py`: the script is run again
/// (200 runs and a few thousand checks: minutes with a release build, so ignored by default;
/// `cargo test --test cli -- --ignored guard_error_rates`, `CALBENCH_BIN` naming a release
/// binary to make it faster) and its tables must be the page's, and the page's claims must
/// hold: at most 1 % of unchanged pairs flagged, and the smallest planted change caught in
/// at least 90 % of the pairs, paired and unpaired.
#[test]
#[ignore]
fn guard_error_rates() {
    let python = std::process::Command::new("python3")
        .arg("--version")
        .output();
    if python.is_err() {
        assert!(!crate::html::ci(), "python3 is not on the PATH");
        eprintln!("SKIP: python3 is not on the PATH");
        return;
    }
    let bin = std::env::var("CALBENCH_BIN")
        .unwrap_or_else(|_| env!("CARGO_BIN_EXE_calbench").to_string());
    let dir = tmp_dir("cli-guard-rates");
    let json = dir.join("rates.json");
    let o = std::process::Command::new("python3")
        .arg(root().join("scripts/guard-calibration.py"))
        .args(["--calbench", &bin, "--work", path_arg(&dir), "--json"])
        .arg(&json)
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = read(&root().join("docs/guard.md"));
    for table in out.split("\n\n").filter(|t| t.starts_with("| comparison")) {
        assert!(page.contains(table.trim()), "docs/guard.md lacks\n{table}");
    }
    let rates = load_json(&json);
    for (tol, r) in rates["tolerances"].as_object().unwrap() {
        let rate = |k: &str| {
            let x = &r[k];
            x["flagged"].as_f64().unwrap() / x["of"].as_f64().unwrap()
        };
        if page.contains(&format!("tolerance {tol} (CI)")) {
            for k in [
                "false alarm, different seeds",
                "false alarm, same seed, moved draws",
            ] {
                assert!(rate(k) <= 0.01, "{tol} {k}: {}", rate(k));
            }
            for kind in ["paired, same draws", "unpaired"] {
                assert!(
                    r.as_object()
                        .unwrap()
                        .keys()
                        .any(|k| k.starts_with(kind) && rate(k) >= 0.9),
                    "{tol}: no planted change caught {kind} in 90 % of the pairs"
                );
            }
        }
    }
}

/// `--tolerance` of `check`, `compare` and `history` is a number from 0 to 10 (1000 %): a
/// larger, negative or non-finite one is refused naming the option and the range, before any
/// work; an accepted one is printed in the short number format, never in hundreds of digits.
#[test]
fn a_tolerance_out_of_range_is_refused_and_a_tiny_one_printed_short() {
    let dir = tmp_dir("cli-guard-tolerance");
    let (base, out) = (committed(), dir.join("cmp"));
    let (b, o) = (path_arg(&base), path_arg(&out));
    let db = dir.join("db.sqlite");
    // `--tolerance -0.5` is the option's value too, not an unknown argument `-0.5`.
    let forms = |t: &str| {
        [
            vec![format!("--tolerance={t}")],
            vec!["--tolerance".into(), t.into()],
        ]
    };
    for form in ["1e308", "10.5", "NaN", "inf", "-0.5"]
        .into_iter()
        .flat_map(forms)
    {
        let tolerance: Vec<&str> = form.iter().map(String::as_str).collect();
        let cases: [Vec<&str>; 3] = [
            [&["check", b, "--baseline", b][..], &tolerance].concat(),
            [&["compare", b, b, "--out", o][..], &tolerance].concat(),
            [
                &["history", "--db", path_arg(&db), "--out", o][..],
                &tolerance,
            ]
            .concat(),
        ];
        for args in cases {
            let r = calbench(&args);
            let err = String::from_utf8_lossy(&r.stderr);
            assert_eq!(r.status.code(), Some(1), "{args:?}: {err}");
            assert!(
                err.contains("--tolerance") && err.contains("from 0 to 10"),
                "{args:?}: {err}"
            );
        }
    }
    assert!(!out.exists() && !db.exists(), "a refused command wrote");
    let (ok, text) = check(&base, &base, &["--tolerance", "1e-300"]);
    assert!(ok && text.contains("beyond tolerance 1e-300\n"), "{text}");
    let text = calbench_ok(&["compare", b, b, "--out", o, "--tolerance", "1e-300"]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.contains("(tolerance 1e-300)"), "{text}");
    assert!(read(&out.join("compare.html")).contains("a tolerance of 1e-300 "));
}

/// `check` reads the `trials.csv` beside a summary strictly: an empty file, a column the
/// comparison reads missing from the header, a row of fewer cells than the header, a cell
/// that is not a number and a trial given twice for an entry are each refused naming the
/// file, the line and the column, where they were skipped or taken as no per-trial values.
#[test]
fn a_malformed_trials_csv_is_refused_naming_file_line_and_column() {
    let dir = tmp_dir("cli-guard-trials-csv");
    let sc = root().join("scenarios/ci-guard.toml");
    let run_dir = dir.join("run");
    run(&sc, &run_dir, &["--trials", "2", "--threads", "1"]);
    let good = read(&run_dir.join("trials.csv"));
    let lines: Vec<&str> = good.lines().collect();
    let head: Vec<&str> = lines[0].split(',').collect();
    let at = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let cells = |l: &str| l.split(',').map(String::from).collect::<Vec<_>>();
    let with_row = |k: usize, row: &[String]| {
        let mut ls: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        ls[k] = row.join(",");
        ls.join("\n") + "\n"
    };
    let mut not_a_number = cells(lines[2]);
    not_a_number[at("after_rms_mm")] = "0.1x".into();
    let short = &cells(lines[3])[..head.len() - 2];
    let termination = at("termination");
    let no_termination: String = lines
        .iter()
        .map(|l| {
            let mut c = cells(l);
            c.remove(termination);
            c.join(",") + "\n"
        })
        .collect();
    let w = |ws: &[&str]| ws.iter().map(|s| s.to_string()).collect::<Vec<String>>();
    let cases: [(String, Vec<String>); 5] = [
        (String::new(), w(&["header", "is empty"])),
        (
            no_termination,
            w(&["line 1, termination", "missing from the header"]),
        ),
        (
            with_row(3, short),
            w(&[&format!("line 4, {}", head[head.len() - 2]), "missing"]),
        ),
        (
            with_row(2, &not_a_number),
            w(&["line 3, after_rms_mm", "\"0.1x\" is not a number"]),
        ),
        (
            format!("{good}{}\n", lines[1]),
            w(&[&format!("line {}, trial", lines.len() + 1), "twice"]),
        ),
    ];
    let csv = run_dir.join("trials.csv");
    for (text, words) in cases {
        std::fs::write(&csv, &text).unwrap();
        let (ok, err) = check(&run_dir.join("summary.json"), &committed(), &[]);
        assert!(!ok, "{text:.200}: accepted");
        let want: Vec<&str> = words.iter().map(String::as_str).collect();
        crate::common::one_line_naming(&err, &csv, &want);
    }
}

/// A run folder's `trials.csv` and a baseline's `per_trial` must be the values behind their
/// summary: `check` and `baseline` refuse a folder holding another run's `trials.csv`
/// (naming the file and the column) and a baseline whose values were edited (naming the key's
/// line); they had been compared from the summaries without a word. An entry whose trials
/// differ between two runs that otherwise pair gets its `unpaired:` line.
#[test]
fn per_trial_values_not_behind_their_summary_are_refused_and_an_unpaired_entry_is_named() {
    let dir = tmp_dir("cli-guard-behind");
    let sc = root().join("scenarios/ci-guard.toml");
    let (a, other) = (dir.join("a"), dir.join("other"));
    run(&sc, &a, &["--trials", "3", "--seed", "5"]);
    run(&sc, &other, &["--trials", "3", "--seed", "6"]);
    let mixed = dir.join("mixed");
    std::fs::create_dir_all(&mixed).unwrap();
    std::fs::copy(a.join("summary.json"), mixed.join("summary.json")).unwrap();
    std::fs::copy(other.join("trials.csv"), mixed.join("trials.csv")).unwrap();
    let (ok, text) = check(&mixed.join("summary.json"), &a.join("summary.json"), &[]);
    assert!(
        !ok && text.contains("mixed/trials.csv: column ") && text.contains("is not of this run"),
        "{text}"
    );
    let o = calbench(&[
        "baseline",
        path_arg(&mixed),
        "--out",
        path_arg(&dir.join("m.json")),
    ]);
    assert!(
        !o.status.success(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(!dir.join("m.json").exists());

    let base = dir.join("base.json");
    calbench_ok(&["baseline", path_arg(&a), "--out", path_arg(&base)]);
    let doc = load_json(&base);
    let edit = |name: &str, f: &dyn Fn(&mut serde_json::Value)| {
        let mut d = doc.clone();
        f(&mut d["per_trial"]["entries"]["lm / random"]);
        let p = dir.join(name);
        std::fs::write(&p, serde_json::to_string_pretty(&d).unwrap()).unwrap();
        p
    };
    // Every value 10 % larger: it was paired elsewhere and this entry said "no change".
    let scaled = edit("scaled.json", &|e| {
        for row in e["values"].as_object_mut().unwrap().values_mut() {
            for v in row.as_array_mut().unwrap() {
                *v = serde_json::json!(v.as_f64().unwrap() * 1.1);
            }
        }
    });
    let (ok, text) = check(&a.join("summary.json"), &scaled, &[]);
    let line = read(&scaled)
        .lines()
        .position(|l| l.contains("\"lm / random\""))
        .unwrap();
    assert!(
        !ok && text.contains("scaled.json: line ")
            && text.contains("per_trial.entries.lm / random.values.")
            && text.contains("where the summary has"),
        "{text}"
    );
    assert!(
        text.contains(&format!("line {}", line + 3)) || text.contains("line "),
        "{text}"
    );
    // Its trials renumbered: no run draws trial 7 of 3 (it had been compared unpaired).
    let renumbered = edit("renumbered.json", &|e| {
        e["trials"] = serde_json::json!([0, 1, 7])
    });
    let (ok, text) = check(&a.join("summary.json"), &renumbered, &[]);
    assert!(
        !ok && text.contains("renumbered.json: line ")
            && text.contains(
                "per_trial.entries.lm / random.trials: holds trial 7 of lm / random, where the \
                 summary ran trials 0 to 2"
            ),
        "{text}"
    );
    // A run's trials.csv cut to its header, or to fewer trials than its summary ran, had made
    // check fall back to the summaries' intervals: it is refused as not the run's whole file.
    let csv = read(&a.join("trials.csv"));
    let rows: Vec<&str> = csv.lines().collect();
    for (name, kept, words) in [
        (
            "header",
            1,
            "holds 0 of the 3 trials of ls / random that the summary ran",
        ),
        (
            "cut",
            rows.len() - 1,
            "holds 2 of the 3 trials of lm / random that the summary ran",
        ),
    ] {
        let cut = dir.join(name);
        std::fs::create_dir_all(&cut).unwrap();
        std::fs::copy(a.join("summary.json"), cut.join("summary.json")).unwrap();
        std::fs::write(cut.join("trials.csv"), rows[..kept].join("\n") + "\n").unwrap();
        let (ok, text) = check(&cut.join("summary.json"), &a.join("summary.json"), &[]);
        let want = format!("{name}/trials.csv: column trial: {words}: ");
        assert!(
            !ok && text.contains(&want) && !text.contains("unpaired"),
            "{text}"
        );
    }
    // A column given twice: which one is the run's is not known (the first had been read).
    let twice = dir.join("twice");
    std::fs::create_dir_all(&twice).unwrap();
    std::fs::copy(a.join("summary.json"), twice.join("summary.json")).unwrap();
    let extra: Vec<String> = rows
        .iter()
        .enumerate()
        .map(|(i, r)| match i {
            0 => format!("{r},after_max_mm"),
            _ => format!("{r},5.0"),
        })
        .collect();
    std::fs::write(twice.join("trials.csv"), extra.join("\n") + "\n").unwrap();
    let (ok, text) = check(&twice.join("summary.json"), &a.join("summary.json"), &[]);
    assert!(
        !ok && text.contains("twice/trials.csv: line 1, column after_max_mm: column \"after_max_mm\" appears twice in the header"),
        "{text}"
    );
}

/// A value of the wrong type inside a summary's error statistic or a baseline's per-trial
/// values is refused naming its own key and line (`results[0].validation_after_mm.mean`,
/// `per_trial.entries.ls / random.values.…[0]`), where the message named the object around it.
#[test]
fn a_bad_value_deep_in_a_summary_or_baseline_is_named_by_its_own_key_and_line() {
    let dir = tmp_dir("cli-guard-deep");
    let (a, base) = three_trials_and_baseline(&dir);
    let mut s = load_json(&a.join("summary.json"));
    s["results"][0]["validation_after_mm"]["mean"] = "x".into();
    let mut b = load_json(&base);
    let values = &mut b["per_trial"]["entries"]["ls / random"]["values"];
    let column = values.as_object().unwrap().keys().next().unwrap().clone();
    values[&column][0] = "x".into();
    // A scenario as run that is not TOML is the baseline's fault, not the other run's.
    let mut c = load_json(&base);
    c["per_trial"]["scenario"] = "x".into();
    for (name, doc, key) in [
        ("c.json", c, "per_trial.scenario".to_string()),
        (
            "s.json",
            s,
            "results[0].validation_after_mm.mean".to_string(),
        ),
        (
            "b.json",
            b,
            format!("per_trial.entries.ls / random.values.{column}[0]"),
        ),
    ] {
        let p = dir.join(name);
        std::fs::write(&p, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
        let line = read(&p).lines().position(|l| l.contains("\"x\"")).unwrap() + 1;
        let (ok, text) = check(&p, &a.join("summary.json"), &[]);
        assert!(
            !ok && text.contains(&format!("{name}: line {line}, {key}: ")),
            "{name}: {text}"
        );
    }
}

/// `baseline --out` one of the files it reads (the run's `summary.json` or `trials.csv`,
/// given the run's folder or its summary) or the run's folder is refused before any work,
/// as every command that writes refuses its own inputs, and the run keeps its bytes; an
/// `--out` that is a symbolic link loop is refused with the OS error, as `compensate` does,
/// and stays a link.
#[test]
fn calbench_baseline_refuses_to_write_over_its_own_inputs() {
    let dir = tmp_dir("cli-guard-baseline-inputs");
    let a = dir.join("a");
    run(
        &root().join("scenarios/ci-guard.toml"),
        &a,
        &["--trials", "2", "--threads", "1"],
    );
    let (summary, trials) = (a.join("summary.json"), a.join("trials.csv"));
    let before = [read(&summary), read(&trials)];
    for (run, out) in [
        (&a, &trials),
        (&a, &summary),
        (&summary, &trials),
        (&summary, &summary),
        (&a, &a),
    ] {
        let o = calbench(&["baseline", path_arg(run), "--out", path_arg(out)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{}: {err}", out.display());
        let words = [
            "error: setting `--out`: ",
            "is an input of this command",
            "(nothing was written)",
        ];
        assert!(words.iter().all(|w| err.contains(w)), "{err}");
        assert_eq!([read(&summary), read(&trials)], before);
    }
    let lp = dir.join("loop.json");
    std::os::unix::fs::symlink(&lp, &lp).unwrap();
    let o = calbench(&["baseline", path_arg(&a), "--out", path_arg(&lp)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with(&format!("error: {}: ", lp.display())) && err.contains("symbolic links"),
        "{err}"
    );
    assert!(lp.is_symlink());
}

/// A path that cannot be told present or missing (a link that loops, a folder where a file is
/// read) is refused with the system's words, naming it: `check` had compared a run whose
/// `trials.csv` is such a path from the summaries alone, saying the folder held none, and a
/// summary or a results database behind a looping link was called missing.
#[test]
fn paths_that_cannot_be_read_are_not_called_missing() {
    let dir = tmp_dir("cli-guard-unreadable");
    let a = dir.join("a");
    run(
        &root().join("scenarios/ci-guard.toml"),
        &a,
        &["--trials", "2", "--threads", "1"],
    );
    let trials = a.join("trials.csv");
    std::fs::remove_file(&trials).unwrap();
    std::fs::create_dir(&trials).unwrap();
    let base = committed();
    let o = calbench(&["check", path_arg(&a), "--baseline", path_arg(&base)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with(&format!("error: {}: ", trials.display())),
        "{err}"
    );
    let looped = dir.join("loop.json");
    std::os::unix::fs::symlink(&looped, &looped).unwrap();
    let db = dir.join("loop.sqlite");
    std::os::unix::fs::symlink(&db, &db).unwrap();
    for args in [
        vec!["check", path_arg(&looped), "--baseline", path_arg(&base)],
        vec!["history", "--db", path_arg(&db), "--regressions"],
    ] {
        let o = calbench(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains("symbolic links") && !err.contains("does not exist"),
            "{err}"
        );
        assert!(!err.contains("no such file"), "{err}");
    }
}

/// A baseline whose `per_trial` holds a metric no run writes, or an entry its own summary
/// has no result of, is refused by `check` naming the file, the line and the key, as its
/// summary's unknown fields are (each at its own key's line); both ran with exit status 0 and no word (docs/formats.md
/// § 2.4.1: the per-trial values are those behind the file's summary).
#[test]
fn a_per_trial_key_the_baseline_s_summary_lacks_is_refused_at_its_line() {
    let dir = tmp_dir("cli-guard-per-trial-keys");
    let doc = load_json(&committed());
    let entries = &doc["per_trial"]["entries"];
    let entry = entries.as_object().unwrap().keys().next().unwrap().clone();
    let mut metric = doc.clone();
    metric["per_trial"]["entries"][&entry]["values"]["bogus_metric"] =
        entries[&entry]["values"]["eta_mean_pct"].clone();
    // A key an entry has not, at its own line (it had been named at the entry's first line).
    let mut field = doc.clone();
    field["results"][0]["foo"] = 1.into();
    let mut extra = doc.clone();
    extra["per_trial"]["entries"]["nosuch / random"] = entries[&entry].clone();
    let cases = [
        (
            "metric",
            metric,
            "\"bogus_metric\"",
            format!("per_trial.entries.{entry}.values.bogus_metric: unknown metric"),
        ),
        (
            "field",
            field,
            "\"foo\"",
            "results[0].foo: not a calbench summary.json: unknown field `foo`".to_string(),
        ),
        (
            "entry",
            extra,
            "\"nosuch / random\"",
            "per_trial.entries.nosuch / random: is not an entry of the summary's results"
                .to_string(),
        ),
    ];
    for (name, d, key, why) in cases {
        let p = dir.join(format!("{name}.json"));
        let text = serde_json::to_string_pretty(&d).unwrap();
        std::fs::write(&p, &text).unwrap();
        let line = text.lines().position(|l| l.contains(key)).unwrap() + 1;
        let (ok, said) = check(&committed(), &p, &[]);
        let want = format!("{name}.json: line {line}, {why}");
        assert!(!ok && said.contains(&want), "{want}: {said}");
    }
}
