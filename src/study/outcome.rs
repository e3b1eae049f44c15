//! What one method on one strategy's measurement gave in one trial ([`Outcome`]), with the
//! statistics only some studies have ([`OptionalStats`]) and a search's runtime numbers
//! ([`SearchRun`]), and a whole trial's ([`TrialResult`]): the values the aggregation, the
//! records and the claims read, apart from how a trial computes them (`super::trial`) and how
//! they are aggregated (`super::stats`). This module imports neither.

use serde::{Deserialize, Serialize};

use crate::calibrate::ErrorStats;
use crate::identify::Termination;
use crate::numeric::Real;

/// One trial's results. Its serde form (trial 0's details and the index aside) is what a
/// record of `records.txt` holds ([`crate::study::records`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TrialResult {
    /// Trial index (a record holds it beside the trial).
    #[serde(skip)]
    pub index: usize,
    /// The injected errors, one per study parameter (0 where none was injected).
    pub truth: Vec<Real>,
    /// The Cramér–Rao trace per strategy (`None` without tracker noise).
    pub crb_trace: Vec<Option<Real>>,
    /// Per strategy, the study parameters (indices) whose non-zero injected error is not
    /// determinable in this trial: at most [`crate::study::crb::DETERMINABLE_SIGMAS`]
    /// Cramér–Rao σ at the strategy's measured rows on the true robot; their η does not
    /// count. Left out of a record when every list is empty (and read so).
    #[serde(default, skip_serializing_if = "all_empty")]
    pub not_determinable: Vec<Vec<usize>>,
    /// One outcome per strategy × method.
    pub outcomes: Vec<Outcome>,
}

impl TrialResult {
    /// The study parameters not determinable in this trial on strategy `strategy`'s
    /// measurement ([`TrialResult::not_determinable`]; none where a record left the lists
    /// out).
    pub fn not_determinable_on(&self, strategy: usize) -> &[usize] {
        self.not_determinable
            .get(strategy)
            .map_or(&[], Vec::as_slice)
    }
}

fn all_empty(v: &[Vec<usize>]) -> bool {
    v.iter().all(Vec::is_empty)
}

/// The targets' precisions Δ: a search reaches target Δ on a trial when its best fitness is
/// at most f_ref · (1 + Δ), f_ref the best final fitness of the searches of the same fitness
/// on the trial's draws (docs/formats.md "Searches compared").
pub const DELTAS: [Real; 4] = [1.0, 0.1, 0.01, 0.001];

/// The budget grid: shares of the smallest evaluation count the searches of the same fitness
/// spent on the trial.
pub const BUDGET_FRACTIONS: [Real; 4] = [0.1, 0.25, 0.5, 1.0];

/// One search's numbers on one trial ([`crate::study::stats::ecdf`] computes and aggregates
/// them).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SearchRun {
    /// The smallest evaluation count of the searches of the same fitness on the trial: the
    /// budget the grid's shares apply to.
    pub budget: usize,
    /// Per target ([`DELTAS`]), the evaluations at which the best fitness first reached it.
    pub hits: [Option<usize>; DELTAS.len()],
    /// Per budget ([`BUDGET_FRACTIONS`]), the best fitness after that many evaluations
    /// (NaN before the first iteration's end).
    pub at_budget: [Real; BUDGET_FRACTIONS.len()],
    /// Its best fitness at the end of its own budget (the last iteration's; NaN without
    /// one): Qiao 2021 fig. 4's curve at its end, the per-trial metric `final_fitness`.
    pub final_fitness: Real,
}

