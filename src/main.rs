//! The `calbench` command line: parse, dispatch, report errors.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Parser, Subcommand};

use calbench::commands;

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
        /// Print JSON to stdout.
        #[arg(long)]
        json: bool,
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
        None => {
            println!("calbench: run `calbench --help` for the commands");
            Ok(())
        }
        Some(Command::Robots { name }) => Ok(commands::robots(name.as_deref())?),
        Some(Command::Fk { robot, q, json }) => Ok(commands::fk(&robot, &q, json)?),
        Some(Command::Identifiability {
            robot,
            measure,
            poses,
            seed,
            json,
        }) => Ok(commands::identifiability(
            &robot, &measure, poses, seed, json,
        )?),
    }
}

#[allow(dead_code)]
fn _unused(_: PathBuf) {}
