//! One identification pipeline: an [`IdentifyRequest`] (the robot, a tracker's measurements
//! or a measurement-kind file, the method and every option of `calbench identify`) gives an
//! [`IdentifyOutcome`] (the compensated robot and everything `identified.json` records,
//! [`super::record`]). The `identify` command and the Python module's `identify` are thin
//! callers: they read their inputs, build the request, call [`IdentifyRequest::run`] and write
//! or return the outcome.
//!
//! For a tracker's file (docs/formats.md § 5.1): the held-out split, the parameter set less
//! the fixed ones (plus compliances), the model choice and cross-validation
//! ([`super::cv`]), the calibration ([`super::calibrate`]) with its convergence trace, the
//! refusal of undetermined data, the validation, how each prior moved its estimate (a second
//! calibration without the priors), the diagnostics, and the refusal of a result that makes
//! the robot worse ([`super::verdict`]). For a kind file (§ 5.3):
//! [`super::on_kind::identify_kind`], with the same refusals.

use std::path::PathBuf;

use super::cv::{self, Holdout, Model};
use super::diagnostics::{diagnose, Subject};
use super::record::{
    tracker_base, IdentifiedJson, Practice, PriorMove, TrackerBase, ALLOWED_WORSE,
};
use super::validation::{point_residuals, validate_file, FileValidation};
use super::verdict::{self, gross_reading, rms, worse_causes, worse_error};
use super::{calibrate, plausibility, Calibrated, Registration};
use crate::error::{Error, Result};
use crate::identify::{MethodSpec, TraceRecorder};
use crate::measurement::kind_csv::KindFile;
use crate::measurement::{Measure, Measurements};
use crate::numeric::{Frame, Real};
use crate::robot::compliance::CompliancePick;
use crate::robot::{param_sets, Param, Robot};
use serde_json::{Map, Value};

pub use super::on_kind::KindOutcome;
use super::on_kind::{identify_kind, validate_positions, Chosen};
pub use super::verdict::{check_names, registration_warning, worse_warning};
use crate::measurement::kind::{Instrument, Kind};

/// The readings an identification runs on.
#[derive(Clone, Debug)]
pub enum IdentifyData {
    /// A tracker's measurements (docs/formats.md § 5.1).
    Tracker(Measurements),
    /// A measurement-kind file: distance, plane, sphere or targets (§ 5.3).
    Kind(KindFile),
}

/// How the caller spells its options in messages: the command line's `--fix`,
/// `--allow-rank-deficient`, or Python's `fix`, `allow_rank_deficient=True`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Spelling {
    /// `calbench identify`.
    #[default]
    Cli,
    /// The Python module's keyword arguments.
    Python,
}

impl Spelling {
    /// The option the command line calls `cli` (`--fix`), as this caller names it.
    pub fn option(self, cli: &str) -> String {
        match self {
            Spelling::Cli => cli.to_string(),
            Spelling::Python => cli.trim_start_matches("--").replace('-', "_"),
        }
    }

    /// `e` with its setting named as this caller names it (a refusal from a lower layer
    /// names the command line's option).
    pub fn respell(self, e: Error) -> Error {
        match e {
            Error::Setting { key, msg } if key.starts_with("--") => {
                Error::setting(self.option(&key), msg)
            }
            e => e,
        }
    }

