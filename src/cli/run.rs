//! `calbench run SCENARIO [--trials N] [--seed S] [--threads T] [--out DIR] [--shard I/N]`:
//! a Monte-Carlo study or a registration study; `calbench run --resume DIR`, a killed run
//! continued from its checkpoint; and `calbench` alone, the default study.

use std::path::{Path, PathBuf};

use anyhow::Result;

use calbench::error::Error;
use calbench::report::registration_study::{report_md, write_all};
use calbench::report::run_study;
use calbench::study::registration_study::RegistrationScenario;
use calbench::study::scenario::{Scenario, MAX_TRIALS};
use calbench::study::{RunOptions, Shard};

use super::{print_table, writable_folder};

/// The files of a run checked before it starts (the plots are checked before they land).
pub const OUTPUTS: [&str; 4] = ["summary.json", "trials.csv", "timing.json", "report.md"];

/// The files of a registration study checked before it starts.
const STUDY_OUTPUTS: [&str; 2] = ["summary.json", "report.md"];

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
    /// partial result for `calbench merge`.
    #[arg(long, value_name = "I/N", value_parser = shard)]
    pub shard: Option<Shard>,
    /// Continue the run into DIR that was killed, from the checkpoint it left (the same
    /// bytes as an uninterrupted run). With SCENARIO, --trials or --seed, refuses a
    /// checkpoint of another scenario, trial count or seed.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["out", "shard"])]
    pub resume: Option<PathBuf>,
}

/// `--shard I/N`.
fn shard(text: &str) -> std::result::Result<Shard, String> {
    Shard::parse(text).map_err(|e| match e {
        Error::Setting { msg, .. } => msg,
        other => other.to_string(),
    })
}

/// `calbench` without arguments: the built-in default study into `results/default/`.
pub fn default_study() -> Result<()> {
    run(&RunArgs::default())
}

/// Runs the scenario (a registration study when it has a `[registration_study]` table),
/// writes its folder and prints the results table and the report's path.
pub fn run(args: &RunArgs) -> Result<()> {
    if let Some(p) = &args.scenario {
        let text = std::fs::read_to_string(p).map_err(|e| Error::io(p, e))?;
        let table: toml::Table =
            toml::from_str(&text).map_err(|e| Error::file(p, "TOML", e.to_string().trim_end()))?;
        if RegistrationScenario::is_one(&table) {
            if args.shard.is_some() {
                return Err(Error::setting(
                    "--shard",
                    "a registration study (`[registration_study]`) runs whole, not in shards",
                )
                .into());
            }
            return registration_study(RegistrationScenario::from_table(table, p)?, args);
        }
    }
    if let Some(dir) = &args.resume {
        return resume(args, dir);
    }
    let sc = scenario_with_overrides(args)?;
    if args.threads == Some(0) {
        return Err(Error::setting("--threads", "must be at least 1").into());
    }
    let shard = args.shard;
    eprintln!(
        "running {}: {} trials{}{}",
        sc.name,
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
    let out = out_folder(args, &sc.name);
    writable_folder(&out, &OUTPUTS)?;
    let opts = RunOptions {
        threads: args.threads,
        out: Some(out),
        progress: true,
        shard,
    };
    let r = run_study(sc, &opts)?;
    finished(&r)
}

/// The scenario of `args` (or the default study) with `--trials` and `--seed` applied.
fn scenario_with_overrides(args: &RunArgs) -> Result<Scenario> {
    let sc = match &args.scenario {
        Some(p) => Scenario::load(p)?,
        None => Scenario::default_study()?,
    };
    Ok(sc.with_run_overrides(args.trials, args.seed)?)
}

/// `calbench run --resume DIR`: the killed run into DIR, continued from its checkpoint; a
/// scenario, `--trials` or `--seed` given too must be those of the checkpoint.
fn resume(args: &RunArgs, dir: &Path) -> Result<()> {
    if args.threads == Some(0) {
        return Err(Error::setting("--threads", "must be at least 1").into());
    }
    let given = if args.scenario.is_some() {
        Some(scenario_with_overrides(args)?)
    } else {
        if args.trials.is_some() || args.seed.is_some() {
            return Err(Error::setting(
                "--resume",
                "--trials and --seed are those of the checkpoint; to check them, give the                  scenario file too",
            )
            .into());
        }
        None
    };
    writable_folder(dir, &OUTPUTS)?;
    eprintln!("resuming the run into {}", dir.display());
    let r = calbench::report::resume_study(dir, given.as_ref(), args.threads)?;
    finished(&r)
}

/// Prints a finished run's table and where its report is (or, for a shard, how to merge).
fn finished(r: &calbench::study::RunResult) -> Result<()> {
    if let Some(s) = r.shard {
        out!(
            "shard {}/{} of {} in {:.1} s: {}; combine all {} shards with `calbench merge`",
            s.index,
            s.count,
            r.scenario.name,
            r.seconds,
            r.out.display(),
            s.count
        );
        return Ok(());
    }
    print_table(r);
    out!(
        "\n{} trials in {:.1} s; report: {}",
        r.scenario.trials * r.blocks.len(),
        r.seconds,
        r.out.join("report.md").display()
    );
    Ok(())
}

/// `--out`, or `results/<name>/` under the current folder.
fn out_folder(args: &RunArgs, name: &str) -> PathBuf {
    args.out
        .clone()
        .unwrap_or_else(|| Path::new("results").join(name))
}

/// `calbench run` of a scenario with a `[registration_study]` table (Ban fig. 3): the grid
/// of SVD against weighted-SVD registration errors, its report and heat map.
fn registration_study(mut sc: RegistrationScenario, args: &RunArgs) -> Result<()> {
    if let Some(n) = args.trials {
        if n == 0 || n > MAX_TRIALS {
            return Err(
                Error::setting("--trials", format!("must be between 1 and {MAX_TRIALS}")).into(),
            );
        }
        sc.trials = n;
    }
    if let Some(s) = args.seed {
        sc.seed = s;
    }
    if args.threads == Some(0) {
        return Err(Error::setting("--threads", "must be at least 1").into());
    }
    let st = &sc.registration_study;
    eprintln!(
        "running {}: registration study, {} × {} cells × {} draws",
        sc.name,
        st.outlier_counts.len(),
        st.magnitude_mm.len(),
        sc.trials
    );
    let out = out_folder(args, &sc.name);
    writable_folder(&out, &STUDY_OUTPUTS)?;
    let t0 = std::time::Instant::now();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .map_err(|e| Error::Compute(e.to_string()))?;
    let cells = pool.install(|| st.run(sc.seed, sc.trials))?;
    write_all(&sc, &cells, &out)?;
    out!(
        "{}\n{} draws per cell in {:.1} s; report: {}",
        report_md(&sc, &cells, "heatmap_difference.png")
            .lines()
            .skip_while(|l| !l.starts_with("## "))
            .take_while(|l| !l.starts_with("!["))
            .collect::<Vec<_>>()
            .join("\n"),
        sc.trials,
        t0.elapsed().as_secs_f64(),
        out.join("report.md").display()
    );
    Ok(())
}
