//! `calbench identify --robot R --data CSV --method M [--registration REG] [--validate CSV |
//! --holdout LAST/EVERY] [--k K] [--set KEY=VALUE …] [--allow-rank-deficient] [--allow-worse]
//! [--export urdf,toml,ur-yaml,dh-csv] [--compliance LIST|gravity] [--params NAMES] [--fix NAMES]
//! [--prior NAME=σ|FILE …] [--cv K [--cv-seed S]] [--models A,B,…] [--seed S] --out DIR`:
//! identification on a measurement file, real or simulated.

use std::path::{Path, PathBuf};

use anyhow::Result;

use calbench::calibrate::pipeline::{IdentifyOutcome, TrackerOutcome};
use calbench::calibrate::request::{IdentifyData, IdentifyRequest};
use calbench::calibrate::{RefitWeights, Registration, RoundsEnd};
use calbench::error::{Error, Opt};
use calbench::identify::{method_by_name, MethodEntry, MethodSpec, METHODS};
use calbench::measurement::csv::read_measurements_at_lines;
use calbench::measurement::kind_csv::read_kind_file;
use calbench::numeric::Real;
use calbench::report::exports;
use calbench::report::identified::IdentifyRecord;
use calbench::report::practice::additions;
use calbench::report::write_identified_with;
use calbench::robot::compliance::CompliancePick;
use calbench::robot::{Param, Robot};

use calbench::calibrate::kernel::KERNEL_FILE;

/// The files always written, and `kernel.json` (`robot.urdf` and the plots depend on the
/// options; `kernel.json` on the model chosen).
const OUTPUTS: [&str; 5] = [
    "identified.json",
    "residuals.csv",
    "robot.toml",
    "report.md",
    KERNEL_FILE,
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
    /// Seed of the cross-validation folds (default 0; with --cv or --models only).
    #[arg(long)]
    pub cv_seed: Option<u64>,
    /// Candidate models compared by their K-fold CV RMS (K from --cv, default 5): terms
    /// `kinematic`, `beta` (Hayati's β where identifiable), `compliance` (the gravity joints;
    /// needs link masses), `gravity` (the mass-free gravity basis: unit weights at the elbow,
    /// the wrist centre and the tool point), `harmonics`, `harmonics2` (joint-angle harmonics
    /// of the revolute joints), `h{n}q{j}` (order n of joint j, `h12q1`), joined by `+`; the
    /// best is identified.
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
    pub prior: Vec<PriorArg>,
    /// Full-pose data only: weight of orientation against position errors, mm per rad
    /// (default 100; about σ_position / σ_orientation of the instrument).
    #[arg(long, allow_negative_numbers = true, value_parser = super::number)]
    pub k: Option<Real>,
    /// A method option, `KEY=VALUE` in TOML (repeatable): any key of the method's
    /// `[[methods]]` entry, e.g. `--set bound_mm=5 --set iterations=4000`.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = method_option)]
    pub options: Vec<(String, toml::Value)>,
    /// Write the result even when the data do not determine every parameter (termination
    /// `rank-deficient`); without it such a result is refused.
    #[arg(long)]
    pub allow_rank_deficient: bool,
    /// Write the result even when it makes the robot worse than the nominal one (validation
    /// or residual RMS after above before, or a solve stopped at its iteration limit with a
    /// growing cost), with a warning in the terminal, identified.json (`allowed_worse`) and
    /// the report; without it such a result is refused.
    #[arg(long)]
    pub allow_worse: bool,
    /// Write the result even when it cannot be physically right (a length moved by a large
    /// share of the robot's reach, an angle by more than 5°, points scaled against the
    /// nominal robot's, a residual far below the stated noise; docs/formats.md "Physical
    /// plausibility"), with a warning in the terminal, identified.json
    /// (`allowed_implausible`) and the reports; without it such a result is refused.
    #[arg(long)]
    pub allow_implausible: bool,
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
    #[command(flatten)]
    pub record: super::record::RecordFlags,
}

