//! One identification pipeline: an [`IdentifyRequest`] ([`super::request`]) gives an
//! [`IdentifyOutcome`] (the compensated robot and everything `identified.json` records,
//! [`super::record`]) by [`IdentifyRequest::run`].
//!
//! For a tracker's file (docs/formats.md § 5.1): the held-out split, the parameter set less
//! the fixed ones (plus compliances), the model choice and cross-validation
//! ([`super::cv`]), the calibration ([`super::calibrate`]) with its convergence trace, the
//! refusal of undetermined data, the validation, how each prior moved its estimate (a second
//! calibration without the priors), the diagnostics, and the refusal of a result that makes
//! the robot worse ([`super::verdict`]). For a kind file (§ 5.3):
//! [`super::on_kind::identify_kind`], with the same refusals.

use super::cv::{self, Model};
use super::diagnostics::{diagnose, Subject};
use super::fit::fit_and_readmit;
use super::frames::{check_frames, Validation};
use super::kernel::{position_errors, KernelResidual};
use super::on_kind::KindOutcome;
use super::orientations::convention_hint;
use super::record::{IdentifiedRecord, PriorMove, Trace};
use super::request::{IdentifyData, IdentifyRequest};
use super::validation::{check_validation_rows, point_residuals, validate_file, FileValidation};
use super::verdict::{
    self, check_names, check_priors_identified, check_some_left, gross_likely, gross_reading,
    radians_hint, registration_warning, rms, worse_causes, worse_error, worse_warning,
    ValidationRows,
};
use super::{calibrate, plausibility, Calibrated, RefitWeights, Registration};
use crate::error::{Error, Opt, Result, Said};
use crate::identify::qiao::method::SearchBox;
use crate::identify::{MethodSpec, TraceRecorder};
use crate::measurement::{Measure, Measurements};
use crate::numeric::{Frame, Real};
use crate::robot::compliance::CompliancePick;
use crate::robot::identifiability::{analyse, Identifiability};
use crate::robot::{param_sets, Param, Robot};

/// An identification's result: on a tracker's file or on a kind file. Its
/// [`IdentifyOutcome::record`] is `identified.json` (and so is its serialisation).
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
    /// The calibration rows (without held-out ones).
    pub data: Measurements,
    /// The registration.
    pub registration: Registration,
    /// The identified parameters, in the order of the estimate.
    pub params: Vec<Param>,
    /// The calibration.
    pub calibrated: Calibrated,
    /// The validation (a separate file or the held-out rows).
    pub validation: Option<FileValidation>,
    /// Per calibration point, the residual before and after (mm)
    /// ([`point_residuals`]).
    pub residuals: (Vec<Real>, Vec<Real>),
    /// `identified.json`: the practice options' results, the diagnostics and why the result
    /// makes the robot worse (kept with `allow_worse`) among the rest.
    pub record: IdentifiedRecord,
    /// Which of all the nominal robot's parameters the calibration poses identify.
    pub identifiability: Identifiability,
    /// The kernel residual of a model with the term `gp` (`kernel.json`), fitted on the
    /// calibration rows' residuals after the parametric model; `robot.toml` cannot carry it.
    pub kernel: Option<KernelResidual>,
    /// For a search, the box it explored (`None` for the other methods).
    pub search_box: Option<SearchBox>,
    /// The warning of a gross reading the fit kept ([`verdict::gross_kept`]).
    pub gross: Option<String>,
}

