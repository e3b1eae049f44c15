//! Refusals of bad input files as a user meets them: the binary run on temporary files, and
//! the message naming the file, the line where there is one, and the key or column.
//!
//! - a robot file with a value out of range, refused by every command that loads it;
//! - a measurement CSV of too few distinct poses, refused by `identify` before any solve;
//! - a CSV value that overflows, in the file or after the conversion to internal units;
//! - a scenario region no pose reaches, refused when the scenario is loaded, at once;
//! - `check` on a summary without results, saying what is missing.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::common::{calbench, path_arg as path, refused};

/// A fresh folder for one test.
fn tmp(name: &str) -> crate::common::TmpDir {
    crate::common::tmp_dir(&format!("refusals-{name}"))
}

/// The built-in TX60 as a robot file, with `edit` applied to the text.
fn tx60_file(dir: &Path, name: &str, edit: impl Fn(&str) -> String) -> PathBuf {
    let o = calbench(&["robots", "tx60"]);
    assert!(o.status.success());
    let text = String::from_utf8(o.stdout).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, edit(&text)).unwrap();
    p
}

/// `text` with the `n`-th (1-based) line that starts with `key = ` replaced by `line`, and
/// the number of that line.
fn replace_nth(text: &str, key: &str, n: usize, line: &str) -> (String, usize) {
    let mut seen = 0;
    let mut at = 0;
    let lines: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if l.starts_with(&format!("{key} = ")) {
                seen += 1;
                if seen == n {
                    at = i + 1;
                    return line.to_string();
                }
            }
            l.to_string()
        })
        .collect();
    assert!(at > 0, "no {n}th `{key}` in the text");
    (lines.join("\n") + "\n", at)
}

/// A small position-measuring scenario of the TX60 (its robot given by `robot`), written
/// into `dir`.
fn scenario(dir: &Path, name: &str, robot: &str, extra: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(
        &p,
        format!(
            "name = \"refusal\"\nseed = 3\ntrials = 2\n\n[robot]\n{robot}\n\n\
             [calibration]\ncount = 12\n\n[validation]\ncount = 6\n{extra}\n\
             [[methods]]\nname = \"ls\"\n"
        ),
    )
    .unwrap();
    p
}

