//! Validation of a compensated robot: per-pose position and orientation errors
//! against true (or measured) frames, their statistics, the validation on a measurement file
//! and the residual of each calibration point. The reports only format what is computed here.

use std::path::Path;

use super::Calibrated;
use crate::error::{Error, Opt, Result};
use crate::identify::qiao::error_models::attitude_error_deg;
use crate::measurement::Measurements;
use crate::numeric::{rotation_vector, Frame, Mat3, Real};
use crate::robot::compliance::is_compliant;
use crate::robot::loaded::LoadedFk;
use crate::robot::Robot;

/// The keys of the validation errors' statistics in `summary.json` and `identified.json`
/// (docs/formats.md), each written once ([`crate::study::metric::Metric`] names them).
pub mod keys {
    /// Validation position errors of the nominal robot (mm).
    pub const BEFORE_MM: &str = "validation_before_mm";
    /// … of the compensated robot.
    pub const AFTER_MM: &str = "validation_after_mm";
    /// Validation orientation errors of the compensated robot, rotation angle (deg).
    pub const AFTER_DEG: &str = "validation_after_deg";
    /// Qiao's attitude errors of the compensated robot (deg).
    pub const AFTER_ATTITUDE_DEG: &str = "validation_after_attitude_deg";
}

/// Mean, RMS, max and standard deviation of a set of errors.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorStats {
    /// Mean (MAE).
    #[serde(deserialize_with = "crate::numeric::nan::real")]
    pub mean: Real,
    /// Root mean square.
    #[serde(deserialize_with = "crate::numeric::nan::real")]
    pub rms: Real,
    /// Maximum.
    #[serde(deserialize_with = "crate::numeric::nan::real")]
    pub max: Real,
    /// Standard deviation (population).
    #[serde(deserialize_with = "crate::numeric::nan::real")]
    pub std: Real,
}

impl ErrorStats {
    /// The statistics of `v` (all zero for an empty slice).
    pub fn of(v: &[Real]) -> ErrorStats {
        if v.is_empty() {
            return ErrorStats::default();
        }
        let n = v.len() as Real;
        let mean = v.iter().sum::<Real>() / n;
        let rms = (v.iter().map(|x| x * x).sum::<Real>() / n).sqrt();
        // NaN if any error is: `Real::max` would pass over it and give 0 for a trial whose
        // errors are all NaN.
        let max = v.iter().fold(0.0, |m: Real, &x| {
            if m.is_nan() || x.is_nan() {
                Real::NAN
            } else {
                m.max(x)
            }
        });
        let std = (v.iter().map(|x| (x - mean) * (x - mean)).sum::<Real>() / n).sqrt();
        ErrorStats {
            mean,
            rms,
            max,
            std,
        }
    }

    /// [`ErrorStats::of`] for values of either sign: `max` is the largest value, however
    /// negative (`of` floors it at zero, the least an error magnitude can be).
    pub fn of_signed(v: &[Real]) -> ErrorStats {
        let max = v.iter().cloned().fold(Real::NEG_INFINITY, Real::max);
        ErrorStats {
            max: if v.is_empty() { 0.0 } else { max },
            ..ErrorStats::of(v)
        }
    }
}

/// The validation errors of a model at each pose.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseErrors {
    /// Position error `|Δp|` (mm).
    pub mm: Vec<Real>,
    /// Orientation error: the rotation angle of `R_modelᵀ R_true` (deg), the geodesic
    /// distance on SO(3), stable at every attitude (docs/formats.md `validation_*_deg`).
    pub deg: Vec<Real>,
    /// Qiao 2021's attitude error `√(Δα² + Δβ² + Δγ²)` of the fixed X-Y-Z angles (deg,
    /// [`crate::identify::qiao::error_models::attitude_error_deg`]); undefined near ±90° pitch, where the angles
    /// are singular (docs/formats.md `validation_*_attitude_deg`; Qiao's ACAE is its mean).
    pub attitude_deg: Vec<Real>,
    /// Guo 2024's per-point position error (§5.2, table 8), "the mean of the errors in the
    /// three directions": `(Δx + Δy + Δz) / 3` with `Δ = p_true − p_model` (mm), signed.
    pub axis_mm: Vec<Real>,
    /// The same with each axis error taken absolute, `(|Δx| + |Δy| + |Δz|) / 3` (mm).
    pub axis_abs_mm: Vec<Real>,
}

