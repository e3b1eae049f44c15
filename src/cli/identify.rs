//! `calbench identify --robot R --data CSV --method M [--registration REG] [--validate CSV |
//! --holdout LAST/EVERY] [--k K] [--set KEY=VALUE …] [--allow-rank-deficient]
//! [--export urdf,toml,ur-yaml,dh-csv] [--compliance LIST|gravity] [--params NAMES] [--fix NAMES]
//! [--prior NAME=σ|FILE …] [--cv K [--cv-seed S]] [--models A,B,…] [--seed S] --out DIR`:
//! identification on a measurement file, real or simulated.

use std::path::{Path, PathBuf};

use anyhow::Result;

use calbench::calibrate::diagnostics::{diagnose, Subject};
use calbench::calibrate::{calibrate, Calibrated, ErrorStats, Registration, RoundsEnd};
use calbench::calibrate::{cv, on_data};
use calbench::error::Error;
use calbench::identify::{method_by_name, MethodEntry, MethodSpec, METHODS};
use calbench::measurement::csv::read_measurements;
use calbench::measurement::{Measure, Measurements};
use calbench::numeric::{Frame, Real};
use calbench::report::exports;
use calbench::report::identified::{registration_warning, validate_file, IdentifyRecord};
use calbench::report::practice::{Practice, PriorMove};
use calbench::report::write_identified_with;
use calbench::robot::compliance::CompliancePick;
use calbench::robot::{param_sets, Param, Robot};

use super::check_out_folder;

/// The files always written (`robot.urdf` and the plots depend on the options).
const OUTPUTS: [&str; 4] = [
    "identified.json",
    "residuals.csv",
    "robot.toml",
    "report.md",
];

/// Arguments of `calbench identify`.
#[derive(clap::Args)]
pub struct IdentifyArgs {
    /// Built-in robot name or robot file.
    #[arg(long)]
    pub robot: String,
    /// The chain of a URDF tree.
    #[command(flatten)]
    pub chain: super::ChainArgs,
    /// The measurement CSV (`q1..qn,x,y,z[,qw,qx,qy,qz]`), or a distance, plane or sphere
    /// file (`q1..qn` and `length_mm`, `step_mm`, `plane` or `sphere`).
    #[arg(long)]
    pub data: PathBuf,
    /// The identification method, with its default options.
    #[arg(long, value_parser = super::entry_of(METHODS, |m| m.name, |m| m.summary))]
    pub method: &'static MethodEntry,
    /// How the measured points are brought into the base frame (known: the points are in the
    /// base frame).
    #[arg(long, default_value = "identify", value_parser = super::named::<Registration>())]
    pub registration: Registration,
    /// A validation measurement CSV.
    #[arg(long, conflicts_with = "holdout")]
    pub validate: Option<PathBuf>,
    /// Hold rows of --data out for validation instead of a --validate file: `LAST/EVERY`,
    /// the last LAST of every EVERY consecutive rows (`3/10`: rows whose 0-based index % 10
    /// ≥ 7).
    #[arg(long, value_name = "LAST/EVERY")]
    pub holdout: Option<calbench::calibrate::cv::Holdout>,
    /// K-fold cross-validation on the calibration rows (seeded folds, the same for every
    /// model): per fold, the position RMS of the held-out points; in identified.json `cv`.
    #[arg(long, value_name = "K")]
    pub cv: Option<usize>,
    /// Seed of the cross-validation folds.
    #[arg(long, default_value_t = 0)]
    pub cv_seed: u64,
    /// Candidate models compared by their K-fold CV RMS (K from --cv, default 5): terms
    /// `kinematic`, `beta` (Hayati's β where identifiable), `compliance` (the gravity joints;
    /// needs link masses), joined by `+`; the best is identified.
    #[arg(long, value_delimiter = ',', conflicts_with = "compliance")]
    pub models: Vec<calbench::calibrate::cv::Model>,
    /// The identified parameters (comma-separated names, e.g. a paper's model); default: the
    /// identifiable set, tool parameters offered first, with the base under the `identify`
    /// registration.
    #[arg(long, value_delimiter = ',', value_parser = param_name, conflicts_with = "models")]
    pub params: Vec<Param>,
    /// Parameters held at their nominal values (comma-separated names, e.g. `a2,theta3`).
    #[arg(long, value_delimiter = ',', value_parser = param_name)]
    pub fix: Vec<Param>,
    /// A prior on a parameter's error: `NAME=σ` (mm, rad; rad/(N·m) for a compliance), or a
    /// TOML file of `NAME = σ` lines (repeatable): a MAP estimate, Tikhonov towards the
    /// nominal value, in the Jacobian methods.
    #[arg(long, value_name = "NAME=σ|FILE", value_parser = prior_arg)]
    pub prior: Vec<Vec<(Param, Real)>>,
    /// Full-pose data only: weight of orientation against position errors, mm per rad
    /// (default 100; about σ_position / σ_orientation of the instrument).
    #[arg(long)]
    pub k: Option<Real>,
    /// A method option, `KEY=VALUE` in TOML (repeatable): any key of the method's
    /// `[[methods]]` entry, e.g. `--set bound_mm=5 --set iterations=4000`.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = method_option)]
    pub options: Vec<(String, toml::Value)>,
    /// Write the result even when the data do not determine every parameter (termination
    /// `rank-deficient`); without it such a result is refused.
    #[arg(long)]
    pub allow_rank_deficient: bool,
    /// What is written besides robot.toml, comma-separated (default: `urdf` for a URDF
    /// robot, else `toml`): `ur-yaml` writes UR's kinematics_params_file (ur-kinematics.yaml),
    /// `dh-csv` the parameter table with nominal, identified, Δ and σ (dh-table.csv).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub export: Vec<Export>,
    /// Joint compliances identified with the kinematic errors (elasto-geometric model):
    /// names such as `c2,c3`, or `gravity` for every joint gravity loads. The gravity
    /// torques use the robot's link masses and each row's `payload_kg`.
    #[arg(long, value_parser = compliance_pick)]
    pub compliance: Option<CompliancePick>,
    /// Seed of the random searches (bas, pso, bas-pso): another seed gives another
    /// identification of the same data (Qiao 2021 fig. 7); the others ignore it.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// `--export`: the compensated robot's format besides `robot.toml`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Export {
    /// Also robot.urdf: for a URDF robot its source with the joint origins updated, for a
    /// robot file a URDF of the compensated robot.
    Urdf,
    /// robot.toml only.
    Toml,
    /// Also ur-kinematics.yaml: UR's `kinematics_params_file`.
    UrYaml,
    /// Also dh-table.csv: nominal, identified, Δ and σ per parameter.
    DhCsv,
}

