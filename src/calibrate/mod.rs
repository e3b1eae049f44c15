//! The calibration pipeline: the frame registration of the
//! measured points alternating with the identification, and the validation of the
//! compensated robot. `calbench run` calls it once per trial, method and pose strategy;
//! `calbench identify` once on a measurement file.
//!
//! - [`registration`]: SVD (Kabsch/Arun) and Ban's weighted SVD of point sets;
//! - [`validation`]: validation errors of a model against true (or measured) frames;
//! - [`request`]: an identification asked for by `identify` or the Python module
//!   ([`request::IdentifyRequest`]);
//! - [`pipeline`]: the one identification pipeline that runs it
//!   ([`request::IdentifyRequest::run`] → [`pipeline::IdentifyOutcome`]), on a tracker's
//!   file or a measurement-kind file;
//! - [`plausibility`]: whether an identified robot can be physically right;
//! - [`record`]: the identification record (`identified.json`);
//! - [`verdict`]: whether a result may be written (undetermined data, a worse robot);
//! - [`on_kind`]: identification on a measurement-kind file (distance, plane, sphere, targets);
//! - [`kernel`]: the kernel residual of the model term `gp` (a Gaussian process on the
//!   parametric model's residuals, `kernel.json`);
//! - [`cv`]: K-fold cross-validation, held-out splits and model choice (`identify --cv`);
//! - [`diagnostics`]: parameter σ and correlations, leverage and Cook's distance, predicted
//!   position σ (`identified.json` `diagnostics`);
//! - this file: [`calibrate`].

pub mod compensate;
pub mod cv;
pub mod diagnostics;
pub mod fit;
pub mod frames;
pub mod kernel;
pub mod on_kind;
pub mod orientations;
pub mod pipeline;
pub mod plausibility;
pub mod recheck;
pub mod record;
pub mod registration;
pub mod request;
pub mod task;
pub mod validation;
pub mod verdict;

use crate::error::Result;
use crate::identify::{CalibrationProblem, Identified, MethodSpec};
use crate::measurement::Measurements;
use crate::numeric::rng::Rng;
use crate::numeric::{Frame, Real, Vec3};
use crate::robot::{Param, Robot};
use registration::{register_rows, register_svd, register_wsvd};

pub use validation::{validation_errors, validation_errors_with, ErrorStats, PoseErrors};

/// How the measured points are brought into the robot's base frame (docs/formats.md
/// `[registration]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "lowercase")]
pub enum Registration {
    /// SVD (Kabsch/Arun) of nominal against measured points, then identification.
    Svd,
    /// Ban's weighted SVD (eqs. 12–25), then identification.
    Wsvd,
    /// SVD for a first estimate, then the base parameters identified with the rest (Li 2018).
    #[default]
    Identify,
    /// The true tracker pose is used (simulation only; for real data: the points are
    /// already in the base frame).
    Known,
}

impl Registration {
    /// The name used in files and on the command line.
    pub fn as_str(self) -> &'static str {
        self.into()
    }
}

/// A compensated robot and how it was obtained.
pub struct Calibrated {
    /// The nominal robot with the identified errors added.
    pub robot: Robot,
    /// The registration: measured (instrument) coordinates → base frame.
    pub frame: Frame,
    /// The registration of the *nominal* robot on the same points (the first round's frame;
    /// the given frame with `known`). "Before" figures are taken in this frame, so they are
    /// the same for every method.
    pub nominal_frame: Frame,
    /// How the alternation of registration and identification ended.
    pub rounds: Rounds,
    /// The identification's result (errors in the order of the parameters passed).
    pub identified: Identified,
}

/// How `svd` / `wsvd` registration and identification alternated (a single round for
/// `identify` and `known`, which do not alternate).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Rounds {
    /// Identifications run.
    pub rounds: usize,
    /// Why the alternation stopped.
    pub termination: RoundsEnd,
    /// The last change of the frame, as the largest displacement it gives a measured point
    /// (mm): translation + RMS radius of the points × rotation angle. 0 without alternation.
    pub last_step_mm: Real,
    /// How the refits of the frame weighed the measured points.
    pub weights: RefitWeights,
}

