//! Scenario files (FORMATS.md, "Scenario file"): parsed, then checked into a validated
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
use crate::compliance::ComplianceSettings;
use crate::error::{Error, Result};
use crate::identify::registry::method_names;
pub use crate::identify::MethodSpec;
use crate::kinematics::Robot;
use crate::math::Real;
use crate::poses::{Objective, Strategy as Optimiser};
use crate::robots;
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
    sweep: Option<SweepSection>,
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
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct ValidationSection {
    count: usize,
    region: Region,
}

impl Default for ValidationSection {
    fn default() -> Self {
        ValidationSection {
            count: 50,
            region: Region::Joint,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepSection {
    key: String,
    values: Vec<toml::Value>,
}

/// `[identification]`: what the methods identify (FORMATS.md, scenario file).
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
}

/// Where the robot comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum RobotRef {
    /// A built-in robot by name.
    Builtin(String),
    /// A robot file (resolved against the scenario file's folder).
    File(PathBuf),
}

/// How a set of calibration poses is chosen (FORMATS.md `calibration.strategies`).
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

impl PoseStrategy {
    /// The name used in files and reports.
    pub fn name(&self) -> &'static str {
        match self {
            PoseStrategy::Random => "random",
            PoseStrategy::Box => "box",
            PoseStrategy::Grid => "grid",
            PoseStrategy::File(_) => "file",
            PoseStrategy::Optimised(o) => o.as_str(),
            PoseStrategy::OptimisedFull(o) => match o {
                Optimiser::Random => "random",
                Optimiser::Detmax => "detmax-full",
                Optimiser::Ide => "ide-full",
                Optimiser::DetmaxIde => "detmax-ide-full",
            },
        }
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
}

/// Validation poses: drawn afresh each trial, never used for identification.
#[derive(Clone, Debug)]
pub struct Validation {
    /// Poses per trial.
    pub count: usize,
    /// Where they are drawn.
    pub region: Region,
}

/// A swept setting: the dotted key and its values.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// The key, e.g. `outliers.count`.
    pub key: String,
    /// The values, as written.
    pub values: Vec<toml::Value>,
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

/// The most trials a study may ask for (FORMATS.md `trials`): more is refused, not run until
/// killed.
pub const MAX_TRIALS: usize = 1_000_000_000;

/// The built-in default study (`scenarios/default.toml`): what `calbench` runs with no
/// arguments.
pub const DEFAULT_SCENARIO: &str = include_str!("../scenarios/default.toml");

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
                "give at least one of: random, box, grid, file, detmax, ide, detmax-ide".into(),
            ));
        }
        let mut strategies = Vec::new();
        for (i, s) in c.strategies.iter().enumerate() {
            let key = format!("calibration.strategies[{i}]");
            let name: StrategyName = crate::names::parse(&key, s)
                .map_err(|_| {
                    ferr(
                        &key,
                        format!(
                            "unknown strategy \"{s}\"; allowed: random, box, grid, file, detmax, ide, detmax-ide"
                        ),
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
        let objective: Objective = crate::names::parse("calibration.objective", &c.objective)
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
            let position_only = raw.tracker.measure.measure() != crate::jacobian::Measure::Pose;
            if position_only && t.contains_key("k") {
                return Err(ferr(
                    &format!("methods[{i}].k"),
                    "k weighs orientation against position errors; the tracker measures \
                     positions only (set tracker.measure = \"pose\" or drop k)"
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
            Some(s) => {
                if s.values.is_empty() {
                    return Err(ferr("sweep.values", "give at least one value".into()));
                }
                if s.key.starts_with("sweep") || s.key == "name" {
                    return Err(ferr("sweep.key", format!("\"{}\" cannot be swept", s.key)));
                }
                Some(Sweep {
                    key: s.key,
                    values: s.values,
                })
            }
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
            },
            validation: Validation {
                count: v.count,
                region: v.region,
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
        if let ParamSelection::List(_) = &scenario.errors.params {
            let measure = scenario.tracker.measure.measure();
            check(selected_params(&robot, &scenario.errors.params, measure).map(|_| ()))?;
        }
        if let ParamSelection::List(names) = &scenario.identification.params {
            let all = robot.params();
            crate::sim::settings::listed_params(names, |n| {
                crate::kinematics::Param::parse(n)
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
            let shown = path.unwrap_or(Path::new("<built-in default scenario>"));
            for v in &sw.values {
                scenario.plan(&sw.key, v.clone()).map_err(|e| match e {
                    Error::Setting { key, msg } => {
                        Error::file(shown, format!("sweep ({key})"), msg)
                    }
                    other => other,
                })?;
            }
        }
        Ok(scenario)
    }

    /// The nominal robot.
    pub fn robot(&self) -> Result<Robot> {
        match &self.robot {
            RobotRef::Builtin(n) => {
                if robots::builtin(n).is_none() {
                    let names: Vec<&str> = robots::BUILTINS.iter().map(|b| b.name).collect();
                    return Err(Error::setting(
                        "robot.builtin",
                        format!("no built-in robot \"{n}\"; built-ins: {}", names.join(", ")),
                    ));
                }
                robots::load(n)
            }
            RobotRef::File(p) => crate::kinematics::read_robot_file(p),
        }
    }

    /// The built-in robot's table entry (for default stiffness and masses), if built-in.
    pub fn builtin(&self) -> Option<&'static robots::Builtin> {
        match &self.robot {
            RobotRef::Builtin(n) => robots::builtin(n),
            RobotRef::File(_) => None,
        }
    }

    /// A copy with one dotted key (`outliers.count`, `trials`, `tracker.mpe_a_um`) set to
    /// `value`, checked again.
    pub fn with_override(&self, key: &str, value: toml::Value) -> Result<Scenario> {
        Scenario::from_table(self.edited(key, value)?, self.path.as_deref())
    }

    /// The study of one swept value: the scenario with `key` set to `value` and no sweep.
    fn plan(&self, key: &str, value: toml::Value) -> Result<Scenario> {
        let mut table = self.edited(key, value)?;
        table.remove("sweep");
        Scenario::from_table(table, self.path.as_deref())
    }

    /// The scenario's table with the dotted `key` set to `value`.
    fn edited(&self, key: &str, value: toml::Value) -> Result<toml::Table> {
        let mut table = self.table.clone();
        if key.starts_with("methods") {
            return Err(Error::setting(key, "methods cannot be swept or overridden"));
        }
        let mut parts: Vec<&str> = key.split('.').collect();
        let last = parts
            .pop()
            .filter(|s| !s.is_empty())
            .ok_or_else(|| Error::setting("sweep.key", format!("\"{key}\" is not a dotted key")))?;
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

    /// One checked scenario per swept value (or the scenario itself when there is no sweep).
    pub fn sweep_plans(&self) -> Result<Vec<(Option<toml::Value>, Scenario)>> {
        match &self.sweep {
            None => Ok(vec![(None, self.clone())]),
            Some(sw) => sw
                .values
                .iter()
                .map(|v| Ok((Some(v.clone()), self.plan(&sw.key, v.clone())?)))
                .collect(),
        }
    }
}
