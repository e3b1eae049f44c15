//! The mass-free gravity basis ([`Param::Gravity`]) and a high harmonic order in the
//! identification problem: the analytic columns against finite differences of the model's
//! forward kinematics, and noise-free recovery of known coefficients.

use super::*;
use crate::robot::identifiability::identifiable_extension;
use crate::robot::loaded::loaded_fk;
use crate::robot::param_sets::identified_params_tool_first;

/// irb2600 with a tool offset; its identifiable kinematic parameters, then the gravity
/// basis and the 12th harmonic of joint 1, each term kept when the generic poses tell it
/// apart (joint 1's axis is vertical: no weight loads it).
fn setup() -> (Robot, Vec<Param>) {
    let mut nominal = builtin::irb2600();
    nominal.set(Param::Tool(0), 80.0);
    nominal.set(Param::Tool(2), 120.0);
    let mut params = identified_params_tool_first(&nominal, Measure::Position, true);
    let mut extra = crate::robot::gravity_basis::params(&nominal);
    extra.extend([Param::Harmonic(0, 22), Param::Harmonic(0, 23)]);
    let kept = identifiable_extension(&nominal, &params, &extra, Measure::Position);
    assert!(
        kept.iter().all(|p| !matches!(p, Param::Gravity(0, _))),
        "{kept:?}"
    );
    assert!(kept.contains(&Param::Gravity(1, 2)) && kept.contains(&Param::Harmonic(0, 23)));
    params.extend(kept);
    (nominal, params)
}

/// 0.2 mm and 1 mrad on the geometry; 0.5–1e-3 rad/(N·m) on the gravity basis (the sag of
/// a compliance of 5e-6 rad/(N·m) under a weight of 100–200 N); 0.3 mrad on the harmonic.
fn errors(params: &[Param]) -> DVector<Real> {
    DVector::from_iterator(
        params.len(),
        params.iter().enumerate().map(|(i, p)| match p {
            Param::Gravity(j, l) => 5e-4 * (1.0 + ((j + l) % 2) as Real) * [1.0, -1.0][l % 2],
            Param::Harmonic(..) => 3e-4 * [1.0, -1.0][i % 2],
            p if p.is_length() => 0.2 * [1.0, -1.0][i % 2],
            _ => 1e-3 * [1.0, -1.0][i % 2],
        }),
    )
}

/// `n` poses and the tool points of `truth` (its gravity basis and harmonics applied).
fn data(nominal: &Robot, truth: &Robot, n: usize) -> RobotData {
    let qs = uniform_joint_poses(nominal, n, &mut rng::stream(9, "gravity"));
    let chain = truth.chain();
    let points = qs
        .iter()
        .map(|q| loaded_fk(truth, &chain, q, 0.0).unwrap().pos)
        .collect();
    RobotData {
        qs,
        points,
        rotations: None,
    }
}

/// The columns of the problem at an estimate with every term non-zero, against central
/// differences of its residual. The torques' own change with the geometry is left out of
/// the analytic columns (second order): the tolerance covers it.
#[test]
fn gravity_and_high_order_columns_match_finite_differences() {
    let (nominal, params) = setup();
    let index: Vec<usize> = params.iter().map(|p| p.index(6)).collect();
    let truth = nominal.with_added(&index, errors(&params).as_slice());
    let d = data(&nominal, &truth, 9);
    let p = d.problem(&nominal, &params, Measure::Position).unwrap();
    let x0 = errors(&params) * 0.5;
    let (m, n) = (3 * d.qs.len(), params.len());
    let mut r = DVector::zeros(m);
    let mut j = DMatrix::zeros(m, n);
    p.evaluate(&x0, &mut r, &mut j);
    let (mut rp, mut rm, mut jj) = (r.clone(), r.clone(), j.clone());
    for (c, param) in params.iter().enumerate() {
        // A gravity coefficient moves the point by ~1e3 mm per unit.
        let fd = central(&p, &x0, c, (&mut rp, &mut rm, &mut jj));
        let scale = 1.0 + fd.amax();
        let err = (&fd - j.column(c)).amax();
        assert!(err < 5e-3 * scale, "{param}: |J − FD| = {err:e}");
        if matches!(param, Param::Gravity(..) | Param::Harmonic(..)) {
            assert!(fd.amax() > 1.0, "{param}: column ≈ 0");
        }
    }
    // At the nominal geometry (x = 0) the basis columns are exact: no geometry error for the
    // torques to depend on.
    let x0 = DVector::zeros(n);
    p.evaluate(&x0, &mut r, &mut j);
    for c in (0..n).filter(|&c| matches!(params[c], Param::Gravity(..))) {
        let fd = central(&p, &x0, c, (&mut rp, &mut rm, &mut jj));
        let err = (&fd - j.column(c)).amax();
        assert!(err < 1e-6 * (1.0 + fd.amax()), "{}: {err:e}", params[c]);
    }
}

