//! `calbench run SCENARIO [--trials N] [--seed S] [--threads T] [--out DIR] [--shard I/N]
//! [--precision TARGET]`:
//! a Monte-Carlo study or a registration study; `calbench run --resume DIR`, a killed run
//! continued from its checkpoint; and `calbench` alone, the default study.

use std::path::{Path, PathBuf};

use anyhow::Result;

use calbench::error::Error;
use calbench::results::Kind;
use calbench::runner::resume::Resumable;
use calbench::runner::run::{refuse_precision, run_study};
use calbench::runner::whole::{self, run_cells_study, Resumed};
use calbench::study::kind::AnyScenario;
use calbench::study::reporter::Terminal;
use calbench::study::scenario::Scenario;
use calbench::study::stats::precision::Precision;
use calbench::study::{RunOptions, Shard};

use super::{print_table, writable_folder};

pub use calbench::report::run::{checked_outputs, OUTPUTS};

/// Arguments of `calbench run`.
#[derive(clap::Args, Default)]
pub struct RunArgs {
    /// The scenario file.
    // Required on the command line (unless --resume); `None` is the built-in default study
    // (`calbench` alone).
    #[arg(required_unless_present = "resume")]
    pub scenario: Option<PathBuf>,
    /// Override the number of trials.
    #[arg(long)]
    pub trials: Option<usize>,
    /// Override the master seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Output folder.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run only share I of N (0 ≤ I < N) of the trials and sweep points, writing a
    /// partial result for `calbench merge`. `auto`: I and N from the scheduler (a Slurm job
    /// array's (SLURM_ARRAY_TASK_ID − SLURM_ARRAY_TASK_MIN) / SLURM_ARRAY_TASK_STEP and
    /// SLURM_ARRAY_TASK_COUNT, or a Kubernetes Indexed Job's JOB_COMPLETION_INDEX with N
    /// from --shard-count).
    #[arg(long, value_name = "I/N|auto", value_parser = shard)]
    pub shard: Option<ShardArg>,
    /// With --shard auto: the number of shards (a Kubernetes Job's completions; under Slurm,
    /// checked against SLURM_ARRAY_TASK_COUNT).
    #[arg(long, value_name = "N", requires = "shard")]
    pub shard_count: Option<u64>,
    /// Run trials in blocks of 32 until every entry's 95 % interval of the mean validation
    /// error after compensation has at most this half-width: relative to the mean (`0.5%`)
    /// or absolute (`0.002mm`); the trials (--trials or the scenario's) are the cap. The
    /// output is that of `--trials N` with the N it stopped at, plus `stopping` in
    /// summary.json. Not with a sweep or --shard.
    #[arg(long, value_name = "TARGET", value_parser = precision, allow_hyphen_values = true)]
    pub precision: Option<Precision>,
    /// Continue the run into DIR that was killed, from the checkpoint it left (the same
    /// bytes as an uninterrupted run). With SCENARIO, --trials or --seed, refuses a
    /// checkpoint of another scenario, trial count or seed.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["out", "shard", "precision"])]
    pub resume: Option<PathBuf>,
    /// Write into the folder (with --resume: continue the checkpoint) of a run whose
    /// process seems to be running on this host (its pid was taken by another program);
    /// without it such a folder is refused, naming the process.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub record: super::record::RecordFlags,
}

/// `--shard I/N` or `--shard auto`.
#[derive(Clone, Copy, Debug)]
pub enum ShardArg {
    /// The share given.
    Given(Shard),
    /// The share the scheduler's environment gives ([`auto_shard`]).
    Auto,
}

/// `--shard I/N` or `auto`.
fn shard(text: &str) -> std::result::Result<ShardArg, String> {
    if text == "auto" {
        return Ok(ShardArg::Auto);
    }
    Shard::parse(text).map(ShardArg::Given).map_err(why)
}

/// `--precision 0.5%` or `--precision 0.002mm`.
fn precision(text: &str) -> std::result::Result<Precision, String> {
    Precision::parse(text).map_err(why)
}

/// What a value parser says of a refused value: the setting's message (the parser names the
/// flag), or the whole error.
fn why(e: Error) -> String {
    match e {
        Error::Setting { msg, .. } | Error::Option { msg, .. } => msg.spell(super::spell),
        other => other.spelled(super::spell),
    }
}

/// `calbench` without arguments: the built-in default study into `results/default/`.
pub fn default_study() -> Result<()> {
    run(&RunArgs::default())
}

