//! `calbench check` and `compare` tell a real change from Monte-Carlo noise (docs/formats.md
//! § 8.4): runs of `scenarios/ci-guard.toml` that differ only in the seed show no regression;
//! a tracker ten times noisier on the same seed is a paired regression of the validation
//! error; one 1.5 times noisier is a real change within the tolerance.

use std::path::{Path, PathBuf};

use crate::common::{
    as_another_version, calbench, calbench_ok, load_json, path_arg, read, root, tmp_dir,
    write_scenario,
};

/// Trials per run: enough for the seed-to-seed noise of the guarded metrics to stay inside
/// their intervals and for the small change to be significant on paired draws.
const TRIALS: &str = "200";

/// `scenarios/ci-guard.toml` with the tracker's MPE scaled by `scale` (1: the file as is).
fn scenario(dir: &Path, scale: f64) -> PathBuf {
    let text = read(&root().join("scenarios/ci-guard.toml"));
    if scale == 1.0 {
        return root().join("scenarios/ci-guard.toml");
    }
    let tracker = format!(
        "[tracker]\nmpe_a_um = {}\nmpe_b_um_per_m = {}\n",
        15.0 * scale,
        6.0 * scale
    );
    write_scenario(
        dir,
        &format!("noise-{scale}"),
        &text.replace("[tracker]\n", &tracker),
    )
}

fn run(scenario: &Path, seed: &str, out: &Path) {
    calbench_ok(&[
        "run",
        path_arg(scenario),
        "--trials",
        TRIALS,
        "--seed",
        seed,
        "--out",
        path_arg(out),
        "--threads",
        "2",
    ]);
}

fn check(new: &Path, base: &Path, extra: &[&str]) -> (bool, String) {
    let (s, b) = (new.join("summary.json"), base.join("summary.json"));
    let mut args = vec!["check", path_arg(&s), "--baseline", path_arg(&b)];
    args.extend(extra);
    let o = calbench(&args);
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    (o.status.success(), text)
}

/// The rows of a `compare.md` (status, interval of the change, Holm-adjusted p), each
/// resolved one (a regression, an improvement, a change within tolerance) checked to have an
/// interval that excludes zero, as docs/formats.md § 8.4 defines them.
fn statuses_agree_with_their_intervals(md: &str) -> Vec<(String, [f64; 2], f64)> {
    let mut rows = Vec::new();
    for line in md.lines() {
        let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
        if cells.len() != 10 || !cells[7].starts_with('[') {
            continue;
        }
        let ci: Vec<f64> = cells[7]
            .trim_matches(|c| c == '[' || c == ']')
            .split(", ")
            .map(|x| x.parse().unwrap())
            .collect();
        let resolved = ["regression", "improved", "changed"]
            .iter()
            .any(|s| cells[6].starts_with(s));
        assert!(
            !resolved || ci[0] > 0.0 || ci[1] < 0.0,
            "{} beside an interval holding zero: {line}",
            cells[6]
        );
        rows.push((
            cells[6].to_string(),
            [ci[0], ci[1]],
            cells[8].parse().unwrap(),
        ));
    }
    assert!(!rows.is_empty(), "no rows in\n{md}");
    rows
}

/// The line of `text` about `metric` of `entry`.
fn line<'t>(text: &'t str, entry: &str, metric: &str) -> &'t str {
    text.lines()
        .find(|l| l.contains(&format!("{entry}: {metric}: ")))
        .unwrap_or("")
}