/// How the refits of an `svd` / `wsvd` alternation weighed the measured points: as the
/// identification weighed them, a weight per point, or a weight per coordinate when the
/// identification weighed each residual row on its own ([`Identified::row_weights`]: IGG3
/// with `per = "coordinate"`; [`registration::register_rows`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RefitWeights {
    /// One weight per point (the SVD; also every registration that does not alternate).
    #[default]
    Point,
    /// One weight per coordinate (x, y, z of the base frame).
    Coordinate,
}

/// Why the alternation of registration and identification stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "kebab-case")]
pub enum RoundsEnd {
    /// The frame moved by less than [`ROUND_TOLERANCE_MM`] in the last round.
    Converged,
    /// [`MAX_ROUNDS`] rounds ran without meeting the tolerance.
    MaxRounds,
    /// The smallest step did not shrink for [`STALL_ROUNDS`] rounds (a cycle: a method whose
    /// point weights jump between rounds need not have a fixed point).
    Stalled,
    /// The registration does not alternate (`identify`, `known`).
    Single,
}

impl RoundsEnd {
    /// The name used in files.
    pub fn as_str(self) -> &'static str {
        self.into()
    }
}

/// The alternation of `svd` / `wsvd` registration with identification stops when the frame
/// moves a measured point by less than this (mm), ...
pub const ROUND_TOLERANCE_MM: Real = 1e-4;
/// ... or after this many identifications.
pub const MAX_ROUNDS: usize = 200;
/// ... or when its smallest step has not shrunk for this many rounds.
pub const STALL_ROUNDS: usize = 25;
/// Depth of the Anderson acceleration of the alternation.
const ANDERSON_DEPTH: usize = 6;

/// Registration and identification of one method on one measurement (Ban eqs. 12–25 for
/// the registration).
///
/// - `svd` and `wsvd`: the nominal robot's registration (SVD, or Ban's weighted SVD) is the
///   first frame; registration (an SVD weighing the points as the identification did, or
///   [`registration::register_rows`] weighing each coordinate when the identification
///   weighed each residual row: IGG3 with `per = "coordinate"`) and identification then
///   alternate until the frame moves a point by less than
///   [`ROUND_TOLERANCE_MM`], or [`MAX_ROUNDS`] rounds (reported in [`Calibrated::rounds`]).
///   The kinematic errors first leak into the frame, and each refit of the frame on the
///   identified model takes some back; the plain alternation is a block coordinate descent
///   whose rate is the coupling between frame and kinematic parameters (on a UR10 it needs
///   hundreds of rounds), so the rounds are Anderson-accelerated (Walker & Ni 2011,
///   depth 6) on the frame's six coordinates (rotation scaled by the points' RMS radius,
///   so both parts are in mm). The fixed point is the plain alternation's.
/// - `identify`: the SVD frame is a first estimate and the base parameters (which must then
///   be among `params`) absorb the rest (Li 2018).
/// - `known`: the frame is `known`.
///
/// Every round identifies from the same random state, so a stochastic method sees the same
/// draws in every round and the rounds converge to a fixed point of one map.
pub fn calibrate(
    nominal: &Robot,
    params: &[Param],
    data: &Measurements,
    registration: Registration,
    known: &Frame,
    method: &MethodSpec,
    rng: &mut Rng,
) -> Result<Calibrated> {
    let how = (registration, RefitWeights::Coordinate);
    calibrate_weighing(nominal, params, data, how, known, method, rng)
}

/// The frame `registration` starts a calibration of `nominal` on `data` in, which takes the
/// measured points into the base frame: `known` itself, or the nominal robot's tool points
/// registered onto the measured ones (by Ban's weighted SVD with `wsvd`, else by SVD with the
/// measurement's weights).
pub fn nominal_frame(
    nominal: &Robot,
    data: &Measurements,
    registration: Registration,
    known: &Frame,
) -> Result<Frame> {
    if registration == Registration::Known {
        return Ok(*known);
    }
    let model = plausibility::tool_points(nominal, &data.qs);
    frame_onto(&model, data, registration, known)
}

/// [`nominal_frame`] from the nominal robot's tool points `model` at the poses of `data`, for
/// a caller that has them already.
pub(crate) fn frame_onto(
    model: &[Vec3],
    data: &Measurements,
    registration: Registration,
    known: &Frame,
) -> Result<Frame> {
    Ok(match registration {
        Registration::Known => *known,
        Registration::Wsvd => register_wsvd(model, &data.points)?.frame,
        _ => register_svd(model, &data.points, data.weights().as_deref())?.frame,
    })
}

