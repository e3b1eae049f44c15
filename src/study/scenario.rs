//! Scenario files (docs/formats.md, "Scenario file"): parsed, then checked into a validated
//! [`Scenario`] before any trial runs. A bad file is refused with the file, the key and what
//! is allowed.
//!
//! Each section's settings type lives with the code that uses it (the simulator's
//! [`ErrorSettings`], [`TrackerSettings`], [`OutlierSettings`], the compliance model's
//! [`ComplianceSettings`]); this module composes them, adds the study-level keys and checks
//! the whole. Sweeps and command-line overrides edit the parsed TOML and check it again, so a
//! swept value is held to the same rules as a written one.

use std::path::{Path, PathBuf};

use serde::Deserialize;

pub use crate::calibrate::Registration;
use crate::error::{Error, Result};
use crate::identify::registry::method_names;
pub use crate::identify::MethodSpec;
use crate::numeric::Real;
use crate::poses::{Objective, Strategy as Optimiser};
use crate::robot::builtin;
use crate::robot::Robot;
use crate::sim::sag::ComplianceSettings;
use crate::sim::settings::{
    ErrorSettings, OutlierSettings, ParamSelection, Region, TrackerSettings,
};
use crate::sim::truth::selected_params;

/// The scenario file, as written. Unknown keys are refused by serde.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScenario {
    name: String,
    #[serde(default)]
    description: String,
    #[serde(default = "default_seed")]
    seed: u64,
    #[serde(default = "default_trials")]
    trials: usize,
    robot: RobotSection,
    #[serde(default)]
    errors: ErrorSettings,
    #[serde(default)]
    tracker: TrackerSettings,
    #[serde(default)]
    outliers: OutlierSettings,
    #[serde(default)]
    compliance: ComplianceSettings,
    #[serde(default)]
    registration: RegistrationSection,
    #[serde(default)]
    calibration: CalibrationSection,
    #[serde(default)]
    validation: ValidationSection,
    #[serde(default)]
    identification: IdentificationSpec,
    methods: Vec<toml::Table>,
    sweep: Option<SweepField>,
}

