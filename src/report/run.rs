//! The files of a run: `summary.json`, `trials.csv`, `report.md` and the plots (docs/formats.md
//! `run`). Writers only read results that are already computed.

use std::fmt::Write as _;

use serde_json::{json, Value};

use crate::analysis::summary::Summary;
use crate::study::metric::Metric;

use super::markdown::{fmt_num, table};
use super::plots;

pub mod claims;
pub mod comparisons;
pub mod searches;
mod sweep;
pub mod trials_csv;

pub use super::output::Figure;
use super::output::{Output, Outputs, Text};
use crate::error::Result;
use crate::numeric::Real;
use crate::study::stats::{Entry, TrialFigures};
use crate::study::{Block, RunResult};
use sweep::{sweep_figures, sweep_tables};
pub use trials_csv::TrialsCsv;

pub use super::output::json_text;

/// The label of a results entry in tables and plots: `method / poses`.
fn entry_label(e: &Entry) -> String {
    format!("{} / {}", e.method, e.poses)
}

/// Per entry of a block: its label, and a value per parameter.
type EtaSeries<T> = Vec<(String, Vec<T>)>;

/// The parameters with an η in some entry of `b` (in name order) and, per entry, its label
/// and mean η of each of those parameters (NaN where it has none: no injected error, or one
/// that was not determinable), and the 95 % interval of each mean (`None` where it has none).
fn eta_by_parameter(b: &Block) -> (Vec<String>, EtaSeries<Real>, EtaSeries<Option<[Real; 2]>>) {
    let params: Vec<String> = b
        .entries
        .iter()
        .flat_map(|e| e.eta.keys().cloned())
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    let series = per_parameter(b, &params, |x| x.map_or(Real::NAN, |x| x.mean));
    let intervals = per_parameter(b, &params, |x| x.and_then(|x| x.mean_ci95));
    (params, series, intervals)
}

/// A section of `report.md`: `## TITLE`, the note that says how to read it, the table.
fn noted_table(title: &str, note: &str, headers: &[&str], rows: &[Vec<String>]) -> String {
    format!("## {title}\n\n{note}\n\n{}", table(headers, rows))
}

/// Per entry of `b`, its label and `f` of its η statistics of each of `params` (`None` where
/// it has none).
fn per_parameter<T>(
    b: &Block,
    params: &[String],
    f: impl Fn(Option<&TrialFigures>) -> T,
) -> EtaSeries<T> {
    b.entries
        .iter()
        .map(|e| {
            let values = params.iter().map(|p| f(e.eta.get(p))).collect();
            (entry_label(e), values)
        })
        .collect()
}