/// `--fix`: one parameter name.
fn param_name(text: &str) -> std::result::Result<Param, String> {
    Param::parse(text.trim())
        .ok_or_else(|| format!("`{text}` is not a parameter name (a2, theta3, base.x, …)"))
}

/// `--prior`: `NAME=σ`, or a TOML file of `NAME = σ` lines.
fn prior_arg(text: &str) -> std::result::Result<Vec<(Param, Real)>, String> {
    use calbench::identify::registry::parse_prior;
    if let Some((name, sigma)) = text.split_once('=') {
        return parse_prior(name, sigma.trim().parse().ok()).map(|p| vec![p]);
    }
    let body = std::fs::read_to_string(text).map_err(|e| format!("{text}: {e}"))?;
    let t: toml::Table = toml::from_str(&body).map_err(|e| format!("{text}: {e}"))?;
    t.iter()
        .map(|(name, v)| {
            let sigma = v.as_float().or_else(|| v.as_integer().map(|i| i as Real));
            parse_prior(name, sigma).map_err(|m| format!("{text}: key `{name}`: {m}"))
        })
        .collect()
}

/// One `--set KEY=VALUE`: the key, and the value read as TOML.
fn method_option(text: &str) -> std::result::Result<(String, toml::Value), String> {
    let (key, value) = text
        .split_once('=')
        .ok_or_else(|| "not KEY=VALUE".to_string())?;
    let v: toml::Table = toml::from_str(&format!("v = {value}"))
        .map_err(|_| format!("\"{value}\" is not a TOML value"))?;
    Ok((key.trim().to_string(), v["v"].clone()))
}

/// `--compliance`: `gravity`, or compliance names separated by commas.
fn compliance_pick(text: &str) -> std::result::Result<CompliancePick, std::convert::Infallible> {
    Ok(CompliancePick::from_arg(text))
}

