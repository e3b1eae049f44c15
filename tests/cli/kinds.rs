//! Measurement-kind files (docs/formats.md § 5.3) as a user runs them: `simulate SCENARIO
//! --measure KIND` writes a distance, plane or sphere file, `identify` reads it back and
//! recovers the injected errors and the instrument's unknowns by every Jacobian method; the
//! parameters a kind cannot see are named, and a malformed file is refused by file, line and
//! column.

use std::path::Path;

use crate::common::{calbench, calbench_ok, load_json, path_arg, read, tmp_dir, write_scenario};

/// The errors every kind below determines on its poses: the distance, plane and sphere
/// readings of the IRB 2600 cannot see the base, the tool's rotation, θ1, d1, d3, a5, α5, θ6,
/// d6, a6, α6, and planes cannot see the arm's scale either: one of a2 and d4 (which one,
/// the poses decide) is left out.
const SEEN: &str = r#"["a1", "a3", "a4", "alpha1", "alpha2", "alpha3", "alpha4", "d2", "d5", "theta2", "theta3", "theta4", "theta5", "tool.x", "tool.y", "tool.z"]"#;

/// A noise-free instruments study of the IRB 2600 with the errors of [`SEEN`] and the
/// instrument `entry`.
fn scenario(entry: &str) -> String {
    format!(
        r#"
name = "kinds"
seed = 4
trials = 2
robot = "irb2600"

[instruments_study]
poses = [60]
strategies = ["random"]
candidates = 120
validation = 20

[errors]
kind = "paper"
length_mm = 0.1
angle_rad = 0.0005
params = {SEEN}

{entry}
"#
    )
}

/// The Jacobian methods, `lm` with adaptive damping to full convergence (the fixed μ = 1 of
/// Guo's eq. 8 stops at its 50 iterations on the sphere's centre).
const METHODS: [&[&str]; 4] = [
    &["--method", "ls"],
    &["--method", "ridge"],
    &["--method", "igg3"],
    &[
        "--method",
        "lm",
        "--set",
        "adaptive=true",
        "--set",
        "eps=1e-12",
        "--set",
        "max_iter=200",
    ],
];

pub(crate) fn simulate(
    dir: &Path,
    name: &str,
    entry: &str,
    measure: &[&str],
) -> std::path::PathBuf {
    let sc = write_scenario(dir, name, &scenario(entry));
    let out = dir.join(format!("sim-{name}"));
    let mut args = vec!["simulate", path_arg(&sc), "--out", path_arg(&out)];
    args.extend_from_slice(measure);
    calbench_ok(&args);
    out
}