    /// How this caller turns on the flag the command line calls `cli`.
    pub fn flag(self, cli: &str) -> String {
        match self {
            Spelling::Cli => cli.to_string(),
            Spelling::Python => format!("{}=True", self.option(cli)),
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
    /// Rows of the data held out for validation instead.
    pub holdout: Option<Holdout>,
    /// K-fold cross-validation (K), and the folds of `models`.
    pub cv: Option<usize>,
    /// Seed of the folds.
    pub cv_seed: u64,
    /// Candidate models compared by cross-validation; the best is identified.
    pub models: Vec<Model>,
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
    /// How the caller's options are named in messages.
    pub spelling: Spelling,
}

/// An identification's result: on a tracker's file or on a kind file. Serialised
/// (`serde_json`), it is `identified.json`.
pub enum IdentifyOutcome {
    /// On a tracker's measurements.
    Tracker(Box<TrackerOutcome>),
    /// On a measurement-kind file.
    Kind(Box<KindOutcome>),
}

/// An identification on a tracker's measurements.
pub struct TrackerOutcome {
    /// The nominal robot of the model identified (a `dh` robot read as `dh_beta` for a β
    /// model).
    pub nominal: Robot,
    /// Where the data were read from.
    pub source: PathBuf,
    /// The calibration rows (without held-out ones).
    pub data: Measurements,
    /// The method's name.
    pub method: &'static str,
    /// The registration.
    pub registration: Registration,
    /// The identified parameters, in the order of the estimate.
    pub params: Vec<Param>,
    /// The calibration.
    pub calibrated: Calibrated,
    /// The validation (a separate file or the held-out rows).
    pub validation: Option<FileValidation>,
    /// The practice options' results and the diagnostics.
    pub practice: Practice,
    /// Per calibration point, the residual before and after (mm)
    /// ([`point_residuals`]).
    pub residuals: (Vec<Real>, Vec<Real>),
    /// Why the result makes the robot worse (kept with `allow_worse`); empty: it does not.
    pub worse: Vec<String>,
    /// Why the result cannot be physically right (kept with `allow_implausible`); empty: it
    /// can.
    pub implausible: Vec<String>,
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
            holdout: None,
            cv: None,
            cv_seed: 0,
            models: Vec::new(),
            params: Vec::new(),
            fix: Vec::new(),
            compliance: None,
            seed: 0,
            allow_rank_deficient: false,
            allow_worse: false,
            allow_implausible: false,
            spelling: Spelling::Cli,
        }
    }

    /// Runs the identification: refuses options that conflict, data that do not determine
    /// every parameter (unless `allow_rank_deficient`) and a result worse than the nominal
    /// robot (unless `allow_worse`), naming the file and the cause.
    pub fn run(&self) -> Result<IdentifyOutcome> {
        let s = self.spelling;
        let conflicts = [
            (
                "--validate",
                self.validate.is_some(),
                "--holdout",
                self.holdout.is_some(),
            ),
            (
                "--models",
                !self.models.is_empty(),
                "--compliance",
                self.compliance.is_some(),
            ),
            (
                "--models",
                !self.models.is_empty(),
                "--params",
                !self.params.is_empty(),
            ),
        ];
        if let Some((a, _, b, _)) = conflicts.iter().find(|c| c.1 && c.3) {
            let why = format!("cannot be used with {}", s.option(a));
            return Err(Error::setting(s.option(b), why));
        }
        let outcome = match &self.data {
            IdentifyData::Tracker(d) => self
                .tracker(d.clone())
                .map(|o| IdentifyOutcome::Tracker(Box::new(o))),
            IdentifyData::Kind(f) => {
                kind_outcome(self, f).map(|o| IdentifyOutcome::Kind(Box::new(o)))
            }
        };
        outcome.map_err(|e| s.respell(e))
    }

