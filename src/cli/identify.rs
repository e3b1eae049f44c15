//! `calbench identify --robot R --data CSV --method M [--registration REG] [--validate CSV]
//! [--k K] [--set KEY=VALUE …] [--allow-rank-deficient] [--export urdf|toml]
//! [--compliance LIST|gravity] [--seed S] --out DIR`: identification on a measurement file,
//! real or simulated.

use std::path::{Path, PathBuf};

use anyhow::Result;

use calbench::calibrate::on_data::identify_on_data;
use calbench::calibrate::{Registration, RoundsEnd};
use calbench::error::Error;
use calbench::identify::{method_by_name, MethodEntry, MethodSpec, METHODS};
use calbench::measurement::csv::read_measurements;
use calbench::measurement::Measure;
use calbench::numeric::Real;
use calbench::report::identified::{validate_file, write_identified, IdentifyRecord};
use calbench::robot::compliance::CompliancePick;
use calbench::robot::{builtin, Robot};

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
    /// The measurement CSV (`q1..qn,x,y,z[,qw,qx,qy,qz]`).
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
    #[arg(long)]
    pub validate: Option<PathBuf>,
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
    /// The compensated robot's format besides robot.toml (default: `urdf` for a URDF robot,
    /// else `toml`).
    #[arg(long, value_enum)]
    pub export: Option<Export>,
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
/// `--allow-rank-deficient`.
pub fn run(args: &IdentifyArgs) -> Result<()> {
    let out = &args.out;
    check_out_folder(out, &OUTPUTS)?;
    let nominal = builtin::load(&args.robot)?;
    let mut spec = method_with_options(args.method.name, &args.options)?;
    let registration = args.registration;
    let d = read_measurements(&args.data, &nominal)?;
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
    let val = args
        .validate
        .as_deref()
        .map(|p| read_measurements(p, &nominal))
        .transpose()?;
    let on = identify_on_data(
        &nominal,
        &d,
        &spec,
        registration,
        args.compliance.as_ref(),
        "--compliance",
        args.seed,
    )?;
    if on.undetermined() && !args.allow_rank_deficient {
        return Err(on
            .undetermined_error(&nominal, &args.data, &d, &spec, "--allow-rank-deficient")
            .into());
    }
    let (params, c) = (&on.params, &on.calibrated);
    if matches!(
        c.rounds.termination,
        RoundsEnd::MaxRounds | RoundsEnd::Stalled
    ) {
        eprintln!(
            "warning: {} registration and identification did not settle within {} mm in {} \
             rounds ({}; the smallest frame step was {:.3e} mm, and that round is the result)",
            registration.as_str(),
            calbench::calibrate::ROUND_TOLERANCE_MM,
            c.rounds.rounds,
            c.rounds.termination.as_str(),
            c.rounds.last_step_mm
        );
    }
    let validation = val
        .as_ref()
        .map(|v| validate_file(&nominal, c, v))
        .transpose()?;
    let record = IdentifyRecord {
        nominal: &nominal,
        data_path: &args.data,
        data: &d,
        method: spec.name(),
        registration,
        params,
        calibrated: c,
        validation: validation.as_ref(),
        urdf: compensated_urdf(&args.robot, args.export, &c.robot)?,
    };
    write_identified(out, &record)?;
    if let Some(v) = &validation {
        out!("validation error (mm)   mean      rms       max       std");
        for (label, s) in [("before", v.before_mm), ("after", v.after_mm)] {
            out!(
                "  {label:<8} {:>10.4} {:>9.4} {:>9.4} {:>9.4}",
                s.mean,
                s.rms,
                s.max,
                s.std
            );
        }
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

/// The method `name` with the `--set KEY=VALUE` options, read like a scenario's
/// `[[methods]]` entry.
fn method_with_options(
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
    export: Option<Export>,
    compensated: &Robot,
) -> calbench::Result<Option<String>> {
    if export == Some(Export::Toml) {
        return Ok(None);
    }
    if !calbench::robot::urdf::is_urdf(robot) {
        return match export {
            Some(Export::Urdf) => calbench::robot::urdf::robot_to_urdf(compensated).map(Some),
            _ => Ok(None),
        };
    }
    let source = calbench::robot::urdf::UrdfRobot::load(Path::new(robot))?;
    source.write(compensated).map(Some)
}
