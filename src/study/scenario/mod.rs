//! Scenario files (docs/formats.md, "Scenario file"): parsed, then checked into a validated
//! [`Scenario`] before any trial runs. A bad file is refused with the file, the key and what
//! is allowed.
//!
//! Each section's settings type lives with the code that uses it (the simulator's
//! [`ErrorSettings`], [`TrackerSettings`], [`OutlierSettings`], the compliance model's
//! [`ComplianceSettings`]); this module composes them, adds the study-level keys and checks
//! the whole. Sweeps and command-line overrides edit the parsed TOML and check it again, so a
//! swept value is held to the same rules as a written one.

mod effect;
mod params;
mod report;
mod sections;
mod source;
mod sweep;

use std::path::{Path, PathBuf};

pub use crate::calibrate::Registration;
use crate::error::{at_line, read_text, Error, Result};
use crate::identify::registry::method_names;
pub use crate::identify::MethodSpec;
use crate::numeric::Real;
use crate::poses::Objective;
use crate::robot::builtin;
use crate::robot::Robot;
use crate::sim::poses::check_region;
use crate::sim::sag::{Compliance, ComplianceSettings};
use crate::sim::settings::{
    ErrorSettings, OutlierSettings, ParamSelection, Region, TrackerSettings,
};
use crate::sim::truth::selected_params;
use crate::sim::unmodelled::UnmodelledSettings;
pub use effect::effect;
pub use report::ReportSettings;
use sections::{
    strategy_names, CalibrationSection, RegistrationSection, RobotSection, ValidationSection,
};
pub use sections::{
    Calibration, IdentificationSpec, OptimiseEach, PoseStrategy, RobotRef, StrategyName, Validation,
};
use serde::Deserialize;
use source::Source;
pub(crate) use sweep::given;
use sweep::SweepField;
pub use sweep::{Sweep, SweepAxis};

/// The scenario file, as written. Unknown keys are refused by serde.
#[derive(Debug, Deserialize)]
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
    unmodelled: UnmodelledSettings,
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
    #[serde(default)]
    report: ReportSettings,
    #[serde(default)]
    claims: Vec<toml::Table>,
}

/// A Monte-Carlo scenario's seed and trials when its file gives none; its table as run
/// (`scenario.toml`) then has no such key either.
pub const DEFAULT_SEED: u64 = 1;
/// See [`DEFAULT_SEED`].
pub const DEFAULT_TRIALS: usize = 100;

fn default_seed() -> u64 {
    DEFAULT_SEED
}
fn default_trials() -> usize {
    DEFAULT_TRIALS
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
    /// Error outside the kinematic model (joint harmonics, backlash).
    pub unmodelled: UnmodelledSettings,
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
    /// How the reports present the study (`[report]`).
    pub report: ReportSettings,
    /// The paper's claims the run evaluates (`[[claims]]`).
    pub claims: Vec<crate::study::claims::Claim>,
    table: toml::Table,
    source: Option<Source>,
}

/// The most trials a study may ask for (docs/formats.md `trials`): more is refused, not run until
/// killed.
pub const MAX_TRIALS: usize = 1_000_000_000;

/// The most points a sweep may have (docs/formats.md § 4.13): each is checked as a scenario
/// before any trial runs, and a grid of a few lists of a thousand values each would be 10⁹.
pub const MAX_SWEEP_POINTS: usize = 1_000_000;

/// The most poses a study may draw per trial (`calibration.count`, `calibration.candidates`,
/// `validation.count`, an instruments study's `candidates` and `validation`): more is refused
/// when the scenario is read, not left to fail allocating them (tests/cli/memory.rs simulates
/// 2 000 000 rows).
pub const MAX_POSES: usize = 10_000_000;

/// Why a pose count `n` is refused: it is above [`MAX_POSES`].
pub(crate) fn pose_count_excess(n: usize) -> Option<String> {
    (n > MAX_POSES).then(|| format!("must be at most {MAX_POSES} poses, got {n}"))
}

