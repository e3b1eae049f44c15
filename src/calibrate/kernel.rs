//! The kernel residual of the model term `gp` (docs/formats.md `identify`, "Cross-validation
//! and model choice"; the file `kernel.json`, § 7.6): a Gaussian process on the position
//! residuals the parametric model leaves, fitted in a second stage on the calibration rows
//! alone.
//!
//! Stage one identifies the parametric model (the other terms) as any model; stage two takes
//! its residuals `r_i = registered measured point − predicted point` (mm, base frame) at the
//! calibration rows and fits a GP with an ARD squared-exponential kernel on the inputs
//! `sin q_j, cos q_j` of every revolute joint ([`crate::numeric::gp`]): the three components
//! share the kernel, the hyperparameters (a length scale per input, the signal and the noise
//! standard deviations) maximise the log marginal likelihood from two fixed starting points
//! ([`starts`]) on at most [`HYPER_ROWS`] evenly spaced calibration rows, and the weights
//! `α = K⁻¹ R` are then taken on every calibration row. A point is predicted as the
//! parametric forward kinematics plus the posterior mean `Σ_i k(x, x_i) α_i`.

use serde::{Deserialize, Serialize};

use super::validation::residual_vectors;
use super::Calibrated;
use crate::error::{Error, Result};
use crate::measurement::Measurements;
use crate::numeric::gp::{self, GpData, Workspace};
use crate::numeric::{Real, Vec3};
use crate::robot::{JointType, Robot};

/// The file beside `robot.toml` that holds the kernel residual.
pub const KERNEL_FILE: &str = "kernel.json";

/// The `format` of [`KERNEL_FILE`].
pub const KERNEL_FORMAT: &str = "calbench-kernel-1";

/// The most calibration rows the hyperparameters are fitted on (evenly spaced in the rows'
/// order): an evaluation of the likelihood costs O(n³), so this bounds a fit's time; the
/// weights α use every row.
pub const HYPER_ROWS: usize = 800;

/// L-BFGS steps per starting point.
pub const ITERATIONS: usize = 100;

/// The kernel's name in the files.
pub const KERNEL_NAME: &str = "ard-squared-exponential";

/// The hyperparameters and how they were found (`identified.json` `kernel_residual`, and
/// `kernel.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KernelHyper {
    /// Evaluations of the likelihood and its gradient.
    pub evaluations: usize,
    /// The rows the hyperparameters were fitted on.
    pub hyperparameter_rows: usize,
    /// The inputs, in order: `sin q1`, `cos q1`, `sin q2`, … (revolute joints only).
    pub inputs: Vec<String>,
    /// ε added to the diagonal (mm²; [`gp::JITTER`] times the residuals' mean square).
    pub jitter_mm2: Real,
    /// [`KERNEL_NAME`].
    pub kernel: String,
    /// The length scale of each input (in the inputs' units: a sine or cosine).
    pub length_scales: Vec<Real>,
    /// The log marginal likelihood at the hyperparameters on the rows they were fitted on.
    pub log_marginal_likelihood: Real,
    /// σ_n (mm).
    pub noise_sd_mm: Real,
    /// σ_f (mm).
    pub signal_sd_mm: Real,
    /// Which of the starting points ended best (0: every length scale 1; 1: every 0.3).
    pub start: usize,
    /// The rows the weights α were taken on (every calibration row).
    pub training_rows: usize,
}

/// A fitted kernel residual: what `kernel.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KernelResidual {
    /// The weights α of each training row (x, y, z; mm).
    pub alpha_mm: Vec<[Real; 3]>,
    /// [`KERNEL_FORMAT`].
    pub format: String,
    /// The hyperparameters.
    pub hyperparameters: KernelHyper,
    /// The joints (1-based) whose sine and cosine are inputs.
    pub joints: Vec<usize>,
    /// The training rows' joint values (rad, the robot's joints in order).
    pub q_rad: Vec<Vec<Real>>,
    /// The compensated robot whose residuals it models (`robot.toml`'s name).
    pub robot: String,
    /// The model term: `gp`.
    pub term: String,
}

/// The inputs of a pose: `sin q_j, cos q_j` of each of `joints` (0-based), into `out`.
fn features(q: &[Real], joints: &[usize], out: &mut [Real]) {
    for (k, &j) in joints.iter().enumerate() {
        let (s, c) = crate::numeric::sin_cos(q[j]);
        out[2 * k] = s;
        out[2 * k + 1] = c;
    }
}

/// The fixed starting points of the hyperparameters, in logs: every length scale 1, then
/// every length scale 0.3; σ_f the residuals' RMS component and σ_n half of it at both.
pub fn starts(d: usize, rms: Real) -> Vec<Vec<Real>> {
    [1.0, 0.3]
        .iter()
        .map(|&l: &Real| {
            let mut t = vec![l.ln(); d];
            t.extend([rms.ln(), (0.5 * rms).ln()]);
            t
        })
        .collect()
}

