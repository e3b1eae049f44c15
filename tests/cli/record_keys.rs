//! `identified.json` is one typed record for a tracker's and a measurement-kind file
//! (`calbench::calibrate::record::IdentifiedRecord`), written with its keys in byte order at
//! every level, as the files have always been (docs/formats.md `identify`).

use std::collections::BTreeMap;
use std::path::Path;

use calbench::calibrate::cv::CrossValidation;
use calbench::calibrate::diagnostics::{Diagnostics, Influential, Pair, Predicted};
use calbench::calibrate::record::{FrameRecord, IdentifiedRecord, PriorMove, Trace};
use calbench::calibrate::{ErrorStats, RefitWeights, Registration, RoundsEnd};
use calbench::identify::{Identified, Termination};
use calbench::measurement::kind::Kind;
use calbench::numeric::Frame;
use calbench::robot::Param;

use crate::common::{
    calbench_ok, identified_round_trip, import_ur10_sample, path_arg, positions_only, read, root,
    tmp_dir, ur10_example,
};

/// Every key at every level is written in byte order: the record's serialisation is the
/// one of its JSON tree (a `serde_json::Map` sorts its keys).
#[test]
fn keys_are_in_byte_order() {
    let stats = ErrorStats {
        mean: 1.0,
        rms: 2.0,
        max: 3.0,
        std: 0.5,
    };
    let cv = CrossValidation {
        model: "kinematic".into(),
        k: 3,
        rms: 0.1,
        fold_rms: vec![0.1, 0.2, 0.3],
        mean: 0.2,
        sd: 0.1,
        parameters: 24,
        key: None,
    };
    let solve = Identified::plain(vec![0.1], 1, 1, Termination::Converged, 2);
    let r = IdentifiedRecord {
        allowed_worse: vec!["worse".into()],
        convergence_trace: Some(Trace {
            trace: vec![1.0, 0.5],
            values: "best fitness per iteration".into(),
        }),
        covariance: Some(vec![vec![1.0]]),
        cv: Some(cv.clone()),
        cv_best: Some("kinematic".into()),
        cv_models: Some(vec![cv]),
        diagnostics: Some(Diagnostics {
            sigma: vec![0.1],
            correlation: vec![vec![1.0]],
            flagged_pairs: vec![Pair {
                a: "a2".into(),
                b: "d4".into(),
                rho: 0.9,
            }],
            leverage: vec![0.5, 0.25],
            cook_distance: vec![0.1, 0.2],
            top_points: vec![Influential {
                row: 1,
                leverage: 0.25,
                cook: 0.2,
            }],
            predicted: Predicted {
                at: "validation".into(),
                rms_mm: 0.1,
                max_mm: 0.2,
                measured_rms_mm: 0.3,
            },
        }),
        fixed: vec!["a2".into()],
        holdout: Some("3/10".into()),
        instrument_unknowns: Some(BTreeMap::from([("pivot_x".into(), 1.0)])),
        kind: Some(Kind::Plane),
        pivot: Some(true),
        plane_axes: Some(vec!["z".into()]),
        priors: vec![PriorMove {
            parameter: "a2".into(),
            sigma: 0.1,
            without_prior: 0.2,
            with_prior: 0.3,
        }],
        readings: Some(4),
        registration: Some(Registration::Identify),
        registration_frame: Some(FrameRecord::from(&Frame::identity())),
        registration_last_step_mm: Some(0.0),
        registration_rounds: Some(1),
        registration_termination: Some(RoundsEnd::Single),
        registration_weights: Some(RefitWeights::Coordinate),
        standard_errors: Some(BTreeMap::from([("a2".into(), 0.1)])),
        targets_mm: Some(vec![[0.0, 1.0, 2.0]]),
        unidentifiable: Some(vec!["theta1".into()]),
        validation_after_attitude_deg: Some(stats),
        validation_after_deg: Some(stats),
        validation_after_mm: Some(stats),
        validation_before_attitude_deg: Some(stats),
        validation_before_deg: Some(stats),
        validation_before_mm: Some(stats),
        ..IdentifiedRecord::of("r", Path::new("d.csv"), "ls", &[Param::A(1)], &solve)
    };
    let text = serde_json::to_string(&r).unwrap();
    let tree = serde_json::to_value(&r).unwrap();
    assert_eq!(text, serde_json::to_string(&tree).unwrap());
    assert_eq!(tree.as_object().unwrap().len(), 42, "{text}");
    // Read back, the record is the one written (format 1: no `format` key).
    assert!(!text.contains("\"format\""), "{text}");
    let back = IdentifiedRecord::from_json(&text, Path::new("x")).unwrap();
    assert_eq!(serde_json::to_string(&back).unwrap(), text);
}