impl PoseErrors {
    /// The errors of a failed calibration at `n` poses: NaN everywhere.
    pub fn failed(n: usize) -> PoseErrors {
        let nan = vec![Real::NAN; n];
        PoseErrors {
            mm: nan.clone(),
            deg: nan.clone(),
            attitude_deg: nan.clone(),
            axis_mm: nan.clone(),
            axis_abs_mm: nan,
        }
    }
}

/// The errors of `model` against the true frames at the joint values `qs` ([`PoseErrors`]);
/// the means over the poses of `mm` and `attitude_deg` are Qiao's ACPE and ACAE (§4.1). A
/// model with joint compliances predicts each pose under its payload (`payloads`, kg; `None`:
/// no payload) by [`crate::robot::loaded::loaded_fk`]; a rigid model ignores the payloads. Fails
/// when the model has compliances but no link masses.
pub fn validation_errors(
    model: &Robot,
    qs: &[Vec<Real>],
    payloads: Option<&[Real]>,
    truth: &[Frame],
) -> crate::Result<PoseErrors> {
    validation_errors_with(model, qs, payloads, truth, true)
}

/// [`validation_errors`], with the orientation errors (`deg`, `attitude_deg`) only where
/// `orientation` is set: without it they are left empty, and the position errors are the same
/// numbers. A study of positions reads no orientation error, and their rotation logarithm and
/// X-Y-Z angles cost it more than the forward kinematics of the pose.
pub fn validation_errors_with(
    model: &Robot,
    qs: &[Vec<Real>],
    payloads: Option<&[Real]>,
    truth: &[Frame],
    orientation: bool,
) -> crate::Result<PoseErrors> {
    let fk = LoadedFk::new(model);
    let n = qs.len().min(truth.len());
    let angles = if orientation { n } else { 0 };
    let mut e = PoseErrors {
        mm: Vec::with_capacity(n),
        deg: Vec::with_capacity(angles),
        attitude_deg: Vec::with_capacity(angles),
        axis_mm: Vec::with_capacity(n),
        axis_abs_mm: Vec::with_capacity(n),
    };
    for (i, (q, t)) in qs.iter().zip(truth).enumerate() {
        let f = fk.at(q, payloads.and_then(|p| p.get(i)).copied().unwrap_or(0.0))?;
        let d = t.pos - f.pos;
        e.mm.push(d.norm());
        e.axis_mm.push(d.sum() / 3.0);
        e.axis_abs_mm.push(d.abs().sum() / 3.0);
        if orientation {
            e.deg.push(rotation_angle_deg(&f, t));
            e.attitude_deg.push(attitude_error_deg(t, &f));
        }
    }
    Ok(e)
}

/// The rotation angle between two frames' orientations, `|log(R_modelᵀ R_true)|`, in degrees.
pub fn rotation_angle_deg(model: &Frame, truth: &Frame) -> Real {
    rotation_vector(&model.rot.tr_mul(&truth.rot))
        .norm()
        .to_degrees()
}

/// Validation of a compensated robot on a measurement file: position errors before
/// (nominal) and after (compensated) and, for full-pose files, orientation errors.
pub struct FileValidation {
    /// Position errors of the nominal robot (mm).
    pub before_mm: ErrorStats,
    /// Position errors of the compensated robot (mm).
    pub after_mm: ErrorStats,
    /// Orientation errors (rotation angle) before and after (deg), for full-pose files.
    pub deg: Option<(ErrorStats, ErrorStats)>,
    /// Qiao's attitude errors before and after (deg), for full-pose files.
    pub attitude_deg: Option<(ErrorStats, ErrorStats)>,
}

