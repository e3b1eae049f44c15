//! The mass-free gravity basis ([`Param::Gravity`]) and a high harmonic order in the
//! identification problem: the analytic columns against finite differences of the model's
//! forward kinematics, and noise-free recovery of known coefficients.

use super::*;
use crate::robot::identifiability::identifiable_extension;

/// irb2600 with a tool offset; its identifiable kinematic parameters, then the gravity
/// basis and the 12th harmonic of joint 1, each term kept when the generic poses tell it
/// apart (joint 1's axis is vertical: no weight loads it).
fn setup() -> (Robot, Vec<Param>) {
    let (nominal, mut params) = irb2600_with_tool();
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
            p => geometry_error(i, p),
        }),
    )
}

/// The columns of the problem at an estimate with every term non-zero, against central
/// differences of its residual. The torques' own change with the geometry is left out of
/// the analytic columns (second order): the tolerance covers it.
#[test]
fn gravity_and_high_order_columns_match_finite_differences() {
    let (nominal, params) = setup();
    let index: Vec<usize> = params.iter().map(|p| p.index(6)).collect();
    let truth = nominal.with_added(&index, errors(&params).as_slice());
    let d = loaded_points(&nominal, &truth, 9, (9, "gravity"));
    let p = d.problem(&nominal, &params, Measure::Position).unwrap();
    let rows = 3 * d.qs.len();
    // A gravity coefficient moves the point by ~1e3 mm per unit.
    let loaded = |q: &Param| matches!(q, Param::Gravity(..) | Param::Harmonic(..));
    let errs = column_errors(&p, rows, &(errors(&params) * 0.5), &params, loaded);
    for (param, e) in params.iter().zip(errs) {
        assert!(e < 5e-3, "{param}: |J − FD| = {e:e} of the column");
    }
    // At the nominal geometry (x = 0) the basis columns are exact: no geometry error for the
    // torques to depend on.
    let at_nominal = column_errors(&p, rows, &DVector::zeros(params.len()), &params, |_| false);
    for (param, e) in params.iter().zip(at_nominal) {
        assert!(
            !matches!(param, Param::Gravity(..)) || e < 1e-6,
            "{param}: {e:e}"
        );
    }
}

#[test]
fn gravity_and_high_order_coefficients_are_recovered_noise_free() {
    let (nominal, params) = setup();
    let lm = LmOptions::default();
    let (truth, d, got) = recovered(
        (&nominal, &params),
        &errors(&params),
        (300, (9, "gravity")),
        &lm,
        1e-7,
    );
    assert!(crate::robot::gravity_basis::has_gravity(&truth));
    truth.check().unwrap();
    // robot.toml carries the model: written, read back, the same points.
    let text = crate::robot::robot_to_toml(&got);
    assert!(
        text.contains("gravity = [") && text.contains("harmonics = ["),
        "{text}"
    );
    let dir = crate::test_dir("gravity");
    let f = dir.join("robot.toml");
    std::fs::write(&f, &text).unwrap();
    let back = crate::robot::read_robot_file(&f).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    // Without the basis the same data leave a residual the size of the sag.
    let gravity = |p: &Param| matches!(p, Param::Gravity(..));
    let robots = (&nominal, &params[..]);
    let (gap, rms) = gap_and_rms_without(&d, (&back, &truth), robots, gravity, &lm);
    assert!(gap < 1e-6 && rms > 0.05, "gap {gap:e}, rms {rms:e}");
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
    bad.set(Param::Gravity(4, 2), 1.5);
    assert!(bad.check().unwrap_err().msg.contains("within"));
    bad.set(Param::Gravity(4, 2), 1e-3);
    assert!(bad.check().is_ok());
}
