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

use crate::compliance::ComplianceSettings;
use crate::errmodel::ErrorModel;
use crate::error::{Error, Result};
use crate::identify::{
    LmOptions, LsOptions, Method, RidgeOptions, RobustOptions, Sigma0, WeightFn, XiRule,
};
use crate::kinematics::Robot;
use crate::math::Real;
use crate::metaheur::{BasOptions, BasPsoOptions, BasStart, PsoOptions, Velocity};
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

/// How the measured points are brought into the robot's base frame (FORMATS.md
/// `[registration]`, SPEC §3 "Registration").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Registration {
    /// SVD (Kabsch/Arun) of nominal against measured points, then identification.
    Svd,
    /// Ban's weighted SVD (eqs. 12–25), then identification.
    Wsvd,
    /// SVD for a first estimate, then the base parameters identified with the rest (Li 2018).
    #[default]
    Identify,
    /// The true tracker pose is used (simulation only).
    Known,
}

impl Registration {
    /// The name used in files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            Registration::Svd => "svd",
            Registration::Wsvd => "wsvd",
            Registration::Identify => "identify",
            Registration::Known => "known",
        }
    }

    /// Parses a command-line value.
    pub fn parse(s: &str) -> Result<Registration> {
        match s {
            "svd" => Ok(Registration::Svd),
            "wsvd" => Ok(Registration::Wsvd),
            "identify" => Ok(Registration::Identify),
            "known" => Ok(Registration::Known),
            _ => Err(Error::setting(
                "registration",
                format!("unknown method \"{s}\"; allowed: svd, wsvd, identify, known"),
            )),
        }
    }
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
    /// Optimised once per study on the nominal robot (Guo 2024 §3).
    Optimised(Optimiser),
}

/// The strategy names accepted in `calibration.strategies`.
pub const STRATEGY_NAMES: &[&str] = &[
    "random",
    "box",
    "grid",
    "file",
    "detmax",
    "ide",
    "detmax-ide",
];

