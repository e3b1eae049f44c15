//! The identification record: what `identified.json` holds (docs/formats.md `identify`), one
//! type for a tracker's file and a measurement-kind file, built once by the pipeline
//! ([`super::request`]) and serialised as it is: the `identify` command writes it, the
//! Python module returns it.
//!
//! The keys are the fields, declared in byte order (as the file has always listed them); the
//! keys a file does not have are left out. Small nested values are written through a JSON
//! tree so that their keys are in byte order too; the per-point vectors of the diagnostics
//! go from their slices to the file, never through a tree.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize, Serializer};

use super::cv::CrossValidation;
use super::diagnostics::Diagnostics;
use super::validation::FileValidation;
use super::{ErrorStats, Registration, RoundsEnd};
use crate::identify::{Identified, Termination};
use crate::measurement::kind::Kind;
use crate::numeric::nan;
use crate::numeric::{Frame, Real};
use crate::robot::Param;

/// The format of the identification records this calbench writes. Format 1 is the first
/// and is written without a `format` key (so its files keep their bytes, as `summary.json`'s
/// format 1 does); a later format writes its number.
pub const FORMAT: u32 = 1;

/// An identification record's format: a record built here is of [`FORMAT`], a file without
/// the key of format 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Format(pub u32);

impl Format {
    fn first() -> Format {
        Format(1)
    }

    fn is_first(&self) -> bool {
        self.0 == 1
    }
}

impl Default for Format {
    fn default() -> Format {
        Format(FORMAT)
    }
}

/// A prior's effect: the estimate without and with it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PriorMove {
    /// The parameter.
    pub parameter: String,
    /// The prior's σ (mm, rad).
    pub sigma: Real,
    /// The estimate without any prior.
    #[serde(deserialize_with = "nan::real")]
    pub without_prior: Real,
    /// The MAP estimate.
    #[serde(deserialize_with = "nan::real")]
    pub with_prior: Real,
}

/// A registration's frame: measured (instrument) coordinates → base frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// Roll, pitch, yaw (rad).
    #[serde(deserialize_with = "nan::read")]
    pub rpy_rad: [Real; 3],
    /// Translation (mm).
    #[serde(deserialize_with = "nan::read")]
    pub xyz_mm: [Real; 3],
}

impl From<&Frame> for FrameRecord {
    fn from(f: &Frame) -> Self {
        let (xyz_mm, rpy_rad) = f.to_xyz_rpy();
        FrameRecord { rpy_rad, xyz_mm }
    }
}

/// The convergence trace: what it holds, and its values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trace {
    /// The values, one per iteration or evaluation.
    #[serde(deserialize_with = "nan::read")]
    pub trace: Vec<Real>,
    /// What they are.
    pub values: String,
}

