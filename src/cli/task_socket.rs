//! `calbench task` on a socket task (docs/formats.md § 9.4): the calibration placement's
//! joint files identified as one socket file, calbench's robot, the nominal one and the
//! authors' calibrated model scored on both placements by the authors' own figures, printed
//! beside the authors' `kpis.yaml`; `identified.json`, `robot.toml`, `task.json` and the task
//! file as run written.

use anyhow::{bail, Result};

use calbench::calibrate::pipeline::IdentifyOutcome;
use calbench::calibrate::request::{IdentifyData, IdentifyRequest};
use calbench::calibrate::task::record::TASK_FILE;
use calbench::calibrate::task::socket::{Placements, SocketFigures, SocketScores, SocketTask};
use calbench::report::identified::identified_json;
use calbench::report::output::{folder, RobotToml, Text};
use calbench::robot::Robot;

/// The files written.
const OUTPUTS: [&str; 4] = ["identified.json", "robot.toml", "task.json", TASK_FILE];

/// What `calbench task` was given for a socket task.
pub struct SocketArgs<'a> {
    /// The method's name.
    pub method: &'static str,
    /// `--set` options.
    pub options: &'a [(String, toml::Value)],
    /// Whether `--models` was given (refused).
    pub models: bool,
    /// The output folder.
    pub out: &'a std::path::Path,
}

/// Runs the entry of the socket task `task` and writes its folder; prints every model's
/// figures on both placements beside the authors'.
pub fn run(args: &SocketArgs, task: &SocketTask) -> Result<()> {
    super::guard_out(args.out, &OUTPUTS, task.inputs())?;
    calbench::report::guard::guard_data_folder(args.out, "--out", task.data_files())?;
    super::check_out_folder(args.out, &OUTPUTS)?;
    if args.models {
        bail!(
            "--models: {} is a socket task, which identifies the kinematic model only",
            task.path.display()
        );
    }
    let spec = super::identify::method_with_options(args.method, args.options)?;
    let nominal = task.load_robot()?;
    let cal = task.placement(&task.calibration, &nominal)?;
    let val = task.placement(&task.validation, &nominal)?;
    let source = task.calibration[0].clone();
    let request = IdentifyRequest {
        fix: task.fix.clone(),
        ..IdentifyRequest::new(
            nominal.clone(),
            IdentifyData::Kind(cal.clone()),
            source,
            spec,
        )
    };
    let IdentifyOutcome::Kind(o) = request.run()? else {
        unreachable!("a socket task's data are socket readings")
    };
    for w in o.warnings() {
        eprintln!("warning: {}", w.spell(super::spell));
    }
    let compensated = o.compensated();
    let both = |robot: &Robot| -> (Vec<f64>, Placements) {
        let (_, calibration) = task.figures(robot, &cal);
        let (rows, validation) = task.figures(robot, &val);
        (
            rows,
            Placements {
                calibration,
                validation,
            },
        )
    };
    let (errors, calbench) = both(&compensated);
    let authors_model = match &task.authors_model {
        Some(p) => Some(both(&task.load_model(p)?).1),
        None => None,
    };
    let scores = SocketScores {
        placements: [
            SocketTask::placement_name(&task.calibration),
            SocketTask::placement_name(&task.validation),
        ],
        calbench,
        nominal: both(&nominal).1,
        authors_model,
        authors_kpis: task.kpis()?,
    };
    let record = task.record(args.method, errors, scores.clone());
    let json = serde_json::to_string_pretty(&record.to_value())? + "\n";
    let [_, robot_file, task_json, task_toml] = OUTPUTS;
    folder(
        args.out,
        &[
            &identified_json(&o.record),
            &RobotToml {
                name: robot_file,
                robot: &compensated,
            },
            &Text {
                name: task_json,
                text: json,
            },
            &Text {
                name: task_toml,
                text: task.text.clone(),
            },
        ],
    )?;
    print_scores(&scores, args.method);
    let ci = record
        .ci95
        .map(|[lo, hi]| format!(" (95 % interval {lo:.3} to {hi:.3})"))
        .unwrap_or_default();
    out!(
        "{} {}: socket_spread_mm = {:.3} mm{ci} on the validation placement, closed \
         division; written to {}",
        task.name,
        args.method,
        record.value,
        args.out.display()
    );
    for p in &task.published {
        out!(
            "  published: {} {:.3} mm ({}, {} division)",
            p.label,
            p.value,
            p.source,
            p.division.as_str()
        );
    }
    if let Some(u) = &task.unpublished {
        out!("  published on the validation placement: {u}");
    }
    if let Some(s) = &task.authors_source {
        out!("  the authors' model and figures: {s}");
    }
    Ok(())
}

/// The table of every model's figures: spread (pooled) and distance error, mm, on the
/// calibration and the validation placement.
fn print_scores(s: &SocketScores, method: &str) {
    let [c, v] = &s.placements;
    out!(
        "{:<34} {:>24} {:>24}",
        "spread / distance error (mm)",
        format!("calibration: {c}"),
        format!("validation: {v}")
    );
    let cell = |f: Option<&SocketFigures>| {
        f.map_or("—".to_string(), |f| {
            format!("{:.3} / {:.3}", f.spread_mm, f.distance_error_mm)
        })
    };
    let row = |label: String, p: Option<&Placements>, kpis: Option<&SocketFigures>| {
        let cal = kpis.or(p.map(|p| &p.calibration));
        out!(
            "  {label:<32} {:>24} {:>24}",
            cell(cal),
            cell(p.map(|p| &p.validation))
        );
    };
    row("nominal".into(), Some(&s.nominal), None);
    row(format!("calbench ({method})"), Some(&s.calbench), None);
    if let Some(a) = &s.authors_model {
        row("the authors' calibrated model".into(), Some(a), None);
    }
    if let Some(k) = &s.authors_kpis {
        row("the authors' kpis.yaml".into(), None, Some(k));
    }
}
