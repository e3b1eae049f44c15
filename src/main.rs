//! The `calbench` command line: parse, dispatch, report errors.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Parser, Subcommand};

mod cli;

use cli as commands;

/// Simulation-driven benchmark harness for the kinematic calibration of industrial robots.
#[derive(Parser)]
#[command(name = "calbench", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// List the built-in robots, or print one as a robot file.
    Robots {
        /// A built-in robot to print as a robot file.
        name: Option<String>,
    },
    /// Forward kinematics of the tool point (the flange if there is no tool).
    Fk {
        /// Built-in robot name or robot file.
        #[arg(long)]
        robot: String,
        /// Joint values in the robot's units, comma-separated (`--q -10,20,30,0,45,0`).
        #[arg(long, allow_hyphen_values = true)]
        q: String,
        /// Print JSON to stdout.
        #[arg(long)]
        json: bool,
    },
    /// Rank, identifiable parameters and dependent groups over random poses.
    Identifiability {
        /// Built-in robot name or robot file.
        #[arg(long)]
        robot: String,
        /// `position` or `pose`.
        #[arg(long, default_value = "position")]
        measure: String,
        /// Number of random poses within the joint limits.
        #[arg(long, default_value_t = 100)]
        poses: usize,
        /// Seed of the random poses.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Analyse these poses instead (a pose list or measurement CSV, `q1..qn` columns).
        #[arg(long)]
        poses_file: Option<PathBuf>,
        /// Also report Guo 2024's ill-conditioned parameter separation of the joint
        /// parameters: each block's GCN before and after, and the removed parameters.
        #[arg(long)]
        gcn_blocks: bool,
        /// GCN threshold of the separation (Guo 2024 §3.1: 1e2).
        #[arg(long, default_value_t = 1e2)]
        gcn_threshold: f64,
        /// Print JSON to stdout.
        #[arg(long)]
        json: bool,
    },
    /// Run a Monte-Carlo study (a scenario file); writes results/<name>/ or --out.
    Run {
        /// The scenario file.
        scenario: PathBuf,
        /// Override the number of trials.
        #[arg(long)]
        trials: Option<usize>,
        /// Override the master seed.
        #[arg(long)]
        seed: Option<u64>,
        /// Worker threads (default: one per core).
        #[arg(long)]
        threads: Option<usize>,
        /// Output folder.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Run only share I of N (0 ≤ I < N) of the trials and sweep points, writing a
        /// partial result for `calbench merge`.
        #[arg(long, value_name = "I/N")]
        shard: Option<String>,
    },
    /// Merge the partial results of `run --shard I/N` (all N of them) into the output of
    /// the whole run.
    Merge {
        /// The shard folders.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
    },
    /// Regression guard: compare a summary.json with a baseline.
    Check {
        /// The summary.json of a run.
        summary: PathBuf,
        /// The baseline summary.json.
        #[arg(long)]
        baseline: PathBuf,
        /// Allowed relative worsening of each metric (0.05 = 5 %).
        #[arg(long, default_value_t = 0.05)]
        tolerance: f64,
    },
    /// Write the simulated measurement of one trial of a scenario.
    Simulate {
        /// The scenario file.
        scenario: PathBuf,
        /// The trial (0-based).
        #[arg(long, default_value_t = 0)]
        trial: usize,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
    },
    /// Identify the kinematic errors from a measurement file (real or simulated).
    Identify {
        /// Built-in robot name or robot file.
        #[arg(long)]
        robot: String,
        /// The measurement CSV (q1..qn,x,y,z[,qw,qx,qy,qz]).
        #[arg(long)]
        data: PathBuf,
        /// ls | ridge | igg3 | lm | bas | pso | bas-pso (default options).
        #[arg(long)]
        method: String,
        /// svd | wsvd | identify | known (known: the points are in the base frame).
        #[arg(long, default_value = "identify")]
        registration: String,
        /// A validation measurement CSV.
        #[arg(long)]
        validate: Option<PathBuf>,
        /// Full-pose data only: weight of orientation against position errors, mm per rad
        /// (default 100; about σ_position / σ_orientation of the instrument).
        #[arg(long)]
        k: Option<f64>,
        /// A method option, `KEY=VALUE` in TOML (repeatable): any key of the method's
        /// `[[methods]]` entry, e.g. `--set bound_mm=5 --set iterations=4000`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        options: Vec<String>,
        /// Write the result even when the data do not determine every parameter (termination
        /// `rank-deficient`); without it such a result is refused.
        #[arg(long)]
        allow_rank_deficient: bool,
        /// The compensated robot's format besides robot.toml: `urdf` (the default for a URDF
        /// robot: robot.urdf, the source with its joint origins updated) or `toml` (robot.toml
        /// only).
        #[arg(long)]
        export: Option<String>,
        /// Joint compliances identified with the kinematic errors (elasto-geometric model):
        /// names such as `c2,c3`, or `gravity` for every joint gravity loads. The gravity
        /// torques use the robot's link masses and each row's `payload_kg`.
        #[arg(long)]
        compliance: Option<String>,
        /// Seed of the random searches (bas, pso, bas-pso): another seed gives another
        /// identification of the same data (Qiao 2021 fig. 7); the others ignore it.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
    },
    /// Turn a tracker's raw export into a measurement CSV, as a mapping file says.
    Import {
        /// The raw export.
        raw: PathBuf,
        /// The mapping file (separator, decimal mark, columns, units, conventions).
        #[arg(long)]
        mapping: PathBuf,
        /// The measurement CSV to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Joint commands for a robot whose controller keeps the nominal model: per program row,
    /// the joints at which the identified robot reaches the nominal pose.
    Compensate {
        /// The nominal robot (the controller's model).
        #[arg(long)]
        robot: String,
        /// The identified (compensated) robot, e.g. identify's robot.toml.
        #[arg(long)]
        identified: String,
        /// The program: a CSV with columns q1..qn (nominal joint commands).
        #[arg(long)]
        joints: PathBuf,
        /// Payload at the tool (kg) while the program runs: a compensated robot with joint
        /// compliances corrects the commands for its gravity sag under this load.
        #[arg(long, default_value_t = 0.0)]
        payload_kg: f64,
        /// The corrected program to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Choose calibration poses for a scenario's robot (random, detmax, ide, detmax-ide).
    Poses {
        /// The scenario file.
        scenario: PathBuf,
        /// random | detmax | ide | detmax-ide.
        #[arg(long)]
        strategy: String,
        /// Number of poses (default: calibration.count).
        #[arg(long)]
        count: Option<usize>,
        /// Print the objective against these pose counts (e.g. 20,40,60,80).
        #[arg(long)]
        curve: Option<String>,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
    },
}

fn main() {
    let cli = Cli::parse();
    if let Err(e) = run(cli) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        None => Ok(commands::run(None, None, None, None, None, None)?),
        Some(Command::Run {
            scenario,
            trials,
            seed,
            threads,
            out,
            shard,
        }) => Ok(commands::run(
            Some(&scenario),
            trials,
            seed,
            threads,
            out,
            shard.as_deref(),
        )?),
        Some(Command::Merge { dirs, out }) => Ok(commands::merge(&dirs, &out)?),
        Some(Command::Check {
            summary,
            baseline,
            tolerance,
        }) => {
            let regressions = commands::check(&summary, &baseline, tolerance)?;
            if regressions.is_empty() {
                use std::io::Write as _;
                let _ = writeln!(
                    std::io::stdout(),
                    "no regression beyond tolerance {tolerance}"
                );
                Ok(())
            } else {
                for r in &regressions {
                    eprintln!("regression: {r}");
                }
                anyhow::bail!("{} metric(s) regressed", regressions.len())
            }
        }
        Some(Command::Import { raw, mapping, out }) => Ok(commands::import(&raw, &mapping, &out)?),
        Some(Command::Compensate {
            robot,
            identified,
            joints,
            payload_kg,
            out,
        }) => Ok(commands::compensate(
            &robot,
            &identified,
            &joints,
            payload_kg,
            &out,
        )?),
        Some(Command::Simulate {
            scenario,
            trial,
            out,
        }) => Ok(commands::simulate(&scenario, trial, &out)?),
        Some(Command::Identify {
            robot,
            data,
            method,
            registration,
            validate,
            k,
            options,
            allow_rank_deficient,
            export,
            compliance,
            seed,
            out,
        }) => Ok(commands::identify_file(
            &robot,
            &data,
            &method,
            &options,
            &registration,
            validate.as_deref(),
            k,
            allow_rank_deficient,
            export.as_deref(),
            compliance.as_deref(),
            seed,
            &out,
        )?),
        Some(Command::Poses {
            scenario,
            strategy,
            count,
            curve,
            out,
        }) => Ok(commands::poses(
            &scenario,
            &strategy,
            count,
            curve.as_deref(),
            &out,
        )?),
        Some(Command::Robots { name }) => Ok(commands::robots(name.as_deref())?),
        Some(Command::Fk { robot, q, json }) => Ok(commands::fk(&robot, &q, json)?),
        Some(Command::Identifiability {
            robot,
            measure,
            poses,
            seed,
            poses_file,
            gcn_blocks,
            gcn_threshold,
            json,
        }) => Ok(commands::identifiability(
            &robot,
            &measure,
            poses,
            seed,
            poses_file.as_deref(),
            gcn_blocks.then_some(gcn_threshold),
            json,
        )?),
    }
}
