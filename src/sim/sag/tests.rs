//! Tests of the gravity sag models.

use super::*;
use crate::numeric::rng::stream;
use crate::robot::builtin::{builtin, load};
use crate::robot::compliance::GRAVITY;
use crate::robot::sampling::uniform_joint_poses;
use crate::robot::{Convention, Joint, Param, Units};
use approx::assert_relative_eq;

fn settings(model: ComplianceModel) -> ComplianceSettings {
    ComplianceSettings {
        model,
        ..Default::default()
    }
}

fn built(name: &str, s: &ComplianceSettings) -> (Robot, Compliance) {
    let robot = load(name).unwrap();
    let c = Compliance::new(s, &robot, builtin(name)).unwrap().unwrap();
    (robot, c)
}

/// One revolute joint about world z turned to horizontal by α = 90°: a single link of
/// length `2l` (mass point at l) along the DH x axis, tool at 2l.
fn pendulum(l: Real) -> Robot {
    let mut values = vec![0.0; crate::robot::value_count(1)];
    // Base turned so that joint 1's axis (base z) is horizontal (world −y... see below).
    values[Param::A(0).index(1)] = 2.0 * l;
    let mut r = Robot {
        name: "pendulum".into(),
        convention: Convention::Dh,
        joints: vec![Joint {
            kind: JointType::Revolute,
            limits: (-3.2, 3.2),
        }],
        values,
        units: Units::DEG_MM,
        coupling: None,
        beta_joints: None,
        link_mass_kg: None,
    };
    // base.rx = −90°: base z becomes world +y; the link (local x) stays along world x at θ = 0.
    r.set(Param::Base(3), -std::f64::consts::FRAC_PI_2);
    r
}

#[test]
fn pendulum_matches_closed_form() {
    let (m, l, k) = (12.0, 400.0, 2.0e4);
    let robot = pendulum(l);
    for model in [ComplianceModel::Linear, ComplianceModel::Rapier] {
        let s = ComplianceSettings {
            model,
            stiffness_nm_per_rad: Some(vec![k]),
            link_mass_kg: Some(vec![m]),
            payload_kg: 0.0,
        };
        let c = Compliance::new(&s, &robot, None).unwrap().unwrap();
        for theta in [0.0, 0.5, -1.0, 2.0] {
            let q = [theta];
            // Positive rotation about +y lowers the link: the sag adds to θ.
            let dth = m * GRAVITY * l * 1e-3 * Real::cos(theta) / k;
            let dq = c.joint_deflection(&robot, &q).unwrap();
            assert_relative_eq!(dq[0], dth, epsilon = 1e-15);
            let f = c.deflected(&robot, &q).unwrap();
            // Tool at 2l along the link, angle θ + Δθ below the horizontal. The linear model
            // uses the closed form Δθ; rapier solves the exact equilibrium
            // k·Δθ' = m·g·l·cos(θ + Δθ') (fixed point here), which differs from it by
            // about Δθ²·(tan θ + Δθ).
            let a = if model == ComplianceModel::Linear {
                theta + dth
            } else {
                let mut d = dth;
                for _ in 0..50 {
                    d = m * GRAVITY * l * 1e-3 * Real::cos(theta + d) / k;
                }
                assert!((d - dth).abs() <= 1.1 * dth * dth * (theta.tan().abs() + dth));
                theta + d
            };
            assert_relative_eq!(f.pos.x, 2.0 * l * a.cos(), epsilon = 1e-9);
            assert_relative_eq!(f.pos.z, -2.0 * l * a.sin(), epsilon = 1e-9);
            assert_relative_eq!(f.pos.y, 0.0, epsilon = 1e-9);
        }
    }
}

#[test]
fn compliance_is_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<Compliance>();
    check::<ComplianceSettings>();
}

