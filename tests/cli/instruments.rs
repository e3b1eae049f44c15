//! Measurement kinds beyond the tracker: `identifiability --measure K` per instrument, and a
//! small run of an instruments study (`[[measurement]]` tables), with refusals by key.

use crate::common::{calbench, calbench_ok, load_json, read, tmp_dir, write_scenario};

/// `identifiability --measure distance|plane|sphere|multi-target --json`: a length sees
/// none of the base frame; several targets per pose see more than one (the tool's rotation).
#[test]
fn identifiability_per_instrument() {
    let json = |k: &str, robot: &str| -> serde_json::Value {
        let o = calbench_ok(&[
            "identifiability",
            "--robot",
            robot,
            "--measure",
            k,
            "--poses",
            "40",
            "--json",
        ]);
        serde_json::from_slice(&o.stdout).unwrap()
    };
    for robot in ["irb2600", "tx60"] {
        let d = json("distance", robot);
        let base: Vec<&str> = d["unidentifiable"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|v| v.as_str())
            .filter(|v| v.starts_with("base"))
            .collect();
        assert_eq!(base.len(), 6, "{robot}: {d}");
        assert_eq!(
            d["instrument_unknowns"].as_array().unwrap().len(),
            3,
            "pivot"
        );
        let p = json("position", robot)["rank"].as_u64().unwrap();
        let m = json("multi-target", robot)["rank"].as_u64().unwrap();
        assert!(m > p, "{robot}: multi-target rank {m}, position {p}");
        for k in ["plane", "sphere"] {
            let v = json(k, robot);
            assert!(v["rank"].as_u64().unwrap() > 10, "{robot} {k}: {v}");
            assert!(!v["instrument_unknowns"].as_array().unwrap().is_empty());
        }
    }
    let o = calbench(&[
        "identifiability",
        "--robot",
        "irb2600",
        "--measure",
        "laser-pointer",
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("multi-target"));
}

/// Counts and poses no instrument can use are refused naming the option given: a plane
/// count beyond a measurement file's had been named `measurement.planes` (a study's key),
/// and one pose between poses `data` ("no observations"); so is an instrument's option with
/// a kind that does not read it, and `--gcn-threshold` without `--gcn-blocks`.
#[test]
fn identifiability_names_the_option_an_instrument_cannot_use() {
    let d = tmp_dir("cli-instruments-options");
    let one = d.join("one.csv");
    std::fs::write(&one, "q1,q2,q3,q4,q5,q6\n0,10,20,0,30,0\n").unwrap();
    let file = one.to_str().unwrap();
    for (args, want) in [
        (
            &["--measure", "plane", "--planes", "5000"][..],
            "setting `--planes`: must be at most 1000",
        ),
        (
            &["--measure", "sphere", "--spheres", "5000"],
            "setting `--spheres`: must be at most 1000",
        ),
        (
            &["--measure", "distance", "--between-poses", "--poses", "1"],
            "setting `--poses`: 1 pose gives no distance reading",
        ),
        (
            &[
                "--measure",
                "distance",
                "--between-poses",
                "--poses-file",
                file,
            ],
            "setting `--poses-file`: 1 pose gives no distance reading",
        ),
        (
            &["--measure", "distance", "--poses", "1"],
            "setting `--poses`: distance 1 has 1 points; it needs at least 5",
        ),
        // An instrument's option with a kind that does not read it is refused, not ignored.
        (
            &["--measure", "position", "--spheres", "3"],
            "setting `--spheres`: is read only with --measure sphere",
        ),
        (
            &["--measure", "sphere", "--planes", "2"],
            "setting `--planes`: is read only with --measure plane",
        ),
        (
            &["--measure", "pose", "--between-poses"],
            "setting `--between-poses`: is read only with --measure distance",
        ),
        (
            &["--gcn-threshold", "5"],
            "the following required arguments were not provided:\n  --gcn-blocks",
        ),
        // A pose count beyond a study's is refused, not left to fail allocating the poses
        // (a panic on capacity overflow, an abort on 2.4 TB).
        (
            &["--poses", "18446744073709551615"],
            "setting `--poses`: must be at most 10000000 poses, got 18446744073709551615",
        ),
        (
            &["--measure", "distance", "--poses", "100000000000"],
            "setting `--poses`: must be at most 10000000 poses, got 100000000000",
        ),
    ] {
        let mut all = vec!["identifiability", "--robot", "irb2600"];
        all.extend_from_slice(args);
        let o = calbench(&all);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && e.contains(want), "{args:?}: {e}");
        assert_eq!(
            o.status.code(),
            Some(if want.contains("required") { 2 } else { 1 })
        );
    }
}

