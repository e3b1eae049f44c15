//! `calbench compare A B --out DIR [--tolerance X]`: two runs side by side, as
//! `compare.html` and `compare.md`.

use std::path::PathBuf;

use anyhow::Result;

use calbench::analysis::regression::Status;
use calbench::report::fmt_num;
use calbench::report::html::compare::{write, Comparison, Side, OUTPUTS};

use super::check::Tolerance;

/// Arguments of `calbench compare`.
#[derive(clap::Args)]
pub struct CompareArgs {
    /// The baseline run: its folder or its summary.json.
    pub a: PathBuf,
    /// The run compared with it: its folder or its summary.json.
    pub b: PathBuf,
    /// Output folder (compare.html, compare.md).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    tolerance: Tolerance,
}

/// Compares the runs, writes the pages and prints how many metrics regressed. Regressions
/// do not fail the command (`check` is the guard); unreadable summaries do.
pub fn run(args: &CompareArgs) -> Result<()> {
    let tolerance = args.tolerance.checked()?;
    super::guard_out(&args.out, &OUTPUTS, [&args.a, &args.b])?;
    let c = Comparison::new(Side::read(&args.a)?, Side::read(&args.b)?, tolerance)?;
    write(&c, &args.out)?;
    let missing = c.missing_in_b();
    out!(
        "{} metrics compared: {} regressed ({missing} of them missing in B), {} unresolved, {} \
         changed within tolerance, {} improved, {} no change (tolerance {}); {} \
         entries only in A, {} only in B; report: {}",
        c.all().len(),
        c.count(Status::Regression),
        c.count(Status::Unresolved),
        c.count(Status::Changed),
        c.count(Status::Improved),
        c.count(Status::NoChange),
        fmt_num(tolerance, 6),
        c.only_in(0).len(),
        c.only_in(1).len(),
        args.out.join("compare.html").display()
    );
    Ok(())
}