/// The README's "Noise or a real difference" quotes these runs (its commands are theirs):
/// IGG3's and LS's validation RMS after with their intervals from `a`'s summary, their paired
/// comparison (the mean difference with its interval, the win rate, the sign test's median
/// and interval with the verdict, the Holm-adjusted Wilcoxon p), and `check`'s tally of `b`
/// against `a` (`check_text`).
fn readme_quotes(a: &Path, check_text: &str) {
    let readme = read(&root().join("README.md"));
    let readme = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    let s = load_json(&a.join("summary.json"));
    let f4 = |v: &serde_json::Value| format!("{:.4}", v.as_f64().unwrap());
    let rms = |method: &str| {
        let results = s["results"].as_array().unwrap();
        let e = results.iter().find(|e| e["method"] == method).unwrap();
        let v = &e["validation_after_mm"];
        let ci = &v["rms_ci95"];
        (f4(&v["rms"]), f4(&ci[0]), f4(&ci[1]))
    };
    let pair = s["comparisons"].as_array().unwrap().iter().find(|c| {
        c["a"] == "ls / random"
            && c["b"] == "igg3 / random"
            && c["metric"] == "validation_after_mm.rms"
    });
    let pair = pair.unwrap();
    let neg = |v: &serde_json::Value| format!("{:.4}", -v.as_f64().unwrap());
    let (igg3, ls) = (rms("igg3"), rms("ls"));
    assert_eq!(pair["test"], "sign", "{pair}");
    let tally = check_text
        .lines()
        .find(|l| l.contains(" metrics compared ("));
    let tally = tally.unwrap_or_else(|| panic!("no tally: {check_text}"));
    let count = |what: &str| {
        let at = tally
            .find(what)
            .unwrap_or_else(|| panic!("{what}: {tally}"));
        tally[..at].rsplit([' ', '(']).next().unwrap().to_string()
    };
    for quote in [
        format!("In {TRIALS} trials of `scenarios/ci-guard.toml`"),
        format!("is {} mm (`rms_ci95` [{}, {}])", igg3.0, igg3.1, igg3.2),
        format!("against LS's {} mm ([{}, {}])", ls.0, ls.1, ls.2),
        format!(
            "lower by {} mm on average [{}, {}] and wins {} % of the trials",
            neg(&pair["diff_mean"]),
            neg(&pair["diff_ci95"][1]),
            neg(&pair["diff_ci95"][0]),
            (100.0 * pair["win_rate"].as_f64().unwrap()).round()
        ),
        format!(
            "the verdict is the sign test's, on their median (docs/formats.md, \"Tests and \
             margins\"): {} mm [{}, {}], `{}` in the report's comparison table, whose \
             Holm-adjusted Wilcoxon p is {:.0e}",
            f4(&pair["estimate"]),
            f4(&pair["ci95"][0]),
            f4(&pair["ci95"][1]),
            pair["verdict"].as_str().unwrap(),
            pair["p_holm"].as_f64().unwrap()
        ),
        format!(
            "{} of the {} metrics `no change`, {} parameter RMSEs `unresolved`",
            count(" no change"),
            tally.split(' ').next().unwrap(),
            count(" unresolved")
        ),
    ] {
        assert!(readme.contains(&quote), "README.md does not say: {quote}");
    }
}

