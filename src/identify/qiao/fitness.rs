//! Qiao 2021's fitness (eq. 14) and the direct identification on the forward kinematics
//! that the searches minimise ([`MetaProblem`]).

use super::search::Bounds;
use crate::error::{Error, Result};
use crate::numeric::{Frame, Mat3, Real, Vec3};
use crate::robot::jacobian::LANES;
use crate::robot::{Chain, ChainVars, Param, Robot, MAX_JOINTS};

/// One pose's term of Qiao's fitness (eq. 14): `k(|Δn| + |Δo| + |Δa|) + |Δp|`, where n, o, a
/// are the columns of the rotation and p the position of the measured and the model frame.
#[inline]
pub fn qiao_term(measured: &Frame, model: &Frame, k: Real) -> Real {
    let dr = measured.rot - model.rot;
    k * (dr.column(0).norm() + dr.column(1).norm() + dr.column(2).norm())
        + (measured.pos - model.pos).norm()
}

/// Qiao 2021's fitness (eq. 14): `Σ_j [k(|Δn_j| + |Δo_j| + |Δa_j|) + |Δp_j|]` over the poses,
/// between measured frames and model frames (in pairs; extra frames of the longer list are
/// ignored). `k` (mm) weighs the dimensionless orientation terms against the position in mm;
/// Qiao gives no value.
pub fn qiao_fitness(measured: &[Frame], model: &[Frame], k: Real) -> Real {
    measured
        .iter()
        .zip(model)
        .map(|(m, t)| qiao_term(m, t, k))
        .sum()
}

/// Default `k` of eq. 14 (mm per unit of `|Δn| + |Δo| + |Δa|`). Qiao gives no value; with
/// 100 mm, an orientation error of 0.001 rad (whose three column differences sum to about
/// 0.002–0.003) weighs like 0.2–0.3 mm, the order of the position errors of Qiao's TX60.
pub const DEFAULT_K: Real = 100.0;

/// Largest `k` (mm per rad, or per unit of eq. 14's column differences): an orientation error
/// of 1 rad then weighs as a position error of 1 km, the bound of a measured coordinate
/// ([`crate::measurement::csv::MAX_POINT_MM`]). Beyond it the orientation rows outweigh the
/// position rows so far that a solve loses rank, and from about 1e154 their squares overflow
/// and it stops, diverged, before its first step.
pub const MAX_K: Real = 1e6;

/// Refuses `k` unless it is finite, positive and at most [`MAX_K`] (the error names `k`).
pub fn check_k(k: Real) -> Result<()> {
    if k.is_finite() && k > 0.0 && k <= MAX_K {
        return Ok(());
    }
    Err(Error::setting(
        "k",
        format!(
            "must be finite, positive and at most {MAX_K:e} mm per rad, got {}",
            crate::error::shown(k)
        ),
    ))
}

/// Largest flat parameter vector handled by [`MetaProblem`] ([`MAX_JOINTS`] joints).
const MAX_VALUES: usize = 6 * MAX_JOINTS + 12;

/// Direct identification on the forward kinematics with Qiao's fitness (eq. 14, §4.2 "error
/// model 3"): the unknowns are errors `x` of `params` added to the nominal robot, and
/// `fitness(x) = Σ_j [k(|Δn| + |Δo| + |Δa|) + |Δp|]` between the measured frames and the
/// forward kinematics of the corrected robot (position-only data: `Σ_j |Δp|`).
///
/// The measured frames are in the robot's world (base-frame) coordinates. The fitness is
/// allocation-free: it walks the nominal robot's [`Chain`] with the errors added to its
/// operations ([`Chain::op_values`], [`Chain::walk_lanes_values`]), from each pose's chain
/// variables and their sines and cosines computed once ([`Chain::variables_of`]), so no robot
/// or chain is built per call.
#[derive(Clone, Debug)]
pub struct MetaProblem<'a> {
    nominal: &'a Robot,
    /// The nominal robot's compiled chain, whose operations the fitness walks.
    chain: Chain,
    params: Vec<Param>,
    qs: Vec<Vec<Real>>,
    points: Vec<Vec3>,
    rotations: Option<Vec<Mat3>>,
    /// The weight of eq. 14 (mm per unit of orientation error).
    k: Real,
    flat: Vec<usize>,
    /// The chain variables of every pose and their sines and cosines.
    vars: Vec<ChainVars>,
    /// `√w_j` of each pose's prior weight, if any.
    point_scale: Option<Vec<Real>>,
    /// Whether the model has joint compliances (searched, or in the nominal robot): the
    /// fitness then uses the elasto-geometric forward kinematics.
    compliant: bool,
    /// The payload of each pose (kg), for the elasto-geometric model.
    loads: Option<Vec<Real>>,
}