impl KernelResidual {
    /// Fits the kernel residual of the calibrated robot `c` (the model `robot`) on the
    /// calibration rows `data` (module docs). Fails for a robot without revolute joints, for
    /// fewer than ten rows, and when no hyperparameters give a positive definite covariance.
    pub fn fit(robot: &Robot, c: &Calibrated, data: &Measurements) -> Result<KernelResidual> {
        let joints: Vec<usize> = (0..robot.dof())
            .filter(|&j| robot.joints[j].kind == JointType::Revolute)
            .collect();
        let n = data.len();
        if joints.is_empty() || n < 10 {
            return Err(Error::Compute(format!(
                "the kernel residual `gp` needs a revolute joint and at least 10 calibration \
                 rows; robot \"{}\" has {} revolute joints, the data {n} rows",
                robot.name,
                joints.len()
            )));
        }
        let d = 2 * joints.len();
        let mut x = vec![0.0; n * d];
        for (i, q) in data.qs.iter().enumerate() {
            features(q, &joints, &mut x[i * d..i * d + d]);
        }
        let r = residual_vectors(c, data)?;
        let y: Vec<Real> = r.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
        let rms = (y.iter().map(|v| v * v).sum::<Real>() / y.len() as Real)
            .sqrt()
            .max(1e-6);
        // The hyperparameters on evenly spaced rows.
        let h = n.min(HYPER_ROWS);
        let rows: Vec<usize> = (0..h).map(|i| i * n / h).collect();
        let hx: Vec<Real> = rows
            .iter()
            .flat_map(|&i| x[i * d..i * d + d].iter().copied())
            .collect();
        let hy: Vec<Real> = rows
            .iter()
            .flat_map(|&i| y[3 * i..3 * i + 3].iter().copied())
            .collect();
        let sub = GpData {
            x: &hx,
            y: &hy,
            n: h,
            d,
            m: 3,
        };
        let mut lo = vec![(0.01 as Real).ln(); d];
        let mut hi = vec![(100.0 as Real).ln(); d];
        lo.extend([(1e-3 * rms).ln(), (1e-4 * rms).ln()]);
        hi.extend([(10.0 * rms).ln(), (10.0 * rms).ln()]);
        let mut ws = Workspace::new(h, d, 3);
        let best = gp::maximise(&sub, &starts(d, rms), (&lo, &hi), ITERATIONS, &mut ws)
            .ok_or_else(|| {
                Error::Compute(
                    "the kernel residual `gp`: no hyperparameters give a positive definite \
                     covariance of the calibration residuals"
                        .into(),
                )
            })?;
        drop(ws);
        let all = GpData {
            x: &x,
            y: &y,
            n,
            d,
            m: 3,
        };
        let mut ws = Workspace::new(n, d, 3);
        gp::log_marginal_likelihood(&all, &best.theta, all.jitter(), &mut ws, None).ok_or_else(
            || Error::Compute("the kernel residual `gp`: K is not positive definite".into()),
        )?;
        let t = &best.theta;
        let inputs = joints
            .iter()
            .flat_map(|j| [format!("sin q{}", j + 1), format!("cos q{}", j + 1)])
            .collect();
        Ok(KernelResidual {
            format: KERNEL_FORMAT.into(),
            term: "gp".into(),
            robot: format!("{}-calibrated", robot.name),
            hyperparameters: KernelHyper {
                kernel: KERNEL_NAME.into(),
                inputs,
                length_scales: t[..d].iter().map(|v| v.exp()).collect(),
                signal_sd_mm: t[d].exp(),
                noise_sd_mm: t[d + 1].exp(),
                jitter_mm2: all.jitter(),
                log_marginal_likelihood: best.lml,
                hyperparameter_rows: h,
                training_rows: n,
                start: best.start,
                evaluations: best.evaluations,
            },
            joints: joints.iter().map(|j| j + 1).collect(),
            q_rad: data.qs.clone(),
            alpha_mm: ws.alpha.chunks(3).map(|a| [a[0], a[1], a[2]]).collect(),
        })
    }

    /// The posterior mean of the residual (mm, base frame) at each of `qs`.
    pub fn means(&self, qs: &[Vec<Real>]) -> Vec<Vec3> {
        let joints: Vec<usize> = self.joints.iter().map(|j| j - 1).collect();
        let d = 2 * joints.len();
        let mut x = vec![0.0; self.q_rad.len() * d];
        for (i, q) in self.q_rad.iter().enumerate() {
            features(q, &joints, &mut x[i * d..i * d + d]);
        }
        let alpha: Vec<Real> = self.alpha_mm.iter().flatten().copied().collect();
        let h = &self.hyperparameters;
        let mut theta: Vec<Real> = h.length_scales.iter().map(|l| l.ln()).collect();
        theta.extend([h.signal_sd_mm.ln(), h.noise_sd_mm.ln()]);
        let mut f = vec![0.0; d];
        qs.iter()
            .map(|q| {
                features(q, &joints, &mut f);
                let mut out = [0.0; 3];
                gp::posterior_mean((&x, &alpha), (d, 3), &theta, &f, &mut out);
                Vec3::new(out[0], out[1], out[2])
            })
            .collect()
    }

    /// `kernel.json`'s text.
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string_pretty(self)
            .map(|s| s + "\n")
            .map_err(|e| Error::Compute(format!("{KERNEL_FILE}: {e}")))
    }
}

/// The position errors (mm) of the calibrated robot `c` at the measured rows `v`, with the
/// kernel residual's posterior mean added to the prediction when there is one.
pub fn position_errors(
    c: &Calibrated,
    kernel: Option<&KernelResidual>,
    v: &Measurements,
) -> Result<Vec<Real>> {
    let r = residual_vectors(c, v)?;
    Ok(match kernel {
        None => r.iter().map(|e| e.norm()).collect(),
        Some(k) => r
            .iter()
            .zip(k.means(&v.qs))
            .map(|(e, m)| (e - m).norm())
            .collect(),
    })
}
