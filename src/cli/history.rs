//! `calbench history [--scenario NAME] [--metric M…] [--out DIR] [--regressions]`: the
//! recorded metrics across versions, as history.html and history.csv, and the regressions of
//! the latest version.

use std::path::PathBuf;

use anyhow::Result;

use calbench::numeric::Real;
use calbench::report::html::history::{csv, page};
use calbench::report::output::{folder, Bytes};
use calbench::results::{db_path, history, Db};

/// The files `history` writes.
const OUTPUTS: [&str; 2] = ["history.html", "history.csv"];

/// Arguments of `calbench history`.
#[derive(clap::Args)]
pub struct HistoryArgs {
    /// The results database (default: $CALBENCH_DB, else results/calbench.sqlite).
    #[arg(long, value_name = "PATH")]
    pub db: Option<PathBuf>,
    /// Only this scenario (task, identification).
    #[arg(long, value_name = "NAME")]
    pub scenario: Option<String>,
    /// The metrics, by key path or its prefix (`validation_after_mm`), comma-separated or
    /// repeated (default: validation_after_mm.mean/.rms/.max, eta_mean_pct, failures and
    /// the tasks' metrics).
    #[arg(long, value_name = "M", value_delimiter = ',')]
    pub metric: Vec<String>,
    /// Output folder for history.html and history.csv.
    #[arg(long, required_unless_present = "regressions")]
    pub out: Option<PathBuf>,
    /// Print the regressions of the latest version of each scenario on each machine against
    /// the version before it; exit non-zero when there is one.
    #[arg(long)]
    pub regressions: bool,
    /// Allowed relative worsening, as for `check`.
    #[arg(long, default_value_t = 0.05, value_name = "X")]
    pub tolerance: Real,
}

/// Writes the pages and prints the regressions (non-zero exit with `--regressions` when
/// there is one).
pub fn run(args: &HistoryArgs) -> Result<()> {
    if !(args.tolerance.is_finite() && args.tolerance >= 0.0) {
        return Err(calbench::Error::setting("--tolerance", "must be a finite number ≥ 0").into());
    }
    if let Some(out) = &args.out {
        super::guard_out(out, &OUTPUTS, None::<&std::path::Path>)?;
        super::check_out_folder(out, &OUTPUTS)?;
    }
    let db = Db::open(&db_path(args.db.as_deref()), false)?;
    let scenario = args.scenario.as_deref();
    let (regressed, compared) = history::regressions(&db, scenario, args.tolerance)?;
    let lines: Vec<String> = regressed
        .iter()
        .map(|r| {
            format!(
                "{} on {}, {} → {}: {}",
                r.scenario, r.machine, r.from, r.to, r.what
            )
        })
        .collect();
    if let Some(out) = &args.out {
        let points = history::points(&db, scenario, &args.metric, args.tolerance)?;
        let html = page(&points, &lines);
        let table = csv(&points)?;
        folder(
            out,
            &[
                &Bytes {
                    name: "history.html",
                    bytes: html.as_bytes(),
                },
                &Bytes {
                    name: "history.csv",
                    bytes: table.as_bytes(),
                },
            ],
        )?;
        out!(
            "{} points; history: {}",
            points.len(),
            out.join("history.html").display()
        );
    }
    if args.regressions {
        for l in &lines {
            out!("regression: {l}");
        }
        if !lines.is_empty() {
            anyhow::bail!(
                "{} regressions of the latest version ({} scenario-machine pairs compared)",
                lines.len(),
                compared
            );
        }
        out!("no regression of the latest version ({compared} scenario-machine pairs compared)");
    }
    Ok(())
}
