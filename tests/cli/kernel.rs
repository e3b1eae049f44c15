//! The kernel residual `gp` run as a user runs it (docs/formats.md § 7.6, `kernel.json`): on a
//! small simulated data set whose points carry a smooth error in joint 1's angle that no
//! kinematic parameter can take (0.5 mm at a period of 120°), `identify --models
//! kinematic,gp` chooses `gp` by cross-validation on the calibration rows, the validation
//! error falls well below the kinematic model's, the length scales of `sin q1` and `cos q1`
//! come out the shortest, `kernel.json` is written beside `robot.toml` with the
//! hyperparameters `identified.json` records, and `identify`'s exports and `compensate` say
//! that they cannot carry it.

use std::path::Path;

use calbench::numeric::rng::stream;
use calbench::robot::{builtin, sampling::uniform_joint_poses, Param};
use rand::Rng;

use crate::common::{calbench_ok, load_json, path_arg, read, tmp_dir, write_points};

/// `n` poses of the irb2600 with an error in a₁ and the smooth residual in q1, with noise
/// of 0.01 mm, written to `file`.
fn write_data(file: &Path, n: usize, seed: u64) {
    let robot = builtin::irb2600();
    let truth = robot.with_errors(&[(Param::A(1), 0.5), (Param::Theta(2), 1e-3)]);
    let mut g = stream(seed, "kernel-cli");
    let qs = uniform_joint_poses(&robot, n, &mut g);
    write_points(file, &robot, qs, |q| {
        let mut p = truth.fk(q).pos;
        p.x += 0.5 * (3.0 * q[0]).sin() + g.random_range(-0.01..0.01);
        p.y += 0.3 * (3.0 * q[0]).cos() + g.random_range(-0.01..0.01);
        p.z += g.random_range(-0.01..0.01);
        p
    });
}

/// `identify` on `cal` with the validation file `val`, the models `models`, 4-fold CV.
fn identify(cal: &Path, val: &Path, models: &str, out: &Path, export: &str) -> String {
    let extra = ["--models", models, "--cv", "4", "--export", export];
    let o = crate::readmit::identify_irb2600_lm(cal, val, &extra, out);
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn the_kernel_residual_is_chosen_by_cv_fitted_written_and_not_carried_by_the_exports() {
    let d = tmp_dir("cli-kernel");
    let (cal, val) = (d.join("cal.csv"), d.join("val.csv"));
    write_data(&cal, 200, 1);
    write_data(&val, 40, 2);
    let gp = d.join("gp");
    let err = identify(&cal, &val, "kinematic,gp", &gp, "dh-csv");
    let id = load_json(&gp.join("identified.json"));
    assert_eq!(id["cv_best"], "gp", "{}", id["cv_models"]);
    let cvs = id["cv_models"].as_array().unwrap();
    let (kin_cv, gp_cv) = (
        cvs[0]["rms"].as_f64().unwrap(),
        cvs[1]["rms"].as_f64().unwrap(),
    );
    assert!(
        gp_cv < 0.5 * kin_cv,
        "CV RMS kinematic {kin_cv}, gp {gp_cv}"
    );
    // What the exports and robot.toml cannot carry, said plainly.
    assert!(
        err.contains("kernel residual")
            && err.contains("kernel.json")
            && err.contains("robot.toml and dh-table.csv carry the parametric model")
            && err.contains("compensate"),
        "{err}"
    );
    // The hyperparameters: joint 1's inputs the shortest length scales.
    let h = &id["kernel_residual"];
    let inputs: Vec<&str> = h["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(inputs[..2], ["sin q1", "cos q1"]);
    assert_eq!(inputs.len(), 12);
    let ls: Vec<f64> = h["length_scales"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let others = ls[2..].iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(ls[0] < others && ls[1] < others, "{ls:?}");
    assert!(h["noise_sd_mm"].as_f64().unwrap() < 0.1, "{h}");
    // kernel.json beside robot.toml, with the same hyperparameters and every calibration row.
    let k = load_json(&gp.join("kernel.json"));
    assert_eq!(k["format"], "calbench-kernel-1");
    assert_eq!(k["term"], "gp");
    assert_eq!(&k["hyperparameters"], h);
    assert_eq!(k["q_rad"].as_array().unwrap().len(), 200);
    assert_eq!(k["alpha_mm"].as_array().unwrap().len(), 200);
    // The validation rows: the kernel residual takes most of the error the kinematic model
    // leaves.
    let kin = d.join("kinematic");
    identify(&cal, &val, "kinematic", &kin, "toml");
    assert!(!kin.join("kernel.json").exists());
    let after = |dir: &Path| {
        load_json(&dir.join("identified.json"))["validation_after_mm"]["rms"]
            .as_f64()
            .unwrap()
    };
    let (a_gp, a_kin) = (after(&gp), after(&kin));
    assert!(
        a_gp < 0.3 * a_kin,
        "validation RMS gp {a_gp}, kinematic {a_kin}"
    );
    // compensate: the program is corrected with the parametric model, and it says so.
    let text = read(&val);
    let program: String = text
        .lines()
        .take(4)
        .map(|l| l.split(',').take(6).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    let prog = d.join("program.csv");
    std::fs::write(&prog, program).unwrap();
    let out = d.join("corrected.csv");
    let o = calbench_ok(&[
        "compensate",
        "--robot",
        "irb2600",
        "--identified",
        path_arg(&gp.join("robot.toml")),
        "--joints",
        path_arg(&prog),
        "--out",
        path_arg(&out),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("kernel.json") && err.contains("cannot carry") && err.contains("parametric"),
        "{err}"
    );
    let o = calbench_ok(&[
        "compensate",
        "--robot",
        "irb2600",
        "--identified",
        path_arg(&kin.join("robot.toml")),
        "--joints",
        path_arg(&prog),
        "--out",
        path_arg(&d.join("corrected-kinematic.csv")),
    ]);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("kernel"));
}

/// The warning's grammar when `robot.toml` is the only file that holds the parametric model
/// (`--export toml`): "robot.toml carries", not "carry".
#[test]
fn the_warning_names_robot_toml_alone_in_the_singular() {
    let d = tmp_dir("cli-kernel-singular");
    let (cal, val) = (d.join("cal.csv"), d.join("val.csv"));
    write_data(&cal, 60, 1);
    write_data(&val, 10, 2);
    let err = identify(&cal, &val, "gp", &d.join("gp"), "toml");
    assert!(
        err.contains("kernel.json only: robot.toml carries the parametric model without it"),
        "{err}"
    );
}