/// Per kind (lengths from a pivot and between consecutive poses, three planes, two
/// spheres), a noise-free simulate → identify round trip recovers every injected error and
/// the instrument's unknowns to 1e-6 by ls, ridge, igg3 and lm; the file's header is the
/// kind's; a second simulate writes the same bytes; what the kind cannot see is named.
#[test]
fn noise_free_round_trip_per_kind() {
    let dir = tmp_dir("cli-kinds-round-trip");
    let quiet = "noise_um = 0.0\nscale_um_per_m = 0.0";
    let kinds = [
        (
            "pivot",
            format!("[[measurement]]\nkind = \"distance\"\n{quiet}"),
            "length_mm",
        ),
        (
            "chain",
            format!("[[measurement]]\nkind = \"distance\"\npivot = false\n{quiet}"),
            "step_mm",
        ),
        (
            "plane",
            format!("[[measurement]]\nkind = \"plane\"\n{quiet}"),
            "plane,offset_mm",
        ),
        (
            "sphere",
            format!("[[measurement]]\nkind = \"sphere\"\nspheres = 2\n{quiet}"),
            "sphere,radius_mm,offset_mm",
        ),
    ];
    for (name, entry, columns) in kinds {
        let sim = simulate(&dir, name, &entry, &[]);
        let again = simulate(&dir, &format!("{name}-again"), &entry, &[]);
        let csv = read(&sim.join("measurements.csv"));
        assert_eq!(csv, read(&again.join("measurements.csv")), "{name}");
        assert!(
            csv.starts_with(&format!("q1,q2,q3,q4,q5,q6,{columns}\n")),
            "{name}: {}",
            csv.lines().next().unwrap()
        );
        let truth = load_json(&sim.join("truth.json"));
        for method in METHODS {
            let out = dir.join(format!("id-{name}-{}", method[1]));
            let data = sim.join("measurements.csv");
            let val = sim.join("validation.csv");
            let validate = [&["--validate", path_arg(&val)][..], method].concat();
            let o = calbench_ok(&identify_args(&data, &out, &validate));
            let stdout = String::from_utf8_lossy(&o.stdout);
            assert!(stdout.contains("not determined by these"), "{stdout}");
            let id = load_json(&out.join("identified.json"));
            assert_eq!(id["termination"], "converged", "{name} {method:?}");
            let errors = id["errors"].as_object().unwrap();
            for (p, v) in errors {
                let t = truth["errors"][p.as_str()].as_f64().unwrap_or(0.0);
                let v = v.as_f64().unwrap();
                assert!(
                    (v - t).abs() < 1e-6,
                    "{name} {method:?}: {p} {v} against {t}"
                );
            }
            for p in SEEN.trim_matches(&['[', ']'][..]).split(", ") {
                let p = p.trim_matches('"');
                assert!(errors.contains_key(p), "{name}: {p} not identified");
            }
            let unknowns = id["instrument_unknowns"].as_object().unwrap();
            assert_eq!(
                unknowns.len(),
                truth["instrument_unknowns"].as_object().unwrap().len(),
                "{name}"
            );
            for (k, v) in unknowns {
                let t = truth["instrument_unknowns"][k.as_str()].as_f64().unwrap();
                let v = v.as_f64().unwrap();
                assert!(
                    (v - t).abs() < 1e-6,
                    "{name} {method:?}: {k} {v} against {t}"
                );
            }
            let blind: Vec<&str> = id["unidentifiable"]
                .as_array()
                .unwrap()
                .iter()
                .filter_map(|v| v.as_str())
                .collect();
            assert!(
                blind.contains(&"base.x") && blind.contains(&"theta1"),
                "{blind:?}"
            );
            let after = id["validation_after_mm"]["rms"].as_f64().unwrap();
            assert!(after < 1e-6, "{name} {method:?}: validation {after} mm");
            assert!(read(&out.join("robot.toml")).contains("irb2600-calibrated"));
        }
        if name == "plane" {
            assert_eq!(truth["plane_axes"], serde_json::json!(["z", "x", "y"]));
            let id = load_json(&dir.join("id-plane-ls").join("identified.json"));
            assert_eq!(id["plane_axes"], truth["plane_axes"]);
        }
    }
}

/// The arguments `identify --robot irb2600 --data DATA --out OUT EXTRA…`.
pub(crate) fn identify_args<'a>(data: &'a Path, out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "identify",
        "--robot",
        "irb2600",
        "--data",
        path_arg(data),
        "--out",
        path_arg(out),
    ];
    args.extend_from_slice(extra);
    args
}

/// `identify --robot irb2600 --data DATA --out OUT --validate VAL EXTRA…`, which must
/// succeed; its `identified.json`.
fn identify(data: &Path, val: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let validate = [&["--validate", path_arg(val)][..], extra].concat();
    calbench_ok(&identify_args(data, out, &validate));
    load_json(&out.join("identified.json"))
}