impl PoseStrategy {
    /// The name used in files and reports.
    pub fn name(&self) -> &'static str {
        match self {
            PoseStrategy::Random => "random",
            PoseStrategy::Box => "box",
            PoseStrategy::Grid => "grid",
            PoseStrategy::File(_) => "file",
            PoseStrategy::Optimised(Optimiser::Random) => "random",
            PoseStrategy::Optimised(Optimiser::Detmax) => "detmax",
            PoseStrategy::Optimised(Optimiser::Ide) => "ide",
            PoseStrategy::Optimised(Optimiser::DetmaxIde) => "detmax-ide",
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

/// The method names accepted in `[[methods]]`.
pub const METHOD_NAMES: &[&str] = &["ls", "ridge", "igg3", "lm", "bas", "pso", "bas-pso"];

/// A derivative-free search of Qiao 2021 (eqs. 12–14) with its options.
#[derive(Clone, Debug)]
pub enum MetaAlgorithm {
    /// Beetle antennae search.
    Bas(BasOptions),
    /// Particle swarm optimisation.
    Pso(PsoOptions),
    /// The BAS-PSO hybrid.
    BasPso(BasPsoOptions),
}

/// A metaheuristic identification: the search, the fitness weight k of eq. 14 and the
/// search box (± `bound_mm` on lengths, ± `bound_rad` on angles, around the nominal values).
#[derive(Clone, Debug)]
pub struct MetaSpec {
    /// The search and its options.
    pub algorithm: MetaAlgorithm,
    /// Weight of the orientation terms in the fitness (Qiao eq. 14), mm.
    pub k: Real,
    /// Half-width of the search box on length parameters, mm.
    pub bound_mm: Real,
    /// Half-width of the search box on angle parameters, rad.
    pub bound_rad: Real,
}

/// How a method identifies the errors.
#[derive(Clone, Debug)]
pub enum Identifier {
    /// A Jacobian-based method (LS, ridge, IGG3, LM) on the analytic identification Jacobian.
    Jacobian {
        /// The method and its options.
        method: Method,
        /// Weight of the orientation rows of full-pose data (mm per rad; see
        /// [`crate::identify::RobotProblem::with_orientation_weight`]).
        k: Real,
    },
    /// Gauss–Newton least squares on one of Qiao 2021's three pose-error models
    /// (§2.2–2.3, §4.2; full-pose data only), `iterations` steps, orientation rows weighted
    /// by `k` (eq. 14's weighting).
    ErrorModel {
        /// The pose-error model.
        model: ErrorModel,
        /// Gauss–Newton steps.
        iterations: usize,
        /// Weight of the orientation rows against the position rows (mm per rad).
        k: Real,
    },
    /// A derivative-free search (Qiao 2021).
    Meta(MetaSpec),
}

impl Identifier {
    /// Sets the weight of orientation against position rows on full-pose data (mm per rad;
    /// the scenario key `k`). Fails unless `k` is finite and positive.
    pub fn set_orientation_weight(&mut self, k: Real) -> Result<()> {
        crate::error::finite_positive("k", k)?;
        match self {
            Identifier::Jacobian { k: w, .. } | Identifier::ErrorModel { k: w, .. } => *w = k,
            Identifier::Meta(m) => m.k = k,
        }
        Ok(())
    }

    /// The method's name.
    pub fn name(&self) -> &'static str {
        match self {
            Identifier::Jacobian { method, .. } => method.name(),
            Identifier::ErrorModel { .. } => "ls",
            Identifier::Meta(m) => match m.algorithm {
                MetaAlgorithm::Bas(_) => "bas",
                MetaAlgorithm::Pso(_) => "pso",
                MetaAlgorithm::BasPso(_) => "bas-pso",
            },
        }
    }
}

/// One identification method of the study, with a label for reports (`label`, defaulting to
/// the method's name).
#[derive(Clone, Debug)]
pub struct MethodSpec {
    /// The name in reports, `summary.json` and `trials.csv`.
    pub label: String,
    /// The method and its options.
    pub method: Identifier,
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
    /// Identification methods compared.
    pub methods: Vec<MethodSpec>,
    /// The optional sweep.
    pub sweep: Option<Sweep>,
    table: toml::Table,
}

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
        if raw.trials == 0 {
            return Err(ferr("trials", "must be at least 1".into()));
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
                format!("give at least one of: {}", STRATEGY_NAMES.join(", ")),
            ));
        }
        let mut strategies = Vec::new();
        for (i, s) in c.strategies.iter().enumerate() {
            let st = match s.as_str() {
                "random" => PoseStrategy::Random,
                "box" => {
                    if !matches!(c.region, Region::Box { .. }) {
                        return Err(ferr(
                            "calibration.region",
                            "strategy \"box\" needs region = { kind = \"box\", … }".into(),
                        ));
                    }
                    PoseStrategy::Box
                }
                "grid" => PoseStrategy::Grid,
                "file" => match &c.poses_file {
                    Some(f) => PoseStrategy::File(dir.join(f)),
                    None => {
                        return Err(ferr(
                            "calibration.poses_file",
                            "strategy \"file\" needs a pose list".into(),
                        ))
                    }
                },
                "detmax" => PoseStrategy::Optimised(Optimiser::Detmax),
                "ide" => PoseStrategy::Optimised(Optimiser::Ide),
                "detmax-ide" => PoseStrategy::Optimised(Optimiser::DetmaxIde),
                other => {
                    return Err(ferr(
                        &format!("calibration.strategies[{i}]"),
                        format!(
                            "unknown strategy \"{other}\"; allowed: {}",
                            STRATEGY_NAMES.join(", ")
                        ),
                    ))
                }
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
        let objective = match c.objective.as_str() {
            "composite" => Objective::Composite,
            "o1" => Objective::O1,
            "o6" => Objective::O6,
            o => {
                return Err(ferr(
                    "calibration.objective",
                    format!("unknown objective \"{o}\"; allowed: composite, o1, o6"),
                ))
            }
        };
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
                    METHOD_NAMES.join(", ")
                ),
            ));
        }
        let mut methods = Vec::new();
        for (i, t) in raw.methods.iter().enumerate() {
            let m = parse_method(t).map_err(|(k, msg)| ferr(&format!("methods[{i}].{k}"), msg))?;
            let position_only = raw.tracker.measure.measure() != crate::jacobian::Measure::Pose;
            if position_only && t.contains_key("k") {
                return Err(ferr(
                    &format!("methods[{i}].k"),
                    "k weighs orientation against position errors; the tracker measures \
                     positions only (set tracker.measure = \"pose\" or drop k)"
                        .into(),
                ));
            }
            if matches!(m.method, Identifier::ErrorModel { .. }) && position_only {
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
            methods,
            sweep,
            table,
        };
        // Settings that need the robot: joint counts of lists, parameter names.
        let robot = scenario.robot()?;
        check(scenario.compliance.check(robot.dof()))?;
        if let ParamSelection::List(_) = &scenario.errors.params {
            let measure = scenario.tracker.measure.measure();
            check(selected_params(&robot, &scenario.errors.params, measure).map(|_| ()))?;
        }
        if let Some(sw) = &scenario.sweep {
            for v in &sw.values {
                scenario.with_override(&sw.key, v.clone())?;
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
        let mut s = Scenario::from_table(table, self.path.as_deref())?;
        s.sweep = None;
        s.table.remove("sweep");
        Ok(s)
    }

    /// One checked scenario per swept value (or the scenario itself when there is no sweep).
    pub fn sweep_plans(&self) -> Result<Vec<(Option<toml::Value>, Scenario)>> {
        match &self.sweep {
            None => Ok(vec![(None, self.clone())]),
            Some(sw) => sw
                .values
                .iter()
                .map(|v| Ok((Some(v.clone()), self.with_override(&sw.key, v.clone())?)))
                .collect(),
        }
    }
}

type MethodError = (String, String);

fn get_real(t: &toml::Table, k: &str) -> std::result::Result<Option<Real>, MethodError> {
    match t.get(k) {
        None => Ok(None),
        Some(v) => {
            let x = v
                .as_float()
                .or_else(|| v.as_integer().map(|i| i as Real))
                .filter(|x| x.is_finite())
                .ok_or_else(|| (k.to_string(), format!("must be a finite number, got {v}")))?;
            Ok(Some(x))
        }
    }
}

fn get_positive(t: &toml::Table, k: &str) -> std::result::Result<Option<Real>, MethodError> {
    match get_real(t, k)? {
        Some(x) if x <= 0.0 => Err((k.to_string(), format!("must be > 0, got {x}"))),
        x => Ok(x),
    }
}

fn get_count(t: &toml::Table, k: &str) -> std::result::Result<Option<usize>, MethodError> {
    match t.get(k) {
        None => Ok(None),
        Some(v) => match v.as_integer() {
            Some(i) if i >= 1 => Ok(Some(i as usize)),
            _ => Err((
                k.to_string(),
                format!("must be a whole number ≥ 1, got {v}"),
            )),
        },
    }
}

fn get_bool(t: &toml::Table, k: &str) -> std::result::Result<Option<bool>, MethodError> {
    match t.get(k) {
        None => Ok(None),
        Some(v) => v
            .as_bool()
            .map(Some)
            .ok_or_else(|| (k.to_string(), format!("must be true or false, got {v}"))),
    }
}

fn get_str<'a>(t: &'a toml::Table, k: &str) -> std::result::Result<Option<&'a str>, MethodError> {
    match t.get(k) {
        None => Ok(None),
        Some(v) => v
            .as_str()
            .map(Some)
            .ok_or_else(|| (k.to_string(), format!("must be a string, got {v}"))),
    }
}

