//! `calbench leaderboard [--db PATH] --out DIR`: leaderboard.html and leaderboard.csv of the
//! task entries recorded.

use std::path::PathBuf;

use anyhow::Result;

use calbench::report::html::leaderboard::{csv, page};
use calbench::results::board;

use super::record::DbArg;

/// The files `leaderboard` writes.
const OUTPUTS: [&str; 2] = ["leaderboard.html", "leaderboard.csv"];

/// Arguments of `calbench leaderboard`.
#[derive(clap::Args)]
pub struct LeaderboardArgs {
    #[command(flatten)]
    pub db: DbArg,
    /// Output folder.
    #[arg(long, required_unless_present = "verify")]
    pub out: Option<PathBuf>,
    /// Compute every entry's figure again from the per-row errors it recorded and refuse a
    /// mismatch (before writing anything; without --out, only verify).
    #[arg(long)]
    pub verify: bool,
}

/// Writes the leaderboard and prints where.
pub fn run(args: &LeaderboardArgs) -> Result<()> {
    if let Some(out) = &args.out {
        // The database is an input: a page written over it would destroy it.
        super::guard_out(out, &OUTPUTS, [args.db.path()])?;
    }
    let db = args.db.open(false)?;
    if args.verify {
        let n = board::verify(&db)?;
        eprintln!("{n} task entries verified: each figure is the one its recorded errors give");
    }
    let Some(out) = &args.out else {
        return Ok(());
    };
    let rows = board::rows(&db)?;
    let html = page(&rows, &board::scores(&rows));
    let table = csv(&rows)?;
    let page = super::write_page(out, &OUTPUTS, &html, &table)?;
    let tasks: std::collections::BTreeSet<&str> = rows.iter().map(|r| r.task.as_str()).collect();
    out!(
        "{} tasks, {} rows; leaderboard: {}",
        tasks.len(),
        rows.len(),
        page.display()
    );
    Ok(())
}
