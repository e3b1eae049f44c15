//! The forward kinematics of the elasto-geometric model ([`loaded_fk`]): the rigid chain
//! with each joint deflected under load by its compliance ([`super::compliance`]) and offset
//! by its joint-angle harmonics ([`super::harmonics`]) and its mass-free gravity basis
//! ([`super::gravity_basis`]).

use crate::error::Result;
use crate::numeric::{Frame, Real};
use crate::robot::compliance::{deflect_vars, gravity_torques, is_compliant};
use crate::robot::{Chain, Param, Robot, MAX_JOINTS};

/// Whether `robot` has no compliance, harmonic or gravity-basis coefficient: then
/// [`loaded_fk`] is the rigid forward kinematics `chain.fk(q)` at every pose and payload, so a
/// caller walking many poses of one robot decides it once.
pub fn is_rigid(robot: &Robot) -> bool {
    !is_compliant(robot)
        && !crate::robot::harmonics::has_harmonics(robot)
        && !crate::robot::gravity_basis::has_gravity(robot)
}

/// What of `robot`'s model a study does not simulate, as a sentence, or `None`: a study's true
/// robot is the nominal chain with the injected errors, its sag the scenario's `[compliance]`
/// model, so a robot file's joint-angle harmonics, gravity basis or compliances would be in the
/// identified model and not in the simulated truth (docs/formats.md § 4.3).
pub fn unsimulated(robot: &Robot) -> Option<String> {
    use crate::robot::{Param, GRAVITY_POINTS, HARMONIC_TERMS};
    // The parameters of joint `j` that a file's key gives.
    let of = |key: &str, j: usize| -> Vec<Param> {
        match key {
            "harmonics" => (0..HARMONIC_TERMS).map(|k| Param::Harmonic(j, k)).collect(),
            "gravity" => (0..GRAVITY_POINTS).map(|l| Param::Gravity(j, l)).collect(),
            _ => vec![Param::Compliance(j)],
        }
    };
    let given: Vec<String> = ["harmonics", "gravity", "compliance"]
        .into_iter()
        .filter_map(|key| {
            let joints: Vec<String> = (0..robot.dof())
                .filter(|&j| of(key, j).iter().any(|&p| robot.get(p) != 0.0))
                .map(|j| (j + 1).to_string())
                .collect();
            let s = if joints.len() > 1 { "s" } else { "" };
            (!joints.is_empty()).then(|| format!("`{key}` on joint{s} {}", joints.join(", ")))
        })
        .collect();
    if given.is_empty() {
        return None;
    }
    Some(format!(
        "robot \"{}\" gives {}: a study simulates its true robot as the nominal chain with the \
         injected errors, and not a robot file's joint-angle harmonics, gravity basis or \
         compliances, which the identification would model; remove them from the file (a study \
         adds joint-angle errors with [unmodelled] and gravity sag with [compliance])",
        robot.name,
        given.join(", ")
    ))
}

/// [`loaded_fk`] of one robot at many poses, with [`is_rigid`] decided once instead of at each
/// pose (it reads every harmonic and gravity-basis coefficient): the same frames, bit for bit.
pub struct LoadedFk<'a> {
    robot: &'a Robot,
    chain: Chain,
    rigid: bool,
}

impl<'a> LoadedFk<'a> {
    /// The forward kinematics of `robot`.
    pub fn new(robot: &'a Robot) -> LoadedFk<'a> {
        LoadedFk {
            robot,
            chain: robot.chain(),
            rigid: is_rigid(robot),
        }
    }

    /// [`loaded_fk`] at `q` under `payload_kg`.
    pub fn at(&self, q: &[Real], payload_kg: Real) -> Result<Frame> {
        if self.rigid {
            return Ok(self.chain.fk(q));
        }
        loaded_fk(self.robot, &self.chain, q, payload_kg)
    }
}

/// The tool frame of `robot` under the elasto-geometric model at joint values `q` (internal
/// units) with `payload_kg` at the tool point: the forward kinematics with every chain
/// variable `j` deflected by `c_j τ_j(q, payload)` ([`gravity_torques`], the robot's
/// compliances [`Param::Compliance`]) and offset by its joint-angle harmonics
/// ([`crate::robot::harmonics`]) and its mass-free gravity basis
/// ([`crate::robot::gravity_basis`]). The rigid forward kinematics when every compliance,
/// harmonic and gravity-basis coefficient is zero. Fails when compliances are set but the robot gives no link
/// masses.
pub fn loaded_fk(robot: &Robot, chain: &Chain, q: &[Real], payload_kg: Real) -> Result<Frame> {
    if is_rigid(robot) {
        return Ok(chain.fk(q));
    }
    let compliant = is_compliant(robot);
    let harmonic = crate::robot::harmonics::has_harmonics(robot);
    let gravity = crate::robot::gravity_basis::has_gravity(robot);
    let n = robot.dof();
    let mut tau = [0.0; MAX_JOINTS];
    if compliant {
        gravity_torques(robot, chain, q, payload_kg, &mut tau[..n])?;
        for (j, t) in tau.iter_mut().enumerate().take(n) {
            *t *= robot.get(Param::Compliance(j));
        }
    }
    let mut vars = chain.variables(q);
    if harmonic {
        crate::robot::harmonics::add_offsets(&robot.values, &vars, &mut tau[..n]);
    }
    if gravity {
        let mut basis = [[0.0; crate::robot::GRAVITY_POINTS]; MAX_JOINTS];
        crate::robot::gravity_basis::torques(robot, chain, &vars, &mut basis);
        crate::robot::gravity_basis::add_offsets(&robot.values, &basis, &mut tau[..n]);
    }
    deflect_vars(&mut vars, &tau[..n]);
    Ok(chain.walk_vars(&vars, |_, _, _| {}))
}
