//! `identified.json` is one typed record for a tracker's and a measurement-kind file
//! (`calbench::calibrate::record::IdentifiedRecord`), written with its keys in byte order at
//! every level, as the files have always been (docs/formats.md `identify`).

use std::collections::BTreeMap;
use std::path::Path;

use calbench::calibrate::cv::CrossValidation;
use calbench::calibrate::diagnostics::{Diagnostics, Influential, Pair, Predicted};
use calbench::calibrate::record::{FrameRecord, IdentifiedRecord, PriorMove, Trace};
use calbench::calibrate::{ErrorStats, Registration, RoundsEnd};
use calbench::identify::{Identified, Termination};
use calbench::measurement::kind::Kind;
use calbench::numeric::Frame;
use calbench::robot::Param;

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
    };
    let solve = Identified::plain(vec![0.1], 1, 1, Termination::Converged, 2);
    let r = IdentifiedRecord {
        allowed_worse: vec!["worse".into()],
        convergence_trace: Some(Trace {
            trace: vec![1.0, 0.5],
            values: "best fitness per iteration",
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
                at: "validation",
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
        plane_axes: Some(vec!["z"]),
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
    assert_eq!(tree.as_object().unwrap().len(), 41, "{text}");
}