/// Identifies the errors, writes the output folder and prints the validation table and a
/// summary line; data that do not determine every parameter are refused unless
/// `--allow-rank-deficient`. For a tracker's file: a measurement-kind file (docs/formats.md
/// § 5.3) goes to `identify_kind::run` (the choice is `main`'s).
pub fn run(args: &IdentifyArgs) -> Result<()> {
    let out = &args.out;
    check_out_folder(out, &OUTPUTS)?;
    let nominal = args.chain.load(&args.robot)?;
    let mut spec = method_with_options(args.method.name, &args.options)?;
    spec.priors.extend(args.prior.iter().flatten().copied());
    let registration = args.registration;
    let mut d = read_measurements(&args.data, &nominal)?;
    let measure = d.measure();
    if let Some(k) = args.k {
        if measure == Measure::Position {
            return Err(Error::setting(
                "--k",
                "weighs orientation against position errors; the data hold positions only",
            )
            .into());
        }
        calbench::error::finite_positive("--k", k)?;
        spec.k = k;
    }
    let mut val = args
        .validate
        .as_deref()
        .map(|p| read_measurements(p, &nominal))
        .transpose()?;
    if let Some(h) = args.holdout {
        let (cal, held) = h.split(d.len());
        val = Some(cv::subset(&d, &held));
        d = cv::subset(&d, &cal);
    }
    let with_base = registration == Registration::Identify;
    let mut kinematic = if args.params.is_empty() {
        param_sets::identified_params_tool_first(&nominal, measure, with_base)
    } else {
        check_names("--params", &nominal, &args.params)?;
        args.params.clone()
    };
    kinematic.retain(|p| !args.fix.contains(p));
    let mut params = kinematic.clone();
    if let Some(c) = &args.compliance {
        params.extend(c.params(&nominal, "--compliance")?);
    }
    params.retain(|p| !args.fix.contains(p));
    check_names("--fix", &nominal, &args.fix)?;
    let setup = cv::CvSetup {
        method: &spec,
        registration,
        seed: args.seed,
        fold_seed: args.cv_seed,
        fixed: &args.fix,
    };
    let folds = args.cv.unwrap_or(5);
    // With --models the best model by CV is the one identified.
    let mut robot = nominal.clone();
    let mut choice = None;
    if !args.models.is_empty() {
        let (cvs, best) = cv::choose_model(&nominal, &args.models, &d, folds, &setup)?;
        (robot, params) =
            args.models[best].robot_and_params(&nominal, &d, registration, &args.fix)?;
        choice = Some((cvs, best));
    }
    let nominal = robot;
    let cross = match (&choice, args.cv) {
        (Some((cvs, best)), _) => Some(cvs[*best].clone()),
        (None, Some(k)) => {
            let model = cv::Model {
                compliance: args.compliance.is_some(),
                ..cv::Model::KINEMATIC
            };
            Some(cv::cross_validate(
                (&nominal, &params, model.name()),
                &d,
                k,
                &setup,
            )?)
        }
        (None, None) => None,
    };
    // For real data "known" means the points are already in the base frame.
    let recorder = calbench::identify::TraceRecorder::default();
    let mut traced = spec.clone();
    traced.trace = Some(recorder.clone());
    let c = calibrate(
        &nominal,
        &params,
        &d,
        registration,
        &Frame::identity(),
        &traced,
        &mut calbench::numeric::rng::stream(args.seed, "identify"),
    )?;
    if on_data::undetermined(&c) && !args.allow_rank_deficient {
        let allow = "--allow-rank-deficient";
        let (all, source) = ((&kinematic[..], params.len()), (args.data.as_path(), &d));
        return Err(on_data::undetermined_error(&nominal, all, &c, source, &spec, allow).into());
    }
    if let Some(w) = registration_warning(&c, registration) {
        eprintln!("warning: {w}");
    }
    let validation = val
        .as_ref()
        .map(|v| validate_file(&nominal, &c, v))
        .transpose()?;
    let priors = prior_moves(&nominal, &params, &d, &spec, &c, (registration, args.seed))?;
    let mut extra = Vec::new();
    if !args.export.contains(&Export::Toml) {
        if args.export.contains(&Export::UrYaml) {
            extra.push(("ur-kinematics.yaml", exports::ur_yaml(&c.robot)?));
        }
        if args.export.contains(&Export::DhCsv) {
            let cov = c.identified.covariance();
            let sigma: Vec<Real> = (0..params.len())
                .map(|i| cov[(i, i)].max(0.0).sqrt())
                .collect();
            extra.push((
                "dh-table.csv",
                exports::dh_csv(&nominal, &c.robot, &params, &sigma),
            ));
        }
    }
    let practice = Practice {
        holdout: args.holdout,
        cv: cross.clone(),
        models: choice.clone(),
        fixed: args.fix.clone(),
        priors,
        trace: convergence_trace(&c, &recorder),
        diagnostics: Some(diagnose(&Subject {
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
        })?),
    };
    let record = IdentifyRecord {
        nominal: &nominal,
        data_path: &args.data,
        data: &d,
        method: spec.name(),
        registration,
        params: &params,
        calibrated: &c,
        validation: validation.as_ref(),
        urdf: compensated_urdf(&args.robot, &args.chain.chain(), &args.export, &c.robot)?,
        residuals: Default::default(),
    };
    write_identified_with(out, &record, &practice.additions(), &extra)?;
    if let Some((cvs, best)) = &choice {
        out!("model             CV RMS (mm)  folds mean ± sd   parameters");
        for (i, m) in cvs.iter().enumerate() {
            out!(
                "  {:<16} {:>10.4} {:>8.4} ± {:<8.4} {:>4}{}",
                m.model,
                m.rms,
                m.mean,
                m.sd,
                m.parameters,
                if i == *best { "  (best)" } else { "" }
            );
        }
    } else if let Some(x) = &cross {
        out!(
            "{}-fold cross-validation: RMS {:.4} mm (folds {:.4} ± {:.4} mm)",
            x.k,
            x.rms,
            x.mean,
            x.sd
        );
    }
    if let Some(v) = &validation {
        print_validation(&v.before_mm, &v.after_mm);
    }
    let r = &c.identified;
    let rounds = match c.rounds.termination {
        RoundsEnd::Single => String::new(),
        end => format!(
            " ({} rounds of {} registration and identification, {})",
            c.rounds.rounds,
            registration.as_str(),
            end.as_str()
        ),
    };
    out!(
        "{} on {} points: {} after {} iterations{rounds}; written to {}",
        spec.name(),
        d.len(),
        r.termination.as_str(),
        r.iterations,
        out.display()
    );
    Ok(())
}