/// Runs the scenario (of the kind its sections give, [`AnyScenario`]), writes its folder and
/// prints the results table and the report's path.
pub fn run(args: &RunArgs) -> Result<()> {
    if let Some(dir) = &args.resume {
        return resume(args, dir);
    }
    // The thread count is checked (0, a malformed SLURM_CPUS_PER_TASK) before anything runs.
    threads(args.threads)?;
    let shard = match args.shard {
        None => None,
        Some(ShardArg::Given(s)) => {
            if let Some(c) = args.shard_count.filter(|&c| c != s.count as u64) {
                let why = format!("{c} contradicts --shard {}/{}", s.index, s.count);
                return Err(Error::setting("--shard-count", why).into());
            }
            Some(s)
        }
        Some(ShardArg::Auto) => Some(auto_shard(args.shard_count, &|k| std::env::var(k).ok())?),
    };
    if shard.is_some() && args.record.record {
        let why = "a shard is part of a run; record the merged run (`merge --record`)";
        return Err(Error::setting("--record", why).into());
    }
    let any = scenario_with_overrides(args)?;
    if let Some(s) = shard {
        // Before the run is announced, as the checkpoint would refuse it after.
        let why = s.fits(any.units());
        why.map_err(|m| Error::option(calbench::error::Opt::Shard, m))?;
    }
    let sc = match any {
        AnyScenario::MonteCarlo(sc) => sc,
        cells => return cells_study(&cells, shard, args),
    };
    let opts = RunOptions {
        threads: threads(args.threads)?,
        out: None,
        progress: true,
        shard,
        precision: args.precision.clone(),
    };
    if opts.precision.is_some() {
        refuse_precision(&sc, &opts)?;
    }
    let outputs = checked_outputs(true, shard.is_some());
    let out = out_folder(args, &sc.name, outputs)?;
    let db = args.record.open()?;
    writable_folder(&out, outputs)?;
    eprintln!(
        "running {}: {}{} trials{}{}",
        sc.name,
        args.precision
            .as_ref()
            .map_or(String::new(), |p| format!("until ±{} or ", p.text)),
        sc.trials,
        sc.sweep.as_ref().map_or(String::new(), |s| format!(
            " × {} sweep points of {}",
            s.points().len(),
            s.keys().join(", ")
        )),
        shard.map_or(String::new(), |s| format!(
            ", shard {}/{}",
            s.index, s.count
        ))
    );
    let opts = RunOptions {
        out: Some(out),
        ..opts
    };
    let path = sc.path.clone();
    let own = ["calibration.", "validation."];
    let r = run_study(sc, &opts, &Terminal).map_err(|e| in_scenario(e, path.as_deref(), &own))?;
    finished(&r)?;
    let record = || super::record::of_run(&r.out, &r.scenario, Kind::Run);
    args.record.finish(db, record)
}

/// The scenario of `args` (or the default study) with `--trials` and `--seed` applied.
fn scenario_with_overrides(args: &RunArgs) -> Result<AnyScenario> {
    let sc = match &args.scenario {
        Some(p) => AnyScenario::load(p)?,
        None => AnyScenario::MonteCarlo(Scenario::default_study()?),
    };
    Ok(sc.with_run_overrides(args.trials, args.seed)?)
}

/// `calbench run --resume DIR`: the killed run into DIR, continued from its checkpoint; a
/// scenario, `--trials` or `--seed` given too must be those of the checkpoint.
fn resume(args: &RunArgs, dir: &Path) -> Result<()> {
    let given = if args.scenario.is_some() {
        Some(scenario_with_overrides(args)?)
    } else {
        if args.trials.is_some() || args.seed.is_some() {
            return Err(Error::setting(
                "--resume",
                "--trials and --seed are those of the checkpoint; to check them, give the \
                 scenario file too",
            )
            .into());
        }
        None
    };
    // The root, the home folder and an input are refused before the checkpoint is read;
    // the files the run writes, once it says whether it is a shard. A live writer is refused
    // by the checkpoint's own check (`Resumable::open`), which names its checkpoint.json and
    // `--force`.
    let guard = |outputs| {
        calbench::report::guard::guard_out_with(dir, "--resume", outputs, &args.scenario, true)
    };
    guard(&[])?;
    let threads = threads(args.threads)?;
    let checked = Resumable::open(dir, given.as_ref(), args.force)?;
    guard(checked.outputs())?;
    writable_folder(dir, checked.outputs())?;
    let db = args.record.open()?;
    eprintln!("resuming the run into {}", dir.display());
    let (t0, trials) = (std::time::Instant::now(), checked.trials());
    match whole::resume(checked, threads, &Terminal)? {
        Resumed::Cells(table) => {
            cells_finished(&table, trials, t0, dir)?;
            args.record
                .finish(db, || super::record::of_study(dir, Kind::Run))
        }
        Resumed::Study(r) => {
            finished(&r)?;
            let record = || super::record::of_run(&r.out, &r.scenario, Kind::Run);
            args.record.finish(db, record)
        }
    }
}

