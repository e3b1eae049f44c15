//! `calbench task TASK --method M [--models A,B,…] [--set KEY=VALUE …] --out DIR`: one entry
//! of a fixed real-data task (docs/formats.md § 9): the task's data and split read, the one
//! identification pipeline run on the calibration rows, scored on the validation rows; the
//! identify outputs, `task.json` and the task file as run (`task.toml`) written.

use std::path::PathBuf;

use anyhow::Result;

use calbench::calibrate::cv::Model;
use calbench::calibrate::pipeline::IdentifyOutcome;
use calbench::calibrate::task::{task_path, Task, TaskEntry};
use calbench::identify::{MethodEntry, METHODS};
use calbench::report::identified::IdentifyRecord;
use calbench::report::practice::additions;
use calbench::report::write_identified_with;

use super::check_out_folder;

/// The files written.
const OUTPUTS: [&str; 7] = [
    calbench::calibrate::kernel::KERNEL_FILE,
    "identified.json",
    "residuals.csv",
    "robot.toml",
    "report.md",
    "task.json",
    calbench::calibrate::task::record::TASK_FILE,
];

/// Arguments of `calbench task`.
#[derive(clap::Args)]
pub struct TaskArgs {
    /// A task under `tasks/` by name (`barrett-wam`), or the path of a task file.
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

/// Runs the entry and writes its folder; prints the task's figure and the published ones.
pub fn run(args: &TaskArgs) -> Result<()> {
    let path = task_path(&args.task);
    if let Some(t) = calbench::calibrate::task::socket::load_socket_task(&path)? {
        let socket = super::task_socket::SocketArgs {
            method: args.method.name,
            options: &args.options,
            models: !args.models.is_empty(),
            out: &args.out,
        };
        return super::task_socket::run(&socket, &t);
    }
    let task = Task::load(&path)?;
    super::guard_out(&args.out, &OUTPUTS, task.inputs())?;
    calbench::report::guard::guard_data_folder(&args.out, "--out", task.data_files())?;
    check_out_folder(&args.out, &OUTPUTS)?;
    let spec = super::identify::method_with_options(args.method.name, &args.options)?;
    let (request, val, origin) = task.entry_request(spec, &args.models)?;
    let candidates = origin.candidates.clone();
    let IdentifyOutcome::Tracker(o) = request.run()? else {
        unreachable!("a task's data are a tracker's measurements")
    };
    for w in o.warnings() {
        eprintln!("warning: {}", w.spell(super::spell));
    }
    let entry = TaskEntry {
        task: &task,
        method: args.method.name.to_string(),
        candidates: &candidates,
        entrant: "calbench".into(),
        origin: Some(&origin),
    };
    let j = entry.json(&o, &val)?;
    let urdf = None;
    let record = IdentifyRecord::of(&o, urdf);
    let mut files = entry.files(&j)?.to_vec();
    if let Some(k) = &o.kernel {
        files.push((calbench::calibrate::kernel::KERNEL_FILE, k.to_json()?));
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
    let ci = j["ci95"]
        .as_array()
        .map(|c| {
            format!(
                " (95 % interval {:.3} to {:.3})",
                c[0].as_f64().unwrap_or(f64::NAN),
                c[1].as_f64().unwrap_or(f64::NAN)
            )
        })
        .unwrap_or_default();
    out!(
        "{} {}: {} = {:.3} mm{ci}, {} division; written to {}",
        task.name,
        args.method.name,
        task.metric.as_str(),
        j["value"].as_f64().unwrap_or(f64::NAN),
        j["division"].as_str().unwrap_or(""),
        args.out.display()
    );
    for p in &task.published {
        out!(
            "  published: {} {:.3} mm ({}, {} division)",
            p.label,
            p.value,
            p.source,
            serde_json::to_value(p.division)?.as_str().unwrap_or("")
        );
    }
    if let Some(u) = &task.unpublished {
        out!("  published: {u}");
    }
    Ok(())
}