/// `identified.json` (docs/formats.md `identify`): the keys of every identification, those of
/// a tracker's file (`covariance`, the registration rounds, the practice options' and the
/// diagnostics) and those of a measurement-kind file (`kind`, the instrument's unknowns and
/// description, `standard_errors`, `unidentifiable`, `readings`). `None` and empty lists are
/// keys the file does not have, but `rank`, which is written as `null`.
#[serde_with::skip_serializing_none]
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IdentifiedRecord {
    /// The format ([`FORMAT`]): written only from format 2 on, so format 1 files have no
    /// `format` key; a file of a later format than [`FORMAT`] is refused.
    #[serde(default = "Format::first", skip_serializing_if = "Format::is_first")]
    pub format: Format,
    /// Why the result cannot be physically right (a result kept although it cannot,
    /// [`super::plausibility`]), its likely cause last; empty: it can.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub allowed_implausible: Vec<String>,
    /// Why the result makes the robot worse (a result kept although it does); empty: it
    /// does not.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub allowed_worse: Vec<String>,
    /// The column-scaled condition number of the solve.
    #[serde(deserialize_with = "nan::real")]
    pub condition_number: Real,
    /// The convergence trace.
    pub convergence_trace: Option<Trace>,
    /// The estimate's covariance (tracker's file).
    #[serde(default, deserialize_with = "nan::read")]
    pub covariance: Option<Vec<Vec<Real>>>,
    /// The cross-validation of the model identified.
    #[serde(serialize_with = "sorted")]
    pub cv: Option<CrossValidation>,
    /// The best of the models compared.
    pub cv_best: Option<String>,
    /// Every model's cross-validation.
    #[serde(serialize_with = "sorted")]
    pub cv_models: Option<Vec<CrossValidation>>,
    /// Where the readings were read from.
    pub data: String,
    /// The diagnostics (tracker's file).
    #[serde(serialize_with = "diagnostics")]
    pub diagnostics: Option<Diagnostics>,
    /// The identified robot errors by parameter.
    #[serde(deserialize_with = "nan::read")]
    pub errors: BTreeMap<String, Real>,
    /// Model evaluations.
    pub evaluations: usize,
    /// Parameters held at their nominal values.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fixed: Vec<String>,
    /// The rows held out for validation (`LAST/EVERY`).
    pub holdout: Option<String>,
    /// The instrument's unknowns at the solution (kind file).
    #[serde(default, deserialize_with = "nan::read")]
    pub instrument_unknowns: Option<BTreeMap<String, Real>>,
    /// Iterations of the solve.
    pub iterations: usize,
    /// The kernel residual's hyperparameters (a model with the term `gp`; the residual itself
    /// is `kernel.json`).
    pub kernel_residual: Option<super::kernel::KernelHyper>,
    /// The readings' kind (kind file).
    pub kind: Option<Kind>,
    /// The method's name.
    pub method: String,
    /// The identified robot parameters, in the order of the estimate.
    pub parameters: Vec<String>,
    /// Distances: whether from a fixed pivot.
    pub pivot: Option<bool>,
    /// Planes: the axis each plane is solved for.
    pub plane_axes: Option<Vec<String>>,
    /// How each prior moved its estimate.
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        serialize_with = "sorted"
    )]
    pub priors: Vec<PriorMove>,
    /// The rank of the solve (`null`: not known).
    #[serialize_always]
    pub rank: Option<usize>,
    /// The number of readings (kind file).
    pub readings: Option<usize>,
    /// The parameters left out at the nominal robot and re-admitted at the identified one
    /// ([`super::recheck`]); absent: none was.
    pub readmitted: Option<super::recheck::Readmission>,
    /// The registration.
    pub registration: Option<Registration>,
    /// The registration's frame.
    pub registration_frame: Option<FrameRecord>,
    /// The last frame step of the alternation (mm; tracker's file).
    #[serde(default, deserialize_with = "nan::read")]
    pub registration_last_step_mm: Option<Real>,
    /// Rounds of registration and identification (tracker's file).
    pub registration_rounds: Option<usize>,
    /// How the alternation ended (tracker's file).
    pub registration_termination: Option<RoundsEnd>,
    /// `coordinate` when the registration's refits weighed each coordinate on its own
    /// (`svd`/`wsvd` with IGG3's `per = "coordinate"`); absent when they weighed points.
    pub registration_weights: Option<super::RefitWeights>,
    /// The RMS residual (mm).
    #[serde(deserialize_with = "nan::real")]
    pub rms_residual_mm: Real,
    /// The nominal robot's name.
    pub robot: String,
    /// The a-posteriori σ₀.
    #[serde(deserialize_with = "nan::real")]
    pub sigma0: Real,
    /// The standard error of every unknown, robot's and instrument's (kind file).
    #[serde(default, deserialize_with = "nan::read")]
    pub standard_errors: Option<BTreeMap<String, Real>>,
    /// Targets: their offsets on the flange (mm).
    #[serde(default, deserialize_with = "nan::read")]
    pub targets_mm: Option<Vec<[Real; 3]>>,
    /// How the solve ended.
    pub termination: Termination,
    /// Parameters the readings cannot determine (kind file).
    pub unidentifiable: Option<Vec<String>>,
    /// Qiao's attitude errors after (deg).
    #[serde(serialize_with = "sorted")]
    pub validation_after_attitude_deg: Option<ErrorStats>,
    /// Orientation errors after (deg).
    #[serde(serialize_with = "sorted")]
    pub validation_after_deg: Option<ErrorStats>,
    /// Position errors after (mm).
    #[serde(serialize_with = "sorted")]
    pub validation_after_mm: Option<ErrorStats>,
    /// Qiao's attitude errors before (deg).
    #[serde(serialize_with = "sorted")]
    pub validation_before_attitude_deg: Option<ErrorStats>,
    /// Orientation errors before (deg).
    #[serde(serialize_with = "sorted")]
    pub validation_before_deg: Option<ErrorStats>,
    /// Position errors before (mm).
    #[serde(serialize_with = "sorted")]
    pub validation_before_mm: Option<ErrorStats>,
}

/// Names as strings.
pub(crate) fn names(v: &[Param]) -> Vec<String> {
    v.iter().map(|p| p.to_string()).collect()
}

impl IdentifiedRecord {
    /// The keys every identification has: the robot, the file, the method, and the solve
    /// `id` of the robot parameters `params` (its estimate's first entries); no other key.
    pub fn of(robot: &str, data: &Path, method: &str, params: &[Param], id: &Identified) -> Self {
        let parameters = names(params);
        IdentifiedRecord {
            condition_number: id.condition_number(),
            data: data.display().to_string(),
            errors: parameters
                .iter()
                .cloned()
                .zip(id.x.iter().copied())
                .collect(),
            evaluations: id.evaluations,
            iterations: id.iterations,
            method: method.to_string(),
            parameters,
            rank: id.rank,
            rms_residual_mm: id.rms_residual,
            robot: robot.to_string(),
            sigma0: id.sigma0,
            termination: id.termination,
            ..Default::default()
        }
    }