/// A number the file writes as `null` (a non-finite condition number, covariance or
/// σ0) reads back as NaN and is written as `null` again: the same bytes.
#[test]
fn null_numbers_read_back_as_nan() {
    let solve = Identified::plain(vec![0.1], 1, 1, Termination::Converged, 2);
    let r = IdentifiedRecord {
        condition_number: f64::INFINITY,
        covariance: Some(vec![vec![f64::NAN]]),
        registration_last_step_mm: Some(f64::NAN),
        sigma0: f64::NAN,
        ..IdentifiedRecord::of("r", Path::new("d.csv"), "ls", &[Param::A(1)], &solve)
    };
    let text = serde_json::to_string_pretty(&r).unwrap();
    assert!(
        text.contains("\"registration_last_step_mm\": null"),
        "{text}"
    );
    let back = IdentifiedRecord::from_json(&text, Path::new("x")).unwrap();
    assert!(back.sigma0.is_nan() && back.registration_last_step_mm.unwrap().is_nan());
    assert_eq!(serde_json::to_string_pretty(&back).unwrap(), text);
}

/// A file of a later format is refused naming the file and the format; an unknown key (a
/// misspelt one) or one of the wrong type is refused naming the file and the key.
#[test]
fn later_formats_and_unknown_keys_are_refused() {
    let solve = Identified::plain(vec![0.1], 1, 1, Termination::Converged, 2);
    let r = IdentifiedRecord::of("r", Path::new("d.csv"), "ls", &[Param::A(1)], &solve);
    let mut tree = serde_json::to_value(&r).unwrap();
    let path = Path::new("out/identified.json");
    let refusal = |tree: &serde_json::Value| {
        let text = serde_json::to_string(tree).unwrap();
        IdentifiedRecord::from_json(&text, path)
            .unwrap_err()
            .to_string()
    };
    tree["format"] = 2.into();
    let e = refusal(&tree);
    assert!(
        e.contains("out/identified.json") && e.contains("format 2"),
        "{e}"
    );
    tree["format"] = 1.into();
    let back = IdentifiedRecord::from_json(&tree.to_string(), path).unwrap();
    assert_eq!(
        serde_json::to_value(&back).unwrap(),
        serde_json::to_value(&r).unwrap()
    );
    tree["iteratoins"] = 3.into();
    let e = refusal(&tree);
    assert!(
        e.contains("out/identified.json") && e.contains("iteratoins"),
        "{e}"
    );
    tree.as_object_mut().unwrap().remove("iteratoins");
    tree["iterations"] = "three".into();
    let e = refusal(&tree);
    assert!(
        e.contains("out/identified.json") && e.contains("iterations"),
        "{e}"
    );
}

/// Every committed `identified.json` (results/**) and those `identify` writes for a tracker's
/// file with the practice options (held-out rows, two models cross-validated, a fixed
/// parameter, a prior, the diagnostics, the convergence trace) read through the type and
/// written again are their own bytes. (A measurement-kind file's record is read the same
/// way wherever a test reads one: `load_json`.)
#[test]
fn identified_json_reads_back_to_its_bytes() {
    let mut files: Vec<std::path::PathBuf> = Vec::new();
    let mut dirs = vec![root().join("results")];
    while let Some(d) = dirs.pop() {
        for e in std::fs::read_dir(&d).unwrap().map(Result::unwrap) {
            let p = e.path();
            if p.is_dir() {
                dirs.push(p);
            } else if p.file_name() == Some("identified.json".as_ref()) {
                files.push(p);
            }
        }
    }
    let d = tmp_dir("record-keys-round-trip");
    let all = d.join("all.csv");
    import_ur10_sample(&ur10_example("mapping.toml"), &all);
    let data = d.join("pos.csv");
    positions_only(&all, &data);
    let robot = ur10_example("ur10.toml");
    for (name, extra) in [
        (
            "cv",
            &[
                "--holdout",
                "3/10",
                "--cv",
                "4",
                "--models",
                "kinematic,beta",
            ][..],
        ),
        ("prior", &["--fix", "theta3", "--prior", "a2=0.001"][..]),
    ] {
        let out = d.join(name);
        let mut args = vec!["identify", "--robot", &robot, "--data", path_arg(&data)];
        args.extend_from_slice(&["--method", "lm"]);
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", path_arg(&out)]);
        calbench_ok(&args);
        files.push(out.join("identified.json"));
    }
    for p in &files {
        identified_round_trip(p, &read(p));
    }
    let text = read(&d.join("cv/identified.json"));
    for key in ["\"cv_models\"", "\"diagnostics\"", "\"convergence_trace\""] {
        assert!(text.contains(key), "{key}");
    }
    assert!(read(&d.join("prior/identified.json")).contains("\"priors\""));
}
