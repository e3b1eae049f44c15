//! Controller exports of `calbench identify --export` (docs/formats.md `identify`,
//! "Controller exports"): UR's `kinematics_params_file` (`ur-yaml`) and a DH table with
//! nominal, identified, Δ and σ columns (`dh-csv`).

use crate::error::{Error, Result};
use crate::numeric::{rot_x, rot_y, rot_z};
use crate::numeric::{Frame, Real, Vec3};
use crate::robot::{Convention, JointType, Param, Robot};

/// UR's segment names in `kinematics_params_file`, joint 1 to 6.
const UR_SEGMENTS: [&str; 6] = [
    "shoulder",
    "upper_arm",
    "forearm",
    "wrist_1",
    "wrist_2",
    "wrist_3",
];

/// Refuses a robot whose frames `ur-yaml` cannot write: it needs six revolute, uncoupled
/// joints in the `dh` or `dh_beta` convention. An identification keeps these, so the nominal
/// robot is checked before one runs.
pub fn ur_like(robot: &Robot) -> Result<()> {
    let six_revolute =
        robot.dof() == 6 && robot.joints.iter().all(|j| j.kind == JointType::Revolute);
    if !six_revolute || robot.convention == Convention::Mdh || robot.coupling.is_some() {
        return Err(Error::option(
            crate::error::Opt::Export,
            format!(
                "ur-yaml needs a UR-like robot: six revolute, uncoupled joints in the dh or \
                 dh_beta convention; robot \"{}\" is not",
                robot.name
            ),
        ));
    }
    Ok(())
}

/// `ur-yaml`: the robot's joint frames as UR's `kinematics_params_file` (the format
/// `ur_calibration` writes and the UR ROS drivers read): per joint `i` the transform from joint
/// `i − 1`'s frame to joint `i`'s, `Tx(a_{i−1}) Rx(α_{i−1}) Ry(β_{i−1}) Tz(d_i) Rz(θ_i)`, as
/// `x, y, z` (m) and fixed-axis `roll, pitch, yaw` (rad). The robot's base and tool
/// transforms and its last link's `a, α, β` are not part of the file (they stay in
/// `robot.toml`). Refused unless the robot has six revolute joints in the `dh` or `dh_beta`
/// convention, and when it has joint-angle harmonics or a gravity basis (the file cannot carry
/// them: writing the geometric part alone would leave the controller short of the model that
/// was chosen).
pub fn ur_yaml(robot: &Robot) -> Result<String> {
    if crate::robot::harmonics::has_harmonics(robot) {
        return Err(Error::option(
            crate::error::Opt::Export,
            "ur-yaml cannot carry the joint-angle harmonics of the chosen model; export \
             dh-csv or use robot.toml (its `harmonics` key)",
        ));
    }
    if crate::robot::gravity_basis::has_gravity(robot) {
        return Err(Error::option(
            crate::error::Opt::Export,
            "ur-yaml cannot carry the gravity basis of the chosen model (joint deflections \
             that depend on the pose); export dh-csv or use robot.toml (its `gravity` key)",
        ));
    }
    ur_like(robot)?;
    // The name in double quotes with its quotes, backslashes and line breaks escaped, so
    // that no name can end the comment line.
    let mut s = format!(
        "# kinematics_params_file of the calibrated robot {:?} (calbench identify)\n\
         kinematics:\n",
        robot.name
    );
    for (i, name) in UR_SEGMENTS.iter().enumerate() {
        let v = |p: Param| robot.get(p);
        let (a, alpha, beta) = if i == 0 {
            (0.0, 0.0, 0.0)
        } else {
            let b = if robot.carries_beta(i - 1) {
                v(Param::Beta(i - 1))
            } else {
                0.0
            };
            (v(Param::A(i - 1)), v(Param::Alpha(i - 1)), b)
        };
        let rot = rot_x(alpha) * rot_y(beta);
        let seg = Frame {
            rot: rot * rot_z(v(Param::Theta(i))),
            pos: Vec3::new(a, 0.0, 0.0) + rot * Vec3::new(0.0, 0.0, v(Param::D(i))),
        };
        let (xyz, rpy) = seg.to_xyz_rpy();
        s += &format!("  {name}:\n");
        for (key, value) in ["x", "y", "z"].iter().zip(xyz) {
            // `+ 0.0` writes a negative zero as 0.
            s += &format!("    {key}: {}\n", value / 1000.0 + 0.0);
        }
        for (key, value) in ["roll", "pitch", "yaw"].iter().zip(rpy) {
            s += &format!("    {key}: {}\n", value + 0.0);
        }
    }
    s += &format!("  hash: calib_calbench_{}\n", fnv(&s));
    Ok(s)
}

