//! An identification asked for: an [`IdentifyRequest`] holds the robot, a tracker's
//! measurements or a measurement-kind file, the method and every option of `calbench
//! identify` (docs/formats.md `identify`). The pipeline that runs it is
//! [`super::pipeline`]; the `identify` command and the Python module's `identify` are thin
//! callers that read their inputs, build the request, run it and write or return the outcome.

use std::path::PathBuf;

use super::cv::{CrossValidation, Holdout, Model};
use super::verdict::ValidationRows;
use super::Registration;
use crate::identify::MethodSpec;
use crate::measurement::kind_csv::KindFile;
use crate::measurement::Measurements;
use crate::numeric::Real;
use crate::robot::compliance::CompliancePick;
use crate::robot::{Param, Robot};

/// The readings an identification runs on.
#[derive(Clone, Debug)]
pub enum IdentifyData {
    /// A tracker's measurements (docs/formats.md § 5.1).
    Tracker(Measurements),
    /// A measurement-kind file: distance, plane, sphere or targets (§ 5.3).
    Kind(KindFile),
}

/// Why `k` does not apply to a tracker's positions.
pub(crate) const K_ON_POSITIONS: &str =
    "weighs orientation against position errors; the data hold positions only";

impl IdentifyData {
    /// Why `k`, the weight of orientation against position errors (`--k`, a method's `k`),
    /// does not apply to these data, if it does not: it applies to a tracker's full poses.
    pub fn k_refusal(&self) -> Option<&'static str> {
        match self {
            IdentifyData::Tracker(m) if m.measure() == crate::measurement::Measure::Position => {
                Some(K_ON_POSITIONS)
            }
            IdentifyData::Tracker(_) => None,
            IdentifyData::Kind(_) => Some(
                "weighs orientation against position errors; it applies to the tracker's \
                 measurement file (§ 5.1) only",
            ),
        }
    }
}

/// Everything one identification takes (the options of `calbench identify`,
/// docs/formats.md `identify`).
#[derive(Clone)]
pub struct IdentifyRequest {
    /// The nominal robot.
    pub robot: Robot,
    /// The readings.
    pub data: IdentifyData,
    /// Where they were read from: named in the record and in every refusal.
    pub source: PathBuf,
    /// The method with its options.
    pub method: MethodSpec,
    /// How the measured points are brought into the base frame.
    pub registration: Registration,
    /// Orientation weight (mm per rad) for full-pose data; `None`: the method's.
    pub k: Option<Real>,
    /// Priors on parameters' errors (σ), added to the method's.
    pub priors: Vec<(Param, Real)>,
    /// A validation measurement (a tracker's).
    pub validate: Option<Measurements>,
    /// The file `validate` was read from, when it was: named in a refusal of its rows.
    pub validate_source: Option<PathBuf>,
    /// The line of `validate_source` of each of its rows, by which a refusal names a reading.
    pub validate_lines: Option<Vec<u64>>,
    /// Rows of the data held out for validation instead.
    pub holdout: Option<Holdout>,
    /// K-fold cross-validation (K), and the folds of `models`.
    pub cv: Option<usize>,
    /// Seed of the folds (0 when `None`); refused without `cv` or `models`, which it would
    /// not change.
    pub cv_seed: Option<u64>,
    /// Candidate models compared by cross-validation; the best is identified.
    pub models: Vec<Model>,
    /// The cross-validations of `models` already run on the request's folds (`cv` folds, or
    /// 5, at `cv_seed`, with its method, registration, seed and fixed parameters), taken
    /// instead of running them again: a task's repeated choice hands over the chosen model's
    /// ([`super::task::Task::entry_request`]). `None`: run them.
    pub cross_validated: Option<Vec<CrossValidation>>,
    /// The identified parameters; empty: the identifiable set.
    pub params: Vec<Param>,
    /// Parameters held at their nominal values.
    pub fix: Vec<Param>,
    /// Joint compliances identified with the kinematic errors.
    pub compliance: Option<CompliancePick>,
    /// Seed of the method's random stream.
    pub seed: u64,
    /// Keep a result whose data do not determine every parameter.
    pub allow_rank_deficient: bool,
    /// Keep a result that makes the robot worse than the nominal one (with a warning).
    pub allow_worse: bool,
    /// Keep a result that cannot be physically right ([`super::plausibility`]), with a
    /// warning.
    pub allow_implausible: bool,
    /// The row of the data file (0-based) of each row of `data`, where `data` is a selection
    /// of the file's rows (a task's calibration rows of its split), so that a refusal names a
    /// row by the file's; `None` where `data` is the file's rows in order.
    pub data_rows: Option<Vec<usize>>,
    /// The line of `source` of each of its data rows, in file order, where the data were read
    /// from a file ([`crate::measurement::csv::read_measurements_at_lines`], a task's export
    /// through its mapping): a refusal names a reading by its line; `None` (arrays) by its
    /// row.
    pub data_lines: Option<Vec<u64>>,
}

impl IdentifyRequest {
    /// A request with the command line's defaults: `identify` registration, no options.
    pub fn new(robot: Robot, data: IdentifyData, source: PathBuf, method: MethodSpec) -> Self {
        IdentifyRequest {
            robot,
            data,
            source,
            method,
            registration: Registration::Identify,
            k: None,
            priors: Vec::new(),
            validate: None,
            validate_source: None,
            validate_lines: None,
            holdout: None,
            cv: None,
            cv_seed: None,
            models: Vec::new(),
            cross_validated: None,
            params: Vec::new(),
            fix: Vec::new(),
            compliance: None,
            seed: 0,
            allow_rank_deficient: false,
            allow_worse: false,
            allow_implausible: false,
            data_rows: None,
            data_lines: None,
        }
    }

    /// The data file's row (0-based) of row `i` of the rows identified on: through the
    /// calibration rows `cal` of a holdout (`None` without one) and [`Self::data_rows`].
    pub(super) fn file_row(&self, cal: Option<&[usize]>, i: usize) -> usize {
        let i = cal.map_or(i, |cal| cal[i]);
        self.data_rows.as_ref().map_or(i, |rows| rows[i])
    }

    /// Where the rows of [`Self::validate`] came from, as a refusal names them: its file, the
    /// arrays of a caller that gave no file, or none.
    pub(super) fn validation_rows(&self) -> ValidationRows<'_> {
        match (self.validate_source.as_deref(), &self.validate) {
            (Some(f), _) => ValidationRows::File(f),
            (None, Some(_)) => ValidationRows::Given,
            (None, None) => ValidationRows::OfData,
        }
    }

    /// The point of row `i` of the validation file ([`Self::validate`]) in words: by its line
    /// of the file, or by its 0-based row of rows that came from no file.
    pub(super) fn validation_point(&self, i: usize) -> String {
        let line = self.validate_lines.as_ref().and_then(|lines| lines.get(i));
        match (&self.validate_source, line) {
            (Some(f), Some(line)) => format!("the point on line {line} of {}", f.display()),
            _ => format!("the point of validation row {i} (0-based)"),
        }
    }

    /// The point of row `i` of the rows identified on ([`Self::file_row`]) in words: by its
    /// line of the file (`the point on line 17 of cal.csv`), or by its 0-based row of data
    /// that came from no file.
    pub(super) fn point_named(&self, cal: Option<&[usize]>, i: usize) -> String {
        let row = self.file_row(cal, i);
        match self.data_lines.as_ref().and_then(|lines| lines.get(row)) {
            Some(line) => format!("the point on line {line} of {}", self.source.display()),
            None => format!("the point of row {row} of the data (0-based)"),
        }
    }
}
