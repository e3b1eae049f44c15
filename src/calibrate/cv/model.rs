//! The candidate models of `identify --models` (docs/formats.md `identify`, "Cross-validation
//! and model choice"): their terms, names, parameters and what they leave out at the nominal
//! robot.

use std::str::FromStr;

use crate::calibrate::Registration;
use crate::error::{Error, Result};
use crate::measurement::Measurements;
use crate::robot::compliance::CompliancePick;
use crate::robot::identifiability::identifiable_extension;
use crate::robot::{
    param_sets, Convention, JointType, Param, Robot, MAX_HARMONIC_ORDER, MAX_JOINTS,
};

/// A candidate model of `identify --models`: the kinematic parameters, plus Hayati's β on
/// the joints where it is identifiable (parallel neighbouring axes) and/or the compliances of
/// the joints gravity loads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Model {
    /// β on the joints where it is identifiable (a `dh` robot is read as `dh_beta`, β = 0).
    pub beta: bool,
    /// The compliances of the gravity-loaded joints (needs the robot's link masses).
    pub compliance: bool,
    /// Joint-angle harmonics up to this order (0: none; 1: `sin q`, `cos q`; 2: also
    /// `sin 2q`, `cos 2q`) on every revolute joint, each term kept when it is identifiable
    /// beside the kinematic parameters over generic poses ([`Param::Harmonic`],
    /// [`identifiable_extension`]).
    pub harmonics: u8,
    /// The mass-free gravity basis ([`Param::Gravity`], [`crate::robot::gravity_basis`]):
    /// the joint deflections of unit weights at the elbow, the wrist centre and the tool
    /// point, with free coefficients (no masses needed).
    pub gravity: bool,
    /// Harmonics of chosen orders on chosen joints (`h12q1`: `sin 12q1`, `cos 12q1`): per
    /// joint (0-based), bit `n − 1` for order `n`.
    pub orders: [u16; MAX_JOINTS],
    /// A kernel residual on the joint angles, fitted on the calibration rows after the
    /// parametric terms ([`crate::calibrate::kernel::KernelResidual`]; `gp`).
    pub gp: bool,
}

impl Model {
    /// The plain kinematic model.
    pub const KINEMATIC: Model = Model {
        beta: false,
        compliance: false,
        harmonics: 0,
        gravity: false,
        orders: [0; MAX_JOINTS],
        gp: false,
    };

    /// Whether the model is kinematic only (β included): a task's closed division.
    pub fn is_kinematic(&self) -> bool {
        !self.compliance
            && self.harmonics == 0
            && !self.gravity
            && self.orders == [0; MAX_JOINTS]
            && !self.gp
    }

    /// `kinematic`, or its terms joined by `+` in the order `beta`, `compliance`, `gravity`,
    /// `harmonics`/`harmonics2`, then each `h{n}q{j}` by joint and order, then `gp`
    /// (`beta+compliance`, `gravity+harmonics+h12q1`, `harmonics+gp`).
    pub fn name(&self) -> String {
        let mut terms: Vec<String> = Vec::new();
        if self.beta {
            terms.push("beta".into());
        }
        if self.compliance {
            terms.push("compliance".into());
        }
        if self.gravity {
            terms.push("gravity".into());
        }
        match self.harmonics {
            0 => {}
            1 => terms.push("harmonics".into()),
            _ => terms.push("harmonics2".into()),
        }
        for (j, bits) in self.orders.iter().enumerate() {
            for n in 1..=MAX_HARMONIC_ORDER {
                if bits & (1 << (n - 1)) != 0 {
                    terms.push(format!("h{n}q{}", j + 1));
                }
            }
        }
        if self.gp {
            terms.push("gp".into());
        }
        if terms.is_empty() {
            "kinematic".into()
        } else {
            terms.join("+")
        }
    }