/// [`calibrate`] with the refits' weights chosen: [`RefitWeights::Coordinate`] weighs each
/// coordinate when the identification weighed each row (what [`calibrate`] does),
/// [`RefitWeights::Point`] each point by its rows' mean weight even then (the refit before
/// [`registration::register_rows`], kept as the baseline the per-coordinate refit is
/// measured against: tests/cli/registration_rows.rs).
pub fn calibrate_weighing(
    nominal: &Robot,
    params: &[Param],
    data: &Measurements,
    (registration, refit_weights): (Registration, RefitWeights),
    known: &Frame,
    method: &MethodSpec,
    rng: &mut Rng,
) -> Result<Calibrated> {
    // The first frame is the nominal robot's registration (Ban's weighted SVD with `wsvd`).
    // The refits then weigh the points as the identification did (the measurement's
    // weights, then the method's final ones), so that both halves of the alternation
    // minimise one weighted sum and the rounds have a fixed point: its joint optimum. (Ban's
    // weights, or no weights under a robust method, make two different sums, and the rounds
    // then drift along the directions the frame and the kinematic errors share.)
    let nominal_frame = nominal_frame(nominal, data, registration, known)?;
    let start = rng.clone();
    let precisions = method.precisions(params)?;
    let mut solve = |frame: Frame| -> Result<(Identified, Robot)> {
        *rng = start.clone();
        let mut problem = CalibrationProblem::new(nominal, params, data, frame, method.k);
        problem.priors.clone_from(&precisions);
        problem.trace.clone_from(&method.trace);
        problem.start.clone_from(&method.start);
        let mut identified = method.method.identify(&problem, rng)?;
        crate::identify::robot::assess(&problem, &mut identified)?;
        let robot = problem.robot_with(identified.x.as_slice());
        Ok((identified, robot))
    };
    if !matches!(registration, Registration::Svd | Registration::Wsvd) {
        let (identified, robot) = solve(nominal_frame)?;
        return Ok(Calibrated {
            robot,
            frame: nominal_frame,
            nominal_frame,
            rounds: Rounds {
                rounds: 1,
                termination: RoundsEnd::Single,
                last_step_mm: 0.0,
                weights: RefitWeights::Point,
            },
            identified,
        });
    }
    let coords = FrameCoordinates::new(&nominal_frame, &data.points);
    let mut anderson = Anderson::default();
    let mut u = coords.of(&nominal_frame);
    // The previous round's (u, g(u), step), and whether `u` came from an accelerated step.
    let mut previous: Option<(Coordinates, Coordinates, Real)> = None;
    let mut accelerated = false;
    let mut best: Option<Calibrated> = None;
    let mut rounds = 0;
    loop {
        let frame = coords.frame(&u);
        let (identified, robot) = solve(frame)?;
        rounds += 1;
        // The refit weighs each coordinate as the identification did when it weighed rows on
        // their own (one sum again, per row), else each point.
        let model = plausibility::tool_points(&robot, &data.qs);
        let rows = identified
            .row_weights
            .as_ref()
            .filter(|_| refit_weights == RefitWeights::Coordinate);
        let (refit, weights) = match rows {
            Some(rows) => {
                let per = rows.len() / data.points.len().max(1);
                let r = register_rows(&model, &data.points, rows, per)?;
                (r, RefitWeights::Coordinate)
            }
            None => {
                let r = register_svd(&model, &data.points, Some(&identified.weights))?;
                (r, RefitWeights::Point)
            }
        };
        let g = coords.of(&refit.frame);
        let step = (g - u).norm();
        let done = step <= ROUND_TOLERANCE_MM;
        let this = Calibrated {
            robot,
            frame,
            nominal_frame,
            rounds: Rounds {
                rounds,
                termination: if done {
                    RoundsEnd::Converged
                } else {
                    RoundsEnd::MaxRounds
                },
                last_step_mm: step,
                weights,
            },
            identified,
        };
        if done {
            return Ok(this);
        }
        if step.is_finite() && best.as_ref().is_none_or(|b| step < b.rounds.last_step_mm) {
            best = Some(this);
        }
        let stalled = best
            .as_ref()
            .is_some_and(|b| rounds - b.rounds.rounds >= STALL_ROUNDS);
        if rounds >= MAX_ROUNDS || stalled {
            // The round with the smallest step is returned, with the rounds run in all.
            let mut b = best.ok_or_else(|| {
                crate::error::Error::Diverged(
                    "the alternation of registration and identification diverged".into(),
                )
            })?;
            b.rounds.rounds = rounds;
            if stalled {
                b.rounds.termination = RoundsEnd::Stalled;
            }
            return Ok(b);
        }
        match previous {
            // An accelerated step that did not shrink the step is undone: the plain step
            // from the previous point instead, and the acceleration starts afresh.
            Some((_, pg, ps)) if accelerated && (step >= ps || step.is_nan()) => {
                anderson.history.clear();
                u = pg;
                accelerated = false;
            }
            _ => {
                previous = Some((u, g, step));
                u = anderson.next(&u, &g);
                accelerated = u != g;
            }
        }
    }
}

