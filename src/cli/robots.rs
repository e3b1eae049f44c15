//! `calbench robots [NAME]`: the built-in robots.

use anyhow::Result;

use calbench::robot::builtin::{Builtin, BUILTINS};
use calbench::robot::robot_to_toml;

/// Arguments of `calbench robots`.
#[derive(clap::Args)]
pub struct RobotsArgs {
    /// A built-in robot to print as a robot file.
    #[arg(value_parser = super::entry_of(BUILTINS, |b| b.name, |b| b.summary))]
    pub name: Option<&'static Builtin>,
}

/// Lists the built-in robots (name and summary), or prints one as a robot file.
pub fn run(args: &RobotsArgs) -> Result<()> {
    match args.name {
        None => {
            for b in BUILTINS {
                out!("{:<12} {}", b.name, b.summary);
            }
        }
        Some(b) => out_raw!("# {}\n{}", b.summary, robot_to_toml(&(b.build)())),
    }
    Ok(())
}
