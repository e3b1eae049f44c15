//! Guo 2024 end to end: the full 21-parameter model of the 3T2R arm (β on joint 2), the
//! `[identification] params` key, LS refused on a rank-deficient list, and the ill-conditioned
//! parameter separation's block GCNs.

use std::path::Path;

use calbench::poses::separate;
use calbench::robot::builtin;
use calbench::robot::{parse_robot_file, robot_to_toml, Param};
use calbench::runner::run::run;
use calbench::study::reporter::Silent;
use calbench::study::scenario::Scenario;
use calbench::study::{RunOptions, Study};

use crate::common::tmp_dir;

const FULL: &str = r#"
name = "guo-full-test"
seed = 3
trials = 2
[robot]
builtin = "guo-3t2r"
[errors]
kind = "paper"
params = "all"
[tracker]
mpe_a_um = 0.0
mpe_b_um_per_m = 0.0
[registration]
method = "known"
[calibration]
count = 40
strategies = ["random"]
[validation]
count = 20
[identification]
params = "all"
[[methods]]
name = "lm"
mu = 1.0
adaptive = false
"#;

#[test]
fn guo_3t2r_has_guos_21_joint_parameters_with_beta2_alone() {
    let r = builtin::guo_3t2r();
    let joint: Vec<String> = r.joint_params().iter().map(|p| p.to_string()).collect();
    assert_eq!(joint.len(), 21, "{joint:?}");
    assert!(joint.contains(&"beta2".to_string()));
    for b in ["beta1", "beta3", "beta4", "beta5"] {
        assert!(!joint.contains(&b.to_string()), "{b} in {joint:?}");
    }
    // The robot file keeps the restriction through a round trip.
    let text = robot_to_toml(&r);
    assert!(text.contains("beta_joints = [2]"), "{text}");
    let back = parse_robot_file(&text, Path::new("guo.toml")).unwrap();
    assert_eq!(back.params(), r.params());
}

#[test]
fn beta_joints_is_checked_naming_the_key() {
    let base = robot_to_toml(&builtin::guo_3t2r());
    for (from, to, key) in [
        ("beta_joints = [2]", "beta_joints = [6]", "beta_joints"),
        ("beta_joints = [2]", "beta_joints = [2, 2]", "beta_joints"),
        (
            "convention = \"dh_beta\"",
            "convention = \"dh\"",
            "beta_joints",
        ),
    ] {
        let text = base.replace(from, to);
        let e = parse_robot_file(&text, Path::new("bad.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.toml") && e.contains(key), "{to}: {e}");
    }
    // A β on a joint that carries none.
    let text = base.replacen("theta = 0.0\n", "theta = 0.0\nbeta = 1.0\n", 1);
    let e = parse_robot_file(&text, Path::new("bad.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("joints[0]") && e.contains("beta"), "{e}");
}

#[test]
fn ls_is_refused_on_the_rank_deficient_full_model_and_lm_runs_it() {
    let text = FULL.replace("name = \"lm\"\nmu = 1.0\nadaptive = false", "name = \"ls\"");
    let s = Scenario::parse(&text, Some(Path::new("full.toml"))).unwrap();
    let e = Study::new(s).err().expect("LS must be refused").to_string();
    assert!(
        e.contains("full.toml") && e.contains("identification.params") && e.contains("\"ls\""),
        "{e}"
    );
    let s = Scenario::parse(FULL, None).unwrap();
    let study = Study::new(s).unwrap();
    assert_eq!(study.params.len(), 24); // 21 joint parameters and the tool point
    assert!(!study.undetermined.is_empty());
}

#[test]
fn lm_on_the_full_model_reports_eta_for_every_parameter_noise_free() {
    let out = tmp_dir("guo-full");
    let s = Scenario::parse(FULL, None).unwrap();
    let opts = RunOptions {
        out: Some(out.clone()),
        threads: Some(1),
        progress: false,
        shard: None,
        precision: None,
    };
    let res = run(s, &opts, &mut (), &Silent).unwrap();
    let r = serde_json::to_value(&res.blocks[0].entries[0]).unwrap();
    assert_eq!(r["failures"], 0, "{r}");
    let eta = r["eta"].as_object().unwrap();
    for name in builtin::guo_3t2r().joint_params() {
        assert!(eta.contains_key(&name.to_string()), "no η for {name}");
    }
    // The damped solution fits the data: noise-free validation after compensation is far
    // below the error before (the undetermined directions do not move the tool point).
    let before = r["validation_before_mm"]["mean"].as_f64().unwrap();
    let after = r["validation_after_mm"]["mean"].as_f64().unwrap();
    assert!(after < 1e-2 * before, "{before} → {after}");
    // The identifiable parameters of the model are recovered (η near 100 %).
    for name in ["theta1", "alpha1", "alpha3"] {
        let m = eta[name]["mean"].as_f64().unwrap();
        assert!(m > 99.0, "η({name}) = {m}");
    }
}

#[test]
fn separation_reports_block_gcns_and_brings_every_block_under_the_threshold() {
    let r = builtin::guo_3t2r();
    let mut g = calbench::numeric::rng::from_seed(8);
    let qs = calbench::robot::sampling::uniform_joint_poses(&r, 100, &mut g);
    let params = r.joint_params();
    let sep = separate(
        &r,
        &params,
        &qs,
        calbench::measurement::Measure::Position,
        1e2,
    );
    assert!(!sep.removed.is_empty());
    let names: Vec<&str> = sep.blocks.iter().map(|b| b.name).collect();
    assert_eq!(names, ["theta", "d", "a", "alpha", "beta"]);
    for b in &sep.blocks {
        assert!(b.gcn_after <= 1e2, "{b:?}");
        // A block left whole keeps its GCN; a reduced one was over the threshold.
        let reduced = sep.removed.iter().any(|p| p.block() == b.name);
        assert_eq!(
            reduced,
            (b.gcn_before > 1e2 || b.gcn_before.is_nan()),
            "{b:?}"
        );
    }
    // Kept and removed partition the model, and the removed ones are the dependent ones:
    // the kept joint parameters of each block are independent (finite block GCN).
    assert_eq!(sep.kept.len() + sep.removed.len(), params.len());
    assert!(sep.removed.iter().all(|p| p.joint().is_some()));
    // Guo's tables 1–3: a4/a5 and d2/d3 are the only dependent pairs (one of each goes), the
    // θ, α and β blocks are whole (the tool point lies off every revolute axis).
    let removed = &sep.removed;
    assert_eq!(removed.len(), 2, "{removed:?}");
    assert!(
        removed.contains(&Param::A(3)) != removed.contains(&Param::A(4)),
        "{removed:?}"
    );
    assert!(
        removed.contains(&Param::D(1)) != removed.contains(&Param::D(2)),
        "{removed:?}"
    );
    let json = sep.to_json();
    // Infinite GCNs are written as null; every block has both keys.
    assert!(json["blocks"]["d"].get("gcn_before").is_some());
    assert!(json["blocks"]["d"]["gcn_after"].is_number());
    assert_eq!(json["removed"].as_array().unwrap().len(), sep.removed.len());
}
