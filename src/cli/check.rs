//! `calbench check SUMMARY --baseline BASELINE [--tolerance X] [--strict]`: the regression
//! guard.

use std::path::{Path, PathBuf};

use anyhow::Result;

use calbench::analysis::regression::{
    baseline_document, checked_tolerance, comparable, compare_with, unpaired_because,
    unpaired_entries, Compared, Side, Status, Unpaired, Which,
};
use calbench::error::{counted, Error};
use calbench::numeric::Real;
use calbench::report::{fmt_num, scenario_file};

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

/// Arguments of `calbench baseline`.
#[derive(clap::Args)]
pub struct BaselineArgs {
    /// The run: its folder (summary.json and trials.csv) or its summary.json.
    pub run: PathBuf,
    /// The baseline file to write (JSON).
    #[arg(long)]
    pub out: PathBuf,
}

/// Writes the baseline of a run: its summary with the per-trial values of the guarded
/// metrics (`per_trial`), read from its trials.csv; refuses a run without them, and, before
/// any work, an `--out` that is one of the files it reads (the summary, `trials.csv`, the
/// run's `scenario.toml`), another of the run's results beside them, or a folder.
pub fn baseline(args: &BaselineArgs) -> Result<()> {
    let [summary, trials] = Side::files(&args.run);
    let folder = summary.parent().unwrap_or(Path::new("."));
    let results = super::run::OUTPUTS.iter().chain(&["report.html"]);
    let beside: Vec<PathBuf> = results.map(|name| folder.join(name)).collect();
    let inputs = [args.run.as_path(), &summary, &trials];
    super::guard_out_file(
        &args.out,
        inputs
            .into_iter()
            .chain(beside.iter().map(PathBuf::as_path)),
    )?;
    if let Some(e) =
        calbench::results::a_shard(&args.run, "write the baseline of the merged folder")
    {
        return Err(e.into());
    }
    let side = Side::read(&args.run)?;
    // `check` refuses a baseline of no entries: nothing is written that it would refuse.
    if side.summary.results.is_empty() {
        let why = "is empty: the summary has no entries, so a baseline of it guards nothing";
        return Err(Error::file(&side.path, "results", why)
            .at_json_key_line()
            .into());
    }
    let Some(trials) = &side.trials else {
        return Err(Error::file(
            &side.path,
            "trials.csv",
            "is not beside this summary: a baseline that pairs needs the run's per-trial \
             values; give the run's folder",
        )
        .into());
    };
    let doc = baseline_document(&side.summary, trials, scenario_file::ran(&side)?)?;
    calbench::report::output::json_file(&args.out, &doc)?;
    out!(
        "wrote {}: the summary of {} with the per-trial values of {}",
        args.out.display(),
        side.path.display(),
        counted(trials.trials.len(), "entry", "entries")
    );
    Ok(())
}

/// Refuses, naming the summary, a run of another scenario than the baseline's when both
/// say what they ran: other settings draw other robots and poses, so the change is not the
/// program's, and trial `i` of one is not trial `i` of the other. The seed and the trials
/// may differ (the comparison is then unpaired).
fn same_scenario(baseline: &Side, summary: &Side) -> calbench::Result<()> {
    let apart = scenario_file::settings_apart(baseline, summary)?;
    if apart.is_empty() {
        return Ok(());
    }
    Err(Error::file(
        &summary.path,
        "scenario",
        format!(
            "is the run of another scenario than the baseline {} ({}): check compares one \
             scenario from version to version; run the baseline's scenario (its seed and \
             trials may differ), or write a baseline of this one with `calbench baseline`",
            baseline.path.display(),
            apart.join("; ")
        ),
    ))
}

/// The metrics whose per-trial values paired but were set aside
/// ([`Compared::not_the_figures`]), entry by entry in the comparison's order.
fn set_aside(all: &[Compared]) -> Vec<(&str, Vec<&str>)> {
    let mut out: Vec<(&str, Vec<&str>)> = Vec::new();
    for c in all.iter().filter(|c| c.not_the_figures) {
        let (entry, metric) = (c.metric.entry.as_str(), c.metric.metric.as_str());
        match out.last_mut() {
            Some((e, m)) if *e == entry => m.push(metric),
            _ => out.push((entry, vec![metric])),
        }
    }
    out
}

/// `--tolerance X`, of `check`, `compare` and `history`.
#[derive(clap::Args)]
pub struct Tolerance {
    /// Allowed relative worsening of each metric (0.05 = 5 %).
    #[arg(
        long,
        default_value_t = 0.05,
        value_name = "X",
        allow_negative_numbers = true,
        value_parser = super::number
    )]
    tolerance: Real,
}