/// Prints the validation table: the position errors before and after (mm).
pub(super) fn print_validation(before: &ErrorStats, after: &ErrorStats) {
    out!("validation error (mm)   mean      rms       max       std");
    for (label, s) in [("before", before), ("after", after)] {
        out!(
            "  {label:<8} {:>10.4} {:>9.4} {:>9.4} {:>9.4}",
            s.mean,
            s.rms,
            s.max,
            s.std
        );
    }
}

/// The method `name` with the `--set KEY=VALUE` options, read like a scenario's
/// `[[methods]]` entry.
pub(super) fn method_with_options(
    name: &str,
    options: &[(String, toml::Value)],
) -> calbench::Result<MethodSpec> {
    if options.is_empty() {
        return method_by_name(name);
    }
    let mut t = toml::Table::new();
    t.insert("name".into(), toml::Value::String(name.into()));
    for (key, value) in options {
        t.insert(key.clone(), value.clone());
    }
    MethodSpec::from_table(&t).map_err(|(k, msg)| Error::setting(format!("--set {k}"), msg))
}

/// The compensated robot as a URDF: for a URDF robot (its source with the joint origins
/// moved) unless `--export toml`, for a robot file with `--export urdf`.
fn compensated_urdf(
    robot: &str,
    chain: &calbench::robot::urdf::UrdfChain,
    export: &[Export],
    compensated: &Robot,
) -> calbench::Result<Option<String>> {
    if export.contains(&Export::Toml) {
        return Ok(None);
    }
    if !calbench::robot::urdf::is_urdf(robot) {
        return if export.contains(&Export::Urdf) {
            calbench::robot::urdf::robot_to_urdf(compensated).map(Some)
        } else {
            Ok(None)
        };
    }
    let source = calbench::robot::urdf::UrdfRobot::load_chain(Path::new(robot), chain)?;
    source.write(compensated).map(Some)
}

/// Refuses a name of `--fix` or `--params` (`option`) the robot's model does not have, a
/// compliance in `--params` (`--compliance` adds those) and a name given twice.
pub(super) fn check_names(option: &str, nominal: &Robot, names: &[Param]) -> calbench::Result<()> {
    let known = nominal.params();
    let bad = |p: &Param| match (known.contains(p), p.is_compliance()) {
        (_, true) if option == "--params" => {
            Some("is a compliance: --compliance adds those".into())
        }
        (false, false) => Some(format!("is not a parameter of robot `{}`", nominal.name)),
        _ => None,
    };
    for (i, p) in names.iter().enumerate() {
        let why = bad(p).or(names[..i].contains(p).then(|| "is given twice".into()));
        if let Some(why) = why {
            return Err(Error::setting(option, format!("`{p}` {why}")));
        }
    }
    Ok(())
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
) -> calbench::Result<Vec<PriorMove>> {
    if spec.priors.is_empty() {
        return Ok(Vec::new());
    }
    let mut free = spec.clone();
    free.priors.clear();
    let f = calibrate(
        nominal,
        params,
        d,
        registration,
        &Frame::identity(),
        &free,
        &mut calbench::numeric::rng::stream(seed, "identify"),
    )?;
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
    recorder: &calbench::identify::TraceRecorder,
) -> Option<(&'static str, Vec<Real>)> {
    if let Some(t) = &c.identified.trace {
        return Some(("best fitness per iteration", t.clone()));
    }
    let t = recorder.lock().ok()?.clone();
    (!t.is_empty()).then_some(("RMS point residual (mm) per evaluation", t))
}