/// The identified errors of `id` but the base's against the truth, to 1e-6, and the
/// validation after calibration below 1e-6 mm.
fn recovered(id: &serde_json::Value, truth: &serde_json::Value, what: &str) {
    assert_eq!(id["termination"], "converged", "{what}");
    for (p, v) in id["errors"].as_object().unwrap() {
        if p.starts_with("base.") {
            continue;
        }
        let t = truth["errors"][p.as_str()].as_f64().unwrap_or(0.0);
        let v = v.as_f64().unwrap();
        assert!((v - t).abs() < 1e-6, "{what}: {p} {v} against {t}");
    }
    let after = id["validation_after_mm"]["rms"].as_f64().unwrap();
    assert!(after < 1e-6, "{what}: validation {after} mm");
}

/// Three targets on the flange, noise-free: the file has a row per target and pose; its
/// points registered onto the nominal robot's, the base then identified, every other
/// injected error comes back to 1e-6 by every Jacobian method, also from the same points in
/// a tracker frame turned by 30° and 10° and moved by metres; with `--registration known`
/// (the points in the base frame) the base is not identified and the rest comes back.
#[test]
fn multi_target_files_are_registered_and_identified() {
    let dir = tmp_dir("cli-kinds-targets");
    let entry = "[[measurement]]\nkind = \"multi-target\"\nnoise_um = 0.0\nscale_um_per_m = 0.0";
    let sim = simulate(&dir, "targets", entry, &[]);
    let (data, val) = (sim.join("measurements.csv"), sim.join("validation.csv"));
    let csv = read(&data);
    assert!(csv.starts_with("q1,q2,q3,q4,q5,q6,target,x,y,z,target_x_mm,target_y_mm,target_z_mm\n"));
    assert_eq!(csv.lines().count(), 1 + 3 * 60);
    let truth = load_json(&sim.join("truth.json"));
    // The same points in a tracker's frame: p' = Rx(10°) Rz(30°) p + t.
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let (c1, s1) = (10f64.to_radians().cos(), 10f64.to_radians().sin());
    let mut moved = String::new();
    for (i, line) in csv.lines().enumerate() {
        if i == 0 {
            moved += line;
            moved.push('\n');
            continue;
        }
        let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
        let p: Vec<f64> = cells[7..10].iter().map(|v| v.parse().unwrap()).collect();
        let z = [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]];
        let x = [z[0], c1 * z[1] - s1 * z[2], s1 * z[1] + c1 * z[2]];
        for (k, t) in [2500.0, -300.0, 400.0].iter().enumerate() {
            cells[7 + k] = format!("{:.9}", x[k] + t);
        }
        moved += &cells.join(",");
        moved.push('\n');
    }
    let tracker = dir.join("tracker-frame.csv");
    std::fs::write(&tracker, moved).unwrap();
    for method in METHODS {
        let what = format!("{method:?}");
        let id = identify(&data, &val, &dir.join(format!("id-{}", method[1])), method);
        recovered(&id, &truth, &what);
        assert_eq!(id["registration"], "identify");
        assert!(id["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p == "base.x"));
        let blind = id["unidentifiable"].as_array().unwrap();
        assert!(blind.iter().any(|p| p == "theta1"), "{blind:?}");
        let out = dir.join(format!("tracker-{}", method[1]));
        let id = identify(&tracker, &val, &out, method);
        recovered(&id, &truth, &format!("tracker frame {what}"));
        let rz = id["registration_frame"]["rpy_rad"][2].as_f64().unwrap();
        assert!((rz + 30f64.to_radians()).abs() < 1e-2, "{rz}");
    }
    let known = ["--method", "ls", "--registration", "known"];
    let id = identify(&data, &val, &dir.join("known"), &known);
    recovered(&id, &truth, "known");
    assert!(!id["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .any(|p| p == "base.x"));
    let svd = ["--method", "ls", "--registration", "svd"];
    let o = calbench(&identify_args(&data, &dir.join("svd"), &svd));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--registration"));
}

/// `--measure` picks the scenario's entry of that kind; a kind the scenario lacks and
/// `--measure` on a tracker scenario are refused.
#[test]
fn simulate_measure_picks_the_instrument() {
    let dir = tmp_dir("cli-kinds-measure");
    let entries = "[[measurement]]\nkind = \"plane\"\n\n[[measurement]]\nkind = \"sphere\"\n\n\
                   [[measurement]]\nkind = \"multi-target\"";
    let sim = simulate(&dir, "two", entries, &["--measure", "sphere"]);
    assert!(read(&sim.join("measurements.csv")).starts_with("q1,q2,q3,q4,q5,q6,sphere,"));
    // With noise each reading has its σ.
    assert!(read(&sim.join("measurements.csv"))
        .lines()
        .next()
        .unwrap()
        .ends_with(",sigma_mm"));
    let sc = write_scenario(&dir, "three", &scenario(entries));
    let o = calbench(&[
        "simulate",
        path_arg(&sc),
        "--measure",
        "distance",
        "--out",
        path_arg(&dir.join("x")),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("no [[measurement]] of kind distance"),
        "{err}"
    );
    let targets = simulate(&dir, "t", entries, &["--measure", "multi-target"]);
    assert!(read(&targets.join("measurements.csv")).starts_with("q1,q2,q3,q4,q5,q6,target,"));
    let o = calbench(&[
        "simulate",
        "scenarios/ci-guard.toml",
        "--measure",
        "plane",
        "--out",
        path_arg(&dir.join("y")),
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("not an instruments study"));
    assert!(!dir.join("x").exists() && !dir.join("y").exists());
}

/// Joint columns of the IRB 2600 with three distinct poses per plane and a fourth.
fn plane_rows(planes: &[&str]) -> String {
    planes
        .iter()
        .enumerate()
        .map(|(i, p)| format!("{},{},10,20,30,40,{p}\n", i * 3, 50 + i))
        .collect()
}

/// Each malformed kind file is refused, naming the file, the line and the column, and
/// nothing is written.
#[test]
fn malformed_kind_files_are_refused_by_line_and_column() {
    let dir = tmp_dir("cli-kinds-bad");
    let q = "q1,q2,q3,q4,q5,q6";
    let ok = plane_rows(&["1", "1", "1", "1", "1"]);
    let t = format!("{q},target,x,y,z,target_x_mm,target_y_mm,target_z_mm");
    // A row of target `g` at offset `[o, 0, 0]` of pose `i`.
    let tr = |i: u32, g: u32, o: u32| format!("{i},10,20,30,40,50,{g},1000,{o},900,{o},0,0\n");
    let cases: Vec<(String, &str, &str)> = vec![
        (
            format!("{q},plane,sphere\n"),
            "line 1, column sphere",
            "one kind of reading",
        ),
        (
            format!("{q},target,x,y,z\n"),
            "line 1",
            "missing column \"target_x_mm\"",
        ),
        (
            format!("{t},sigma_mm\n"),
            "line 1, column 14",
            "unknown column \"sigma_mm\"",
        ),
        (
            format!("{t}\n{}{}{}", tr(0, 1, 0), tr(0, 2, 100), tr(1, 1, 100)),
            "line 4, column target_x_mm",
            "one target has one offset",
        ),
        (
            format!("{t}\n{}{}", tr(0, 1, 0), tr(0, 1, 0)),
            "line 3, column target",
            "target 1 twice in the pose that starts on line 2",
        ),
        (
            format!(
                "{t}\n{}{}{}{}{}",
                tr(0, 1, 0),
                tr(0, 2, 100),
                tr(1, 1, 0),
                tr(2, 1, 0),
                tr(2, 2, 100)
            ),
            "line 4",
            "the pose that starts here has no row of target 2",
        ),
        (
            format!("{q},plane,x\n"),
            "line 1, column 8",
            "unknown column \"x\"",
        ),
        (
            format!("{q},sphere,offset_mm\n"),
            "line 1",
            "missing column \"radius_mm\"",
        ),
        (
            format!("{q},plane\n{ok}0,0,0,0,0,0,0\n"),
            "line 7, column plane",
            "\"0\" is not a plane number",
        ),
        (
            format!("{q},plane\n{ok}# note\n0,0,0,0,0,0,1.5\n"),
            "line 8, column plane",
            "\"1.5\"",
        ),
        (
            format!("{q},plane\n{ok}0,0,0,0,0,0,3\n"),
            "line 7, column plane",
            "no row of plane 2",
        ),
        (
            format!("{q},plane,offset_mm\n0,0,0,0,0,0,1,abc\n"),
            "line 2, column offset_mm",
            "\"abc\" is not a finite number",
        ),
        (
            format!("{q},sphere,radius_mm\n0,0,0,0,0,0,1,25.4\n1,0,0,0,0,0,1,25.5\n"),
            "line 3, column radius_mm",
            "sphere 1 has radius 25.4 mm on line 2",
        ),
        (
            format!("{q},sphere,radius_mm\n0,0,0,0,0,0,1,0\n"),
            "line 2, column radius_mm",
            "not a radius",
        ),
        (
            format!("{q},length_mm\n0,0,0,0,0,0,-3\n"),
            "line 2, column length_mm",
            "not a length",
        ),
        (
            format!("{q},step_mm\n0,0,0,0,0,0,12\n"),
            "line 2, column step_mm",
            "the first row has no pose before it",
        ),
        (
            format!("{q},step_mm\n0,0,0,0,0,0,\n1,0,0,0,0,0,\n"),
            "line 3, column step_mm",
            "is not a finite number",
        ),
        (
            format!("{q},length_mm,sigma_mm\n0,0,0,0,0,0,3,0\n"),
            "line 2, column sigma_mm",
            "positive",
        ),
        (
            format!("{q},length_mm\n0,400,0,0,0,0,3\n"),
            "line 2, column q2",
            "limits",
        ),
        (
            format!("{q},length_mm\n0,0,0,0,0,3\n"),
            "line 2",
            "6 fields, expected 7",
        ),
        (
            format!("{q},length_mm\n0,0,0,0,0,0,3\n0,0,0,0,0,0,4\n"),
            "line 2",
            "distinct poses",
        ),
        (format!("{q},plane\n"), "line 1", "no data rows"),
        (
            // The file's refusal, not the library's setting `measurements` after it.
            format!("{q},plane\n{}", plane_rows(&["1", "1", "2", "2", "2"])),
            "data: plane 1 has 2 points",
            "it needs at least 4",
        ),
    ];
    for (i, (text, place, says)) in cases.iter().enumerate() {
        let f = dir.join(format!("bad{i}.csv"));
        std::fs::write(&f, text).unwrap();
        let out = dir.join(format!("o{i}"));
        let o = calbench(&identify_args(&f, &out, &["--method", "ls"]));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success()
                && err.contains(&format!("bad{i}.csv: {place}"))
                && err.contains(says),
            "case {i} ({place}, {says}): {err}"
        );
        assert!(!out.exists(), "case {i}");
    }
}

/// Parameters a kind cannot see are refused when named in `--params` (with the groups they
/// fall in), unless `--allow-rank-deficient`; the searches and the tracker's options are
/// refused on a kind file.
#[test]
fn what_a_kind_cannot_determine_is_refused() {
    let dir = tmp_dir("cli-kinds-params");
    let entry = "[[measurement]]\nkind = \"distance\"";
    let sim = simulate(&dir, "d", entry, &[]);
    let data = sim.join("measurements.csv");
    let run = |extra: &[&str], out: &str| {
        let out = dir.join(out);
        let o = calbench(&identify_args(&data, &out, extra));
        (o, out)
    };
    let (o, out) = run(&["--method", "ls", "--params", "a2,a3,base.x"], "p");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("measurements.csv: data: distance readings")
            && err.contains("undetermined: base.x")
            && err.contains("--allow-rank-deficient"),
        "{err}"
    );
    assert!(!out.exists());
    let (o, out) = run(
        &["--method", "lm", "--params", "a2,a3", "--fix", "a3"],
        "fixed",
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let id = load_json(&out.join("identified.json"));
    assert_eq!(id["parameters"], serde_json::json!(["a2"]));
    assert_eq!(id["fixed"], serde_json::json!(["a3"]));
    for (extra, option) in [
        (&["--method", "bas"][..], "--method"),
        (&["--method", "ls", "--cv", "3"][..], "--cv"),
        (
            &["--method", "ls", "--registration", "known"][..],
            "--registration",
        ),
        (
            &["--method", "ls", "--compliance", "gravity"][..],
            "--compliance",
        ),
        (&["--method", "lm", "--k", "10"][..], "--k"),
        // `k` as a method option weighs nothing here either (it was taken and ignored).
        (&["--method", "lm", "--set", "k=10"][..], "--set k"),
    ] {
        let (o, out) = run(extra, "o");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(option),
            "{option}: {err}"
        );
        assert!(!out.exists());
    }
}

/// Sockets cannot see the base's rotations (a turned base turns the sockets' unknown places
/// with it): `identify` leaves them at their nominal values and lists them, as
/// `identifiability --measure socket` does, and refuses them when given. Its choice had been
/// made where the nominal points lie apart from their socket, whose direction made the gauge
/// look determined: the base came out turned by a degree or two, tens of mm at the tool.
#[test]
fn a_socket_file_leaves_the_base_rotations_nominal() {
    let dir = tmp_dir("cli-kinds-socket-base");
    let entry = "[[measurement]]\nkind = \"socket\"\nnoise_um = 13.0";
    let data = simulate(&dir, "s", entry, &[]).join("measurements.csv");
    let rotations = ["base.rx", "base.ry", "base.rz"];
    let out = dir.join("ls");
    calbench_ok(&identify_args(&data, &out, &["--method", "ls"]));
    let id = load_json(&out.join("identified.json"));
    let listed = |key: &str| -> Vec<String> {
        let names = id[key].as_array().unwrap().iter();
        names.map(|v| v.as_str().unwrap().to_string()).collect()
    };
    let (fitted, unseen) = (listed("parameters"), listed("unidentifiable"));
    for r in rotations {
        assert!(!fitted.iter().any(|p| p == r), "{r} fitted: {fitted:?}");
        assert!(unseen.iter().any(|p| p == r), "{r} not listed: {unseen:?}");
    }
    let o = calbench(&[
        "identifiability",
        "--robot",
        "irb2600",
        "--measure",
        "socket",
    ]);
    let said = String::from_utf8_lossy(&o.stdout);
    let line = said
        .lines()
        .find(|l| l.starts_with("unidentifiable:"))
        .unwrap();
    assert!(rotations.iter().all(|r| line.contains(r)), "{said}");
    // `identifiability --poses-file` of the file judges its readings as `identify` does (it
    // refused the file's `socket` column, and its poses cut to their joints were scored
    // against another layout of sockets).
    let args = [
        "identifiability",
        "--robot",
        "irb2600",
        "--poses-file",
        path_arg(&data),
    ];
    let o = calbench_ok(&[&args[..], &["--measure", "socket", "--json"]].concat());
    let a: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mut seen: Vec<String> = a["identifiable"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    let mut fitted = fitted.clone();
    seen.sort();
    fitted.sort();
    assert_eq!(seen, fitted);
    let o = calbench(&[&args[..], &["--measure", "plane"]].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("`--measure`") && err.contains("is a socket file"),
        "{err}"
    );
    let given = dir.join("given");
    let o = calbench(&identify_args(
        &data,
        &given,
        &["--method", "ls", "--params", "a2,base.rx"],
    ));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("undetermined: base.rx"),
        "{err}"
    );
    assert!(!given.exists());
}
