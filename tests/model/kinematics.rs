//! Kinematics core: forward kinematics against hand computations and between conventions,
//! the analytic identification Jacobian against finite differences, identifiability.

use approx::assert_relative_eq;
use nalgebra::DMatrix;
use proptest::prelude::*;

use calbench::measurement::Measure;
use calbench::numeric::rng;
use calbench::numeric::{Mat3, Real, Vec3};
use calbench::robot::builtin;
use calbench::robot::identifiability::analyse;
use calbench::robot::jacobian::{
    jacobian, jacobian_fd, pose_rows4, pose_rows_vars, Columns, LANES,
};
use calbench::robot::sampling::uniform_joint_poses;
use calbench::robot::{Convention, Joint, JointType, Param, Robot, Units};

const DEG: Real = std::f64::consts::PI / 180.0;

fn fk_user(robot: &Robot, q_user: &[Real]) -> calbench::numeric::Frame {
    robot.fk(&robot.q_from_user(q_user))
}

fn assert_frame(f: &calbench::numeric::Frame, pos: [Real; 3], cols: [[Real; 3]; 3]) {
    assert_relative_eq!(f.pos, Vec3::from(pos), epsilon = 1e-9);
    let r = Mat3::from_columns(&cols.map(Vec3::from));
    assert_relative_eq!(f.rot, r, epsilon = 1e-12);
}