impl IdentifyRequest {
    /// Runs the identification: refuses options that conflict, data that do not determine
    /// every parameter (unless `allow_rank_deficient`) and a result worse than the nominal
    /// robot (unless `allow_worse`), naming the file and the cause. The readings move into
    /// the pipeline (a tracker's rows are not copied).
    pub fn run(mut self) -> Result<IdentifyOutcome> {
        use Opt::{Compliance, Holdout, Models, Params, Validate};
        let conflicts = [
            (
                Validate,
                self.validate.is_some(),
                Holdout,
                self.holdout.is_some(),
            ),
            (
                Models,
                !self.models.is_empty(),
                Compliance,
                self.compliance.is_some(),
            ),
            (
                Models,
                !self.models.is_empty(),
                Params,
                !self.params.is_empty(),
            ),
        ];
        if let Some((a, _, b, _)) = conflicts.iter().find(|c| c.1 && c.3) {
            let why = Said::from("cannot be used with ").name(*a);
            return Err(Error::option(*b, why));
        }
        if self.cv_seed.is_some() && self.cv.is_none() && self.models.is_empty() {
            let why = Said::from("seeds the folds of ")
                .name(Opt::Cv)
                .text(" or ")
                .name(Models)
                .text(", and neither is given");
            return Err(Error::option(Opt::CvSeed, why));
        }
        // Two names of one model (`gravity+harmonics`, `harmonics+gravity`) would be
        // cross-validated twice and tie.
        let twice = (1..self.models.len()).find(|&i| self.models[..i].contains(&self.models[i]));
        if let Some(i) = twice {
            let why = format!("`{}` is listed twice", self.models[i].name());
            return Err(Error::option(Models, why));
        }
        let empty = IdentifyData::Tracker(Measurements::default());
        let outcome = match std::mem::replace(&mut self.data, empty) {
            IdentifyData::Tracker(d) => self
                .tracker(d)
                .map(|o| IdentifyOutcome::Tracker(Box::new(o))),
            IdentifyData::Kind(f) => {
                super::on_kind::kind_outcome(&self, &f).map(|o| IdentifyOutcome::Kind(Box::new(o)))
            }
        }?;
        // `robot.toml` reads back as the robot identified (docs/formats.md § 3.1): a value
        // beyond a robot file's range (a search's box of a billion mm, kept past every
        // refusal) would be written as a file no command reads.
        if let Err(issue) = outcome.compensated().check() {
            let msg = format!(
                "{} identified a robot that no robot file holds ({}: {}), so nothing was \
                 written",
                self.method.shown_name(),
                issue.place,
                issue.msg
            );
            return Err(Error::file(&self.source, "data", msg));
        }
        Ok(outcome)
    }

