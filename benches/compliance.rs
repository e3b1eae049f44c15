//! Deflected tool frame per pose: linear small-deflection model vs the rapier multibody.

use calbench::numeric::rng::stream;
use calbench::robot::builtin::{builtin, load};
use calbench::robot::sampling::uniform_joint_poses;
use calbench::sim::sag::{Compliance, ComplianceModel, ComplianceSettings};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let robot = load("irb2600").expect("built-in robot");
    let chain = robot.chain();
    let qs = uniform_joint_poses(&robot, 64, &mut stream(1, "bench-compliance"));
    for (name, model) in [
        ("linear", ComplianceModel::Linear),
        ("rapier", ComplianceModel::Rapier),
    ] {
        let s = ComplianceSettings {
            model,
            payload_kg: 5.0,
            ..Default::default()
        };
        let comp = Compliance::new(&s, &robot, builtin("irb2600"))
            .expect("valid settings")
            .expect("a model");
        let mut i = 0;
        c.bench_function(&format!("compliance/deflected/{name}/irb2600"), |b| {
            b.iter(|| {
                i = (i + 1) % qs.len();
                black_box(comp.deflected_with_chain(&robot, &chain, black_box(&qs[i])))
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
