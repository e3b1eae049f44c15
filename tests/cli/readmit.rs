//! Identifiability re-checked at the identified robot, run as a user runs it (docs/formats.md
//! § 2.6.1, "Parameters re-checked at the identified robot"): the IRB2600's nominal tool point
//! lies on joint 6's axis, so joint 6's harmonics (`hs6`, `hc6`) are left out at the nominal
//! robot. On data whose tool stays on that axis, with tracker noise or without, nothing is
//! re-admitted and the result is the nominal choice's to the byte; on data whose tool sits
//! 5.8 mm off the axis with a harmonic error of joint 6, the re-check re-admits both terms,
//! recovers the injected values within three of their σ and the validation error falls to
//! the noise.

use std::path::Path;

use calbench::numeric::rng::stream;
use calbench::robot::{builtin, loaded::loaded_fk, sampling::uniform_joint_poses, Param};
use rand::Rng;

use crate::common::{calbench, calbench_ok, load_json, path_arg, read, tmp_dir, write_points};
use crate::task::{task, task_lm};

/// The injected errors every data set has: lengths and angles of the arm, none on the tool.
pub(crate) const ARM: [(Param, f64); 4] = [
    (Param::A(1), 0.5),
    (Param::Theta(2), 1e-3),
    (Param::D(3), 0.3),
    (Param::Alpha(2), 5e-4),
];

/// `n` poses of the irb2600 with the errors `errors`, measured with uniform noise of ±`noise`
/// mm per coordinate (σ = noise/√3), written to `file`. The true points are the library's
/// forward kinematics with the harmonics (`loaded_fk`).
pub(crate) fn write_data(file: &Path, errors: &[(Param, f64)], noise: f64, n: usize, seed: u64) {
    let robot = builtin::irb2600();
    let truth = robot.with_errors(errors);
    let chain = truth.chain();
    let mut g = stream(seed, "readmit-cli");
    let qs = uniform_joint_poses(&robot, n, &mut g);
    write_points(file, &robot, qs, |q| {
        let mut p = loaded_fk(&truth, &chain, q, 0.0).unwrap().pos;
        if noise > 0.0 {
            for k in 0..3 {
                p[k] += g.random_range(-noise..noise);
            }
        }
        p
    });
}

/// The off-axis case's errors: [`ARM`], the tool point 5.8 mm off joint 6's axis and a
/// harmonic error of joint 6 (`hs6`, `hc6`).
pub(crate) fn off_axis_errors(hs: f64, hc: f64) -> Vec<(Param, f64)> {
    let mut errors = ARM.to_vec();
    errors.extend([
        (Param::Tool(0), 5.0),
        (Param::Tool(1), -3.0),
        (Param::Harmonic(5, 0), hs),
        (Param::Harmonic(5, 1), hc),
    ]);
    errors
}

/// `identify --robot irb2600 --method lm` of `cal` against `val`, with `extra` arguments,
/// into `out` (it must succeed).
pub(crate) fn identify_irb2600_lm(
    cal: &Path,
    val: &Path,
    extra: &[&str],
    out: &Path,
) -> std::process::Output {
    identify_irb2600(cal, val, &["lm"], extra, out)
}

/// `identify --robot irb2600 --method METHOD…` (`method`: the name and its `--set`s) of `cal`
/// against `val`, with `extra` arguments, into `out` (it must succeed).
fn identify_irb2600(
    cal: &Path,
    val: &Path,
    method: &[&str],
    extra: &[&str],
    out: &Path,
) -> std::process::Output {
    let mut args = vec![
        "identify",
        "--robot",
        "irb2600",
        "--data",
        path_arg(cal),
        "--validate",
        path_arg(val),
        "--out",
        path_arg(out),
        "--method",
    ];
    args.extend_from_slice(method);
    args.extend_from_slice(extra);
    calbench_ok(&args)
}

/// [`identify_irb2600_lm`], and its `identified.json`.
fn identify(cal: &Path, val: &Path, extra: &[&str], out: &Path) -> serde_json::Value {
    identify_with(cal, val, &["lm"], extra, out)
}

