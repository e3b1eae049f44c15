//! `calbench task TASK --method M [--models A,B,…] [--set KEY=VALUE …] --out DIR`: one entry
//! of a fixed real-data task (docs/formats.md § 9): the task's data and split read, the one
//! identification pipeline run on the calibration rows, scored on the validation rows; the
//! identify outputs, `task.json` and the task file as run (`task.toml`) written. A socket
//! task (§ 9.4) identifies its calibration placement and scores every model on both.

use std::path::PathBuf;

use anyhow::Result;

use calbench::calibrate::cv::Model;
use calbench::calibrate::pipeline::IdentifyOutcome;
use calbench::calibrate::record::IdentifiedRecord;
use calbench::calibrate::task::record::{OUTPUTS, SOCKET_OUTPUTS};
use calbench::calibrate::task::socket::{
    load_socket_task, Placements, SocketFigures, SocketScores, SocketTask,
};
use calbench::calibrate::task::{
    task_file, unconverged_warning, Published, Task, TaskEntry, TaskRecord,
};
use calbench::identify::{MethodEntry, METHODS};
use calbench::report::identified::IdentifyRecord;
use calbench::report::practice::additions;
use calbench::report::{write_identified_with, write_kind};

/// Arguments of `calbench task`.
#[derive(clap::Args)]
pub struct TaskArgs {
    /// A task under `tasks/` by name (`barrett-wam`), or the path of a task file.
    #[arg(value_parser = clap::builder::NonEmptyStringValueParser::new())]
    pub task: String,
    /// The identification method, with its default options.
    #[arg(long, value_parser = super::entry_of(METHODS, |m| m.name, |m| m.summary))]
    pub method: &'static MethodEntry,
    /// Candidate models (terms `kinematic`, `beta`, `compliance`, `gravity`, `harmonics`,
    /// `harmonics2`, `h{n}q{j}`, `gp`, joined by `+`);
    /// several are compared by 5-fold cross-validation on the calibration rows alone and the
    /// best is identified. Default: `kinematic`.
    #[arg(long, value_delimiter = ',')]
    pub models: Vec<Model>,
    /// A method option, `KEY=VALUE` in TOML (repeatable), as in `identify`.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = super::identify::method_option)]
    pub options: Vec<(String, toml::Value)>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// How `task` spells an option the library names
/// ([`task_option`](calbench::calibrate::task::task_option)): its own (`--method`,
/// `--models`, which `--cv`'s folds are) as the command line does, and one it does not take
/// as `identify`'s (`identify's --allow-implausible`).
pub fn spell(opt: calbench::error::Opt, on: bool) -> String {
    match calbench::calibrate::task::task_option(opt) {
        Ok(own) => super::spell(own, on),
        Err(other) => format!("identify's {}", super::spell(other, on)),
    }
}

/// Runs the entry and writes its folder; prints the task's figure and the published ones.
pub fn run(args: &TaskArgs) -> Result<()> {
    let path = task_file(&args.task)?;
    if let Some(t) = load_socket_task(&path)? {
        return run_socket(args, &t);
    }
    let task = Task::load(&path)?;
    super::guard_out(&args.out, &OUTPUTS, task.head.inputs())?;
    calbench::report::guard::guard_data_folder(&args.out, "--out", task.data_files())?;
    let spec = super::identify::method_with_options(args.method.name, &args.options)?;
    let (request, val, origin) = task.entry_request(spec, &args.models)?;
    let IdentifyOutcome::Tracker(o) = request.run()? else {
        unreachable!("a task's data are a tracker's measurements")
    };
    for w in o.warnings() {
        eprintln!("warning: {}", w.spell(super::spell));
    }
    unconverged(&o.record);
    let entry = TaskEntry {
        task: &task,
        method: args.method.name.to_string(),
        models: &origin,
        entrant: "calbench".into(),
    };
    let j = entry.json(&o, &val)?;
    let urdf = None;
    let record = IdentifyRecord::of(&o, urdf);
    let files = task.head.entry_files(&j.to_value(), &o)?;
    if o.kernel.is_some() {
        eprintln!(
            "warning: {}",
            super::identify::kernel_not_carried(&["robot.toml"])
        );
    }
    write_identified_with(&args.out, &record, &additions(&o), &files)?;
    if let Some(c) = &origin.choice {
        out!(
            "  the task's candidates, {}-fold CV repeated over fold seeds {:?}:",
            c.folds,
            c.fold_seeds
        );
        for (i, m) in c.models.iter().enumerate() {
            out!(
                "  {:<24} mean CV RMS {:>8.4} mm, lowest at {} of {} seeds{}",
                m.model,
                m.mean,
                m.wins,
                c.fold_seeds.len(),
                if i == c.best { "  (chosen)" } else { "" }
            );
        }
    }
    if let (Some(cvs), Some(best)) = (&o.record.cv_models, o.record.best_model()) {
        for (i, m) in cvs.iter().enumerate() {
            out!(
                "  {:<24} CV RMS {:>8.4} mm{}",
                m.model,
                m.rms,
                if i == best { "  (chosen)" } else { "" }
            );
        }
    }
    print_figure(&j, "", &args.out);
    print_published(&task.head.published);
    if let Some(u) = &task.head.unpublished {
        out!("  published: {u}");
    }
    Ok(())
}

/// Prints the entry's figure `r`, its interval and division, `on` saying where it is scored,
/// and the folder `out` it is written to.
fn print_figure(r: &TaskRecord, on: &str, out: &std::path::Path) {
    let ci = r
        .ci95
        .map(|[lo, hi]| format!(" (95 % interval {lo:.3} to {hi:.3})"))
        .unwrap_or_default();
    out!(
        "{} {}: {} = {:.3} mm{ci}{on}, {} division; written to {}",
        r.task,
        r.method,
        r.metric.as_str(),
        r.value,
        r.division.as_str(),
        out.display()
    );
}

/// Prints the data's authors' figures `published`, one line each.
fn print_published(published: &[Published]) {
    for p in published {
        out!(
            "  published: {} {:.3} mm ({}, {} division)",
            p.label,
            p.value,
            p.source,
            p.division.as_str()
        );
    }
}

/// The entry of the socket task `task` (docs/formats.md § 9.4), run by the library
/// ([`SocketTask::entry`]), its folder written (`identified.json`, `robot.toml`, `task.json`
/// and the task file as run); prints every model's figures on both placements beside the
/// authors' `kpis.yaml`.
fn run_socket(args: &TaskArgs, task: &SocketTask) -> Result<()> {
    let (head, out, method) = (&task.head, args.out.as_path(), args.method.name);
    super::guard_out(out, &SOCKET_OUTPUTS, head.inputs())?;
    calbench::report::guard::guard_data_folder(out, "--out", task.data_files())?;
    if !args.models.is_empty() {
        let why = format!(
            "{} is a socket task, which identifies the kinematic model only",
            head.path.display()
        );
        return Err(calbench::Error::setting("--models", why).into());
    }
    let spec = super::identify::method_with_options(method, &args.options)?;
    let e = task.entry(spec, method)?;
    for w in e.outcome.warnings() {
        eprintln!("warning: {}", w.spell(super::spell));
    }
    unconverged(&e.outcome.record);
    let files = head.files(&e.record.to_value())?;
    write_kind(out, &e.outcome.record, &e.robot, &files)?;
    if let Some(scores) = &e.record.socket {
        print_scores(scores, method);
    }
    print_figure(&e.record, " on the validation placement", out);
    print_published(&head.published);
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

/// Warns when the entry's identification stopped short of convergence
/// ([`unconverged_warning`]).
fn unconverged(r: &IdentifiedRecord) {
    if let Some(w) = unconverged_warning(r) {
        eprintln!("warning: {w}");
    }
}