/// The calibration measurement of trial 0 of a TX60 scenario: (header, data rows).
fn measurement(dir: &Path) -> (String, Vec<String>) {
    let sc = scenario(dir, "sim.toml", "builtin = \"tx60\"", "");
    let out = dir.join("sim");
    let o = calbench(&["simulate", path(&sc), "--out", path(&out)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("measurements.csv")).unwrap();
    let mut lines = text.lines().map(str::to_string);
    let header = lines.next().unwrap();
    (header, lines.collect())
}

#[test]
fn a_robot_value_out_of_range_is_refused_by_every_command_naming_file_line_and_key() {
    let d = tmp("robot");
    // The TX60 in metres with a2 = 1e308 m, infinite in mm; and α2 = 400°.
    let (metres, a_line) = {
        let t = tx60_file(&d, "m.toml", |t| {
            t.replace("length_unit = \"mm\"", "length_unit = \"m\"")
        });
        let text = std::fs::read_to_string(t).unwrap();
        replace_nth(&text, "a", 2, "a = 1e308")
    };
    let huge = d.join("huge.toml");
    std::fs::write(&huge, metres).unwrap();
    let (twisted, alpha_line) = {
        let text = String::from_utf8(calbench(&["robots", "tx60"]).stdout).unwrap();
        replace_nth(&text, "alpha", 2, "alpha = 400")
    };
    let bent = d.join("bent.toml");
    std::fs::write(&bent, twisted).unwrap();
    let (csv_header, rows) = measurement(&d);
    let data = d.join("data.csv");
    std::fs::write(&data, format!("{csv_header}\n{}\n", rows.join("\n"))).unwrap();

    for (file, line, key) in [
        (&huge, a_line, "joint 2 (joints[1]), key `a`"),
        (&bent, alpha_line, "joint 2 (joints[1]), key `alpha`"),
    ] {
        let name = file.file_name().unwrap().to_str().unwrap();
        let place = format!("{name}: line {line}, {key}: ");
        let words = [place.as_str(), "must be a finite"];
        refused(
            &calbench(&["identifiability", "--robot", path(file)]),
            &words,
        );
        refused(
            &calbench(&["fk", "--robot", path(file), "--q", "0,0,0,0,0,0"]),
            &words,
        );
        let out = d.join(format!("out-{name}"));
        refused(
            &calbench(&[
                "identify",
                "--robot",
                path(file),
                "--data",
                path(&data),
                "--method",
                "ls",
                "--out",
                path(&out),
            ]),
            &words,
        );
        assert!(!out.exists());
        let sc = scenario(&d, &format!("sc-{name}"), &format!("file = \"{name}\""), "");
        let out = d.join(format!("run-{name}"));
        refused(&calbench(&["run", path(&sc), "--out", path(&out)]), &words);
        assert!(!out.exists());
    }
}

#[test]
fn a_measurement_of_too_few_distinct_poses_is_refused_before_any_solve() {
    let d = tmp("poses");
    let (header, rows) = measurement(&d);
    let identify = |name: &str, body: &[&String]| {
        let data = d.join(name);
        let text: Vec<&str> = body.iter().map(|s| s.as_str()).collect();
        std::fs::write(&data, format!("{header}\n{}\n", text.join("\n"))).unwrap();
        let out = d.join(format!("out-{name}"));
        let t = Instant::now();
        let o = calbench(&[
            "identify",
            "--robot",
            "tx60",
            "--data",
            path(&data),
            "--method",
            "lm",
            "--out",
            path(&out),
        ]);
        assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
        assert!(!out.exists());
        o
    };
    // Every row the same pose (lines 2 to 31).
    let same: Vec<&String> = std::iter::repeat_n(&rows[0], 30).collect();
    let e = refused(
        &identify("same.csv", &same),
        &[
            "same.csv: line 2: ",
            "all 30 rows (lines 2 to 31) are the same pose",
            "at least 3 distinct poses",
        ],
    );
    assert!(e.contains("q1…q6"), "{e}");
    // Two poses, alternating.
    let two: Vec<&String> = (0..20).map(|i| &rows[i % 2]).collect();
    refused(
        &identify("two.csv", &two),
        &[
            "two.csv: line 2: ",
            "hold only 2 distinct poses, first seen on lines 2 and 3",
        ],
    );
}

#[test]
fn a_csv_value_that_overflows_is_refused_naming_file_line_and_column() {
    let d = tmp("overflow");
    let (header, rows) = measurement(&d);
    let columns: Vec<&str> = header.split(',').collect();
    let x = columns.iter().position(|c| *c == "x").unwrap();
    let with = |column: usize, value: &str| {
        let mut r: Vec<String> = rows[4].split(',').map(str::to_string).collect();
        r[column] = value.to_string();
        let mut body = rows.clone();
        body[4] = r.join(",");
        format!("{header}\n{}\n", body.join("\n"))
    };
    let identify = |name: &str, text: String| {
        let data = d.join(name);
        std::fs::write(&data, text).unwrap();
        calbench(&[
            "identify",
            "--robot",
            "tx60",
            "--data",
            path(&data),
            "--method",
            "ls",
            "--out",
            path(&d.join("out")),
        ])
    };
    // Row 5 of the data is line 6.
    refused(
        &identify("inf.csv", with(x, "1e400")),
        &["inf.csv: line 6, column x: ", "not a finite number"],
    );
    refused(
        &identify("far.csv", with(x, "1e308")),
        &["far.csv: line 6, column x: ", "out of range", "1 km"],
    );
    refused(
        &identify("q.csv", with(0, "1e400")),
        &["q.csv: line 6, column q1: "],
    );
    // Finite in metres, infinite in mm: a prismatic joint's travel.
    let prismatic = tx60_file(&d, "slide.toml", |t| {
        let t = t.replace("length_unit = \"mm\"", "length_unit = \"m\"");
        let (t, _) = replace_nth(&t, "type", 3, "type = \"prismatic\"");
        let (t, _) = replace_nth(&t, "limits", 3, "limits = [0.0, 0.5]");
        t
    });
    let slide = d.join("slide.csv");
    let mut text = String::from("q1,q2,q3,q4,q5,q6,x,y,z\n");
    for i in 0..4 {
        text += &format!("{i},0,0.1,0,0,0,1,2,3\n");
    }
    text += "0,0,1e306,0,0,0,1,2,3\n";
    std::fs::write(&slide, text).unwrap();
    refused(
        &calbench(&[
            "identify",
            "--robot",
            path(&prismatic),
            "--data",
            path(&slide),
            "--method",
            "ls",
            "--out",
            path(&d.join("out")),
        ]),
        &["slide.csv: line 6, column q3: ", "overflows"],
    );
}

#[test]
fn a_scenario_region_no_pose_reaches_is_refused_at_once_naming_file_line_and_key() {
    let d = tmp("region");
    let far = "region = { kind = \"box\", center_mm = [5000.0, 0.0, 500.0], size_mm = [100.0, 100.0, 100.0] }";
    let tiny = "region = { kind = \"box\", center_mm = [300.0, 0.0, 300.0], size_mm = [0.01, 0.01, 0.01] }";
    for (name, extra, key, why) in [
        (
            "far.toml",
            format!("{far}\n"),
            "calibration.region",
            "no tool point is farther",
        ),
        (
            "tiny.toml",
            format!("\n[validation]\ncount = 6\n{tiny}\n"),
            "validation.region",
            "not one of 200000 random joint configurations",
        ),
    ] {
        let text = format!(
            "name = \"refusal\"\nseed = 3\ntrials = 2\n\n[robot]\nbuiltin = \"tx60\"\n\n\
             [calibration]\ncount = 12\n{extra}\n[[methods]]\nname = \"ls\"\n"
        );
        let line = text.lines().position(|l| l.starts_with("region")).unwrap() + 1;
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        let out = d.join(format!("out-{name}"));
        let place = format!("{name}: line {line}, {key}: ");
        let t = Instant::now();
        let o = calbench(&["run", path(&p), "--out", path(&out)]);
        assert!(t.elapsed() < Duration::from_secs(10), "{:?}", t.elapsed());
        let e = refused(&o, &[place.as_str(), "out of reach", why]);
        assert!(o.stdout.is_empty(), "a run started: {e}");
        assert!(!out.exists());
        refused(
            &calbench(&["simulate", path(&p), "--out", path(&out)]),
            &[place.as_str()],
        );
    }
}

/// A SCARA cannot tilt its tool: a workspace region that asks for another tool axis than the
/// one it keeps, or for a cone about it, is refused for that cause, with the axis it keeps; the
/// region along that axis with no cone is run. The refusal had named the search's start.
#[test]
fn a_workspace_region_a_scara_cannot_tilt_to_is_refused_for_that_cause() {
    let d = tmp("scara-tilt");
    std::fs::write(d.join("scara.toml"), crate::readmit::scara()).unwrap();
    let scenario = |axis: &str, cone: f64| {
        let region = format!(
            "region = {{ kind = \"workspace\", center_mm = [416.0, 485.0, 230.0], size_mm = \
             [100.0, 100.0, 50.0], axis = {axis}, cone_deg = {cone:?}, start = [30.0, 40.0, \
             100.0, 0.0] }}"
        );
        let text = format!(
            "name = \"tilt\"\nseed = 3\ntrials = 1\n\n[robot]\nfile = \"scara.toml\"\n\n\
             [calibration]\ncount = 12\n{region}\n\n[[methods]]\nname = \"ls\"\n"
        );
        let p = d.join(format!("tilt-{cone}-{}.toml", axis.len()));
        std::fs::write(&p, text).unwrap();
        p
    };
    let down = "[0.0, 0.0, -1.0]";
    for (p, why) in [
        (scenario(down, 10.0), "drawn within 10° of [0.0, 0.0, -1.0]"),
        (
            scenario("[0.0, 0.0, 1.0]", 0.0),
            "180.0° from the region's axis",
        ),
    ] {
        let out = d.join("out");
        let o = calbench(&["simulate", path(&p), "--out", path(&out)]);
        refused(
            &o,
            &[
                "line 10, calibration.region: ",
                "robot \"scara\" cannot tilt its tool: its flange z axis is along [0, 0, -1]",
                why,
                "takes axis = [0, 0, -1] and cone_deg = 0",
            ],
        );
        assert!(!out.exists());
    }
    let out = d.join("along");
    let o = calbench(&["simulate", path(&scenario(down, 0.0)), "--out", path(&out)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Found by the scenario fuzzer: a workspace box of 1.8e308 mm hung the loading (the inverse
/// kinematics met an overflowing target). Boxes are bounded at 1 km and refused at once.
#[test]
fn a_region_box_beyond_a_kilometre_is_refused_at_once() {
    let d = tmp("huge-box");
    for (i, region) in [
        "{ kind = \"workspace\", center_mm = [1200.0, 0.0, 900.0], size_mm = [1.7976931348623157e308, 1000.0, 800.0], axis = [1.0, 0.0, 0.0], cone_deg = 30.0 }",
        "{ kind = \"box\", center_mm = [2e6, 0.0, 900.0], size_mm = [100.0, 100.0, 100.0] }",
    ]
    .iter()
    .enumerate()
    {
        let text = format!(
            "name = \"huge\"\nseed = 3\ntrials = 2\n\n[robot]\nbuiltin = \"irb2600\"\n\n\
             [calibration]\ncount = 12\n\n[validation]\ncount = 6\nregion = {region}\n\n\
             [[methods]]\nname = \"ls\"\n"
        );
        let p = d.join(format!("huge{i}.toml"));
        std::fs::write(&p, text).unwrap();
        let t = Instant::now();
        let o = calbench(&["run", path(&p), "--out", path(&d.join(format!("out{i}")))]);
        assert!(t.elapsed() < Duration::from_secs(10), "{:?}", t.elapsed());
        refused(
            &o,
            &[&format!("huge{i}.toml: line 13, validation.region: "), "e6 mm"],
        );
    }
}

#[test]
fn check_on_a_summary_without_results_says_what_is_missing() {
    let d = tmp("check");
    let baseline = Path::new(env!("CARGO_MANIFEST_DIR")).join("results/baselines/ci-guard.json");
    let text = std::fs::read_to_string(&baseline).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let entries: Vec<String> = v["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            format!(
                "{} / {}",
                e["method"].as_str().unwrap(),
                e["poses"].as_str().unwrap()
            )
        })
        .collect();
    v["results"] = serde_json::json!([]);
    let pretty = serde_json::to_string_pretty(&v).unwrap();
    let line = pretty
        .lines()
        .position(|l| l.starts_with("  \"results\""))
        .unwrap()
        + 1;
    let empty = d.join("empty.json");
    std::fs::write(&empty, &pretty).unwrap();
    let place = format!("empty.json: line {line}, results: is empty");
    let e = refused(
        &calbench(&["check", path(&empty), "--baseline", path(&baseline)]),
        &[place.as_str(), "ci-guard.json"],
    );
    for entry in &entries {
        assert!(e.contains(entry.as_str()), "{entry} missing from: {e}");
    }
    // A summary whose entries are none of the baseline's lists what is missing and what is
    // there (a summary alone: per-trial values of entries it has no result of are refused).
    v.as_object_mut().unwrap().remove("per_trial");
    if let Some(r) = v["results"].as_array_mut() {
        r.push(serde_json::json!({"method": "pso", "poses": "random", "eta_mean_pct": 90.0}));
    }
    let other = d.join("other.json");
    let pretty = serde_json::to_string_pretty(&v).unwrap();
    let line = pretty
        .lines()
        .position(|l| l.starts_with("  \"results\""))
        .unwrap()
        + 1;
    std::fs::write(&other, pretty).unwrap();
    let place = format!("other.json: line {line}, results: ");
    let e = refused(
        &calbench(&["check", path(&other), "--baseline", path(&baseline)]),
        &[place.as_str(), "here: pso / random"],
    );
    for entry in &entries {
        assert!(e.contains(entry.as_str()), "{entry} missing from: {e}");
    }
}

/// `--out` that is the root folder, the home folder, an input file or an input folder of the
/// same command, or a folder where the command would overwrite an input with an output of the
/// same name, is refused by every command that writes, before any work, and nothing is
/// written: inputs keep their bytes, and neither `/` nor the home folder gain a file.
#[test]
fn outputs_never_land_where_they_destroy() {
    let dir = tmp("destroy");
    let home = dir.join("home");
    std::fs::create_dir_all(&home).unwrap();
    let root = crate::common::root();
    let sc = dir.join("ci-guard.toml");
    std::fs::copy(root.join("scenarios/ci-guard.toml"), &sc).unwrap();
    let raw = dir.join("raw.csv");
    std::fs::write(&raw, "a,b\n1,2\n").unwrap();
    let shard = dir.join("shard0");
    std::fs::create_dir_all(&shard).unwrap();
    std::fs::write(shard.join("shard.json"), "{}\n").unwrap();
    let inside = dir.join("inside");
    std::fs::create_dir_all(&inside).unwrap();
    let residuals = inside.join("residuals.csv");
    std::fs::write(&residuals, "q1\n").unwrap();
    // A scenario named like the file a run writes beside its results.
    let named = dir.join("named");
    std::fs::create_dir_all(&named).unwrap();
    let named_sc = named.join("scenario.toml");
    std::fs::copy(&sc, &named_sc).unwrap();
    let (s, r, h) = (path(&sc), path(&raw), path(&home));
    let sh = path(&shard);
    let home_dot = format!("{h}/.");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["run", s, "--out", "/"], "root folder"),
        (vec!["run", s, "--out", h], "home folder"),
        (vec!["run", s, "--out", &home_dot], "home folder"),
        (vec!["run", s, "--out", s], "input"),
        (
            vec!["run", path(&named_sc), "--out", path(&named)],
            "writes its scenario.toml there",
        ),
        (vec!["run", "--resume", "/"], "root folder"),
        (vec!["merge", sh, "--out", sh], "input"),
        (vec!["import", r, "--mapping", s, "--out", r], "input"),
        (vec!["simulate", s, "--out", s], "input"),
        (vec!["simulate", s, "--out", h], "home folder"),
        (
            vec!["poses", s, "--strategy", "detmax", "--out", "/"],
            "root folder",
        ),
        (vec!["compare", sh, sh, "--out", sh], "input"),
        (
            vec![
                "identify", "--robot", "irb2600", "--data", r, "--method", "ls", "--out", r,
            ],
            "input",
        ),
        (
            vec![
                "identify",
                "--robot",
                "irb2600",
                "--data",
                path(&residuals),
                "--method",
                "ls",
                "--out",
                path(&inside),
            ],
            "residuals.csv",
        ),
        (
            vec![
                "compensate",
                "--robot",
                "irb2600",
                "--identified",
                "irb2600",
                "--joints",
                r,
                "--out",
                r,
            ],
            "input",
        ),
    ];
    let inputs = [&sc, &raw, &shard.join("shard.json"), &residuals, &named_sc];
    let before: Vec<String> = inputs
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    let root_had_summary = Path::new("/summary.json").exists();
    for (args, why) in &cases {
        let o = crate::common::bin()
            .args(args)
            .env("HOME", &home)
            .output()
            .unwrap();
        // The option given: `--resume DIR`, else `--out`.
        let option = if args.contains(&"--resume") {
            "--resume"
        } else {
            "--out"
        };
        let err = refused(&o, &[option, why]);
        assert!(err.trim_end().lines().count() == 1, "{args:?}: {err}");
    }
    let after: Vec<String> = inputs
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    assert_eq!(before, after, "an input changed");
    assert_eq!(
        std::fs::read_dir(&home).unwrap().count(),
        0,
        "the home folder gained a file"
    );
    assert_eq!(std::fs::read_dir(&shard).unwrap().count(), 1);
    assert_eq!(std::fs::read_dir(&inside).unwrap().count(), 1);
    assert_eq!(std::fs::read_dir(&named).unwrap().count(), 1);
    assert_eq!(Path::new("/summary.json").exists(), root_had_summary);
}

/// A search's population or iteration count too large to allocate its swarm or its trace is
/// refused naming the method's key, where `run` panicked with "capacity overflow".
#[test]
fn a_search_population_or_iteration_count_too_large_is_refused_at_its_key() {
    let d = tmp("huge-search");
    for (method, key, most) in [
        ("pso", "population", "1000000"),
        ("bas-pso", "population", "1000000"),
        ("pso", "iterations", "10000000"),
        ("bas", "iterations", "10000000"),
    ] {
        let p = d.join(format!("{method}-{key}.toml"));
        std::fs::write(
            &p,
            format!(
                "name = \"huge\"\nseed = 1\ntrials = 2\n[robot]\nbuiltin = \"tx60\"\n\
                 [errors]\nkind = \"paper\"\n[tracker]\nmeasure = \"pose\"\n\
                 [calibration]\ncount = 20\n[[methods]]\nname = \"{method}\"\n\
                 {key} = 9223372036854775807\n"
            ),
        )
        .unwrap();
        let out = d.join("out");
        let o = calbench(&["run", path(&p), "--out", path(&out)]);
        refused(
            &o,
            &[&format!(
                "{method}-{key}.toml: line 14, methods[0].{key}: must be at most {most}, got \
                 9223372036854775807"
            )],
        );
        assert!(!out.join("summary.json").exists());
    }
}

/// An injected error beyond a robot file's range (`a2 = 1e308` mm in `errors.values`) is
/// refused naming the scenario, the line and the key, where `simulate` wrote a measurement
/// file of `NaN` points with exit status 0.
#[test]
fn an_injected_error_beyond_a_robot_files_range_is_refused_at_its_key() {
    let d = tmp("huge-error");
    let root = crate::common::root();
    let text = std::fs::read_to_string(root.join("scenarios/li2018-irb2600.toml")).unwrap();
    let line = text
        .lines()
        .position(|l| l.starts_with("a2 = "))
        .expect("errors.values.a2")
        + 1;
    let edited: Vec<String> = text
        .lines()
        .map(|l| {
            if l.starts_with("a2 = ") {
                "a2 = 1e308".to_string()
            } else {
                l.to_string()
            }
        })
        .collect();
    let p = d.join("huge-error.toml");
    std::fs::write(&p, edited.join("\n")).unwrap();
    let out = d.join("out");
    let o = calbench(&["simulate", path(&p), "--out", path(&out)]);
    refused(
        &o,
        &[&format!(
            "huge-error.toml: line {line}, errors.values.a2: must be within \
             ±1000000 mm"
        )],
    );
    assert!(!out.exists());
}

/// A `[[methods]]` entry without `name` was refused naming no line (`methods[0].name:
/// missing`): the key is not written, so the refusal now names the entry's line.
#[test]
fn a_method_without_a_name_is_refused_naming_the_entry_line() {
    let d = tmp("method-name");
    let text =
        std::fs::read_to_string(crate::common::root().join("scenarios/ci-guard.toml")).unwrap();
    let entry = text.lines().position(|l| l == "[[methods]]").unwrap() + 1;
    let sc = d.join("nameless.toml");
    std::fs::write(&sc, text.replacen("name = \"ls\"\n", "", 1)).unwrap();
    refused(
        &calbench(&["run", path(&sc), "--out", path(&d.join("out"))]),
        &[&format!(
            "nameless.toml: line {entry}, methods[0].name: missing; allowed: ls,"
        )],
    );
}

/// A key missing on one joint that the others give (`mass_kg` on joint 1 alone) is refused at
/// the line of that joint's `[[joints]]`, where the file has no line of the key to name.
#[test]
fn a_key_missing_on_one_joint_is_refused_at_its_joint_s_line() {
    let d = tmp("mass-missing");
    // The TX60's masses on joint 1 alone.
    let file = tx60_file(&d, "masses.toml", |t| {
        let mut first = true;
        let kept = t.lines().filter(|l| {
            let mass = l.starts_with("mass_kg");
            let keep = !mass || first;
            first &= !mass;
            keep
        });
        kept.map(|l| format!("{l}\n")).collect()
    });
    let text = std::fs::read_to_string(&file).unwrap();
    let second = text
        .lines()
        .enumerate()
        .filter(|(_, l)| *l == "[[joints]]")
        .nth(1)
        .map(|(i, _)| i + 1)
        .unwrap();
    let place = format!("masses.toml: line {second}, joint 2 (joints[1]), key `mass_kg`: ");
    let words = [place.as_str(), "give `mass_kg` on every joint or on none"];
    refused(
        &calbench(&["fk", "--robot", path(&file), "--q", "0,0,0,0,0,0"]),
        &words,
    );
}

/// A robot path the system cannot resolve is named with the system's reason; a symlink loop
/// had been called "neither a built-in robot … nor an existing robot file".
#[test]
fn a_robot_path_that_loops_is_named_with_the_system_s_reason() {
    let dir = tmp("cli-robot-loop");
    let lp = dir.join("loop.toml");
    std::os::unix::fs::symlink(&lp, &lp).unwrap();
    let o = calbench(&["fk", "--robot", path(&lp), "--q", "0,0,0,0,0,0"]);
    let err = refused(&o, &[&format!("{}: ", lp.display()), "symbolic links"]);
    assert!(!err.contains("neither a built-in robot"), "{err}");
    let gone = dir.join("absent.toml");
    let o = calbench(&["fk", "--robot", path(&gone), "--q", "0,0,0,0,0,0"]);
    refused(&o, &["neither a built-in robot"]);
}