/// Prints a finished run's table and where its report is (or, for a shard, how to merge).
fn finished(r: &calbench::study::RunResult) -> Result<()> {
    if let Some(s) = r.shard {
        let what = format!(
            "shard {}/{} of {} in {:.1} s",
            s.index, s.count, r.scenario.name, r.seconds
        );
        shard_written(&what, &r.out, Some(s.count));
        return Ok(());
    }
    print_table(r);
    let trials = r.scenario.trials * r.blocks.len();
    out!(
        "\n{} in {:.1} s; report: {}",
        calbench::error::counted(trials, "trial", "trials"),
        r.seconds,
        r.out.join("report.md").display()
    );
    Ok(())
}

/// Prints the line of a finished shard: `what` it ran, the folder `out` it wrote and how the
/// run is completed (merging all `count` shards, when known).
fn shard_written(what: &str, out: &Path, count: Option<usize>) {
    let all = count.map_or("all".to_string(), |n| format!("all {n}"));
    out!(
        "{what}: {}; combine {all} shards with `calbench merge`",
        out.display()
    );
}

/// `--out`, or `results/<name>/` under the current folder, where a run writing the files
/// `outputs` destroys nothing ([`super::guard_out`]).
fn out_folder(args: &RunArgs, name: &str, outputs: &[&str]) -> Result<PathBuf> {
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("results").join(name));
    calbench::report::guard::guard_out_with(&out, "--out", outputs, &args.scenario, args.force)?;
    Ok(out)
}

/// `calbench run` of a registration study (`[registration_study]`, Ban fig. 3) or an
/// instruments study (`[instruments_study]`): its cells on the runner of every study (checkpoint,
/// `--shard`), its files and the table of its cells.
fn cells_study(sc: &AnyScenario, shard: Option<Shard>, args: &RunArgs) -> Result<()> {
    let what = match sc {
        AnyScenario::Registration(_) => "a registration study (`[registration_study]`)",
        _ => "an instruments study (`[instruments_study]`)",
    };
    if args.precision.is_some() {
        let fixed = format!("{what} runs its --trials draws in every cell");
        return Err(Error::setting("--precision", fixed).into());
    }
    let outputs = checked_outputs(false, shard.is_some());
    let out = out_folder(args, sc.name(), outputs)?;
    let db = args.record.open()?;
    writable_folder(&out, outputs)?;
    // A registration study's cells are one block: each trial draws every cell.
    let cells = match sc {
        AnyScenario::Registration(s) => s.registration_study.cell_names().len(),
        _ => sc.blocks().0,
    };
    eprintln!(
        "running {}: {what}, {cells} cells × {} trials{}",
        sc.name(),
        sc.trials(),
        shard.map_or(String::new(), |s| format!(
            ", shard {}/{}",
            s.index, s.count
        ))
    );
    let opts = RunOptions {
        threads: threads(args.threads)?,
        out: Some(out.clone()),
        progress: true,
        shard,
        precision: None,
    };
    let t0 = std::time::Instant::now();
    let own = ["registration_study.", "instruments_study."];
    let table =
        run_cells_study(sc, &opts, &Terminal).map_err(|e| in_scenario(e, sc.path(), &own))?;
    if let Some(s) = shard {
        let what = format!("shard {}/{} of {}", s.index, s.count, sc.name());
        shard_written(&what, &out, Some(s.count));
        return Ok(());
    }
    cells_finished(&table, sc.trials(), t0, &out)?;
    args.record
        .finish(db, || super::record::of_study(&out, Kind::Run))
}

/// A refusal of the study's own setting (a key under one of the tables `own`), met while it
/// runs (a box that draws collinear points, a region that yields too few poses), placed in
/// the scenario file `path` at that key's line; any other error as it is.
fn in_scenario(e: Error, path: Option<&Path>, own: &[&str]) -> Error {
    let own = |key: &str| own.iter().any(|t| key.starts_with(t));
    match (&e, path) {
        (Error::Setting { key, .. }, Some(path)) if own(key) => {
            let text = std::fs::read_to_string(path).unwrap_or_default();
            e.in_file(path).at_key_line(&text)
        }
        _ => e,
    }
}

/// Prints a finished study of cells' `table`, its `trials` (each draws every cell) and where
/// its report is (a shard's table is empty).
fn cells_finished(table: &str, trials: usize, t0: std::time::Instant, out: &Path) -> Result<()> {
    if table.is_empty() {
        shard_written("shard written", out, None);
        return Ok(());
    }
    out!(
        "{table}\n{} in {:.1} s; report: {}",
        calbench::error::counted(trials, "trial", "trials"),
        t0.elapsed().as_secs_f64(),
        out.join("report.md").display()
    );
    Ok(())
}

