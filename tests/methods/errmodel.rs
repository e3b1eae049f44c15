//! Qiao 2021's three pose-error models (§2.2–2.3, §4.2) and accuracy figures (§4.1–4.2).

use approx::assert_relative_eq;
use calbench::identify::qiao::error_models::{
    acpe_acae, identify, pose_errors, residual_and_jacobian, stack, ErrorModel,
};
use calbench::identify::qiao::DEFAULT_K as K;
use calbench::numeric::rng::stream;
use calbench::numeric::{rot_x, Frame, Real, Vec3};
use calbench::robot::builtin::tx60_qiao_params;
use calbench::robot::{Param, Robot};
use nalgebra::DMatrix;
use rand_distr::{Distribution, Normal};

use crate::common::{alternating_errors, qiao_cube_poses};

fn setup(n: usize, seed: u64) -> (Robot, Vec<Vec<Real>>) {
    let nominal = calbench::robot::builtin::load("tx60").unwrap();
    let qs = qiao_cube_poses(&nominal, n, &mut stream(seed, "poses"));
    (nominal, qs)
}

#[test]
fn jacobians_are_minus_the_derivative_of_the_residuals() {
    // Independent truth: central differences of each model's residual over the parameters,
    // both where the model pose meets the measured one and away from it (a linearisation
    // point 0.5 mm / 0.005 rad off), so that iterated Gauss–Newton is exact for every model.
    let (nominal, qs) = setup(3, 1);
    let params = tx60_qiao_params();
    let real = nominal.with_errors(&alternating_errors(&params, 0.3, 0.003));
    let at = nominal.with_errors(&alternating_errors(&params, -0.2, -0.002));
    let h = 1e-6;
    for model in ErrorModel::ALL {
        for q in &qs {
            for m in [at.fk(q), real.fk(q)] {
                let rows = model.rows();
                let mut r = vec![0.0; rows];
                let mut j = DMatrix::zeros(rows, params.len());
                residual_and_jacobian(model, &at, &params, q, &m, &mut r, &mut j).unwrap();
                for (c, p) in params.iter().enumerate() {
                    let (mut rp, mut rm) = (vec![0.0; rows], vec![0.0; rows]);
                    let mut scratch = DMatrix::zeros(rows, params.len());
                    let plus = at.with_errors(&[(*p, h)]);
                    let minus = at.with_errors(&[(*p, -h)]);
                    residual_and_jacobian(model, &plus, &params, q, &m, &mut rp, &mut scratch)
                        .unwrap();
                    residual_and_jacobian(model, &minus, &params, q, &m, &mut rm, &mut scratch)
                        .unwrap();
                    for k in 0..rows {
                        let fd = -(rp[k] - rm[k]) / (2.0 * h);
                        assert!(
                            (fd - j[(k, c)]).abs() < 1e-5 * (1.0 + fd.abs()),
                            "{model} {p} row {k}: analytic {} fd {fd}",
                            j[(k, c)]
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn residuals_vanish_on_the_model_pose() {
    let (nominal, qs) = setup(2, 2);
    let params = tx60_qiao_params();
    for model in ErrorModel::ALL {
        let measured: Vec<Frame> = qs.iter().map(|q| nominal.fk(q)).collect();
        let (r, j) = stack(model, &nominal, &params, &qs, &measured, K).unwrap();
        assert_eq!(r.len(), model.rows() * 2);
        assert_eq!(j.shape(), (model.rows() * 2, 24));
        assert!(r.amax() < 1e-9, "{model}");
    }
}

/// One linearised step of each model from the nominal robot; returns the estimates and the
/// validation ACPE/ACAE of each.
#[allow(clippy::type_complexity)]
fn one_step(len: Real, ang: Real) -> (Vec<Vec<Real>>, Vec<(Real, Real)>, Vec<Real>) {
    let (nominal, qs) = setup(50, 3);
    let (_, val) = setup(30, 4);
    let params = tx60_qiao_params();
    let errs = alternating_errors(&params, len, ang);
    let real = nominal.with_errors(&errs);
    let measured: Vec<Frame> = qs.iter().map(|q| real.fk(q)).collect();
    let truth_val: Vec<Frame> = val.iter().map(|q| real.fk(q)).collect();
    let mut xs = Vec::new();
    let mut acc = Vec::new();
    for model in ErrorModel::ALL {
        let fit = identify(model, &nominal, &params, &qs, &measured, 1, K, None).unwrap();
        let model_val: Vec<Frame> = val.iter().map(|q| fit.robot.fk(q)).collect();
        acc.push(acpe_acae(&truth_val, &model_val).unwrap());
        xs.push(fit.x);
    }
    (xs, acc, errs.iter().map(|e| e.1).collect())
}

fn rel(a: &[Real], b: &[Real]) -> Real {
    let d: Real = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<Real>()
        .sqrt();
    d / b.iter().map(|y| y * y).sum::<Real>().sqrt()
}

#[test]
fn models_agree_to_first_order_and_differ_for_large_errors() {
    // Small errors (0.001 mm / 1e-5 rad): every one-step estimate is within a relative
    // 1e-3 of the truth, so the models agree to first order.
    let (xs, _, truth) = one_step(1e-3, 1e-5);
    for (m, x) in ErrorModel::ALL.iter().zip(&xs) {
        assert!(rel(x, &truth) < 1e-3, "{m}: {}", rel(x, &truth));
    }
    // Halving the errors roughly quarters the one-step error (second order).
    let (xs_a, _, ta) = one_step(0.4, 0.004);
    let (xs_b, _, tb) = one_step(0.2, 0.002);
    for m in 0..3 {
        let (ea, eb) = (rel(&xs_a[m], &ta), rel(&xs_b[m], &tb));
        assert!(ea / eb > 1.6 && ea / eb < 2.5, "{m}: {ea} {eb}");
    }
    // Large errors (2 mm / 0.02 rad): the one-step estimates differ between models.
    let (xs, acc, truth) = one_step(2.0, 0.02);
    let spread = (0..3)
        .flat_map(|a| (a + 1..3).map(move |b| (a, b)))
        .map(|(a, b)| rel(&xs[a], &xs[b]))
        .fold(0.0, Real::max);
    eprintln!("largest relative difference between one-step estimates: {spread:.3e}");
    assert!(spread > 1e-6, "{spread}");
    for (m, (x, (p, o))) in ErrorModel::ALL.iter().zip(xs.iter().zip(&acc)) {
        eprintln!(
            "{m}: parameter error {:.4} (relative), validation ACPE {p:.4} mm ACAE {o:.4} deg",
            rel(x, &truth)
        );
    }
}

/// Qiao §4.2's comparison on simulated tracker data: mean validation APE (mm) and AAE (deg)
/// over `draws` error draws (normal, σ `len` mm / `ang` rad on the 24 parameters) of
/// models 1 and 2 as linear models at the nominal parameters (one step) and model 3 as
/// identification on the forward kinematics (Gauss–Newton to convergence), with measurement
/// noise σ `sp` mm per axis and `sa` rad per axis.
fn qiao_comparison(len: Real, ang: Real, sp: Real, sa: Real, draws: u64) -> [(Real, Real); 3] {
    let (nominal, _) = setup(1, 0);
    let params = tx60_qiao_params();
    let g = Normal::new(0.0, 1.0).unwrap();
    let runs = [
        (ErrorModel::CoordinateTransfer, 1),
        (ErrorModel::Differential, 1),
        (ErrorModel::DirectFk, 10),
    ];
    let mut out = [(0.0, 0.0); 3];
    for draw in 0..draws {
        let mut rng = stream(draw, "qiao-comparison");
        let (qs, val) = (
            qiao_cube_poses(&nominal, 50, &mut rng),
            qiao_cube_poses(&nominal, 30, &mut rng),
        );
        let errs: Vec<(Param, Real)> = params
            .iter()
            .map(|p| {
                (
                    *p,
                    g.sample(&mut rng) * if p.is_length() { len } else { ang },
                )
            })
            .collect();
        let real = nominal.with_errors(&errs);
        let mut v3 = || Vec3::new(g.sample(&mut rng), g.sample(&mut rng), g.sample(&mut rng));
        let measured: Vec<Frame> = qs
            .iter()
            .map(|q| {
                let f = real.fk(q);
                let turn = nalgebra::Rotation3::from_scaled_axis(v3() * sa).into_inner();
                Frame {
                    rot: turn * f.rot,
                    pos: f.pos + v3() * sp,
                }
            })
            .collect();
        let truth: Vec<Frame> = val.iter().map(|q| real.fk(q)).collect();
        for (o, (model, steps)) in out.iter_mut().zip(runs) {
            let fit = identify(model, &nominal, &params, &qs, &measured, steps, K, None).unwrap();
            let model_val: Vec<Frame> = val.iter().map(|q| fit.robot.fk(q)).collect();
            let (p, a) = acpe_acae(&truth, &model_val).unwrap();
            o.0 += p / draws as Real;
            o.1 += a / draws as Real;
        }
    }
    out
}

#[test]
fn models_rank_as_qiao_reports() {
    // Qiao §4.2: APE/AAE 0.1035 mm / 0.1642° (coordinate transfer, model 1), 0.1009 / 0.1565
    // (differential, model 2), 0.0975 / 0.0986 (forward kinematics, model 3). Here with a
    // tracker's noise (15 µm, 0.005° per axis) and errors of 0.3 mm / 0.003 rad.
    let [ct, diff, direct] = qiao_comparison(0.3, 0.003, 0.015, 0.005f64.to_radians(), 20);
    eprintln!("APE/AAE: coordinate transfer {ct:?}, differential {diff:?}, direct {direct:?}");
    assert!(
        ct.0 > diff.0 && diff.0 > direct.0,
        "APE {ct:?} {diff:?} {direct:?}"
    );
    assert!(
        ct.1 > diff.1 && diff.1 > direct.1,
        "AAE {ct:?} {diff:?} {direct:?}"
    );
    // Without noise the forward-kinematics identification neglects nothing and is exact;
    // the linear models keep their second-order error.
    let [ct, diff, direct] = qiao_comparison(0.3, 0.003, 0.0, 0.0, 3);
    assert!(direct.0 < 1e-8 && direct.1 < 1e-8, "{direct:?}");
    assert!(ct.0 > 1e-4 && diff.0 > 1e-4, "{ct:?} {diff:?}");
}

#[test]
fn iterated_models_recover_noise_free_errors() {
    let (nominal, qs) = setup(50, 5);
    let params = tx60_qiao_params();
    let errs = alternating_errors(&params, 0.5, 0.005);
    let real = nominal.with_errors(&errs);
    let measured: Vec<Frame> = qs.iter().map(|q| real.fk(q)).collect();
    for model in ErrorModel::ALL {
        let fit = identify(model, &nominal, &params, &qs, &measured, 5, K, None).unwrap();
        for (x, (p, e)) in fit.x.iter().zip(&errs) {
            assert!((x - e).abs() < 1e-8, "{model} {p}: {x} vs {e}");
        }
    }
}

#[test]
fn accuracy_figures_by_hand() {
    let truth = vec![
        Frame::identity(),
        Frame::from_xyz_rpy([10.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
    ];
    let shifted: Vec<Frame> = truth
        .iter()
        .map(|f| Frame {
            rot: f.rot,
            pos: f.pos + Vec3::new(3.0, 4.0, 0.0),
        })
        .collect();
    let turned: Vec<Frame> = truth
        .iter()
        .map(|f| Frame {
            rot: rot_x(0.01) * f.rot,
            pos: f.pos,
        })
        .collect();
    let (p, a) = acpe_acae(&truth, &shifted).unwrap();
    assert_relative_eq!(p, 5.0, epsilon = 1e-12);
    assert_relative_eq!(a, 0.0, epsilon = 1e-12);
    let (p, a) = acpe_acae(&truth, &turned).unwrap();
    assert_relative_eq!(p, 0.0, epsilon = 1e-12);
    assert_relative_eq!(a, 0.01f64.to_degrees(), epsilon = 1e-10);
    // Angles wrap: yaw 179° against −179° is 2° apart.
    let t = [Frame::from_xyz_rpy(
        [0.0; 3],
        [0.0, 0.0, 179f64.to_radians()],
    )];
    let m = [Frame::from_xyz_rpy(
        [0.0; 3],
        [0.0, 0.0, -179f64.to_radians()],
    )];
    assert_relative_eq!(acpe_acae(&t, &m).unwrap().1, 2.0, epsilon = 1e-9);
    let s = pose_errors(&truth, &[shifted, turned]).unwrap();
    assert_relative_eq!(s.ape, 2.5, epsilon = 1e-12);
    assert_relative_eq!(s.aae, 0.5 * 0.01f64.to_degrees(), epsilon = 1e-10);
    assert_eq!(s.acpe_mm.len(), 2);
    assert!(pose_errors(&truth, &[]).is_err());
    assert!(acpe_acae(&truth, &truth[..1]).is_err());
}

#[test]
fn model_names_round_trip() {
    for m in ErrorModel::ALL {
        assert_eq!(
            calbench::robot::names::parse::<ErrorModel>("error_model", m.as_str()).unwrap(),
            m
        );
    }
    assert!(calbench::robot::names::parse::<ErrorModel>("error_model", "dh").is_err());
}

#[test]
fn harness_validation_errors_are_qiao_acpe_and_acae() {
    // The harness's per-pose errors average to Qiao's ACPE and ACAE (docs/formats.md).
    let (nominal, qs) = setup(10, 6);
    let params = tx60_qiao_params();
    let real = nominal.with_errors(&alternating_errors(&params, 0.3, 0.003));
    let truth: Vec<Frame> = qs.iter().map(|q| real.fk(q)).collect();
    let model: Vec<Frame> = qs.iter().map(|q| nominal.fk(q)).collect();
    let e = calbench::calibrate::validation_errors(&nominal, &qs, None, &truth).unwrap();
    let (p, a) = (e.mm, e.attitude_deg);
    let (acpe, acae) = acpe_acae(&truth, &model).unwrap();
    let mean = |v: &[Real]| v.iter().sum::<Real>() / v.len() as Real;
    assert_relative_eq!(mean(&p), acpe, epsilon = 1e-12);
    assert_relative_eq!(mean(&a), acae, epsilon = 1e-12);
    assert!(acae > 0.01);
}
