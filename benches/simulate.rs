//! Measuring 50 poses with the simulated tracker (no sag), position and full pose, with
//! outliers; and the two registrations of 50 points.

use calbench::calibrate::registration::{register_svd, register_wsvd};
use calbench::numeric::rng::stream;
use calbench::robot::sampling::uniform_joint_poses;
use calbench::robot::Robot;
use calbench::sim::sag::{Compliance, ComplianceModel, ComplianceSettings};
use calbench::sim::{
    measure_poses, MeasureSetting, OutlierSettings, SagFn, Tracker, TrackerSettings,
};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::hint::black_box;

fn simulate(c: &mut Criterion) {
    let robot = calbench::robot::builtin::irb2600();
    let qs = uniform_joint_poses(&robot, 50, &mut stream(1, "poses"));
    let outliers = OutlierSettings {
        count: Some(4),
        ..Default::default()
    };
    let mut g = c.benchmark_group("measure_50_poses");
    for (name, measure) in [
        ("position", MeasureSetting::Position),
        ("pose", MeasureSetting::Pose),
    ] {
        let tracker = Tracker::new(&TrackerSettings {
            measure,
            angle_noise_deg: if measure == MeasureSetting::Pose {
                0.01
            } else {
                0.0
            },
            ..Default::default()
        })
        .expect("valid tracker settings");
        g.bench_with_input(BenchmarkId::from_parameter(name), &tracker, |b, t| {
            let mut rng = stream(2, "noise");
            b.iter(|| {
                measure_poses(
                    &robot,
                    black_box(&qs),
                    t,
                    Some(&outliers),
                    None,
                    None,
                    &mut rng,
                )
                .expect("measurement")
            })
        });
    }
    g.finish();

    // 50 poses with gravity sag: none, linear and rapier (default irb2600 stiffness/masses).
    let tracker = Tracker::new(&TrackerSettings::default()).expect("valid tracker settings");
    let mut g = c.benchmark_group("measure_50_poses_sag");
    g.sample_size(10);
    for model in [
        ComplianceModel::None,
        ComplianceModel::Linear,
        ComplianceModel::Rapier,
    ] {
        let settings = ComplianceSettings {
            model,
            ..Default::default()
        };
        let comp = Compliance::new(
            &settings,
            &robot,
            calbench::robot::builtin::builtin("irb2600"),
        )
        .expect("compliance");
        let sag = comp.map(|c| {
            Box::new(move |r: &Robot, q: &[f64], _: Option<f64>| c.deflected(r, q)) as Box<SagFn>
        });
        g.bench_function(format!("{model:?}").to_lowercase(), |b| {
            let mut rng = stream(2, "noise");
            b.iter(|| {
                measure_poses(
                    &robot,
                    black_box(&qs),
                    &tracker,
                    None,
                    sag.as_deref(),
                    None,
                    &mut rng,
                )
                .expect("measurement")
            })
        });
    }
    g.finish();

    let m = measure_poses(
        &robot,
        &qs,
        &tracker,
        Some(&outliers),
        None,
        None,
        &mut stream(3, "noise"),
    )
    .expect("measurement");
    let mut g = c.benchmark_group("register_50_points");
    g.bench_function("svd", |b| {
        b.iter(|| register_svd(black_box(&m.truth.true_points), &m.data.points, None).expect("svd"))
    });
    g.bench_function("wsvd", |b| {
        b.iter(|| register_wsvd(black_box(&m.truth.true_points), &m.data.points).expect("wsvd"))
    });
    g.finish();
}

criterion_group!(benches, simulate);
criterion_main!(benches);