/// `--export`: the compensated robot's format besides `robot.toml`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Export {
    /// Also robot.urdf: for a URDF robot its source with the joint origins updated, for a
    /// robot file a URDF of the compensated robot.
    Urdf,
    /// robot.toml (always written); for a URDF robot, without `urdf` as well, no robot.urdf.
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

/// One `--prior`: a prior given on the command line, or a file of them, read by
/// [`calbench::identify::registry::prior_file`] once the command runs (so that its refusals
/// name the file and line).
#[derive(Clone, Debug)]
pub enum PriorArg {
    /// `NAME=σ`.
    One(Param, Real),
    /// A TOML file of `NAME = σ` lines.
    File(PathBuf),
}

/// `--prior`: `NAME=σ`, or the path of a file of priors.
fn prior_arg(text: &str) -> std::result::Result<PriorArg, String> {
    use calbench::identify::registry::parse_prior;
    match text.split_once('=') {
        Some((name, sigma)) => {
            parse_prior(name, sigma.trim().parse().ok()).map(|(p, sigma)| PriorArg::One(p, sigma))
        }
        None => Ok(PriorArg::File(text.into())),
    }
}

/// The priors of `--prior` arguments in their order, each file's by name: a file that
/// is not TOML, holds no prior, or names a parameter or σ that is not one is refused naming
/// the file, the line and the key.
fn priors(args: &[PriorArg], robot: &Robot) -> calbench::Result<Vec<(Param, Real)>> {
    let mut all = Vec::new();
    for a in args {
        match a {
            PriorArg::One(p, sigma) => all.push((*p, *sigma)),
            PriorArg::File(path) => {
                all.extend(calbench::identify::registry::prior_file(path, robot)?);
            }
        }
    }
    Ok(all)
}

/// One `--set KEY=VALUE`: the key, and the value read as TOML.
pub(super) fn method_option(text: &str) -> std::result::Result<(String, toml::Value), String> {
    let (key, value) = text
        .split_once('=')
        .ok_or_else(|| "not KEY=VALUE".to_string())?;
    let text = format!("v = {value}");
    let v: toml::Table =
        toml::from_str(&text).map_err(|_| format!("\"{value}\" is not a TOML value"))?;
    if let Some((_, _, msg)) = calbench::error::toml_underflow(&text) {
        return Err(msg);
    }
    Ok((key.trim().to_string(), v["v"].clone()))
}

/// `--compliance`: `gravity`, or compliance names separated by commas.
fn compliance_pick(text: &str) -> std::result::Result<CompliancePick, std::convert::Infallible> {
    Ok(CompliancePick::from_arg(text))
}

/// Identifies the errors ([`IdentifyRequest`]), writes the output folder and prints the
/// validation table and a summary line. A measurement-kind file (docs/formats.md § 5.3) is
/// written by [`super::identify_kind::write`].
pub fn run(args: &IdentifyArgs) -> Result<()> {
    let db = args.record.open()?;
    identify(args)?;
    let record = || Ok(calbench::results::Record::of_folder(&args.out, None, None)?);
    args.record.finish(db, record)
}

