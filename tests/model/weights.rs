//! Per-point weights from the measurement file's standard deviations (`sigma_mm`): weighted
//! least squares must equal the unweighted fit of the data with the heavier point repeated
//! (a point of σ/√2 carries the information of two points of σ), for the Jacobian methods,
//! the pose-error models and Qiao's fitness of the searches.

use calbench::calibrate::{calibrate, Registration};
use calbench::identify::qiao::error_models::{identify, ErrorModel};
use calbench::identify::qiao::MetaProblem;
use calbench::identify::{method_by_name, MethodSpec};
use calbench::measurement::Measure;
use calbench::measurement::Measurements;
use calbench::numeric::rng;
use calbench::numeric::{quaternion, Frame, Real, Vec3};
use calbench::robot::param_sets::identified_params;
use calbench::robot::sampling::uniform_joint_poses;
use calbench::robot::{Param, Robot};
use rand::Rng as _;

/// The IRB2600 with small errors on its identifiable parameters, 30 poses measured with a
/// deterministic pseudo-noise of ~0.05 mm, in the base frame.
fn noisy_data(pose: bool) -> (Robot, Vec<Param>, Measurements) {
    let nominal = calbench::robot::builtin::irb2600();
    let measure = if pose {
        Measure::Pose
    } else {
        Measure::Position
    };
    let params = identified_params(&nominal, measure, false);
    let errors: Vec<(Param, Real)> = params
        .iter()
        .map(|&p| (p, if p.is_length() { 0.2 } else { 0.001 }))
        .collect();
    let truth = nominal.with_errors(&errors);
    let mut r = rng::from_seed(7);
    let qs = uniform_joint_poses(&nominal, 30, &mut r);
    let frames: Vec<Frame> = qs.iter().map(|q| truth.fk(q)).collect();
    let points = frames
        .iter()
        .map(|f| f.pos + Vec3::new(r.random(), r.random(), r.random()) * 0.1)
        .collect();
    let quats = pose.then(|| frames.iter().map(|f| quaternion(&f.rot)).collect());
    let data = Measurements {
        qs,
        points,
        quats,
        sigma_mm: None,
        payload_kg: None,
    };
    (nominal, params, data)
}

/// `data` with point 0 given σ = 1/√2 and the others σ = 1, and `data` with point 0 repeated.
fn weighted_and_repeated(data: &Measurements) -> (Measurements, Measurements) {
    let mut weighted = data.clone();
    let mut sigma = vec![1.0; data.len()];
    sigma[0] = 0.5f64.sqrt();
    weighted.sigma_mm = Some(sigma);
    let mut repeated = data.clone();
    repeated.qs.push(data.qs[0].clone());
    repeated.points.push(data.points[0]);
    if let Some(q) = &mut repeated.quats {
        q.push(q[0]);
    }
    (weighted, repeated)
}

fn fit(nominal: &Robot, params: &[Param], data: &Measurements, spec: &MethodSpec) -> Vec<Real> {
    let c = calibrate(
        nominal,
        params,
        data,
        Registration::Known,
        &Frame::identity(),
        spec,
        &mut rng::from_seed(1),
    )
    .unwrap();
    c.identified.x.iter().copied().collect()
}

#[test]
fn weighted_least_squares_equals_the_repeated_point() {
    let (nominal, params, data) = noisy_data(false);
    let (weighted, repeated) = weighted_and_repeated(&data);
    for name in ["ls", "ridge", "lm"] {
        let mut spec = method_by_name(name).unwrap();
        if name == "ridge" {
            // A fixed ξ = 0: the ridge is plain least squares whatever the weights' scale.
            spec = MethodSpec::from_table(&toml::from_str("name = \"ridge\"\nxi = 0").unwrap())
                .unwrap();
        }
        if name == "lm" {
            spec = MethodSpec::from_table(
                &toml::from_str("name = \"lm\"\nadaptive = true\neps = 1e-12").unwrap(),
            )
            .unwrap();
        }
        let a = fit(&nominal, &params, &weighted, &spec);
        let b = fit(&nominal, &params, &repeated, &spec);
        let plain = fit(&nominal, &params, &data, &spec);
        let (mut diff, mut moved) = (0.0f64, 0.0f64);
        for ((x, y), z) in a.iter().zip(&b).zip(&plain) {
            diff = diff.max((x - y).abs());
            moved = moved.max((x - z).abs());
        }
        assert!(
            diff < 1e-8,
            "{name}: weighted and repeated differ by {diff}"
        );
        assert!(
            moved > 1e3 * diff.max(1e-12),
            "{name}: the weights changed nothing ({moved})"
        );
    }
}

#[test]
fn weighted_pose_error_model_equals_the_repeated_pose() {
    let (nominal, params, data) = noisy_data(true);
    let frames = |d: &Measurements| -> Vec<Frame> {
        d.points
            .iter()
            .zip(d.quats.as_ref().unwrap())
            .map(|(p, q)| Frame {
                rot: calbench::numeric::quaternion_matrix(q),
                pos: *p,
            })
            .collect()
    };
    let (_, repeated) = weighted_and_repeated(&data);
    let mut w = vec![1.0; data.len()];
    w[0] = 2.0;
    let m = ErrorModel::DirectFk;
    let a = identify(
        m,
        &nominal,
        &params,
        &data.qs,
        &frames(&data),
        5,
        100.0,
        Some(&w),
    )
    .unwrap();
    let b = identify(
        m,
        &nominal,
        &params,
        &repeated.qs,
        &frames(&repeated),
        5,
        100.0,
        None,
    )
    .unwrap();
    for (x, y) in a.x.iter().zip(&b.x) {
        assert!((x - y).abs() < 1e-9, "{x} vs {y}");
    }
}

#[test]
fn weighted_fitness_equals_the_repeated_pose() {
    let (nominal, params, data) = noisy_data(true);
    let (_, repeated) = weighted_and_repeated(&data);
    let rots = |d: &Measurements| {
        d.quats
            .as_ref()
            .map(|q| q.iter().map(calbench::numeric::quaternion_matrix).collect())
    };
    // Qiao's fitness is a sum of norms: a pose counted twice is a pose scaled by 2 = √4.
    let mut w = vec![1.0; data.len()];
    w[0] = 4.0;
    let weighted = MetaProblem::new(
        &nominal,
        params.clone(),
        data.qs.clone(),
        data.points.clone(),
        rots(&data),
        100.0,
    )
    .unwrap()
    .with_weights(Some(&w))
    .unwrap();
    let twice = MetaProblem::new(
        &nominal,
        params.clone(),
        repeated.qs.clone(),
        repeated.points.clone(),
        rots(&repeated),
        100.0,
    )
    .unwrap();
    let mut r = rng::from_seed(3);
    for _ in 0..5 {
        let x: Vec<Real> = params.iter().map(|_| r.random_range(-0.01..0.01)).collect();
        let (a, b) = (weighted.fitness(&x), twice.fitness(&x));
        assert!((a - b).abs() <= 1e-9 * b, "{a} vs {b}");
    }
    assert!(
        MetaProblem::new(&nominal, params, data.qs, data.points, None, 1.0)
            .unwrap()
            .with_weights(Some(&[1.0]))
            .is_err()
    );
}
