//! The kinematic identification problem of a robot: measured tool points (and orientations)
//! at known joint values, unknown errors of chosen parameters.
//!
//! The unknown `x` holds the errors added to the nominal values of the chosen parameters
//! (mm, rad); the model is the forward kinematics of the robot with those errors, and the
//! Jacobian is the analytic one of [`crate::robot::jacobian`] (Li 2018 eqs. 6–12). The residual of
//! a point is `p_meas − p_model(x)`; for full poses the orientation rows are
//! `φ = log(R_meas · R_model(x)ᵀ)` with its exact derivative `J_r⁻¹(φ) J_ω`
//! ([`crate::robot::jacobian::log_orientation_rows`]), weighted against the position rows.

use std::cell::RefCell;

use nalgebra::{DMatrix, DVector};

use super::solver::{
    self, rank, solve, solve_from, start_weights, Column, LeastSquares, Matrix, Size, Solver, Work,
};
use super::{CalibrationProblem, Identified, Method, Termination};
use crate::error::Error;
use crate::measurement::Measure;
use crate::numeric::rng::Rng;
use crate::numeric::{Frame, Mat3, Real, Vec3};
use crate::robot::compliance::{deflect_vars, gravity_torques_vars};
use crate::robot::jacobian::{log_orientation_rows, pose_rows4, pose_rows_vars, Columns, LANES};
use crate::robot::{Chain, ChainVars, JointType, Param, Robot, GRAVITY_POINTS, MAX_JOINTS};

/// A [`LeastSquares`] problem over a robot's parameter errors.
#[derive(Debug)]
pub struct RobotProblem<'a> {
    nominal: &'a Robot,
    params: Vec<Param>,
    index: Vec<usize>,
    cols: Columns,
    points: &'a [Vec3],
    rotations: Option<&'a [Mat3]>,
    measure: Measure,
    /// The joint values, from which a streamed problem computes each block's chain
    /// variables.
    qs: &'a [Vec<Real>],
    /// Working parameter values and the chain compiled from them, updated in place at each
    /// evaluation.
    work: RefCell<(Vec<Real>, Chain)>,
    /// The chain variables of every pose and their sines and cosines ([`Chain::variables`]);
    /// empty when the problem is streamed ([`solver::streams`]): then `block_vars` holds
    /// those of one block at a time.
    vars: Vec<ChainVars>,
    block_vars: RefCell<Vec<ChainVars>>,
    /// Weight of the orientation rows of full-pose data, mm per rad.
    orientation_weight: Real,
    /// Prior weight of each point, if any.
    prior: Option<&'a [Real]>,
    /// Tikhonov precision of each parameter (priors towards the nominal value), if any.
    tikhonov: Option<&'a [Real]>,
    /// Where the RMS point residual of each evaluation is recorded, if anywhere.
    trace: Option<super::TraceRecorder>,
    /// The joints whose compliance is identified, with their columns.
    compliant: Vec<(usize, usize)>,
    /// Per point, the payload (kg) under which the elasto-geometric model computes the
    /// gravity torques ([`crate::robot::compliance::gravity_torques`], with the nominal link masses
    /// and the current estimate's geometry); empty when the model has no compliance (none
    /// identified, none in the nominal robot).
    loads: Vec<Real>,
    /// The nominal robot's link masses (kg), when the model has compliances.
    masses: Vec<Real>,
    /// Whether the model has joint-angle harmonics (identified, or in the nominal robot):
    /// each pose's chain variables are then offset by them ([`crate::robot::harmonics`]).
    harmonic: bool,
    /// Whether the model has the mass-free gravity basis (identified, or in the nominal
    /// robot): each pose's chain variables are then offset by `Σ_l k_jl τ_jl`
    /// ([`crate::robot::gravity_basis`]).
    gravity: bool,
    /// The largest distance of a measured point from the base (mm): the scale of the
    /// rounding of the data and of their model ([`LeastSquares::rounding_floor`]).
    largest_point: Real,
}

/// How many units in the last place of the largest point (or of a radian, scaled by the
/// orientation weight) a residual component counts as rounding. The identification's chain
/// walk against the loaded forward kinematics rounds by 0.24 to 0.36 of one (RMS per
/// component) on the IRB 2600, its MDH form, Ban's IRB 2600 and the TX60, on narrow and on
/// uniform poses (`identify::tests::floor`); 16 leaves a wide margin, and on a 2 m arm it is
/// 7e-12 mm, eight orders below a micrometre of noise.
const ROUNDING_ULPS: Real = 16.0;

