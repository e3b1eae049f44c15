//! A method supplied from outside the library: a function of an [`ExternalProblem`] that
//! returns the estimate (the Python module's methods, docs/python.md). A study runs it like
//! any registered method, on the same trials, measurements and validation poses, with the
//! same metrics.
//!
//! The problem is the kinematic least squares of the built-in Jacobian methods
//! ([`RobotProblem`]), weighted as they weigh it: `residual(x)` is `√P (measured − model(x))`
//! per row (P the point's prior weight) and `jacobian(x)` its derivative, `−√P ∂model/∂x`,
//! so that a Gauss–Newton step is `x − lstsq(J, r)` and its fixed point is that of `ls`.
//! The problem owns its data, so a function may keep it; every evaluation compiles the
//! kinematic problem afresh (a few µs), and the last evaluation is cached so that a
//! `residual` and a `jacobian` at the same `x` cost one.

use std::sync::{Arc, Mutex};

use nalgebra::{DMatrix, DVector};

use super::robot::RobotProblem;
use super::solver::{LeastSquares, Size};
use super::{CalibrationProblem, Identified, Method, Termination};
use crate::error::{Error, Result};
use crate::measurement::Measure;
use crate::numeric::rng::Rng;
use crate::numeric::{Mat3, Real, Vec3};
use crate::robot::{Param, Robot};

/// The name of every external method in [`super::MethodSpec::name`].
pub const EXTERNAL: &str = "external";

/// What an external function returns: the estimate and, optionally, the name of its
/// termination ([`Termination`]'s names; default `converged`); or the message of its failure.
pub type Outcome = std::result::Result<(Vec<Real>, Option<String>), String>;

/// The function of an external method.
pub type ExternalFn = dyn Fn(Arc<ExternalProblem>) -> Outcome + Send + Sync;

/// A method that calls a function supplied from outside.
#[derive(Clone)]
pub struct External {
    /// The method's name, as its refusals name it (`the method `mine` returned …`).
    pub name: String,
    /// The function.
    pub run: Arc<ExternalFn>,
}

impl std::fmt::Debug for External {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "External({})", self.name)
    }
}

impl Method for External {
    fn check(&self) -> Result<()> {
        Ok(())
    }

    /// Calls the function on the problem. Its failure, an estimate of the wrong length or
    /// with non-finite values, or an unknown termination name is an `Err` carrying the
    /// message, which names the method (in a study: a failure of the method in that trial).
    fn identify(&self, problem: &CalibrationProblem, _: &mut Rng) -> Result<Identified> {
        let p = Arc::new(ExternalProblem::of(problem)?);
        let (x, termination) = (self.run)(p.clone()).map_err(Error::Compute)?;
        let refused = |what: String| Error::Compute(format!("the method `{}` {what}", self.name));
        let t = p.params.len();
        if x.len() != t {
            return Err(refused(format!(
                "returned {} values for {t} parameters",
                x.len()
            )));
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(refused(format!(
                "returned a non-finite value for `{}`: {}",
                p.params[i], x[i]
            )));
        }
        // An error no robot file can hold is no robot's (compliances and the residual
        // terms have no such range).
        let beyond = (0..t).find_map(|i| {
            let q = p.params[i];
            let msg =
                crate::robot::beyond_range(x[i], q.is_length()).filter(|_| q.is_geometric())?;
            Some(format!("returned an error of `{q}` that {msg}"))
        });
        if let Some(what) = beyond {
            return Err(refused(what));
        }
        let termination = match termination {
            None => Termination::Converged,
            Some(name) => name.parse().map_err(|_| {
                refused(format!(
                    "returned the unknown termination \"{name}\"; allowed: {}",
                    <Termination as strum::VariantNames>::VARIANTS.join(", ")
                ))
            })?,
        };
        let evaluations = p.evaluations();
        Ok(Identified::plain(
            x,
            evaluations,
            evaluations,
            termination,
            p.points.len(),
        ))
    }

    /// An external method is given any problem: whether it copes with parameters the data
    /// do not determine is for its results to show.
    fn tolerates_rank_deficiency(&self) -> bool {
        true
    }
}

/// The last evaluation: `x`, the weighted residual and its Jacobian.
type Cached = (Vec<Real>, DVector<Real>, DMatrix<Real>);

