//! `calbench check SUMMARY --baseline BASELINE [--tolerance X] [--strict]`: the regression
//! guard.

use std::path::PathBuf;

use anyhow::Result;

use calbench::error::Error;
use calbench::numeric::Real;
use calbench::report::check::{comparable, compare_with, read_json, Status, Trials};
use calbench::report::fmt_num;

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
    /// Fail on unresolved metrics too (worse beyond the tolerance, within the noise).
    #[arg(long)]
    pub strict: bool,
}

/// The per-trial values of the run whose summary is `summary`: its folder's `trials.csv`,
/// when there is one.
pub fn trials_beside(summary: &std::path::Path) -> calbench::Result<Option<Trials>> {
    let csv = summary
        .parent()
        .unwrap_or(std::path::Path::new("."))
        .join("trials.csv");
    if csv.is_file() {
        Trials::read(&csv)
    } else {
        Ok(None)
    }
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

/// Compares the summary with the baseline (trial by trial when both folders hold the same
/// trials in `trials.csv`): prints every metric that is not "no change" with its status and
/// the interval of its change, then `no regression beyond tolerance X` and the count of each
/// status; fails (exit status 1) on a regression, or with `--strict` on an unresolved metric.
pub fn run(args: &CheckArgs) -> Result<()> {
    let tolerance = args.tolerance.checked()?;
    let s = read_json(&args.summary)?;
    let b = read_json(&args.baseline)?;
    comparable(&s, &args.summary, &b, &args.baseline)?;
    let (ts, tb) = (
        trials_beside(&args.summary)?,
        trials_beside(&args.baseline)?,
    );
    let pairs = tb.as_ref().zip(ts.as_ref());
    let all = compare_with(&s, &b, tolerance, pairs);
    let count = |st: Status| all.iter().filter(|c| c.status == st).count();
    for c in all.iter().filter(|c| c.status != Status::NoChange) {
        let m = &c.metric;
        let line = match c.diff_ci {
            None => format!("{}: {m}", c.status.as_str()),
            Some([lo, hi]) => format!(
                "{}: {}: {}: {} → {} (change {} in [{}, {}], {}, p Holm {}){}",
                c.status.as_str(),
                m.entry,
                m.metric,
                fmt_num(m.baseline, 6),
                fmt_num(m.value, 6),
                fmt_num(m.value - m.baseline, 4),
                fmt_num(lo, 4),
                fmt_num(hi, 4),
                if c.paired { "paired" } else { "unpaired" },
                fmt_num(c.p_holm, 3),
                c.trials_needed.map_or(String::new(), |n| format!(
                    "; about {n} trials per run would resolve it"
                ))
            ),
        };
        if matches!(c.status, Status::Regression | Status::Unresolved) {
            eprintln!("{line}");
        } else {
            out!("{line}");
        }
    }
    let (reg, unres) = (count(Status::Regression), count(Status::Unresolved));
    let paired = all.iter().filter(|c| c.paired).count();
    let tally = format!(
        "{} metrics compared ({paired} paired): {reg} regression, {unres} unresolved, {} \
         changed within tolerance, {} improved, {} no change",
        all.len(),
        count(Status::Changed),
        count(Status::Improved),
        count(Status::NoChange)
    );
    if reg > 0 {
        eprintln!("{tally}");
        anyhow::bail!("{reg} metric(s) regressed");
    }
    if args.strict && unres > 0 {
        eprintln!("{tally}");
        anyhow::bail!("{unres} metric(s) unresolved (--strict)");
    }
    out!("no regression beyond tolerance {tolerance}");
    out!("{tally}");
    Ok(())
}
