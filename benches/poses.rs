//! DETMAX-IDE choosing 60 of 1000 candidates on the IRB2600 (identifiable parameters,
//! position data), and DETMAX alone.

use calbench::measurement::Measure;
use calbench::numeric::rng::from_seed;
use calbench::poses::{select, RobotPoseModel, SelectOptions, Strategy};
use calbench::robot::identifiability::analyse;
use calbench::robot::sampling::uniform_joint_poses;
use calbench::robot::Param;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

fn bench(c: &mut Criterion) {
    let mut robot = calbench::robot::builtin::irb2600();
    robot.set(Param::Tool(0), 80.0);
    robot.set(Param::Tool(2), 120.0);
    let qs = uniform_joint_poses(&robot, 80, &mut from_seed(11));
    let params = analyse(&robot, &robot.params(), &qs, Measure::Position).identifiable;
    let model = RobotPoseModel::new(&robot, &params, Measure::Position);
    let cands = uniform_joint_poses(&robot, 1000, &mut from_seed(7));
    let opts = SelectOptions::new(60);
    let mut g = c.benchmark_group("poses_irb2600_60_of_1000");
    g.sample_size(10);
    for strategy in [Strategy::Detmax, Strategy::DetmaxIde] {
        g.bench_with_input(
            BenchmarkId::from_parameter(strategy.as_str()),
            &strategy,
            |b, &s| b.iter(|| select(&model, &cands, s, &opts, &mut from_seed(1)).unwrap()),
        );
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