/// The problem an external method solves: a copy of a [`CalibrationProblem`]'s kinematic
/// least squares.
pub struct ExternalProblem {
    nominal: Robot,
    params: Vec<Param>,
    /// Position or full pose, and the orientation weight (mm per rad).
    measure: (Measure, Real),
    /// Per point: prior weights and payloads, when given.
    prior: Option<Vec<Real>>,
    payloads: Option<Vec<Real>>,
    /// The joint values, and the measured points and rotations in the base frame.
    qs: Vec<Vec<Real>>,
    points: Vec<Vec3>,
    rotations: Option<Vec<Mat3>>,
    /// Evaluations so far, and the last one.
    last: Mutex<(usize, Option<Cached>)>,
}

impl std::fmt::Debug for ExternalProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExternalProblem")
            .field("params", &self.params)
            .field("points", &self.points.len())
            .finish()
    }
}

impl ExternalProblem {
    /// The kinematic least squares of `problem`; fails where [`RobotProblem::of`] does.
    pub fn of(problem: &CalibrationProblem) -> Result<ExternalProblem> {
        RobotProblem::of(problem)?;
        Ok(ExternalProblem {
            nominal: problem.nominal.clone(),
            params: problem.params.to_vec(),
            measure: (problem.measure, problem.k),
            prior: problem.weights.clone(),
            payloads: problem.data.payload_kg.clone(),
            qs: problem.poses().to_vec(),
            points: problem.points.clone(),
            rotations: problem.rotations.clone(),
            last: Mutex::new((0, None)),
        })
    }

    /// The identified parameters, in the order of the estimate.
    pub fn params(&self) -> &[Param] {
        &self.params
    }

    /// The start: no error.
    pub fn x0(&self) -> Vec<Real> {
        vec![0.0; self.params.len()]
    }

    /// The prior weight of each point (1 without standard deviations).
    pub fn weights(&self) -> Vec<Real> {
        self.prior
            .clone()
            .unwrap_or_else(|| vec![1.0; self.points.len()])
    }

    /// The problem's size: parameters, points and rows per point.
    pub fn size(&self) -> Size {
        Size::new(self.params.len(), self.points.len(), self.measure.0.rows())
    }

    /// Evaluations of the model so far (a residual and a Jacobian at one `x` count once).
    pub fn evaluations(&self) -> usize {
        self.last.lock().map_or(0, |l| l.0)
    }

    /// The weighted residual `√P (measured − model(x))` and its Jacobian `−√P ∂model/∂x` at
    /// `x`, handed to `with`.
    pub fn evaluate<T>(
        &self,
        x: &[Real],
        with: impl FnOnce(&DVector<Real>, &DMatrix<Real>) -> T,
    ) -> Result<T> {
        let size = self.size();
        if x.len() != size.params {
            return Err(Error::setting(
                "x",
                format!("{} values for {} parameters", x.len(), size.params),
            ));
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(Error::setting(
                "x",
                format!("`{}` is not finite: {}", self.params[i], x[i]),
            ));
        }
        let mut last = self
            .last
            .lock()
            .map_err(|_| Error::Compute("the problem's cache is poisoned".into()))?;
        if let Some((lx, r, j)) = &last.1 {
            if lx.as_slice() == x {
                return Ok(with(r, j));
            }
        }
        let rp = RobotProblem::new(
            &self.nominal,
            &self.params,
            &self.qs,
            &self.points,
            self.rotations.as_deref(),
            self.measure.0,
        )?
        .with_orientation_weight(self.measure.1)?
        .with_prior_weights(self.prior.as_deref())?
        .with_payloads(self.payloads.as_deref())?;
        let (mut r, mut j) = match last.1.take() {
            Some((_, r, j)) => (r, j),
            None => (
                DVector::zeros(size.rows()),
                DMatrix::zeros(size.rows(), size.params),
            ),
        };
        rp.evaluate(&DVector::from_column_slice(x), &mut r, &mut j);
        j.neg_mut();
        if let Some(w) = &self.prior {
            let rows = size.rows_per_point;
            for (i, wi) in w.iter().enumerate() {
                let s = wi.sqrt();
                for row in rows * i..rows * (i + 1) {
                    r[row] *= s;
                    j.row_mut(row).scale_mut(s);
                }
            }
        }
        let out = with(&r, &j);
        last.0 += 1;
        last.1 = Some((x.to_vec(), r, j));
        Ok(out)
    }
}