/// Six coordinates of a frame near a reference, both parts in mm: the rotation vector of
/// `R · R₀ᵀ` times the RMS radius of the measured points about their centroid, then where
/// the frame puts that centroid. A change `δ` of them moves a measured point by about `|δ|`.
struct FrameCoordinates {
    reference: nalgebra::Matrix3<Real>,
    centroid: Vec3,
    radius: Real,
}

type Coordinates = nalgebra::Vector6<Real>;

impl FrameCoordinates {
    fn new(reference: &Frame, points: &[Vec3]) -> Self {
        let n = points.len().max(1) as Real;
        let centroid = points.iter().sum::<Vec3>() / n;
        let radius = (points
            .iter()
            .map(|p| (p - centroid).norm_squared())
            .sum::<Real>()
            / n)
            .sqrt()
            .max(1.0);
        Self {
            reference: reference.rot,
            centroid,
            radius,
        }
    }

    fn of(&self, frame: &Frame) -> Coordinates {
        let w = crate::numeric::rotation_vector(&(frame.rot * self.reference.transpose()));
        let (s, c) = (self.radius, frame.apply(&self.centroid));
        Coordinates::new(s * w.x, s * w.y, s * w.z, c.x, c.y, c.z)
    }

    fn frame(&self, u: &Coordinates) -> Frame {
        let w = Vec3::new(u[0], u[1], u[2]) / self.radius;
        let rot = nalgebra::Rotation3::new(w).into_inner() * self.reference;
        Frame {
            rot,
            pos: Vec3::new(u[3], u[4], u[5]) - rot * self.centroid,
        }
    }
}

/// Anderson acceleration (type II; Walker & Ni, SIAM J. Numer. Anal. 49, 2011) of a
/// fixed-point iteration `u ← g(u)`: the next iterate is `g_k − ΔG γ` with `γ` the least-
/// squares fit of the residual `f_k = g_k − u_k` by the differences `ΔF` of the last
/// residuals. [`calibrate`] safeguards it: an accelerated step that does not shrink the
/// residual is replaced by the plain step and the history restarts.
#[derive(Default)]
struct Anderson {
    /// The last (u, g) pairs, oldest first.
    history: Vec<(Coordinates, Coordinates)>,
}

impl Anderson {
    fn next(&mut self, u: &Coordinates, g: &Coordinates) -> Coordinates {
        let f = g - u;
        self.history.push((*u, *g));
        if self.history.len() > ANDERSON_DEPTH + 1 {
            self.history.remove(0);
        }
        let k = self.history.len() - 1;
        if k == 0 {
            return *g;
        }
        let mut df = nalgebra::DMatrix::<Real>::zeros(6, k);
        let mut dg = nalgebra::DMatrix::<Real>::zeros(6, k);
        for j in 0..k {
            let (u0, g0) = &self.history[j];
            let (u1, g1) = &self.history[j + 1];
            df.set_column(j, &((g1 - u1) - (g0 - u0)));
            dg.set_column(j, &(g1 - g0));
        }
        let rhs = nalgebra::DVector::from_column_slice(f.as_slice());
        let tol = 1e-12 * f.norm().max(1e-300);
        let Some(Ok(gamma)) =
            crate::numeric::linalg::svd(df, true, true).map(|s| s.solve(&rhs, tol))
        else {
            return *g;
        };
        let next = g - Coordinates::from_column_slice((dg * gamma).as_slice());
        if next.iter().all(|x| x.is_finite()) {
            next
        } else {
            *g
        }
    }
}