#[test]
fn zero_mass_gives_zero_sag() {
    let robot = load("irb2600").unwrap();
    let mut qs = uniform_joint_poses(&robot, 5, &mut stream(3, "zero-mass"));
    qs.push(vec![0.0; 6]);
    for model in [ComplianceModel::Linear, ComplianceModel::Rapier] {
        let s = ComplianceSettings {
            model,
            link_mass_kg: Some(vec![0.0; 6]),
            ..Default::default()
        };
        let c = Compliance::new(&s, &robot, builtin("irb2600"))
            .unwrap()
            .unwrap();
        for q in &qs {
            let rigid = robot.fk(q);
            let f = c.deflected(&robot, q).unwrap();
            assert!((f.pos - rigid.pos).norm() < 1e-9, "{model:?}");
            assert!((f.rot - rigid.rot).norm() < 1e-12);
            assert!(c
                .joint_deflection(&robot, q)
                .unwrap()
                .iter()
                .all(|d| *d == 0.0));
        }
    }
}

/// The linear torques against a finite difference of the potential energy
/// V(q) = −Σ m_i g·c_i(q): τ_j = −∂V/∂q_j.
#[test]
fn torques_are_minus_gradient_of_potential() {
    let (robot, c) = built(
        "irb2600",
        &ComplianceSettings {
            model: ComplianceModel::Linear,
            payload_kg: 5.0,
            ..Default::default()
        },
    );
    let chain = robot.chain();
    let potential = |q: &[Real]| {
        let m = c.masses(&chain, q);
        let mut v = c.payload * GRAVITY * m.tool.pos.z;
        for i in 0..6 {
            v += c.link_mass[i] * GRAVITY * m.points[i].z;
        }
        v * 1e-3
    };
    for q in uniform_joint_poses(&robot, 10, &mut stream(5, "potential")) {
        let mut t = [0.0; 6];
        c.torques(&robot, &c.masses(&chain, &q), c.payload, &mut t);
        for j in 0..6 {
            let h = 1e-6;
            let (mut a, mut b) = (q.clone(), q.clone());
            a[j] += h;
            b[j] -= h;
            let fd = -(potential(&a) - potential(&b)) / (2.0 * h);
            crate::assert_fd(t[j], fd, 1e-5, &format!("j{j}"));
        }
    }
}

#[test]
fn rapier_and_linear_agree_on_irb2600() {
    let robot = load("irb2600").unwrap();
    let qs = uniform_joint_poses(&robot, 100, &mut stream(11, "agree"));
    let chain = robot.chain();
    for payload in [0.0, 8.0] {
        let mk = |model| {
            let s = ComplianceSettings {
                model,
                payload_kg: payload,
                ..Default::default()
            };
            Compliance::new(&s, &robot, builtin("irb2600"))
                .unwrap()
                .unwrap()
        };
        let (lin, rap) = (mk(ComplianceModel::Linear), mk(ComplianceModel::Rapier));
        let mut worst: Real = 0.0;
        let mut sag: Real = 0.0;
        for q in &qs {
            // Settled: the last step moved no joint by more than the tolerance.
            let st = rap.settle(&robot, &chain, q, rap.payload).unwrap();
            assert!(st.last_step_change < rapier::STEP_TOLERANCE);
            let a = lin.deflected_with_chain(&robot, &chain, q).unwrap();
            let b = rap.deflected_with_chain(&robot, &chain, q).unwrap();
            worst = worst.max((a.pos - b.pos).norm());
            // ‖R_a − R_b‖_F ≈ √2 × the angle between the orientations.
            let rot_err = (a.rot - b.rot).norm();
            assert!(rot_err < 2e-7, "orientation differs by {rot_err} rad");
            sag = sag.max((a.pos - chain.fk(q).pos).norm());
        }
        eprintln!(
            "payload {payload} kg: max sag {sag:.4} mm, max |rapier − linear| {worst:.2e} mm"
        );
        assert!(sag > 0.05, "sag too small to test agreement: {sag}");
        // The exact equilibrium differs from the small-deflection model by second-order
        // terms: 6e-5 mm at most here.
        assert!(worst < 1e-4, "payload {payload}: {worst} mm");
    }
}

