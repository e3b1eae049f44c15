//! `calbench task` on a socket task (docs/formats.md § 9.4): the entry run by the library
//! ([`SocketTask::entry`]: the calibration placement's joint files identified as one socket
//! file, calbench's robot, the nominal one and the authors' calibrated model scored on both
//! placements), its folder written (`identified.json`, `robot.toml`, `task.json` and the task
//! file as run), and every model's figures printed beside the authors' `kpis.yaml`.

use anyhow::{bail, Result};

use calbench::calibrate::task::record::TASK_FILE;
use calbench::calibrate::task::socket::{Placements, SocketFigures, SocketScores, SocketTask};
use calbench::report::write_kind;

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
    let head = &task.head;
    super::guard_out(args.out, &OUTPUTS, head.inputs())?;
    calbench::report::guard::guard_data_folder(args.out, "--out", task.data_files())?;
    super::check_out_folder(args.out, &OUTPUTS)?;
    if args.models {
        bail!(
            "--models: {} is a socket task, which identifies the kinematic model only",
            head.path.display()
        );
    }
    let spec = super::identify::method_with_options(args.method, args.options)?;
    let e = task.entry(spec, args.method)?;
    for w in e.outcome.warnings() {
        eprintln!("warning: {}", w.spell(super::spell));
    }
    let files = head.files(&e.record.to_value())?;
    write_kind(args.out, &e.outcome.record, &e.robot, &files)?;
    if let Some(scores) = &e.record.socket {
        print_scores(scores, args.method);
    }
    super::task::print_figure(&e.record, " on the validation placement", args.out);
    super::task::print_published(&head.published);
    if let Some(u) = &head.unpublished {
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