    /// The record with the position errors before and after on a validation file.
    pub fn validated(self, before: ErrorStats, after: ErrorStats) -> Self {
        IdentifiedRecord {
            validation_before_mm: Some(before),
            validation_after_mm: Some(after),
            ..self
        }
    }

    /// The record with a tracker's validation `v`: positions, and orientations and
    /// attitudes where the file has them.
    pub fn validated_file(self, v: &FileValidation) -> Self {
        let (bd, ad) = v.deg.unzip();
        let (bt, at) = v.attitude_deg.unzip();
        IdentifiedRecord {
            validation_before_deg: bd,
            validation_after_deg: ad,
            validation_before_attitude_deg: bt,
            validation_after_attitude_deg: at,
            ..self.validated(v.before_mm, v.after_mm)
        }
    }

    /// The model the cross-validation chose, with every model's results (`cv_models`,
    /// `cv_best`): its index in `cv_models`.
    pub fn best_model(&self) -> Option<usize> {
        let best = self.cv_best.as_ref()?;
        self.cv_models
            .as_ref()?
            .iter()
            .position(|m| &m.model == best)
    }
}

impl IdentifiedRecord {
    /// Reads `identified.json` from its text (`path` names it in errors): a key this calbench
    /// does not know, or of the wrong type, is refused naming the key path; a file of a later
    /// format than [`FORMAT`] is refused naming the format.
    pub fn from_json(text: &str, path: &Path) -> crate::Result<IdentifiedRecord> {
        crate::error::unique_keys(path, text)?;
        let mut de = serde_json::Deserializer::from_str(text);
        let r: IdentifiedRecord = crate::error::read_typed(&mut de, path, "identified.json")?;
        crate::error::newer_format(path, "identification record", r.format.0, FORMAT)?;
        Ok(r)
    }

    /// What the identification ran on and how, as the file names them: `robot`, `data` and
    /// `method`, and where the record has them `registration`, `kind`, `holdout` and
    /// `cv_best` (the results database's settings of an identify folder).
    pub fn settings(&self) -> BTreeMap<&'static str, String> {
        let given = [
            (
                "registration",
                self.registration.map(|r| r.as_str().to_string()),
            ),
            ("kind", self.kind.map(|k| <&str>::from(k).to_string())),
            ("holdout", self.holdout.clone()),
            ("cv_best", self.cv_best.clone()),
        ];
        let mut s = BTreeMap::from([
            ("robot", self.robot.clone()),
            ("data", self.data.clone()),
            ("method", self.method.clone()),
        ]);
        s.extend(given.into_iter().filter_map(|(k, v)| Some((k, v?))));
        s
    }
}

/// `v` written through a JSON tree: its keys in byte order.
fn sorted<T: Serialize, S: Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    serde_json::to_value(v)
        .map_err(serde::ser::Error::custom)?
        .serialize(s)
}

/// The diagnostics with their keys in byte order: everything but the per-point vectors as a
/// (small) tree, those two from their slices.
fn diagnostics<S: Serializer>(d: &Option<Diagnostics>, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap as _;
    let Some(d) = d else {
        return s.serialize_none();
    };
    let small = Diagnostics {
        leverage: Vec::new(),
        cook_distance: Vec::new(),
        ..d.clone()
    };
    let serde_json::Value::Object(tree) =
        serde_json::to_value(&small).map_err(serde::ser::Error::custom)?
    else {
        return s.serialize_none();
    };
    let mut m = s.serialize_map(Some(tree.len()))?;
    for (k, v) in &tree {
        match k.as_str() {
            "leverage" => m.serialize_entry(k, &d.leverage)?,
            "cook_distance" => m.serialize_entry(k, &d.cook_distance)?,
            _ => m.serialize_entry(k, v)?,
        }
    }
    m.end()
}
/// What to warn of when an identification stopped short of convergence (at its iteration
/// limit, diverging or making no progress) and was written: its result, and a task's figure,
/// are then those of an unconverged solve (`identified.json`'s `termination` says so). The
/// command line prints it on stderr after `identify` and `task`; Python's `identify` and
/// `task` warn with it.
pub fn unconverged_warning(r: &IdentifiedRecord) -> Option<String> {
    matches!(
        r.termination,
        crate::identify::Termination::MaxIterations
            | crate::identify::Termination::Diverged
            | crate::identify::Termination::NoProgress
    )
    .then(|| {
        format!(
            "the identification ended `{}` after {} (RMS residual {:.4} mm): the \
             result is that of a solve that did not converge (identified.json, `termination`)",
            r.termination.as_str(),
            crate::error::counted(r.iterations, "iteration", "iterations"),
            r.rms_residual_mm
        )
    })
}