fn default_seed() -> u64 {
    1
}
fn default_trials() -> usize {
    100
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotSection {
    builtin: Option<String>,
    file: Option<PathBuf>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RegistrationSection {
    #[serde(default)]
    method: Registration,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct CalibrationSection {
    count: usize,
    strategies: Vec<String>,
    poses_file: Option<PathBuf>,
    region: Region,
    candidates: usize,
    objective: String,
    separate: bool,
    separate_threshold: Real,
    payloads_kg: Option<Vec<Real>>,
}

impl Default for CalibrationSection {
    fn default() -> Self {
        CalibrationSection {
            count: 50,
            strategies: vec!["random".into()],
            poses_file: None,
            region: Region::Joint,
            candidates: 1000,
            objective: "composite".into(),
            separate: false,
            separate_threshold: 1e2,
            payloads_kg: None,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct ValidationSection {
    count: usize,
    region: Region,
    payload_kg: Option<Real>,
}

impl Default for ValidationSection {
    fn default() -> Self {
        ValidationSection {
            count: 50,
            region: Region::Joint,
            payload_kg: None,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepSection {
    key: String,
    values: Vec<toml::Value>,
    #[serde(default)]
    zip: bool,
}

/// `[sweep]` (one axis) or `[[sweep]]` (a grid of axes).
#[derive(Deserialize)]
#[serde(untagged)]
enum SweepField {
    One(SweepSection),
    Grid(Vec<SweepSection>),
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
    /// Optimised once per study on the nominal robot (Guo 2024 §3), on the separated model
    /// when `calibration.separate` is set.
    Optimised(Optimiser),
    /// Optimised once per study on the full model, every joint parameter with no separation
    /// (Guo 2024 fig. 6 and table 8, "full-parameter model").
    OptimisedFull(Optimiser),
}

/// The names accepted in `calibration.strategies` (serde, kebab-case).
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

/// The names of `calibration.strategies`, comma-separated (for messages).
fn strategy_names() -> String {
    <StrategyName as strum::VariantNames>::VARIANTS.join(", ")
}

impl PoseStrategy {
    /// The name used in files and reports.
    pub fn name(&self) -> &'static str {
        let name = match self {
            PoseStrategy::Random
            | PoseStrategy::Optimised(Optimiser::Random)
            | PoseStrategy::OptimisedFull(Optimiser::Random) => StrategyName::Random,
            PoseStrategy::Box => StrategyName::Box,
            PoseStrategy::Grid => StrategyName::Grid,
            PoseStrategy::File(_) => StrategyName::File,
            PoseStrategy::Optimised(Optimiser::Detmax) => StrategyName::Detmax,
            PoseStrategy::Optimised(Optimiser::Ide) => StrategyName::Ide,
            PoseStrategy::Optimised(Optimiser::DetmaxIde) => StrategyName::DetmaxIde,
            PoseStrategy::OptimisedFull(Optimiser::Detmax) => StrategyName::DetmaxFull,
            PoseStrategy::OptimisedFull(Optimiser::Ide) => StrategyName::IdeFull,
            PoseStrategy::OptimisedFull(Optimiser::DetmaxIde) => StrategyName::DetmaxIdeFull,
        };
        name.into()
    }
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
}

/// One axis of a sweep: a dotted key and its values.
#[derive(Clone, Debug)]
pub struct SweepAxis {
    /// The key, e.g. `outliers.count` or `methods.<label>.k0`.
    pub key: String,
    /// The values, as written.
    pub values: Vec<toml::Value>,
}

/// The swept settings (docs/formats.md `[sweep]`, `[[sweep]]`): one axis, or several axes run as
/// their cartesian product (the last axis varying fastest) or, with `zip`, paired value by
/// value.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// The axes, in file order.
    pub axes: Vec<SweepAxis>,
    /// The axes' lists are paired (`zip = true` on the first axis) instead of crossed.
    pub zip: bool,
}

impl Sweep {
    /// The swept keys, in axis order.
    pub fn keys(&self) -> Vec<&str> {
        self.axes.iter().map(|a| a.key.as_str()).collect()
    }

    /// Every point of the sweep: one value per axis, in run order.
    pub fn points(&self) -> Vec<Vec<toml::Value>> {
        if self.zip {
            let n = self.axes[0].values.len();
            return (0..n)
                .map(|i| self.axes.iter().map(|a| a.values[i].clone()).collect())
                .collect();
        }
        let mut points: Vec<Vec<toml::Value>> = vec![Vec::new()];
        for a in &self.axes {
            points = points
                .iter()
                .flat_map(|p| {
                    a.values.iter().map(move |v| {
                        let mut q = p.clone();
                        q.push(v.clone());
                        q
                    })
                })
                .collect();
        }
        points
    }

    /// The number of independent dimensions the results span: 1 for one axis or zipped
    /// axes, else the number of axes.
    pub fn dims(&self) -> usize {
        if self.zip {
            1
        } else {
            self.axes.len()
        }
    }
}

/// A checked scenario: every value in range, ready to run.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// The file it came from (`None` for the built-in default).
    pub path: Option<PathBuf>,
    /// Study name (the results folder).
    pub name: String,
    /// What the study asks.
    pub description: String,
    /// Master seed: trial i uses `rng::trial_seed(seed, i)`.
    pub seed: u64,
    /// Number of Monte-Carlo trials.
    pub trials: usize,
    /// The robot.
    pub robot: RobotRef,
    /// The injected errors.
    pub errors: ErrorSettings,
    /// The simulated laser tracker.
    pub tracker: TrackerSettings,
    /// Gross outliers in the calibration measurements.
    pub outliers: OutlierSettings,
    /// Gravity sag.
    pub compliance: ComplianceSettings,
    /// Registration of the tracker frame.
    pub registration: Registration,
    /// Calibration poses.
    pub calibration: Calibration,
    /// Validation poses.
    pub validation: Validation,
    /// What the methods identify.
    pub identification: IdentificationSpec,
    /// Identification methods compared.
    pub methods: Vec<MethodSpec>,
    /// The optional sweep.
    pub sweep: Option<Sweep>,
    table: toml::Table,
}

/// The most trials a study may ask for (docs/formats.md `trials`): more is refused, not run until
/// killed.
pub const MAX_TRIALS: usize = 1_000_000_000;

/// The built-in default study (`scenarios/default.toml`): what `calbench` runs with no
/// arguments.
pub const DEFAULT_SCENARIO: &str = include_str!("../../scenarios/default.toml");

impl Scenario {
    /// Reads and checks a scenario file.
    pub fn load(path: &Path) -> Result<Scenario> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Scenario::parse(&text, Some(path))
    }

    /// The built-in default study.
    pub fn default_study() -> Result<Scenario> {
        Scenario::parse(DEFAULT_SCENARIO, None)
    }

    /// Parses and checks a scenario's text; `path` (for messages and relative files) is the
    /// file it came from.
    pub fn parse(text: &str, path: Option<&Path>) -> Result<Scenario> {
        let shown = path.unwrap_or(Path::new("<built-in default scenario>"));
        let table: toml::Table = toml::from_str(text)
            .map_err(|e| Error::file(shown, "TOML", e.to_string().trim_end()))?;
        Scenario::from_table(table, path)
    }

    fn from_table(table: toml::Table, path: Option<&Path>) -> Result<Scenario> {
        let shown = path
            .unwrap_or(Path::new("<built-in default scenario>"))
            .to_path_buf();
        let ferr = |place: &str, msg: String| Error::file(&shown, place, msg);
        if table.contains_key("registration_study") {
            return Err(ferr(
                "registration_study",
                "this is a registration study (Ban fig. 3), which `calbench run` runs on its \
                 own; it is not a calibration scenario"
                    .into(),
            ));
        }
        let raw: RawScenario = toml::Value::Table(table.clone())
            .try_into()
            .map_err(|e: toml::de::Error| ferr("scenario", e.to_string().trim_end().into()))?;
        let dir = path
            .and_then(Path::parent)
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let check = |r: Result<()>| r.map_err(|e| ferr("setting", e.to_string()));

        if raw.name.trim().is_empty() || raw.name.contains(['/', '\\']) {
            return Err(ferr(
                "name",
                "must be a non-empty name without slashes".into(),
            ));
        }
        if raw.trials == 0 || raw.trials > MAX_TRIALS {
            return Err(ferr(
                "trials",
                format!("must be between 1 and {MAX_TRIALS}, got {}", raw.trials),
            ));
        }
        let robot = match (raw.robot.builtin, raw.robot.file) {
            (Some(b), None) => RobotRef::Builtin(b),
            (None, Some(f)) => RobotRef::File(dir.join(f)),
            _ => {
                return Err(ferr(
                    "robot",
                    "give exactly one of `builtin = \"NAME\"` or `file = \"PATH\"`".into(),
                ))
            }
        };
        check(raw.errors.check())?;
        check(raw.tracker.check())?;
        check(raw.outliers.check())?;

        let c = raw.calibration;
        if c.count == 0 {
            return Err(ferr("calibration.count", "must be at least 1".into()));
        }
        if c.strategies.is_empty() {
            return Err(ferr(
                "calibration.strategies",
                format!("give at least one of: {}", strategy_names()),
            ));
        }
        let mut strategies = Vec::new();
        for (i, s) in c.strategies.iter().enumerate() {
            let key = format!("calibration.strategies[{i}]");
            let name: StrategyName = crate::robot::names::parse(&key, s).map_err(|_| {
                ferr(
                    &key,
                    format!("unknown strategy \"{s}\"; allowed: {}", strategy_names()),
                )
            })?;
            let st = match name {
                StrategyName::Random => PoseStrategy::Random,
                StrategyName::Box => {
                    if !matches!(c.region, Region::Box { .. }) {
                        return Err(ferr(
                            "calibration.region",
                            "strategy \"box\" needs region = { kind = \"box\", … }".into(),
                        ));
                    }
                    PoseStrategy::Box
                }
                StrategyName::Grid => PoseStrategy::Grid,
                StrategyName::File => match &c.poses_file {
                    Some(f) => PoseStrategy::File(dir.join(f)),
                    None => {
                        return Err(ferr(
                            "calibration.poses_file",
                            "strategy \"file\" needs a pose list".into(),
                        ))
                    }
                },
                StrategyName::Detmax => PoseStrategy::Optimised(Optimiser::Detmax),
                StrategyName::Ide => PoseStrategy::Optimised(Optimiser::Ide),
                StrategyName::DetmaxIde => PoseStrategy::Optimised(Optimiser::DetmaxIde),
                StrategyName::DetmaxFull => PoseStrategy::OptimisedFull(Optimiser::Detmax),
                StrategyName::IdeFull => PoseStrategy::OptimisedFull(Optimiser::Ide),
                StrategyName::DetmaxIdeFull => PoseStrategy::OptimisedFull(Optimiser::DetmaxIde),
            };
            if strategies
                .iter()
                .any(|x: &PoseStrategy| x.name() == st.name())
            {
                return Err(ferr(
                    &format!("calibration.strategies[{i}]"),
                    format!("\"{s}\" is listed twice"),
                ));
            }
            strategies.push(st);
        }
        let optimised = strategies
            .iter()
            .any(|s| matches!(s, PoseStrategy::Optimised(_)));
        if optimised && c.candidates < c.count {
            return Err(ferr(
                "calibration.candidates",
                format!("must be at least calibration.count ({})", c.count),
            ));
        }
        let objective: Objective =
            crate::robot::names::parse("calibration.objective", &c.objective)
                .map_err(|e| ferr("calibration.objective", e.to_string()))?;
        if !(c.separate_threshold.is_finite() && c.separate_threshold > 0.0) {
            return Err(ferr(
                "calibration.separate_threshold",
                "must be a positive number".into(),
            ));
        }
        check(c.region.check("calibration.region"))?;
        let v = raw.validation;
        if v.count == 0 {
            return Err(ferr("validation.count", "must be at least 1".into()));
        }
        check(v.region.check("validation.region"))?;
        let load = |key: &str, w: Real| {
            if w.is_finite() && w >= 0.0 {
                Ok(())
            } else {
                Err(ferr(
                    key,
                    format!("must be a finite payload ≥ 0 kg, got {w}"),
                ))
            }
        };
        if let Some(p) = &c.payloads_kg {
            if p.is_empty() {
                return Err(ferr(
                    "calibration.payloads_kg",
                    "give at least one payload, or leave the key out".into(),
                ));
            }
            for (i, &w) in p.iter().enumerate() {
                load(&format!("calibration.payloads_kg[{i}]"), w)?;
            }
        }
        if let Some(w) = v.payload_kg {
            load("validation.payload_kg", w)?;
        }
        if let Some(n) = raw.outliers.count {
            if n > c.count {
                return Err(ferr(
                    "outliers.count",
                    format!("{n} outliers but only {} calibration poses", c.count),
                ));
            }
        }

        if raw.methods.is_empty() {
            return Err(ferr(
                "methods",
                format!(
                    "give at least one [[methods]]; allowed names: {}",
                    method_names()
                ),
            ));
        }
        let mut methods = Vec::new();
        for (i, t) in raw.methods.iter().enumerate() {
            let m = MethodSpec::from_table(t).map_err(|(k, msg)| {
                let place = if k.is_empty() {
                    format!("methods[{i}]")
                } else {
                    format!("methods[{i}].{k}")
                };
                ferr(&place, msg)
            })?;
            let position_only = raw.tracker.measure.measure() != crate::measurement::Measure::Pose;
            if position_only && t.contains_key("k") {
                return Err(ferr(
                    &format!("methods[{i}].k"),
                    "k weighs orientation against position errors; the tracker measures \
                     positions only (set tracker.measure = \"pose\" or drop k)"
                        .into(),
                ));
            }
            if t.contains_key("error_model")
                && raw.identification.compliance != crate::robot::compliance::CompliancePick::None
            {
                return Err(ferr(
                    &format!("methods[{i}].error_model"),
                    "the pose-error models are kinematic; identification.compliance needs \
                     ls, ridge, igg3, lm or a search"
                        .into(),
                ));
            }
            if t.contains_key("error_model") && position_only {
                return Err(ferr(
                    &format!("methods[{i}].error_model"),
                    "the pose-error models need full-pose data: set tracker.measure = \"pose\""
                        .into(),
                ));
            }
            if methods.iter().any(|x: &MethodSpec| x.label == m.label) {
                return Err(ferr(
                    &format!("methods[{i}].label"),
                    format!(
                        "\"{}\" is used twice: give each method a distinct `label`",
                        m.label
                    ),
                ));
            }
            methods.push(m);
        }

        let sweep = match raw.sweep {
            None => None,
            Some(field) => Some(check_sweep(field).map_err(|(k, m)| ferr(&k, m))?),
        };

        let scenario = Scenario {
            path: path.map(Path::to_path_buf),
            name: raw.name,
            description: raw.description,
            seed: raw.seed,
            trials: raw.trials,
            robot,
            errors: raw.errors,
            tracker: raw.tracker,
            outliers: raw.outliers,
            compliance: raw.compliance,
            registration: raw.registration.method,
            calibration: Calibration {
                count: c.count,
                strategies,
                region: c.region,
                candidates: c.candidates,
                objective,
                separate: c.separate,
                separate_threshold: c.separate_threshold,
                payloads_kg: c.payloads_kg,
            },
            validation: Validation {
                count: v.count,
                region: v.region,
                payload_kg: v.payload_kg,
            },
            identification: raw.identification,
            methods,
            sweep,
            table,
        };
        // Settings that need the robot: joint counts of lists, parameter names.
        let robot = scenario.robot().map_err(|e| match e {
            Error::Setting { key, msg } => ferr(&key, msg),
            Error::File { .. } => e,
            other => ferr("robot.file", other.to_string()),
        })?;
        check(scenario.compliance.check(robot.dof()))?;
        check(
            scenario
                .identification
                .compliance
                .params(&robot, "identification.compliance")
                .map(|_| ()),
        )?;
        let selection = scenario.errors.selection();
        if let ParamSelection::List(_) = &selection {
            let measure = scenario.tracker.measure.measure();
            let key = scenario.errors.key();
            check(selected_params(&robot, &selection, measure, key).map(|_| ()))?;
        }
        if let ParamSelection::List(names) = &scenario.identification.params {
            let all = robot.params();
            crate::sim::settings::listed_params(names, |n| {
                crate::robot::Param::parse(n)
                    .filter(|p| all.contains(p))
                    .ok_or_else(|| {
                        Error::setting(
                            "identification.params",
                            format!(
                                "\"{n}\" is not a parameter of robot \"{}\" ({} convention, {} joints)",
                                robot.name,
                                robot.convention.as_str(),
                                robot.dof()
                            ),
                        )
                    })
            })
            .map_err(|e| match e {
                Error::Setting { msg, .. } => ferr("identification.params", msg),
                other => other,
            })?;
            if names.is_empty() {
                return Err(ferr(
                    "identification.params",
                    "give at least one parameter name".into(),
                ));
            }
        }
        if let Some(sw) = &scenario.sweep {
            for point in sw.points() {
                scenario.plan(&point)?;
            }
        }
        Ok(scenario)
    }

    /// The nominal robot.
    pub fn robot(&self) -> Result<Robot> {
        match &self.robot {
            RobotRef::Builtin(n) => {
                if builtin::builtin(n).is_none() {
                    let names: Vec<&str> = builtin::BUILTINS.iter().map(|b| b.name).collect();
                    return Err(Error::setting(
                        "robot.builtin",
                        format!("no built-in robot \"{n}\"; built-ins: {}", names.join(", ")),
                    ));
                }
                builtin::load(n)
            }
            RobotRef::File(p) => crate::robot::read_robot_file(p),
        }
    }

    /// The built-in robot's table entry (for default stiffness and masses), if built-in.
    pub fn builtin(&self) -> Option<&'static builtin::Builtin> {
        match &self.robot {
            RobotRef::Builtin(n) => builtin::builtin(n),
            RobotRef::File(_) => None,
        }
    }

    /// A copy with one dotted key (`outliers.count`, `trials`, `tracker.mpe_a_um`) set to
    /// `value`, checked again.
    pub fn with_override(&self, key: &str, value: toml::Value) -> Result<Scenario> {
        if key.starts_with("methods") {
            return Err(Error::setting(key, "methods cannot be overridden"));
        }
        Scenario::from_table(
            self.edited(self.table.clone(), key, value)?,
            self.path.as_deref(),
        )
    }

    /// The study of one sweep point (one value per axis): the scenario with each swept key
    /// set and no sweep, checked again. A refusal names the file and the swept key.
    pub fn plan(&self, point: &[toml::Value]) -> Result<Scenario> {
        let shown = self
            .path
            .clone()
            .unwrap_or_else(|| PathBuf::from("<built-in default scenario>"));
        let Some(sw) = &self.sweep else {
            return Ok(self.clone());
        };
        let mut table = self.table.clone();
        table.remove("sweep");
        let mut keys = Vec::new();
        for (axis, v) in sw.axes.iter().zip(point) {
            table = self.edited(table, &axis.key, v.clone()).map_err(|e| {
                Error::file(&shown, format!("sweep key \"{}\"", axis.key), e.to_string())
            })?;
            keys.push(format!("{} = {v}", axis.key));
        }
        Scenario::from_table(table, self.path.as_deref()).map_err(|e| {
            let msg = match e {
                Error::File { place, msg, .. } => format!("{place}: {msg}"),
                other => other.to_string(),
            };
            Error::file(&shown, format!("sweep ({})", keys.join(", ")), msg)
        })
    }

    /// `table` with the dotted `key` set to `value`. `methods.<label>.<key>` sets a key of
    /// the method whose `label` (or, without one, name) is `<label>`. The key must be one
    /// the scenario can hold: an unknown one is refused when the table is checked again.
    fn edited(&self, mut table: toml::Table, key: &str, value: toml::Value) -> Result<toml::Table> {
        let mut parts: Vec<&str> = key.split('.').collect();
        if parts.iter().any(|p| p.is_empty()) {
            return Err(Error::setting(key, "is not a dotted key"));
        }
        let last = parts.pop().unwrap_or_default();
        if parts.first() == Some(&"methods") {
            if parts.len() != 2 {
                return Err(Error::setting(
                    key,
                    "a method key is swept as methods.<label>.<key>",
                ));
            }
            let label = parts[1];
            let methods = table
                .get_mut("methods")
                .and_then(toml::Value::as_array_mut)
                .ok_or_else(|| Error::setting(key, "the scenario has no [[methods]]"))?;
            let label_of = |t: &toml::Table| {
                t.get("label")
                    .or_else(|| t.get("name"))
                    .and_then(toml::Value::as_str)
                    .map(str::to_string)
            };
            let labels: Vec<String> = methods
                .iter()
                .filter_map(|m| m.as_table().and_then(label_of))
                .collect();
            let m = methods
                .iter_mut()
                .filter_map(toml::Value::as_table_mut)
                .find(|t| label_of(t).as_deref() == Some(label))
                .ok_or_else(|| {
                    Error::setting(
                        key,
                        format!(
                            "no method labelled \"{label}\"; labels: {}",
                            labels.join(", ")
                        ),
                    )
                })?;
            if last == "name" || last == "label" {
                return Err(Error::setting(
                    key,
                    "a method's name and label cannot be swept",
                ));
            }
            m.insert(last.to_string(), value);
            return Ok(table);
        }
        if matches!(parts.first(), Some(&"sweep")) || (parts.is_empty() && last == "name") {
            return Err(Error::setting(key, "cannot be swept or overridden"));
        }
        let mut t = &mut table;
        for p in parts {
            t = t
                .entry(p.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                .as_table_mut()
                .ok_or_else(|| Error::setting(key, format!("`{p}` is not a section")))?;
        }
        t.insert(last.to_string(), value);
        Ok(table)
    }

    /// One checked scenario per sweep point, with the point's values (or the scenario itself
    /// when there is no sweep).
    pub fn sweep_plans(&self) -> Result<Vec<(Option<Vec<toml::Value>>, Scenario)>> {
        match &self.sweep {
            None => Ok(vec![(None, self.clone())]),
            Some(sw) => sw
                .points()
                .into_iter()
                .map(|p| {
                    let plan = self.plan(&p)?;
                    Ok((Some(p), plan))
                })
                .collect(),
        }
    }

    /// The scenario as a TOML table (as written, before checking): what a shard records so
    /// that shards of different scenarios are told apart.
    pub fn table(&self) -> &toml::Table {
        &self.table
    }
}

/// Checks the sweep section: every axis a key and a non-empty list, keys distinct, zipped
/// lists of one length. Returns (key, message) on refusal.
fn check_sweep(field: SweepField) -> std::result::Result<Sweep, (String, String)> {
    let (sections, grid) = match field {
        SweepField::One(s) => (vec![s], false),
        SweepField::Grid(v) => (v, true),
    };
    if sections.is_empty() {
        return Err(("sweep".into(), "give at least one [[sweep]] axis".into()));
    }
    let zip = sections[0].zip;
    let mut axes: Vec<SweepAxis> = Vec::new();
    for (i, s) in sections.into_iter().enumerate() {
        let place = if grid {
            format!("sweep[{i}]")
        } else {
            "sweep".into()
        };
        if s.zip && i > 0 {
            return Err((
                format!("{place}.zip"),
                "zip = true belongs on the first axis".into(),
            ));
        }
        if s.values.is_empty() {
            return Err((
                format!("{place}.values"),
                format!("\"{}\": give at least one value", s.key),
            ));
        }
        if axes.iter().any(|a| a.key == s.key) {
            return Err((
                format!("{place}.key"),
                format!("\"{}\" is swept twice", s.key),
            ));
        }
        if zip && s.values.len() != axes.first().map_or(s.values.len(), |a| a.values.len()) {
            return Err((
                format!("{place}.values"),
                format!(
                    "zipped axes need lists of one length: \"{}\" has {}, \"{}\" {}",
                    axes[0].key,
                    axes[0].values.len(),
                    s.key,
                    s.values.len()
                ),
            ));
        }
        axes.push(SweepAxis {
            key: s.key,
            values: s.values,
        });
    }
    Ok(Sweep { axes, zip })
}