/// The exact static equilibrium `K Δq = τ_g(q + Δq)` by fixed-point iteration (revolute
/// joints, no coupling).
fn exact_deflection(c: &Compliance, robot: &Robot, chain: &Chain, q: &[Real]) -> Vec<Real> {
    let n = q.len();
    let mut dq = vec![0.0; n];
    for _ in 0..60 {
        let qd: Vec<Real> = q.iter().zip(&dq).map(|(a, b)| a + b).collect();
        let mut t = vec![0.0; n];
        c.torques(robot, &c.masses(chain, &qd), c.payload, &mut t);
        for j in 0..n {
            dq[j] = t[j] / c.stiffness[j];
        }
    }
    dq
}

/// Rapier's settled joints against the exact equilibrium, to 1e-12 rad: the reused world,
/// the start from the linear model and the step count leave nothing measurable.
#[test]
fn rapier_matches_exact_equilibrium_on_irb2600() {
    let robot = load("irb2600").unwrap();
    let chain = robot.chain();
    let qs = uniform_joint_poses(&robot, 100, &mut stream(13, "exact"));
    for payload in [0.0, 8.0] {
        let s = ComplianceSettings {
            model: ComplianceModel::Rapier,
            payload_kg: payload,
            ..Default::default()
        };
        let c = Compliance::new(&s, &robot, builtin("irb2600"))
            .unwrap()
            .unwrap();
        let mut worst: Real = 0.0;
        let mut most_steps = 0;
        for q in &qs {
            let st = c.settle(&robot, &chain, q, c.payload).unwrap();
            let exact = exact_deflection(&c, &robot, &chain, q);
            for (a, b) in st.deflection().iter().zip(&exact) {
                worst = worst.max((a - b).abs());
            }
            let qd: Vec<Real> = q.iter().zip(&exact).map(|(a, b)| a + b).collect();
            let f = chain.fk(&qd);
            assert!((st.tool.pos - f.pos).norm() < 1e-9);
            assert!((st.tool.rot - f.rot).norm() < 1e-12);
            most_steps = most_steps.max(st.steps);
        }
        eprintln!("payload {payload} kg: |rapier − exact| ≤ {worst:.1e} rad, ≤ {most_steps} steps");
        assert!(worst < 1e-12, "{worst}");
        assert_eq!(most_steps, rapier::MIN_STEPS);
    }
}

