//! The chain read from a URDF (docs/formats.md § 3.2). A URDF whose consecutive joint axes are
//! a hair from parallel (a rounded `rpy`, as Kinova's Gen3 lite URDF writes −3.1416 for −π) was
//! refused: the DH common normal of the two lines lay tens of kilometres away. The link takes
//! Hayati's β instead, and the robot's FK is the URDF's, against an FK computed here from the
//! URDF's joints alone. And the tool an identified URDF adds after a tip that is a moving
//! joint's child is part of the chain that tip names.

use nalgebra::{Rotation3, Unit, Vector3};

use calbench::numeric::Real;
use calbench::robot::urdf::{UrdfChain, UrdfRobot};
use calbench::robot::Convention;

use crate::common::{root, tmp_dir};

/// The UR10 example with its elbow axis tilted by `[rx, ry]` rad: about y, coplanar with the
/// shoulder-lift axis, meeting it 0.612 m / `ry` away; about x, the common normal.
fn tilted_ur10([rx, ry]: [Real; 2]) -> String {
    let text = std::fs::read_to_string(root().join("examples/ipa-ur10/ur10.urdf")).unwrap();
    let elbow = "<origin xyz=\"-0.612 0.0 0.0\" rpy=\"0.0 0.0 0.0\"/>";
    assert!(text.contains(elbow));
    let tilted = format!("<origin xyz=\"-0.612 0.0 0.0\" rpy=\"{rx:e} {ry:e} 0.0\"/>");
    text.replace(elbow, &tilted)
}

/// The tool point (mm) of the URDF `text` at the joint values `q`, from its joints' origins
/// and axes (urdf-rs), root to leaf: each joint's origin, then its turn about its axis.
fn urdf_tool_point(text: &str, q: &[Real]) -> Vector3<Real> {
    let urdf = urdf_rs::read_from_string(text).unwrap();
    let (mut rot, mut pos) = (Rotation3::identity(), Vector3::zeros());
    let mut k = 0;
    for j in &urdf.joints {
        let o = &j.origin;
        pos += rot * Vector3::new(o.xyz[0], o.xyz[1], o.xyz[2]);
        rot *= Rotation3::from_euler_angles(o.rpy[0], o.rpy[1], o.rpy[2]);
        if j.joint_type != urdf_rs::JointType::Fixed {
            let axis =
                Unit::new_normalize(Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]));
            rot *= Rotation3::from_axis_angle(&axis, q[k]);
            k += 1;
        }
    }
    assert_eq!(k, q.len());
    pos * 1000.0
}

#[test]
fn nearly_parallel_axes_take_hayatis_beta_and_keep_the_urdfs_fk() {
    let d = tmp_dir("model-urdf-parallel");
    let qs: [[Real; 6]; 3] = [
        [0.0; 6],
        [0.3, -1.1, 1.4, -0.7, 0.9, 2.0],
        [-2.0, -0.4, -1.9, 1.2, -1.5, -0.3],
    ];
    // 7.3e-6 rad (0.00042°) puts the lines' meeting 84 km away, 1e-3 rad 612 m: beyond ten
    // times the chain's 1.7 m; 0.1 rad 6.1 m, within it, where DH is kept; 1e-8 rad about the
    // common normal made DH's d NaN.
    for (tilt, hayati) in [
        ([0.0, 7.3e-6], Some(true)),
        ([0.0, 1e-3], Some(true)),
        ([0.0, 0.1], Some(false)),
        ([0.0, 0.0], Some(false)),
        ([1e-8, 0.0], None),
        ([2e-9, 0.0], None),
    ] {
        let text = tilted_ur10(tilt);
        let path = d.join(format!("ur10-{}-{}.urdf", tilt[0], tilt[1]));
        std::fs::write(&path, &text).unwrap();
        let robot = UrdfRobot::load(&path).unwrap().robot;
        match hayati {
            Some(true) => {
                assert_eq!(robot.convention, Convention::DhBeta);
                // Link 2 (0-based 1), from the shoulder-lift axis to the elbow's.
                assert_eq!(robot.beta_joints, Some(vec![1]));
            }
            Some(false) => assert_eq!(robot.convention, Convention::Dh),
            None => {}
        }
        for q in &qs {
            let got = robot.fk(q).pos;
            let want = urdf_tool_point(&text, q);
            let gap = (Vector3::new(got[0], got[1], got[2]) - want).norm();
            assert!(
                gap < 1e-6,
                "tilt {tilt:?}, q {q:?}: {gap} mm from the URDF's FK"
            );
        }
    }
}

/// The identified robot written back into the URDF (`identify --export urdf`) reads back with
/// the same FK, β included.
#[test]
fn a_robot_with_hayatis_beta_is_written_back_into_its_urdf() {
    let d = tmp_dir("model-urdf-parallel-write");
    let path = d.join("ur10.urdf");
    std::fs::write(&path, tilted_ur10([0.0, 7.3e-6])).unwrap();
    let urdf = UrdfRobot::load(&path).unwrap();
    let mut moved = urdf.robot.clone();
    for (name, dv) in [("beta2", 2e-4), ("a2", 0.3), ("alpha3", -1e-3)] {
        let p = calbench::robot::Param::parse(name).unwrap();
        moved.set(p, moved.get(p) + dv);
    }
    let back = d.join("back.urdf");
    std::fs::write(&back, urdf.write(&moved).unwrap()).unwrap();
    let again = UrdfRobot::load(&back).unwrap().robot;
    let q = [0.3, -1.1, 1.4, -0.7, 0.9, 2.0];
    let gap = (again.fk(&q).pos - moved.fk(&q).pos).norm();
    assert!(gap < 1e-6, "{gap} mm");
    assert!(again.fk(&q).rot.relative_eq(&moved.fk(&q).rot, 1e-9, 1e-9));
}

/// `identify --tip LINK` on a tip that is a moving joint's child writes its tool as a new link
/// `calbench_tool`; `compensate --tip LINK --identified robot.urdf` read the identified URDF's
/// chain to LINK, without that tool, and compensated another robot (1.5 mm off on a Panda's
/// finger) with every row `ok`.
#[test]
fn the_tool_an_identified_urdf_adds_ends_the_chain_its_tip_names() {
    let d = tmp_dir("model-urdf-added-tool");
    let path = root().join("examples/ipa-ur10/ur10.urdf");
    let tip = UrdfChain {
        base: None,
        tip: Some("link_6".into()),
    };
    let urdf = UrdfRobot::load_chain(&path, &tip).unwrap();
    let mut moved = urdf.robot.clone();
    for (name, dv) in [("tool.x", 5.0), ("tool.rz", 0.01), ("a2", 0.3)] {
        let p = calbench::robot::Param::parse(name).unwrap();
        moved.set(p, moved.get(p) + dv);
    }
    let text = urdf.write(&moved).unwrap();
    assert!(text.contains("<link name=\"calbench_tool\"/>"), "{text}");
    let back = d.join("identified.urdf");
    std::fs::write(&back, text).unwrap();
    let again = UrdfRobot::load_chain(&back, &tip).unwrap().robot;
    let q = [0.3, -1.1, 1.4, -0.7, 0.9, 2.0];
    let gap = (again.fk(&q).pos - moved.fk(&q).pos).norm();
    assert!(gap < 1e-6, "{gap} mm");
}