    /// The identification on a tracker's measurements `d`.
    fn tracker(&self, mut d: Measurements) -> Result<TrackerOutcome> {
        let s = self.spelling;
        let nominal = &self.robot;
        let mut spec = self.method.clone();
        spec.priors.extend(self.priors.iter().copied());
        let registration = self.registration;
        if let Some(k) = self.k {
            let key = s.option("--k");
            if d.measure() == Measure::Position {
                let why =
                    "weighs orientation against position errors; the data hold positions only";
                return Err(Error::setting(key, why));
            }
            crate::error::finite_positive(&key, k)?;
            spec.k = k;
        }
        let mut val = self.validate.clone();
        if let Some(h) = self.holdout {
            let (cal, held) = h.split(d.len());
            val = Some(cv::subset(&d, &held));
            d = cv::subset(&d, &cal);
        }
        let with_base = registration == Registration::Identify;
        let mut kinematic = if self.params.is_empty() {
            param_sets::identified_params_tool_first(nominal, d.measure(), with_base)
        } else {
            check_names(&s.option("--params"), true, nominal, &self.params)?;
            self.params.clone()
        };
        kinematic.retain(|p| !self.fix.contains(p));
        let mut params = kinematic.clone();
        if let Some(c) = &self.compliance {
            params.extend(c.params(nominal, &s.option("--compliance"))?);
        }
        params.retain(|p| !self.fix.contains(p));
        check_names(&s.option("--fix"), false, nominal, &self.fix)?;
        let setup = cv::CvSetup {
            method: &spec,
            registration,
            seed: self.seed,
            fold_seed: self.cv_seed,
            fixed: &self.fix,
        };
        // With models the best model by CV is the one identified.
        let mut robot = nominal.clone();
        let mut choice = None;
        if !self.models.is_empty() {
            let folds = self.cv.unwrap_or(5);
            let (cvs, best) = cv::choose_model(nominal, &self.models, &d, folds, &setup)?;
            (robot, params) =
                self.models[best].robot_and_params(nominal, &d, registration, &self.fix)?;
            choice = Some((cvs, best));
        }
        let nominal = robot;
        let cross = match (&choice, self.cv) {
            (Some((cvs, best)), _) => Some(cvs[*best].clone()),
            (None, Some(k)) => {
                let model = Model {
                    compliance: self.compliance.is_some(),
                    ..Model::KINEMATIC
                };
                let model = (&nominal, &params[..], model.name());
                Some(cv::cross_validate(model, &d, k, &setup)?)
            }
            (None, None) => None,
        };
        // For real data `known` means the points are already in the base frame.
        let recorder = TraceRecorder::default();
        let mut traced = spec.clone();
        traced.trace = Some(recorder.clone());
        let c = calibrate_on(&nominal, &params, &d, registration, &traced, self.seed)?;
        if verdict::undetermined(&c) && !self.allow_rank_deficient {
            let allow = s.flag("--allow-rank-deficient");
            let (all, source) = ((&kinematic[..], params.len()), (self.source.as_path(), &d));
            return Err(verdict::undetermined_error(
                &nominal, all, &c, source, &spec, &allow,
            ));
        }
        let validation = val
            .as_ref()
            .map(|v| validate_file(&nominal, &c, v))
            .transpose()?;
        let residuals = point_residuals(&nominal, &c, &d)?;
        let trace = convergence_trace(&c, &recorder);
        let evaluations = match (&c.identified.trace, &trace) {
            (None, Some((_, t))) => t.first().map(|&first| (first, c.identified.rms_residual)),
            _ => None,
        };
        let worse = worse_causes(
            validation
                .as_ref()
                .map(|v| (v.before_mm.rms, v.after_mm.rms)),
            (rms(&residuals.0), rms(&residuals.1)),
            c.identified.termination,
            evaluations,
        );
        let gross = gross_reading(&residuals.1)
            .map(|g| ("after", g))
            .or_else(|| gross_reading(&residuals.0).map(|g| ("before", g)))
            .map(|(at, (i, r))| {
                format!("point {i} has a residual {r:.0} times the median {at} calibration")
            });
        if !worse.is_empty() && !self.allow_worse {
            return Err(worse_error(
                &self.source,
                &worse,
                gross,
                &s.flag("--allow-worse"),
            ));
        }
        let implausible = plausibility::check(
            (&nominal, &c.robot, &params),
            Some((&plausibility::tool_points(&nominal, &d.qs), &d.points)),
            (rms(&residuals.1), d.sigma_mm.as_deref()),
            gross,
            (
                &self.source,
                self.allow_implausible,
                &s.flag("--allow-implausible"),
            ),
        )?;
        let priors = prior_moves(&nominal, &params, &d, &spec, &c, (registration, self.seed))?;
        let diagnostics = diagnose(&Subject {
            nominal: &nominal,
            params: &params,
            data: &d,
            calibrated: &c,
            k: spec.k,
            priors: &spec.precisions(&params)?,
            validation: val
                .as_ref()
                .zip(validation.as_ref())
                .map(|(v, s)| (v, s.after_mm.rms)),
        })?;
        let practice = Practice {
            holdout: self.holdout,
            cv: cross,
            models: choice,
            fixed: self.fix.clone(),
            priors,
            trace,
            diagnostics: Some(diagnostics),
        };
        Ok(TrackerOutcome {
            nominal,
            source: self.source.clone(),
            data: d,
            method: spec.name(),
            registration,
            params,
            calibrated: c,
            validation,
            practice,
            residuals,
            worse,
            implausible,
        })
    }
}