impl<'a> MetaProblem<'a> {
    /// A problem over the errors of `params` of `nominal`, with joint values `qs` (internal
    /// units), measured tool points (mm, world) and optionally measured tool rotations, and
    /// the weight `k` of eq. 14.
    pub fn new(
        nominal: &'a Robot,
        params: Vec<Param>,
        qs: Vec<Vec<Real>>,
        points: Vec<Vec3>,
        rotations: Option<Vec<Mat3>>,
        k: Real,
    ) -> Result<MetaProblem<'a>> {
        let dof = nominal.dof();
        if dof > MAX_JOINTS {
            return Err(Error::setting(
                "robot",
                format!("at most {MAX_JOINTS} joints are supported"),
            ));
        }
        if params.is_empty() {
            return Err(Error::setting("params", "no parameters to identify"));
        }
        let all = nominal.params();
        let mut flat = Vec::with_capacity(params.len());
        for p in &params {
            let compliance_ok = matches!(*p, Param::Compliance(j)
                if j < dof && nominal.joints[j].kind == crate::robot::JointType::Revolute);
            if !(all.contains(p) || compliance_ok) {
                return Err(Error::setting(
                    "params",
                    format!("{p} is not a parameter of robot {}", nominal.name),
                ));
            }
            let i = p.index(dof);
            if flat.contains(&i) {
                return Err(Error::setting("params", format!("{p} is listed twice")));
            }
            flat.push(i);
        }
        if qs.is_empty() {
            return Err(Error::setting("poses", "no poses"));
        }
        if points.len() != qs.len() {
            return Err(Error::setting(
                "measurements",
                format!("{} poses but {} measured points", qs.len(), points.len()),
            ));
        }
        if let Some(r) = &rotations {
            if r.len() != qs.len() {
                return Err(Error::setting(
                    "measurements",
                    format!("{} poses but {} measured rotations", qs.len(), r.len()),
                ));
            }
        }
        if !(k.is_finite() && k >= 0.0) {
            return Err(Error::setting(
                "k",
                format!("must be finite and non-negative, got {k}"),
            ));
        }
        for (i, q) in qs.iter().enumerate() {
            if q.len() != dof || q.iter().any(|v| !v.is_finite()) {
                return Err(Error::setting(
                    "poses",
                    format!("pose {i}: expected {dof} finite joint values"),
                ));
            }
            if !points[i].iter().all(|v| v.is_finite()) {
                return Err(Error::setting(
                    "measurements",
                    format!("pose {i}: non-finite point"),
                ));
            }
        }
        let chain = nominal.chain();
        let vars = chain.variables_of(&qs);
        let compliant = params.iter().any(|p| p.is_compliance())
            || crate::robot::compliance::is_compliant(nominal);
        Ok(MetaProblem {
            nominal,
            params,
            qs,
            points,
            rotations,
            k,
            chain,
            flat,
            vars,
            point_scale: None,
            compliant,
            loads: None,
        })
    }

    /// Sets the payload of each pose (kg; `None`: no payload), under which an
    /// elasto-geometric model deflects the arm. Fails unless there is one finite payload ≥ 0
    /// per pose.
    pub fn with_payloads(mut self, loads: Option<&[Real]>) -> Result<Self> {
        if let Some(w) = loads {
            crate::robot::compliance::check_payloads(w, self.qs.len())?;
        }
        self.loads = loads.map(<[Real]>::to_vec);
        Ok(self)
    }

    /// Weighs pose `j`'s term of the fitness by `√w_j` (the weights `w_j ∝ 1/σ_j²` of
    /// [`crate::measurement::Measurements::weights`]: a sum of norms divided by each point's
    /// σ). `None` leaves every term at 1. Fails unless there is one finite, positive weight
    /// per pose.
    pub fn with_weights(mut self, w: Option<&[Real]>) -> Result<Self> {
        if let Some(w) = w {
            if w.len() != self.qs.len() || w.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(Error::setting(
                    "weights",
                    format!(
                        "need {} finite positive weights, got {}",
                        self.qs.len(),
                        w.len()
                    ),
                ));
            }
        }
        self.point_scale = w.map(|w| w.iter().map(|v| v.sqrt()).collect());
        Ok(self)
    }

    /// A problem from measured frames (full pose: position and rotation).
    pub fn from_frames(
        nominal: &'a Robot,
        params: Vec<Param>,
        qs: Vec<Vec<Real>>,
        measured: &[Frame],
        k: Real,
    ) -> Result<MetaProblem<'a>> {
        let points = measured.iter().map(|f| f.pos).collect();
        let rots = measured.iter().map(|f| f.rot).collect();
        MetaProblem::new(nominal, params, qs, points, Some(rots), k)
    }

    /// The nominal robot with the errors `x` added (the identified robot).
    pub fn robot(&self, x: &[Real]) -> Result<Robot> {
        if x.len() != self.params.len() {
            return Err(Error::setting(
                "x",
                format!("expected {} values, got {}", self.params.len(), x.len()),
            ));
        }
        let errs: Vec<(Param, Real)> = self.params.iter().copied().zip(x.iter().copied()).collect();
        Ok(self.nominal.with_errors(&errs))
    }

    /// Bounds of half width `length_mm` on length parameters, `angle_rad` on angles and
    /// `compliance` (rad/(N·m)) on joint compliances.
    pub fn bounds(&self, length_mm: Real, angle_rad: Real, compliance: Real) -> Bounds {
        let widths = [length_mm, angle_rad, compliance];
        let w: Vec<Real> = self.params.iter().map(|&p| widths[box_side(p)]).collect();
        Bounds::symmetric(&w)
    }

    /// Pose `j`'s term of the fitness for the model frame `(r, p)`.
    #[inline(always)]
    fn term(&self, j: usize, r: &Mat3, p: &Vec3) -> Real {
        let position = (self.points[j] - p).norm();
        let orientation = self.rotations.as_ref().map_or(0.0, |rots| {
            let dr = rots[j] - r;
            self.k * (dr.column(0).norm() + dr.column(1).norm() + dr.column(2).norm())
        });
        match &self.point_scale {
            None => position + orientation,
            Some(s) => s[j] * (position + orientation),
        }
    }

    /// The fitness of an elasto-geometric model: the corrected robot's forward kinematics
    /// under each pose's payload ([`crate::robot::loaded::loaded_fk`]). Builds the robot (this
    /// path allocates); `+∞` when a pose cannot be evaluated.
    fn fitness_loaded(&self, x: &[Real]) -> Real {
        let Ok(robot) = self.robot(x) else {
            return Real::INFINITY;
        };
        let chain = robot.chain();
        let mut total = 0.0;
        for (j, q) in self.qs.iter().enumerate() {
            let load = self.loads.as_ref().map_or(0.0, |l| l[j]);
            match crate::robot::loaded::loaded_fk(&robot, &chain, q, load) {
                Ok(f) => total += self.term(j, &f.rot, &f.pos),
                Err(_) => return Real::INFINITY,
            }
        }
        total
    }

    /// Qiao's fitness (eq. 14) of the errors `x`; `+∞` if `x` has the wrong length.
    /// Allocation-free.
    pub fn fitness(&self, x: &[Real]) -> Real {
        if x.len() != self.flat.len() {
            return Real::INFINITY;
        }
        if self.compliant {
            return self.fitness_loaded(x);
        }
        let mut errors = [0.0; MAX_VALUES];
        for (&i, &v) in self.flat.iter().zip(x) {
            errors[i] = v;
        }
        let values = self.chain.op_values(&errors);
        // Four poses per chain walk (four-wide vectors where the processor has AVX2), the rest
        // one by one; the terms summed in pose order.
        crate::numeric::simd::dispatch(
            #[inline(always)]
            |_| {
                let mut total = 0.0;
                let whole = self.vars.len() / LANES * LANES;
                for j0 in (0..whole).step_by(LANES) {
                    let vars: [&ChainVars; LANES] = std::array::from_fn(|l| &self.vars[j0 + l]);
                    let f = self.chain.walk_lanes_values(&values, vars, |_, _| {});
                    for l in 0..LANES {
                        total += self.term(j0 + l, &f.rot(l), &f.pos(l));
                    }
                }
                for j in whole..self.vars.len() {
                    let f = self
                        .chain
                        .walk_lanes_values(&values, [&self.vars[j]], |_, _| {});
                    total += self.term(j, &f.rot(0), &f.pos(0));
                }
                total
            },
        )
    }

    /// The model frames of the corrected robot at every pose (for reports; allocates).
    pub fn frames(&self, x: &[Real]) -> Result<Vec<Frame>> {
        let r = self.robot(x)?;
        let chain = r.chain();
        Ok(self.qs.iter().map(|q| chain.fk(q)).collect())
    }
}