    /// The robot to identify (for β, a `dh` robot as `dh_beta` with β = 0: the same
    /// kinematics) and the parameters: those `identify` takes for measured data
    /// ([`param_sets::identified_params_tool_first`]), plus the gravity joints' compliances
    /// and the identifiable joint-angle harmonics and gravity-basis terms (harmonics first,
    /// then the gravity basis, then the chosen orders), less the `fixed` ones. Fails when a
    /// chosen order names a joint the robot does not have or one that is not revolute, or the
    /// gravity basis is asked of a robot of fewer than four joints.
    pub fn robot_and_params(
        &self,
        nominal: &Robot,
        data: &Measurements,
        registration: Registration,
        fixed: &[Param],
    ) -> Result<(Robot, Vec<Param>)> {
        let robot = self.robot(nominal);
        let with_base = registration == Registration::Identify;
        let mut params =
            param_sets::identified_params_tool_first(&robot, data.measure(), with_base);
        if self.compliance {
            params.extend(
                CompliancePick::Gravity
                    .params(&robot, "models")
                    .map_err(|e| e.of_option(crate::error::Opt::Models))?,
            );
        }
        let extra = self.terms(&robot)?;
        let kept = match extra.is_empty() {
            true => Vec::new(),
            false => identifiable_extension(&robot, &params, &extra, data.measure()),
        };
        self.adds_to(&robot, &kept)?;
        params.extend(kept);
        params.retain(|p| !fixed.contains(p));
        Ok((robot, params))
    }

    /// [`Model::robot_and_params`] and the parameters that the re-check at the identified
    /// robot may re-admit ([`Model::left_out`]): what each fold of its cross-validation
    /// identifies, as `identify` does.
    pub fn for_cv(
        &self,
        nominal: &Robot,
        data: &Measurements,
        registration: Registration,
        fixed: &[Param],
    ) -> Result<(Robot, Vec<Param>, Vec<Param>)> {
        let (robot, params) = self.robot_and_params(nominal, data, registration, fixed)?;
        let candidates = self.left_out(&robot, registration, fixed, &params)?;
        Ok((robot, params, candidates))
    }

    /// The robot whose parameters the model identifies: `nominal`, a `dh` robot read as
    /// `dh_beta` (β = 0, the same kinematics) for a model with `beta`.
    fn robot(&self, nominal: &Robot) -> Robot {
        let mut robot = nominal.clone();
        if self.beta && robot.convention == Convention::Dh {
            robot.convention = Convention::DhBeta;
        }
        robot
    }

    /// The parameters the model offers that [`Model::robot_and_params`] leaves out of
    /// `params` (its choice at the nominal robot): the kinematic parameters of the robot's
    /// model not chosen (the base's only with the `identify` registration) and the harmonic
    /// and gravity-basis terms not kept, in that order, less the `fixed` ones. Compliances
    /// are never left out. These are the candidates that identifiability re-checked at the
    /// identified robot may re-admit ([`crate::calibrate::recheck`]).
    pub fn left_out(
        &self,
        nominal: &Robot,
        registration: Registration,
        fixed: &[Param],
        params: &[Param],
    ) -> Result<Vec<Param>> {
        let robot = self.robot(nominal);
        let with_base = registration == Registration::Identify;
        let kinematic = robot
            .params()
            .into_iter()
            .filter(|p| with_base || !matches!(p, Param::Base(_)));
        Ok(kinematic
            .chain(self.terms(&robot)?)
            .filter(|p| !params.contains(p) && !fixed.contains(p) && !p.is_compliance())
            .collect())
    }

    /// Refuses `harmonics` or `gravity` where none of its terms is among the parameters
    /// `kept` (those the poses can tell apart, [`identifiable_extension`]): the model would be
    /// the kinematic one under another name (`gravity` on a SCARA, whose revolute axes gravity
    /// does not load; `harmonics` on a gantry, which has no revolute joint).
    fn adds_to(&self, robot: &Robot, kept: &[Param]) -> Result<()> {
        let none = |is: fn(&Param) -> bool| !kept.iter().any(is);
        let term = if self.harmonics > 0 && none(|p| matches!(p, Param::Harmonic(..))) {
            "harmonics"
        } else if self.gravity && none(|p| matches!(p, Param::Gravity(..))) {
            "gravity"
        } else {
            return Ok(());
        };
        let msg = format!(
            "`{term}` adds no parameter to robot \"{}\" that the poses can tell apart from \
             the kinematic ones: the model would be `kinematic` under another name",
            robot.name
        );
        Err(Error::option(crate::error::Opt::Models, msg))
    }