    /// The identification on a tracker's measurements `d`.
    fn tracker(&self, mut d: Measurements) -> Result<TrackerOutcome> {
        let nominal = &self.robot;
        let mut spec = self.method.clone();
        spec.priors.extend(self.priors.iter().copied());
        let registration = self.registration;
        if let Some(k) = self.k {
            if d.measure() == Measure::Position {
                return Err(Error::option(Opt::K, super::request::K_ON_POSITIONS));
            }
            crate::identify::qiao::check_k(k).map_err(|e| e.of_option(Opt::K))?;
            spec.k = k;
        }
        let repeated: Vec<(usize, usize)> = d
            .repeated_rows()
            .into_iter()
            .map(|(a, b)| (self.file_row(None, a), self.file_row(None, b)))
            .collect();
        if !repeated.is_empty() {
            let why = crate::measurement::repeated_rows_refusal(
                &repeated,
                crate::measurement::SAME_MEASUREMENT,
                crate::measurement::REPEATED_CALIBRATION,
            );
            return Err(Error::file(&self.source, "data", why));
        }
        let mut val = self.validate.clone();
        // Under a holdout, the data's rows of the calibration and of the validation.
        let mut held_out = None;
        if let Some(h) = self.holdout {
            let (cal, held) = h.split(d.len());
            if held.is_empty() {
                let why = format!(
                    "`{0}/{1}` holds out no row: of every {1} rows the last {0} are held out, \
                     and the data have {2} rows",
                    h.last,
                    h.every,
                    d.len()
                );
                return Err(Error::option(Opt::Holdout, why));
            }
            let v = cv::subset(&d, &held);
            let c = cv::subset(&d, &cal);
            // The rows held out are a validation file's rows, and the rows left a data
            // file's, each refused as a file of theirs would be (with words of their own:
            // they have no lines of a file).
            let sides = [
                (&v, "holds out", "a validation, as a validation file"),
                (&c, "leaves", "a calibration, as a data file"),
            ];
            for (rows, does, what) in sides {
                if crate::measurement::csv::distinct_poses(&rows.qs, &[], nominal.dof()).is_err() {
                    let why = format!(
                        "`{}/{}` {does} {} of the data's {} rows, of fewer than {MIN} distinct \
                         poses: {what}, needs at least {MIN} (rows of distinct joint values)",
                        h.last,
                        h.every,
                        rows.len(),
                        d.len(),
                        MIN = crate::measurement::csv::MIN_DISTINCT_POSES
                    );
                    return Err(Error::option(Opt::Holdout, why));
                }
            }
            val = Some(v);
            d = c;
            held_out = Some((cal, held));
        }
        // Rows held out of data without copies repeat none of the rest; a validation file's
        // may.
        if let (Some(v), None) = (&val, &held_out) {
            let file = self.validate_source.as_deref();
            let compliance = self.compliance.is_some();
            check_validation_rows((nominal, compliance), (&d, &self.source), (v, file))?;
        }
        // A held-out row is a row of the data file; a validation file's, of its own.
        let validation_row = |i| match &held_out {
            Some((_, held)) => self.point_named(Some(held.as_slice()), i),
            None => self.validation_point(i),
        };
        let validation = val.as_ref().map(|rows| Validation {
            rows,
            opt: if held_out.is_some() {
                Opt::Holdout
            } else {
                Opt::Validate
            },
            file: self
                .validate_source
                .as_deref()
                .filter(|_| held_out.is_none()),
            point: &validation_row,
        });
        check_frames(nominal, &d, validation, registration)?;
        let with_base = registration == Registration::Identify;
        let mut kinematic = if self.params.is_empty() {
            param_sets::identified_params_tool_first(nominal, d.measure(), with_base)
        } else {
            check_names(Opt::Params, nominal, &self.params)?;
            self.params.clone()
        };
        kinematic.retain(|p| !self.fix.contains(p));
        let mut params = kinematic.clone();
        if let Some(c) = &self.compliance {
            let compliances = c.params(nominal, "compliance");
            let compliances = compliances.map_err(|e| e.of_option(Opt::Compliance))?;
            if compliances.is_empty() && *c == CompliancePick::Gravity {
                // A study identifies none then (tests/model/compliance.rs); an identification
                // asked for them would write a kinematic model without a word.
                return Err(Error::option(
                    Opt::Compliance,
                    format!(
                        "\"gravity\" picks no joint of robot \"{}\": gravity loads none of its \
                         revolute joints (their axes stay vertical), so no compliance shows in \
                         static readings; identify without it",
                        nominal.name
                    ),
                ));
            }
            params.extend(compliances);
        }
        params.retain(|p| !self.fix.contains(p));
        check_names(Opt::Fix, nominal, &self.fix)?;
        check_some_left(&params, &self.fix)?;
        let setup = cv::CvSetup {
            method: &spec,
            registration,
            seed: self.seed,
            fold_seed: self.cv_seed.unwrap_or(0),
            fixed: &self.fix,
            done: self.cross_validated.as_deref().unwrap_or(&[]),
        };
        // With models the best model by CV is the one identified.
        let mut robot = nominal.clone();
        let mut choice = None;
        let mut model = Model {
            compliance: self.compliance.is_some(),
            ..Model::KINEMATIC
        };
        if !self.models.is_empty() {
            let folds = self.cv.unwrap_or(5);
            let (cvs, best) = cv::choose_model(nominal, &self.models, &d, folds, &setup)?;
            model = self.models[best];
            (robot, params) = model.robot_and_params(nominal, &d, registration, &self.fix)?;
            choice = Some((cvs, best));
        }
        let nominal = robot;
        let kernel_term = model.gp;
        // The parameters left out at the nominal robot, re-checked at the identified one
        // (not for a list of parameters given by name), in every fold of the
        // cross-validation as in the final fit.
        let candidates = if self.params.is_empty() {
            model.left_out(&nominal, registration, &self.fix, &params)?
        } else {
            Vec::new()
        };
        check_priors_identified(&self.priors, &params)?;
        if !self.allow_rank_deficient {
            let poses = (d.len(), d.measure().rows());
            let priors = !self.priors.is_empty();
            verdict::as_many_readings_as_parameters(&self.source, poses, params.len(), priors)?;
        }
        let cross = match (&choice, self.cv) {
            (Some((cvs, best)), _) => Some(cvs[*best].clone()),
            (None, Some(k)) => {
                let model = cv::CvModel {
                    robot: &nominal,
                    params: &params,
                    candidates: &candidates,
                    kernel: false,
                    name: model.name(),
                };
                Some(cv::cross_validate(&model, &d, k, &setup)?)
            }
            (None, None) => None,
        };
        // For real data `known` means the points are already in the base frame.
        let mut recorders = Vec::new();
        let mut fit = |params: &[Param], start: &[Real]| {
            let recorder = TraceRecorder::default();
            let mut traced = spec.clone();
            traced.trace = Some(recorder.clone());
            traced.start = start.to_vec();
            recorders.push(recorder);
            calibrate_on(&nominal, params, &d, registration, &traced, self.seed)
                .map_err(|e| in_data(&self.source, e))
        };
        // The point of row `i` of the rows identified on, by its line of the data file, as
        // refusals name it.
        let point = |i| self.point_named(held_out.as_ref().map(|(cal, _)| cal.as_slice()), i);
        let undetermined = |c: &Calibrated, params: &[Param]| {
            if verdict::undetermined(c) && !self.allow_rank_deficient {
                let (all, source) = ((&kinematic[..], params.len()), (self.source.as_path(), &d));
                // What the readings show against the nominal robot's points.
                let shown = || {
                    let model = plausibility::tool_points(&nominal, &d.qs);
                    plausibility::data_causes(&model, &d.points).1
                };
                return Err(verdict::undetermined_error(
                    &nominal,
                    all,
                    c,
                    source,
                    &spec,
                    (&point, &shown),
                ));
            }
            Ok(())
        };
        let on = (&nominal, &d, registration, spec.k);
        let kept = fit_and_readmit(on, params, &candidates, &mut fit, &undetermined)?;
        let recorder = recorders.swap_remove(kept.attempt);
        let (c, params, readmitted) = (kept.calibrated, kept.params, kept.readmitted);
        // The kernel residual's second stage, on the calibration rows' residuals.
        let kernel = kernel_term
            .then(|| KernelResidual::fit(&nominal, &c, &d))
            .transpose()?;
        let validation = val
            .as_ref()
            .map(|v| -> Result<FileValidation> {
                let mut f = validate_file(&nominal, &c, v)?;
                if let Some(k) = &kernel {
                    f.after_mm = super::ErrorStats::of(&position_errors(&c, Some(k), v)?);
                }
                Ok(f)
            })
            .transpose()?;
        // The per-point residuals (16 bytes a row) are dropped after the check of a worse
        // robot and computed again after the diagnostics, which need memory of their own.
        let (before, after) = point_residuals(&nominal, &c, &d)?;
        let trace = convergence_trace(&c, &recorder);
        let evaluations = match (&c.identified.trace, &trace) {
            (None, Some(t)) => t.trace.first().map(|&f| (f, c.identified.rms_residual)),
            _ => None,
        };
        let validated = validation
            .as_ref()
            .map(|v| (v.before_mm.rms, v.after_mm.rms));
        let worse = worse_causes(
            validated,
            (rms(&before), rms(&after)),
            c.identified.termination,
            evaluations,
        );
        let gross = gross_reading(&after)
            .map(|g| ("after", g))
            .or_else(|| gross_reading(&before).map(|g| ("before", g)))
            .map(|(at, (i, r))| {
                format!(
                    "{} has a residual {r:.0} times the median {at} calibration",
                    point(i)
                )
            });
        // Orientations read with another convention than they were written in: a likely
        // cause of either refusal (looked for only when one is due).
        let convention = || convention_hint(&nominal, &d);
        if !worse.is_empty() && !self.allow_worse {
            let likely = radians_hint(&nominal, &d.qs)
                .or_else(convention)
                .or_else(|| gross.clone().map(gross_likely));
            let rows = match held_out {
                Some(_) => ValidationRows::OfData,
                None => self.validation_rows(),
            };
            return Err(worse_error(
                &self.source,
                rows,
                &self.method,
                &worse,
                likely,
            ));
        }
        let implausible = plausibility::check(
            (&nominal, &c.robot, &params, &d.qs),
            Some((&plausibility::tool_points(&nominal, &d.qs), &d.points)),
            (rms(&after), d.sigma_mm.as_deref()),
            || {
                let gross = gross.map(plausibility::gross_cause);
                convention().into_iter().chain(gross).collect()
            },
            (
                &self.source,
                self.allow_implausible,
                self.method.is_external(),
            ),
        )?;
        let kept_gross = verdict::gross_kept((&before, &after), &c.identified, point);
        drop((before, after));
        let priors = prior_moves(&nominal, &params, &d, &spec, &c, (registration, self.seed))?;
        let (diagnostics, left_out) = diagnose(&Subject {
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
        let kept_gross = match (kept_gross, left_out) {
            (None, Some(l)) => verdict::gross_left_out(l, &c.identified, point),
            (kept, _) => kept,
        };
        let id = &c.identified;
        let mut record =
            IdentifiedRecord::of(&nominal.name, &self.source, spec.name(), &params, id);
        if let Some(v) = &validation {
            record = record.validated_file(v);
        }
        let covariance = c.identified.covariance();
        let (cv_models, cv_best) = choice
            .map(|(cvs, best)| (cvs[best].model.clone(), cvs))
            .map(|(best, cvs)| (Some(cvs), Some(best)))
            .unwrap_or_default();
        let record = IdentifiedRecord {
            allowed_implausible: implausible,
            allowed_worse: worse.iter().map(ToString::to_string).collect(),
            convergence_trace: trace,
            covariance: Some(
                covariance
                    .row_iter()
                    .map(|r| r.iter().copied().collect())
                    .collect(),
            ),
            cv: cross,
            cv_best,
            cv_models,
            diagnostics: Some(diagnostics),
            fixed: super::record::names(&self.fix),
            holdout: self.holdout.map(|h| format!("{}/{}", h.last, h.every)),
            kernel_residual: kernel.as_ref().map(|k| k.hyperparameters.clone()),
            priors,
            readmitted,
            registration: Some(registration),
            registration_frame: Some((&c.frame).into()),
            registration_last_step_mm: Some(c.rounds.last_step_mm),
            registration_rounds: Some(c.rounds.rounds),
            registration_termination: Some(c.rounds.termination),
            registration_weights: (c.rounds.weights == RefitWeights::Coordinate)
                .then_some(RefitWeights::Coordinate),
            ..record
        };
        let residuals = point_residuals(&nominal, &c, &d)?;
        let identifiability = analyse(&nominal, &nominal.params(), &d.qs, d.measure());
        Ok(TrackerOutcome {
            search_box: spec.method.search_box().cloned(),
            identifiability,
            nominal,
            data: d,
            registration,
            params,
            calibrated: c,
            validation,
            residuals,
            record,
            kernel,
            gross: kept_gross,
        })
    }
}

/// A failure the data read from `source` cause ([`Error::Singular`]: the points do not
/// determine the registration; [`Error::Diverged`]: the alternation diverged on them) as a
/// refusal of that file; any other error as it is.
fn in_data(source: &std::path::Path, e: Error) -> Error {
    match e {
        Error::Singular(m) | Error::Diverged(m) => Error::file(source, "data", m),
        e => e,
    }
}

impl TrackerOutcome {
    /// The compensated robot, named `<nominal>-calibrated`, as `robot.toml` holds it.
    pub fn compensated(&self) -> Robot {
        let mut r = self.calibrated.robot.clone();
        r.name = format!("{}-calibrated", self.nominal.name);
        r
    }

    /// The warnings printed when the result is written: a registration that did not settle
    /// ([`registration_warning`]) and the causes of a result kept worse than the nominal
    /// robot.
    pub fn warnings(&self) -> Vec<Said> {
        let settle = registration_warning(&self.calibrated, self.registration).map(Said::from);
        let implausible = plausibility::implausible_warning(&self.record.allowed_implausible);
        let worse = self.worse_warning();
        let edge = self.edge_warning().map(Said::from);
        let gross = self.gross.clone().map(Said::from);
        let others = worse
            .into_iter()
            .chain(implausible)
            .chain(edge)
            .chain(gross);
        settle.into_iter().chain(others).collect()
    }

    /// The warning of a search that ended with parameters on the edge of its box
    /// ([`SearchBox::edge_warning`]), if it did.
    pub fn edge_warning(&self) -> Option<String> {
        let x = self.calibrated.identified.x.as_slice();
        (self.search_box.as_ref()).and_then(|b| b.edge_warning(&self.params, x))
    }

    /// The warning of a result kept worse than the nominal robot, if it is.
    pub fn worse_warning(&self) -> Option<Said> {
        worse_warning(&self.record.allowed_worse)
    }
}

impl IdentifyOutcome {
    /// `identified.json`.
    pub fn record(&self) -> &IdentifiedRecord {
        match self {
            IdentifyOutcome::Tracker(o) => &o.record,
            IdentifyOutcome::Kind(o) => &o.record,
        }
    }

    /// The warnings `calbench identify` prints before its own of the files it writes: a
    /// registration that did not settle, a result kept worse than the nominal robot or
    /// physically implausible.
    pub fn warnings(&self) -> Vec<Said> {
        match self {
            IdentifyOutcome::Tracker(o) => o.warnings(),
            IdentifyOutcome::Kind(o) => o.warnings(),
        }
    }

    /// The compensated robot, named `<nominal>-calibrated`, as `robot.toml` holds it.
    pub fn compensated(&self) -> Robot {
        match self {
            IdentifyOutcome::Tracker(o) => o.compensated(),
            IdentifyOutcome::Kind(o) => o.compensated(),
        }
    }
}

/// `identified.json`.
impl serde::Serialize for IdentifyOutcome {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.record().serialize(s)
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
fn convergence_trace(c: &Calibrated, recorder: &TraceRecorder) -> Option<Trace> {
    if let Some(t) = &c.identified.trace {
        return Some(Trace {
            values: "best fitness per iteration".into(),
            trace: t.clone(),
        });
    }
    let t = recorder.lock().ok()?.clone();
    (!t.is_empty()).then_some(Trace {
        values: "RMS point residual (mm) per evaluation".into(),
        trace: t,
    })
}