/// Which of a search box's three half-widths bounds parameter `p`: 0 on lengths (mm), 1 on
/// angles (rad), 2 on joint compliances (rad/(N·m)).
pub fn box_side(p: Param) -> usize {
    if p.is_compliance() {
        2
    } else if p.is_length() {
        0
    } else {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::{stream, Rng};
    use approx::assert_relative_eq;
    use rand::Rng as _;

    fn key(e: Error) -> String {
        e.key()
            .unwrap_or_else(|| panic!("not a setting error: {e}"))
            .into()
    }

    #[test]
    fn qiao_term_by_hand() {
        let m = Frame::from_xyz_rpy([1.0, 2.0, 3.0], [0.0, 0.0, 0.0]);
        let t = Frame {
            rot: crate::numeric::rot_z(0.1),
            pos: Vec3::new(4.0, 6.0, 3.0),
        };
        // |Δp| = 5; Rz(0.1) moves n and o each by 2 sin(0.05), a not at all.
        let expect = 5.0 + 10.0 * 2.0 * (2.0 * (0.05 as Real).sin());
        assert_relative_eq!(qiao_term(&m, &t, 10.0), expect, epsilon = 1e-12);
        assert_relative_eq!(qiao_fitness(&[m, m], &[t, t], 10.0), 2.0 * expect);
    }

    fn random_x(n: usize, rng: &mut Rng, scale: Real) -> Vec<Real> {
        (0..n)
            .map(|_| scale * rng.random_range(-1.0..1.0))
            .collect()
    }

    #[test]
    fn problem_fitness_matches_forward_kinematics() {
        // Independent truth: the robot with the errors applied, through Chain::fk.
        let mut rng = stream(5, "t");
        for name in ["tx60", "irb2600-mdh", "guo-3t2r"] {
            let nominal = crate::robot::builtin::load(name).unwrap();
            let params = nominal.params();
            let qs = crate::robot::sampling::uniform_joint_poses(&nominal, 7, &mut rng);
            let x_true = random_x(params.len(), &mut rng, 0.05);
            let p0 = MetaProblem::new(
                &nominal,
                params.clone(),
                qs.clone(),
                vec![Vec3::zeros(); qs.len()],
                None,
                1.0,
            )
            .unwrap();
            let truth = p0.frames(&x_true).unwrap();
            let full = MetaProblem::from_frames(&nominal, params.clone(), qs.clone(), &truth, 37.0)
                .unwrap();
            let points = truth.iter().map(|f| f.pos).collect();
            let pos =
                MetaProblem::new(&nominal, params.clone(), qs.clone(), points, None, 37.0).unwrap();
            assert!(full.fitness(&x_true) < 1e-9, "{name}");
            for _ in 0..3 {
                let x = random_x(params.len(), &mut rng, 0.05);
                let model = full.frames(&x).unwrap();
                assert_relative_eq!(
                    full.fitness(&x),
                    qiao_fitness(&truth, &model, 37.0),
                    max_relative = 1e-10
                );
                let by_points: Real = truth
                    .iter()
                    .zip(&model)
                    .map(|(t, m)| (t.pos - m.pos).norm())
                    .sum();
                assert_relative_eq!(pos.fitness(&x), by_points, max_relative = 1e-10);
            }
            assert_eq!(full.fitness(&[0.0]), Real::INFINITY);
        }
    }

    #[test]
    fn problem_refuses_bad_inputs() {
        let nominal = crate::robot::builtin::load("tx60").unwrap();
        let q = vec![vec![0.0; 6]];
        let pts = vec![Vec3::zeros()];
        let mk = |params: Vec<Param>, qs: Vec<Vec<Real>>, pts: Vec<Vec3>, k: Real| {
            key(MetaProblem::new(&nominal, params, qs, pts, None, k).unwrap_err())
        };
        assert_eq!(mk(vec![], q.clone(), pts.clone(), 1.0), "params");
        assert_eq!(
            mk(vec![Param::A(0), Param::A(0)], q.clone(), pts.clone(), 1.0),
            "params"
        );
        assert_eq!(mk(vec![Param::A(9)], q.clone(), pts.clone(), 1.0), "params");
        assert_eq!(
            mk(vec![Param::A(0)], q.clone(), vec![], 1.0),
            "measurements"
        );
        assert_eq!(
            mk(vec![Param::A(0)], vec![vec![0.0; 5]], pts.clone(), 1.0),
            "poses"
        );
        assert_eq!(mk(vec![Param::A(0)], q.clone(), pts.clone(), -1.0), "k");
    }
}
