//! The Monte-Carlo harness end to end: files and keys, thread-count determinism, the
//! regression guard, and the CI baseline.

use std::path::Path;

use calbench::analysis::regression::{
    compare, compare_with, read_json, read_summary, trials_of, Status, Trials,
};
use calbench::study::scenario::Scenario;
use calbench::study::RunOptions;

use crate::common::{calbench, path_arg, read, root, tmp_dir};

const TINY: &str = r#"
name = "tiny"
description = "a tiny study for the tests"
seed = 5
trials = 4
[robot]
builtin = "irb2600"
[errors]
kind = "paper"
[tracker]
pose = [2500.0, 0.0, 500.0, 0.0, 0.0, 180.0]
[outliers]
count = 2
magnitude_mm = [0.5, 1.0]
[compliance]
model = "linear"
[calibration]
count = 30
strategies = ["random", "detmax"]
candidates = 150
[validation]
count = 20
[[methods]]
name = "ls"
[[methods]]
name = "lm"
"#;

fn tiny() -> Scenario {
    Scenario::parse(TINY, None).unwrap()
}

fn run_to(s: Scenario, out: &Path, threads: usize) {
    calbench::runner::run::run_study(
        s,
        &RunOptions {
            threads: Some(threads),
            out: Some(out.to_path_buf()),
            progress: false,
            shard: None,
            precision: None,
        },
        &calbench::study::reporter::Silent,
    )
    .unwrap();
}