fn parse_xi(t: &toml::Table) -> std::result::Result<Option<XiRule>, MethodError> {
    match t.get("xi") {
        None => Ok(None),
        Some(toml::Value::String(s)) => match s.as_str() {
            "double-h" => Ok(Some(XiRule::DoubleH)),
            "gcv" => Ok(Some(XiRule::Gcv)),
            "l-curve" => Ok(Some(XiRule::LCurve)),
            _ => Err((
                "xi".into(),
                format!("unknown rule \"{s}\"; allowed: \"double-h\", \"gcv\", \"l-curve\" or a number ≥ 0"),
            )),
        },
        Some(_) => match get_real(t, "xi")? {
            Some(x) if x >= 0.0 => Ok(Some(XiRule::Fixed(x))),
            x => Err(("xi".into(), format!("must be ≥ 0, got {x:?}"))),
        },
    }
}

/// Parses one `[[methods]]` table: `name`, an optional `label`, and the method's options.
/// Every key is checked; an unknown one is refused with the keys the method accepts.
fn parse_method(t: &toml::Table) -> std::result::Result<MethodSpec, MethodError> {
    let name = get_str(t, "name")?.ok_or_else(|| {
        (
            "name".to_string(),
            format!("missing; allowed: {}", METHOD_NAMES.join(", ")),
        )
    })?;
    let allowed: &[&str] = match name {
        "ls" => &["eps", "max_iter", "error_model", "iterations", "k"],
        "bas" => &[
            "iterations",
            "antenna",
            "step",
            "decay",
            "antenna_floor",
            "step_floor",
            "start",
            "k",
            "bound_mm",
            "bound_rad",
        ],
        "pso" => &[
            "population",
            "iterations",
            "c1",
            "c2",
            "max_velocity",
            "inertia",
            "k",
            "bound_mm",
            "bound_rad",
        ],
        "bas-pso" => &[
            "population",
            "iterations",
            "c1",
            "c2",
            "c3",
            "antenna",
            "step",
            "decay",
            "antenna_floor",
            "step_floor",
            "max_velocity",
            "inertia",
            "k",
            "bound_mm",
            "bound_rad",
        ],
        "ridge" => &["xi", "eps", "max_iter", "k"],
        "igg3" => &["k0", "k1", "sigma0", "weight", "xi", "eps", "max_iter", "k"],
        "lm" => &[
            "mu",
            "adaptive",
            "marquardt",
            "lambda0",
            "eps",
            "max_iter",
            "k",
        ],
        other => {
            return Err((
                "name".into(),
                format!(
                    "unknown method \"{other}\"; allowed: {}",
                    METHOD_NAMES.join(", ")
                ),
            ))
        }
    };
    for k in t.keys() {
        if k != "name" && k != "label" && !allowed.contains(&k.as_str()) {
            return Err((
                k.clone(),
                format!(
                    "unknown key for method \"{name}\"; allowed: name, label, {}",
                    allowed.join(", ")
                ),
            ));
        }
    }
    let label = get_str(t, "label")?.unwrap_or(name).to_string();
    if name == "ls" {
        if let Some(m) = get_str(t, "error_model")? {
            let model = ErrorModel::parse("error_model", m)
                .map_err(|e| ("error_model".to_string(), e.to_string()))?;
            let iterations = get_count(t, "iterations")?.unwrap_or(10);
            let k = get_positive(t, "k")?.unwrap_or(crate::metaheur::DEFAULT_K);
            return Ok(MethodSpec {
                label,
                method: Identifier::ErrorModel {
                    model,
                    iterations,
                    k,
                },
            });
        }
        if t.contains_key("iterations") {
            return Err(("iterations".into(), "only with error_model".into()));
        }
    }
    if matches!(name, "bas" | "pso" | "bas-pso") {
        return Ok(MethodSpec {
            label,
            method: Identifier::Meta(parse_meta(name, t)?),
        });
    }
    let method = match name {
        "ls" => {
            let mut o = LsOptions::default();
            if let Some(e) = get_positive(t, "eps")? {
                o.eps = e;
            }
            if let Some(n) = get_count(t, "max_iter")? {
                o.max_iter = n;
            }
            Method::Ls(o)
        }
        "ridge" => {
            let mut o = RidgeOptions::default();
            if let Some(x) = parse_xi(t)? {
                o.xi = x;
            }
            if let Some(e) = get_positive(t, "eps")? {
                o.eps = e;
            }
            if let Some(n) = get_count(t, "max_iter")? {
                o.max_iter = n;
            }
            Method::Ridge(o)
        }
        "igg3" => {
            let mut o = RobustOptions::default();
            if let Some(x) = get_positive(t, "k0")? {
                o.k0 = x;
            }
            if let Some(x) = get_positive(t, "k1")? {
                o.k1 = x;
            }
            if o.k1 <= o.k0 {
                return Err((
                    "k1".into(),
                    format!("must exceed k0 ({}), got {}", o.k0, o.k1),
                ));
            }
            if let Some(s) = get_str(t, "sigma0")? {
                o.sigma0 = match s {
                    "classical" => Sigma0::Classical,
                    "mad" => Sigma0::Mad,
                    _ => {
                        return Err((
                            "sigma0".into(),
                            format!("unknown estimator \"{s}\"; allowed: classical, mad"),
                        ))
                    }
                };
            }
            if let Some(s) = get_str(t, "weight")? {
                o.weight = match s {
                    "igg3" => WeightFn::Igg3,
                    "huber" => WeightFn::Huber,
                    "tukey" => WeightFn::Tukey,
                    _ => {
                        return Err((
                            "weight".into(),
                            format!("unknown weight function \"{s}\"; allowed: igg3, huber, tukey"),
                        ))
                    }
                };
            }
            if let Some(x) = parse_xi(t)? {
                o.xi = x;
            }
            if let Some(e) = get_positive(t, "eps")? {
                o.eps = e;
            }
            if let Some(n) = get_count(t, "max_iter")? {
                o.max_iter = n;
            }
            Method::Igg3(o)
        }
        _ => {
            let mut o = LmOptions::default();
            if let Some(x) = get_positive(t, "mu")? {
                o.mu = x;
            }
            if let Some(b) = get_bool(t, "adaptive")? {
                o.adaptive = b;
            }
            if let Some(b) = get_bool(t, "marquardt")? {
                o.marquardt = b;
            }
            if let Some(x) = get_positive(t, "lambda0")? {
                o.lambda0 = x;
            }
            if let Some(e) = get_positive(t, "eps")? {
                o.eps = e;
            }
            if let Some(n) = get_count(t, "max_iter")? {
                o.max_iter = n;
            }
            Method::Lm(o)
        }
    };
    Ok(MethodSpec {
        label,
        method: Identifier::Jacobian {
            method,
            k: get_positive(t, "k")?.unwrap_or(crate::metaheur::DEFAULT_K),
        },
    })
}