impl TrackerOutcome {
    /// The base keys of `identified.json` ([`tracker_base`]).
    pub fn base_keys(&self) -> Map<String, Value> {
        tracker_base(&TrackerBase {
            nominal: &self.nominal,
            source: &self.source,
            method: self.method,
            registration: self.registration,
            params: &self.params,
            calibrated: &self.calibrated,
            validation: self.validation.as_ref(),
        })
    }

    /// The keys the options add to them: the practice options' ([`Practice::json`]) and,
    /// for a result kept worse than the nominal robot, [`ALLOWED_WORSE`].
    pub fn more_keys(&self) -> Map<String, Value> {
        let mut j = self.practice.json();
        if !self.worse.is_empty() {
            j.insert(ALLOWED_WORSE.into(), serde_json::json!(self.worse));
        }
        if !self.implausible.is_empty() {
            let key = plausibility::ALLOWED_IMPLAUSIBLE.into();
            j.insert(key, serde_json::json!(self.implausible));
        }
        j
    }

    /// The compensated robot, named `<nominal>-calibrated`, as `robot.toml` holds it.
    pub fn compensated(&self) -> Robot {
        let mut r = self.calibrated.robot.clone();
        r.name = format!("{}-calibrated", self.nominal.name);
        r
    }

    /// The warnings printed when the result is written: a registration that did not settle
    /// ([`registration_warning`]) and the causes of a result kept worse than the nominal
    /// robot.
    pub fn warnings(&self) -> Vec<String> {
        let settle = registration_warning(&self.calibrated, self.registration);
        let implausible = plausibility::implausible_warning(&self.implausible);
        let worse = self.worse_warning();
        settle.into_iter().chain(worse).chain(implausible).collect()
    }

    /// The warning of a result kept worse than the nominal robot, if it is.
    pub fn worse_warning(&self) -> Option<String> {
        worse_warning(&self.worse)
    }
}

impl serde::Serialize for TrackerOutcome {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let (base, more) = (self.base_keys(), self.more_keys());
        let diagnostics = self.practice.diagnostics.as_ref();
        IdentifiedJson {
            base: &base,
            more: &more,
            diagnostics,
        }
        .serialize(s)
    }
}

/// `identified.json`.
impl serde::Serialize for IdentifyOutcome {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            IdentifyOutcome::Tracker(o) => o.serialize(s),
            IdentifyOutcome::Kind(o) => o.record().serialize(s),
        }
    }
}

/// [`calibrate`] of real data (`known`: the points are in the base frame) with the method's
/// stream `identify` of `seed`.
fn calibrate_on(
    nominal: &Robot,
    params: &[Param],
    d: &Measurements,
    registration: Registration,
    spec: &MethodSpec,
    seed: u64,
) -> Result<Calibrated> {
    let mut rng = crate::numeric::rng::stream(seed, "identify");
    calibrate(
        nominal,
        params,
        d,
        registration,
        &Frame::identity(),
        spec,
        &mut rng,
    )
}