/// A column of a results table: its header and how an entry fills it.
pub type Column = (&'static str, fn(&Entry) -> String);

/// A 95 % interval as `[lo, hi]` with `digits` significant digits (empty when there is
/// none).
pub fn fmt_ci(ci: Option<[Real; 2]>, digits: usize) -> String {
    ci.map_or(String::new(), |[lo, hi]| {
        format!("[{}, {}]", fmt_num(lo, digits), fmt_num(hi, digits))
    })
}

/// The columns of the results tables (the printed one and the report's take these in
/// different selections).
pub mod columns {
    use super::{fmt_ci, fmt_num, Column, Metric, Real};

    /// 95 % interval of the mean η.
    pub const ETA_MEAN_CI: Column = ("η mean 95 % CI", |e| fmt_ci(e.eta_mean_pct_ci95, 4));
    /// 95 % interval of the median η, simultaneous over the parameters.
    pub const ETA_MEDIAN_CI: Column = ("η median 95 % CI, simultaneous", |e| {
        fmt_ci(e.eta_median_pct_ci95, 4)
    });
    /// 95 % interval of the mean validation error after compensation.
    pub const AFTER_MEAN_CI: Column = ("after mean 95 % CI", |e| {
        fmt_ci(e.validation_after_mm.mean_ci95, 4)
    });
    /// 95 % interval of the validation RMS after compensation.
    pub const AFTER_RMS_CI: Column = ("after RMS 95 % CI", |e| {
        fmt_ci(e.validation_after_mm.rms_ci95, 4)
    });

    /// Mean η.
    pub const ETA_MEAN: Column = ("η mean %", |e| fmt_num(e.eta_mean_pct, 4));
    /// Median η.
    pub const ETA_MEDIAN: Column = ("η median %", |e| fmt_num(e.eta_median_pct, 4));
    /// Mean validation error before compensation.
    pub const BEFORE_MEAN: Column = ("before mean mm", |e| {
        fmt_num(e.validation_before_mm.mean, 4)
    });
    /// RMS validation error before compensation.
    pub const BEFORE_RMS: Column = ("before RMS mm", |e| fmt_num(e.validation_before_mm.rms, 4));
    /// Largest validation error before compensation.
    pub const BEFORE_MAX: Column = ("before max mm", |e| fmt_num(e.validation_before_mm.max, 4));
    /// Mean validation error after compensation.
    pub const AFTER_MEAN: Column = ("after mean mm", |e| fmt_num(e.validation_after_mm.mean, 4));
    /// RMS validation error after compensation.
    pub const AFTER_RMS: Column = ("after RMS mm", |e| fmt_num(e.validation_after_mm.rms, 4));
    /// Largest validation error after compensation.
    pub const AFTER_MAX: Column = ("after max mm", |e| fmt_num(e.validation_after_mm.max, 4));
    /// Improvement of the mean error.
    pub const IMPROVEMENT: Column = ("improvement %", |e| fmt_num(e.improvement_pct, 4));
    /// Mean orientation error before compensation (full pose).
    pub const BEFORE_DEG: Column = ("before mean °", |e| {
        fmt_num(
            e.optional
                .get("validation_before_deg")
                .map_or(Real::NAN, |d| d.mean),
            4,
        )
    });
    /// Mean orientation error after compensation (full pose).
    pub const AFTER_DEG: Column = ("after mean °", |e| {
        fmt_num(
            e.optional
                .get(Metric::DegAfterMean.spec().field)
                .map_or(Real::NAN, |d| d.mean),
            4,
        )
    });
    /// Ratio to the Cramér–Rao bound.
    pub const CRB_RATIO: Column = ("CRB ratio", |e| {
        fmt_num(e.crb_ratio.unwrap_or(Real::NAN), 3)
    });
    /// Failed identifications.
    pub const FAILURES: Column = (Metric::Failures.spec().field, |e| e.failures.to_string());
    /// Mean model evaluations per identification (the budget spent).
    pub const EVALUATIONS: Column = (Metric::Evaluations.spec().field, |e| {
        fmt_num(e.evaluations_mean, 5)
    });
    /// Wall time per identification.
    pub const MS_PER_IDENTIFICATION: Column = ("ms / identification", |e| {
        fmt_num(e.seconds_per_identification * 1e3, 3)
    });
}

/// The validation columns of the results tables: before and after (mean, RMS, max), the
/// improvement, and on full-pose data the mean orientation errors.
pub fn validation_columns(pose: bool) -> Vec<Column> {
    use columns::*;
    let mut cols = vec![
        BEFORE_MEAN,
        BEFORE_RMS,
        BEFORE_MAX,
        AFTER_MEAN,
        AFTER_RMS,
        AFTER_MAX,
        IMPROVEMENT,
    ];
    if pose {
        cols.extend([BEFORE_DEG, AFTER_DEG]);
    }
    cols
}

/// The headers and rows of a table with one row per results entry: the swept value (for
/// sweeps), the method, the poses, then `columns`.
pub fn entry_table(r: &RunResult, columns: &[Column]) -> (Vec<String>, Vec<Vec<String>>) {
    entry_table_by(r, columns.iter().map(|c| c.0.to_string()), |e: &Entry| {
        columns.iter().map(|c| (c.1)(e)).collect()
    })
}

/// [`entry_table`] with any cells: the columns `headers`, filled per entry by `cells`.
pub fn entry_table_by(
    r: &RunResult,
    headers: impl IntoIterator<Item = String>,
    cells: impl Fn(&Entry) -> Vec<String>,
) -> (Vec<String>, Vec<Vec<String>>) {
    let mut head: Vec<String> = Vec::new();
    if let Some(sw) = &r.scenario.sweep {
        head.extend(sw.axes.iter().map(|a| a.key.clone()));
    }
    head.extend(["method", "poses"].map(String::from));
    head.extend(headers);
    let mut rows = Vec::new();
    for b in &r.blocks {
        for e in &b.entries {
            let mut row = Vec::new();
            if let Some(p) = &b.info.point {
                row.extend(p.iter().map(|v| v.to_string()));
            }
            row.extend([e.method.clone(), e.poses.clone()]);
            row.extend(cells(e));
            rows.push(row);
        }
    }
    (head, rows)
}

/// `report.md`: the tables a paper would print, and the plots.
pub fn report_md(r: &RunResult, summary: &Summary, plots_written: &[(String, String)]) -> String {
    let sc = &r.scenario;
    let first = &r.blocks[0].info;
    let mut s = String::new();
    let _ = writeln!(s, "# {}\n\n{}\n", sc.name, sc.description);
    let _ = writeln!(
        s,
        "Robot `{}`, {} trials from seed {}, {} measurement, registration `{}`, {} calibration and {} validation poses per trial. Identified parameters: {}.\n",
        first.robot,
        sc.trials,
        sc.seed,
        if first.full_pose { "full-pose" } else { "position" },
        sc.registration.as_str(),
        sc.calibration.count,
        sc.validation.count,
        first.params.iter().map(|p| format!("`{p}`")).collect::<Vec<_>>().join(", ")
    );
    if let Some(w) = summary.stopping.as_ref().and_then(|st| st.shortfall()) {
        let _ = writeln!(
            s,
            "**Warning:** {w}.
"
        );
    }
    let (h, rows) = claims::table(summary);
    if !rows.is_empty() {
        s += &noted_table("The paper's claims", claims::NOTE, &h, &rows);
        s += "\n";
    }
    let pose = first.full_pose;
    use columns::*;
    let mut cols = vec![ETA_MEAN, ETA_MEDIAN];
    cols.extend(validation_columns(pose));
    cols.extend([CRB_RATIO, FAILURES, EVALUATIONS, MS_PER_IDENTIFICATION]);
    let (headers, rows) = entry_table(r, &cols);
    let headers: Vec<&str> = headers.iter().map(String::as_str).collect();
    s += "## Validation errors and identification accuracy\n\n";
    s += "Validation errors are against the true (sagging) arm at fresh poses, free of tracker noise; each statistic is averaged over trials.\n\n";
    s += &table(&headers, &rows);
    let (headers, rows) = entry_table(r, &INTERVAL_COLUMNS);
    let headers: Vec<&str> = headers.iter().map(String::as_str).collect();
    s += "\n";
    s += &noted_table("Uncertainty over trials", INTERVAL_NOTE, &headers, &rows);
    let (h, rows) = comparisons::table(summary);
    if !rows.is_empty() {
        s += "\n";
        s += &noted_table("Paired comparisons", comparisons::NOTE, &h, &rows);
    }
    let (h, rows) = searches::table(r);
    if !rows.is_empty() {
        let h: Vec<&str> = h.iter().map(String::as_str).collect();
        s += "\n";
        s += &noted_table("Searches compared", searches::NOTE, &h, &rows);
    }
    if let Some(sw) = &sc.sweep {
        s += &sweep_tables(r, summary, sw);
    }
    s += "\n## Identification accuracy η per parameter (mean %, Guo 2024 eq. 29)\n\n";
    let (h, mut eta_rows) = eta_table(&r.blocks[0]);
    for row in &mut eta_rows {
        row[0] = format!("`{}`", row[0]);
    }
    let h: Vec<&str> = h.iter().map(String::as_str).collect();
    s += &table(&h, &eta_rows);
    if r.blocks.len() > 1 {
        s += "\n(η table of the first swept value.)\n";
    }
    if let Some((text, lines)) = not_determinable(&r.blocks[0]) {
        let _ = writeln!(s, "\n{text}\n");
        for l in lines {
            let _ = writeln!(s, "- {l}");
        }
    }
    s += "\n## Plots\n\n";
    for (file, caption) in plots_written {
        let _ = writeln!(s, "![{caption}]({file})\n");
    }
    s += "## What the metrics mean\n\n";
    for (term, text) in METRIC_NOTES {
        let _ = writeln!(s, "- **{term}**{text}");
    }
    s
}

/// The headline figures with their 95 % intervals (`report.md`, `report.html`).
pub const INTERVAL_COLUMNS: [Column; 8] = {
    use columns::*;
    [
        ETA_MEAN,
        ETA_MEAN_CI,
        ETA_MEDIAN,
        ETA_MEDIAN_CI,
        AFTER_MEAN,
        AFTER_MEAN_CI,
        AFTER_RMS,
        AFTER_RMS_CI,
    ]
};

/// What the intervals of the reports are (docs/formats.md "summary.json").
pub const INTERVAL_NOTE: &str = "95 % intervals of each figure over the Monte-Carlo trials: \
    the t interval of a mean (mean ± t₀.₉₇₅,ₙ₋₁ · s / √n), and for the median η a \
    simultaneous interval over the p parameters: the distribution-free interval of order \
    statistics of each parameter's median at level 1 − 0.05 / p (Bonferroni, so that all p \
    hold together with 95 %), averaged over the parameters — wider than a 95 % interval of \
    one parameter's median. A difference between two entries whose \
    intervals overlap may still be real: the entries share their draws, so a paired \
    comparison is far more precise.";

/// The metrics of a run's reports, each as its term and the rest of its explanation.
pub const METRIC_NOTES: [(&str, &str); 6] = [
    ("η", " = (1 − |x − x̂| / |x|) · 100 % per parameter with a non-zero injected error x (Guo 2024 eq. 29), counted where x is determinable (|x| above 3 Cramér–Rao σ); 100 % is exact recovery."),
    ("before / after", ": position error |Δp| at the validation poses of the nominal and of the compensated robot; mean (MAE), RMS, max."),
    ("improvement", " = (before − after) / before of the mean error."),
    ("CRB ratio", ": trace of the empirical covariance of the identified errors over trials divided by the mean Cramér–Rao trace (JᵀWJ)⁻¹ of the tracker noise; ≈ 1 for an efficient estimator under Gaussian noise, above 1 with outliers and sag."),
    (Metric::Failures.spec().field, ": identifications that diverged, were singular or gave non-finite values."),
    (Metric::Evaluations.spec().field, ": model evaluations per identification, mean over trials (residuals for the Jacobian methods, fitness eq. 14 for BAS, PSO and BAS-PSO): the budget each method spent."),
];

/// The bottom of the η-per-parameter chart (%): a mean η below it (the estimate's error
/// over three times the injected error) is cut at the axis with its value written.
pub const ETA_FLOOR_PCT: Real = -200.0;

/// The parameters of block `b` whose injected error was not determinable (docs/formats.md
/// `eta_not_determinable`): a sentence saying what that means, then one line per entry that
/// has any, naming each parameter and the trials it was not determinable in; `None` when no
/// entry has any.
pub fn not_determinable(b: &Block) -> Option<(String, Vec<String>)> {
    let lines: Vec<String> = b
        .entries
        .iter()
        .filter(|e| !e.eta_not_determinable.is_empty())
        .map(|e| {
            let each: Vec<String> = e
                .eta_not_determinable
                .iter()
                .map(|(p, n)| format!("{p} ({n} of {} trials)", n_usable(e)))
                .collect();
            format!("{}: {}", entry_label(e), each.join(", "))
        })
        .collect();
    (!lines.is_empty()).then(|| {
        let k = crate::study::crb::DETERMINABLE_SIGMAS;
        let text = format!(
            "Not determinable: an injected error of at most {k} Cramér–Rao σ of its parameter \
             (the tracker noise at the trial's calibration rows on the true robot) cannot be \
             told from 0, so its η measures the noise, and the error of a parameter that is \
             not estimable (the poses determine only a combination of it with others) can be \
             told only beyond the share of the whole injected error that the combination can \
             move onto it; those trials' η of the parameter is left out of every η figure, and \
             a parameter not determinable in any trial has no η."
        );
        (text, lines)
    })
}

/// The usable trials of entry `e` (its trials without the failed identifications).
fn n_usable(e: &Entry) -> usize {
    e.terminations.values().sum::<usize>() - e.failures
}

/// The η table of block `b`: headers (`parameter`, then one per entry) and one row per
/// parameter with the mean η of each entry (%).
pub fn eta_table(b: &Block) -> (Vec<String>, Vec<Vec<String>>) {
    let (params, series, _) = eta_by_parameter(b);
    let mut h = vec!["parameter".to_string()];
    h.extend(series.iter().map(|(label, _)| label.clone()));
    let rows = params
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut row = vec![p.clone()];
            row.extend(series.iter().map(|(_, eta)| fmt_num(eta[i], 4)));
            row
        })
        .collect();
    (h, rows)
}

