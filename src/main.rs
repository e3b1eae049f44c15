//! The `calbench` command line: parse, dispatch, report errors. Each command's arguments and
//! work are in its module of `cli/`.

use clap::{Parser, Subcommand};

mod cli;

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
    Robots(cli::robots::RobotsArgs),
    /// Forward kinematics of the tool point (the flange if there is no tool).
    Fk(cli::fk::FkArgs),
    /// Rank, identifiable parameters and dependent groups over random poses.
    Identifiability(cli::identifiability::IdentifiabilityArgs),
    /// Run a Monte-Carlo study (a scenario file); writes `results/<name>/` or `--out`.
    Run(cli::run::RunArgs),
    /// Merge the partial results of `run --shard I/N` (all N of them) into the output of
    /// the whole run.
    Merge(cli::merge::MergeArgs),
    /// Regression guard: compare a summary.json with a baseline.
    Check(cli::check::CheckArgs),
    /// Write a baseline for `check` from a run folder: its summary.json with the per-trial
    /// values that let `check` compare a run of the same seed trial by trial.
    Baseline(cli::check::BaselineArgs),
    /// Write the simulated measurement of one trial of a scenario.
    Simulate(cli::simulate::SimulateArgs),
    /// Identify the kinematic errors from a measurement file (real or simulated).
    Identify(Box<cli::identify::IdentifyArgs>),
    /// Turn a tracker's raw export into a measurement CSV, as a mapping file says.
    Import(cli::import::ImportArgs),
    /// Joint commands for a robot whose controller keeps the nominal model: per program row,
    /// the joints at which the identified robot reaches the nominal pose.
    Compensate(cli::compensate::CompensateArgs),
    /// Choose calibration poses for a scenario's robot.
    Poses(cli::poses::PosesArgs),
    /// Two runs side by side, entry by entry, as compare.html and compare.md.
    #[command(
        after_help = "Regressions are marked by the rules and tolerance of `check`; the \
                            exit status is 0 whatever the comparison finds (`check` is the guard)."
    )]
    Compare(cli::compare::CompareArgs),
    /// One entry of a fixed real-data task under tasks/: identify on its calibration rows,
    /// score on its validation rows, write the identify outputs and task.json.
    Task(Box<cli::task::TaskArgs>),
    /// Store the results of run, merge, identify and task folders in the results database.
    Record(cli::record::RecordArgs),
    /// The recorded metrics across versions (history.html, history.csv), and the
    /// regressions of the latest version.
    History(cli::history::HistoryArgs),
    /// The tasks' leaderboard from the results database (leaderboard.html, .csv).
    Leaderboard(cli::leaderboard::LeaderboardArgs),
}

fn main() {
    // clap's refusal repeats the value it refuses: printed escaped, as every error is, so that
    // a control character in it (`--label $'v1\u{202e}'`) does not reach the terminal raw.
    let cli = Cli::try_parse().unwrap_or_else(|e| match e.use_stderr() {
        false => e.exit(),
        true => {
            eprint!("{}", cli::for_terminal(&e.to_string()));
            std::process::exit(e.exit_code())
        }
    });
    if let Err(e) = calbench::numeric::simd_forced_scalar() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
    let done = match &cli.command {
        Some(Command::Compare(a)) => cli::compare::run(a),
        Some(Command::Task(a)) => cli::task::run(a),
        None => cli::run::default_study(),
        Some(Command::Robots(a)) => cli::robots::run(a),
        Some(Command::Fk(a)) => cli::fk::run(a),
        Some(Command::Identifiability(a)) => cli::identifiability::run(a),
        Some(Command::Run(a)) => cli::run::run(a),
        Some(Command::Merge(a)) => cli::merge::run(a),
        Some(Command::Check(a)) => cli::check::run(a),
        Some(Command::Baseline(a)) => cli::check::baseline(a),
        Some(Command::Simulate(a)) => cli::simulate::run(a),
        Some(Command::Identify(a)) => cli::identify::run(a),
        Some(Command::Import(a)) => cli::import::run(a),
        Some(Command::Compensate(a)) => cli::compensate::run(a),
        Some(Command::Poses(a)) => cli::poses::run(a),
        Some(Command::Record(a)) => cli::record::run(a),
        Some(Command::History(a)) => cli::history::run(a),
        Some(Command::Leaderboard(a)) => cli::leaderboard::run(a),
    };
    if let Err(e) = done {
        let spell: calbench::error::Spell = match &cli.command {
            Some(Command::Task(_)) => cli::task::spell,
            _ => cli::spell,
        };
        eprintln!("error: {}", cli::message(&e, spell));
        std::process::exit(1);
    }
}