/// `--threads` (0 refused), else `SLURM_CPUS_PER_TASK` when set (the CPUs Slurm gave the
/// task), else `None` (one per core): [`calbench::runner::threads::requested`].
fn threads(given: Option<usize>) -> Result<Option<usize>> {
    let env = |k: &str| std::env::var(k).ok();
    Ok(calbench::runner::threads::requested(
        "--threads",
        given,
        &env,
    )?)
}

/// `--shard auto`: the share from the scheduler's environment (`var` reads a variable).
/// Slurm: I = (`SLURM_ARRAY_TASK_ID` − `SLURM_ARRAY_TASK_MIN`) / `SLURM_ARRAY_TASK_STEP`
/// (1 when unset), N = `SLURM_ARRAY_TASK_COUNT` (`count`, when given, must agree; the array's
/// IDs must be evenly stepped up to `SLURM_ARRAY_TASK_MAX`); Kubernetes: I =
/// `JOB_COMPLETION_INDEX` (below `count`), N = `count`.
fn auto_shard(count: Option<u64>, var: &dyn Fn(&str) -> Option<String>) -> Result<Shard> {
    let refuse = |why: String| -> anyhow::Error { Error::setting("--shard", why).into() };
    let number =
        |name: &str| -> Result<Option<u64>> {
            match var(name) {
                None => Ok(None),
                Some(v) => v.trim().parse::<u64>().map(Some).map_err(|_| {
                    refuse(format!("auto: {name} is \"{v}\", not a whole number ≥ 0"))
                }),
            }
        };
    let (index, n) = if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
        let (Some(min), Some(n)) = (
            number("SLURM_ARRAY_TASK_MIN")?,
            number("SLURM_ARRAY_TASK_COUNT")?,
        ) else {
            return Err(refuse(
                "auto: SLURM_ARRAY_TASK_ID is set without SLURM_ARRAY_TASK_MIN and \
                 SLURM_ARRAY_TASK_COUNT (run as a job array: sbatch --array=0-N)"
                    .into(),
            ));
        };
        // A stepped array (--array=0-8:2) holds the IDs MIN, MIN + STEP, …, MAX.
        let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1);
        let max = number("SLURM_ARRAY_TASK_MAX")?;
        let last = n
            .checked_sub(1)
            .and_then(|k| k.checked_mul(step)?.checked_add(min));
        let regular = step >= 1 && last.is_some() && max.is_none_or(|m| Some(m) == last);
        if !regular {
            return Err(refuse(format!(
                "auto: SLURM_ARRAY_TASK_MIN {min}, SLURM_ARRAY_TASK_MAX {}, \
                 SLURM_ARRAY_TASK_STEP {step} and SLURM_ARRAY_TASK_COUNT {n} are not an \
                 array of evenly stepped IDs (--array=MIN-MAX:STEP); a list of IDs cannot be \
                 shards",
                max.map_or("unset".to_string(), |m| m.to_string())
            )));
        }
        let off = id
            .checked_sub(min)
            .filter(|o| o % step == 0 && o / step < n);
        let Some(off) = off else {
            return Err(refuse(format!(
                "auto: SLURM_ARRAY_TASK_ID {id} is not one of the array's IDs \
                 (SLURM_ARRAY_TASK_MIN {min}, SLURM_ARRAY_TASK_STEP {step}, \
                 SLURM_ARRAY_TASK_COUNT {n})"
            )));
        };
        if let Some(c) = count.filter(|&c| c != n) {
            return Err(refuse(format!(
                "auto: --shard-count {c} differs from SLURM_ARRAY_TASK_COUNT {n}"
            )));
        }
        (off / step, n)
    } else if let Some(i) = number("JOB_COMPLETION_INDEX")? {
        let Some(n) = count else {
            return Err(refuse(
                "auto: JOB_COMPLETION_INDEX is set; give the number of shards (the Job's \
                 completions) with --shard-count N"
                    .into(),
            ));
        };
        if i >= n {
            return Err(refuse(format!(
                "auto: JOB_COMPLETION_INDEX {i} is not below --shard-count {n} (the Job's \
                 completions)"
            )));
        }
        (i, n)
    } else {
        return Err(refuse(
            "auto: neither SLURM_ARRAY_TASK_ID (a Slurm job array) nor JOB_COMPLETION_INDEX \
             (a Kubernetes Indexed Job) is set; give --shard I/N"
                .into(),
        ));
    };
    Shard::parse(&format!("{index}/{n}")).map_err(|e| refuse(format!("auto: {e}")))
}