#[test]
fn gravity_and_high_order_coefficients_are_recovered_noise_free() {
    let (nominal, params) = setup();
    let want = errors(&params);
    let index: Vec<usize> = params.iter().map(|p| p.index(6)).collect();
    let truth = nominal.with_added(&index, want.as_slice());
    assert!(crate::robot::gravity_basis::has_gravity(&truth));
    truth.check().unwrap();
    let d = data(&nominal, &truth, 300);
    let p = d.problem(&nominal, &params, Measure::Position).unwrap();
    let out = solve(&LmOptions::default(), &p, &DVector::zeros(params.len()));
    assert!(out.rms_residual < 1e-7, "rms {:e}", out.rms_residual);
    for (c, q) in params.iter().enumerate() {
        let tol = match q {
            Param::Gravity(..) => 1e-9,
            q if q.is_length() => 1e-6,
            _ => 1e-9,
        };
        assert!(
            (out.x[c] - want[c]).abs() < tol,
            "{q}: got {:e}, want {:e}",
            out.x[c],
            want[c]
        );
    }
    // robot.toml carries the model: written, read back, the same points.
    let got = p.robot_with(&out.x);
    let text = crate::robot::robot_to_toml(&got);
    assert!(
        text.contains("gravity = [") && text.contains("harmonics = ["),
        "{text}"
    );
    let dir = std::env::temp_dir().join(format!("calbench-gravity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("robot.toml");
    std::fs::write(&f, &text).unwrap();
    let back = crate::robot::read_robot_file(&f).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let (cb, ct) = (back.chain(), truth.chain());
    for q in &d.qs[..10] {
        let e = loaded_fk(&back, &cb, q, 0.0).unwrap().pos
            - loaded_fk(&truth, &ct, q, 0.0).unwrap().pos;
        assert!(e.norm() < 1e-6, "{e}");
    }
    // Without the basis the same data leave a residual the size of the sag.
    let kin: Vec<Param> = params
        .iter()
        .copied()
        .filter(|p| !matches!(p, Param::Gravity(..)))
        .collect();
    let pk = d.problem(&nominal, &kin, Measure::Position).unwrap();
    let out = solve(&LmOptions::default(), &pk, &DVector::zeros(kin.len()));
    assert!(out.rms_residual > 0.05, "rms {:e}", out.rms_residual);
}

#[test]
fn gravity_coefficients_only_where_their_weight_loads_the_joint() {
    let (nominal, _) = setup();
    let mut bad = nominal.clone();
    bad.set(Param::Gravity(4, 0), 1e-3);
    let issue = bad.check().unwrap_err();
    assert!(
        issue.place.contains("gravity") && issue.msg.contains("ge5"),
        "{issue:?}"
    );
    bad.set(Param::Gravity(4, 0), 0.0);
    bad.set(Param::Gravity(4, 2), 1.0);
    assert!(bad.check().unwrap_err().msg.contains("within"));
    bad.set(Param::Gravity(4, 2), 1e-3);
    assert!(bad.check().is_ok());
}

/// The central difference (step 1e-6) of `p`'s point residual along parameter `c` at `x0`:
/// the Jacobian column its analytic one must match; `scratch` the residual and Jacobian
/// buffers it evaluates into.
fn central(
    p: &RobotProblem,
    x0: &DVector<Real>,
    c: usize,
    (rp, rm, jj): (&mut DVector<Real>, &mut DVector<Real>, &mut DMatrix<Real>),
) -> DVector<Real> {
    let h = 1e-6;
    let mut xp = x0.clone();
    xp[c] += h;
    let mut xm = x0.clone();
    xm[c] -= h;
    p.evaluate(&xp, rp, jj);
    p.evaluate(&xm, rm, jj);
    (&*rm - &*rp) / (2.0 * h)
}