/// The figure of `traces` against the iteration (`names` = stem, title, y label; log scale
/// with `log_y`) captioned `text`; none without traces.
fn trace_figure<'a>(
    names: (&'a str, &'a str, &'a str),
    traces: Vec<(String, Vec<Real>)>,
    log_y: bool,
    text: &str,
) -> Option<Figure<'a>> {
    if traces.is_empty() {
        return None;
    }
    let (stem, title, y_label) = names;
    Some(Figure::new(stem, text, move |p| {
        plots::traces(p, title, "iteration", y_label, &traces, log_y)
    }))
}

/// The run's figures, in the order `report.md` lists them.
pub fn figures<'a>(r: &'a RunResult, summary: &Summary) -> Vec<Figure<'a>> {
    let mut figs = Vec::new();
    let b0 = &r.blocks[0];
    let info = &b0.info;
    // η per parameter per method × strategy (Guo 2024 fig. 8), with its 95 % interval.
    let (params, series, intervals) = eta_by_parameter(b0);
    let intervals: Vec<Vec<Option<[Real; 2]>>> = intervals.into_iter().map(|(_, v)| v).collect();
    figs.push(Figure::new(
        Metric::Eta.spec().field,
        "η per parameter and method, with the 95 % interval of each parameter's mean (η below −200 % cut at the axis, its value written)",
        move |p| {
            plots::grouped_bars_with_floor(
                p,
                "Identification accuracy per parameter",
                "mean η (%) with its 95 % interval",
                &params,
                &series,
                &intervals,
                Some(ETA_FLOOR_PCT),
            )
        },
    ));
    // The headline figure of each entry with its 95 % interval.
    let entries: Vec<String> = b0.entries.iter().map(entry_label).collect();
    let rms = vec![(
        "mean validation RMS after compensation".to_string(),
        b0.entries
            .iter()
            .map(|e| e.validation_after_mm.rms)
            .collect::<Vec<Real>>(),
    )];
    let rms_ci = vec![b0
        .entries
        .iter()
        .map(|e| e.validation_after_mm.rms_ci95)
        .collect::<Vec<_>>()];
    figs.push(Figure::new(
        "headline_rms",
        "validation RMS after compensation per method and pose strategy, with the 95 % interval of each mean",
        move |p| {
            plots::grouped_bars_with_floor(
                p,
                "Validation RMS after compensation",
                "RMS (mm) with its 95 % interval",
                &entries,
                &rms,
                &rms_ci,
                None,
            )
        },
    ));
    // Validation error per point, trial 0, the first method and strategy (Li 2018 fig. 3).
    if let Some((si, mi, before, after)) = b0.trial0.as_ref().and_then(|t| t.per_point.as_ref()) {
        let title = format!(
            "Validation errors, trial 0, {} on {} poses",
            info.methods[*mi], info.strategies[*si]
        );
        // Full-pose data: the attitude errors of the same points (Qiao 2021 fig. 6).
        let attitude = b0
            .trial0
            .as_ref()
            .and_then(|t| t.per_point_attitude_deg.as_ref())
            .map(|(b, a)| {
                let title = format!("{title}: attitude");
                Figure::new(
                    "validation_trial0_attitude",
                    "validation attitude error per point before and after compensation, trial 0",
                    move |p| plots::before_after_in(p, &title, "attitude error (deg)", b, a),
                )
            });
        figs.push(Figure::new(
            "validation_trial0",
            "validation error per point before and after compensation, trial 0",
            move |p| plots::before_after(p, &title, before, after),
        ));
        figs.extend(attitude);
    }
    // Validation RMS over trials per method × strategy.
    let groups: Vec<(String, Vec<Real>)> = b0
        .entries
        .iter()
        .zip(&b0.after_rms)
        .map(|(e, v)| (entry_label(e), v.clone()))
        .collect();
    figs.push(Figure::new(
        "validation_rms",
        "validation RMS over trials",
        move |p| {
            plots::box_plot(
                p,
                "Validation RMS after compensation over trials",
                "RMS (mm)",
                &groups,
            )
        },
    ));
    // The paired comparisons' per-trial differences, each entry against its baseline.
    // With the estimate and interval of the test each verdict is judged on.
    for (stem, title, y_label, metric) in comparisons::DIFF_PLOTS {
        let shown: Vec<_> = summary
            .differences
            .iter()
            .filter(|d| d.metric == metric)
            .collect();
        let groups: Vec<(String, Vec<Real>)> = shown
            .iter()
            .map(|d| (d.label.clone(), d.values.clone()))
            .collect();
        let marks: Vec<Option<plots::Mark>> = shown.iter().map(|d| d.mark).collect();
        if !groups.is_empty() {
            figs.push(Figure::new(stem, title, move |p| {
                plots::box_plot_with_marks(p, title, y_label, &groups, &marks)
            }));
        }
    }
    // Objective traces of the optimised pose sets (Guo 2024 fig. 9).
    let traces: Vec<(String, Vec<Real>)> = info
        .strategies
        .iter()
        .zip(&info.fixed)
        .filter_map(|(s, f)| {
            f.as_ref()
                .filter(|f| !f.trace.is_empty())
                .map(|f| (s.clone(), f.trace.clone()))
        })
        .collect();
    figs.extend(trace_figure(
        (
            "objective_trace",
            "Pose-set objective per iteration",
            "objective",
        ),
        traces,
        false,
        "pose optimisation objective per iteration",
    ));
    // … and the metaheuristics' convergence (Qiao 2021 fig. 4).
    figs.extend(trace_figure(
        (
            "fitness_trace",
            "Best fitness per iteration, trial 0",
            "fitness (eq. 14)",
        ),
        b0.fitness_traces(),
        true,
        "metaheuristic convergence, trial 0",
    ));
    figs.extend(searches::figures(r));
    if let Some(sw) = &r.scenario.sweep {
        figs.extend(sweep_figures(r, summary, sw));
    }
    figs
}