/// IRB2600 at q = 0, chained by hand from Li 2018 table 1: flange at (1288, 0, 1495) mm,
/// x = −z₀, y = y₀, z = x₀.
#[test]
fn irb2600_home_pose_by_hand() {
    let r = builtin::irb2600();
    let f = fk_user(&r, &[0.0; 6]);
    assert_frame(
        &f,
        [1288.0, 0.0, 1495.0],
        [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
    );
    // Joint 1 at 90°: the whole arm turns about z₀.
    let f = fk_user(&r, &[90.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert_relative_eq!(f.pos, Vec3::new(0.0, 1288.0, 1495.0), epsilon = 1e-9);
}

#[test]
fn irb2600_mdh_home_pose_by_hand() {
    let f = fk_user(&builtin::irb2600_mdh(), &[0.0; 6]);
    assert_frame(
        &f,
        [1288.0, 0.0, 1495.0],
        [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
    );
}

/// TX60 at q = 0, by hand from Qiao 2021 table 1: upright, flange at (0, 20, 670) mm with the
/// base orientation; on its mounting face (`tx60-floor`) 375 mm higher.
#[test]
fn tx60_home_pose_by_hand() {
    let up = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    assert_frame(
        &fk_user(&builtin::tx60(), &[0.0; 6]),
        [0.0, 20.0, 670.0],
        up,
    );
    let floor = builtin::load("tx60-floor").unwrap();
    assert_frame(&fk_user(&floor, &[0.0; 6]), [0.0, 20.0, 1045.0], up);
}

/// guo-3t2r with equal screw travels (ψ = 0, ξ = 200 mm), J4 = J5 = 0, J3 travel 0: by
/// hand, z1 = z2 = +y (the ξ screw and J4), frame 2 sits at (0, 500, 300) with x2 = −z;
/// a3 = 100 along x2, then d4 = 150 along z3 = (1, 1, 0)/√2, then x4 = −z, y4 = (1, 1, 0)/√2,
/// z4 = (1, −1, 0)/√2 carry the tool point (50, 30, 60): (240/√2, 500 + 120/√2, 150) mm.
#[test]
fn guo_3t2r_pose_by_hand() {
    let r = builtin::guo_3t2r();
    let f = fk_user(&r, &[200.0, 200.0, 0.0, 0.0, 0.0]);
    let c = 1.0 / 2f64.sqrt();
    assert_relative_eq!(
        f.pos,
        Vec3::new(240.0 * c, 500.0 + 120.0 * c, 150.0),
        epsilon = 1e-9
    );
    // Unequal travels turn the turntable by ψ = atan((q1 − q2) / L1).
    let f2 = fk_user(&r, &[300.0, 100.0, 0.0, 0.0, 0.0]);
    let psi = (200.0f64 / 400.0).atan();
    let expect = nalgebra::Rotation3::from_axis_angle(&Vec3::z_axis(), psi) * f.pos;
    assert_relative_eq!(f2.pos, expect, epsilon = 1e-9);
}

#[test]
fn dh_and_mdh_descriptions_agree_in_fk() {
    let (dh, mdh) = (builtin::irb2600(), builtin::irb2600_mdh());
    let mut g = rng::stream(7, "test");
    for q in uniform_joint_poses(&dh, 200, &mut g) {
        let (a, b) = (dh.fk(&q), mdh.fk(&q));
        assert_relative_eq!(a.pos, b.pos, epsilon = 1e-9);
        assert_relative_eq!(a.rot, b.rot, epsilon = 1e-12);
    }
}

/// ‖J − J_fd‖_F / ‖J‖_F for every parameter of `robot`.
fn jacobian_mismatch(robot: &Robot, qs: &[Vec<Real>], measure: Measure) -> Real {
    let cols = Columns::new(&robot.params(), robot.dof());
    let j = jacobian(robot, &cols, qs, measure);
    let fd = jacobian_fd(robot, &cols, qs, measure, 1e-5);
    (&j - &fd).norm() / j.norm()
}

#[test]
fn builtin_jacobians_match_finite_differences() {
    for b in builtin::BUILTINS {
        let robot = (b.build)();
        let mut g = rng::stream(11, b.name);
        let qs = uniform_joint_poses(&robot, 20, &mut g);
        for measure in [Measure::Position, Measure::Pose] {
            let e = jacobian_mismatch(&robot, &qs, measure);
            assert!(e < 1e-6, "{} {measure:?}: relative error {e:e}", b.name);
        }
    }
}

/// The rows of four poses walked together ([`pose_rows4`], vector instructions where the
/// processor has them) are those of the poses one by one to the bit, with every kind of
/// column: geometric parameters of all conventions, base, tool and joint compliances.
#[test]
fn four_poses_at_once_are_the_poses_one_by_one_to_the_bit() {
    for b in builtin::BUILTINS {
        let mut robot = (b.build)();
        let mut g = rng::stream(5, b.name);
        // Off-nominal values, so that no column is special.
        let perturbed = uniform_joint_poses(&robot, 1, &mut g)[0].clone();
        for (k, v) in robot.values.iter_mut().enumerate() {
            *v += 1e-3 * perturbed[k % perturbed.len()] * (k as Real + 1.0);
        }
        let qs = uniform_joint_poses(&robot, 3 * LANES, &mut g);
        let mut params = robot.params();
        params.extend((0..robot.dof()).map(Param::Compliance));
        let cols = Columns::new(&params, robot.dof());
        let chain = robot.chain();
        let vars: Vec<_> = qs.iter().map(|q| chain.variables(q)).collect();
        for measure in [Measure::Position, Measure::Pose] {
            let rows = measure.rows();
            let mut one = DMatrix::from_element(rows * qs.len(), cols.len(), Real::NAN);
            let mut four = one.clone();
            let frames: Vec<_> = (0..qs.len())
                .map(|i| pose_rows_vars(&chain, &cols, &vars[i], measure, &mut one, rows * i))
                .collect();
            for i0 in (0..qs.len()).step_by(LANES) {
                let f = pose_rows4(&chain, &cols, &vars[i0..], measure, &mut four, rows * i0);
                for l in 0..LANES {
                    let want = &frames[i0 + l];
                    assert_eq!(f.frame(l).pos, want.pos, "{} pose {}", b.name, i0 + l);
                    assert_eq!(f.frame(l).rot, want.rot, "{} pose {}", b.name, i0 + l);
                }
            }
            assert!(
                one.iter().all(|v| v.is_finite()),
                "{}: a row left unwritten",
                b.name
            );
            let same = one
                .iter()
                .zip(four.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "{} {measure:?}: the rows differ", b.name);
        }
    }
}

/// A random serial robot of `n` joints in any convention, with prismatic joints, base and
/// tool: the generator behind the property tests.
fn arb_robot() -> impl Strategy<Value = Robot> {
    (2usize..=6, 0usize..3)
        .prop_flat_map(|(n, conv)| {
            (
                Just(n),
                Just(conv),
                proptest::collection::vec(
                    (any::<bool>(), proptest::array::uniform5(-1.0f64..1.0)),
                    n,
                ),
                proptest::array::uniform12(-1.0f64..1.0),
            )
        })
        .prop_map(|(n, conv, joints, ends)| {
            let convention = [Convention::Dh, Convention::DhBeta, Convention::Mdh][conv];
            let mut values = vec![0.0; 5 * n + 12];
            let mut js = Vec::new();
            for (i, (prismatic, v)) in joints.iter().enumerate() {
                values[Param::Theta(i).index(n)] = v[0] * 3.0;
                values[Param::D(i).index(n)] = v[1] * 500.0;
                values[Param::A(i).index(n)] = v[2] * 500.0;
                values[Param::Alpha(i).index(n)] = v[3] * 3.0;
                if convention.has_beta() {
                    values[Param::Beta(i).index(n)] = v[4] * 0.5;
                }
                js.push(Joint {
                    kind: if *prismatic {
                        JointType::Prismatic
                    } else {
                        JointType::Revolute
                    },
                    limits: if *prismatic {
                        (-300.0, 300.0)
                    } else {
                        (-3.0, 3.0)
                    },
                });
            }
            for k in 0..6 {
                let s = if k < 3 { 300.0 } else { 1.0 };
                values[Param::Base(k).index(n)] = ends[k] * s;
                values[Param::Tool(k).index(n)] = ends[6 + k] * s;
            }
            Robot {
                name: "random".into(),
                convention,
                joints: js,
                values,
                units: Units::DEG_MM,
                coupling: None,
                beta_joints: None,
                link_mass_kg: None,
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn jacobian_equals_finite_differences(robot in arb_robot(), seed in any::<u64>(), pose in any::<bool>()) {
        let mut g = rng::from_seed(seed);
        let qs = uniform_joint_poses(&robot, 4, &mut g);
        let measure = if pose { Measure::Pose } else { Measure::Position };
        let e = jacobian_mismatch(&robot, &qs, measure);
        prop_assert!(e < 1e-6, "relative error {e:e}");
    }

    #[test]
    fn builtin_jacobians_at_random_poses(which in 0usize..4, seed in any::<u64>()) {
        let robot = (builtin::BUILTINS[which].build)();
        let mut g = rng::from_seed(seed);
        let qs = uniform_joint_poses(&robot, 3, &mut g);
        for measure in [Measure::Position, Measure::Pose] {
            let e = jacobian_mismatch(&robot, &qs, measure);
            prop_assert!(e < 1e-6, "{} {measure:?}: relative error {e:e}", robot.name);
        }
    }
}

/// Li 2018 eqs. 8–11: with the base at the origin, the base-frame columns are `[I, −[p]×]`.
#[test]
fn base_columns_are_li_2018_eq_8_to_11() {
    let robot = builtin::irb2600();
    let n = robot.dof();
    let params: Vec<Param> = (0..6).map(Param::Base).collect();
    let cols = Columns::new(&params, n);
    let q = vec![0.3, -0.2, 0.4, 1.0, -0.5, 0.7];
    let j = jacobian(&robot, &cols, std::slice::from_ref(&q), Measure::Position);
    let p = robot.fk(&q).pos;
    let mut expect = DMatrix::zeros(3, 6);
    expect.view_mut((0, 0), (3, 3)).copy_from(&Mat3::identity());
    // Base rotation applied Rz·Ry·Rx at zero angles: small rotations about x, y, z.
    expect
        .view_mut((0, 3), (3, 3))
        .copy_from(&(-calbench::numeric::skew(&p)));
    assert_relative_eq!(j, expect, epsilon = 1e-9);
}

#[test]
fn irb2600_position_groups_d2_with_d3() {
    let robot = builtin::irb2600();
    let mut g = rng::stream(3, "test");
    let qs = uniform_joint_poses(&robot, 60, &mut g);
    let a = analyse(&robot, &robot.params(), &qs, Measure::Position);
    let (d2, d3) = (Param::D(1), Param::D(2));
    assert!(
        a.groups.iter().any(|g| g.contains(&d2) && g.contains(&d3)),
        "groups {:?}",
        a.groups
    );
    assert_eq!(a.rank, a.identifiable.len());
    assert_eq!(a.rank + a.unidentifiable.len(), robot.params().len());
    // θ6 and the tool are coupled for position-only data: something is unidentifiable.
    assert!(a.condition_number.is_finite() && a.condition_number > 1.0);
}

#[test]
fn irb2600_mdh_beta2_is_identifiable() {
    let robot = builtin::irb2600_mdh();
    let mut g = rng::stream(3, "test");
    let qs = uniform_joint_poses(&robot, 60, &mut g);
    let a = analyse(&robot, &robot.params(), &qs, Measure::Position);
    assert!(a.identifiable.contains(&Param::Beta(1)));
}

#[test]
fn full_pose_identifies_more_than_position() {
    let robot = builtin::irb2600();
    let mut g = rng::stream(5, "test");
    let qs = uniform_joint_poses(&robot, 40, &mut g);
    let p = analyse(&robot, &robot.params(), &qs, Measure::Position);
    let f = analyse(&robot, &robot.params(), &qs, Measure::Pose);
    assert!(
        f.rank > p.rank,
        "pose rank {} position rank {}",
        f.rank,
        p.rank
    );
}

#[test]
fn bad_robot_files_name_the_key() {
    use calbench::robot::parse_robot_file;
    let head = "name = \"x\"\nconvention = \"dh\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n";
    let joint = |body: &str| format!("{head}[[joints]]\ntype = \"revolute\"\n{body}");
    let cases = [
        (joint("a = 0.0\nd = 0.0\ntheta = 0.0\nlimits = [-1.0, 1.0]"), "alpha"),
        (joint("alpha = 0.0\na = 0.0\nd = 0.0\ntheta = 0.0\nlimits = [1.0, -1.0]"), "limits"),
        (joint("alpha = 0.0\na = 0.0\nd = 0.0\ntheta = 0.0\nlimits = [1.0]"), "limits"),
        (joint("alpha = 0.0\na = 0.0\nd = inf\ntheta = 0.0\nlimits = [-1.0, 1.0]"), "d"),
        (joint("alpha = 0.0\na = 0.0\nd = 0.0\ntheta = 0.0\nbeta = 0.1\nlimits = [-1.0, 1.0]"), "beta"),
        (
            head.replace("\"dh\"", "\"dhx\"") + "[[joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 0.0\nd = 0.0\ntheta = 0.0\nlimits = [-1.0, 1.0]",
            "convention",
        ),
        (
            format!("{head}[[joints]]\ntype = \"spherical\"\nalpha = 0.0\na = 0.0\nd = 0.0\ntheta = 0.0\nlimits = [-1.0, 1.0]"),
            "type",
        ),
    ];
    for (text, key) in cases {
        let e = parse_robot_file(&text, std::path::Path::new("bad.toml"))
            .expect_err(&format!("accepted:\n{text}"))
            .to_string();
        assert!(
            e.contains("bad.toml") && e.contains(key),
            "message `{e}` lacks `{key}`"
        );
    }
}

#[test]
fn printed_builtins_load_back_identically() {
    use calbench::robot::{parse_robot_file, robot_to_toml};
    for b in builtin::BUILTINS {
        let r = (b.build)();
        let back = parse_robot_file(&robot_to_toml(&r), std::path::Path::new("x.toml")).unwrap();
        assert_eq!(back.dof(), r.dof());
        assert_eq!(back.coupling, r.coupling);
        for (a, b) in back.values.iter().zip(&r.values) {
            assert_relative_eq!(a, b, epsilon = 1e-9);
        }
        let q = r.q_from_user(&vec![10.0; r.dof()]);
        assert_relative_eq!(back.fk(&q).pos, r.fk(&q).pos, epsilon = 1e-9);
    }
}

#[test]
fn units_m_rad_equal_mm_deg() {
    use calbench::robot::parse_robot_file;
    let mm = "name = \"a\"\nconvention = \"dh\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n[[joints]]\ntype = \"revolute\"\nalpha = 90.0\na = 100.0\nd = 200.0\ntheta = 10.0\nlimits = [-90.0, 90.0]\n[[joints]]\ntype = \"prismatic\"\nalpha = 0.0\na = 50.0\nd = 0.0\ntheta = 0.0\nlimits = [0.0, 300.0]\n";
    let m = "name = \"a\"\nconvention = \"dh\"\nlength_unit = \"m\"\nangle_unit = \"rad\"\n[[joints]]\ntype = \"revolute\"\nalpha = 1.5707963267948966\na = 0.1\nd = 0.2\ntheta = 0.17453292519943295\nlimits = [-1.5707963267948966, 1.5707963267948966]\n[[joints]]\ntype = \"prismatic\"\nalpha = 0.0\na = 0.05\nd = 0.0\ntheta = 0.0\nlimits = [0.0, 0.3]\n";
    let p = std::path::Path::new("u.toml");
    let (a, b) = (
        parse_robot_file(mm, p).unwrap(),
        parse_robot_file(m, p).unwrap(),
    );
    let fa = a.fk(&a.q_from_user(&[30.0, 120.0]));
    let fb = b.fk(&b.q_from_user(&[30.0 * DEG, 0.12]));
    assert_relative_eq!(fa.pos, fb.pos, epsilon = 1e-9);
}