    /// The harmonic and gravity-basis terms the model offers on `robot`, before the choice
    /// of the identifiable ones: the harmonics of every revolute joint, the gravity basis,
    /// then the chosen orders. Fails when a chosen order names a joint the robot does not
    /// have or one that is not revolute, or the gravity basis is asked of a robot of fewer
    /// than four joints.
    fn terms(&self, robot: &Robot) -> Result<Vec<Param>> {
        // Every revolute joint's terms that the poses of a generic set can tell apart from
        // the kinematic parameters and from each other: joint 1's harmonics although θ1 is
        // left to base.rz (a constant offset is, sin q1 and cos q1 are not), not the last
        // joint's when the tool point lies on its axis.
        let mut extra: Vec<Param> = Vec::new();
        if self.harmonics > 0 {
            let terms = 2 * usize::from(self.harmonics.min(2));
            extra.extend(
                (0..robot.dof())
                    .filter(|&j| robot.joints[j].kind == JointType::Revolute)
                    .flat_map(|j| (0..terms).map(move |k| Param::Harmonic(j, k))),
            );
        }
        if self.gravity {
            let basis = crate::robot::gravity_basis::params(robot);
            if basis.is_empty() {
                return Err(Error::option(
                    crate::error::Opt::Models,
                    format!(
                        "`gravity`: robot \"{}\" has {} joints; the gravity basis needs an \
                         elbow and a wrist centre (at least four joints)",
                        robot.name,
                        robot.dof()
                    ),
                ));
            }
            extra.extend(basis);
        }
        for (j, bits) in self.orders.iter().enumerate() {
            for n in (1..=MAX_HARMONIC_ORDER).filter(|n| bits & (1 << (n - 1)) != 0) {
                if j >= robot.dof() || robot.joints[j].kind != JointType::Revolute {
                    return Err(Error::option(
                        crate::error::Opt::Models,
                        format!(
                            "`h{n}q{}`: robot \"{}\" has no revolute joint {}",
                            j + 1,
                            robot.name,
                            j + 1
                        ),
                    ));
                }
                for k in [2 * (n - 1), 2 * (n - 1) + 1] {
                    if !extra.contains(&Param::Harmonic(j, k)) {
                        extra.push(Param::Harmonic(j, k));
                    }
                }
            }
        }
        Ok(extra)
    }
}

impl FromStr for Model {
    type Err = String;

    /// `kinematic`, `beta`, `compliance`, `gravity` (the mass-free gravity basis),
    /// `harmonics` (first harmonic), `harmonics2` (first and second), `h{n}q{j}` (the
    /// harmonic of order n, 1 to 16, of joint j), `gp` (a kernel residual on the joint
    /// angles), or terms joined by `+` (`beta+compliance`, `gravity+harmonics+h12q1`,
    /// `harmonics+gp`).
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let mut m = Model::KINEMATIC;
        let terms: Vec<&str> = s.split('+').map(str::trim).collect();
        for (i, term) in terms.iter().enumerate() {
            // Merged silently, a term given twice had named a model other than the one fitted.
            if terms[..i].contains(term) {
                return Err(format!("`{term}` is given twice in `{s}`"));
            }
            match *term {
                "kinematic" => {}
                "beta" => m.beta = true,
                "compliance" => m.compliance = true,
                "gravity" => m.gravity = true,
                "harmonics" => m.harmonics = m.harmonics.max(1),
                "harmonics2" => m.harmonics = 2,
                "gp" => m.gp = true,
                other => {
                    let Some((n, j)) = order_term(other) else {
                        return Err(format!(
                            "unknown model term `{other}`; known: kinematic, beta, compliance, \
                             gravity, harmonics, harmonics2, h{{n}}q{{j}} (order n of 1 to \
                             {MAX_HARMONIC_ORDER} on joint j, `h12q1`), gp (a kernel residual); \
                             joined by +)"
                        ));
                    };
                    m.orders[j - 1] |= 1 << (n - 1);
                }
            }
        }
        // An order `harmonics` (1) or `harmonics2` (1 and 2) already gives every revolute
        // joint is merged into it, as `harmonics` is into `harmonics2`: named again, it would
        // list a term that adds nothing.
        let given = (1u16 << m.harmonics) - 1;
        for bits in &mut m.orders {
            *bits &= !given;
        }
        Ok(m)
    }
}

/// `h{n}q{j}`: the order n (1 to [`MAX_HARMONIC_ORDER`]) and the joint j (1 to
/// [`MAX_JOINTS`]).
fn order_term(term: &str) -> Option<(usize, usize)> {
    let (n, j) = term.strip_prefix('h')?.split_once('q')?;
    let plain =
        |s: &str| !s.is_empty() && !s.starts_with('0') && s.bytes().all(|b| b.is_ascii_digit());
    if !plain(n) || !plain(j) {
        return None;
    }
    let (n, j): (usize, usize) = (n.parse().ok()?, j.parse().ok()?);
    ((1..=MAX_HARMONIC_ORDER).contains(&n) && (1..=MAX_JOINTS).contains(&j)).then_some((n, j))
}