#[test]
fn another_seed_is_no_regression_and_a_planted_one_is_caught() {
    let dir = tmp_dir("cli-noise");
    let (a, b) = (dir.join("a"), dir.join("b"));
    run(&scenario(&dir, 1.0), "42", &a);
    run(&scenario(&dir, 1.0), "9", &b);
    // Seeds 42 and 9: unpaired, every metric "no change" or "unresolved".
    let (ok, text) = check(&b, &a, &[]);
    assert!(ok, "{text}");
    assert!(
        text.contains("no regression beyond tolerance 0.05"),
        "{text}"
    );
    assert!(text.contains("(0 paired): 0 regression"), "{text}");
    readme_quotes(&a, &text);
    let cmp = dir.join("cmp");
    let o = calbench_ok(&[
        "compare",
        path_arg(&a),
        path_arg(&b),
        "--out",
        path_arg(&cmp),
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains(": 0 regressed (0 of them missing in B)"),
        "{out}"
    );
    // The counts add up to the metrics compared.
    let (m, rest) = out.split_once(" metrics compared: ").unwrap();
    let sum: usize = rest
        .split(", ")
        .take(5)
        .map(|p| p.split(' ').next().unwrap().parse::<usize>().unwrap())
        .sum();
    assert_eq!(sum, m.trim().parse::<usize>().unwrap(), "{out}");
    let md = read(&cmp.join("compare.md"));
    assert!(md.contains("No regression"), "{md}");

    // Ten times the tracker noise on the same seed: a paired regression of the validation
    // error, and check fails.
    let loud = dir.join("loud");
    run(&scenario(&dir, 10.0), "42", &loud);
    as_another_version(&loud);
    let (ok, text) = check(&loud, &a, &[]);
    assert!(!ok, "{text}");
    let l = line(&text, "lm / random", "validation_after_mm.rms");
    assert!(
        l.starts_with("regression: ") && l.contains("paired"),
        "{text}"
    );
    let cmp2 = dir.join("cmp2");
    calbench_ok(&[
        "compare",
        path_arg(&a),
        path_arg(&loud),
        "--out",
        path_arg(&cmp2),
    ]);
    let md = read(&cmp2.join("compare.md"));
    assert!(md.contains("metrics of B regressed"), "{md}");
    statuses_agree_with_their_intervals(&md);

    // Three times: the rank test rejects on some parameters' squared errors whose interval
    // still holds zero; those are unresolved, never a regression beside that interval.
    let three = dir.join("three");
    run(&scenario(&dir, 3.0), "42", &three);
    as_another_version(&three);
    let cmp3 = dir.join("cmp3");
    calbench_ok(&[
        "compare",
        path_arg(&a),
        path_arg(&three),
        "--out",
        path_arg(&cmp3),
    ]);
    let rows = statuses_agree_with_their_intervals(&read(&cmp3.join("compare.md")));
    assert!(rows.iter().any(|r| r.0 == "regression"), "{rows:?}");
    assert!(
        rows.iter()
            .any(|r| r.0.starts_with("unresolved") && r.2 < 0.01 && r.1[0] <= 0.0),
        "{rows:?}"
    );

    // 1.5 times: a real change of the validation error within the tolerance.
    let mild = dir.join("mild");
    run(&scenario(&dir, 1.5), "42", &mild);
    as_another_version(&mild);
    let (_, text) = check(&mild, &a, &[]);
    let l = line(&text, "lm / random", "validation_after_mm.rms");
    assert!(
        l.starts_with("changed, within tolerance: ") && l.contains("paired"),
        "{text}"
    );
}

#[test]
fn strict_fails_on_unresolved() {
    // Two trials per run differing in the seed: the guarded errors move by more than the
    // tolerance, far within the noise.
    let dir = tmp_dir("cli-noise-strict");
    let (a, b) = (dir.join("a"), dir.join("b"));
    for (seed, out) in [("1", &a), ("2", &b)] {
        calbench_ok(&[
            "run",
            path_arg(&root().join("scenarios/ci-guard.toml")),
            "--trials",
            "3",
            "--seed",
            seed,
            "--out",
            path_arg(out),
        ]);
    }
    let (ok, text) = check(&b, &a, &[]);
    assert!(ok, "{text}");
    assert!(text.contains("unresolved: "), "{text}");
    assert!(text.contains("trials per run would resolve it"), "{text}");
    let (ok, text) = check(&b, &a, &["--strict"]);
    assert!(!ok && text.contains("unresolved (--strict)"), "{text}");
}

#[test]
fn two_sweeps_are_compared_point_by_point_on_their_shared_trials() {
    // A sweep of the outlier count, run twice on one seed: the second with a tracker ten
    // times noisier. Each entry is paired at its own sweep point.
    let sweep = "\n[sweep]\nkey = \"outliers.count\"\nvalues = [0, 2]\n";
    sweeps_compared_point_by_point("cli-noise-sweep", sweep, ["0", "2"]);
}

#[test]
fn sweep_points_that_identify_other_parameters_are_paired_too() {
    // Full-pose data identify the tool's orientation too: `trials.csv` has columns the
    // position point leaves empty, which had left that point's every metric unpaired.
    let sweep = "\n[sweep]\nkey = \"tracker.measure\"\nvalues = [\"position\", \"pose\"]\n";
    sweeps_compared_point_by_point("cli-noise-measure", sweep, ["position", "pose"]);
}

/// ci-guard with `sweep` run on one seed, twice as it is and once with a tracker ten times
/// noisier (as another version): the same run has every metric but the always unpaired
/// ones paired and nothing changed; the noisier one regresses at both `points`, paired.
fn sweeps_compared_point_by_point(name: &str, sweep: &str, points: [&str; 2]) {
    let dir = tmp_dir(name);
    let plain = write_scenario(
        &dir,
        "plain",
        &format!("{}{sweep}", read(&root().join("scenarios/ci-guard.toml"))),
    );
    let loud = write_scenario(
        &dir,
        "loud",
        &format!("{}{sweep}", read(&scenario(&dir, 10.0))),
    );
    // The two files carry one scenario name, and the loud run stands for another version of
    // the program on the plain scenario: `check` refuses runs of two scenarios.
    let (a, b, same) = (dir.join("a"), dir.join("b"), dir.join("same"));
    for (sc, out) in [(&plain, &a), (&loud, &b), (&plain, &same)] {
        calbench_ok(&[
            "run",
            path_arg(sc),
            "--trials",
            "30",
            "--seed",
            "42",
            "--out",
            path_arg(out),
            "--threads",
            "2",
        ]);
    }
    as_another_version(&b);
    // The same run again: every metric paired, nothing changed.
    let (ok, text) = check(&same, &a, &[]);
    assert!(ok, "{text}");
    // "N metrics compared (P paired)": all but failures and eta_median_pct, which are
    // always compared unpaired (2 of each entry's metrics; 2 points × 3 methods).
    let counts: Vec<usize> = text
        .split(" metrics compared (")
        .flat_map(|s| s.split(" paired)"))
        .filter_map(|s| s.rsplit(['\n', ' ']).next()?.parse().ok())
        .collect();
    let [compared, paired] = counts[..] else {
        panic!("no tally: {text}");
    };
    assert_eq!(paired, compared - 2 * 6, "{text}");
    assert!(
        text.contains(" 0 regression, 0 unresolved, 0 changed within tolerance, 0 improved"),
        "{text}"
    );
    // The noisier tracker: the validation error regresses at both sweep points, paired.
    let (ok, text) = check(&b, &a, &[]);
    assert!(!ok, "{text}");
    for point in points {
        let l = line(
            &text,
            &format!("lm / random / {point}"),
            "validation_after_mm.rms",
        );
        assert!(
            l.starts_with("regression: ") && l.contains("paired") && !l.contains("unpaired"),
            "point {point}: {text}"
        );
    }
}

/// A copy of run `a` as run `b` in which entry `method`'s validation RMS after compensation
/// (`after_rms_mm` in `trials.csv`, `validation_after_mm.rms` in `summary.json`) moves by
/// `shift(k)` on the k-th trial, the summary's figure the mean of the new values.
fn shifted_copy(a: &Path, b: &Path, method: &str, shift: impl Fn(usize) -> f64) {
    std::fs::create_dir_all(b).unwrap();
    let csv = read(&a.join("trials.csv"));
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let (mc, rc) = (col("method"), col("after_rms_mm"));
    let (mut out, mut values) = (vec![head.join(",")], Vec::new());
    for l in lines {
        let mut cells: Vec<String> = l.split(',').map(String::from).collect();
        if cells[mc] == method {
            let v = cells[rc].parse::<f64>().unwrap() + shift(values.len());
            cells[rc] = format!("{v:?}");
            values.push(v);
        }
        out.push(cells.join(","));
    }
    std::fs::write(b.join("trials.csv"), out.join("\n") + "\n").unwrap();
    let mut s = crate::common::load_json(&a.join("summary.json"));
    let e = s["results"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|e| e["method"] == method)
        .unwrap();
    e["validation_after_mm"]["rms"] = (values.iter().sum::<f64>() / values.len() as f64).into();
    std::fs::write(b.join("summary.json"), s.to_string()).unwrap();
}

#[test]
fn a_paired_check_prints_the_interval_of_the_reports_test_of_the_pair() {
    let dir = tmp_dir("cli-noise-median");
    let sc = write_scenario(&dir, "small", crate::common::SMALL_STUDY);
    let a = dir.join("a");
    calbench_ok(&[
        "run",
        path_arg(&sc),
        "--trials",
        "30",
        "--out",
        path_arg(&a),
    ]);
    // Heavy-tailed changes (3 stalls of 0.5 mm among 30 trials of +0.002 mm): the report
    // would locate their median, and check prints the median's interval, which holds the
    // typical change and not the stalls' pull on the mean (0.052 mm).
    let heavy = dir.join("heavy");
    shifted_copy(&a, &heavy, "ls", |k| if k % 10 == 3 { 0.5 } else { 0.002 });
    let (_, text) = check(&heavy, &a, &[]);
    let l = line(&text, "ls / random", "validation_after_mm.rms");
    let interval = l
        .split("median change (sign test) in [")
        .nth(1)
        .and_then(|r| r.split(']').next())
        .unwrap_or_else(|| panic!("no median interval: {text}"));
    let bounds: Vec<f64> = interval.split(", ").map(|x| x.parse().unwrap()).collect();
    assert!(
        bounds.iter().all(|b| (b - 0.002).abs() < 1e-6),
        "{l}: the median change is 0.002"
    );
    assert!(l.contains("paired"), "{l}");
    // Light-tailed changes: the t interval of the mean, as the report's.
    let light = dir.join("light");
    shifted_copy(&a, &light, "ls", |k| {
        0.002 + 0.0004 * ((k * 7 % 11) as f64 - 5.0)
    });
    let (_, text) = check(&light, &a, &[]);
    let l = line(&text, "ls / random", "validation_after_mm.rms");
    assert!(
        l.contains(" in [") && !l.contains("median") && l.contains("paired"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Four trials: too few for the interval of a median's η (`eta_median_pct_ci95` is null),
/// so another seed's change of it is unresolved, its noise not known; it had been taken as
/// exact, as in a summary written before intervals, and failed `check` with p Holm 0.
#[test]
fn a_figure_without_an_interval_at_few_trials_is_unresolved_not_exact() {
    let dir = tmp_dir("cli-noise-few");
    let sc = root().join("scenarios/ci-guard.toml");
    let runs = ["42", "9"].map(|seed| {
        let out = dir.join(seed);
        let args = ["--trials", "4", "--seed", seed, "--out", path_arg(&out)];
        calbench_ok(&[&["run", path_arg(&sc)][..], &args].concat());
        out
    });
    let base = load_json(&runs[0].join("summary.json"));
    assert!(base["results"][0]["eta_median_pct_ci95"].is_null());
    assert!(base["results"][0]["eta_mean_pct_ci95"].is_array());
    let (ok, text) = check(&runs[1], &runs[0], &["--tolerance", "0.01"]);
    assert!(ok, "{text}");
    let median = line(&text, "ls / random", "eta_median_pct");
    assert!(
        median.starts_with("unresolved: ")
            && median.contains("with no interval (neither summary has one at its trials)")
            && median.contains("p Holm 1)"),
        "{text}"
    );
}

/// One sweep written with floats in one run and integers of the same values in the other
/// (`15.0` and `15`) is one scenario: `check` and `compare` match its entries point by point
/// and pair them, where every entry had been missing on the other side.
#[test]
fn sweep_values_written_as_integer_or_float_are_one_point() {
    let dir = tmp_dir("cli-noise-int-float");
    let text = read(&root().join("scenarios/ci-guard.toml"));
    let (a, b) = (dir.join("a"), dir.join("b"));
    for (values, out) in [("[15.0, 60.0]", &a), ("[15, 60]", &b)] {
        let sweep = format!("\n[sweep]\nkey = \"tracker.mpe_a_um\"\nvalues = {values}\n");
        let file = write_scenario(
            &dir,
            out.file_name().unwrap().to_str().unwrap(),
            &format!("{text}{sweep}"),
        );
        calbench_ok(&[
            "run",
            path_arg(&file),
            "--trials",
            "10",
            "--out",
            path_arg(out),
        ]);
    }
    let (ok, text) = check(&b, &a, &[]);
    assert!(ok, "{text}");
    assert!(
        text.contains(" 0 regression, 0 unresolved, 0 changed within tolerance, 0 improved"),
        "{text}"
    );
    assert!(!text.contains("unpaired"), "{text}");
    let cmp = dir.join("cmp");
    let o = calbench(&[
        "compare",
        path_arg(&a),
        path_arg(&b),
        "--out",
        path_arg(&cmp),
    ]);
    let said = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && said.contains("0 entries only in A, 0 only in B"),
        "{said}"
    );
    // Recorded as two versions, the history finds no step between them (it had found every
    // metric missing).
    let db = dir.join("h.sqlite");
    for (run, label) in [(&a, "1.0.0"), (&b, "2.0.0")] {
        calbench_ok(&[
            "record",
            path_arg(run),
            "--db",
            path_arg(&db),
            "--label",
            label,
        ]);
    }
    let o = calbench(&["history", "--db", path_arg(&db), "--regressions"]);
    let said = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && said.contains("no regression or drift"),
        "{said}"
    );
}

/// A run of one trial has no spread to tell its figures' noise by. Two such runs of other
/// seeds had been compared as exact, every difference a certain change (`change 0.1477 in
/// [0.1477, 0.1477], p Holm 0`): `check` failed with 30 regressions. Now the change of two
/// one-trial runs is of unknown noise (never resolved), and a one-trial run against a
/// baseline of 40 trials borrows the baseline's spread, as a summary without intervals does.
#[test]
fn a_run_of_one_trial_is_not_compared_as_exact() {
    let dir = tmp_dir("noise-one-trial");
    let guard = root().join("scenarios/ci-guard.toml");
    let runs = [("1", "3"), ("1", "5"), ("40", "7")].map(|(trials, seed)| {
        let out = dir.join(format!("t{trials}-s{seed}"));
        calbench_ok(&[
            "run",
            path_arg(&guard),
            "--trials",
            trials,
            "--seed",
            seed,
            "--out",
            path_arg(&out),
        ]);
        out
    });
    for (new, base) in [(&runs[1], &runs[0]), (&runs[0], &runs[2])] {
        let (ok, text) = check(new, base, &[]);
        assert!(ok, "{text}");
        assert!(!text.contains("regression:"), "{text}");
        assert!(!text.contains("p Holm 0)"), "{text}");
    }
    // Against the baseline of 40 trials the change has an interval of non-zero width.
    let (_, text) = check(&runs[0], &runs[2], &["--strict"]);
    let widths: Vec<f64> = text
        .split(" in [")
        .skip(1)
        .filter_map(|s| {
            let (lo, rest) = s.split_once(", ")?;
            let hi = rest.split(']').next()?;
            Some(hi.parse::<f64>().ok()? - lo.parse::<f64>().ok()?)
        })
        .collect();
    assert!(!widths.is_empty(), "{text}");
    assert!(widths.iter().all(|w| *w > 0.0), "{text}");
}
