//! Built-in robots with the source of every number.
//!
//! Built-ins take joint values in degrees (revolute) and mm (prismatic). `calbench robots NAME`
//! prints one as a robot file to copy and edit.

use std::path::Path;

use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::robot::{read_robot_file, Convention, Coupling, Joint, JointType, Param, Robot, Units};

/// A built-in robot's entry in the table.
pub struct Builtin {
    /// Name used on the command line and in scenarios.
    pub name: &'static str,
    /// One line on what it is and where its numbers come from.
    pub summary: &'static str,
    /// Builds the robot.
    pub build: fn() -> Robot,
    /// Default joint stiffness (N·m/rad revolute, N/mm prismatic) for gravity sag.
    pub stiffness: &'static [Real],
    /// Default link masses (kg) for gravity sag.
    pub link_mass_kg: &'static [Real],
}

/// IRB2600ID joint stiffness (both of its models). Guessed: of the order reported for arms of
/// this class (10⁶–10⁷ N·m/rad on the main axes), chosen so that the gravity sag with
/// [`IRB2600_LINK_MASS_KG`] and no payload has a median of 0.19 mm over uniform joint poses
/// (p95 0.37, max 0.41 mm; measured by `compliance::tests::sag_of_builtins`), about 20 % of
/// Li 2018's pre-calibration RMS error of 0.83 mm (Li 2018 §1: ~20 % of the error is
/// non-geometric).
const IRB2600_STIFFNESS: [Real; 6] = [4.0e6, 3.5e6, 2.5e6, 4.0e5, 4.0e5, 2.0e5];

/// IRB2600ID link masses (kg, both of its models). Guessed from its total mass (about
/// 284 kg, ABB product specification), less the fixed base.
const IRB2600_LINK_MASS_KG: [Real; 6] = [60.0, 40.0, 25.0, 10.0, 4.0, 1.0];

/// TX60 joint stiffnesses (N·m/rad), guessed, scaled down from the IRB2600 values for a 51 kg
/// arm (Stäubli data sheet): median sag 0.09 mm over uniform poses (max 0.23 mm), a realistic
/// share of a small arm's sub-millimetre pre-calibration error.
const TX60_STIFFNESS: [Real; 6] = [2.0e5, 2.0e5, 1.0e5, 1.5e4, 1.5e4, 5.0e3];
/// TX60 link masses (kg), guessed as the stiffnesses.
const TX60_LINK_MASS_KG: [Real; 6] = [12.0, 10.0, 6.0, 3.0, 1.5, 0.5];

/// The built-in robots.
pub const BUILTINS: &[Builtin] = &[
    Builtin {
        name: "irb2600",
        summary: "ABB IRB2600ID-8/2.0, standard DH (Li 2018 table 1)",
        build: irb2600,
        stiffness: &IRB2600_STIFFNESS,
        link_mass_kg: &IRB2600_LINK_MASS_KG,
    },
    Builtin {
        name: "irb2600-mdh",
        summary: "the same ABB IRB2600ID in Craig's MD-H with β2 on the parallel joints 2/3 (Ban)",
        build: irb2600_mdh,
        stiffness: &IRB2600_STIFFNESS,
        link_mass_kg: &IRB2600_LINK_MASS_KG,
    },
    Builtin {
        name: "tx60",
        summary: "Stäubli TX60, DH + β (Qiao 2021 table 1)",
        build: tx60,
        stiffness: &TX60_STIFFNESS,
        link_mass_kg: &TX60_LINK_MASS_KG,
    },
    Builtin {
        name: "tx60-floor",
        summary: "the same Stäubli TX60 with its base frame at the mounting face, 375 mm below \
                  the shoulder (d1 = 375 mm; Qiao 2021's cube)",
        build: tx60_floor,
        stiffness: &TX60_STIFFNESS,
        link_mass_kg: &TX60_LINK_MASS_KG,
    },
    Builtin {
        name: "guo-3t2r",
        summary: "approximation of Guo 2024's 3T2R arm rebuilt from its GCN tables: differential \
                  screws 1/2, revolute J4-J5 at 45°, screw J3 last, β on joint 2 (lengths guessed)",
        build: guo_3t2r,
        // Guessed. Joints 1, 3 and 4 are revolute (N·m/rad); joints 2 and 5 are ball screws
        // (N/mm), rigid in the sag model.
        stiffness: &[1.0e6, 2.0e5, 5.0e4, 2.0e4, 2.0e5],
        link_mass_kg: &[20.0, 15.0, 10.0, 3.0, 1.0],
    },
];

