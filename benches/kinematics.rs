//! Forward kinematics and the 50-pose identification Jacobian of a 6-axis arm.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::DMatrix;
use std::hint::black_box;

use calbench::robot::jacobian::{pose_rows, Columns};

use calbench::measurement::Measure;
use calbench::numeric::rng;
use calbench::robot::builtin;
use calbench::robot::sampling::uniform_joint_poses;

fn kinematics(c: &mut Criterion) {
    let robot = builtin::irb2600();
    let chain = robot.chain();
    let mut g = rng::stream(1, "bench");
    let qs = uniform_joint_poses(&robot, 50, &mut g);

    c.bench_function("fk/irb2600", |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) % qs.len();
            black_box(chain.fk(black_box(&qs[i])))
        })
    });

    let cols = Columns::new(&robot.params(), robot.dof());
    let mut group = c.benchmark_group("jacobian/irb2600");
    for measure in [Measure::Position, Measure::Pose] {
        let rows = measure.rows();
        let mut j = DMatrix::zeros(rows * qs.len(), cols.len());
        group.bench_with_input(
            BenchmarkId::new(format!("{measure:?}").to_lowercase(), "50 poses"),
            &measure,
            |b, &measure| {
                b.iter(|| {
                    for (i, q) in qs.iter().enumerate() {
                        pose_rows(&chain, &cols, q, measure, &mut j, rows * i);
                    }
                    black_box(&j);
                })
            },
        );
    }
    group.finish();
}

criterion_group!(benches, kinematics);
criterion_main!(benches);