/// The files of a run checked before it starts, by whoever writes it (`calbench run --out`,
/// `merge`, the Python module's `study.write`): none may be a folder, and none may be an
/// input of the run (a scenario named `scenario.toml` in the output folder). The plots are
/// checked before they land.
pub const OUTPUTS: [&str; 5] = [
    "summary.json",
    "trials.csv",
    "timing.json",
    "report.md",
    super::scenario_file::NAME,
];

/// [`OUTPUTS`] of a registration or instruments study (docs/formats.md § 4). An instruments
/// study's `report.html`, which a registration study does not write, is checked as a
/// Monte-Carlo run's is: with the plots, before they land.
pub const STUDY_OUTPUTS: [&str; 3] = ["summary.json", "report.md", super::scenario_file::NAME];

/// [`OUTPUTS`] of one shard of a Monte-Carlo study (`--shard I/N`, docs/formats.md § 4.4),
/// the files `merge` reads; a shard of a study of cells writes all but `trials.csv`.
pub const SHARD_OUTPUTS: [&str; 3] = ["trials.csv", "records.txt", "shard.json"];

/// The files a run checks before it starts ([`super::guard::guard_out`]): a whole
/// Monte-Carlo study's [`OUTPUTS`], a study of cells' [`STUDY_OUTPUTS`], a shard's
/// [`SHARD_OUTPUTS`]. A shard's folder and a whole run's hold other results, and the guard
/// refuses to write one into the other.
pub fn checked_outputs(monte_carlo: bool, shard: bool) -> &'static [&'static str] {
    match (monte_carlo, shard) {
        (true, false) => &OUTPUTS,
        (false, false) => &STUDY_OUTPUTS,
        (true, true) => &SHARD_OUTPUTS,
        (false, true) => &SHARD_OUTPUTS[1..],
    }
}

