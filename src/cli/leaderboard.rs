//! `calbench leaderboard [--db PATH] --out DIR`: leaderboard.html and leaderboard.csv of the
//! task entries recorded.

use std::path::PathBuf;

use anyhow::Result;

use calbench::report::html::leaderboard::{csv, page};
use calbench::report::output::{folder, Bytes};
use calbench::results::{board, db_path, Db};

/// The files `leaderboard` writes.
const OUTPUTS: [&str; 2] = ["leaderboard.html", "leaderboard.csv"];

/// Arguments of `calbench leaderboard`.
#[derive(clap::Args)]
pub struct LeaderboardArgs {
    /// The results database (default: $CALBENCH_DB, else results/calbench.sqlite).
    #[arg(long, value_name = "PATH")]
    pub db: Option<PathBuf>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// Writes the leaderboard and prints where.
pub fn run(args: &LeaderboardArgs) -> Result<()> {
    super::guard_out(&args.out, &OUTPUTS, None::<&std::path::Path>)?;
    super::check_out_folder(&args.out, &OUTPUTS)?;
    let db = Db::open(&db_path(args.db.as_deref()), false)?;
    let rows = board::rows(&db)?;
    let html = page(&rows, &board::scores(&rows));
    let table = csv(&rows)?;
    folder(
        &args.out,
        &[
            &Bytes {
                name: "leaderboard.html",
                bytes: html.as_bytes(),
            },
            &Bytes {
                name: "leaderboard.csv",
                bytes: table.as_bytes(),
            },
        ],
    )?;
    let tasks: std::collections::BTreeSet<&str> = rows.iter().map(|r| r.task.as_str()).collect();
    out!(
        "{} tasks, {} rows; leaderboard: {}",
        tasks.len(),
        rows.len(),
        args.out.join("leaderboard.html").display()
    );
    Ok(())
}
