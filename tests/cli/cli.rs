//! The file-level commands end to end: `simulate` reruns give the same bytes, and
//! `identify` on its output writes a compensated robot that every command loads.

use std::path::Path;

use crate::common::{
    bin, calbench, calbench_ok, load_json, path_arg, read, root, tmp_dir, ur10_example,
};

fn scenario() -> String {
    root().join("scenarios/ci-guard.toml").display().to_string()
}

#[test]
fn simulate_reruns_are_byte_identical() {
    let (a, b) = (tmp_dir("cli-sim-a"), tmp_dir("cli-sim-b"));
    for d in [&a, &b] {
        calbench_ok(&[
            "simulate",
            &scenario(),
            "--trial",
            "3",
            "--out",
            d.to_str().unwrap(),
        ]);
    }
    for f in ["measurements.csv", "validation.csv", "truth.json"] {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(!x.is_empty() && x == y, "{f} differs between reruns");
    }
    let truth = load_json(&a.join("truth.json"));
    assert_eq!(truth["outliers"].as_array().unwrap().len(), 2);
    assert_eq!(truth["sag_mm"].as_array().unwrap().len(), 40);
}

#[test]
fn identify_on_simulated_data_compensates_and_writes_a_loadable_robot() {
    let sim = tmp_dir("cli-id-sim");
    let out = tmp_dir("cli-id-out");
    calbench_ok(&["simulate", &scenario(), "--out", sim.to_str().unwrap()]);
    let o = calbench_ok(&[
        "identify",
        "--robot",
        "irb2600",
        "--data",
        sim.join("measurements.csv").to_str().unwrap(),
        "--method",
        "igg3",
        "--validate",
        sim.join("validation.csv").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("validation error"));
    let j = load_json(&out.join("identified.json"));
    let before = j["validation_before_mm"]["rms"].as_f64().unwrap();
    let after = j["validation_after_mm"]["rms"].as_f64().unwrap();
    assert!(after < 0.01 * before, "validation RMS {before} → {after}");
    let robot = out.join("robot.toml");
    let o = calbench_ok(&[
        "fk",
        "--robot",
        robot.to_str().unwrap(),
        "--q",
        "10,20,30,40,50,60",
        "--json",
    ]);
    let fk: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(fk["position_mm"].as_array().unwrap().len(), 3);
    let csv = std::fs::read_to_string(out.join("residuals.csv")).unwrap();
    assert_eq!(csv.lines().count(), 41);
}

#[test]
fn identify_takes_an_orientation_weight_for_full_pose_files_only() {
    let qiao = root().join("scenarios/qiao2021-tx60.toml");
    let (pose, pos) = (tmp_dir("cli-k-pose"), tmp_dir("cli-k-pos"));
    calbench_ok(&[
        "simulate",
        qiao.to_str().unwrap(),
        "--out",
        pose.to_str().unwrap(),
    ]);
    calbench_ok(&["simulate", &scenario(), "--out", pos.to_str().unwrap()]);
    let id = |sim: &Path, robot: &str, k: &str, out: &Path| {
        calbench(&[
            "identify",
            "--robot",
            robot,
            "--data",
            sim.join("measurements.csv").to_str().unwrap(),
            "--method",
            "lm",
            "--validate",
            sim.join("validation.csv").to_str().unwrap(),
            "--k",
            k,
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let o = id(&pose, "tx60-floor", "150", &tmp_dir("cli-k-out"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (sim, robot, k) in [(&pose, "tx60-floor", "0"), (&pos, "irb2600", "100")] {
        let o = id(sim, robot, k, &tmp_dir("cli-k-bad"));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains("--k"), "k = {k}: {err}");
    }
    // A weight whose squared rows overflow (the solve stopped, diverged, before its first
    // step and the nominal robot was written with exit status 0) is refused.
    let out = tmp_dir("cli-k-huge").join("o");
    let o = id(&pose, "tx60-floor", "1e308", &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(
            "setting `--k`: must be finite, positive and at most 1e6 mm per rad, got 1e308"
        ),
        "{err}"
    );
    assert!(!out.exists());
}

/// A file on which only joint 1 moves determines a handful of the parameters: every method
/// must say so (`rank-deficient`, or `singular` for plain least squares) instead of writing
/// a compensated robot as if converged, unless the user asks for the result anyway.
#[test]
fn identify_refuses_data_that_do_not_determine_the_parameters() {
    let robot = calbench::robot::builtin::irb2600();
    let truth = robot.with_errors(&[(calbench::robot::Param::A(1), 0.5)]);
    let qs: Vec<Vec<f64>> = (0..30)
        .map(|i| {
            let mut q = vec![0.3, -0.4, 0.5, 0.2, 0.6, 0.1];
            q[0] = -1.0 + 0.07 * i as f64;
            q
        })
        .collect();
    let dir = tmp_dir("cli-rank");
    let file = dir.join("joint1.csv");
    crate::common::write_points(&file, &robot, qs, |q| truth.fk(q).pos);
    for method in ["ls", "ridge", "igg3", "lm", "bas"] {
        let out = dir.join(method);
        let args = [
            "identify",
            "--robot",
            "irb2600",
            "--data",
            file.to_str().unwrap(),
            "--method",
            method,
            "--out",
            out.to_str().unwrap(),
        ];
        let o = calbench(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{method} accepted rank-deficient data");
        assert!(
            err.contains("joint1.csv") && err.contains("undetermined") && err.contains("theta2"),
            "{method}: {err}"
        );
        // The undetermined parameters, as `--fix` takes them, hold the rest determined.
        let fix = err
            .split("hold them with --fix ")
            .nth(1)
            .and_then(|t| t.split(", or pass").next());
        let fix = fix.unwrap_or_else(|| panic!("{method}: no --fix offered: {err}"));
        let held = dir.join(format!("{method}-held"));
        let args = ["identify", "--robot", "irb2600", "--data", path_arg(&file)];
        let o = calbench(
            &[
                &args[..],
                &["--method", method, "--fix", fix, "--out", path_arg(&held)],
            ]
            .concat(),
        );
        assert!(
            o.status.success(),
            "{method} --fix {fix}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(!out.exists(), "{method} wrote output");
    }
    let out = dir.join("allowed");
    calbench_ok(&[
        "identify",
        "--robot",
        "irb2600",
        "--data",
        file.to_str().unwrap(),
        "--method",
        "lm",
        "--allow-rank-deficient",
        "--out",
        out.to_str().unwrap(),
    ]);
    let j = load_json(&out.join("identified.json"));
    assert_eq!(j["termination"], "rank-deficient");
    // The page says so in plain words, and gives no σ without a covariance.
    let page = read(&out.join("report.html"));
    let warning = format!(
        "the data determine only {} of the {} parameters (rank deficiency",
        j["rank"],
        j["parameters"].as_array().unwrap().len()
    );
    assert!(page.contains(&warning), "{warning}");
    assert!(page.contains("No covariance"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Five poses give 15 position readings for the 24 parameters: no method can determine them,
/// so each refuses the data, naming the file and the number of poses needed, instead of
/// writing the nominal robot as an identification; `--allow-rank-deficient` writes it, its
/// termination `rank-deficient`.
#[test]
fn identify_refuses_fewer_readings_than_parameters() {
    let robot = calbench::robot::builtin::irb2600();
    let truth = robot.with_errors(&[(calbench::robot::Param::A(1), 0.5)]);
    let qs: Vec<Vec<f64>> = (0..5)
        .map(|i| {
            let t = 0.2 * i as f64;
            vec![t - 0.4, 0.3 - t, 0.1 + t, 0.5 - t, t, 0.2 * t]
        })
        .collect();
    let dir = tmp_dir("cli-few");
    let file = dir.join("five.csv");
    crate::common::write_points(&file, &robot, qs, |q| truth.fk(q).pos);
    let data = path_arg(&file);
    for method in ["ls", "ridge", "igg3", "lm"] {
        let out = dir.join(method);
        let args = [
            "identify", "--robot", "irb2600", "--data", data, "--method", method,
        ];
        let o = calbench(&[&args[..], &["--out", path_arg(&out)]].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{method}: {err}");
        assert!(
            err.contains("five.csv: data:")
                && err.contains(
                    "5 poses give 15 readings for 24 parameters: measure at least 9 poses"
                )
                && err.contains("--allow-rank-deficient"),
            "{method}: {err}"
        );
        assert!(!out.exists(), "{method} wrote output");
    }
    let out = dir.join("allowed");
    let args = [
        "identify", "--robot", "irb2600", "--data", data, "--method", "lm",
    ];
    calbench_ok(
        &[
            &args[..],
            &["--allow-rank-deficient", "--out", path_arg(&out)],
        ]
        .concat(),
    );
    let j = load_json(&out.join("identified.json"));
    assert_eq!(
        (&j["termination"], &j["rank"]),
        (&"rank-deficient".into(), &15.into())
    );
}

/// Eight poses of positions give 24 readings for the IRB2600's 24 parameters: refused before
/// any solve, as a kind file of as many readings as unknowns is; `ls` had matched every
/// reading and written `sigma0` null. A prior on one parameter, or
/// `--allow-rank-deficient`, writes it.
#[test]
fn identify_refuses_as_many_readings_as_parameters() {
    let robot = calbench::robot::builtin::irb2600();
    let truth = robot.with_errors(&[(calbench::robot::Param::A(1), 0.5)]);
    // Poses spread over the joints' ranges (rad), as no formula of one variable spreads them.
    let qs: Vec<Vec<f64>> = (0..8)
        .map(|i| {
            let joint = |j: usize| 1.2 * (1.7 * i as f64 + 2.3 * j as f64 + 0.5).sin();
            (0..6).map(joint).collect()
        })
        .collect();
    let dir = tmp_dir("cli-exact-count");
    let file = dir.join("eight.csv");
    crate::common::write_points(&file, &robot, qs, |q| truth.fk(q).pos);
    let prior = dir.join("prior.toml");
    std::fs::write(&prior, "a2 = 0.5\n").unwrap();
    let identify = |extra: &[&str], out: &str| {
        let args = ["identify", "--robot", "irb2600", "--data", path_arg(&file)];
        let out = dir.join(out);
        let o = calbench(
            &[
                &args[..],
                &["--method", "ls", "--out", path_arg(&out)],
                extra,
            ]
            .concat(),
        );
        (o, out)
    };
    let (o, out) = identify(&[], "refused");
    let err = String::from_utf8_lossy(&o.stderr);
    let want = "eight.csv: data: 8 poses give 24 readings for 24 parameters: a fit would match \
                every reading and leave none to check it, so nothing was written. Measure at \
                least 9 poses, or pass --allow-rank-deficient";
    assert!(
        !o.status.success() && err.contains(want) && !out.exists(),
        "{err}"
    );
    for (extra, name) in [
        (&["--prior", path_arg(&prior)][..], "prior"),
        (&["--allow-rank-deficient"][..], "allowed"),
    ] {
        let (o, out) = identify(extra, name);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(out.join("identified.json").exists());
    }
}

/// `identify --set KEY=VALUE` sets any option of the method (here the search box of BAS on
/// real data), refusing unknown keys by name; `identifiability --poses-file` analyses the
/// user's poses.
#[test]
fn identify_takes_method_options_and_identifiability_the_users_poses() {
    let dir = tmp_dir("cli-set");
    calbench_ok(&[
        "simulate",
        &scenario(),
        "--out",
        dir.join("sim").to_str().unwrap(),
    ]);
    let data = dir.join("sim/measurements.csv");
    let identify = |extra: &[&str], out: &str| {
        let mut args = vec![
            "identify",
            "--robot",
            "irb2600",
            "--data",
            data.to_str().unwrap(),
            "--method",
            "bas",
        ];
        args.extend_from_slice(extra);
        let out = dir.join(out);
        args.extend_from_slice(&["--out", out.to_str().unwrap()]);
        calbench(&args)
    };
    let o = identify(&["--set", "iterations=50", "--set", "bound_mm=4"], "ok");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j = load_json(&dir.join("ok/identified.json"));
    assert_eq!(j["iterations"], 50);
    let o = identify(&["--set", "iterationz=50"], "bad");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("iterationz"));
    // A key given twice is refused, as a scenario's duplicate key is: not the last one kept.
    let o = identify(
        &["--set", "iterations=50", "--set", "iterations=60"],
        "twice",
    );
    assert!(!o.status.success());
    assert_eq!(
        String::from_utf8_lossy(&o.stderr).trim(),
        "error: setting `--set iterations`: is given twice (50, then 60): one value per option"
    );
    assert!(!dir.join("twice").exists());
    let o = calbench_ok(&[
        "identifiability",
        "--robot",
        "irb2600",
        "--poses-file",
        data.to_str().unwrap(),
        "--json",
    ]);
    let a: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(a["rank"].as_u64().unwrap() > 10);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `identifiability --gcn-blocks --json` reports Guo 2024's separation of the joint
/// parameters (README, Commands): each block's GCN before and after, and what was removed;
/// its output is REPRODUCTION.md's committed `gcn_blocks.json`, byte for byte.
#[test]
fn identifiability_reports_gcn_blocks_of_the_separation() {
    let o = calbench_ok(&[
        "identifiability",
        "--robot",
        "guo-3t2r",
        "--measure",
        "position",
        "--gcn-blocks",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let blocks = a["blocks"].as_object().unwrap();
    for name in ["theta", "d", "a", "alpha", "beta"] {
        let after = blocks[name]["gcn_after"].as_f64().unwrap();
        assert!(after <= 1e2, "{name}: {after}");
    }
    assert!(!a["removed"].as_array().unwrap().is_empty());
    assert!(a["rank"].as_u64().is_some());
    let committed =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("results/reproduction/guo2024/gcn_blocks.json");
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        std::fs::read_to_string(&committed).unwrap(),
        "{} is not what identifiability --gcn-blocks --json writes",
        committed.display()
    );
    let o = calbench(&[
        "identifiability",
        "--robot",
        "guo-3t2r",
        "--gcn-blocks",
        "--gcn-threshold=-1",
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--gcn-threshold"));
}

/// Qiao 2021 fig. 7: `examples/qiao-fig7/run.sh` with two runs per model (BAS-PSO on each
/// pose-error model of one data set, brought into the base frame, Qiao's 24 parameters), then
/// one of its identifications again: the same `--seed` gives the same bytes, another seed
/// another identification of the same budget, each better than the nominal robot.
#[test]
fn identify_seed_repeats_a_random_search_on_one_data_set() {
    let out = tmp_dir("cli-fig7");
    let o = std::process::Command::new("bash")
        .arg(root().join("examples/qiao-fig7/run.sh"))
        .arg(&*out)
        .arg("2")
        .env("CALBENCH", env!("CARGO_BIN_EXE_calbench"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = String::from_utf8_lossy(&o.stdout);
    for model in ["differential", "coordinate_transfer", "direct_fk"] {
        assert!(table.contains(&format!("| {model} | 2 |")), "{table}");
    }
    let csv = read(&out.join("fig7.csv"));
    assert_eq!(csv.lines().count(), 7, "{csv}");
    for model in ["differential-1", "differential-2", "direct_fk-1"] {
        let j = load_json(&out.join(model).join("identified.json"));
        assert_eq!(j["parameters"].as_array().unwrap().len(), 24);
        let e = j["evaluations"].as_u64().unwrap();
        assert!((59000..=60000).contains(&e), "{e} evaluations for 60000");
        assert!(
            j["validation_after_mm"]["mean"].as_f64().unwrap()
                < j["validation_before_mm"]["mean"].as_f64().unwrap()
        );
    }
    // The script's differential run with seed 1, again by hand.
    let again = out.join("again");
    let params: Vec<String> = load_json(&out.join("differential-1/identified.json"))["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_str().unwrap().to_string())
        .collect();
    calbench_ok(&[
        "identify",
        "--robot",
        "tx60-floor",
        "--data",
        out.join("data/base-measurements.csv").to_str().unwrap(),
        "--validate",
        out.join("data/base-validation.csv").to_str().unwrap(),
        "--registration",
        "known",
        "--params",
        &params.join(","),
        "--method",
        "bas-pso",
        "--set",
        "max_evaluations=60000",
        "--set",
        "error_model=\"differential\"",
        "--seed",
        "1",
        "--out",
        again.to_str().unwrap(),
    ]);
    assert_eq!(
        read(&out.join("differential-1/identified.json")),
        read(&again.join("identified.json"))
    );
    let two = load_json(&out.join("differential-2/identified.json"));
    let by_hand = load_json(&again.join("identified.json"));
    assert_ne!(by_hand["errors"], two["errors"]);
    assert_eq!(by_hand["parameters"], serde_json::json!(params));
    // --params refuses a name given twice and a compliance, naming the option.
    for bad in ["a2,theta1,a2", "c2"] {
        let o = calbench(&[
            "identify",
            "--robot",
            "tx60-floor",
            "--data",
            out.join("data/base-measurements.csv").to_str().unwrap(),
            "--method",
            "lm",
            "--params",
            bad,
            "--out",
            out.join("refused").to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains("--params"), "{err}");
        if bad == "c2" {
            // The library's reason names the model and its option by type; the command line
            // spells that option as its flag.
            assert!(err.contains("the compliance model adds those"), "{err}");
            assert!(err.contains("(--compliance)"), "{err}");
        }
    }
}

/// A missing file is named once with the system's reason, not with the reason twice.
#[test]
fn a_missing_file_is_reported_once() {
    let missing = tmp_dir("cli-missing").join("nope.csv");
    let o = bin()
        .args(["identify", "--robot", "irb2600", "--data"])
        .arg(&missing)
        .args(["--method", "ls", "--out"])
        .arg(tmp_dir("cli-missing-out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("nope.csv"), "{err}");
    assert_eq!(err.matches("(os error").count(), 1, "{err}");
}

#[test]
fn fk_warns_naming_the_first_joint_outside_its_limits_in_the_robots_units() {
    // The warning said only that some value lay outside; the user had to find which.
    for (robot, q, joint) in [
        (
            "irb2600".to_string(),
            "10,-20,30,500,-50,-401",
            "joint 4 is 500 deg, outside its limits [-175, 175]",
        ),
        (
            "irb2600".to_string(),
            "10,-200,30,40,-50,60",
            "joint 2 is -200 deg, outside its limits [-95, 155]",
        ),
        (
            ur10_example("ur10.urdf"),
            "0,0,0,0,0,30",
            "joint 6 is 30 rad, outside its limits [-6.28318530718, 6.28318530718]",
        ),
    ] {
        let o = calbench_ok(&["fk", "--robot", &robot, "--q", q]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(&format!(
                "warning: the joint values lie outside the robot's joint limits: {joint}"
            )),
            "{robot} at {q}: {err}"
        );
    }
    let o = calbench_ok(&["fk", "--robot", "irb2600", "--q", "10,-20,30,40,-50,60"]);
    assert!(
        o.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn a_run_counts_its_trials_in_words() {
    let dir = tmp_dir("cli-one-trial");
    for (n, words) in [("1", "\n1 trial in "), ("2", "\n2 trials in ")] {
        let out = dir.join(n);
        let o = calbench_ok(&["run", &scenario(), "--trials", n, "--out", path_arg(&out)]);
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains(words), "{text}");
    }
}