/// The files of a complete run but `trials.csv` (streamed as the trials finished,
/// [`TrialsCsv`]) and `report.html` ([`super::run_outputs`] adds it), in the order they are
/// written: `summary.json`, `timing.json`, `scenario.toml` ([`super::scenario_file`]), the
/// `figures` ([`figures`]), then `report.md`,
/// which shows them.
pub fn outputs<'a>(
    r: &'a RunResult,
    summary: &Summary,
    figures: Vec<Figure<'a>>,
) -> Result<Outputs<'a>> {
    let timing: Vec<Value> = r
        .blocks
        .iter()
        .flat_map(|b| {
            b.entries.iter().map(|e| {
                json!({"method": e.method, "poses": e.poses, "sweep_value": e.sweep_value,
                       "seconds_per_identification": e.seconds_per_identification})
            })
        })
        .collect();
    let timing = json!({"run_seconds": r.seconds, "results": timing});
    let listed: Vec<(String, String)> = figures.iter().map(Figure::listed).collect();
    let mut out: Outputs<'a> = vec![
        Box::new(Text {
            name: "summary.json",
            text: summary.to_json()?,
        }),
        Box::new(Text {
            name: "timing.json",
            text: json_text(&timing)?,
        }),
        Box::new(Text {
            name: super::scenario_file::NAME,
            text: super::scenario_file::text(&r.scenario)?,
        }),
    ];
    out.extend(figures.into_iter().map(|f| Box::new(f) as Box<dyn Output>));
    out.push(Box::new(Text {
        name: "report.md",
        text: report_md(r, summary, &listed),
    }));
    Ok(out)
}