/// What one method on one strategy's measurement gave in one trial.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Outcome {
    /// Index into the scenario's methods.
    pub method: usize,
    /// Index into the scenario's strategies.
    pub strategy: usize,
    /// Identified errors, one per study parameter (mm, rad).
    pub identified: Vec<Real>,
    /// Validation position errors (mm) before compensation: statistics.
    pub before_mm: ErrorStats,
    /// … after compensation.
    pub after_mm: ErrorStats,
    /// Position errors (mm) at the calibration poses against their noise-free true points
    /// (sag included): the nominal robot, before.
    pub calibration_before_mm: ErrorStats,
    /// … the compensated robot, in its registration, after.
    pub calibration_after_mm: ErrorStats,
    /// The statistics only some studies have (absent: `None`).
    pub optional: OptionalStats,
    /// Per-point validation errors before and after (kept for trial 0's plot only).
    #[serde(skip)]
    pub per_point: Option<(Vec<Real>, Vec<Real>)>,
    /// Per-point attitude errors (Qiao's, deg) before and after, for full-pose data (trial 0
    /// only; Qiao 2021 fig. 6).
    #[serde(skip)]
    pub per_point_attitude_deg: Option<(Vec<Real>, Vec<Real>)>,
    /// A metaheuristic's best fitness per iteration (trial 0 only).
    #[serde(skip)]
    pub trace: Option<Vec<Real>>,
    /// A search's runtime and fixed-budget numbers on this trial (`None` for the methods
    /// without a fitness trace; [`crate::study::stats::ecdf`]).
    pub search: Option<SearchRun>,
    /// Iterations of the identification.
    pub iterations: usize,
    /// Evaluations of the model in the identification ([`crate::identify::Identified`]'s
    /// `evaluations`: residuals for the Jacobian methods, fitness for the searches).
    pub evaluations: usize,
    /// How it ended.
    pub termination: Termination,
    /// Whether the identified list is known to be rank-deficient (`identification.params`
    /// names undetermined parameters): a `rank-deficient` termination is then the expected
    /// outcome of a damped method, not a failure.
    pub rank_deficient_expected: bool,
    /// Wall time of registration and identification (s). Not part of the reproducible output.
    pub seconds: Real,
    /// Why the calibration gave no result, when it failed with an error (a method supplied
    /// from outside that raised, an inconsistent problem).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// Declares [`OptionalStats`] from its fields: the field names are the `summary.json` names
/// (and those of a record in `records.txt`).
macro_rules! optional_stats {
    ($($(#[$doc:meta])* $name:ident,)*) => {
        /// The statistics only some studies have, each `None` where a study has none:
        /// validation orientation (rotation angle, Qiao's attitude) before and after for
        /// full-pose data, the fitted "before" (`validation.before_fitted`), Guo's axis errors
        /// (`validation.axis_errors`; [`crate::calibrate::PoseErrors::axis_mm`], [`crate::calibrate::PoseErrors::axis_abs_mm`]) and
        /// Qiao's attitude at the calibration poses for full-pose data. Each field's name is
        /// its key in `summary.json` (docs/formats.md § 7.1).
        #[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
        pub struct OptionalStats {
            $($(#[$doc])* pub $name: Option<ErrorStats>,)*
        }

        impl OptionalStats {
            /// The fields' names, in their order.
            pub const NAMES: [&'static str; [$(stringify!($name)),*].len()] =
                [$(stringify!($name)),*];

            /// The fields' values, in the order of [`OptionalStats::NAMES`].
            pub fn values(&self) -> [Option<ErrorStats>; OptionalStats::NAMES.len()] {
                [$(self.$name),*]
            }
        }
    };
}

optional_stats! {
    /// Validation orientation error before, rotation angle (deg).
    validation_before_deg,
    /// … after.
    validation_after_deg,
    /// Validation attitude error (Qiao 2021) before (deg).
    validation_before_attitude_deg,
    /// … after.
    validation_after_attitude_deg,
    /// The "before" of a nominal model fitted in its registration (mm).
    validation_before_fitted_mm,
    /// Guo's signed axis errors before (mm).
    validation_before_axis_mm,
    /// … after.
    validation_after_axis_mm,
    /// Guo's absolute axis errors before (mm).
    validation_before_axis_abs_mm,
    /// … after.
    validation_after_axis_abs_mm,
    /// Attitude error at the calibration poses before (deg).
    calibration_before_attitude_deg,
    /// … after.
    calibration_after_attitude_deg,
}

/// The `summary.json` names of [`Outcome::optional`], in its order.
pub const OPTIONAL_STATS: [&str; OptionalStats::NAMES.len()] = OptionalStats::NAMES;
