//! The sections of a scenario file: the sections as written (deserialised, unchecked) and
//! the checked settings of the study-level sections.

use std::path::PathBuf;

use serde::Deserialize;

use super::Registration;
use crate::numeric::Real;
use crate::poses::{Objective, Strategy as Optimiser};
use crate::sim::settings::{ParamSelection, Region};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RobotSection {
    pub(super) builtin: Option<String>,
    pub(super) file: Option<PathBuf>,
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RegistrationSection {
    #[serde(default)]
    pub(super) method: Registration,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct CalibrationSection {
    pub(super) count: usize,
    pub(super) strategies: Vec<String>,
    pub(super) poses_file: Option<PathBuf>,
    pub(super) region: Region,
    pub(super) candidates: usize,
    pub(super) objective: String,
    pub(super) separate: bool,
    pub(super) separate_threshold: Real,
    pub(super) payloads_kg: Option<Vec<Real>>,
    pub(super) optimise: OptimiseEach,
}

impl Default for CalibrationSection {
    fn default() -> Self {
        CalibrationSection {
            count: 50,
            strategies: vec!["random".into()],
            poses_file: None,
            region: Region::Joint {},
            candidates: 1000,
            objective: "composite".into(),
            separate: false,
            separate_threshold: 1e2,
            payloads_kg: None,
            optimise: OptimiseEach::Trial,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub(super) struct ValidationSection {
    pub(super) count: usize,
    pub(super) region: Region,
    pub(super) payload_kg: Option<Real>,
    pub(super) before_fitted: bool,
    pub(super) axis_errors: bool,
}

impl Default for ValidationSection {
    fn default() -> Self {
        ValidationSection {
            count: 50,
            region: Region::Joint {},
            payload_kg: None,
            before_fitted: false,
            axis_errors: false,
        }
    }
}

/// `[identification]`: what the methods identify (docs/formats.md, scenario file).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IdentificationSpec {
    /// The identified parameters: `"identifiable"` (the default: the joint and tool
    /// parameters pivoted QR finds identifiable, with the base when the registration is
    /// identified), `"all"` (every joint parameter of the model, θ, d, a, α and the β that
    /// exist, Guo 2024's full 21-parameter model of eq. 7, with the identifiable base and tool
    /// parameters) or a list of names. Lists that the data cannot determine are refused for
    /// the methods that need full rank (LS); LM and ridge solve them by their damping.
    pub params: ParamSelection,
    /// The joint compliances identified with the kinematic errors (elasto-geometric model,
    /// [`crate::robot::Param::Compliance`]): none by default, `"gravity"` or names.
    pub compliance: crate::robot::compliance::CompliancePick,
}

/// Where the robot comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum RobotRef {
    /// A built-in robot by name.
    Builtin(String),
    /// A robot file (resolved against the scenario file's folder).
    File(PathBuf),
}

/// How a set of calibration poses is chosen (docs/formats.md `calibration.strategies`).
#[derive(Clone, Debug, PartialEq)]
pub enum PoseStrategy {
    /// Drawn afresh each trial, uniformly within `calibration.region`.
    Random,
    /// Drawn afresh each trial with the tool point in the box `calibration.region`.
    Box,
    /// A regular grid over the joint ranges (the same every trial).
    Grid,
    /// The pose list `calibration.poses_file`.
    File(PathBuf),
    /// Optimised on the nominal robot (Guo 2024 §3) per trial or once per study
    /// (`calibration.optimise`), on the separated model when `calibration.separate` is set.
    Optimised(Optimiser),
    /// Optimised as [`PoseStrategy::Optimised`] on the full model, every joint parameter with no separation
    /// (Guo 2024 fig. 6 and table 8, "full-parameter model").
    OptimisedFull(Optimiser),
}

/// Every pose strategy by name: the one table of the names accepted in
/// `calibration.strategies` (serde, kebab-case), by `calbench poses --strategy` and in the
/// messages that list them, with what each runs ([`StrategyName::selection`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "kebab-case")]
pub enum StrategyName {
    /// [`PoseStrategy::Random`].
    Random,
    /// [`PoseStrategy::Box`].
    Box,
    /// [`PoseStrategy::Grid`].
    Grid,
    /// [`PoseStrategy::File`].
    File,
    /// DETMAX ([`PoseStrategy::Optimised`]).
    Detmax,
    /// IDE ([`PoseStrategy::Optimised`]).
    Ide,
    /// DETMAX-IDE ([`PoseStrategy::Optimised`]).
    DetmaxIde,
    /// DETMAX on the full model ([`PoseStrategy::OptimisedFull`]).
    DetmaxFull,
    /// IDE on the full model ([`PoseStrategy::OptimisedFull`]).
    IdeFull,
    /// DETMAX-IDE on the full model ([`PoseStrategy::OptimisedFull`]).
    DetmaxIdeFull,
}

impl StrategyName {
    /// The optimiser the strategy runs on a candidate pool and whether over the full model
    /// (every joint parameter, no separation); `None` for `box`, `grid` and `file`, which
    /// choose no poses among candidates.
    pub fn selection(self) -> Option<(Optimiser, bool)> {
        use StrategyName as N;
        Some(match self {
            N::Random => (Optimiser::Random, false),
            N::Box | N::Grid | N::File => return None,
            N::Detmax => (Optimiser::Detmax, false),
            N::Ide => (Optimiser::Ide, false),
            N::DetmaxIde => (Optimiser::DetmaxIde, false),
            N::DetmaxFull => (Optimiser::Detmax, true),
            N::IdeFull => (Optimiser::Ide, true),
            N::DetmaxIdeFull => (Optimiser::DetmaxIde, true),
        })
    }

    /// The name of `optimiser` over the separated (`full = false`) or the full model: the
    /// inverse of [`StrategyName::selection`]. `random` has one name on either model (a random
    /// subset depends on no model).
    pub fn of(optimiser: Optimiser, full: bool) -> StrategyName {
        use strum::IntoEnumIterator as _;
        let on = |full| StrategyName::iter().find(|n| n.selection() == Some((optimiser, full)));
        on(full)
            .or_else(|| on(!full))
            .unwrap_or_else(|| unreachable!("the table names every optimiser"))
    }

    /// The name used in files and messages.
    pub fn as_str(self) -> &'static str {
        self.into()
    }
}

/// The names of `calibration.strategies`, comma-separated (for messages).
pub(crate) fn strategy_names() -> String {
    <StrategyName as strum::VariantNames>::VARIANTS.join(", ")
}

impl PoseStrategy {
    /// The name used in files and reports.
    pub fn name(&self) -> &'static str {
        let name = match self {
            PoseStrategy::Random => StrategyName::Random,
            PoseStrategy::Box => StrategyName::Box,
            PoseStrategy::Grid => StrategyName::Grid,
            PoseStrategy::File(_) => StrategyName::File,
            PoseStrategy::Optimised(o) => StrategyName::of(*o, false),
            PoseStrategy::OptimisedFull(o) => StrategyName::of(*o, true),
        };
        name.into()
    }
}

/// How often the optimised pose sets are optimised (docs/formats.md `calibration.optimise`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OptimiseEach {
    /// Once per trial, on a candidate pool and with an optimiser drawn from the trial's seed,
    /// so that the trials vary the set the optimiser happens to choose and every interval
    /// covers it.
    #[default]
    Trial,
    /// Once per study, from the study's seed: every trial measures the same set, and the
    /// intervals are conditional on it.
    Study,
}

