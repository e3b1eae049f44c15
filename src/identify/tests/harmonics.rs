//! Joint-angle harmonics ([`Param::Harmonic`]) in the identification problem: the analytic
//! columns against finite differences, and noise-free recovery of known amplitudes.

use super::*;
use crate::robot::loaded::loaded_fk;
use crate::robot::param_sets::identified_params_tool_first;

/// irb2600 with a tool offset, its identifiable kinematic parameters and the harmonics of
/// every joint whose θ is among them.
fn setup() -> (Robot, Vec<Param>) {
    let mut nominal = builtin::irb2600();
    nominal.set(Param::Tool(0), 80.0);
    nominal.set(Param::Tool(2), 120.0);
    let mut params = identified_params_tool_first(&nominal, Measure::Position, true);
    let joints: Vec<usize> = (0..nominal.dof())
        .filter(|&j| params.contains(&Param::Theta(j)))
        .collect();
    for j in joints {
        params.extend((0..4).map(|k| Param::Harmonic(j, k)));
    }
    (nominal, params)
}

/// Errors on every parameter: 0.2 mm and 1 mrad on the geometry, 0.5–2 mrad on the
/// harmonics (different per joint and term).
fn errors(params: &[Param]) -> DVector<Real> {
    DVector::from_iterator(
        params.len(),
        params.iter().enumerate().map(|(i, p)| match p {
            Param::Harmonic(j, k) => 5e-4 * (1.0 + ((j * 4 + k) % 4) as Real) * [1.0, -1.0][k % 2],
            p if p.is_length() => 0.2 * [1.0, -1.0][i % 2],
            _ => 1e-3 * [1.0, -1.0][i % 2],
        }),
    )
}

/// `n` poses and the tool points of `truth` (its harmonics applied) there.
fn data(nominal: &Robot, truth: &Robot, n: usize) -> RobotData {
    let qs = uniform_joint_poses(nominal, n, &mut rng::stream(7, "harmonics"));
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

#[test]
fn harmonic_columns_match_finite_differences() {
    let (nominal, params) = setup();
    assert!(params.iter().any(|p| matches!(p, Param::Harmonic(_, 3))));
    let truth = nominal.with_added(
        &params.iter().map(|p| p.index(6)).collect::<Vec<_>>(),
        errors(&params).as_slice(),
    );
    let d = data(&nominal, &truth, 9);
    let p = d.problem(&nominal, &params, Measure::Position).unwrap();
    let x0 = errors(&params) * 0.5;
    let (m, n) = (3 * d.qs.len(), params.len());
    let mut r = DVector::zeros(m);
    let mut j = DMatrix::zeros(m, n);
    p.evaluate(&x0, &mut r, &mut j);
    let h = 1e-6;
    let (mut rp, mut rm, mut jj) = (r.clone(), r.clone(), j.clone());
    for c in 0..n {
        let mut xp = x0.clone();
        xp[c] += h;
        let mut xm = x0.clone();
        xm[c] -= h;
        p.evaluate(&xp, &mut rp, &mut jj);
        p.evaluate(&xm, &mut rm, &mut jj);
        // r = measured − model, so the model's derivative is −∂r/∂x.
        let fd = (&rm - &rp) / (2.0 * h);
        let scale = 1.0 + fd.amax();
        let err = (&fd - j.column(c)).amax();
        assert!(err < 1e-5 * scale, "{}: |J − FD| = {err:e}", params[c]);
        if matches!(params[c], Param::Harmonic(..)) {
            assert!(fd.amax() > 1.0, "{}: column ≈ 0", params[c]);
        }
    }
}

#[test]
fn harmonic_amplitudes_are_recovered_noise_free() {
    let (nominal, params) = setup();
    let want = errors(&params);
    let index: Vec<usize> = params.iter().map(|p| p.index(6)).collect();
    let truth = nominal.with_added(&index, want.as_slice());
    assert!(crate::robot::harmonics::has_harmonics(&truth));
    let d = data(&nominal, &truth, 200);
    let p = d.problem(&nominal, &params, Measure::Position).unwrap();
    let out = solve(&LsOptions::default(), &p, &DVector::zeros(params.len()));
    assert!(out.rms_residual < 1e-8, "rms {:e}", out.rms_residual);
    for (c, q) in params.iter().enumerate() {
        let tol = if q.is_length() { 1e-6 } else { 1e-9 };
        assert!(
            (out.x[c] - want[c]).abs() < tol,
            "{q}: got {:e}, want {:e}",
            out.x[c],
            want[c]
        );
    }
    // The identified robot reproduces the truth through the model's forward kinematics.
    let got = p.robot_with(&out.x);
    let (cg, ct) = (got.chain(), truth.chain());
    for q in &d.qs[..10] {
        let e =
            loaded_fk(&got, &cg, q, 0.0).unwrap().pos - loaded_fk(&truth, &ct, q, 0.0).unwrap().pos;
        assert!(e.norm() < 1e-8);
    }
    // Without the harmonics the same data leave a residual the size of their effect.
    let kin: Vec<Param> = params
        .iter()
        .copied()
        .filter(|p| !matches!(p, Param::Harmonic(..)))
        .collect();
    let pk = d.problem(&nominal, &kin, Measure::Position).unwrap();
    let out = solve(&LsOptions::default(), &pk, &DVector::zeros(kin.len()));
    assert!(out.rms_residual > 0.1, "rms {:e}", out.rms_residual);
}

#[test]
fn harmonics_only_on_revolute_joints_and_in_range() {
    let (nominal, _) = setup();
    let d = data(&nominal, &nominal, 3);
    assert!(d
        .problem(&nominal, &[Param::Harmonic(6, 0)], Measure::Position)
        .is_err());
    let mut bad = nominal.clone();
    bad.set(Param::Harmonic(1, 2), 0.5);
    let issue = bad.check().unwrap_err();
    assert!(issue.place.contains("harmonics"), "{issue:?}");
    bad.set(Param::Harmonic(1, 2), 0.01);
    assert!(bad.check().is_ok());
}
