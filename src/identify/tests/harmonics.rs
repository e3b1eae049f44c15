//! Joint-angle harmonics ([`Param::Harmonic`]) in the identification problem: the analytic
//! columns against finite differences, and noise-free recovery of known amplitudes.

use super::*;

/// irb2600 with a tool offset, its identifiable kinematic parameters and the harmonics of
/// every joint whose θ is among them.
fn setup() -> (Robot, Vec<Param>) {
    let (nominal, mut params) = irb2600_with_tool();
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
            p => geometry_error(i, p),
        }),
    )
}

#[test]
fn harmonic_columns_match_finite_differences() {
    let (nominal, params) = setup();
    assert!(params.iter().any(|p| matches!(p, Param::Harmonic(_, 3))));
    let truth = nominal.with_added(
        &params.iter().map(|p| p.index(6)).collect::<Vec<_>>(),
        errors(&params).as_slice(),
    );
    let d = loaded_points(&nominal, &truth, 9, (7, "harmonics"));
    let p = d.problem(&nominal, &params, Measure::Position).unwrap();
    let loaded = |q: &Param| matches!(q, Param::Harmonic(..));
    let errs = column_errors(
        &p,
        3 * d.qs.len(),
        &(errors(&params) * 0.5),
        &params,
        loaded,
    );
    for (param, e) in params.iter().zip(errs) {
        assert!(e < 1e-5, "{param}: |J − FD| = {e:e} of the column");
    }
}

#[test]
fn harmonic_amplitudes_are_recovered_noise_free() {
    let (nominal, params) = setup();
    let ls = LsOptions::default();
    let (truth, d, got) = recovered(
        (&nominal, &params),
        &errors(&params),
        (200, (7, "harmonics")),
        &ls,
        1e-8,
    );
    assert!(crate::robot::harmonics::has_harmonics(&truth));
    // The identified robot reproduces the truth through the model's forward kinematics;
    // without the harmonics the same data leave a residual the size of their effect.
    let harmonic = |p: &Param| matches!(p, Param::Harmonic(..));
    let (gap, rms) = gap_and_rms_without(&d, (&got, &truth), (&nominal, &params), harmonic, &ls);
    assert!(gap < 1e-8 && rms > 0.1, "gap {gap:e}, rms {rms:e}");
}

#[test]
fn harmonics_only_on_revolute_joints_and_in_range() {
    let (nominal, _) = setup();
    let d = loaded_points(&nominal, &nominal, 3, (7, "harmonics"));
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