/// Validates `c` on the measurements `v`, brought into the base frame by the calibration's
/// registration; a compensated robot with compliances predicts each point under its
/// `payload_kg`. Fails when such a robot has no link masses.
pub fn validate_file(nominal: &Robot, c: &Calibrated, v: &Measurements) -> Result<FileValidation> {
    let truth = |frame: &Frame| -> Vec<Frame> {
        let (points, rotations) = v.in_frame(frame);
        points
            .into_iter()
            .enumerate()
            .map(|(i, pos)| Frame {
                rot: rotations.as_ref().map_or(Mat3::identity(), |r| r[i]),
                pos,
            })
            .collect()
    };
    // "Before" in the nominal robot's own registration, the same for every method.
    let loads = v.payload_kg.as_deref();
    let b = validation_errors(nominal, &v.qs, loads, &truth(&c.nominal_frame))?;
    let a = validation_errors(&c.robot, &v.qs, loads, &truth(&c.frame))?;
    let pose = v.quats.is_some();
    Ok(FileValidation {
        before_mm: ErrorStats::of(&b.mm),
        after_mm: ErrorStats::of(&a.mm),
        deg: pose.then(|| (ErrorStats::of(&b.deg), ErrorStats::of(&a.deg))),
        attitude_deg: pose.then(|| {
            (
                ErrorStats::of(&b.attitude_deg),
                ErrorStats::of(&a.attitude_deg),
            )
        }),
    })
}

/// Per calibration point of `data`, the residual (mm) before — the `nominal` robot in its own
/// registration — and after — the compensated robot of `c`, under the point's payload, in
/// the final registration.
pub fn point_residuals(
    nominal: &Robot,
    c: &Calibrated,
    data: &Measurements,
) -> Result<(Vec<Real>, Vec<Real>)> {
    let cn = nominal.chain();
    let before = data
        .qs
        .iter()
        .zip(&data.points)
        .map(|(q, p)| (c.nominal_frame.apply(p) - cn.fk(q).pos).norm())
        .collect();
    let after = residual_vectors(c, data)?
        .iter()
        .map(|v| v.norm())
        .collect();
    Ok((before, after))
}

/// Per measured point of `data`, the residual of the compensated robot in the final
/// registration: measured (registered) − predicted, mm (the predicted point under the row's
/// payload when the robot has compliances).
pub fn residual_vectors(c: &Calibrated, data: &Measurements) -> Result<Vec<crate::numeric::Vec3>> {
    let fk = LoadedFk::new(&c.robot);
    let loads = data.payload_kg.as_deref();
    data.qs
        .iter()
        .zip(&data.points)
        .enumerate()
        .map(|(i, (q, p))| Ok(c.frame.apply(p) - fk.at(q, loads.map_or(0.0, |l| l[i]))?.pos))
        .collect()
}