/// The built-in called `name`.
pub fn builtin(name: &str) -> Option<&'static Builtin> {
    BUILTINS.iter().find(|b| b.name == name)
}

/// A robot by built-in name or robot-file path.
pub fn load(name_or_path: impl AsRef<Path>) -> Result<Robot> {
    load_chain(name_or_path, &crate::robot::urdf::UrdfChain::default())
}

/// [`load`], a URDF's chain chosen by `which` (`--base`, `--tip`; refused for a robot that
/// is not a URDF).
pub fn load_chain(
    name_or_path: impl AsRef<Path>,
    which: &crate::robot::urdf::UrdfChain,
) -> Result<Robot> {
    let path = name_or_path.as_ref();
    let name_or_path = path.display();
    let urdf = path.exists() && crate::robot::urdf::is_urdf(path);
    if !urdf && *which != crate::robot::urdf::UrdfChain::default() {
        let msg = crate::error::Said::default()
            .name(crate::error::Opt::Base)
            .text(" and ");
        let msg = msg.name(crate::error::Opt::Tip);
        let msg = msg.text(format!(
            " choose a chain of a URDF; \"{name_or_path}\" is not one"
        ));
        // Named by the option given (the tip when both are).
        let given = match which.tip {
            None => crate::error::Opt::Base,
            Some(_) => crate::error::Opt::Tip,
        };
        return Err(Error::option(given, msg));
    }
    if let Some(b) = path.to_str().and_then(builtin) {
        return Ok((b.build)());
    }
    if urdf {
        return Ok(crate::robot::urdf::UrdfRobot::load_chain(path, which)?.robot);
    }
    // A path that cannot be resolved (a symlink loop, a folder without permission) is named
    // with the system's reason, not as a name calbench does not know.
    if path.try_exists().map_err(|e| Error::io(path, e))? {
        return read_robot_file(path);
    }
    let names: Vec<&str> = BUILTINS.iter().map(|b| b.name).collect();
    Err(Error::setting(
        "robot",
        format!(
            "\"{name_or_path}\" is neither a built-in robot ({}) nor an existing robot file",
            names.join(", ")
        ),
    ))
}

/// One row of a DH-style table in file units (deg, mm): (θ, d, a, α, β, limits).
type Row = (Real, Real, Real, Real, Real, (Real, Real));

fn from_table(name: &str, convention: Convention, kinds: &[JointType], rows: &[Row]) -> Robot {
    let n = rows.len();
    let deg = std::f64::consts::PI / 180.0;
    let mut values = vec![0.0; crate::robot::value_count(n)];
    let mut joints = Vec::with_capacity(n);
    for (j, &(theta, d, a, alpha, beta, (lo, hi))) in rows.iter().enumerate() {
        values[Param::Theta(j).index(n)] = theta * deg;
        values[Param::D(j).index(n)] = d;
        values[Param::A(j).index(n)] = a;
        values[Param::Alpha(j).index(n)] = alpha * deg;
        values[Param::Beta(j).index(n)] = beta * deg;
        let f = if kinds[j] == JointType::Revolute {
            deg
        } else {
            1.0
        };
        joints.push(Joint {
            kind: kinds[j],
            limits: (lo * f, hi * f),
        });
    }
    Robot {
        name: name.into(),
        convention,
        joints,
        values,
        units: Units::DEG_MM,
        coupling: None,
        beta_joints: None,
        link_mass_kg: builtin(name)
            .filter(|b| b.link_mass_kg.len() == n)
            .map(|b| b.link_mass_kg.to_vec()),
    }
}

const R6: [JointType; 6] = [JointType::Revolute; 6];

/// ABB IRB2600ID-8/2.0 in standard DH.
///
/// Geometry: Li 2018 table 1.
/// Joint limits: ABB IRB 2600ID product specification, working range per axis:
/// axis 1 ±180°, axis 2 +155°/−95°, axis 3 +75°/−180°, axis 4 ±175°, axis 5 ±120°,
/// axis 6 ±400°.
pub fn irb2600() -> Robot {
    from_table(
        "irb2600",
        Convention::Dh,
        &R6,
        &[
            (0.0, 445.0, 150.0, -90.0, 0.0, (-180.0, 180.0)),
            (-90.0, 0.0, 900.0, 0.0, 0.0, (-95.0, 155.0)),
            (0.0, 0.0, 150.0, -90.0, 0.0, (-180.0, 75.0)),
            (0.0, 938.0, 0.0, 90.0, 0.0, (-175.0, 175.0)),
            (0.0, 0.0, 0.0, -90.0, 0.0, (-120.0, 120.0)),
            (180.0, 200.0, 0.0, 0.0, 0.0, (-400.0, 400.0)),
        ],
    )
}

