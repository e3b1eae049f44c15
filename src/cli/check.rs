//! `calbench check SUMMARY --baseline BASELINE [--tolerance X]`: the regression guard.

use std::path::PathBuf;

use anyhow::Result;

use calbench::error::Error;
use calbench::numeric::Real;
use calbench::report::check::{comparable, compare, read_json};

/// Arguments of `calbench check`.
#[derive(clap::Args)]
pub struct CheckArgs {
    /// The summary.json of a run.
    pub summary: PathBuf,
    /// The baseline summary.json.
    #[arg(long)]
    pub baseline: PathBuf,
    #[command(flatten)]
    tolerance: Tolerance,
}

/// `--tolerance X`, of `check` and `compare`.
#[derive(clap::Args)]
pub struct Tolerance {
    /// Allowed relative worsening of each metric (0.05 = 5 %).
    #[arg(long, default_value_t = 0.05)]
    tolerance: Real,
}

impl Tolerance {
    /// The tolerance, refused unless a finite number ≥ 0.
    pub fn checked(&self) -> calbench::Result<Real> {
        let t = self.tolerance;
        if t.is_finite() && t >= 0.0 {
            Ok(t)
        } else {
            Err(Error::setting("--tolerance", "must be a number ≥ 0"))
        }
    }
}

/// Compares the summary with the baseline: prints `no regression beyond tolerance X`, or
/// each regression on stderr and fails (exit status 1) naming how many metrics regressed.
pub fn run(args: &CheckArgs) -> Result<()> {
    let tolerance = args.tolerance.checked()?;
    let s = read_json(&args.summary)?;
    let b = read_json(&args.baseline)?;
    comparable(&s, &args.summary, &b, &args.baseline)?;
    let regressions = compare(&s, &b, tolerance);
    if regressions.is_empty() {
        out!("no regression beyond tolerance {tolerance}");
        return Ok(());
    }
    for r in &regressions {
        eprintln!("regression: {r}");
    }
    anyhow::bail!("{} metric(s) regressed", regressions.len())
}