/// How each prior moved its parameter's estimate: the same identification without the
/// priors, against the MAP estimate of `c`.
fn prior_moves(
    nominal: &Robot,
    params: &[Param],
    d: &Measurements,
    spec: &MethodSpec,
    c: &Calibrated,
    (registration, seed): (Registration, u64),
) -> Result<Vec<PriorMove>> {
    if spec.priors.is_empty() {
        return Ok(Vec::new());
    }
    let mut free = spec.clone();
    free.priors.clear();
    let f = calibrate_on(nominal, params, d, registration, &free, seed)?;
    Ok(spec
        .priors
        .iter()
        .filter_map(|&(p, sigma)| {
            let k = params.iter().position(|q| *q == p)?;
            Some(PriorMove {
                parameter: p.to_string(),
                sigma,
                without_prior: f.identified.x[k],
                with_prior: c.identified.x[k],
            })
        })
        .collect())
}

/// The convergence trace: the searches' best fitness per iteration, or the RMS point
/// residual (mm) at each evaluation of the Jacobian methods' model (every round of an `svd`
/// or `wsvd` alternation; adaptive LM's rejected trial steps included).
fn convergence_trace(
    c: &Calibrated,
    recorder: &TraceRecorder,
) -> Option<(&'static str, Vec<Real>)> {
    if let Some(t) = &c.identified.trace {
        return Some(("best fitness per iteration", t.clone()));
    }
    let t = recorder.lock().ok()?.clone();
    (!t.is_empty()).then_some(("RMS point residual (mm) per evaluation", t))
}