/// The IRB2600ID of [`irb2600`] rewritten in Craig's MD-H (Ban, eq. 1): row i holds
/// α_{i−1}, a_{i−1} of the DH table (`Tx(a)Rx(α)` commutes), so the same joint values give the
/// same flange frame; β2 (about y after joint 2) models the non-parallelism of axes 2 and 3,
/// and no other joint carries a β.
pub fn irb2600_mdh() -> Robot {
    let mut r = from_table(
        "irb2600-mdh",
        Convention::Mdh,
        &R6,
        &[
            // (θ, d, a_{i-1}, α_{i-1}, β, limits)
            (0.0, 445.0, 0.0, 0.0, 0.0, (-180.0, 180.0)),
            (-90.0, 0.0, 150.0, -90.0, 0.0, (-95.0, 155.0)),
            (0.0, 0.0, 900.0, 0.0, 0.0, (-180.0, 75.0)),
            (0.0, 938.0, 150.0, -90.0, 0.0, (-175.0, 175.0)),
            (0.0, 0.0, 0.0, 90.0, 0.0, (-120.0, 120.0)),
            (180.0, 200.0, 0.0, -90.0, 0.0, (-400.0, 400.0)),
        ],
    );
    // β only on joint 2, whose axis is parallel to joint 3's (Ban): elsewhere the
    // neighbouring axes are not parallel and α models the tilt.
    r.beta_joints = Some(vec![1]);
    r
}

/// Stäubli TX60 in DH + β.
///
/// Geometry: Qiao 2021 table 1 (θ, α in rad there:
/// π, π/2, … written here in degrees). Joint limits: Stäubli TX60 data sheet, working range
/// J1 ±180°, J2 ±127.5°, J3 ±142.5°, J4 ±270°, J5 +133.5°/−121°, J6 ±270°.
pub fn tx60() -> Robot {
    from_table(
        "tx60",
        Convention::DhBeta,
        &R6,
        &[
            (180.0, 0.0, 0.0, 90.0, 0.0, (-180.0, 180.0)),
            (90.0, 0.0, 290.0, 0.0, 0.0, (-127.5, 127.5)),
            (90.0, 20.0, 0.0, 90.0, 0.0, (-142.5, 142.5)),
            (180.0, 310.0, 0.0, 90.0, 0.0, (-270.0, 270.0)),
            (180.0, 0.0, 0.0, 90.0, 0.0, (-121.0, 133.5)),
            (0.0, 70.0, 0.0, 0.0, 0.0, (-270.0, 270.0)),
        ],
    )
}

/// [`tx60`] with its base frame at the arm's mounting face. Qiao's table 1 starts the chain at
/// the shoulder (d1 = 0); the mounting face is 375 mm below it (ROS-Industrial's
/// `staubli_tx60_support`, `urdf/tx60_macro.xacro`: joint 1 at z = 0.375 m above
/// `base_link`), so d1 = 375 mm here. Qiao places the poses in a 1000 mm cube centred at
/// (550, 0, 550) mm of the robot's base frame, which the arm (670 mm from the shoulder to the
/// flange) reaches in its lower part from the mounting face; from the shoulder the cube's centre
/// is 778 mm away.
pub fn tx60_floor() -> Robot {
    let mut r = tx60();
    r.name = "tx60-floor".into();
    let n = r.dof();
    r.values[Param::D(0).index(n)] = 375.0;
    r
}

/// The 24 TX60 parameters Qiao 2021 identifies (§3.2): θ, d, a, α of every joint except
/// d2 (joints 2 and 3 are parallel, so d2 is not identifiable and β2 describes their
/// relative tilt instead), plus β2, in that order.
pub fn tx60_qiao_params() -> Vec<Param> {
    let mut v = Vec::new();
    for j in 0..6 {
        v.extend([Param::Theta(j), Param::D(j), Param::A(j), Param::Alpha(j)]);
    }
    v.retain(|p| *p != Param::D(1));
    v.push(Param::Beta(1));
    v
}