/// Refuses a validation file's rows (`v`, read from `file` where they came from one, beside
/// the calibration data `d` read from `source` for `nominal`) that would not measure the
/// calibration: rows repeated or shared with the data, full poses of a position calibration,
/// poses without the payload under which compliances (`compliance`: identified) are. A
/// refusal names the file, as the refusal of `--validate`.
pub(super) fn check_validation_rows(
    (nominal, compliance): (&Robot, bool),
    (d, source): (&Measurements, &Path),
    (v, file): (&Measurements, Option<&Path>),
) -> Result<()> {
    // A refusal of the validation's rows names its file, as every refusal of a file's
    // rows does (and says when it is the data's own file).
    let refused = |why: String| {
        let why = match file {
            Some(v) => {
                let same = |p: &Path| std::fs::canonicalize(p).ok();
                match same(v).is_some_and(|c| same(source) == Some(c)) {
                    true => format!("{} is the data's own file: {why}", v.display()),
                    false => format!("{}: {why}", v.display()),
                }
            }
            None => why,
        };
        Err(Error::option(Opt::Validate, why))
    };
    // A validation's rows repeated would weigh their points twice in its figures.
    let repeated = v.repeated_rows();
    if !repeated.is_empty() {
        let why = crate::measurement::REPEATED_VALIDATION;
        let same = crate::measurement::SAME_MEASUREMENT;
        let msg = crate::measurement::repeated_rows_refusal(&repeated, same, why);
        return refused(msg);
    }
    let shared = d.shared_rows(v);
    if !shared.is_empty() {
        return refused(crate::measurement::shared_rows_refusal(
            &shared,
            "rows of each file",
        ));
    }
    // Orientations the calibration does not determine would be scored (a file of
    // other rows: copies of the data's are refused as such, above): positions
    // leave the tool's rotation to its nominal values, so a full-pose validation of
    // them reported degrees of orientation error that measure nothing the data fixed.
    if v.quats.is_some() && d.quats.is_none() {
        return refused(
            "holds orientations and the calibration data positions only, which do \
             not determine the tool's orientation: the validation's orientation errors \
             would not measure the calibration; validate on its positions alone"
                .into(),
        );
    }
    // A robot with joint compliances predicts each pose under its payload: validation
    // poses without one would be predicted unloaded, their errors the sag's.
    let loaded = d
        .payload_kg
        .as_ref()
        .is_some_and(|p| p.iter().any(|&w| w != 0.0));
    let sags = compliance || is_compliant(nominal);
    if loaded && sags && v.payload_kg.is_none() {
        return refused(
            "gives no payload, and the calibration rows carry one under which the \
             joint compliances are identified: the validation poses would be predicted \
             with no load; give each validation row its payload (`payload_kg`, 0 for a \
             pose without one)"
                .into(),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::{rot_x, rot_z, rpy_matrix, Vec3};
    use crate::robot::sampling::uniform_joint_poses;

    #[test]
    fn an_error_that_is_nan_makes_every_statistic_nan() {
        let s = ErrorStats::of(&[1.0, Real::NAN, 2.0]);
        assert!(s.mean.is_nan() && s.rms.is_nan() && s.max.is_nan() && s.std.is_nan());
        assert_eq!(ErrorStats::of(&[1.0, 3.0, 2.0]).max, 3.0);
    }

    #[test]
    fn orientation_error_is_the_rotation_angle_at_every_pitch() {
        for pitch in [89.99f64, 90.0, -89.999, 30.0, 0.0] {
            let model = Frame {
                rot: rpy_matrix([0.3, pitch.to_radians(), -0.7]),
                pos: Vec3::zeros(),
            };
            for turn in [rot_x(0.05f64.to_radians()), rot_z(0.05f64.to_radians())] {
                let truth = Frame {
                    rot: model.rot * turn,
                    pos: Vec3::zeros(),
                };
                let deg = rotation_angle_deg(&model, &truth);
                approx::assert_relative_eq!(deg, 0.05, max_relative = 1e-9);
            }
        }
    }

    #[test]
    fn without_orientation_the_position_errors_keep_their_bits() {
        use crate::robot::Param;
        let nominal = crate::robot::builtin::irb2600();
        let qs = uniform_joint_poses(&nominal, 12, &mut crate::numeric::rng::from_seed(7));
        let truth: Vec<Frame> = qs
            .iter()
            .map(|q| {
                let mut f = nominal.fk(q);
                f.pos += Vec3::new(0.3, -0.2, 0.1);
                f.rot *= rot_x(0.01);
                f
            })
            .collect();
        let loads: Vec<Real> = (0..qs.len()).map(|i| i as Real).collect();
        // A rigid model and one whose compliance moves each pose under its payload.
        let mut soft = nominal.clone();
        soft.set(Param::Compliance(1), 1.0 / 3.5e6);
        assert!(crate::robot::loaded::is_rigid(&nominal));
        assert!(!crate::robot::loaded::is_rigid(&soft));
        for model in [&nominal, &soft] {
            let all = validation_errors(model, &qs, Some(&loads), &truth).unwrap();
            let part = validation_errors_with(model, &qs, Some(&loads), &truth, false).unwrap();
            let bits = |v: &[Real]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&part.mm), bits(&all.mm));
            assert_eq!(bits(&part.axis_mm), bits(&all.axis_mm));
            assert_eq!(bits(&part.axis_abs_mm), bits(&all.axis_abs_mm));
            assert!(part.deg.is_empty() && part.attitude_deg.is_empty());
            assert_eq!(all.deg.len(), qs.len());
            // The position error against the forward kinematics written out: the rigid model
            // is off by the planted offset, the soft one by that and its sag.
            let c = model.chain();
            for (i, (q, t)) in qs.iter().zip(&truth).enumerate() {
                let f = crate::robot::loaded::loaded_fk(model, &c, q, loads[i]).unwrap();
                assert_eq!(part.mm[i].to_bits(), (t.pos - f.pos).norm().to_bits());
            }
            let planted = Vec3::new(0.3, -0.2, 0.1).norm();
            let off = (part.mm[5] - planted).abs();
            if model.values == nominal.values {
                assert!(off < 1e-9, "{off}");
            } else {
                assert!(off > 1e-6, "{off}");
            }
        }
    }
}