/// The thread's rapier world is reused across poses: the result must not depend on what it
/// settled before (rayon hands trials to threads in any order). The same poses in two
/// orders, and each in a world of its own, give the same bits.
#[test]
fn reused_rapier_world_gives_the_same_bits() {
    let robot = load("irb2600").unwrap();
    let chain = robot.chain();
    let qs = uniform_joint_poses(&robot, 40, &mut stream(17, "reuse"));
    let s = ComplianceSettings {
        model: ComplianceModel::Rapier,
        payload_kg: 3.0,
        ..Default::default()
    };
    let c = Compliance::new(&s, &robot, builtin("irb2600"))
        .unwrap()
        .unwrap();
    let bits = |st: &rapier::Settled| {
        let mut v: Vec<u64> = st.tool.rot.iter().map(|x| x.to_bits()).collect();
        v.extend(st.tool.pos.iter().map(|x| x.to_bits()));
        v.extend(st.deflection().iter().map(|x| x.to_bits()));
        v
    };
    let forward: Vec<_> = qs
        .iter()
        .map(|q| bits(&c.settle(&robot, &chain, q, c.payload).unwrap()))
        .collect();
    // Another arm size in between rebuilds the thread's world.
    let pendulum = pendulum(400.0);
    let ps = ComplianceSettings {
        model: ComplianceModel::Rapier,
        stiffness_nm_per_rad: Some(vec![2e4]),
        link_mass_kg: Some(vec![12.0]),
        payload_kg: 0.0,
    };
    let p = Compliance::new(&ps, &pendulum, None).unwrap().unwrap();
    p.deflected(&pendulum, &[0.3]).unwrap();
    for (q, want) in qs.iter().zip(&forward).rev() {
        assert_eq!(
            &bits(&c.settle(&robot, &chain, q, c.payload).unwrap()),
            want
        );
    }
    for (i, (q, want)) in qs.iter().zip(&forward).enumerate().step_by(7) {
        let m = c.masses(&chain, q);
        let mut dc = [0.0; 16];
        c.torques(&robot, &m, c.payload, &mut dc[..6]);
        for (d, k) in dc.iter_mut().zip(&c.stiffness) {
            *d /= k;
        }
        let sb = c.spring_bodies(&robot, &m, &dc, c.payload);
        let mut fresh = rapier::Arm::new(sb.count).unwrap();
        let st = fresh
            .settle(
                &sb.bodies[..sb.count],
                &sb.masses[..sb.mass_count],
                &m.tool,
                &sb.start[..sb.count],
            )
            .unwrap();
        assert_eq!(&bits(&st), want, "pose {i}");
    }
    // Across threads too.
    let other = std::thread::scope(|sc| {
        sc.spawn(|| bits(&c.settle(&robot, &chain, &qs[5], c.payload).unwrap()))
            .join()
            .unwrap()
    });
    assert_eq!(other, forward[5]);
}

#[test]
fn coupled_robot_deflects_link_angle_only() {
    let (robot, c) = built("guo-3t2r", &settings(ComplianceModel::Linear));
    let q = robot.q_from_user(&[250.0, 150.0, 30.0, 40.0, 200.0]);
    let dq = c.joint_deflection(&robot, &q).unwrap();
    // The screw travels change oppositely (ξ kept); the screw J3 (joint 5) is rigid.
    assert_relative_eq!(dq[0], -dq[1], epsilon = 1e-15);
    assert_eq!(dq[4], 0.0);
    let rap = Compliance::new(
        &settings(ComplianceModel::Rapier),
        &robot,
        builtin("guo-3t2r"),
    )
    .unwrap()
    .unwrap();
    let a = c.deflected(&robot, &q).unwrap();
    let b = rap.deflected(&robot, &q).unwrap();
    assert!((a.pos - b.pos).norm() < 2e-3, "{}", (a.pos - b.pos).norm());
}

