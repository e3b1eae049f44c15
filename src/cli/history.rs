//! `calbench history [--scenario NAME] [--metric M…] [--out DIR] [--regressions]`: the
//! recorded metrics across versions, as history.html and history.csv, and the regressions of
//! the latest version.

use std::path::PathBuf;

use anyhow::Result;

use calbench::error::counted;
use calbench::report::html::history::{csv, page, Point, Series};
use calbench::results::history;
use calbench::results::history::{Flag, Regressed};

use super::record::DbArg;

/// The files `history` writes.
const OUTPUTS: [&str; 2] = ["history.html", "history.csv"];

/// Arguments of `calbench history`.
#[derive(clap::Args)]
pub struct HistoryArgs {
    #[command(flatten)]
    pub db: DbArg,
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
    #[command(flatten)]
    pub tolerance: super::check::Tolerance,
}

/// Writes the pages and prints the regressions (non-zero exit with `--regressions` when
/// there is one).
pub fn run(args: &HistoryArgs) -> Result<()> {
    let tolerance = args.tolerance.checked()?;
    if let Some(out) = &args.out {
        // The database is an input: a page written over it would destroy it.
        super::guard_out(out, &OUTPUTS, [args.db.path()])?;
    }
    let db = args.db.open(false)?;
    let scenario = args.scenario.as_deref();
    let (regressed, compared, unjudged) = history::regressions(&db, scenario, tolerance)?;
    let lines: Vec<String> = regressed.iter().map(line).collect();
    if let Some(out) = &args.out {
        let points = history::points(&db, scenario, &args.metric, tolerance)?;
        let html = page(&points, &series(&points, &regressed));
        let table = csv(&points)?;
        let page = super::write_page(out, &OUTPUTS, &html, &table)?;
        out!("{} points; history: {}", points.len(), page.display());
    }
    if args.regressions {
        for l in &lines {
            out!("{l}");
        }
        let count = |f: Flag| regressed.iter().filter(|r| r.flag == f).count();
        let (reg, drift) = (count(Flag::Regression), count(Flag::Drift));
        let pairs = counted(compared, "scenario-machine pair", "scenario-machine pairs");
        // A registration or instruments study's pairs are said not to be judged, never
        // counted as compared.
        let unjudged = match unjudged {
            0 => String::new(),
            n => format!(
                "; {} of a registration or instruments study not judged: check's rule \
                 compares the entries of Monte-Carlo summaries only",
                counted(n, "pair", "pairs")
            ),
        };
        if reg + drift > 0 {
            anyhow::bail!(
                "{} and {} of the latest version ({pairs} compared{unjudged})",
                counted(reg, "regression", "regressions"),
                counted(drift, "drift", "drifts")
            );
        }
        out!(
            "no regression or drift of the latest version ({pairs} compared, {} with a changed \
             scenario{unjudged})",
            count(Flag::ScenarioChanged)
        );
    }
    Ok(())
}

/// One flagged change as `--regressions` prints it and the page lists it.
fn line(r: &Regressed) -> String {
    let path = if r.through.is_empty() {
        format!("{} → {}", r.from, r.to)
    } else {
        format!("{} → {} → {}", r.from, r.through.join(" → "), r.to)
    };
    match r.flag {
        Flag::Regression => format!(
            "regression: {} on {}, {path}: {}",
            r.scenario, r.machine, r.what
        ),
        Flag::Drift => format!(
            "drift: {} on {}, {path} ({} steps, each within the tolerance): {}",
            r.scenario,
            r.machine,
            r.through.len() + 1,
            r.what
        ),
        Flag::ScenarioChanged => format!(
            "scenario changed: {} on {}, {path}: the scenario differs (beyond seed and trials), \
             so the versions are not compared",
            r.scenario, r.machine
        ),
    }
}

/// The opening lines of the page: each scenario and machine with runs among `points`, its
/// state from what `regressed` flags, and the lines of its flags.
fn series(points: &[Point], regressed: &[Regressed]) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for p in points
        .iter()
        .filter(|p| calbench::results::Kind::is_study(&p.kind))
    {
        if out
            .iter()
            .any(|s| s.scenario == p.scenario && s.machine == p.machine)
        {
            continue;
        }
        let mine: Vec<&Regressed> = regressed
            .iter()
            .filter(|r| r.scenario == p.scenario && r.machine == p.machine)
            .collect();
        let has = |f: Flag| mine.iter().any(|r| r.flag == f);
        let versions = points
            .iter()
            .filter(|q| q.scenario == p.scenario && q.machine == p.machine)
            .map(|q| q.label.as_str())
            .collect::<std::collections::BTreeSet<_>>()
            .len();
        let state = if has(Flag::Regression) {
            "regressed"
        } else if has(Flag::Drift) {
            "drifting"
        } else if has(Flag::ScenarioChanged) {
            "scenario changed"
        } else if versions < 2 {
            "one version"
        } else {
            "unchanged"
        };
        out.push(Series {
            scenario: p.scenario.clone(),
            machine: p.machine.clone(),
            state: state.to_string(),
            flags: mine.into_iter().map(line).collect(),
        });
    }
    out.sort_by(|a, b| (&a.scenario, &a.machine).cmp(&(&b.scenario, &b.machine)));
    out
}
