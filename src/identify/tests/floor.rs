//! The rounding floor ([`LeastSquares::rounding_floor`]): exact data from narrow poses end
//! converged, the chain's rounding lies below the floor, and noisy data never reach it.

use nalgebra::DVector;

use super::*;
use crate::robot::param_sets;

/// The robots and measures of the tests below.
fn cases() -> Vec<(Robot, Measure)> {
    vec![
        (builtin::irb2600(), Measure::Position),
        (builtin::irb2600(), Measure::Pose),
        (builtin::irb2600_mdh(), Measure::Position),
        (builtin::tx60(), Measure::Position),
        (ban_irb2600(), Measure::Position),
    ]
}

/// robots/ban-irb2600.toml, Ban's IRB 2600 with its short tool.
fn ban_irb2600() -> Robot {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/robots/ban-irb2600.toml");
    builtin::load(path).expect("robots/ban-irb2600.toml")
}

/// `n` poses within `span` degrees of (0°, 10°, 20°, …), the robot's joints all revolute.
fn narrow_poses(robot: &Robot, n: usize, span: Real, r: &mut Rng) -> Vec<Vec<Real>> {
    (0..n)
        .map(|_| {
            (0..robot.dof())
                .map(|k| (10.0 * k as Real + r.random_range(-span..span)).to_radians())
                .collect()
        })
        .collect()
}

/// The points (and for full poses the rotations) of `truth` at `qs`, exact but for the
/// rounding of their evaluation: by the loaded forward kinematics (as `calbench fk` and
/// `Robot.fk` compute them), whose rounding differs from the identification's chain walk.
fn exact(truth: &Robot, qs: Vec<Vec<Real>>, measure: Measure) -> RobotData {
    let chain = truth.chain();
    let frames: Vec<_> = qs
        .iter()
        .map(|q| crate::robot::loaded::loaded_fk(truth, &chain, q, 0.0).expect("fk"))
        .collect();
    RobotData {
        points: frames.iter().map(|f| f.pos).collect(),
        rotations: (measure == Measure::Pose).then(|| frames.iter().map(|f| f.rot).collect()),
        qs,
    }
}

/// The methods whose steps the floor ends on exact data: `ls` (first), `ridge` (ξ by the
/// double-h rule) and `igg3` with either σ0, at their defaults. With ξ by GCV or the L-curve,
/// chosen anew at each step on a residual near zero, the ridge may take many steps with the
/// floor or without; adaptive LM stops by its own rule, and fixed-damping LM contracts the
/// weak directions of poses this narrow too slowly for its 50 iterations
/// (`fixed_damping_contracts_the_weakest_direction_by_mu_over_sigma2_plus_mu`).
fn floored_methods() -> Vec<Box<dyn Solver>> {
    let mad = Robustness {
        sigma0: Sigma0::Mad,
        ..Default::default()
    };
    vec![
        Box::new(LsOptions::default()),
        Box::new(RidgeOptions::default()),
        Box::new(RobustOptions::default()),
        Box::new(RobustOptions {
            robust: mad,
            ..Default::default()
        }),
    ]
}