/// [`identify_irb2600`], and its `identified.json`.
fn identify_with(
    cal: &Path,
    val: &Path,
    method: &[&str],
    extra: &[&str],
    out: &Path,
) -> serde_json::Value {
    identify_irb2600(cal, val, method, extra, out);
    load_json(&out.join("identified.json"))
}

pub(crate) fn names(id: &serde_json::Value) -> Vec<String> {
    id["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_str().unwrap().to_string())
        .collect()
}

/// The failure of a rank test at the identified robot: there, errors at the noise level move
/// the identified tool point a few µm off joint 6's axis and break every exact dependency a
/// little. The bound sees that joint 6's harmonics are then determined to no better than
/// radians, and re-admits nothing: the result of the default choice is byte for byte that of
/// the same parameters given by name (which are never re-checked).
#[test]
fn on_axis_data_with_or_without_noise_re_admit_nothing() {
    let d = tmp_dir("cli-readmit-on-axis");
    for (case, noise) in [("noisy", 0.01), ("exact", 0.0)] {
        let (cal, val) = (
            d.join(format!("{case}-cal.csv")),
            d.join(format!("{case}-val.csv")),
        );
        write_data(&cal, &ARM, noise, 200, 1);
        write_data(&val, &ARM, noise, 40, 2);
        // A model with joint 6's harmonics on offer: they stay out.
        let h = identify(
            &cal,
            &val,
            &["--models", "harmonics", "--cv", "4"],
            &d.join(format!("{case}-h")),
        );
        assert!(h.get("readmitted").is_none(), "{case}: {}", h["readmitted"]);
        let params = names(&h);
        assert!(params.contains(&"hs5".to_string()), "{case}: {params:?}");
        assert!(
            !params
                .iter()
                .any(|p| p.ends_with('6') && p.starts_with('h')),
            "{case}: {params:?}"
        );
        let md = read(&d.join(format!("{case}-h")).join("report.md"));
        assert!(!md.contains("Re-admitted"), "{case}");
        // The kinematic default against the same list given by name: the same bytes.
        let (def, named) = (
            d.join(format!("{case}-default")),
            d.join(format!("{case}-named")),
        );
        let k = identify(&cal, &val, &[], &def);
        assert!(k.get("readmitted").is_none(), "{case}");
        let list = names(&k).join(",");
        identify(&cal, &val, &["--params", &list], &named);
        for f in ["identified.json", "residuals.csv", "robot.toml"] {
            let (a, b) = (read(&def.join(f)), read(&named.join(f)));
            assert!(a == b, "{case}: {f} differs");
        }
    }
}

/// A tool point 5.8 mm off joint 6's axis and a harmonic error of joint 6 (0.01 rad in
/// sin q6, −0.005 rad in cos q6), σ ≈ 0.006 mm: joint 6's harmonics, left out at the nominal
/// robot, are determined at the identified one (σ below 1e-3 rad against the threshold 0.029
/// rad) and their values are told from 0, so both are re-admitted and identified: the injected
/// values come back within three of their σ, the residual and the validation error fall to
/// the noise. Joint 5's `a5` and `alpha5`, which the tool's offsets take only while the tool
/// point lies on joint 6's axis, are determined there too but are 0 in truth: they stay out.
/// So under `lm`, and under `igg3` per point and per coordinate, whose second identification
/// starts at the identified robot (from the nominal one, where the harmonics' columns vanish,
/// its first Gauss–Newton step in them was unbounded and it never converged, so the
/// re-admission was given up).
#[test]
fn an_off_axis_tool_re_admits_the_last_joints_harmonics_and_recovers_them() {
    let d = tmp_dir("cli-readmit-off-axis");
    let (cal, val) = (d.join("cal.csv"), d.join("val.csv"));
    let (hs, hc) = (0.01, -0.005);
    let errors = off_axis_errors(hs, hc);
    write_data(&cal, &errors, 0.01, 200, 3);
    write_data(&val, &errors, 0.01, 40, 4);
    let methods: [&[&str]; 3] = [&["lm"], &["igg3"], &["igg3", "--set", "per=\"coordinate\""]];
    for (m, method) in methods.into_iter().enumerate() {
        let out = d.join(format!("h{m}"));
        let extra = ["--models", "harmonics", "--cv", "4"];
        let id = identify_with(&cal, &val, method, &extra, &out);
        recovers_the_harmonics(&id, &out, (hs, hc), method);
    }
    // The kinematic model offers no harmonic, and nothing it left out is re-admitted: θ6,
    // which the tool's x and y take exactly at any robot, and joint 5's pair, 0 in truth.
    let k = identify(&cal, &val, &[], &d.join("k"));
    assert!(k.get("readmitted").is_none(), "{}", k["readmitted"]);
}

/// The checks of [`an_off_axis_tool_re_admits_the_last_joints_harmonics_and_recovers_them`]
/// on the identification `id` written to `out` by `method`, `(hs, hc)` the injected values.
fn recovers_the_harmonics(
    id: &serde_json::Value,
    out: &Path,
    (hs, hc): (f64, f64),
    method: &[&str],
) {
    assert_eq!(id["termination"], "converged", "{method:?}");
    let r = &id["readmitted"];
    let admitted: Vec<&str> = r["parameters"]
        .as_array()
        .unwrap_or_else(|| panic!("{method:?}: nothing re-admitted: {id}"))
        .iter()
        .map(|p| p["parameter"].as_str().unwrap())
        .collect();
    assert_eq!(admitted, ["hs6", "hc6"], "{method:?}: {r}");
    for p in r["parameters"].as_array().unwrap() {
        let (s, t) = (
            p["sigma"].as_f64().unwrap(),
            p["threshold"].as_f64().unwrap(),
        );
        // A third of the plausibility bound: 5° for an angle or a harmonic, 2 % of the
        // IRB2600's reach (2 783 mm) for a length.
        assert!((t - 5f64.to_radians() / 3.0).abs() < 1e-12, "{p}");
        assert!(s > 0.0 && s < t / 20.0, "{p}");
        // The one step from the identified robot already lands near the injected value.
        let want = if p["parameter"] == "hs6" { hs } else { hc };
        let step = p["estimate"].as_f64().unwrap();
        assert!((step - want).abs() < 0.2 * want.abs(), "{p}");
    }
    // The re-admitted terms are identified: last in the estimate, each within 3σ of the
    // injected value (σ from the covariance of the final fit).
    let params = names(id);
    let n = params.len();
    assert_eq!(&params[n - 2..], admitted);
    for (k, want) in [(n - 2, hs), (n - 1, hc)] {
        let got = id["errors"][&params[k]].as_f64().unwrap();
        let sigma = id["covariance"][k][k].as_f64().unwrap().sqrt();
        assert!(
            (got - want).abs() <= 3.0 * sigma,
            "{method:?} {}: {got} against {want} (σ {sigma})",
            params[k]
        );
    }
    // The fit improves: residual and validation at the noise (σ ≈ 0.0058 mm per coordinate,
    // 0.01 mm per point), against what the terms left out cost before.
    let before = r["before_rms_residual_mm"].as_f64().unwrap();
    let after = id["rms_residual_mm"].as_f64().unwrap();
    assert!(
        after < 0.012 && before > 3.0 * after,
        "{method:?}: {before} → {after}"
    );
    let val_rms = id["validation_after_mm"]["rms"].as_f64().unwrap();
    assert!(val_rms < 0.015, "{method:?}: {val_rms}");
    let md = read(&out.join("report.md"));
    assert!(
        md.contains("## Re-admitted at the identified robot") && md.contains("hs6"),
        "{method:?}: {md}"
    );
}

/// The IPA UR10's Series A, kinematic model: joint 5's `a5` passes the bound at the identified
/// robot (σ ≈ 6 mm against the threshold 11.9 mm, one step 20 mm: 3.25 σ, on a residual that is
/// mostly not noise), but the identification with it stops at its iteration limit where it
/// converged without it; the re-admission is given up and the entry is the nominal choice's,
/// converged, its validation RMS as docs/results.md gives it (0.4433 mm).
#[test]
fn a_re_admission_the_identification_cannot_settle_is_given_up() {
    let d = tmp_dir("cli-readmit-series-a");
    let out = d.join("a");
    task_lm(
        calbench_ok,
        &task("ipa-ur10-series-a"),
        Some("kinematic"),
        &out,
    );
    let id = load_json(&out.join("identified.json"));
    assert!(id.get("readmitted").is_none(), "{}", id["readmitted"]);
    assert_eq!(id["termination"], "converged");
    assert!(!names(&id).contains(&"a5".to_string()));
    let j = load_json(&out.join("task.json"));
    let value = j["value"].as_f64().unwrap();
    assert!((value - 0.4433).abs() < 0.00005, "{value}");
}

/// The IPA UR10's Series D and A, kinematic model, with `ls` and `igg3`: the re-check
/// re-admits `a5`, and the robot identified with it moves `theta5` or `alpha5` by 6–12°,
/// beyond the 5° bound, where the first identification was plausible: the re-admission is
/// given up and the entry written, where it was refused as implausible, its validation RMS
/// `lm`'s within 0.01 mm (docs/results.md).
#[test]
fn a_re_admission_that_makes_a_plausible_robot_implausible_is_given_up() {
    let d = tmp_dir("cli-readmit-implausible");
    for (name, method, lm_rms) in [
        ("ipa-ur10-series-d", "ls", 0.396),
        ("ipa-ur10-series-a-blocked", "igg3", 0.439),
    ] {
        let out = d.join(format!("{name}-{method}"));
        calbench_ok(&[
            "task",
            path_arg(&task(name)),
            "--method",
            method,
            "--models",
            "kinematic",
            "--out",
            path_arg(&out),
        ]);
        let id = load_json(&out.join("identified.json"));
        assert!(id.get("readmitted").is_none(), "{}", id["readmitted"]);
        assert!(!names(&id).contains(&"a5".to_string()));
        let value = load_json(&out.join("task.json"))["value"].as_f64().unwrap();
        assert!((value - lm_rms).abs() < 0.01, "{name} {method}: {value}");
    }
}

/// A four-axis SCARA (DH, mm, deg; joint 3 prismatic), its tool 30 mm off joint 4's axis:
/// the robot file's text.
pub(crate) fn scara() -> String {
    let joint = |kind: &str, alpha: f64, a: f64, d: f64, limits: &str| {
        format!(
            "[[joints]]\ntype = \"{kind}\"\nalpha = {alpha:?}\na = {a:?}\nd = {d:?}\n\
             theta = 0.0\nlimits = {limits}\n\n"
        )
    };
    format!(
        "name = \"scara\"\nconvention = \"dh\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n\n\
         {}{}{}{}[tool]\nxyz = [30.0, 0.0, 20.0]\nrpy = [0.0, 0.0, 0.0]\n",
        joint("revolute", 0.0, 350.0, 400.0, "[-130.0, 130.0]"),
        joint("revolute", 180.0, 300.0, 0.0, "[-140.0, 140.0]"),
        joint("prismatic", 0.0, 0.0, 0.0, "[0.0, 200.0]"),
        joint("revolute", 0.0, 0.0, 50.0, "[-360.0, 360.0]"),
    )
}

/// A SCARA whose θ3 turns the tool like a move of `tool.y` at the nominal robot (the tool
/// 30 mm off joint 4's axis, joint 3 prismatic): θ3 is left out there and re-admitted at the
/// identified robot. On noise-free data every method recovers it: the fit with it starts at
/// the re-check's Gauss–Newton step, since `lm`'s fixed damping, started with θ3 alone at its
/// estimate, moved it back to 0 (its step in θ3 is swamped by the damping of the 30 mm
/// lever's move of the tool) and stopped there as converged.
#[test]
fn a_re_admitted_error_is_recovered_by_a_damped_method_too() {
    let d = tmp_dir("cli-readmit-scara");
    std::fs::write(d.join("scara.toml"), scara()).unwrap();
    std::fs::write(
        d.join("s.toml"),
        "name = \"scara\"\nseed = 3\ntrials = 1\n[robot]\nfile = \"scara.toml\"\n[errors]\n\
         kind = \"normal\"\nlength_mm = 0.3\nangle_rad = 0.003\nparams = \"identifiable\"\n\
         [tracker]\nmpe_a_um = 0.0\nmpe_b_um_per_m = 0.0\n[outliers]\ncount = 0\n\
         [calibration]\ncount = 40\nstrategies = [\"random\"]\n[validation]\ncount = 20\n\
         [[methods]]\nname = \"lm\"\n",
    )
    .unwrap();
    let sim = d.join("sim");
    calbench_ok(&[
        "simulate",
        path_arg(&d.join("s.toml")),
        "--out",
        path_arg(&sim),
    ]);
    let truth = load_json(&sim.join("truth.json"))["errors"]["theta3"]
        .as_f64()
        .unwrap();
    assert!(truth.abs() > 1e-3, "{truth}");
    let (robot, data) = (d.join("scara.toml"), sim.join("measurements.csv"));
    // `identify --method METHOD` of the SCARA's points, with `extra`, into `d/OUT`.
    let identify = |method: &str, out: &Path, extra: &[&str]| {
        let mut args = vec!["identify", "--robot", path_arg(&robot), "--data"];
        args.extend([path_arg(&data), "--method", method, "--out", path_arg(out)]);
        args.extend(extra);
        calbench(&args)
    };
    for method in ["lm", "ls", "igg3"] {
        let out = d.join(method);
        let o = identify(method, &out, &[]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let id = load_json(&out.join("identified.json"));
        let readmitted = &id["readmitted"]["parameters"][0];
        assert_eq!(readmitted["parameter"], "theta3", "{method}");
        let sigma = readmitted["sigma"].as_f64().unwrap();
        let got = id["errors"]["theta3"].as_f64().unwrap();
        // Within a hundredth of the re-check's σ of the truth: the data are noise-free.
        assert!(
            (got - truth).abs() < 0.01 * sigma,
            "{method}: {got} against {truth}"
        );
    }
    // The gravity basis adds nothing to an arm whose revolute axes stay vertical: the model
    // had run and been labelled `gravity`, the kinematic model under another name.
    let o = identify("ls", &d.join("gravity"), &["--models", "kinematic,gravity"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("setting `--models`: `gravity` adds no parameter to robot \"scara\""),
        "{err}"
    );
    assert!(!d.join("gravity").exists());
}

/// Registered by `svd` or `wsvd`, the re-check re-admits what it re-admits under `identify`
/// registration: noise-free data of the TX60 with an error on every parameter (a5 and α5,
/// left out at the nominal robot, included). The fit holds θ1 and d1, which turn and move the
/// robot as the frame's rz and z do; solved along with the frame's six parameters they had
/// made every normal matrix singular, so nothing was ever re-admitted and the fit stopped
/// 8e-4 mm from the points.
#[test]
fn a_rigid_registration_re_admits_as_the_identified_one_does() {
    let d = tmp_dir("cli-readmit-svd");
    let scenario = d.join("s.toml");
    std::fs::write(
        &scenario,
        "name = \"svd-recheck\"\nseed = 1\ntrials = 1\n[robot]\nbuiltin = \"tx60\"\n\
         [errors]\nkind = \"normal\"\nlength_mm = 0.5\nangle_rad = 0.003\nparams = \"all\"\n\
         [tracker]\npose = [2000.0, -300.0, 400.0, 2.9, -1.1, 166.0]\nmpe_a_um = 0.0\n\
         mpe_b_um_per_m = 0.0\n[calibration]\ncount = 60\n[validation]\ncount = 20\n\
         [[methods]]\nname = \"ls\"\n",
    )
    .unwrap();
    let sim = d.join("sim");
    calbench_ok(&[
        "simulate",
        path_arg(&scenario),
        "--trial",
        "0",
        "--out",
        path_arg(&sim),
    ]);
    let data = sim.join("measurements.csv");
    for registration in ["identify", "svd", "wsvd"] {
        let out = d.join(registration);
        calbench_ok(&[
            "identify",
            "--robot",
            "tx60",
            "--data",
            path_arg(&data),
            "--method",
            "ls",
            "--registration",
            registration,
            "--out",
            path_arg(&out),
        ]);
        let id = load_json(&out.join("identified.json"));
        let readmitted: Vec<&str> = id["readmitted"]["parameters"]
            .as_array()
            .map(|v| v.iter().filter_map(|p| p["parameter"].as_str()).collect())
            .unwrap_or_default();
        assert_eq!(
            readmitted,
            ["a5", "alpha5"],
            "{registration}: {}",
            id["readmitted"]
        );
        let rms = id["rms_residual_mm"].as_f64().unwrap();
        assert!(rms < 1e-4, "{registration}: {rms} mm");
    }
}