/// Calibration poses: how many, how chosen, from where.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// Poses per calibration set.
    pub count: usize,
    /// The strategies compared.
    pub strategies: Vec<PoseStrategy>,
    /// Region of random poses and of the optimisers' candidate pool.
    pub region: Region,
    /// Size of the optimisers' candidate pool.
    pub candidates: usize,
    /// The optimisers' objective.
    pub objective: Objective,
    /// Ill-conditioned parameter separation before optimising (Guo 2024 §3.1).
    pub separate: bool,
    /// GCN threshold of the separation.
    pub separate_threshold: Real,
    /// Whether the optimised sets are optimised per trial or once per study.
    pub optimise: OptimiseEach,
    /// Payloads (kg) under which every calibration pose is measured, once each (docs/formats.md
    /// `calibration.payloads_kg`); `None`: once, under `compliance.payload_kg`.
    pub payloads_kg: Option<Vec<Real>>,
}

/// Validation poses: drawn afresh each trial, never used for identification.
#[derive(Clone, Debug)]
pub struct Validation {
    /// Poses per trial.
    pub count: usize,
    /// Where they are drawn.
    pub region: Region,
    /// Payload (kg) of the validation poses (docs/formats.md `validation.payload_kg`); `None`:
    /// `compliance.payload_kg`.
    pub payload_kg: Option<Real>,
    /// Also report the nominal robot's validation errors after the best rigid fit of its
    /// points to the true ones (docs/formats.md `validation.before_fitted`; Li 2018 §1.1).
    pub before_fitted: bool,
    /// Also report Guo 2024's per-point position error, the mean of the errors along the
    /// three axes (docs/formats.md `validation.axis_errors`; Guo 2024 §5.3, table 8).
    pub axis_errors: bool,
}