/// An approximation of Guo 2024's 3T2R arm (§1.1 and fig. 1), rebuilt from what Guo's
/// tables 1–7 imply about the chain. The paper gives the structure but not the geometry.
///
/// From the paper: joints J1–J3 are ball screws; J1 and J2 drive link 1 together, in
/// parallel and differentially, so that link 1 turns by ψ = atan(s_x(φ1 − φ2)/(2π L1)) and
/// moves by ξ = s_x(φ1 + φ2)/(4π) ([`Coupling::Differential`]); ψ stays within ±45°
/// (eq. 17); J4 and J5 are revolute with axes at 45°.
///
/// From Guo's tables (Guo's parameter names): d2/d3 are dependent (table 3) so z1 ∥ z2 in
/// every pose (α2 = 0, the one adjacent parallel pair, where β2 lives, eq. 5); a4/a5 are
/// dependent (table 2) so x4 ∥ x5 in every pose (no joint turns in the last link); a1, a2,
/// a3, d1, d4, d5 are in no dependency; the θ block is well-conditioned (table 1), so the
/// measured point lies off every revolute axis.
///
/// calbench's chain has one joint variable per link, so Guo's A1 (ψ and ξ together) and
/// fixed A5 cannot be copied; **chosen** instead, a standard-DH chain whose parameters of the
/// same names have exactly those dependencies (`calbench identifiability --robot guo-3t2r
/// --gcn-blocks` removes d3 and a5 and nothing else): joint 1 revolute (ψ, the turntable
/// about the vertical, α1 = −90°), joint 2 prismatic (ξ, horizontal, θ2 = 90° so that x2 is
/// not x1), joint 3 revolute (J4) about an axis parallel to the ξ screw (α2 = 0, β2 between
/// them), joint 4 revolute (J5) at 45° to J4 (α3 = 45°), joint 5 prismatic (the screw J3,
/// placed last so that its travel turns no axis: x4 ∥ x5 with θ5 = 0, α4 = 90°). A vertical
/// J3 next to the vertical ψ would make d1 dependent on d2, which Guo's tables rule out.
/// Joint values: q1, q2 are the two screw travels (mm), q3, q4 in degrees, q5 the J3 travel
/// (mm).
///
/// The model is Guo's position error model (eqs. 5–7): θ, d, a, α of the five joints and
/// Hayati's β on joint 2 alone (nominal 0), 21 parameters; Guo introduces β2 for the arm's one
/// pair of adjacent parallel joints (the text under eq. 6) and sets ∂A_i/∂β_i = 0 for every
/// other joint. The convention is `dh_beta` with [`Robot::beta_joints`] = joint 2.
///
/// **Guessed** (not in the paper): every length (d1 = 400, d2 = 300, a2 = 100, a3 = 100,
/// d4 = 150 mm, tool point (50, 30, 60) mm, off every revolute axis), L1 = 400 mm, the screw
/// travels 0–400 mm (which keep |ψ| ≤ 45° as eq. 17 asks), the J3 travel 0–500 mm and the
/// ranges of J4 (±180°) and J5 (±120°).
pub fn guo_3t2r() -> Robot {
    use JointType::{Prismatic, Revolute};
    let mut r = from_table(
        "guo-3t2r",
        Convention::DhBeta,
        &[Revolute, Prismatic, Revolute, Revolute, Prismatic],
        &[
            // (θ, d, a, α, β, limits); limits of joints 1–2 are screw travels in mm.
            (0.0, 400.0, 0.0, -90.0, 0.0, (0.0, 400.0)),
            (90.0, 300.0, 100.0, 0.0, 0.0, (0.0, 400.0)),
            (0.0, 0.0, 100.0, 45.0, 0.0, (-180.0, 180.0)),
            (0.0, 150.0, 0.0, 90.0, 0.0, (-120.0, 120.0)),
            (0.0, 0.0, 0.0, 0.0, 0.0, (0.0, 500.0)),
        ],
    );
    // Joint 1's limits are screw travels (mm), not angles.
    r.joints[0].limits = (0.0, 400.0);
    r.coupling = Some(Coupling::Differential { l1_mm: 400.0 });
    r.beta_joints = Some(vec![1]);
    r.set(Param::Tool(0), 50.0);
    r.set(Param::Tool(1), 30.0);
    r.set(Param::Tool(2), 60.0);
    r
}