impl<'a> RobotProblem<'a> {
    /// The problem of identifying the errors of `params` of `nominal` from the tool points
    /// `points` (mm, base frame) and, for full poses, the tool rotations `rotations` measured
    /// at the joint values `qs`.
    ///
    /// Fails when `params` is empty, repeats a parameter or names one the robot's model does
    /// not have, when the data's lengths disagree, a joint vector has the wrong length, a
    /// value is not finite, or `measure` is [`Measure::Pose`] without rotations.
    pub fn new(
        nominal: &'a Robot,
        params: &[Param],
        qs: &'a [Vec<Real>],
        points: &'a [Vec3],
        rotations: Option<&'a [Mat3]>,
        measure: Measure,
    ) -> crate::Result<Self> {
        if params.is_empty() {
            return Err(Error::setting("params", "no parameters to identify"));
        }
        let known = nominal.params();
        for (i, p) in params.iter().enumerate() {
            if let Param::Compliance(j) | Param::Harmonic(j, _) | Param::Gravity(j, _) = *p {
                if j >= nominal.dof() || nominal.joints[j].kind != JointType::Revolute {
                    return Err(Error::setting(
                        p.block(),
                        format!(
                            "`{p}`: robot `{}` has no revolute joint {} (only revolute joints \
                             are compliant or have joint-angle harmonics in calbench's model)",
                            nominal.name,
                            j + 1
                        ),
                    ));
                }
            } else if !known.contains(p) {
                return Err(Error::setting(
                    "params",
                    format!("`{p}` is not a parameter of robot `{}`", nominal.name),
                ));
            }
            if params[..i].contains(p) {
                return Err(Error::setting("params", format!("`{p}` is listed twice")));
            }
        }
        if qs.len() != points.len() {
            return Err(Error::setting(
                "data",
                format!(
                    "{} joint vectors but {} measured points",
                    qs.len(),
                    points.len()
                ),
            ));
        }
        if qs.is_empty() {
            return Err(Error::setting("data", "no measured points"));
        }
        let dof = nominal.dof();
        for (i, q) in qs.iter().enumerate() {
            if q.len() != dof {
                return Err(Error::joint_count(
                    "data",
                    format_args!("point {i}"),
                    q.len(),
                    dof,
                ));
            }
            if q.iter().any(|v| !v.is_finite()) || points[i].iter().any(|v| !v.is_finite()) {
                return Err(Error::setting(
                    "data",
                    format!("point {i}: value not finite"),
                ));
            }
        }
        match (rotations, measure) {
            (None, Measure::Pose) => {
                return Err(Error::setting(
                    "measure",
                    "full-pose identification needs measured orientations",
                ))
            }
            (Some(r), _) if r.len() != points.len() => {
                return Err(Error::setting(
                    "data",
                    format!(
                        "{} orientations but {} measured points",
                        r.len(),
                        points.len()
                    ),
                ))
            }
            (Some(r), Measure::Pose) if r.iter().any(|m| m.iter().any(|v| !v.is_finite())) => {
                return Err(Error::setting("data", "orientation not finite"))
            }
            _ => {}
        }
        let chain = nominal.chain();
        let streamed = solver::streams(qs.len());
        let vars = if streamed {
            Vec::new()
        } else {
            chain.variables_of(qs)
        };
        let block = if streamed { solver::BLOCK_POINTS } else { 0 };
        let compliant = params
            .iter()
            .enumerate()
            .filter_map(|(c, p)| match *p {
                Param::Compliance(j) => Some((j, c)),
                _ => None,
            })
            .collect();
        let cols = Columns::new(params, dof);
        let harmonic = cols.has_harmonics() || crate::robot::harmonics::has_harmonics(nominal);
        let gravity = cols.has_gravity() || crate::robot::gravity_basis::has_gravity(nominal);
        let problem = RobotProblem {
            nominal,
            params: params.to_vec(),
            index: params.iter().map(|p| p.index(dof)).collect(),
            cols,
            points,
            rotations,
            measure,
            qs,
            work: RefCell::new((nominal.values.clone(), chain)),
            vars,
            block_vars: RefCell::new(vec![([0.0; MAX_JOINTS], [(0.0, 1.0); MAX_JOINTS]); block]),
            orientation_weight: 1.0,
            largest_point: points.iter().map(|p| p.norm()).fold(0.0, Real::max),
            prior: None,
            tikhonov: None,
            trace: None,
            compliant,
            loads: Vec::new(),
            masses: Vec::new(),
            harmonic,
            gravity,
        };
        problem.with_payloads(None)
    }

