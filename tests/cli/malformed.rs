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

/// `scenarios/ci-guard.toml` with `edit` applied, written to `dir/NAME.toml`; the path.
fn ci_guard_with(dir: &Path, name: &str, edit: impl Fn(String) -> String) -> PathBuf {
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
    for _ in 0..2 {
        let args = [
            "compensate",
            "--robot",
            path_arg(&ur10),
            "--identified",
            path_arg(&ur10),
        ];
        calbench_ok(
            &[
                &args[..],
                &["--joints", path_arg(&prog), "--out", path_arg(&out)],
            ]
            .concat(),
        );
        assert!(read(&out).contains(",ok"), "{}", read(&out));
    }
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
    ] {
        let sc = ci_guard_with(&d, name, |t| t.replace(from, to));
        let out = d.join(name);
        let o = calbench(&["simulate", path_arg(&sc), "--out", path_arg(&out)]);
        refused(&o, &[&format!("{name}.toml"), key, "a robot file's range"]);
        assert!(!out.exists());
    }
}