impl Tolerance {
    /// The tolerance, refused unless a number from 0 to 10 ([`checked_tolerance`]).
    pub fn checked(&self) -> calbench::Result<Real> {
        checked_tolerance(self.tolerance, "--tolerance")
    }
}

/// Compares the summary with the baseline (trial by trial when both folders hold the same
/// trials in `trials.csv`): prints every metric that is not "no change" with its status and
/// the interval of its change, then `no regression beyond tolerance X` and the count of each
/// status; fails (exit status 1) on a regression, or with `--strict` on an unresolved metric.
pub fn run(args: &CheckArgs) -> Result<()> {
    let tolerance = args.tolerance.checked()?;
    let (s, b) = (Side::read(&args.summary)?, Side::read(&args.baseline)?);
    comparable(&s.summary, &s.path, &b.summary, &b.path)?;
    same_scenario(&b, &s)?;
    let pairs = b.trials.as_ref().zip(s.trials.as_ref());
    let all = compare_with(&s.summary, &b.summary, tolerance, pairs);
    match unpaired_because(&b, &s) {
        Some(why) => out!("unpaired: {}", unpaired_text(&why, &b)),
        None => {
            for (entry, why) in unpaired_entries(&b, &s) {
                out!("unpaired: {entry}: {why}, so its metrics are compared from the summaries' intervals");
            }
            for (entry, metrics) in set_aside(&all) {
                out!(
                    "unpaired: {entry}: {}: over the trials usable in both runs their per-trial \
                     values do not give the summaries' figures (a trial counts in one run only, a \
                     parameter's η in one run or in some trials only, or a trials.csv is of \
                     another run or edited), so they are compared from the summaries' \
                     intervals",
                    metrics.join(", ")
                );
            }
        }
    }
    let count = |st: Status| all.iter().filter(|c| c.status == st).count();
    for c in all.iter().filter(|c| c.status != Status::NoChange) {
        let m = &c.metric;
        let line = match c.diff_ci {
            None => format!("{}: {m}", c.status.as_str()),
            Some([lo, hi]) => format!(
                "{}: {}: {}: {} → {} (change {}{}, {}, p Holm {}){}",
                c.status.as_str(),
                m.entry,
                m.metric,
                fmt_num(m.baseline, 6),
                fmt_num(m.value, 6),
                fmt_num(m.value - m.baseline, 4),
                match (lo.is_finite(), hi.is_finite()) {
                    // A figure whose summaries have no interval at their trials.
                    (false, false) =>
                        " with no interval (neither summary has one at its trials)".into(),
                    // The interval of the report's test of the pair: the median's for the
                    // sign test.
                    _ => format!(
                        "{} [{}, {}]",
                        if c.median {
                            ", median change (sign test) in"
                        } else {
                            " in"
                        },
                        fmt_num(lo, 4),
                        fmt_num(hi, 4)
                    ),
                },
                if c.paired { "paired" } else { "unpaired" },
                fmt_num(c.p_holm, 3),
                c.trials_needed.map_or(String::new(), |n| format!(
                    "; about {n} trials per run would resolve it"
                ))
            ),
        };
        if matches!(c.status, Status::Regression | Status::Unresolved) {
            err!("{line}");
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
    out!("no regression beyond tolerance {}", fmt_num(tolerance, 6));
    out!("{tally}");
    Ok(())
}

/// Why a comparison is unpaired, and what a paired one would take, in words.
pub fn unpaired_text(why: &Unpaired, baseline: &Side) -> String {
    match why {
        Unpaired::NoTrials(Which::Baseline) => format!(
            "{} holds a summary without per-trial values, so every metric is compared from \
             the summaries' intervals; a baseline written by `calbench baseline RUN --out \
             FILE` (or a run folder with its trials.csv) is compared trial by trial",
            baseline.path.display()
        ),
        Unpaired::NoTrials(Which::Summary) => "the summary's folder holds no trials.csv, so \
             every metric is compared from the summaries' intervals; compare the run's \
             summary.json in its folder to pair"
            .to_string(),
        Unpaired::Differs {
            key,
            baseline: a,
            summary: b,
        } => {
            let take = match *key {
                _ if a == "none" => "a run of the baseline's scenario".to_string(),
                "seed" => format!("a run with --seed {a}"),
                "trials" => format!("a run with --trials {a}"),
                _ => "a run of the baseline's scenario and sweep".to_string(),
            };
            format!(
                "the runs differ in their {key} (baseline {a}, this run {b}), so every metric \
                 is compared from the summaries' intervals; {take} (the baseline's seed, \
                 trials and sweep) is compared trial by trial"
            )
        }
    }
}