const STUDY: &str = r#"
name = "instruments-small"
seed = 5
trials = 3
robot = "irb2600"

[instruments_study]
poses = [40]
strategies = ["random", "detmax-ide"]
candidates = 100
validation = 10

[errors]
kind = "paper"
length_mm = 0.1
angle_rad = 0.0005

[[measurement]]
kind = "position"

[[measurement]]
kind = "distance"
noise_um = 1.0
scale_um_per_m = 1.0

[[measurement]]
kind = "plane"
noise_um = 13.0
scale_um_per_m = 0.0

[[measurement]]
kind = "sphere"
noise_um = 13.0
scale_um_per_m = 0.0

[[measurement]]
kind = "multi-target"
"#;

/// A small instruments study runs every kind and strategy into `summary.json` and
/// `report.md`, the same bytes for one and two threads, without a failed trial (DETMAX-IDE's
/// poses on planes and spheres included); calibration beats the nominal robot.
#[test]
fn instruments_study_runs_every_kind() {
    let dir = tmp_dir("instruments-small");
    let sc = write_scenario(&dir, "s.toml", STUDY);
    let run = |threads: &str, out: &str| {
        let out = dir.join(out);
        calbench_ok(&[
            "run",
            sc.to_str().unwrap(),
            "--threads",
            threads,
            "--out",
            out.to_str().unwrap(),
        ]);
        out
    };
    let a = run("1", "a");
    let b = run("2", "b");
    assert_eq!(read(&a.join("summary.json")), read(&b.join("summary.json")));
    let html = read(&a.join("report.html"));
    assert_eq!(html, read(&b.join("report.html")));
    for k in [
        "position",
        "distance",
        "plane",
        "sphere",
        "multi-target",
        "cannot see",
    ] {
        assert!(html.contains(k), "report.html lacks {k}");
    }
    let s = load_json(&a.join("summary.json"));
    let cells = s["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 5 * 2);
    for k in ["position", "distance", "plane", "sphere", "multi-target"] {
        let c: Vec<_> = cells.iter().filter(|c| c["kind"] == k).collect();
        assert_eq!(c.len(), 2, "{k}");
        for c in c {
            assert_eq!(c["failures"], 0, "{k}: {c}");
            let (before, after) = (
                c["validation_before_mm"].as_f64().unwrap(),
                c["validation_after_mm"].as_f64().unwrap(),
            );
            assert!(after < before, "{k}: {after} ≥ {before}");
        }
    }
    let d = cells.iter().find(|c| c["kind"] == "distance").unwrap();
    assert!(d["unidentifiable"]
        .as_array()
        .unwrap()
        .iter()
        .any(|p| p == "d1"));
    assert!(read(&a.join("report.md")).contains("cannot see"));
}

/// A bad instrument is refused before any trial, naming the file and the key.
#[test]
fn instruments_study_refuses_bad_settings() {
    let dir = tmp_dir("instruments-bad");
    for (bad, key) in [
        (
            STUDY.replace(
                "kind = \"sphere\"\n",
                "kind = \"sphere\"\nradius_mm = -1.0\n",
            ),
            "radius_mm",
        ),
        (
            STUDY.replace("kind = \"distance\"\n", "kind = \"distanse\"\n"),
            "distanse",
        ),
        (STUDY.replace("poses = [40]", "poses = [400]"), "poses"),
        (
            STUDY.replace("validation = 10\n", "validation = 10\nvalidatoin = 3\n"),
            "instruments_study.validatoin",
        ),
        (
            STUDY.replace("kind = \"plane\"\n", "kind = \"plane\"\nplanes = 0\n"),
            "planes",
        ),
        // No sphere and no socket are named by their count's key and line, not by the
        // radius or distance beside it.
        (
            STUDY.replace("kind = \"sphere\"\n", "kind = \"sphere\"\nspheres = 0\n"),
            "line 33, measurement[3].spheres: needs at least one sphere",
        ),
        (
            socket_study(13.0).replace("sockets = 2", "sockets = 0"),
            "line 22, measurement[0].sockets: needs at least one socket",
        ),
        // Fewer distances than the 18 robot and 3 pivot parameters they identify: refused
        // when read, where DETMAX's refusal had come after the run began, naming neither the
        // file nor the study's key (`calibration.count`).
        (
            "name = \"few\"\nseed = 2\ntrials = 2\nrobot = \"irb2600\"\n\
             [instruments_study]\nposes = [30, 20]\nstrategies = [\"random\", \"detmax\"]\n\
             candidates = 60\nvalidation = 10\n[[measurement]]\nkind = \"distance\"\n"
                .to_string(),
            "line 6, instruments_study.poses: 20 poses give 20 readings of measurement[0] \
             (distance) for the 21 parameters it identifies (18 of the robot's, 3 of the \
             instrument's): at least 21 poses are needed",
        ),
    ] {
        let err = refused_run(&dir, "bad.toml", &bad);
        assert!(
            err.contains("bad.toml") && err.contains(key),
            "{key}: {err}"
        );
    }
}

/// `calbench run` of the scenario `text` written as `name` in `dir`: it must fail and write
/// no output folder; its stderr.
fn refused_run(dir: &std::path::Path, name: &str, text: &str) -> String {
    let sc = write_scenario(dir, name, text);
    let out = dir.join("o");
    let o = calbench(&["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(!o.status.success() && !out.exists());
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// A scenario of the layout before `[instruments_study]` (the study's keys at the top level
/// beside `[[measurement]]`) is refused, naming the file and the key and saying how to
/// migrate (CHANGELOG.md, docs/formats.md § 4.15). Migrated, it is `STUDY`, which
/// `instruments_study_runs_every_kind` runs.
#[test]
fn an_instruments_study_of_the_old_layout_is_refused_saying_how_to_migrate() {
    let dir = tmp_dir("instruments-old-layout");
    let old = STUDY.replace("\n[instruments_study]\n", "\n");
    let bare = STUDY
        .lines()
        .filter(|l| {
            ![
                "[instruments_study]",
                "poses",
                "strategies",
                "candidates",
                "validation",
            ]
            .iter()
            .any(|k| l.starts_with(k))
        })
        .collect::<Vec<_>>()
        .join("\n");
    for (text, key) in [(old, "poses"), (bare, "measurement")] {
        let err = refused_run(&dir, "old.toml", &text);
        assert!(
            err.contains("old.toml")
                && err.contains(&format!("{key}: "))
                && err.contains("add `[instruments_study]` and move those keys under it"),
            "{key}: {err}"
        );
    }
}

/// A key an instruments study does not take at the top level is refused at its line, naming
/// what the file takes; the keys of `[instruments_study]`, which are not top-level ones, are
/// not offered (serde's list of the scenario's fields had named them).
#[test]
fn an_unknown_top_level_key_of_an_instruments_study_is_refused_at_its_line() {
    let dir = tmp_dir("instruments-unknown-key");
    let text = STUDY.replacen(
        "\n[instruments_study]\n",
        "\nbogus = 1\n\n[instruments_study]\n",
        1,
    );
    let line = 1 + text
        .lines()
        .position(|l| l == "bogus = 1")
        .expect("the key");
    let err = refused_run(&dir, "unknown", &text);
    let want = format!(
        "unknown.toml: line {line}, bogus: unknown key: a scenario with [instruments_study] \
         takes name, description, seed, trials, robot, [errors], [instruments_study] and its \
         [[measurement]] tables"
    );
    assert!(err.contains(&want), "{err}");
    assert!(!err.contains("`poses`"), "{err}");
}

/// A socket study: the tool point held in two sockets 50 mm apart.
fn socket_study(noise_um: f64) -> String {
    format!(
        r#"
name = "instruments-socket"
seed = 5
trials = 10
robot = "irb2600"

[instruments_study]
poses = [100]
strategies = ["random"]
candidates = 200
validation = 20

[errors]
kind = "paper"
length_mm = 0.1
angle_rad = 0.0005

[[measurement]]
kind = "socket"
noise_um = {noise_um}
scale_um_per_m = 0.0
sockets = 2
socket_distance_mm = 50.0
"#
    )
}

/// A simulated socket study recovers the injected errors to within its noise (issue 54): with
/// a vanishing noise every parameter the sockets identify comes back (η ≥ 99.9 %) and the
/// validation error is nil; at the 13 µm of scenarios/instruments.toml the identified
/// parameters' errors are those the noise predicts (their RMS over the trials against the
/// Cramér–Rao bound, `crb_ratio`, between 0.5 and 2), and the sockets see neither theta1 nor
/// d1 (a rigid motion of the sockets absorbs them). Without noise the ratio is `null`.
#[test]
fn a_simulated_socket_study_recovers_the_injected_errors_to_within_its_noise() {
    let dir = tmp_dir("instruments-socket");
    let cell = |noise: f64, name: &str| {
        let sc = write_scenario(&dir, &format!("{name}.toml"), &socket_study(noise));
        let out = dir.join(name);
        calbench_ok(&["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        let s = load_json(&out.join("summary.json"));
        let cells = s["cells"].as_array().unwrap().clone();
        assert_eq!(cells.len(), 1, "{name}");
        let c = cells[0].clone();
        assert_eq!(c["kind"], "socket");
        assert_eq!(c["failures"], 0, "{c}");
        c
    };
    let exact = cell(0.01, "exact");
    let identified: Vec<&str> = exact["identified"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_str().unwrap())
        .collect();
    assert!(identified.len() >= 17, "{identified:?}");
    for p in &identified {
        let eta = exact["eta"][*p].as_f64().unwrap();
        assert!(eta >= 99.9, "{p}: η {eta} % with a vanishing noise");
    }
    let after = exact["validation_after_mm"].as_f64().unwrap();
    assert!(after < 1e-3, "validation {after} mm with a vanishing noise");
    for p in ["theta1", "d1"] {
        assert!(
            exact["unidentifiable"]
                .as_array()
                .unwrap()
                .iter()
                .any(|u| u == p),
            "the sockets should not see {p}"
        );
    }

    // Without noise there is no bound (a run's rule): it read 0.
    let noiseless = cell(0.0, "noiseless");
    assert!(noiseless["crb_ratio"].is_null(), "{noiseless}");

    let noisy = cell(13.0, "noisy");
    let crb = noisy["crb_ratio"].as_f64().unwrap();
    assert!((0.5..2.0).contains(&crb), "CRB ratio {crb}");
    let (before, after) = (
        noisy["validation_before_mm"].as_f64().unwrap(),
        noisy["validation_after_mm"].as_f64().unwrap(),
    );
    assert!(after < before / 10.0, "{after} against {before}");
}

/// `simulate` of an instruments study whose injected errors keep the true robot off a plane
/// (`alpha3 = -1` rad) named neither the file nor the entry ("trial 0: the true robot does not
/// touch its plane …"); it names the file, the `[[measurement]]` entry and its line.
#[test]
fn a_plane_the_true_robot_cannot_touch_is_refused_naming_the_entry() {
    let d = tmp_dir("instruments-touch");
    let text = read(&crate::common::root().join("scenarios/instruments.toml"));
    let line = text.lines().position(|l| l == "kind = \"plane\"").unwrap();
    let edited: String = text
        .lines()
        .map(|l| match l.starts_with("alpha3 = ") {
            true => "alpha3 = -1".to_string(),
            false => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let sc = write_scenario(&d, "far", &edited);
    let out = d.join("out");
    let o = calbench(&[
        "simulate",
        sc.to_str().unwrap(),
        "--measure",
        "plane",
        "--out",
        out.to_str().unwrap(),
    ]);
    crate::common::refused(
        &o,
        &[&format!(
            "far.toml: line {line}, measurement[3]: trial 0: the true robot (the nominal one \
             with the [errors]) does not touch its plane"
        )],
    );
    assert!(!out.exists());
}

/// An instrument whose surface the robot's draws do not reach (a sphere beside a gantry of
/// metre travels) is refused naming the scenario file and the `[[measurement]]` entry with its
/// line, by `run` and by `simulate`, where the message named neither. So is a socket of
/// several that the arm does not reach (3 m from socket 1): `simulate` had written a file of
/// the other sockets' rows, which `identify` refused, and `run` had refused it as the setting
/// `measurements`, of no file or line.
#[test]
fn an_instrument_the_arm_does_not_reach_is_named() {
    let dir = tmp_dir("instruments-unreached");
    let far =
        socket_study(13.0).replace("socket_distance_mm = 50.0", "socket_distance_mm = 3000.0");
    let line = 1 + far.lines().position(|l| l == "[[measurement]]").unwrap();
    let sc = write_scenario(&dir, "far", &far);
    let sc_arg = sc.to_str().unwrap();
    for (args, out) in [
        (vec!["run", sc_arg, "--out"], dir.join("far-run")),
        (vec!["simulate", sc_arg, "--out"], dir.join("far-sim")),
    ] {
        let mut args = args;
        args.push(out.to_str().unwrap());
        let o = calbench(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        let said = format!(
            "{sc_arg}: line {line}, measurement[0]: socket 2 of 2 is reached by none of the"
        );
        assert!(err.contains(&said), "{args:?}: {err}");
        assert!(!out.exists(), "{} written", out.display());
    }
    unreached_sphere(&dir);
}

/// The sphere of [`an_instrument_the_arm_does_not_reach_is_named`].
fn unreached_sphere(dir: &std::path::Path) {
    let prismatic = |alpha: f64, theta: f64, travel: f64| {
        format!(
            "[[joints]]\ntype = \"prismatic\"\nalpha = {alpha:?}\na = 0.0\nd = 0.0\n\
             theta = {theta:?}\nlimits = [0.0, {travel:?}]\n\n"
        )
    };
    let gantry = format!(
        "name = \"gantry\"\nconvention = \"dh\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n\n\
         {}{}{}[[joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 0.0\nd = 100.0\ntheta = 0.0\n\
         limits = [-180.0, 180.0]\n\n[tool]\nxyz = [50.0, 0.0, 30.0]\n",
        prismatic(-90.0, 0.0, 2000.0),
        prismatic(-90.0, -90.0, 1500.0),
        prismatic(0.0, 0.0, 800.0),
    );
    std::fs::write(dir.join("gantry.toml"), gantry).unwrap();
    let text = format!(
        "name = \"g\"\nseed = 3\ntrials = 2\nrobot = \"{}\"\n\n[instruments_study]\n\
         poses = [30]\nstrategies = [\"random\"]\ncandidates = 120\nvalidation = 10\n\n\
         [errors]\nkind = \"paper\"\n\n[[measurement]]\nkind = \"distance\"\n\n\
         [[measurement]]\nkind = \"sphere\"\n",
        dir.join("gantry.toml").display()
    );
    let sc = write_scenario(dir, "g", &text);
    let sc_arg = sc.to_str().unwrap();
    for (args, out) in [
        (vec!["run", sc_arg, "--out"], dir.join("run")),
        (
            vec!["simulate", sc_arg, "--measure", "sphere", "--out"],
            dir.join("sim"),
        ),
    ] {
        let mut args = args;
        args.push(out.to_str().unwrap());
        let o = calbench(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains(sc_arg)
                && err.contains("line 18, measurement[1]")
                && err.contains("reach their sphere"),
            "{args:?}: {err}"
        );
        assert!(!out.exists(), "{} written", out.display());
    }
}

/// A solve that stops at a local minimum is a failed trial, not a figure: one 25.4 mm sphere
/// read by a seven-axis arm (a KUKA iiwa's DH table) whose injected errors move its tool point
/// by about the sphere's radius, noise-free. At seed 9 one of four trials' solves converged
/// with a 0.8 mm residual, and the cell had said 0 failures, η 18 % and 5.3 mm after; the
/// other three trials are exact.
#[test]
fn a_solve_stopped_at_a_local_minimum_is_a_failure() {
    let dir = tmp_dir("instruments-local-minimum");
    let joint = |alpha: f64, d: f64, lim: f64| {
        format!(
            "[[joints]]\ntype = \"revolute\"\nalpha = {alpha}\na = 0.0\nd = {d}\ntheta = 0.0\n\
             limits = [-{lim}, {lim}]\n"
        )
    };
    let robot = [
        "name = \"iiwa7\"\nconvention = \"dh\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n"
            .to_string(),
        joint(-90.0, 360.0, 170.0),
        joint(90.0, 0.0, 120.0),
        joint(90.0, 420.0, 170.0),
        joint(-90.0, 0.0, 120.0),
        joint(-90.0, 400.0, 170.0),
        joint(90.0, 0.0, 120.0),
        joint(0.0, 126.0, 175.0),
        "[tool]\nxyz = [0.0, 0.0, 100.0]\nrpy = [0.0, 0.0, 0.0]\n".to_string(),
    ]
    .concat();
    std::fs::write(dir.join("iiwa7.toml"), robot).unwrap();
    let text = r#"
name = "sphere-iiwa7"
seed = 9
trials = 4
robot = "iiwa7.toml"

[instruments_study]
poses = [60]
strategies = ["random"]
candidates = 300
validation = 50

[errors]
kind = "paper"
length_mm = 0.5
angle_rad = 0.01

[[measurement]]
kind = "sphere"
noise_um = 0.0
scale_um_per_m = 0.0
spheres = 1
radius_mm = 25.4
"#;
    // The robot file is found beside the scenario, not in the folder the run starts in.
    let sc = write_scenario(&dir, "sphere", text);
    let out = dir.join("out");
    calbench_ok(&["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let s = load_json(&out.join("summary.json"));
    let cell = &s["cells"][0];
    assert_eq!(cell["failures"], 1, "{cell}");
    let after = cell["validation_after_mm"].as_f64().unwrap();
    assert!(after < 1e-6, "{cell}");
}