/// [`run`] without the recording.
fn identify(args: &IdentifyArgs) -> Result<()> {
    let kind = calbench::measurement::kind_csv::file_kind(&args.data).is_some();
    let outputs: &[&str] = if kind {
        &super::identify_kind::OUTPUTS
    } else {
        &OUTPUTS
    };
    super::guard_out(&args.out, outputs, super::identify_inputs(args))?;
    if args.export.contains(&Export::UrYaml) && calbench::robot::urdf::is_urdf(&args.robot) {
        return Err(Error::option(
            Opt::Export,
            "ur-yaml writes the robot's own DH frames, and a URDF's joints are read into DH \
             frames of calbench's choosing, not UR's (the UR10 example's: joint 1 turned by \
             180°, the last link's offset in the tool): a UR driver would read another arm; \
             export ur-yaml with a robot file in UR's DH frames (examples/ipa-ur10/ur10.toml), \
             or use robot.urdf",
        )
        .into());
    }
    let nominal = args.chain.load(&args.robot)?;
    if args.export.contains(&Export::UrYaml) {
        exports::ur_like(&nominal)?;
    }
    let (data, data_lines) = if kind {
        (
            IdentifyData::Kind(read_kind_file(&args.data, &nominal)?),
            None,
        )
    } else {
        let (m, lines) = read_measurements_at_lines(&args.data, &nominal)?;
        (IdentifyData::Tracker(m), Some(lines))
    };
    let spec = method_with_options(args.method.name, &args.options)?;
    if let Some(why) = data
        .k_refusal()
        .filter(|_| args.options.iter().any(|(k, _)| k == "k"))
    {
        return Err(Error::setting("--set k", why).into());
    }
    let (validate, validate_lines) = match args.validate.as_deref() {
        Some(p) => {
            let (m, lines) = read_measurements_at_lines(p, &nominal)?;
            (Some(m), Some(lines))
        }
        None => (None, None),
    };
    let request = IdentifyRequest {
        registration: args.registration,
        k: args.k,
        priors: priors(&args.prior, &nominal)?,
        validate,
        validate_source: args.validate.clone(),
        validate_lines,
        holdout: args.holdout,
        cv: args.cv,
        cv_seed: args.cv_seed,
        models: args.models.clone(),
        params: args.params.clone(),
        fix: args.fix.clone(),
        compliance: args.compliance.clone(),
        seed: args.seed,
        allow_rank_deficient: args.allow_rank_deficient,
        allow_worse: args.allow_worse,
        allow_implausible: args.allow_implausible,
        data_lines,
        ..IdentifyRequest::new(nominal, data, args.data.clone(), spec)
    };
    if let (IdentifyData::Kind(f), false) = (&request.data, args.export.is_empty()) {
        let why = "it applies to the tracker's measurement file (§ 5.1) only";
        let kind = f.data.instrument.kind();
        return Err(
            calbench::calibrate::on_kind::kind_refusal(&request, kind, Opt::Export, why).into(),
        );
    }
    match request.run()? {
        IdentifyOutcome::Tracker(o) => write(args, &o),
        IdentifyOutcome::Kind(o) => super::identify_kind::write(&args.out, &o),
    }
}

/// Writes the output folder of an identification on a tracker's file and prints its
/// warnings, the cross-validation or model choice, the validation table and a summary line.
fn write(args: &IdentifyArgs, o: &TrackerOutcome) -> Result<()> {
    let out = &args.out;
    for w in o.warnings() {
        eprintln!("warning: {}", w.spell(super::spell));
    }
    if let Some(w) = calbench::calibrate::record::unconverged_warning(&o.record) {
        eprintln!("warning: {w}");
    }
    let c = &o.calibrated;
    let mut extra = Vec::new();
    if args.export.contains(&Export::UrYaml) {
        extra.push(("ur-kinematics.yaml", exports::ur_yaml(&c.robot)?));
    }
    if args.export.contains(&Export::DhCsv) {
        let sigma = c.identified.standard_errors();
        let table = exports::dh_csv(&o.nominal, &c.robot, &o.params, &sigma);
        extra.push(("dh-table.csv", table));
    }
    let urdf = compensated_urdf(
        &args.robot,
        &args.chain.chain(),
        &args.export,
        &o.compensated(),
    )?;
    if let Some(k) = &o.kernel {
        extra.push((KERNEL_FILE, k.to_json()?));
        let mut carried = vec!["robot.toml"];
        carried.extend(
            extra
                .iter()
                .map(|(name, _)| *name)
                .filter(|n| *n != KERNEL_FILE),
        );
        if urdf.is_some() {
            carried.push("robot.urdf");
        }
        eprintln!("warning: {}", kernel_not_carried(&carried));
    }
    let record = IdentifyRecord::of(o, urdf);
    write_identified_with(out, &record, &additions(o), &extra)?;
    if let (Some(cvs), Some(best)) = (&o.record.cv_models, o.record.best_model()) {
        out!("model             CV RMS (mm)  folds mean ± sd   parameters");
        for (i, m) in cvs.iter().enumerate() {
            out!(
                "  {:<16} {:>10.4} {:>8.4} ± {:<8.4} {:>4}{}",
                m.model,
                m.rms,
                m.mean,
                m.sd,
                m.parameters,
                if i == best { "  (best)" } else { "" }
            );
        }
    } else if let Some(x) = &o.record.cv {
        out!(
            "{}-fold cross-validation: RMS {:.4} mm (folds {:.4} ± {:.4} mm)",
            x.k,
            x.rms,
            x.mean,
            x.sd
        );
    }
    if let Some(v) = &o.validation {
        super::identify_kind::print_validation(&v.before_mm, &v.after_mm);
    }
    let r = &c.identified;
    let rounds = match c.rounds.termination {
        RoundsEnd::Single => String::new(),
        end => format!(
            " ({} rounds of {} registration{} and identification, {})",
            c.rounds.rounds,
            o.registration.as_str(),
            match c.rounds.weights {
                RefitWeights::Coordinate => " weighing each coordinate",
                RefitWeights::Point => "",
            },
            end.as_str()
        ),
    };
    out!(
        "{} on {} points: {} after {}{rounds}; written to {}",
        o.record.method,
        o.data.len(),
        r.termination.as_str(),
        calbench::error::counted(r.iterations, "iteration", "iterations"),
        out.display()
    );
    Ok(())
}