/// FNV-1a of `s`: the `hash` UR's drivers compare with the controller's calibration.
fn fnv(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// `dh-csv`: one row per parameter of the robot's model (joint parameters in the robot's
/// convention, then base and tool), in the robot file's units (lengths in its `length_unit`,
/// angles in its `angle_unit`; a compliance in rad/(N·m)): `joint,parameter,unit,nominal,
/// identified,delta,sigma`. `sigma` is the identification's standard error (√ of the
/// covariance's diagonal); empty for a parameter not identified (fixed or not identifiable).
pub fn dh_csv(nominal: &Robot, identified: &Robot, params: &[Param], sigma: &[Real]) -> String {
    let mut s = String::from("joint,parameter,unit,nominal,identified,delta,sigma\n");
    let (len, ang) = (nominal.units.length_to_mm(), nominal.units.angle_to_rad());
    let mut all = nominal.params();
    for p in params {
        if !all.contains(p) {
            all.push(*p);
        }
    }
    for p in all {
        let (scale, unit) = if p.is_compliance() || matches!(p, Param::Gravity(..)) {
            (1.0, "rad/(N·m)")
        } else if matches!(p, Param::Harmonic(..)) {
            (1.0, "rad")
        } else if p.is_length() {
            (len, nominal.units.length_name())
        } else {
            (ang, nominal.units.angle_name())
        };
        let joint = p.joint().or(match p {
            Param::Compliance(j) | Param::Harmonic(j, _) | Param::Gravity(j, _) => Some(j),
            _ => None,
        });
        let name = p.to_string();
        let bare = name.trim_end_matches(|c: char| c.is_ascii_digit());
        let (a, b) = (nominal.get(p) / scale, identified.get(p) / scale);
        let sd = params
            .iter()
            .position(|q| *q == p)
            .and_then(|k| sigma.get(k))
            .filter(|v| v.is_finite())
            .map_or(String::new(), |v| (v / scale).to_string());
        s += &format!(
            "{},{bare},{unit},{a},{b},{},{sd}\n",
            joint.map_or(String::new(), |j| (j + 1).to_string()),
            b - a
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// UR10's published default kinematics (ur_description `default_kinematics.yaml`): the
    /// segments of UR's DH table.
    #[test]
    fn ur_yaml_of_the_ur10_is_ur_default_file() {
        let ur = crate::robot::builtin::load("../examples/ipa-ur10/ur10.toml")
            .or_else(|_| crate::robot::builtin::load("examples/ipa-ur10/ur10.toml"))
            .unwrap();
        let y = ur_yaml(&ur).unwrap();
        let seg = |name: &str| -> Vec<Real> {
            let at = y.find(&format!("  {name}:\n")).unwrap();
            y[at..]
                .lines()
                .skip(1)
                .take(6)
                .map(|l| l.split(':').nth(1).unwrap().trim().parse().unwrap())
                .collect()
        };
        let close = |a: &[Real], b: &[Real]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9);
        let pi = std::f64::consts::PI;
        assert!(close(&seg("shoulder"), &[0.0, 0.0, 0.1273, 0.0, 0.0, 0.0]));
        assert!(close(&seg("forearm"), &[-0.612, 0.0, 0.0, 0.0, 0.0, 0.0]));
        assert!(close(
            &seg("wrist_1"),
            &[-0.5723, 0.0, 0.163941, 0.0, 0.0, 0.0]
        ));
        let w2 = seg("wrist_2");
        assert!(close(&w2[..2], &[0.0, -0.1157]) && (w2[3] - pi / 2.0).abs() < 1e-9);
        assert!(y.contains("hash: calib_"));
        let irb = crate::robot::builtin::load("irb2600").unwrap();
        let mut seven = irb.clone();
        seven.joints.push(seven.joints[5]);
        assert!(ur_yaml(&seven).is_err());
    }

    #[test]
    fn ur_yaml_keeps_any_name_inside_its_comment() {
        let mut ur = crate::robot::builtin::load("../examples/ipa-ur10/ur10.toml")
            .or_else(|_| crate::robot::builtin::load("examples/ipa-ur10/ur10.toml"))
            .unwrap();
        let plain = ur_yaml(&ur).unwrap();
        assert!(plain.starts_with("# kinematics_params_file of the calibrated robot \"ur10\" "));
        ur.name = "R&D <arm> \"x\"\nkinematics: {}\r\\".into();
        let y = ur_yaml(&ur).unwrap();
        let first = y.lines().next().unwrap();
        assert_eq!(
            first,
            r#"# kinematics_params_file of the calibrated robot "R&D <arm> \"x\"\nkinematics: {}\r\\" (calbench identify)"#
        );
        // Past the comment, the file is the plain name's line for line.
        assert_eq!(
            y.lines().skip(1).take(36).collect::<Vec<_>>(),
            plain.lines().skip(1).take(36).collect::<Vec<_>>()
        );
        assert_eq!(
            y.lines().filter(|l| l.starts_with("kinematics:")).count(),
            1
        );
    }

    #[test]
    fn dh_csv_has_a_row_per_parameter_with_delta_and_sigma() {
        let r = crate::robot::builtin::load("irb2600").unwrap();
        let id = r.with_errors(&[(Param::A(1), 0.25)]);
        let csv = dh_csv(&r, &id, &[Param::A(1)], &[0.01]);
        assert!(csv.starts_with("joint,parameter,unit,nominal,identified,delta,sigma\n"));
        let row = csv.lines().find(|l| l.starts_with("2,a,")).unwrap();
        let f: Vec<&str> = row.split(',').collect();
        assert!((f[5].parse::<Real>().unwrap() - 0.25).abs() < 1e-9, "{row}");
        assert_eq!(f[6], "0.01");
        assert_eq!(csv.lines().count(), 1 + r.params().len());
    }
}