/// A method by name with its default options (for `calbench identify --method`).
pub fn method_by_name(name: &str) -> Result<MethodSpec> {
    let mut t = toml::Table::new();
    t.insert("name".into(), toml::Value::String(name.into()));
    parse_method(&t).map_err(|(_, msg)| Error::setting("--method", msg))
}

/// Options of `bas`, `pso` and `bas-pso` (Qiao 2021 eqs. 12–14); the defaults are the
/// options structs' own.
fn parse_meta(name: &str, t: &toml::Table) -> std::result::Result<MetaSpec, MethodError> {
    let real = |k: &str, v: &mut Real| -> std::result::Result<(), MethodError> {
        if let Some(x) = get_positive(t, k)? {
            *v = x;
        }
        Ok(())
    };
    let count = |k: &str, v: &mut usize| -> std::result::Result<(), MethodError> {
        if let Some(x) = get_count(t, k)? {
            *v = x;
        }
        Ok(())
    };
    // The floors d0, δ0 of eq. 13 may be zero (pure geometric decay).
    let floor = |k: &str, v: &mut Real| -> std::result::Result<(), MethodError> {
        if let Some(x) = get_real(t, k)? {
            if x < 0.0 {
                return Err((k.into(), format!("must be at least 0, got {x}")));
            }
            *v = x;
        }
        Ok(())
    };
    // Velocity rule of the swarms: Clerc's constriction (eq. 12) unless `inertia = [w0, w1]`.
    let velocity = |v: &mut Velocity| -> std::result::Result<(), MethodError> {
        if let Some(x) = t.get("inertia") {
            let w: Vec<Real> = x
                .as_array()
                .map(|a| {
                    a.iter()
                        .filter_map(|e| e.as_float().or_else(|| e.as_integer().map(|i| i as Real)))
                        .filter(|e| e.is_finite() && *e >= 0.0)
                        .collect()
                })
                .unwrap_or_default();
            if w.len() != 2 || x.as_array().map_or(0, |a| a.len()) != 2 {
                return Err((
                    "inertia".into(),
                    format!("must be [start, end], two weights at least 0, got {x}"),
                ));
            }
            *v = Velocity::Inertia {
                start: w[0],
                end: w[1],
            };
        }
        Ok(())
    };
    let algorithm = match name {
        "bas" => {
            let mut o = BasOptions::default();
            count("iterations", &mut o.iterations)?;
            real("antenna", &mut o.antenna)?;
            real("step", &mut o.step)?;
            real("decay", &mut o.decay)?;
            floor("antenna_floor", &mut o.antenna_floor)?;
            floor("step_floor", &mut o.step_floor)?;
            if let Some(x) = get_str(t, "start")? {
                o.start = match x {
                    "centre" | "center" => BasStart::Centre,
                    "halton" => BasStart::Halton,
                    other => {
                        return Err((
                            "start".into(),
                            format!("\"{other}\" is not a start (centre, halton)"),
                        ))
                    }
                };
            }
            MetaAlgorithm::Bas(o)
        }
        "pso" => {
            let mut o = PsoOptions::default();
            count("population", &mut o.population)?;
            count("iterations", &mut o.iterations)?;
            real("c1", &mut o.c1)?;
            real("c2", &mut o.c2)?;
            real("max_velocity", &mut o.max_velocity)?;
            velocity(&mut o.velocity)?;
            MetaAlgorithm::Pso(o)
        }
        _ => {
            let mut o = BasPsoOptions::default();
            count("population", &mut o.population)?;
            count("iterations", &mut o.iterations)?;
            real("c1", &mut o.c1)?;
            real("c2", &mut o.c2)?;
            real("c3", &mut o.c3)?;
            real("antenna", &mut o.antenna)?;
            real("step", &mut o.step)?;
            real("decay", &mut o.decay)?;
            floor("antenna_floor", &mut o.antenna_floor)?;
            floor("step_floor", &mut o.step_floor)?;
            real("max_velocity", &mut o.max_velocity)?;
            velocity(&mut o.velocity)?;
            MetaAlgorithm::BasPso(o)
        }
    };
    let mut spec = MetaSpec {
        algorithm,
        k: crate::metaheur::DEFAULT_K,
        bound_mm: 2.0,
        bound_rad: 0.02,
    };
    real("k", &mut spec.k)?;
    real("bound_mm", &mut spec.bound_mm)?;
    real("bound_rad", &mut spec.bound_rad)?;
    Ok(spec)
}
