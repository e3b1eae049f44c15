//! The kinematic identification problem of a robot: measured tool points (and orientations)
//! at known joint values, unknown errors of chosen parameters (SPEC §2, §4).
//!
//! The unknown `x` holds the errors added to the nominal values of the chosen parameters
//! (mm, rad); the model is the forward kinematics of the robot with those errors, and the
//! Jacobian is the analytic one of [`crate::jacobian`] (Li 2018 eqs. 6–12). The residual of
//! a point is `p_meas − p_model(x)`; for full poses the orientation rows are
//! `φ = log(R_meas · R_model(x)ᵀ)` with its exact derivative `J_r⁻¹(φ) J_ω`
//! ([`crate::jacobian::log_orientation_rows`]), weighted against the position rows.

use std::cell::RefCell;

use nalgebra::{DMatrix, DVector};

use super::Problem;
use crate::error::Error;
use crate::jacobian::{log_orientation_rows, pose_rows_vars, Columns, Measure};
use crate::kinematics::{Chain, ChainVars, Param, Robot};
use crate::math::{Mat3, Real, Vec3};

/// Measured data for identification.
#[derive(Clone, Debug, Default)]
pub struct RobotData {
    /// Joint values per point, internal units (rad, mm).
    pub qs: Vec<Vec<Real>>,
    /// Measured tool points, mm, in the robot's world (base-frame) coordinates.
    pub points: Vec<Vec3>,
    /// Measured tool orientations in the world, needed for [`Measure::Pose`].
    pub rotations: Option<Vec<Mat3>>,
}

/// A [`Problem`] over a robot's parameter errors.
#[derive(Debug)]
pub struct RobotProblem<'a> {
    nominal: &'a Robot,
    params: Vec<Param>,
    index: Vec<usize>,
    cols: Columns,
    data: &'a RobotData,
    measure: Measure,
    /// Working parameter values and the chain compiled from them, updated in place at each
    /// evaluation.
    work: RefCell<(Vec<Real>, Chain)>,
    /// The chain variables of every pose and their sines and cosines ([`Chain::variables`]).
    vars: Vec<ChainVars>,
    /// Weight of the orientation rows of full-pose data, mm per rad.
    orientation_weight: Real,
}

impl<'a> RobotProblem<'a> {
    /// The problem of identifying the errors of `params` of `nominal` from `data`.
    ///
    /// Fails when `params` is empty, repeats a parameter or names one the robot's model does
    /// not have, when the data's lengths disagree, a joint vector has the wrong length, a
    /// value is not finite, or `measure` is [`Measure::Pose`] without rotations.
    pub fn new(
        nominal: &'a Robot,
        params: &[Param],
        data: &'a RobotData,
        measure: Measure,
    ) -> crate::Result<Self> {
        if params.is_empty() {
            return Err(Error::setting("params", "no parameters to identify"));
        }
        let known = nominal.params();
        for (i, p) in params.iter().enumerate() {
            if !known.contains(p) {
                return Err(Error::setting(
                    "params",
                    format!("`{p}` is not a parameter of robot `{}`", nominal.name),
                ));
            }
            if params[..i].contains(p) {
                return Err(Error::setting("params", format!("`{p}` is listed twice")));
            }
        }
        if data.qs.len() != data.points.len() {
            return Err(Error::setting(
                "data",
                format!(
                    "{} joint vectors but {} measured points",
                    data.qs.len(),
                    data.points.len()
                ),
            ));
        }
        if data.qs.is_empty() {
            return Err(Error::setting("data", "no measured points"));
        }
        let dof = nominal.dof();
        for (i, q) in data.qs.iter().enumerate() {
            if q.len() != dof {
                return Err(Error::setting(
                    "data",
                    format!(
                        "point {i}: {} joint values for a {dof}-joint robot",
                        q.len()
                    ),
                ));
            }
            if q.iter().any(|v| !v.is_finite()) || data.points[i].iter().any(|v| !v.is_finite()) {
                return Err(Error::setting(
                    "data",
                    format!("point {i}: value not finite"),
                ));
            }
        }
        match (&data.rotations, measure) {
            (None, Measure::Pose) => {
                return Err(Error::setting(
                    "measure",
                    "full-pose identification needs measured orientations",
                ))
            }
            (Some(r), _) if r.len() != data.points.len() => {
                return Err(Error::setting(
                    "data",
                    format!(
                        "{} orientations but {} measured points",
                        r.len(),
                        data.points.len()
                    ),
                ))
            }
            (Some(r), Measure::Pose) if r.iter().any(|m| m.iter().any(|v| !v.is_finite())) => {
                return Err(Error::setting("data", "orientation not finite"))
            }
            _ => {}
        }
        let chain = nominal.chain();
        let vars = data.qs.iter().map(|q| chain.variables(q)).collect();
        Ok(RobotProblem {
            nominal,
            params: params.to_vec(),
            index: params.iter().map(|p| p.index(dof)).collect(),
            cols: Columns::new(params, dof),
            data,
            measure,
            work: RefCell::new((nominal.values.clone(), chain)),
            vars,
            orientation_weight: 1.0,
        })
    }