/// Exact data (evaluated apart from the identification's chain walk, so rounding apart)
/// from poses within ±2° of (0°, 10°, …), errors of 0.2 mm and 1 mrad on the parameters
/// `calbench identify` identifies, or none (the fit starts at the truth): `ls`, `ridge` and
/// `igg3` end converged within 10 iterations, `ls` reproducing the data to 1e-8 mm.
///
/// With the step rule alone they take more than 20 in some case (on Ban's IRB 2600 with its
/// short tool, the set's condition number near 1e7): there each step of 1e-8 or more is
/// rounding noise that falls below ε = 1e-9 only by chance. And from the truth, `igg3` with
/// σ0 by MAD weighed the rounding noise as residuals (σ0 at 1e-13 mm is not below 1e-9 of a
/// start that is itself rounding) and ended `singular`, rank-deficient or at
/// `max-iterations` on full poses.
#[test]
fn exact_data_from_narrow_poses_end_converged() {
    let mut step_rule_alone = 0;
    for (nominal, measure) in cases() {
        for (seed, scale) in (0..3).flat_map(|s| [(s, 1.0), (s, 0.0)]) {
            let mut r = rng::from_seed(40 + seed);
            let qs = narrow_poses(&nominal, 60, 2.0, &mut r);
            let params = param_sets::identified_params_tool_first(&nominal, measure, false);
            let pairs: Vec<(Param, Real)> = params
                .iter()
                .enumerate()
                .map(|(i, p)| (*p, scale * geometry_error(i, p)))
                .collect();
            let data = exact(&nominal.with_errors(&pairs), qs, measure);
            let p = data.problem(&nominal, &params, measure).expect("problem");
            let x0 = DVector::zeros(params.len());
            let case = format!("{} {measure:?} seed {seed} errors ×{scale}", nominal.name);
            for (k, m) in floored_methods().iter().enumerate() {
                let out = solve(m.as_ref(), &Whole { p: &p, floor: true }, &x0);
                assert_eq!(out.termination, Termination::Converged, "{case}: {m:?}");
                assert!(out.iterations <= 10, "{case}: {m:?}: {}", out.iterations);
                if k == 0 {
                    assert!(out.rms_residual < 1e-8, "{case}: {}", out.rms_residual);
                }
                let alone = solve(
                    m.as_ref(),
                    &Whole {
                        p: &p,
                        floor: false,
                    },
                    &x0,
                );
                step_rule_alone = step_rule_alone.max(alone.iterations);
            }
        }
    }
    assert!(
        step_rule_alone > 20,
        "the step rule alone: {step_rule_alone}"
    );
}

/// The chain's own rounding at the truth, on narrow and on uniform poses, lies at least four
/// times below [`LeastSquares::rounding_floor`] per component (a 16th of its cost).
#[test]
fn the_chain_rounds_below_the_floor() {
    for (nominal, measure) in cases() {
        let mut r = rng::from_seed(3);
        for qs in [
            narrow_poses(&nominal, 60, 2.0, &mut r),
            uniform_joint_poses(&nominal, 200, &mut r),
        ] {
            let params = nominal.params();
            let data = exact(&nominal, qs, measure);
            let p = data.problem(&nominal, &params, measure).expect("problem");
            let size = p.size();
            let mut res = DVector::zeros(size.rows());
            let mut j = DMatrix::zeros(size.rows(), size.params);
            p.evaluate(&DVector::zeros(size.params), &mut res, &mut j);
            let floor = p.rounding_floor() * size.points as Real;
            let cost = res.norm_squared();
            assert!(
                cost <= floor / 16.0,
                "{} {measure:?}: cost {cost:e} against the floor {floor:e}",
                nominal.name
            );
        }
    }
}

/// With 1 nm of noise no fit reaches the floor: every method gives the same estimate to the
/// bit, the same iterations and the same ending with the floor as with the step rule alone.
#[test]
fn noisy_data_never_reach_the_floor() {
    let s = paper_setup();
    let mut r = rng::from_seed(8);
    let data = measure(
        &s.truth,
        uniform_joint_poses(&s.nominal, 50, &mut r),
        1e-6,
        &mut r,
    );
    let p = data
        .problem(&s.nominal, &s.params, Measure::Position)
        .expect("problem");
    let x0 = DVector::zeros(s.params.len());
    for m in all_methods() {
        let with = solve(m.as_ref(), &Whole { p: &p, floor: true }, &x0);
        let without = solve(
            m.as_ref(),
            &Whole {
                p: &p,
                floor: false,
            },
            &x0,
        );
        assert_eq!(with.x, without.x, "{m:?}");
        assert_eq!(with.iterations, without.iterations, "{m:?}");
        assert_eq!(with.termination, without.termination, "{m:?}");
    }
}