    /// Sets the payload of each point (kg; `None`: no payload), under which the
    /// elasto-geometric model computes each pose's gravity torques when the model has
    /// compliances (identified, or in the nominal robot). Fails when it does and the robot
    /// gives no link masses, or a payload is not a finite number ≥ 0, or the payloads do not
    /// match the points.
    pub fn with_payloads(mut self, payloads: Option<&[Real]>) -> crate::Result<Self> {
        self.loads.clear();
        if self.compliant.is_empty() && !crate::robot::compliance::is_compliant(self.nominal) {
            return Ok(self);
        }
        let Some(mass) = self.nominal.link_mass_kg.clone() else {
            return Err(Error::setting(
                "mass_kg",
                format!(
                    "robot \"{}\" gives no link masses (`mass_kg` on every joint of the robot \
                     file), which the compliance model needs for its gravity torques",
                    self.nominal.name
                ),
            ));
        };
        let m = self.points.len();
        let loads = payloads.map_or_else(|| vec![0.0; m], <[Real]>::to_vec);
        crate::robot::compliance::check_payloads(&loads, m)?;
        self.loads = loads;
        self.masses = mass;
        Ok(self)
    }

    /// Weights the orientation rows of full-pose data (residual and Jacobian) by `k` (mm per
    /// rad; default 1), so that the least squares balance orientation against position
    /// errors: the part of the weighting factor `k` of Qiao 2021's fitness (eq. 14). With
    /// `k = 1` a radian counts as a millimetre and the orientation data are nearly ignored;
    /// the statistically matched weight is `σ_position / σ_orientation` of the instrument
    /// (about 150 mm/rad for a tracker with 15 µm and 0.005°). Fails unless `k` is finite
    /// and positive.
    pub fn with_orientation_weight(mut self, k: Real) -> crate::Result<Self> {
        crate::identify::qiao::check_k(k)?;
        self.orientation_weight = k;
        Ok(self)
    }

    /// Gives point `i` the prior weight `w[i]` (e.g. `1/σ_i²`, [`crate::measurement::Measurements::weights`]);
    /// `None` leaves every point at 1. Fails unless there is one finite, positive weight per
    /// point.
    pub fn with_prior_weights(mut self, w: Option<&'a [Real]>) -> crate::Result<Self> {
        if let Some(w) = w {
            crate::measurement::check_weights(w, self.points.len())?;
        }
        self.prior = w;
        Ok(self)
    }

    /// Gives each parameter the Tikhonov precision `λ[k]` towards its nominal value (a MAP
    /// estimate, [`LeastSquares::tikhonov`]); `None` or empty: no priors. Fails unless there
    /// is one finite precision ≥ 0 per parameter.
    pub fn with_tikhonov(mut self, l: Option<&'a [Real]>) -> crate::Result<Self> {
        let l = l.filter(|l| !l.is_empty());
        if let Some(l) = l {
            if l.len() != self.params.len() || l.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(Error::setting(
                    "priors",
                    format!(
                        "{} prior precisions for {} parameters, or one not finite ≥ 0",
                        l.len(),
                        self.params.len()
                    ),
                ));
            }
        }
        self.tikhonov = l;
        Ok(self)
    }

    /// The kinematic least squares of a calibration problem: its base-frame data, orientation
    /// weight `k`, prior weights and parameter priors.
    pub fn of(problem: &'a CalibrationProblem) -> crate::Result<Self> {
        RobotProblem::new(
            problem.nominal,
            problem.params,
            problem.poses(),
            &problem.points,
            problem.rotations.as_deref(),
            problem.measure,
        )?
        .with_orientation_weight(problem.k)?
        .with_prior_weights(problem.weights.as_deref())?
        .with_tikhonov(Some(&problem.priors))?
        .with_payloads(problem.data.payload_kg.as_deref())
        .map(|mut p| {
            p.trace.clone_from(&problem.trace);
            p
        })
    }

    /// The compensated robot: the nominal robot with the errors `x` added.
    pub fn robot_with(&self, x: &DVector<Real>) -> Robot {
        self.nominal.with_added(&self.index, x.as_slice())
    }
}

