//! Identifications that make the robot worse are refused, naming the file and the cause, and
//! written with a warning under `--allow-worse`: a plane file whose `plane` column is all 1, a
//! multi-target file whose `x` column is all 0, a tracker's file with a column scaled; a gross
//! reading is named; and `--export toml,ur-yaml` writes both files. These results can also be
//! physically implausible (docs/formats.md "Physical plausibility"), so keeping them takes
//! `--allow-implausible` too.

use std::path::{Path, PathBuf};

use crate::common::{
    calbench, calbench_ok, load_json, path_arg, read, tmp_dir, ur10_example as ex, ur10_positions,
};

/// `simulate scenarios/instruments.toml --measure KIND` into `dir`: the measurement and
/// validation files.
fn simulated(dir: &Path, kind: &str) -> (PathBuf, PathBuf) {
    let out = dir.join(format!("sim-{kind}"));
    let sc = crate::common::root().join("scenarios/instruments.toml");
    calbench_ok(&[
        "simulate",
        path_arg(&sc),
        "--measure",
        kind,
        "--out",
        path_arg(&out),
    ]);
    (out.join("measurements.csv"), out.join("validation.csv"))
}

/// `src` with column `column` set to `value` (on row `row` only, 0-based, when given),
/// written to `dst`.
fn with_column(src: &Path, dst: &Path, column: &str, value: &str, row: Option<usize>) {
    let text = read(src);
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let k = header.split(',').position(|c| c == column).unwrap();
    let mut out = format!("{header}\n");
    for (i, line) in lines.enumerate() {
        let mut cells: Vec<&str> = line.split(',').collect();
        if row.is_none_or(|r| r == i) {
            cells[k] = value;
        }
        out += &(cells.join(",") + "\n");
    }
    std::fs::write(dst, out).unwrap();
}

/// `identify --robot irb2600 --data DATA --validate VAL EXTRA… --out OUT` (EXTRA without
/// `--method`: `--method lm`).
fn identify(data: &Path, val: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "identify",
        "--robot",
        "irb2600",
        "--data",
        path_arg(data),
        "--validate",
        path_arg(val),
        "--out",
        path_arg(out),
    ];
    args.extend_from_slice(extra);
    if !extra.contains(&"--method") {
        args.extend_from_slice(&["--method", "lm"]);
    }
    calbench(&args)
}

/// An `identify --allow-worse` that succeeded with the warning on stderr: its
/// `OUT/identified.json`.
fn written_with_warning(o: &std::process::Output, out: &Path) -> serde_json::Value {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("warning: the identification makes the robot worse"),
        "{err}"
    );
    load_json(&out.join("identified.json"))
}