/// The options of a request that a kind file does not take: each with whether it was given.
fn tracker_only(q: &IdentifyRequest) -> [(&'static str, bool); 6] {
    [
        ("--holdout", q.holdout.is_some()),
        ("--cv", q.cv.is_some()),
        ("--models", !q.models.is_empty()),
        ("--compliance", q.compliance.is_some()),
        (
            "--prior",
            !q.priors.is_empty() || !q.method.priors.is_empty(),
        ),
        ("--k", q.k.is_some()),
    ]
}

/// The option a kind file (of targets or not) refuses and why, if any: the tracker's
/// options, a registration the kind does not take, a method that is not a Jacobian one
/// (`solver`: it is).
fn refusal(q: &IdentifyRequest, targets: bool, solver: bool) -> Option<(&'static str, String)> {
    if let Some((option, _)) = tracker_only(q).into_iter().find(|o| o.1) {
        let why = "it applies to the tracker's measurement file (§ 5.1) only";
        return Some((option, why.to_string()));
    }
    let registration = q.registration;
    if registration != Registration::Identify && !(targets && registration == Registration::Known) {
        let why = if targets {
            "multi-target points are registered by SVD onto the nominal robot with the base \
             identified after (identify), or taken in the base frame (known)"
        } else {
            "the instrument is placed by its own unknowns, identified with the robot"
        };
        return Some((
            "--registration",
            format!("{} is not taken: {why}", registration.as_str()),
        ));
    }
    (!solver).then(|| {
        let why = format!(
            "{} is not one of the Jacobian methods (ls, ridge, igg3, lm) that identify them",
            q.method.name()
        );
        ("--method", why)
    })
}

/// The refusal, by file, of an option `option` a kind file does not take (`why`).
pub fn kind_refusal(q: &IdentifyRequest, kind: Kind, option: &str, why: &str) -> Error {
    let msg = format!(
        "{} holds {} readings (docs/formats.md § 5.3): {why}",
        q.source.display(),
        kind.as_str()
    );
    Error::setting(q.spelling.option(option), msg)
}

/// The identification of request `q` on the kind file `file` ([`identify_kind`]), with its
/// refusals: options the kind does not take, undetermined data, a worse robot.
fn kind_outcome(q: &IdentifyRequest, file: &KindFile) -> Result<KindOutcome> {
    let s = q.spelling;
    let nominal = &q.robot;
    let kind = file.data.instrument.kind();
    let targets = matches!(file.data.instrument, Instrument::Targets(_));
    if let Some((option, why)) = refusal(q, targets, q.method.method.solver().is_some()) {
        return Err(kind_refusal(q, kind, option, &why));
    }
    let solver = q
        .method
        .method
        .solver()
        .unwrap_or_else(|| unreachable!("refusal() refuses the methods that are not solvers"));
    check_names(&s.option("--params"), true, nominal, &q.params)?;
    check_names(&s.option("--fix"), false, nominal, &q.fix)?;
    let chosen = if q.params.is_empty() {
        Chosen::Identifiable
    } else {
        Chosen::Given(&q.params, q.allow_rank_deficient)
    };
    let register = q.registration == Registration::Identify;
    let fit = identify_kind(nominal, file, &q.source, (chosen, &q.fix, register), solver)?;
    let r = &fit.identified;
    let readings = fit.data.instrument.observations(file.qs.len());
    // The file row of reading `i` (a step of distances is read at its second row).
    let line = |i: usize| match &fit.data.instrument {
        Instrument::Targets(t) => {
            let (pose, target) = (i / t.len().max(1), i % t.len().max(1) + 1);
            file.lines.get(pose).map_or(format!("reading {i}"), |l| {
                format!("target {target} of the pose that starts on line {l}")
            })
        }
        _ => {
            let row = i + file.qs.len() - readings;
            file.lines
                .get(row)
                .map_or(format!("reading {i}"), |l| format!("line {l}"))
        }
    };
    let gross = || {
        let (before, after) = &fit.residuals;
        let (at, (i, ratio)) = gross_reading(after)
            .map(|g| ("after", g))
            .or_else(|| gross_reading(before).map(|g| ("before", g)))?;
        Some(format!(
            "the reading of {} has a residual {ratio:.0} times the median {at} calibration",
            line(i)
        ))
    };
    if super::verdict::undetermined_termination(r.termination) && !q.allow_rank_deficient {
        let total = r.x.len();
        let cause = match r.rank {
            Some(k) if k < total => {
                format!("do not determine every parameter (rank {k} of {total})")
            }
            Some(_) => "determine every parameter, yet the solve did not settle".to_string(),
            None => "do not give a finite solve".to_string(),
        };
        let hint = gross().map_or(String::new(), |g| {
            format!("; {g}: a gross reading is the likely cause")
        });
        return Err(Error::file(
            &q.source,
            "data",
            format!(
                "the {} readings {cause}{hint}; {} ended {}, so nothing was written. Measure \
                 poses that move every joint, leave parameters out with {}, or pass {}",
                kind.as_str(),
                q.method.name(),
                r.termination.as_str(),
                s.option("--fix"),
                s.flag("--allow-rank-deficient"),
            ),
        ));
    }
    let validation = q
        .validate
        .as_ref()
        .map(|v| validate_positions(nominal, &fit.robot, v))
        .transpose()?;
    let worse = worse_causes(
        validation.as_ref().map(|(b, a)| (b.rms, a.rms)),
        fit.rms,
        r.termination,
        None,
    );
    if !worse.is_empty() && !q.allow_worse {
        return Err(worse_error(
            &q.source,
            &worse,
            gross(),
            &s.flag("--allow-worse"),
        ));
    }
    let points = plausibility::target_points(nominal, &file.qs, &file.data);
    let implausible = plausibility::check(
        (nominal, &fit.robot, &fit.params),
        points.as_ref().map(|(m, s)| (&m[..], &s[..])),
        (fit.rms.1, file.sigma_mm.as_deref()),
        gross(),
        (
            &q.source,
            q.allow_implausible,
            &s.flag("--allow-implausible"),
        ),
    )?;
    Ok(KindOutcome {
        nominal: nominal.clone(),
        source: q.source.clone(),
        kind,
        readings,
        method: q.method.name(),
        registration: q.registration,
        fixed: q.fix.clone(),
        identifiable: matches!(chosen, Chosen::Identifiable),
        fit,
        validation,
        worse,
        implausible,
    })
}
