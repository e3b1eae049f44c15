//! `calbench identify` on a measurement-kind file (docs/formats.md § 5.3: `length_mm`,
//! `step_mm`, `plane`, `sphere` or `target` readings): the robot's parameters and the
//! instrument's unknowns (or, for targets, the registration) by a Jacobian method, written to
//! `identified.json` and `robot.toml`.

use anyhow::Result;

use calbench::calibrate::on_kind::{identify_kind, validate_positions, Chosen};
use calbench::calibrate::{on_data, Registration};
use calbench::error::Error;
use calbench::measurement::csv::read_measurements;
use calbench::measurement::kind::Instrument;
use calbench::measurement::kind_csv::read_kind_file;
use calbench::numeric::Real;
use calbench::robot::robot_to_toml;

use super::identify::{check_names, method_with_options, IdentifyArgs};
use super::{check_out_folder, to_json_text, write_file};

/// The files written.
const OUTPUTS: [&str; 2] = ["identified.json", "robot.toml"];

/// The options of `identify` that a kind file does not take: each with whether it was given.
fn tracker_only(args: &IdentifyArgs) -> [(&'static str, bool); 7] {
    [
        ("--holdout", args.holdout.is_some()),
        ("--cv", args.cv.is_some()),
        ("--models", !args.models.is_empty()),
        ("--compliance", args.compliance.is_some()),
        ("--prior", !args.prior.is_empty()),
        ("--k", args.k.is_some()),
        ("--export", !args.export.is_empty()),
    ]
}

/// The option a kind file (of targets or not) refuses and why, if any: the
/// tracker's options, a registration the kind does not take, a method that is not a
/// Jacobian one (`solver`: it is).
fn refusal(args: &IdentifyArgs, targets: bool, solver: bool) -> Option<(&'static str, String)> {
    if let Some((option, _)) = tracker_only(args).into_iter().find(|o| o.1) {
        let why = "it applies to the tracker's measurement file (§ 5.1) only";
        return Some((option, why.to_string()));
    }
    let registration = args.registration;
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
            args.method.name
        );
        ("--method", why)
    })
}