impl LeastSquares for RobotProblem<'_> {
    fn size(&self) -> Size {
        Size::new(self.params.len(), self.points.len(), self.measure.rows())
    }

    fn prior(&self) -> Option<&[Real]> {
        self.prior
    }

    fn tikhonov(&self) -> Option<&[Real]> {
        self.tikhonov
    }

    /// Forward kinematics and the analytic Jacobian at `nominal + x`, from the tool frame
    /// [`pose_rows_vars`] returns (one chain walk per point, the joints' sines and cosines
    /// computed once in [`RobotProblem::new`]). Allocation-free: the chain is
    /// updated in place ([`Chain::set_values`]).
    /// A streamed problem (no stored chain variables) computes them all here first: the
    /// solvers evaluate it by blocks ([`LeastSquares::evaluate_points`]) instead.
    fn evaluate(&self, x: &DVector<Real>, r: &mut DVector<Real>, j: &mut DMatrix<Real>) {
        if self.vars.is_empty() {
            let vars = self.work.borrow().1.variables_of(self.qs);
            self.evaluate_block(x, &vars, 0, r, j);
        } else {
            self.evaluate_block(x, &self.vars, 0, r, j);
        }
        if let Some(t) = &self.trace {
            let rms = (r.norm_squared() / self.points.len() as Real).sqrt();
            if let Ok(mut t) = t.lock() {
                t.push(rms);
            }
        }
    }

    fn block_points(&self) -> Option<usize> {
        solver::streams(self.points.len()).then_some(solver::BLOCK_POINTS)
    }

    /// Each of a point's three position components rounded by 16 units in the last place of
    /// the largest point (`ROUNDING_ULPS`), and for full poses each orientation component by as
    /// many of a radian times the orientation weight.
    fn rounding_floor(&self) -> Real {
        let ulp = ROUNDING_ULPS * Real::EPSILON;
        let mut floor = 3.0 * (ulp * self.largest_point).powi(2);
        if self.measure == Measure::Pose {
            floor += 3.0 * (ulp * self.orientation_weight).powi(2);
        }
        floor
    }

    /// [`LeastSquares::evaluate`] of one block of points: their chain variables computed
    /// for the block (allocation-free, into a buffer of [`solver::BLOCK_POINTS`] poses).
    fn evaluate_points(&self, x: &Column, i: usize, r: &mut Column, j: &mut Matrix) {
        let count = r.len() / self.measure.rows();
        if !self.vars.is_empty() {
            return self.evaluate_block(x, &self.vars[i..i + count], i, r, j);
        }
        let mut vars = self.block_vars.borrow_mut();
        if vars.len() < count {
            vars.resize(count, ([0.0; MAX_JOINTS], [(0.0, 1.0); MAX_JOINTS]));
        }
        {
            let guard = self.work.borrow();
            for (v, q) in vars.iter_mut().zip(&self.qs[i..i + count]) {
                *v = guard.1.variables(q);
            }
        }
        self.evaluate_block(x, &vars[..count], i, r, j);
    }
}