    /// Weights the orientation rows of full-pose data (residual and Jacobian) by `k` (mm per
    /// rad; default 1), so that the least squares balance orientation against position
    /// errors: the part of the weighting factor `k` of Qiao 2021's fitness (eq. 14). With
    /// `k = 1` a radian counts as a millimetre and the orientation data are nearly ignored;
    /// the statistically matched weight is `σ_position / σ_orientation` of the instrument
    /// (about 150 mm/rad for a tracker with 15 µm and 0.005°). Fails unless `k` is finite
    /// and positive.
    pub fn with_orientation_weight(mut self, k: Real) -> crate::Result<Self> {
        crate::error::finite_positive("k", k)?;
        self.orientation_weight = k;
        Ok(self)
    }

    /// The parameters, one per entry of `x`.
    pub fn params(&self) -> &[Param] {
        &self.params
    }

    /// The measure (rows per point).
    pub fn measure(&self) -> Measure {
        self.measure
    }

    /// The compensated robot: the nominal robot with the errors `x` added.
    pub fn robot_with(&self, x: &DVector<Real>) -> Robot {
        let mut r = self.nominal.clone();
        for (&i, &v) in self.index.iter().zip(x.iter()) {
            r.values[i] += v;
        }
        r
    }
}

impl Problem for RobotProblem<'_> {
    fn n_params(&self) -> usize {
        self.params.len()
    }

    fn n_points(&self) -> usize {
        self.data.points.len()
    }

    fn rows_per_point(&self) -> usize {
        self.measure.rows()
    }

    /// Forward kinematics and the analytic Jacobian at `nominal + x`, from the tool frame
    /// [`pose_rows_vars`] returns (one chain walk per point, the joints' sines and cosines
    /// computed once in [`RobotProblem::new`]). Allocation-free: the chain is
    /// updated in place ([`Chain::set_values`]).
    fn evaluate(&self, x: &DVector<Real>, r: &mut DVector<Real>, j: &mut DMatrix<Real>) {
        let mut guard = self.work.borrow_mut();
        let (values, chain) = &mut *guard;
        values.copy_from_slice(&self.nominal.values);
        for (&i, &v) in self.index.iter().zip(x.iter()) {
            values[i] += v;
        }
        chain.set_values(values);
        let chain = &*chain;
        let rows = self.measure.rows();
        let rots = match self.measure {
            Measure::Pose => self.data.rotations.as_deref(),
            Measure::Position => None,
        };
        for (i, (v, pm)) in self.vars.iter().zip(&self.data.points).enumerate() {
            let f = pose_rows_vars(chain, &self.cols, v, self.measure, j, rows * i);
            let dp = pm - f.pos;
            for k in 0..3 {
                r[rows * i + k] = dp[k];
            }
            if let Some(rots) = rots {
                let w = self.orientation_weight;
                log_orientation_rows(&rots[i], &f.rot, w, r, j, rows * i + 3);
            }
        }
    }
}
