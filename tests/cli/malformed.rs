//! Inputs a malformed-file corpus found taken or mishandled, each refused or kept as the
//! user contract says (docs/formats.md § 8).

use std::path::{Path, PathBuf};

use crate::common::{bin, calbench, calbench_ok, path_arg, read, refused, root, tmp_dir};

/// A study name of `.` or `..` would put the run beside or above `results/` (its default
/// folder is `results/<name>/`): refused with the file, line and key, in a Monte-Carlo and a
/// whole study alike, and nothing is written.
#[test]
fn a_name_that_is_not_a_folder_is_refused() {
    let d = tmp_dir("cli-malformed-name");
    for (file, name) in [
        ("ci-guard.toml", ".."),
        ("ban-fig3.toml", "."),
        ("ci-guard.toml", "a\\u0001b"),
    ] {
        let text = std::fs::read_to_string(root().join("scenarios").join(file)).unwrap();
        let line = text.lines().position(|l| l.starts_with("name = ")).unwrap() + 1;
        let edited: String = text
            .lines()
            .map(|l| {
                if l.starts_with("name = ") {
                    format!("name = \"{name}\"")
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        let dir = d.join(format!("{}-{}", file, name.len()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(file);
        std::fs::write(&path, edited).unwrap();
        let o = bin()
            .current_dir(&dir)
            .args(["run", file])
            .output()
            .unwrap();
        let line = format!("line {line}, name");
        refused(
            &o,
            &[
                path.file_name().unwrap().to_str().unwrap(),
                &line,
                "not `.` or `..`",
            ],
        );
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(left.len(), 1, "{file} {name}: something was written");
    }
}

/// A study name longer than a folder name may be is refused at its line, where the run
/// failed at the end with the file system's "File name too long" for `results/<name>/`.
#[test]
fn a_name_longer_than_a_folder_name_is_refused() {
    let d = tmp_dir("cli-malformed-long-name");
    let long = "n".repeat(201);
    let sc = ci_guard_with(&d, "long", |t| {
        t.replace("name = \"ci-guard\"", &format!("name = \"{long}\""))
    });
    let line = read(&sc)
        .lines()
        .position(|l| l.starts_with("name = "))
        .unwrap()
        + 1;
    let o = bin()
        .current_dir(&d)
        .args(["run", "long.toml", "--trials", "2"])
        .output()
        .unwrap();
    refused(
        &o,
        &[
            "long.toml",
            &format!("line {line}, name"),
            "at most 200 bytes",
        ],
    );
    assert!(!d.join("results").exists(), "something was written");
}

/// `scenarios/ci-guard.toml` with `edit` applied, written to `dir/NAME.toml`; the path.
pub(crate) fn ci_guard_with(dir: &Path, name: &str, edit: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(root().join("scenarios/ci-guard.toml")).unwrap();
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, edit(text)).unwrap();
    path
}

/// Keys a scenario holds to no effect are refused, naming the file and key: a key in a
/// `kind = "joint"` region (taken unread, where the other kinds refuse it), a sweep of
/// `trials` (every point ran the run's trials, the report showing an axis that was not) and a
/// sweep value given twice (two identical points).
#[test]
fn keys_with_no_effect_are_refused() {
    let d = tmp_dir("cli-malformed-keys");
    let region = ci_guard_with(&d, "region", |t| {
        t.replace(
            "[validation]\n",
            "[validation]\nregion = { kind = \"joint\", foo = 1 }\n",
        )
    });
    refused(
        &calbench(&["run", path_arg(&region), "--out", path_arg(&d.join("o1"))]),
        &["region.toml", "validation", "unknown field `foo`"],
    );
    for (name, sweep, want) in [
        (
            "trials",
            "key = \"trials\"\nvalues = [1, 2]",
            "\"trials\" cannot be swept",
        ),
        (
            "twice",
            "key = \"outliers.count\"\nvalues = [2, 1, 2]",
            "2 is given twice",
        ),
        // Named with the allowed keys, where serde's untagged enum matched no variant.
        (
            "unknown",
            "key = \"outliers.count\"\nvalues = [1]\nfoo = 1",
            "unknown field `foo`",
        ),
    ] {
        let sc = ci_guard_with(&d, name, |t| format!("{t}\n[sweep]\n{sweep}\n"));
        refused(
            &calbench(&["run", path_arg(&sc), "--out", path_arg(&d.join(name))]),
            &[&format!("{name}.toml"), "sweep", want],
        );
        assert!(!d.join(name).exists());
    }
}

/// A summary with two entries of one method and poses is refused by `check` naming the
/// second, where the guard paired whichever stood first and passed a regressed copy.
#[test]
fn check_refuses_a_summary_with_an_entry_twice() {
    let d = tmp_dir("cli-malformed-twice");
    let base = root().join("results/baselines/ci-guard.json");
    let mut v: serde_json::Value = serde_json::from_str(&read(&base)).unwrap();
    let results = v["results"].as_array_mut().unwrap();
    let n = results.len();
    let mut worse = results[0].clone();
    worse["failures"] = serde_json::json!(2);
    results.push(worse);
    let twice = d.join("summary.json");
    std::fs::write(&twice, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    refused(
        &calbench(&["check", path_arg(&twice), "--baseline", path_arg(&base)]),
        &[
            "summary.json",
            &format!("results[{n}]"),
            "second entry",
            "results[0]",
        ],
    );
}

/// `compensate` replaces the file it wrote before, as docs/formats.md § 1.7 says, where the
/// second run was refused as "not a folder".
#[test]
fn compensate_replaces_its_earlier_output() {
    let d = tmp_dir("cli-malformed-compensate");
    let prog = d.join("prog.csv");
    std::fs::write(&prog, "q1,q2,q3,q4,q5,q6\n10,-80,20,-90,30,5\n").unwrap();
    let ur10 = root().join("examples/ipa-ur10/ur10.toml");
    let out = d.join("corrected.csv");
    let compensate = |identified: &Path, extra: &[&str], out: &Path| {
        let args = [
            "compensate",
            "--robot",
            path_arg(&ur10),
            "--identified",
            path_arg(identified),
            "--joints",
            path_arg(&prog),
            "--out",
            path_arg(out),
        ];
        calbench(&[&args[..], extra].concat())
    };
    for _ in 0..2 {
        let o = compensate(&ur10, &[], &out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(read(&out).contains(",ok"), "{}", read(&out));
    }
    // An identified robot that is not there is refused as `--identified`, not `--robot`.
    refused(
        &compensate(&d.join("nope.toml"), &[], &d.join("o.csv")),
        &[
            "setting `--identified`",
            "nope.toml",
            "nor an existing robot file",
        ],
    );
    // `--payload-kg -1` is the option's value, refused by its range, not an unknown argument.
    refused(
        &compensate(&ur10, &["--payload-kg", "-1"], &d.join("o.csv")),
        &["setting `--payload-kg`: must be a mass from 0 to 100000 kg, got -1"],
    );
}

/// A robot of zero length read by a distance instrument: every reading's direction is 0/0.
/// `identifiability` says so, where nalgebra's SVD of the non-finite Jacobian never returned.
#[test]
fn a_distance_jacobian_that_is_not_finite_is_an_error_not_a_hang() {
    let d = tmp_dir("cli-malformed-zero");
    let text = read(&root().join("examples/ipa-ur10/ur10.toml"));
    let zero: String = text
        .lines()
        .map(|l| match l.split_once(" = ") {
            Some(("a" | "d", _)) => l.split(" = ").next().unwrap().to_string() + " = 0.0",
            Some(("xyz", _)) => "xyz = [0.0, 0.0, 0.0]".to_string(),
            _ => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let robot = d.join("zero.toml");
    std::fs::write(&robot, zero).unwrap();
    let o = calbench(&[
        "identifiability",
        "--robot",
        path_arg(&robot),
        "--measure",
        "distance",
        "--poses",
        "5",
    ]);
    refused(&o, &["distance", "not finite"]);
}

/// A pose list that is not there is named by the scenario's file, line and key, where the
/// refusal named the missing CSV alone.
#[test]
fn a_missing_pose_list_is_named_by_its_key() {
    let d = tmp_dir("cli-malformed-poses-file");
    let sc = ci_guard_with(&d, "file", |t| {
        t.replace(
            "strategies = [\"random\"]",
            "strategies = [\"file\"]\nposes_file = \"nope.csv\"",
        )
    });
    let line = read(&sc)
        .lines()
        .position(|l| l.starts_with("poses_file"))
        .unwrap()
        + 1;
    refused(
        &calbench(&["run", path_arg(&sc), "--out", path_arg(&d.join("o"))]),
        &[
            "file.toml",
            &format!("line {line}, calibration.poses_file"),
            "nope.csv is not a file",
        ],
    );
}

/// A name read from a file reaches the terminal with its control characters escaped and cut
/// to a line of 2000 characters, where an ESC of a CSV header coloured the terminal and a
/// header of megabytes was printed whole.
#[test]
fn names_from_a_file_reach_the_terminal_escaped_and_cut() {
    let d = tmp_dir("cli-malformed-terminal");
    let long = "n".repeat(50_000);
    for (name, column, says) in [
        (
            "esc",
            "a\u{1b}[31mRED\u{7}",
            "unknown column \"a\\u{1b}[31mRED\\u{7}\"",
        ),
        (
            "long",
            long.as_str(),
            "\"nnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnn… (50000 bytes)\"",
        ),
    ] {
        let csv = d.join(format!("{name}.csv"));
        std::fs::write(&csv, format!("q1,q2,q3,q4,q5,q6,x,y,z,{column}\n")).unwrap();
        let o = calbench(&[
            "identify",
            "--robot",
            "irb2600",
            "--data",
            path_arg(&csv),
            "--method",
            "ls",
            "--out",
            path_arg(&d.join("o")),
        ]);
        refused(&o, &[&format!("{name}.csv"), "line 1, column 10", says]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains('\u{1b}') && !err.contains('\u{7}'), "{err}");
        assert!(
            err.lines().all(|l| l.chars().count() < 2100),
            "{}",
            err.len()
        );
    }
    // serde's message quotes a scenario's unknown key whole: the terminal's line is cut.
    let sc = ci_guard_with(&d, "key", |t| {
        t.replace("[tracker]\n", &format!("[tracker]\n{long} = 1\n"))
    });
    let o = calbench(&["run", path_arg(&sc), "--out", path_arg(&d.join("o"))]);
    refused(
        &o,
        &[
            "key.toml",
            "tracker: unknown field `nnnn",
            "characters more)",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.lines().all(|l| l.chars().count() < 2100),
        "{}",
        err.len()
    );
}

/// A robot's name with control characters never reaches the terminal raw: the robot file is
/// refused at its `name` (`identifiability` had printed the ESC raw, and later escaped it;
/// an exported URDF could not hold it), and the refusal shows no ESC or BEL.
#[test]
fn a_robot_name_with_control_characters_is_refused_without_reaching_the_terminal() {
    let d = tmp_dir("cli-malformed-robot-name");
    let text = String::from_utf8(calbench_ok(&["robots", "irb2600"]).stdout).unwrap();
    let robot = d.join("esc.toml");
    std::fs::write(
        &robot,
        text.replace("name = \"irb2600\"", "name = \"a\\u001b[31mRED\\u0007\""),
    )
    .unwrap();
    let o = calbench(&[
        "identifiability",
        "--robot",
        path_arg(&robot),
        "--poses",
        "20",
    ]);
    let err = refused(
        &o,
        &["esc.toml: line ", ", name: must be a name without control"],
    );
    let out = String::from_utf8_lossy(&o.stdout);
    for text in [err.as_str(), &out] {
        assert!(
            !text.contains('\u{1b}') && !text.contains('\u{7}'),
            "{text}"
        );
    }
}

/// Lengths beyond a robot file's range, which made every trial fail and `simulate` write
/// `inf`, are refused naming the file and the key.
#[test]
fn lengths_beyond_a_robot_files_range_are_refused() {
    let d = tmp_dir("cli-malformed-huge");
    for (name, from, to, key) in [
        ("pose", "pose = [2500.0,", "pose = [1e300,", "tracker"),
        (
            "errors",
            "kind = \"paper\"",
            "kind = \"paper\"\nlength_mm = 1e300",
            "length_mm",
        ),
        (
            "magnitude",
            "magnitude_mm = [0.5, 1.0]",
            "magnitude_mm = [0.5, 1e308]",
            "magnitude",
        ),
        (
            "mpe",
            "[tracker]\n",
            "[tracker]\nmpe_a_um = 1e308\n",
            "tracker.mpe_a_um",
        ),
    ] {
        let sc = ci_guard_with(&d, name, |t| t.replace(from, to));
        let out = d.join(name);
        let o = calbench(&["simulate", path_arg(&sc), "--out", path_arg(&out)]);
        let range = match name {
            "mpe" => "1 m, far beyond any tracker's error",
            _ => "a robot file's range",
        };
        refused(&o, &[&format!("{name}.toml"), key, range]);
        assert!(!out.exists());
    }
    // A tracker turned beyond one turn, as a robot file's angles are bounded: 1e300° ran.
    for (name, to) in [
        ("turned", "pose = [2500.0, 0.0, 500.0, 0.0, 0.0, 1e300]"),
        (
            "turned-back",
            "pose = [2500.0, 0.0, 500.0, -361.0, 0.0, 180.0]",
        ),
    ] {
        let from = "pose = [2500.0, 0.0, 500.0, 0.0, 0.0, 180.0]";
        let sc = ci_guard_with(&d, name, |t| t.replace(from, to));
        let out = d.join(name);
        let o = calbench(&["simulate", path_arg(&sc), "--out", path_arg(&out)]);
        refused(
            &o,
            &[
                &format!("{name}.toml"),
                "tracker",
                "rx, ry, rz must be within ±360° (one turn)",
            ],
        );
        assert!(!out.exists());
    }
    let sc = ci_guard_with(&d, "turned-in", |t| {
        t.replace("0.0, 0.0, 180.0]", "0.0, 0.0, -360.0]")
    });
    let o = calbench(&["simulate", path_arg(&sc), "--out", path_arg(&d.join("in"))]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// The 1-based line of `text` that starts with `start`.
pub(crate) fn line_of(text: &str, start: &str) -> usize {
    let at = text.lines().position(|l| l.starts_with(start));
    at.unwrap_or_else(|| panic!("no line starts with {start}")) + 1
}

/// Values no arm or instrument has, which ran with every trial failed or absurd figures (a
/// payload of 1e300 kg gave η = −45 568 %), or failed in the run naming no key (`nuisance`,
/// "collinear points"), and keys their context does not read (a plane count on a distance
/// instrument, `lambda0` of the fixed damping, a negative stiffness with the sag model off),
/// are refused as the file is read, naming the file, the line and the key.
#[test]
fn values_and_keys_a_study_cannot_use_are_refused_at_their_line() {
    let d = tmp_dir("cli-malformed-unusable");
    let scenario = |file: &str| read(&root().join("scenarios").join(file));
    let ci = scenario("ci-guard.toml");
    let ins = scenario("instruments.toml");
    let ban = scenario("ban-fig3.toml");
    let position = "[[measurement]]\nkind = \"position\"\n";
    let distance = "kind = \"distance\"\n";
    let cases: Vec<(&str, String, &str, &str, &str)> = vec![
        // (name, text, the line's start, key, words)
        (
            // serde's type names (`expected usize`, `f64`) are said in words.
            "count",
            ci.replace("trials = 16", "trials = 16.5"),
            "trials",
            "trials",
            "invalid type: floating point `16.5`, expected a whole number ≥ 0",
        ),
        (
            "noise",
            ci.replace("[tracker]\n", "[tracker]\nmpe_a_um = \"15\"\n"),
            "mpe_a_um",
            "tracker.mpe_a_um",
            "invalid type: string \"15\", expected a number",
        ),
        (
            "angle",
            ci.replace(
                "[tracker]\n",
                "[tracker]\nmeasure = \"pose\"\nangle_noise_deg = 1e300\n",
            ),
            "angle_noise_deg",
            // Refused as the section is read: the place is the key serde names (§ 8.1).
            "tracker.angle_noise_deg",
            "from 0 to 360 ° (one turn), got 1e300",
        ),
        (
            // An orientation noise where no orientation is measured had been ignored.
            "angle-unread",
            ci.replace("[tracker]\n", "[tracker]\nangle_noise_deg = 0.01\n"),
            "angle_noise_deg",
            "tracker.angle_noise_deg",
            "is read only with measure = \"pose\" (measure is \"position\"",
        ),
        (
            // An array of the wrong length has no span of its own: it is placed at its key.
            "magnitudes",
            ci.replace(
                "magnitude_mm = [0.5, 1.0]",
                "magnitude_mm = [0.1, 0.2, 0.3]",
            ),
            "magnitude_mm",
            "outliers.magnitude_mm",
            "invalid length 3",
        ),
        (
            "payload",
            ci.replace(
                "model = \"linear\"",
                "model = \"linear\"\npayload_kg = 1e300",
            ),
            "payload_kg",
            "compliance.payload_kg",
            "must be a mass from 0 to 100000 kg, got 1e300",
        ),
        (
            "stiffness",
            ci.replace(
                "model = \"linear\"",
                "model = \"linear\"\nstiffness_nm_per_rad = [1e6, 1e6, 1e6, 1e5, 1e5, 1e-300]",
            ),
            "stiffness",
            "compliance.stiffness_nm_per_rad",
            "joint 6: stiffness must be a finite number ≥ 1 N·m/rad",
        ),
        (
            "sagless",
            ci.replace(
                "model = \"linear\"",
                "model = \"none\"\nstiffness_nm_per_rad = [-1.0, 1e6, 1e6, 1e5, 1e5, 1e5]",
            ),
            "stiffness",
            "compliance.stiffness_nm_per_rad",
            "joint 1: stiffness must be",
        ),
        (
            // toml spoke of a serde "unit variant".
            "kind",
            ci.replace("kind = \"paper\"", "kind = 3"),
            "kind = 3",
            "errors.kind",
            "must be a name in double quotes (a TOML string)",
        ),
        (
            "lambda",
            ci.replace("name = \"lm\"", "name = \"lm\"\nlambda0 = 5.0"),
            "lambda0",
            "methods[2].lambda0",
            "is not read with adaptive = false",
        ),
        (
            "mu",
            ci.replace("name = \"lm\"", "name = \"lm\"\nadaptive = true\nmu = 0.5"),
            "mu",
            "methods[2].mu",
            "is not read with adaptive = true",
        ),
        (
            "label",
            ci.replace("name = \"igg3\"", "name = \"igg3\"\nlabel = \" \""),
            "label",
            "methods[1].label",
            "must name the method in the reports",
        ),
        (
            "tracker-nan",
            ins.replacen(
                position,
                &format!("{position}tracker_mm = [nan, 0.0, 0.0]\n"),
                1,
            ),
            "tracker_mm",
            "measurement[0].tracker_mm",
            "must be finite and within ±1000000 mm",
        ),
        (
            "pivot",
            ins.replace("pivot_mm = [1200.0,", "pivot_mm = [1e300,"),
            "pivot_mm",
            "measurement[2].pivot_mm",
            "got 1e300",
        ),
        (
            "noise",
            ins.replacen("noise_um = 1.0", "noise_um = 1e300", 1),
            "noise_um = 1e300",
            "measurement[2].noise_um",
            "must be from 0 to 1000000000 µm",
        ),
        (
            "planes",
            ins.replace(distance, &format!("{distance}planes = 3\n")),
            "planes = 3",
            "measurement[2].planes",
            "is read only by kind = \"plane\" (this entry's kind is \"distance\")",
        ),
        (
            "pivotless",
            ins.replace(distance, &format!("{distance}pivot = false\n")),
            "pivot_mm",
            "measurement[2].pivot_mm",
            "is read only with pivot = true",
        ),
        (
            "poses",
            ins.replace("poses = [50, 200]", "poses = []"),
            "poses",
            "instruments_study.poses",
            "needs at least a pose count",
        ),
        (
            "strategies",
            ins.replace(
                "strategies = [\"random\", \"detmax-ide\"]",
                "strategies = []",
            ),
            "strategies",
            "instruments_study.strategies",
            "needs at least a strategy",
        ),
        (
            "strategy",
            ins.replace(
                "strategies = [\"random\", \"detmax-ide\"]",
                "strategies = [\"random\", \"ide\"]",
            ),
            "strategies",
            "instruments_study.strategies[1]",
            "unknown strategy \"ide\"; allowed: random, detmax, detmax-ide",
        ),
        (
            // The key lacking has no line: the strategy that needs it has.
            "file",
            ci.replace("strategies = [\"random\"", "strategies = [\"file\""),
            "strategies",
            "calibration.strategies[0]",
            "strategy \"file\" needs a pose list: calibration.poses_file",
        ),
        (
            "registration",
            ban.replace("noise_mm = 0.02", "noise_mm = 1e300"),
            "noise_mm",
            "registration_study.noise_mm",
            "must be finite and within ±1000000 mm",
        ),
        (
            "center",
            ban.replace("center_mm = [1000.0,", "center_mm = [1e300,"),
            "center_mm",
            "registration_study.center_mm",
            "got 1e300",
        ),
    ];
    for (name, text, start, key, words) in cases {
        let sc = d.join(format!("{name}.toml"));
        std::fs::write(&sc, &text).unwrap();
        let out = d.join(name);
        let o = calbench(&["run", path_arg(&sc), "--out", path_arg(&out)]);
        let at = format!("{name}.toml: line {}, {key}: ", line_of(&text, start));
        refused(&o, &[&at, words]);
        assert!(!out.exists(), "{name}: a run was written");
    }
}

/// `--trials` of 2^63 or more wrapped to a negative count, refused as the scenario file's
/// (`scenario: invalid value: integer -1`); it is refused as the option it is.
#[test]
fn a_trial_count_beyond_any_run_is_refused_as_the_option() {
    let d = tmp_dir("cli-malformed-trials");
    let sc = root().join("scenarios/ci-guard.toml");
    for n in ["9223372036854775808", "18446744073709551615"] {
        let out = d.join(n);
        let o = calbench(&["run", path_arg(&sc), "--trials", n, "--out", path_arg(&out)]);
        let want = format!("setting `--trials`: must be between 1 and 1000000000, got {n}");
        refused(&o, &[&want]);
        assert!(!out.exists());
    }
}

/// The strategy "box" without a box region is refused at the strategy's line, where the
/// refusal named `calibration.region`, which the file does not write, with no line.
#[test]
fn a_box_strategy_without_its_region_is_named_at_its_line() {
    let d = tmp_dir("cli-malformed-box");
    let sc = ci_guard_with(&d, "box", |t| {
        t.replace("strategies = [\"random\"]", "strategies = [\"box\"]")
    });
    let line = read(&sc)
        .lines()
        .position(|l| l.starts_with("strategies"))
        .unwrap()
        + 1;
    refused(
        &calbench(&["run", path_arg(&sc), "--out", path_arg(&d.join("o"))]),
        &[
            "box.toml",
            &format!("line {line}, calibration.strategies[0]: strategy \"box\" needs"),
        ],
    );
}