/// Refuses a pose count `n` of `key` above [`MAX_POSES`].
pub fn check_pose_count(key: &str, n: usize) -> Result<()> {
    pose_count_excess(n).map_or(Ok(()), |msg| Err(Error::setting(key, msg)))
}

/// The built-in default study (`scenarios/default.toml`): what `calbench` runs with no
/// arguments.
pub const DEFAULT_SCENARIO: &str = include_str!("../../../scenarios/default.toml");

impl Scenario {
    /// Reads and checks a scenario file.
    pub fn load(path: &Path) -> Result<Scenario> {
        let text = read_text(path)?;
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
        let table: toml::Table = crate::error::toml_keys(shown, text)?;
        let source = Source {
            text: text.into(),
            edited: Vec::new(),
        };
        Scenario::from_table(table, path, Some(source))?.with_paper_points_checked()
    }

    /// Checks a scenario given as a table rather than as a file's text (the Python module's
    /// `run` of a dict): refusals name `shown` and the key, without a line; relative file
    /// paths are taken from the current folder.
    pub fn from_toml_table(table: toml::Table, shown: &Path) -> Result<Scenario> {
        Scenario::from_table(table, Some(shown), None)?.with_paper_points_checked()
    }

    /// Checks the parsed `table` of the file `path`; `source` gives the lines of refused keys
    /// (`line 14, calibration.count`).
    fn from_table(
        table: toml::Table,
        path: Option<&Path>,
        source: Option<Source>,
    ) -> Result<Scenario> {
        let shown = path
            .unwrap_or(Path::new("<built-in default scenario>"))
            .to_path_buf();
        let line = |key: &str| source.as_ref().and_then(|s| s.line(key));
        // An error whose line is that of `key` (the place itself, or the key of a setting).
        let at = |key: &str, place: &str, msg: String| {
            Error::file(&shown, at_line(line(key), place), msg)
        };
        let ferr = |place: &str, msg: String| at(place, place, msg);
        if table.contains_key("registration_study") {
            return Err(ferr(
                "registration_study",
                "this is a registration study (Ban fig. 3), which `calbench run` runs on its \
                 own; it is not a calibration scenario"
                    .into(),
            ));
        }
        for key in ["instruments_study", "measurement"] {
            if table.contains_key(key) {
                return Err(ferr(
                    key,
                    "this is an instruments study (docs/formats.md § 4.15), which `calbench \
                     run` runs on its own; it is not a calibration scenario"
                        .into(),
                ));
            }
        }
        let raw: RawScenario =
            toml::Value::Table(table.clone())
                .try_into()
                .map_err(|e: toml::de::Error| {
                    // The same refusal read from the text has a span: its line; one
                    // without (an array of the wrong length) is placed at its key's line.
                    let spanned = source
                        .as_ref()
                        .filter(|s| s.edited.is_empty())
                        .and_then(|s| {
                            let spanned = toml::from_str::<RawScenario>(&s.text).err()?;
                            crate::error::toml_error_line(&s.text, &spanned)
                        });
                    let (msg, place) = crate::error::scenario_value_error(&e);
                    Error::file(
                        &shown,
                        at_line(spanned.or_else(|| line(&place)), place),
                        msg,
                    )
                })?;
        let dir = path
            .and_then(Path::parent)
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let check = |r: Result<()>| {
            r.map_err(|e| match e {
                Error::Setting { key, msg } => Error::file(&shown, at_line(line(&key), key), msg),
                e => ferr("setting", e.to_string()),
            })
        };

        if let Err(msg) = crate::study::whole::folder_name(&raw.name) {
            return Err(ferr("name", msg.into()));
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
        check(raw.unmodelled.check())?;

        let c = raw.calibration;
        if c.count == 0 {
            return Err(ferr("calibration.count", "must be at least 1".into()));
        }
        check(check_pose_count("calibration.count", c.count))?;
        check(check_pose_count("calibration.candidates", c.candidates))?;
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
                            &key,
                            "strategy \"box\" needs calibration.region = { kind = \"box\", … }"
                                .into(),
                        ));
                    }
                    PoseStrategy::Box
                }
                StrategyName::Grid => PoseStrategy::Grid,
                StrategyName::File => match &c.poses_file {
                    Some(f) if !dir.join(f).is_file() => {
                        let msg = format!("{} is not a file", dir.join(f).display());
                        return Err(ferr("calibration.poses_file", msg));
                    }
                    Some(f) => PoseStrategy::File(dir.join(f)),
                    // Refused at the strategy, which the file writes, rather than at the
                    // key it lacks, which has no line.
                    None => {
                        return Err(ferr(
                            &key,
                            "strategy \"file\" needs a pose list: calibration.poses_file".into(),
                        ))
                    }
                },
                other => match other.selection() {
                    Some((o, false)) => PoseStrategy::Optimised(o),
                    Some((o, true)) => PoseStrategy::OptimisedFull(o),
                    None => unreachable!("box, grid and file are matched above"),
                },
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
        check(check_pose_count("validation.count", v.count))?;
        check(v.region.check("validation.region"))?;
        let load = |key: &str, w: Real| match crate::robot::compliance::not_a_mass(w) {
            None => Ok(()),
            Some(msg) => Err(ferr(key, msg)),
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
                let entry = format!("methods[{i}]");
                let place = if k.is_empty() {
                    entry.clone()
                } else {
                    format!("{entry}.{k}")
                };
                // A key the entry does not write (a missing `name`): the entry's line.
                let written = t.contains_key(k.split('.').next().unwrap_or_default());
                at(if written { &place } else { &entry }, &place, msg)
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
                // At the `label` the entry writes, or at the entry (a default label).
                let written = ["", ".label"][usize::from(t.contains_key("label"))];
                return Err(at(
                    &format!("methods[{i}]{written}"),
                    &format!("methods[{i}].label"),
                    format!(
                        "\"{}\" is used twice: give each method a distinct `label`",
                        m.label
                    ),
                ));
            }
            methods.push(m);
        }
        raw.report.check(&methods).map_err(|(k, m)| ferr(&k, m))?;

        let strategy_names: Vec<String> = strategies.iter().map(|s| s.name().to_string()).collect();
        let labels: Vec<String> = methods
            .iter()
            .map(|m: &MethodSpec| m.label.clone())
            .collect();
        let names = crate::study::claims::Names {
            methods: &labels,
            strategies: &strategy_names,
            pose: raw.tracker.measure.measure() == crate::measurement::Measure::Pose,
            axis: v.axis_errors,
            unmodelled: raw.unmodelled.is_active(),
            searches: methods.iter().any(|m| m.method.fitness_model().is_some()),
        };
        let claims = crate::study::claims::parse(&raw.claims, &names).map_err(|(k, m)| {
            let on = Some(k.as_str()).filter(|k| line(k).is_some());
            at(on.unwrap_or(crate::study::claims::claim_of(&k)), &k, m)
        })?;

        let sweep = match raw.sweep {
            None => None,
            Some(field) => Some(sweep::check_sweep(field).map_err(|(k, m)| ferr(&k, m))?),
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
            unmodelled: raw.unmodelled,
            registration: raw.registration.method,
            calibration: Calibration {
                count: c.count,
                strategies,
                region: c.region,
                candidates: c.candidates,
                objective,
                separate: c.separate,
                separate_threshold: c.separate_threshold,
                optimise: c.optimise,
                payloads_kg: c.payloads_kg,
            },
            validation: Validation {
                count: v.count,
                region: v.region,
                payload_kg: v.payload_kg,
                before_fitted: v.before_fitted,
                axis_errors: v.axis_errors,
            },
            identification: raw.identification,
            methods,
            sweep,
            report: raw.report,
            claims,
            table,
            source: source.clone(),
        };
        // Settings that need the robot: joint counts of lists, parameter names.
        let robot = scenario.robot().map_err(|e| match e {
            Error::Setting { key, msg } => ferr(&key, msg.to_string()),
            Error::File { .. } => e,
            other => ferr("robot.file", other.to_string()),
        })?;
        if let Some(msg) =
            crate::robot::loaded::unsimulated(&robot).or_else(|| unmeasurable(&robot))
        {
            return Err(ferr("robot.file", msg));
        }
        // The sag model whole, with the built-in robot's stiffness and masses where none are
        // given: a value missing is named at the `[compliance]` table's line.
        Compliance::new(&scenario.compliance, &robot, scenario.builtin()).map_err(|e| match e {
            Error::Setting { key, msg } => {
                let given = line(&key).or_else(|| line("compliance"));
                Error::file(&shown, at_line(given, &key), msg.to_string())
            }
            other => other,
        })?;
        // Regions no pose reaches, refused now rather than after a search in the run.
        let keyed = |r: Result<()>| {
            r.map_err(|e| match e {
                Error::Setting { key, msg } => ferr(&key, msg.to_string()),
                other => other,
            })
        };
        let cal = &scenario.calibration;
        let drawn = cal
            .strategies
            .iter()
            .filter_map(|s| match s {
                PoseStrategy::Random | PoseStrategy::Box => Some(cal.count),
                PoseStrategy::Optimised(_) | PoseStrategy::OptimisedFull(_) => Some(cal.candidates),
                PoseStrategy::Grid | PoseStrategy::File(_) => None,
            })
            .max();
        if let Some(n) = drawn {
            keyed(check_region(&robot, &cal.region, n, "calibration.region"))?;
        }
        let val = &scenario.validation;
        keyed(check_region(
            &robot,
            &val.region,
            val.count,
            "validation.region",
        ))?;
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
                Error::Setting { msg, .. } => ferr("identification.params", msg.to_string()),
                other => other,
            })?;
            if names.is_empty() {
                return Err(ferr(
                    "identification.params",
                    "give at least one parameter name".into(),
                ));
            }
        }
        if scenario.claims.iter().any(|c| c.parameters.is_some()) {
            let injected = scenario.error_params(&robot)?;
            crate::study::claims::check_parameters(&scenario.claims, &robot, &injected)
                .map_err(|(k, m)| ferr(&k, m))?;
        }
        keyed(scenario.check_readings(&robot))?;
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
            RobotRef::File(p) if crate::robot::urdf::is_urdf(p) => Err(Error::setting(
                "robot.file",
                format!(
                    "\"{}\" is a URDF, which a scenario does not take: give a robot file \
                         in TOML (docs/formats.md § 3.1)",
                    p.display()
                ),
            )),
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

    /// The scenario as a TOML table (as written, before checking): what a shard records so
    /// that shards of different scenarios are told apart.
    pub fn table(&self) -> &toml::Table {
        &self.table
    }
}

/// Why a study cannot measure `robot`, or `None`: its tool points may lie farther from the
/// base's origin than the range a measurement file is read in (docs/formats.md § 5.1, ±1 km),
/// which `simulate` refuses in the file it would write. A robot file whose lengths in mm are
/// declared `length_unit = "m"` is the usual cause.
fn unmeasurable(robot: &Robot) -> Option<String> {
    use crate::measurement::csv::MAX_POINT_MM;
    let reach = crate::robot::sampling::reach_bound_mm(robot) + robot.base().pos.norm();
    (reach > MAX_POINT_MM).then(|| {
        format!(
            "robot \"{}\" may reach {reach:.0} mm from the world's origin (its base's \
             offset, its joints' lengths and offsets, its travels and its tool's), beyond the \
             ±{MAX_POINT_MM} mm (1 km) a measurement is read in; are the robot's lengths in its \
             length_unit?",
            robot.name
        )
    })
}