/// Each bad file: refused (exit non-zero, nothing written) at the validation file, whose
/// figure is the one worse, naming the file identified on (it had been refused at the data
/// file, naming the validation only as `the validation RMS`); with `--allow-worse` written,
/// the warning on stderr and the causes in identified.json's `allowed_worse`. The untouched
/// file passes as before.
#[test]
fn a_worse_robot_is_refused_unless_allowed() {
    let d = tmp_dir("cli-worse");
    let (plane, plane_val) = simulated(&d, "plane");
    let (targets, targets_val) = simulated(&d, "multi-target");
    let plane1 = d.join("plane1.csv");
    with_column(&plane, &plane1, "plane", "1", None);
    let x0 = d.join("x0.csv");
    with_column(&targets, &x0, "x", "0", None);
    for (bad, val) in [(&plane1, &plane_val), (&x0, &targets_val)] {
        let out = d.join("refused");
        let o = identify(bad, val, &out, &[]);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(!o.status.success(), "{err}");
        let (b, v) = (bad.display(), val.display());
        let at = format!("error: {v}: data: the identification on {b} makes the robot worse");
        assert!(err.starts_with(&at), "{err}");
        assert!(err.contains(": the validation RMS is "), "{err}");
        assert!(err.contains(&format!("Check the readings of {b} and {v} (")));
        assert!(err.contains("--allow-worse"), "{err}");
        assert!(!out.exists(), "nothing is written");
        let kept = d.join("kept");
        let j = written_with_warning(
            &identify(bad, val, &kept, &["--allow-worse", "--allow-implausible"]),
            &kept,
        );
        let causes = j["allowed_worse"].as_array().unwrap();
        assert!(
            causes[0].as_str().unwrap().contains("validation RMS"),
            "{causes:?}"
        );
        let after = j["validation_after_mm"]["rms"].as_f64().unwrap();
        let before = j["validation_before_mm"]["rms"].as_f64().unwrap();
        assert!(after > 10.0 * before, "{after} {before}");
        std::fs::remove_dir_all(&kept).unwrap();
    }
    for (good, val) in [(&plane, &plane_val), (&targets, &targets_val)] {
        let out = d.join("good");
        let o = identify(good, val, &out, &[]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(load_json(&out.join("identified.json"))
            .get("allowed_worse")
            .is_none());
        std::fs::remove_dir_all(&out).unwrap();
    }
}

/// One reading of 999999 in a sphere or multi-target file (the third target of the second
/// pose): refused, naming the reading's place as the likely cause, never with "rank N of N".
#[test]
fn a_gross_reading_is_named() {
    let d = tmp_dir("cli-gross");
    let places = [
        ("sphere", "offset_mm", "the reading of line 7"),
        (
            "multi-target",
            "x",
            "target 3 of the pose that starts on line 5",
        ),
    ];
    for (kind, column, place) in places {
        let (data, val) = simulated(&d, kind);
        let bad = d.join(format!("{kind}-gross.csv"));
        with_column(&data, &bad, column, "999999", Some(5));
        for method in ["ls", "lm"] {
            let out = d.join("out");
            let o = identify(&bad, &val, &out, &["--method", method]);
            let err = String::from_utf8_lossy(&o.stderr).to_string();
            assert!(!o.status.success(), "{kind} {method}: {err}");
            assert!(!out.exists());
            assert!(err.contains(place), "{kind} {method}: {err}");
            assert!(err.contains("gross reading"), "{kind} {method}: {err}");
            let words: Vec<&str> = err.split_whitespace().collect();
            for w in words.windows(4) {
                let same = w[0] == "(rank" && w[2] == "of" && w[1] == w[3].trim_end_matches(')');
                assert!(!same, "{kind} {method}: {err}");
            }
        }
    }
}

/// A tracker's reading moved by 300 mm (row 20 of the data, 0-based, on line 22) is named by
/// its line of the data file under `--holdout`, where it had been named by its place among
/// the calibration rows (`point 14`); so is one moved by 900 m, which leaves the solve
/// singular.
#[test]
fn a_gross_tracker_reading_is_named_by_its_line_of_the_file() {
    let d = tmp_dir("cli-gross-tracker");
    let pos = ur10_positions(&d);
    let text = read(&pos);
    for (moved, said) in [(300.0, "has a residual"), (9e5, "lies")] {
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        let mut cells: Vec<String> = lines[21].split(',').map(str::to_string).collect();
        cells[7] = (cells[7].parse::<f64>().unwrap() + moved).to_string();
        lines[21] = cells.join(",");
        let bad = d.join("gross.csv");
        std::fs::write(&bad, lines.join("\n") + "\n").unwrap();
        for split in [&["--holdout", "3/10"][..], &["--holdout", "1/4"][..]] {
            let out = d.join("out");
            let mut args = vec!["identify", "--robot"];
            let (robot, data) = (ex("ur10.toml"), path_arg(&bad).to_string());
            args.extend([robot.as_str(), "--data", &data, "--method", "ls"]);
            args.extend(split);
            args.extend(["--out", path_arg(&out)]);
            let o = calbench(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(!o.status.success() && !out.exists(), "{split:?}: {err}");
            let row = format!("the point on line 22 of {} {said}", bad.display());
            assert!(err.contains(&row), "{moved} {split:?}: {err}");
        }
    }
}

/// A tracker's file whose `y` column is scaled by 0.9 about its mean: validated on the
/// untouched rows the robot comes out worse, so it is refused at the validation file, naming
/// the data file; with `--allow-worse` the warning is on stderr, in identified.json and in
/// both reports. (Scaled about the tracker's origin, the column also moves the rows by 300 mm
/// as a whole, and the two files are refused before any identification as not lying in one
/// frame.) A search cut short that leaves both the validation and the calibration figures
/// worse is refused at the data file, naming both files' readings.
#[test]
fn a_worse_robot_from_a_tracker_file_is_refused_unless_allowed() {
    let d = tmp_dir("cli-worse-tracker");
    let pos = ur10_positions(&d);
    let text = read(&pos);
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let y = |line: &str| line.split(',').nth(7).unwrap().parse::<f64>().unwrap();
    let rows: Vec<&str> = lines.collect();
    let mean = rows.iter().map(|l| y(l)).sum::<f64>() / rows.len() as f64;
    let (mut cal, mut bad, mut val) = (header.clone(), header.clone(), header.clone());
    let mut moved = header;
    for (i, line) in rows.into_iter().enumerate() {
        if i % 10 >= 7 {
            val += &format!("\n{line}");
            continue;
        }
        cal += &format!("\n{line}");
        let mut c: Vec<String> = line.split(',').map(String::from).collect();
        c[7] = format!("{}", mean + 0.9 * (y(line) - mean));
        bad += &format!("\n{}", c.join(","));
        c[7] = format!("{}", 0.9 * y(line));
        moved += &format!("\n{}", c.join(","));
    }
    for (name, text) in [
        ("cal.csv", &cal),
        ("bad.csv", &bad),
        ("val.csv", &val),
        ("moved.csv", &moved),
    ] {
        std::fs::write(d.join(name), format!("{text}\n")).unwrap();
    }
    let robot = ex("ur10.toml");
    let run = |data: &str, out: &Path, extra: &[&str]| {
        let (data, val) = (d.join(data), d.join("val.csv"));
        let mut args = vec!["identify", "--robot", &robot, "--data", path_arg(&data)];
        args.extend_from_slice(&["--validate", path_arg(&val), "--out", path_arg(out)]);
        if !extra.contains(&"--method") {
            args.extend_from_slice(&["--method", "lm"]);
        }
        args.extend_from_slice(extra);
        calbench(&args)
    };
    let o = run("moved.csv", &d.join("refused"), &["--allow-worse"]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        err.contains("setting `--validate`: the nominal robot misses the validation points")
            && err.contains("do not lie in one frame"),
        "{err}"
    );
    assert!(!d.join("refused").exists());
    let o = run("bad.csv", &d.join("refused"), &[]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(!o.status.success(), "{err}");
    let [bad, val, cal] =
        ["bad.csv", "val.csv", "cal.csv"].map(|f| d.join(f).display().to_string());
    let at = format!("error: {val}: data: the identification on {bad} makes the robot worse: ");
    assert!(
        err.starts_with(&format!("{at}the validation RMS is ")),
        "{err}"
    );
    assert!(err.contains(&format!("Check the readings of {bad} and {val} (")));
    assert!(!d.join("refused").exists());
    let search = [
        "--set",
        "max_evaluations=80",
        "--set",
        "bound_mm=20",
        "--seed",
        "1",
    ];
    let o = run(
        "cal.csv",
        &d.join("refused"),
        &[&["--method", "pso"][..], &search].concat(),
    );
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    let at = format!("error: {cal}: data: the identification makes the robot worse: ");
    assert!(
        err.starts_with(&format!("{at}the validation RMS is ")),
        "{err}"
    );
    assert!(
        err.contains("; the RMS residual on the calibration readings is "),
        "{err}"
    );
    assert!(err.contains(&format!("Check the readings of {cal} and {val} (")));
    assert!(!d.join("refused").exists());
    let kept = d.join("kept");
    let j = written_with_warning(
        &run("bad.csv", &kept, &["--allow-worse", "--allow-implausible"]),
        &kept,
    );
    assert!(j["allowed_worse"][0]
        .as_str()
        .unwrap()
        .contains("validation RMS"));
    for report in ["report.md", "report.html"] {
        assert!(
            read(&kept.join(report)).contains("makes the robot worse"),
            "{report}"
        );
    }
    let good = d.join("good");
    let o = run("cal.csv", &good, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(load_json(&good.join("identified.json"))
        .get("allowed_worse")
        .is_none());
}

/// `--export toml,ur-yaml` writes robot.toml and ur-kinematics.yaml (it wrote no YAML), and
/// the YAML is the one `--export ur-yaml` writes.
#[test]
fn export_toml_and_ur_yaml_writes_both() {
    let d = tmp_dir("cli-export-both");
    let pos = ur10_positions(&d);
    let run = |export: &str| {
        let out = d.join(export.replace(',', "-"));
        let robot = ex("ur10.toml");
        calbench_ok(&[
            "identify",
            "--robot",
            &robot,
            "--data",
            path_arg(&pos),
            "--method",
            "lm",
            "--export",
            export,
            "--out",
            path_arg(&out),
        ]);
        out
    };
    let both = run("toml,ur-yaml");
    let yaml = run("ur-yaml");
    assert!(both.join("robot.toml").is_file());
    assert_eq!(
        read(&both.join("ur-kinematics.yaml")),
        read(&yaml.join("ur-kinematics.yaml"))
    );
    assert_eq!(
        read(&both.join("robot.toml")),
        read(&yaml.join("robot.toml"))
    );
}

/// A tracker reading moved by 20 mm (line 22) is kept by `ls`, which the fit does not make
/// worse: the result is written with a warning naming the reading's line, on stderr and in
/// `report.md`; `igg3` rejects the reading, and warns of nothing. A distance file with a
/// reading 50 mm long is written by `lm` with the same warning, naming its line.
#[test]
fn a_gross_reading_the_fit_keeps_is_warned_of() {
    let d = tmp_dir("cli-gross-kept");
    let pos = ur10_positions(&d);
    let text = read(&pos);
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut cells: Vec<String> = lines[21].split(',').map(str::to_string).collect();
    cells[7] = (cells[7].parse::<f64>().unwrap() + 20.0).to_string();
    lines[21] = cells.join(",");
    let bad = d.join("gross.csv");
    std::fs::write(&bad, lines.join("\n") + "\n").unwrap();
    let said = format!(
        "warning: the point on line 22 of {} has a residual of ",
        bad.display()
    );
    for (method, warned) in [("ls", true), ("igg3", false)] {
        let out = d.join(format!("out-{method}"));
        let robot = ex("ur10.toml");
        let args = ["identify", "--robot", &robot, "--data", path_arg(&bad)];
        let o = calbench(&[&args[..], &["--method", method, "--out", path_arg(&out)]].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{method}: {err}");
        assert_eq!(err.contains(&said), warned, "{method}: {err}");
        if warned {
            assert!(err.contains("and the fit kept it"), "{err}");
            let report = read(&out.join("report.md"));
            assert!(
                report.contains("## Warnings") && report.contains("line 22 of"),
                "{report}"
            );
        }
    }
    // The distance file's line 12 (its 11th length from the pivot) read 50 mm longer.
    let (dist, _) = simulated(&d, "distance");
    let text = read(&dist);
    let header = text.lines().next().unwrap();
    let k = header.split(',').position(|c| c.ends_with("_mm")).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut cells: Vec<String> = lines[11].split(',').map(str::to_string).collect();
    cells[k] = (cells[k].parse::<f64>().unwrap() + 50.0).to_string();
    lines[11] = cells.join(",");
    let bad = d.join("gross-distance.csv");
    std::fs::write(&bad, lines.join("\n") + "\n").unwrap();
    let out = d.join("out-distance");
    let args = ["identify", "--robot", "irb2600", "--data", path_arg(&bad)];
    let o = calbench(&[&args[..], &["--method", "lm", "--out", path_arg(&out)]].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("warning: the reading of line 12 has a residual of "),
        "{err}"
    );
}

/// A tracker reading 50 mm off among 30, which `ls` spreads over the rest (its residual after
/// calibration a few times the median, too few to stand out, and the error before
/// calibration is the arm's own, as large): the distance of its point from the fit of the
/// other readings names it, and the result is written with the warning; `igg3` rejects the
/// reading and warns of nothing, and the clean file warns of nothing. It had been written
/// with no word.
#[test]
fn a_gross_reading_the_fit_spreads_is_warned_of() {
    let d = tmp_dir("cli-gross-spread");
    // The CI guard's arm without its two injected outliers (0.5 to 1 mm, themselves gross
    // readings against its 15 µm noise).
    let scenario = d.join("no-outliers.toml");
    let guard = read(&crate::common::root().join("scenarios/ci-guard.toml"));
    let no_outliers = guard.replace("[outliers]\ncount = 2\n", "[outliers]\ncount = 0\n");
    assert_ne!(guard, no_outliers);
    std::fs::write(&scenario, no_outliers).unwrap();
    let sim = d.join("sim");
    calbench_ok(&["simulate", path_arg(&scenario), "--out", path_arg(&sim)]);
    let text = read(&sim.join("measurements.csv"));
    let mut lines: Vec<String> = text.lines().take(31).map(str::to_string).collect();
    let clean = d.join("clean.csv");
    std::fs::write(&clean, lines.join("\n") + "\n").unwrap();
    let mut cells: Vec<String> = lines[15].split(',').map(str::to_string).collect();
    cells[6] = (cells[6].parse::<f64>().unwrap() + 50.0).to_string();
    lines[15] = cells.join(",");
    let bad = d.join("gross.csv");
    std::fs::write(&bad, lines.join("\n") + "\n").unwrap();
    let identify = |file: &Path, method: &str| {
        let out = d.join(format!(
            "out-{method}-{}",
            file.file_stem().unwrap().to_string_lossy()
        ));
        let args = ["identify", "--robot", "irb2600", "--data", path_arg(file)];
        let o = calbench(&[&args[..], &["--method", method, "--out", path_arg(&out)]].concat());
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(o.status.success(), "{method}: {err}");
        (err, out)
    };
    // docs/formats.md § 8.5 gives this warning and the 9.8 times of the residual after.
    let said = format!(
        "warning: the point on line 16 of {} lies 49.961 mm from the fit of the other \
         readings, 332 times the median residual of that fit, and the fit kept it: one gross \
         reading pulls a least-squares fit towards it. Check that reading and leave it out, or \
         identify with a robust method (igg3), which rejects it\n",
        bad.display()
    );
    let (err, out) = identify(&bad, "ls");
    assert!(err.contains(&said), "{err}");
    let residuals = read(&out.join("residuals.csv"));
    let mut after: Vec<f64> = residuals
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
        .collect();
    let gross = after[14];
    after.sort_by(f64::total_cmp);
    let ratio = gross / after[after.len() / 2];
    assert!((9.75..9.85).contains(&ratio), "{ratio}");
    assert!(read(&out.join("report.md")).contains("line 16 of"));
    for (file, method) in [(&bad, "igg3"), (&clean, "ls"), (&clean, "lm")] {
        let (err, _) = identify(file, method);
        assert!(
            !err.contains("warning"),
            "{method} {}: {err}",
            file.display()
        );
    }
}

/// A search's box of 1e20 mm, its worse and implausible result kept: the robot identified
/// has lengths no robot file holds, and is refused naming the value's place; it had been
/// written as a `robot.toml` that `fk` then refused.
#[test]
fn a_robot_no_robot_file_holds_is_not_written() {
    let d = tmp_dir("cli-unwritable-robot");
    let data = crate::plausible::simulated(&d, "scenarios/ci-guard.toml", None);
    let out = d.join("out");
    let o = calbench(&[
        "identify",
        "--robot",
        "irb2600",
        "--data",
        path_arg(&data),
        "--method",
        "bas-pso",
        "--set",
        "bound_mm=1e20",
        "--allow-worse",
        "--allow-implausible",
        "--out",
        path_arg(&out),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    let want = "data: bas-pso identified a robot that no robot file holds (joint ";
    assert!(!o.status.success() && err.contains(want), "{err}");
    assert!(
        err.contains("must be a finite length within ±1000000 mm") && !out.exists(),
        "{err}"
    );
}

/// The UR10 sample with its standard deviations (`sigma_mm`): `ls` and `lm` weigh its points
/// by 1/σ² and reweigh none, yet `report.md` had called 135 of its 199 points "weighed down
/// as suspect" (their prior weights, normalised to mean 1, are below 1). A point is weighed
/// down only below its prior weight: `igg3`, which reweighs, may still say so, and then of
/// fewer points than the prior weights below 1; so does its list of the points it weighed
/// down.
#[test]
fn prior_weights_are_not_called_suspect() {
    let d = tmp_dir("cli-prior-weights");
    ur10_positions(&d);
    let all = d.join("all.csv");
    let below_one = read(&all)
        .lines()
        .skip(1)
        .filter_map(|l| l.rsplit(',').next()?.parse::<f64>().ok())
        .collect::<Vec<_>>();
    let mean_w = below_one.iter().map(|s| 1.0 / (s * s)).sum::<f64>() / below_one.len() as f64;
    let priors_below_one = below_one
        .iter()
        .filter(|s| 1.0 / (*s * *s) / mean_w < 1.0)
        .count();
    assert!(priors_below_one > 100, "{priors_below_one}");
    for method in ["ls", "lm", "igg3"] {
        let out = d.join(method);
        calbench_ok(&[
            "identify",
            "--robot",
            &ex("ur10.toml"),
            "--data",
            path_arg(&all),
            "--method",
            method,
            "--k",
            "100",
            "--out",
            path_arg(&out),
        ]);
        let report = read(&out.join("report.md"));
        let said = report
            .lines()
            .find(|l| l.contains("weighed down"))
            .map(str::to_string);
        match (method, said) {
            ("igg3", Some(l)) => {
                let n: usize = l.split_whitespace().find_map(|w| w.parse().ok()).unwrap();
                assert!(n < priors_below_one, "{l}");
            }
            ("igg3", None) => {}
            (_, said) => assert_eq!(said, None, "{method}"),
        }
        // IGG3's list of the points it weighed down: its rejections, and fewer than the
        // prior weights below 1.
        if method == "igg3" {
            let list = report
                .lines()
                .find_map(|l| l.strip_prefix("Points weighed below their weight before the fit"))
                .unwrap();
            let listed = list.matches(" (").count() - 2;
            assert!(list.contains(" (0)") && listed < priors_below_one, "{list}");
        }
    }
}