#[test]
fn tiny_study_writes_every_file_with_finite_values() {
    let out = tmp_dir("harness-tiny");
    run_to(tiny(), &out, 2);
    for f in [
        "summary.json",
        "trials.csv",
        "report.md",
        "eta.png",
        "eta.svg",
        "validation_trial0.png",
        "validation_rms.svg",
        "objective_trace.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // Position data: no attitude plot.
    assert!(!out.join("validation_trial0_attitude.png").exists());
    let s = read_json(&out.join("summary.json")).unwrap();
    for k in ["scenario", "trials", "seed", "results"] {
        assert!(s.get(k).is_some(), "summary lacks {k}");
    }
    let results = s["results"].as_array().unwrap();
    assert_eq!(results.len(), 4);
    for e in results {
        for k in [
            "method",
            "poses",
            "eta_mean_pct",
            "eta_median_pct",
            "eta",
            "validation_before_mm",
            "validation_after_mm",
            "param_rmse",
            "param_bias",
            "crb_ratio",
            "failures",
            "seconds_per_identification",
        ] {
            assert!(e.get(k).is_some(), "entry lacks {k}");
        }
        for k in ["mean", "rms", "max", "std"] {
            let b = e["validation_before_mm"][k].as_f64().unwrap();
            let a = e["validation_after_mm"][k].as_f64().unwrap();
            assert!(
                b.is_finite() && a.is_finite() && a < b,
                "{k}: before {b} after {a}"
            );
        }
        assert!(e["eta_mean_pct"].as_f64().unwrap().is_finite());
    }
    let csv = std::fs::read_to_string(out.join("trials.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 4 * 2 * 2);
}

#[test]
fn one_and_two_threads_give_the_same_bytes() {
    let (a, b) = (tmp_dir("harness-threads1"), tmp_dir("harness-threads2"));
    run_to(tiny(), &a, 1);
    run_to(tiny(), &b, 2);
    assert_eq!(read(&a.join("trials.csv")), read(&b.join("trials.csv")));
    let strip = |d: &Path| {
        read(&d.join("summary.json"))
            .lines()
            .filter(|l| !l.contains("seconds_per_identification"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(strip(&a), strip(&b));
}

#[test]
fn noise_free_study_recovers_the_injected_errors() {
    let text = TINY
        .replace(
            "[tracker]\n",
            "[tracker]\nmpe_a_um = 0.0\nmpe_b_um_per_m = 0.0\n",
        )
        .replace("count = 2\n", "count = 0\n")
        .replace("model = \"linear\"", "model = \"none\"");
    let out = tmp_dir("harness-noisefree");
    run_to(Scenario::parse(&text, None).unwrap(), &out, 2);
    let s = read_json(&out.join("summary.json")).unwrap();
    for e in s["results"].as_array().unwrap() {
        let rms = e["validation_after_mm"]["rms"].as_f64().unwrap();
        let eta = e["eta_mean_pct"].as_f64().unwrap();
        assert!(rms < 1e-4, "{}: after RMS {rms}", e["method"]);
        assert!(eta > 99.99, "{}: η {eta}", e["method"]);
        // At the calibration poses too: the errors go, and the nominal robot's were there.
        let cal = e["calibration_after_mm"]["rms"].as_f64().unwrap();
        let cal0 = e["calibration_before_mm"]["rms"].as_f64().unwrap();
        assert!(cal < 1e-4, "{}: calibration RMS after {cal}", e["method"]);
        assert!(cal0 > 1.0, "{}: calibration RMS before {cal0}", e["method"]);
    }
    // With sag, noise and outliers the calibration points are fitted, not free of error: the
    // compensated robot misses their true points by the sag it cannot model.
    let out = tmp_dir("harness-calpoints");
    run_to(tiny(), &out, 2);
    let s = read_json(&out.join("summary.json")).unwrap();
    for e in s["results"].as_array().unwrap() {
        let cal = e["calibration_after_mm"]["mean"].as_f64().unwrap();
        assert!(
            cal > 1e-3 && cal < 1.0,
            "{}: calibration mean after {cal}",
            e["method"]
        );
    }
}

#[test]
fn check_fails_on_a_worsened_summary() {
    let out = tmp_dir("harness-check");
    run_to(tiny(), &out, 2);
    let typed = read_summary(&out.join("summary.json")).unwrap();
    assert!(compare(&typed, &typed, 0.0).is_empty());
    let s = read_json(&out.join("summary.json")).unwrap();
    let mut worse = s.clone();
    let rms = worse["results"][0]["validation_after_mm"]["rms"]
        .as_f64()
        .unwrap();
    // Far beyond the Monte-Carlo noise of 4 trials: a regression, not an unresolved change.
    worse["results"][0]["validation_after_mm"]["rms"] = serde_json::json!(rms * 10.0);
    let path = out.join("worse.json");
    std::fs::write(&path, serde_json::to_string(&worse).unwrap()).unwrap();
    let o = calbench(&[
        "check",
        path_arg(&path),
        "--baseline",
        path_arg(&out.join("summary.json")),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("validation_after_mm.rms"), "{err}");
    let summary = out.join("summary.json");
    let o = calbench(&[
        "check",
        path_arg(&summary),
        "--baseline",
        path_arg(&summary),
    ]);
    assert!(o.status.success());
}

/// The regression guard CI runs: the small study `scenarios/ci-guard.toml` against
/// `results/baselines/ci-guard.json`, which carries its run's per-trial values, so the two
/// are compared trial by trial (docs/guard.md). After a deliberate change of results,
/// refresh the baseline with `calbench run scenarios/ci-guard.toml --out guard` and
/// `calbench baseline guard --out results/baselines/ci-guard.json`.
#[test]
fn ci_guard_matches_the_baseline() {
    let s = Scenario::load(&root().join("scenarios/ci-guard.toml")).unwrap();
    let out = tmp_dir("harness-ci-guard");
    run_to(s, &out, 2);
    let now = read_summary(&out.join("summary.json")).unwrap();
    let path = root().join("results/baselines/ci-guard.json");
    let base = read_summary(&path).unwrap();
    let (tb, _) = trials_of(&read_json(&path).unwrap(), &path)
        .unwrap()
        .expect("the baseline's per-trial values");
    let tn = Trials::read(&out.join("trials.csv")).unwrap();
    // The guard's rule at its tolerance (docs/guard.md): every metric that has per-trial
    // values compared trial by trial, and none a regression.
    let all = compare_with(&now, &base, GUARD_TOLERANCE, Some((&tb, &tn)));
    assert!(all.iter().filter(|c| c.paired).count() > all.len() / 2);
    let r: Vec<String> = all
        .into_iter()
        .filter(|c| c.status == Status::Regression)
        .map(|c| format!("{}: {}", c.status.as_str(), c.metric))
        .collect();
    assert!(r.is_empty(), "regressions: {}", r.join("; "));
}

/// The CI guard's tolerance, chosen from its measured error rates (docs/guard.md).
const GUARD_TOLERANCE: f64 = 0.02;

#[test]
fn bad_scenarios_are_refused_naming_the_key() {
    let cases = [
        (
            TINY.replace("[outliers]\n", "[outliers]\ncuont = 3\n"),
            "cuont",
        ),
        (TINY.replace("name = \"lm\"", "name = \"lmm\""), "lmm"),
        (TINY.replace("\"detmax\"", "\"detmx\""), "detmx"),
        (
            TINY.replace("count = 2\n", "count = 99\n"),
            "outliers.count",
        ),
        (
            TINY.replace("[tracker]\n", "[tracker]\nmpe_a_um = -1.0\n"),
            "mpe_a_um",
        ),
        // The orientation weight belongs to the pose-error models only, and must be positive.
        (
            TINY.replace("name = \"ls\"", "name = \"ls\"\nk = 100.0"),
            "methods[0].k",
        ),
        (
            TINY.replace(
                "name = \"ls\"",
                "name = \"ls\"\nerror_model = \"direct_fk\"\nk = 0.0",
            ),
            "methods[0].k",
        ),
        (
            TINY.replace("name = \"lm\"", "name = \"bas\"\nstep_floor = -1.0"),
            "methods[1].step_floor",
        ),
        (
            TINY.replace("name = \"lm\"", "name = \"bas\"\nstart = \"random\""),
            "methods[1].start",
        ),
        (
            TINY.replace("name = \"lm\"", "name = \"pso\"\ninertia = [0.9]"),
            "methods[1].inertia",
        ),
    ];
    for (text, key) in cases {
        let e = Scenario::parse(&text, Some(Path::new("bad.toml")))
            .err()
            .unwrap_or_else(|| panic!("accepted: {key}"));
        let m = e.to_string();
        assert!(m.contains(key), "message `{m}` lacks `{key}`");
    }
}

#[test]
fn metaheuristic_schedules_and_velocity_rules_are_settable() {
    let text = TINY.replace(
        "name = \"lm\"",
        "name = \"bas\"\nstart = \"halton\"\nantenna_floor = 0.0\nstep_floor = 2e-4\n\
         [[methods]]\nname = \"bas-pso\"\ninertia = [0.9, 0.4]\nmax_velocity = 0.3\nstep_floor = 0",
    );
    let s = Scenario::parse(&text, None).unwrap();
    // The options as the method holds them (its Debug form).
    let bas = format!("{:?}", s.methods[1].method);
    assert_eq!(s.methods[1].name(), "bas");
    assert!(bas.contains("start: Halton"), "{bas}");
    assert!(bas.contains("d0: 0.0, delta0: 0.0002"), "{bas}");
    let hybrid = format!("{:?}", s.methods[2].method);
    assert_eq!(s.methods[2].name(), "bas-pso");
    assert!(
        hybrid.contains("velocity: Inertia { start: 0.9, end: 0.4 }"),
        "{hybrid}"
    );
    assert!(hybrid.contains("max_velocity: 0.3"), "{hybrid}");
    assert!(hybrid.contains("delta0: 0.0"), "{hybrid}");
}

#[test]
fn full_pose_study_reports_qiao_acae() {
    let text = TINY
        .replace(
            "[tracker]\n",
            "[tracker]\nmeasure = \"pose\"\nangle_noise_deg = 0.005\n",
        )
        .replace(
            "strategies = [\"random\", \"detmax\"]",
            "strategies = [\"random\"]",
        );
    let out = tmp_dir("harness-tiny-pose");
    run_to(Scenario::parse(&text, None).unwrap(), &out, 2);
    let s = read_json(&out.join("summary.json")).unwrap();
    for e in s["results"].as_array().unwrap() {
        // Orientation errors (rotation angles) before and after, and Qiao's attitude
        // errors, whose means are Qiao's ACAE.
        for key in ["deg", "attitude_deg"] {
            let (b, a) = (
                e[format!("validation_before_{key}")]["mean"]
                    .as_f64()
                    .unwrap(),
                e[format!("validation_after_{key}")]["mean"]
                    .as_f64()
                    .unwrap(),
            );
            assert!(a.is_finite() && a < b, "{key}: {b} -> {a}");
        }
    }
    let report = read(&out.join("report.md"));
    assert!(report.contains("after mean °"));
}

#[test]
fn every_shipped_scenario_loads() {
    let dir = root().join("scenarios");
    let mut n = 0;
    for f in std::fs::read_dir(&dir).unwrap() {
        let p = f.unwrap().path();
        if p.extension().is_some_and(|e| e == "toml") {
            use calbench::study::kind::AnyScenario;
            // The kind read by serde from the file's sections.
            let kind = match AnyScenario::load(&p) {
                Ok(AnyScenario::MonteCarlo(_)) => None,
                Ok(AnyScenario::Registration(_)) => Some("registration study"),
                Ok(AnyScenario::Instruments(_)) => Some("instruments study"),
                Err(e) => panic!("{}: {e}", p.display()),
            };
            match kind {
                // Not a calibration scenario, and said so by the commands that take one.
                Some(kind) => {
                    let Err(e) = Scenario::load(&p) else {
                        panic!("a {kind} is not a calibration scenario")
                    };
                    assert!(e.to_string().contains(kind), "{e}");
                }
                None => {
                    Scenario::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
                }
            }
            n += 1;
        }
    }
    assert!(n >= 6, "{n} scenarios");
}

/// A fixed pose set on a true robot that is the same in every trial has its rapier sag
/// computed once for the study; each trial must measure exactly what it would have
/// measured by running the sag model itself.
#[test]
fn the_memoised_sag_of_a_fixed_pose_set_is_the_one_each_trial_computes() {
    let text = TINY
        .replace("model = \"linear\"", "model = \"rapier\"")
        .replace("count = 30", "count = 12")
        .replace("candidates = 150", "candidates = 40\noptimise = \"study\"");
    let mut study = calbench::study::Study::new(Scenario::parse(&text, None).unwrap()).unwrap();
    let fixed = study.fixed[1].as_ref().expect("detmax gives a fixed set");
    assert!(
        fixed.sag.is_some(),
        "paper errors + rapier sag + fixed set: memoised"
    );
    // Everything but the wall time.
    let outcomes = |study: &calbench::study::Study| {
        let mut t = calbench::study::run_trial(study, 2).unwrap();
        t.outcomes.iter_mut().for_each(|o| o.seconds = 0.0);
        format!("{:?}", t.outcomes)
    };
    let with = outcomes(&study);
    for f in study.fixed.iter_mut().flatten() {
        f.sag = None;
    }
    assert_eq!(with, outcomes(&study));
}

/// Full-pose data add the per-point attitude plot (Qiao 2021 fig. 6) beside the position one.
#[test]
fn full_pose_study_plots_the_attitude_error_per_point() {
    let text = TINY
        .replace("[tracker]", "[tracker]\nmeasure = \"pose\"")
        .replace(
            "strategies = [\"random\", \"detmax\"]",
            "strategies = [\"random\"]",
        );
    let out = tmp_dir("harness-attitude");
    run_to(Scenario::parse(&text, None).unwrap(), &out, 2);
    for f in [
        "validation_trial0_attitude.png",
        "validation_trial0_attitude.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let report = read(&out.join("report.md"));
    assert!(report.contains("validation_trial0_attitude.png"));
}

/// `CALBENCH_SIMD=scalar` (docs/formats.md) forces the portable kernels: the default study
/// writes the same `summary.json` and `trials.csv` bytes on them as on the processor's best
/// path (AVX2 and FMA where it has them), and a misspelt value is refused before any work.
#[test]
fn the_portable_path_writes_the_same_bytes_as_the_vector_path() {
    // The study `calbench` runs without arguments.
    let default_study = root().join("scenarios/default.toml").display().to_string();
    let run = |simd: &str, name: &str| {
        let out = tmp_dir(name);
        let o = crate::common::bin()
            .env("CALBENCH_SIMD", simd)
            .args([
                "run",
                &default_study,
                "--trials",
                "3",
                "--out",
                path_arg(&out),
            ])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    };
    let (scalar, best) = (
        run("scalar", "harness-simd-scalar"),
        run("auto", "harness-simd-auto"),
    );
    for f in ["summary.json", "trials.csv"] {
        let (a, b) = (
            std::fs::read(scalar.join(f)).unwrap(),
            std::fs::read(best.join(f)).unwrap(),
        );
        assert!(
            !a.is_empty() && a == b,
            "{f} differs between the SIMD paths"
        );
    }
    let bad = tmp_dir("harness-simd-bad");
    let o = crate::common::bin()
        .env("CALBENCH_SIMD", "avx512")
        .args([
            "run",
            &default_study,
            "--trials",
            "1",
            "--out",
            path_arg(&bad),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("CALBENCH_SIMD=\"avx512\"") && err.contains("\"scalar\""),
        "{err}"
    );
    assert!(!bad.join("summary.json").exists());
}