#[test]
fn bad_settings_are_refused_naming_the_key() {
    let robot = load("irb2600").unwrap();
    let key = |s: ComplianceSettings, d: Option<&Builtin>| match Compliance::new(&s, &robot, d) {
        Err(Error::Setting { key, .. }) => key,
        other => panic!("expected a setting error, got {other:?}"),
    };
    let base = settings(ComplianceModel::Rapier);
    let b = builtin("irb2600");
    for k in [
        vec![1e6, 1e6, 1e6, 1e5, 1e5, 0.0],
        vec![1e6, -1.0, 1e6, 1e5, 1e5, 1e5],
        // Below 1 N·m/rad: a compliance beyond a robot file's range.
        vec![1e6, 1e6, 1e6, 1e5, 1e5, 1e-300],
        vec![1e6; 5],
        vec![Real::NAN; 6],
    ] {
        let s = ComplianceSettings {
            stiffness_nm_per_rad: Some(k),
            ..base.clone()
        };
        assert_eq!(key(s, b), "compliance.stiffness_nm_per_rad");
    }
    for m in [
        vec![1.0; 7],
        vec![1.0, 1.0, -1.0, 1.0, 1.0, 1.0],
        vec![1.0, 1.0, 1.0, 1.0, 1.0, 2e5],
    ] {
        let s = ComplianceSettings {
            link_mass_kg: Some(m),
            ..base.clone()
        };
        assert_eq!(key(s, b), "compliance.link_mass_kg");
    }
    for payload_kg in [-2.0, 1e300, Real::NAN] {
        let s = ComplianceSettings {
            payload_kg,
            ..base.clone()
        };
        assert_eq!(key(s, b), "compliance.payload_kg");
    }
    // The bounds hold at the edges.
    let s = ComplianceSettings {
        stiffness_nm_per_rad: Some(vec![1.0; 6]),
        link_mass_kg: Some(vec![crate::robot::compliance::MAX_MASS_KG; 6]),
        payload_kg: crate::robot::compliance::MAX_MASS_KG,
        ..base.clone()
    };
    assert!(Compliance::new(&s, &robot, b).unwrap().is_some());
    // A robot file without built-in defaults needs the stiffness, and the masses unless
    // the file gives them (`mass_kg`).
    assert_eq!(key(base.clone(), None), "compliance.stiffness_nm_per_rad");
    let s = ComplianceSettings {
        stiffness_nm_per_rad: Some(vec![1e6; 6]),
        ..base.clone()
    };
    let mut bare = robot.clone();
    bare.link_mass_kg = None;
    match Compliance::new(&s, &bare, None) {
        Err(Error::Setting { key, .. }) => assert_eq!(key, "compliance.link_mass_kg"),
        other => panic!("expected a setting error, got {other:?}"),
    }
    let c = Compliance::new(&s, &robot, None).unwrap().unwrap();
    assert_eq!(c.link_mass_kg(), robot.link_mass_kg.as_deref().unwrap());
    // "none" needs nothing, but what it is given is checked all the same.
    assert!(
        Compliance::new(&settings(ComplianceModel::None), &robot, None)
            .unwrap()
            .is_none()
    );
    let s = ComplianceSettings {
        model: ComplianceModel::None,
        stiffness_nm_per_rad: Some(vec![-1.0, 1.0, 1.0, 1.0, 1.0, 1.0]),
        ..base.clone()
    };
    assert_eq!(key(s, None), "compliance.stiffness_nm_per_rad");
    // TOML: unknown keys and models are refused.
    assert!(toml::from_str::<ComplianceSettings>("model = \"rapier\"\nstiff = 1").is_err());
    assert!(toml::from_str::<ComplianceSettings>("model = \"fem\"").is_err());
    let s: ComplianceSettings = toml::from_str("model = \"linear\"\npayload_kg = 3.0").unwrap();
    assert_eq!(s.model, ComplianceModel::Linear);
    assert_eq!(s.payload_kg, 3.0);
    // A wrong joint vector is an error, not a panic.
    let c = Compliance::new(&base, &robot, b).unwrap().unwrap();
    assert!(c.deflected(&robot, &[0.0; 5]).is_err());
    assert!(c.joint_deflection(&robot, &[Real::NAN; 6]).is_err());
}

/// Median and largest sag of every built-in robot at its default stiffness and masses
/// (linear model, no payload), over 1000 uniform poses. Prints the table; checks that the
/// IRB2600 defaults give a median sag in 0.1–0.3 mm (about 20 % of a real arm's
/// pre-calibration error, Li 2018: 0.83 mm RMS).
#[test]
fn sag_of_builtins() {
    let mut irb = None;
    for b in crate::robot::builtin::BUILTINS {
        let (robot, c) = built(b.name, &settings(ComplianceModel::Linear));
        let qs = uniform_joint_poses(&robot, 1000, &mut stream(7, "sag-stats"));
        let s = sag_stats(&c, &robot, &qs).unwrap();
        eprintln!(
            "{:12} median {:.3} mm  p95 {:.3} mm  max {:.3} mm  rms {:.3} mm",
            b.name, s.median_mm, s.p95_mm, s.max_mm, s.rms_mm
        );
        if b.name == "irb2600" {
            irb = Some(s);
        }
    }
    let s = irb.unwrap();
    assert!(s.median_mm > 0.1 && s.median_mm < 0.3, "{s:?}");
}