/// Identifies the robot from the kind file `--data`, writes the output folder and prints
/// the validation table (with `--validate`, a tracker's file) and a summary line.
pub fn run(args: &IdentifyArgs) -> Result<()> {
    let out = &args.out;
    super::guard_out(out, &OUTPUTS, super::identify_inputs(args))?;
    check_out_folder(out, &OUTPUTS)?;
    let nominal = args.chain.load(&args.robot)?;
    let file = read_kind_file(&args.data, &nominal)?;
    let kind = file.data.instrument.kind().as_str();
    let targets = matches!(file.data.instrument, Instrument::Targets(_));
    let spec = method_with_options(args.method.name, &args.options)?;
    if let Some((option, why)) = refusal(args, targets, spec.method.solver().is_some()) {
        let msg = format!(
            "{} holds {kind} readings (docs/formats.md § 5.3): {why}",
            args.data.display()
        );
        return Err(Error::setting(option, msg).into());
    }
    let solver = spec
        .method
        .solver()
        .unwrap_or_else(|| unreachable!("refusal() refuses the methods that are not solvers"));
    check_names("--params", &nominal, &args.params)?;
    check_names("--fix", &nominal, &args.fix)?;
    let chosen = if args.params.is_empty() {
        Chosen::Identifiable
    } else {
        Chosen::Given(&args.params, args.allow_rank_deficient)
    };
    let validation = args
        .validate
        .as_deref()
        .map(|p| read_measurements(p, &nominal))
        .transpose()?;
    let fit = identify_kind(
        &nominal,
        &file,
        &args.data,
        (
            chosen,
            &args.fix,
            args.registration == Registration::Identify,
        ),
        solver,
    )?;
    let r = &fit.identified;
    if on_data::undetermined_termination(r.termination) && !args.allow_rank_deficient {
        return Err(Error::file(
            &args.data,
            "data",
            format!(
                "the {kind} readings do not determine every parameter (rank {} of {}); {} \
                 ended {}, so nothing was written. Measure poses that move every joint, leave \
                 parameters out with --fix, or pass --allow-rank-deficient",
                r.rank.map_or("?".into(), |k| k.to_string()),
                r.x.len(),
                spec.name(),
                r.termination.as_str()
            ),
        )
        .into());
    }
    let valid = validation
        .as_ref()
        .map(|v| validate_positions(&nominal, &fit.robot, v))
        .transpose()?;
    let inst = &fit.data.instrument;
    let t = fit.params.len();
    let cov = r.covariance();
    let sigma = |k: usize| cov.get((k, k)).map_or(Real::NAN, |v| v.sqrt());
    let names: Vec<String> = fit
        .params
        .iter()
        .map(|p| p.to_string())
        .chain(inst.nuisance_names())
        .collect();
    let map = |f: &dyn Fn(usize) -> Real, range: std::ops::Range<usize>| -> serde_json::Value {
        range
            .map(|k| (names[k].clone(), serde_json::json!(f(k))))
            .collect::<serde_json::Map<_, _>>()
            .into()
    };
    let strs =
        |v: &[calbench::robot::Param]| -> Vec<String> { v.iter().map(|p| p.to_string()).collect() };
    let mut j = serde_json::json!({
        "robot": nominal.name,
        "data": args.data.display().to_string(),
        "kind": kind,
        "method": spec.name(),
        "parameters": &names[..t],
        "errors": map(&|k| r.x[k], 0..t),
        "instrument_unknowns": map(&|k| fit.nuisance[k - t], t..names.len()),
        "standard_errors": map(&sigma, 0..names.len()),
        "unidentifiable": strs(&fit.analysis.unidentifiable),
        "readings": inst.observations(file.qs.len()),
        "condition_number": r.condition_number(),
        "rank": r.rank,
        "sigma0": r.sigma0,
        "rms_residual_mm": r.rms_residual,
        "iterations": r.iterations,
        "evaluations": r.evaluations,
        "termination": r.termination.as_str(),
    });
    match inst {
        Instrument::Targets(offsets) => {
            let offsets: Vec<[Real; 3]> = offsets.iter().map(|o| [o.x, o.y, o.z]).collect();
            j["targets_mm"] = serde_json::json!(offsets);
            j["registration"] = serde_json::json!(args.registration.as_str());
            if let Some(f) = &fit.registration {
                let (xyz, rpy) = f.to_xyz_rpy();
                j["registration_frame"] = serde_json::json!({"xyz_mm": xyz, "rpy_rad": rpy});
            }
        }
        Instrument::Distance { pivot } => j["pivot"] = serde_json::json!(pivot),
        Instrument::Planes(axes) => {
            let axes: Vec<&str> = axes.iter().map(|&a| ["x", "y", "z"][a]).collect();
            j["plane_axes"] = serde_json::json!(axes);
        }
        Instrument::Spheres(_) => {}
    }
    if !args.fix.is_empty() {
        j["fixed"] = serde_json::json!(strs(&args.fix));
    }
    if let Some((before, after)) = &valid {
        j["validation_before_mm"] = serde_json::json!(before);
        j["validation_after_mm"] = serde_json::json!(after);
    }
    let mut compensated = fit.robot.clone();
    compensated.name = format!("{}-calibrated", nominal.name);
    let [identified, robot_file] = OUTPUTS;
    calbench::report::atomically(out, |dir| {
        write_file(&dir.join(identified), &to_json_text(&j)?)?;
        write_file(&dir.join(robot_file), &robot_to_toml(&compensated))
    })?;
    if let Some((before, after)) = &valid {
        super::identify::print_validation(before, after);
    }
    if !fit.analysis.unidentifiable.is_empty() {
        let left = match chosen {
            Chosen::Identifiable => " (left at their nominal values)",
            Chosen::Given(..) => "",
        };
        out!(
            "not determined by these {kind} readings{left}: {}",
            strs(&fit.analysis.unidentifiable).join(" ")
        );
    }
    out!(
        "{} on {} {kind} readings: {} after {} iterations; written to {}",
        spec.name(),
        inst.observations(file.qs.len()),
        r.termination.as_str(),
        r.iterations,
        out.display()
    );
    Ok(())
}