impl RobotProblem<'_> {
    /// The rows of the points `first..first + vars.len()` (their chain variables `vars`)
    /// into `r` and `j` from row 0: the whole problem with `first = 0` and every pose.
    fn evaluate_block(
        &self,
        x: &DVector<Real>,
        vars: &[ChainVars],
        first: usize,
        r: &mut DVector<Real>,
        j: &mut DMatrix<Real>,
    ) {
        let mut guard = self.work.borrow_mut();
        let (values, chain) = &mut *guard;
        self.nominal
            .set_chain_with_added(&self.index, x.as_slice(), values, chain);
        let chain = &*chain;
        let rows = self.measure.rows();
        let rots = match self.measure {
            Measure::Pose => self.rotations,
            Measure::Position => None,
        };
        let dof = self.nominal.dof();
        // Each point's residual from its tool frame `f` (the rows of `j` are in place); `i`
        // counts from the block's first point.
        let residual = |i: usize, f: &Frame, r: &mut DVector<Real>, j: &mut DMatrix<Real>| {
            let dp = self.points[first + i] - f.pos;
            for k in 0..3 {
                r[rows * i + k] = dp[k];
            }
            if let Some(rots) = rots {
                let w = self.orientation_weight;
                log_orientation_rows(&rots[first + i], &f.rot, w, r, j, rows * i + 3);
            }
        };
        if self.loads.is_empty() && !self.harmonic && !self.gravity {
            // Rigid model: four points per chain walk, the rest one by one.
            let whole = vars.len() / LANES * LANES;
            for i0 in (0..whole).step_by(LANES) {
                let v = &vars[i0..];
                let f = pose_rows4(chain, &self.cols, v, self.measure, j, rows * i0);
                for l in 0..LANES {
                    residual(i0 + l, &f.frame(l), r, j);
                }
            }
            for (i, v) in vars.iter().enumerate().skip(whole) {
                let f = pose_rows_vars(chain, &self.cols, v, self.measure, j, rows * i);
                residual(i, &f, r, j);
            }
            return;
        }
        for (i, v) in vars.iter().enumerate() {
            // Elasto-geometric model: each chain variable deflected by c_j τ_j, the gravity
            // torques of the current geometry at the commanded pose; the column of c_j is the
            // derivative by that variable times τ_j (τ's own dependence on the geometry is
            // second order and left out). Joint-angle harmonics offset each variable by
            // Σ h_jk f_k(q_j); the column of h_jk is the derivative by that variable times
            // f_k(q_j) ([`Columns::fill_harmonics`]).
            let mut tau = [0.0; MAX_JOINTS];
            let mut dv = [0.0; MAX_JOINTS];
            if !self.loads.is_empty() {
                let load = self.loads[first + i];
                gravity_torques_vars(self.nominal, chain, v, &self.masses, load, &mut tau[..dof]);
                for (k, d) in dv.iter_mut().enumerate().take(dof) {
                    *d = values[Param::Compliance(k).index(dof)] * tau[k];
                }
            }
            if self.harmonic {
                crate::robot::harmonics::add_offsets(values, v, &mut dv[..dof]);
            }
            // The mass-free gravity basis: the torques of unit weights at the current
            // geometry's elbow, wrist centre and tool point at the commanded pose; the
            // column of k_jl is the derivative by joint j's variable times τ_jl.
            let mut basis = [[0.0; GRAVITY_POINTS]; MAX_JOINTS];
            if self.gravity {
                crate::robot::gravity_basis::torques(self.nominal, chain, v, &mut basis);
                crate::robot::gravity_basis::add_offsets(values, &basis, &mut dv[..dof]);
            }
            let mut vd = *v;
            deflect_vars(&mut vd, &dv[..dof]);
            let f = pose_rows_vars(chain, &self.cols, &vd, self.measure, j, rows * i);
            self.cols.fill_terms(v, &basis, j, rows * i, rows);
            for &(k, c) in &self.compliant {
                for r in rows * i..rows * (i + 1) {
                    j[(r, c)] *= tau[k];
                }
            }
            residual(i, &f, r, j);
        }
    }
}

/// Runs the Jacobian-based `solver` on a calibration problem: the errors of
/// `problem.params` from zero, on the base-frame data, orientation rows weighted by
/// `problem.k`. Fails when the problem is inconsistent (see [`RobotProblem::new`]).
pub fn identify_robot(
    solver: &dyn Solver,
    problem: &CalibrationProblem,
) -> crate::Result<Identified> {
    let rp = RobotProblem::of(problem)?;
    let x0 = DVector::zeros(problem.params.len());
    Ok(match &problem.start[..] {
        [] => solve(solver, &rp, &x0),
        s => solve_from(solver, &rp, (&x0, &DVector::from_column_slice(s))),
    })
}

/// Fills in what a method that does not form `JᵀPJ` (the searches)
/// leaves out: the rank and condition number of the column-scaled, weighted Jacobian and the
/// RMS point residual at its estimate, from the problem's kinematic least squares; and marks a
/// solution whose parameters the data do not all determine [`Termination::RankDeficient`].
pub fn assess(problem: &CalibrationProblem, out: &mut Identified) -> crate::Result<()> {
    if out.rank.is_some() || out.x.len() != problem.params.len() {
        return Ok(());
    }
    let rp = RobotProblem::of(problem)?;
    let size = rp.size();
    // The solvers' own buffers and normal equations: JᵀPJ with the prior weights.
    let mut work = Work::new(&rp);
    let w = start_weights(&rp);
    work.evaluate(&rp, &out.x, &w);
    work.normal(&rp, &w);
    let rank = rank(&work.n);
    out.rank = Some(rank);
    out.normal = work.n.clone();
    out.rms_residual = (work.r.norm_squared() / size.points as Real).sqrt();
    if rank < size.params
        && matches!(
            out.termination,
            Termination::Converged | Termination::MaxIterations | Termination::TargetReached
        )
    {
        out.termination = Termination::RankDeficient;
    }
    Ok(())
}

/// Every [`Solver`] is a [`Method`]: on a calibration problem it runs [`identify_robot`].
impl<S: Solver> Method for S {
    fn check(&self) -> crate::Result<()> {
        Solver::check(self)
    }

    fn identify(&self, problem: &CalibrationProblem, _: &mut Rng) -> crate::Result<Identified> {
        identify_robot(self, problem)
    }

    fn tolerates_rank_deficiency(&self) -> bool {
        Solver::tolerates_rank_deficiency(self)
    }

    fn solver(&self) -> Option<&dyn Solver> {
        Some(self)
    }
}