/// What the files `carried` cannot hold of a model with a kernel residual: "robot.toml
/// carries", "robot.toml and dh-table.csv carry", "robot.toml, dh-table.csv and robot.urdf
/// carry".
pub(super) fn kernel_not_carried(carried: &[&str]) -> String {
    let files = match carried {
        [] => "no file carries".to_string(),
        [a] => format!("{a} carries"),
        [a, b] => format!("{a} and {b} carry"),
        [init @ .., a, b] => format!("{}, {a} and {b} carry", init.join(", ")),
    };
    format!(
        "the chosen model's kernel residual `gp` is written to {KERNEL_FILE} only: {files} the \
         parametric model without it, and `compensate` and the controller exports cannot apply \
         it (their predictions lack the residual's correction)"
    )
}

/// The method `name` with the `--set KEY=VALUE` options, read like a scenario's
/// `[[methods]]` entry: a key given twice is refused, as a scenario refuses a duplicate key.
pub(super) fn method_with_options(
    name: &str,
    options: &[(String, toml::Value)],
) -> calbench::Result<MethodSpec> {
    if options.is_empty() {
        return method_by_name(name);
    }
    if let Some(j) = (1..options.len()).find(|&j| options[..j].iter().any(|o| o.0 == options[j].0))
    {
        let (key, second) = &options[j];
        let first = &options
            .iter()
            .find(|o| o.0 == *key)
            .expect("found before j")
            .1;
        return Err(Error::setting(
            format!("--set {key}"),
            format!("is given twice ({first}, then {second}): one value per option"),
        ));
    }
    let t = options.iter().cloned().collect();
    MethodSpec::with_options(name, t).map_err(|(k, msg)| Error::setting(format!("--set {k}"), msg))
}

/// The compensated robot as a URDF: for a URDF robot (its source with the joint origins
/// moved) unless `--export toml` without `urdf`, for a robot file with `--export urdf`.
fn compensated_urdf(
    robot: &str,
    chain: &calbench::robot::urdf::UrdfChain,
    export: &[Export],
    compensated: &Robot,
) -> calbench::Result<Option<String>> {
    if export.contains(&Export::Toml) && !export.contains(&Export::Urdf) {
        return Ok(None);
    }
    let wants_urdf = export.contains(&Export::Urdf) || calbench::robot::urdf::is_urdf(robot);
    if wants_urdf && calbench::robot::harmonics::has_harmonics(compensated) {
        return Err(calbench::Error::setting(
            "--export",
            "a URDF cannot carry the joint-angle harmonics of the chosen model; use \
             `--export toml` (robot.toml's `harmonics` key) or a model without harmonics",
        ));
    }
    if wants_urdf && calbench::robot::gravity_basis::has_gravity(compensated) {
        return Err(calbench::Error::setting(
            "--export",
            "a URDF cannot carry the gravity basis of the chosen model; use `--export toml` \
             (robot.toml's `gravity` key) or a model without it",
        ));
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
