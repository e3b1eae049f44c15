//! The files of a run: `summary.json`, `trials.csv`, `report.md` and the plots (docs/formats.md
//! `run`). Writers only read results that are already computed.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use super::markdown::{fmt_num, table};
use super::plots;
use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::study::scenario::Sweep;
use crate::study::stats::{eta, Entry};
use crate::study::{toml_to_json, Block, BlockInfo, RunResult, TrialResult, TrialSink};

fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}

/// `v` as pretty-printed JSON with a final newline: the text of the JSON files.
pub fn json_text(v: &Value) -> Result<String> {
    let s = serde_json::to_string_pretty(v).map_err(|e| Error::Compute(e.to_string()))?;
    Ok(s + "\n")
}

/// Writes `v` as [`json_text`].
fn write_json(path: &Path, v: &Value) -> Result<()> {
    write(path, &json_text(v)?)
}

/// The metaheuristics' best fitness per iteration in trial 0 (Qiao 2021 fig. 4), labelled
/// `method / poses`.
fn fitness_traces(b: &Block) -> Vec<(String, Vec<Real>)> {
    b.trial0
        .as_ref()
        .map(|t| {
            t.traces
                .iter()
                .map(|(si, mi, tr)| {
                    let label = format!("{} / {}", b.info.methods[*mi], b.info.strategies[*si]);
                    (label, tr.clone())
                })
                .collect()
        })
        .unwrap_or_default()
}

/// The label of a results entry in tables and plots: `method / poses`.
fn entry_label(e: &Entry) -> String {
    format!("{} / {}", e.method, e.poses)
}

/// The parameters with an η (those of the first entry) and, per entry of `b`, its label and
/// mean η of each of those parameters (NaN where it has none).
fn eta_by_parameter(b: &Block) -> (Vec<String>, Vec<(String, Vec<Real>)>) {
    let params: Vec<String> = b
        .entries
        .first()
        .map(|e| e.eta.keys().cloned().collect())
        .unwrap_or_default();
    let series = b
        .entries
        .iter()
        .map(|e| {
            let eta = params
                .iter()
                .map(|p| e.eta.get(p).map_or(Real::NAN, |x| x.mean))
                .collect();
            (entry_label(e), eta)
        })
        .collect();
    (params, series)
}

/// The relative distance from the final objective within which a pose optimisation counts
/// as settled (`settled_iteration` in `summary.json`).
pub const SETTLED: Real = 1e-3;

/// The first iteration (1-based) from which the objective `trace` stays within `rel` of
/// its final value (relative to it): the iteration count at which an objective curve such
/// as Guo 2024 fig. 6 flattens. `None` for an empty trace.
pub fn settled_iteration(trace: &[Real], rel: Real) -> Option<usize> {
    let last = *trace.last()?;
    let tol = rel * last.abs();
    let outside = trace.iter().rposition(|v| (v - last).abs() > tol);
    Some(outside.map_or(1, |i| i + 2))
}

/// `summary.json` as a JSON value.
pub fn summary(r: &RunResult) -> Value {
    let sc = &r.scenario;
    let first = &r.blocks[0].info;
    let mut optimised = serde_json::Map::new();
    for (si, s) in first.strategies.iter().enumerate() {
        if let Some(set) = &first.fixed[si] {
            optimised.insert(
                s.clone(),
                json!({"poses": set.poses, "iterations": set.trace.len(),
                       "final_objective": set.trace.last(), "scores": set.scores,
                       "trace": set.trace,
                       "settled_iteration": settled_iteration(&set.trace, SETTLED)}),
            );
        }
    }
    let results: Vec<Value> = r
        .blocks
        .iter()
        .flat_map(|b| {
            b.entries
                .iter()
                .map(|e| serde_json::to_value(e).unwrap_or(Value::Null))
        })
        .collect();
    let b0 = &r.blocks[0];
    let mut convergence = serde_json::Map::new();
    for (label, trace) in fitness_traces(b0) {
        convergence.insert(label, json!(trace));
    }
    let mut s = json!({
        "scenario": sc.name,
        "description": sc.description,
        "robot": first.robot,
        "trials": sc.trials,
        "seed": sc.seed,
        "measure": if first.full_pose { "pose" } else { "position" },
        "registration": sc.registration.as_str(),
        "parameters": first.params,
        "error_parameters": first.error_params,
        "fixed_pose_sets": optimised,
        "fitness_trace_trial0": convergence,
        "timing": "timing.json",
        "results": results,
    });
    if let Some(sep) = &first.separation {
        s["separation"] = sep.clone();
    }
    // The simulated arm's compliances, from the first sweep point that sags.
    if let Some(c) = r
        .blocks
        .iter()
        .find_map(|b| b.info.true_compliance.as_ref())
    {
        s["true_compliance"] = c.clone();
    }
    if let Some(sw) = &sc.sweep {
        if let [axis] = sw.axes.as_slice() {
            s["sweep_key"] = json!(axis.key);
            s["sweep_values"] = Value::Array(axis.values.iter().map(toml_to_json).collect());
        }
        s["sweep_keys"] = json!(sw.keys());
        s["sweep_zip"] = json!(sw.zip);
    }
    s
}

fn num(v: Real) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// A column of a results table: its header and how an entry fills it.
pub type Column = (&'static str, fn(&Entry) -> String);

/// The columns of the results tables (the printed one and the report's take these in
/// different selections).
pub mod columns {
    use super::{fmt_num, Column, Real};

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
                .get("validation_after_deg")
                .map_or(Real::NAN, |d| d.mean),
            4,
        )
    });
    /// Ratio to the Cramér–Rao bound.
    pub const CRB_RATIO: Column = ("CRB ratio", |e| {
        fmt_num(e.crb_ratio.unwrap_or(Real::NAN), 3)
    });
    /// Failed identifications.
    pub const FAILURES: Column = ("failures", |e| e.failures.to_string());
    /// Mean model evaluations per identification (the budget spent).
    pub const EVALUATIONS: Column = ("evaluations", |e| fmt_num(e.evaluations_mean, 5));
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

/// `trials.csv`, written as trials finish: one row per trial × strategy × method (× sweep
/// point), in trial order. The header comes from the first block; one axis adds the column
/// `sweep_value`, a grid one column per swept key. It goes to a file ([`TrialsCsv::create`])
/// or, for a run held in memory, to bytes ([`TrialsCsv::in_memory`]): the same bytes.
pub struct TrialsCsv<W: std::io::Write = std::io::BufWriter<std::fs::File>> {
    path: PathBuf,
    out: W,
    sweep_columns: Vec<String>,
    header: bool,
}

impl TrialsCsv {
    /// Creates `path` for the trials of a run of a scenario with `sweep`.
    pub fn create(path: &Path, sweep: Option<&Sweep>) -> Result<TrialsCsv> {
        let file = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
        Ok(TrialsCsv::to(path, std::io::BufWriter::new(file), sweep))
    }
}

impl TrialsCsv<Vec<u8>> {
    /// `trials.csv` of a run of a scenario with `sweep`, kept in memory.
    pub fn in_memory(sweep: Option<&Sweep>) -> TrialsCsv<Vec<u8>> {
        TrialsCsv::to(Path::new("trials.csv"), Vec::new(), sweep)
    }

    /// The bytes written.
    pub fn into_bytes(self) -> Vec<u8> {
        self.out
    }
}

impl<W: std::io::Write> TrialsCsv<W> {
    fn to(path: &Path, out: W, sweep: Option<&Sweep>) -> TrialsCsv<W> {
        let sweep_columns = match sweep {
            None => Vec::new(),
            Some(sw) if sw.axes.len() == 1 => vec!["sweep_value".into()],
            Some(sw) => sw.axes.iter().map(|a| a.key.clone()).collect(),
        };
        TrialsCsv {
            path: path.to_path_buf(),
            out,
            sweep_columns,
            header: false,
        }
    }

    /// Flushes the file.
    pub fn finish(mut self) -> Result<()> {
        self.out.flush().map_err(|e| Error::io(&self.path, e))
    }

    fn header(&self, info: &BlockInfo) -> String {
        let mut head = vec!["trial".to_string()];
        head.extend(self.sweep_columns.iter().cloned());
        head.extend(
            [
                "method",
                "poses",
                "eta_mean_pct",
                "before_mean_mm",
                "before_rms_mm",
                "before_max_mm",
                "after_mean_mm",
                "after_rms_mm",
                "after_max_mm",
            ]
            .map(String::from),
        );
        if info.full_pose {
            head.extend(
                [
                    "before_mean_deg",
                    "before_rms_deg",
                    "after_mean_deg",
                    "after_rms_deg",
                ]
                .map(String::from),
            );
        }
        head.extend(["iterations", "termination"].map(String::from));
        head.extend(info.params.iter().map(|n| format!("true_{n}")));
        head.extend(info.params.iter().map(|n| format!("identified_{n}")));
        if info.external {
            head.push("error".into());
        }
        head.join(",") + "\n"
    }
}

impl<W: std::io::Write> TrialSink for TrialsCsv<W> {
    fn trial(&mut self, info: &BlockInfo, t: &TrialResult) -> Result<()> {
        let mut out = String::new();
        if !self.header {
            out += &self.header(info);
            self.header = true;
        }
        for o in &t.outcomes {
            let mut row = vec![t.index.to_string()];
            if let Some(p) = &info.point {
                row.extend(p.iter().map(|v| v.to_string().replace(',', ";")));
            }
            let etas: Vec<Real> = t
                .truth
                .iter()
                .zip(&o.identified)
                .filter_map(|(&x, &y)| eta(x, y))
                .collect();
            let eta_mean = if etas.is_empty() {
                Real::NAN
            } else {
                etas.iter().sum::<Real>() / etas.len() as Real
            };
            row.push(info.methods[o.method].clone());
            row.push(info.strategies[o.strategy].clone());
            for v in [
                eta_mean,
                o.before_mm.mean,
                o.before_mm.rms,
                o.before_mm.max,
                o.after_mm.mean,
                o.after_mm.rms,
                o.after_mm.max,
            ] {
                row.push(num(v));
            }
            if info.full_pose {
                let (bd, ad) = (
                    o.optional.validation_before_deg.unwrap_or_default(),
                    o.optional.validation_after_deg.unwrap_or_default(),
                );
                for v in [bd.mean, bd.rms, ad.mean, ad.rms] {
                    row.push(num(v));
                }
            }
            row.push(o.iterations.to_string());
            row.push(o.termination.as_str().into());
            row.extend(t.truth.iter().map(|&v| num(v)));
            row.extend(o.identified.iter().map(|&v| num(v)));
            if info.external {
                row.push(csv_text(o.error.as_deref().unwrap_or("")));
            }
            out += &row.join(",");
            out.push('\n');
        }
        self.out
            .write_all(out.as_bytes())
            .map_err(|e| Error::io(&self.path, e))
    }
}

/// `text` as one CSV field: quoted (inner quotes doubled) when it holds a comma, a quote or
/// a line break.
fn csv_text(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// `report.md`: the tables a paper would print, and the plots.
pub fn report_md(r: &RunResult, plots_written: &[(String, String)]) -> String {
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
    if let Some(sw) = &sc.sweep {
        s += &sweep_tables(r, sw);
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

/// The metrics of a run's reports, each as its term and the rest of its explanation.
pub const METRIC_NOTES: [(&str, &str); 6] = [
    ("η", " = (1 − |x − x̂| / |x|) · 100 % per parameter with a non-zero injected error x (Guo 2024 eq. 29); 100 % is exact recovery."),
    ("before / after", ": position error |Δp| at the validation poses of the nominal and of the compensated robot; mean (MAE), RMS, max."),
    ("improvement", " = (before − after) / before of the mean error."),
    ("CRB ratio", ": trace of the empirical covariance of the identified errors over trials divided by the mean Cramér–Rao trace (JᵀWJ)⁻¹ of the tracker noise; ≈ 1 for an efficient estimator under Gaussian noise, above 1 with outliers and sag."),
    ("failures", ": identifications that diverged, were singular or gave non-finite values."),
    ("evaluations", ": model evaluations per identification, mean over trials (residuals for the Jacobian methods, fitness eq. 14 for BAS, PSO and BAS-PSO): the budget each method spent."),
];

/// The η table of block `b`: headers (`parameter`, then one per entry) and one row per
/// parameter with the mean η of each entry (%).
pub fn eta_table(b: &Block) -> (Vec<String>, Vec<Vec<String>>) {
    let (params, series) = eta_by_parameter(b);
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

/// The sweep section of `report.md`: the headline metrics per sweep point, and for a
/// two-axis grid the validation RMS after compensation of each method and strategy as a
/// table of the first axis (rows) against the second (columns).
fn sweep_tables(r: &RunResult, sw: &Sweep) -> String {
    use columns::*;
    let mut s = String::from("\n## Sweep\n\n");
    let _ = writeln!(
        s,
        "Swept: {}{}.\n",
        sw.keys()
            .iter()
            .map(|k| format!("`{k}`"))
            .collect::<Vec<_>>()
            .join(", "),
        if sw.zip { " (paired)" } else { "" }
    );
    let (headers, rows) = entry_table(
        r,
        &[AFTER_RMS, ETA_MEDIAN, CRB_RATIO, MS_PER_IDENTIFICATION],
    );
    let headers: Vec<&str> = headers.iter().map(String::as_str).collect();
    s += &table(&headers, &rows);
    if sw.dims() == 2 {
        let (xa, ya) = (&sw.axes[0], &sw.axes[1]);
        for (k, e) in r.blocks[0].entries.iter().enumerate() {
            let _ = writeln!(
                s,
                "\nValidation RMS after (mm), {}: `{}` down, `{}` across.\n",
                entry_label(e),
                xa.key,
                ya.key
            );
            let mut h = vec![String::new()];
            h.extend(ya.values.iter().map(|v| v.to_string()));
            let h: Vec<&str> = h.iter().map(String::as_str).collect();
            let rows: Vec<Vec<String>> = xa
                .values
                .iter()
                .enumerate()
                .map(|(i, xv)| {
                    let mut row = vec![xv.to_string()];
                    row.extend((0..ya.values.len()).map(|j| {
                        r.blocks
                            .get(i * ya.values.len() + j)
                            .map_or(String::new(), |b| {
                                fmt_num(b.entries[k].validation_after_mm.rms, 4)
                            })
                    }));
                    row
                })
                .collect();
            s += &table(&h, &rows);
        }
    }
    s
}

/// A sweep value as a plot position: the number itself, or `None` (then the plots place the
/// values at their list positions).
fn numeric(v: &toml::Value) -> Option<Real> {
    v.as_float().or(v.as_integer().map(|i| i as Real))
}

/// The headline metrics of the sweep plots: file stem, title, y label, value and spread
/// over trials of an entry.
type SweepMetric = (
    &'static str,
    &'static str,
    &'static str,
    fn(&Entry) -> (Real, Real),
);

const SWEEP_METRICS: [SweepMetric; 4] = [
    (
        "sweep_validation_rms",
        "Validation RMS after compensation (± 1 s.d. over trials)",
        "RMS (mm)",
        |e| (e.validation_after_mm.rms, e.spread.after_rms),
    ),
    (
        "sweep_eta_median",
        "Identification accuracy: median η (± mean s.d. of η)",
        "median η (%)",
        |e| (e.eta_median_pct, e.spread.eta),
    ),
    (
        "sweep_crb_ratio",
        "Parameter covariance over the Cramér–Rao bound",
        "CRB ratio",
        |e| (e.crb_ratio.unwrap_or(Real::NAN), Real::NAN),
    ),
    (
        "sweep_seconds",
        "Wall time per identification (± 1 s.d.)",
        "time (s)",
        |e| (e.seconds_per_identification, e.spread.seconds),
    ),
];

/// The sweep plots: for one axis (or paired axes) each headline metric against the swept
/// value, one line per method × strategy with its spread; for a two-axis grid a heat map of
/// the validation RMS after compensation per method × strategy.
fn write_sweep_plots(r: &RunResult, sw: &Sweep, out: &Path) -> Result<Vec<(String, String)>> {
    let mut done = Vec::new();
    let b0 = &r.blocks[0];
    if sw.dims() == 1 {
        let axis = &sw.axes[0];
        // Zipped axes move together: the x axis numbers the points and names every key.
        let zipped = sw.axes.len() > 1;
        let numbers: Option<Vec<Real>> = if zipped {
            None
        } else {
            axis.values.iter().map(numeric).collect()
        };
        let keys = sw.keys().join(" + ");
        let (xs, x_label) = match numbers {
            Some(v) => (v, axis.key.clone()),
            None => (
                (0..axis.values.len()).map(|i| i as Real).collect(),
                format!(
                    "{keys} (value no.: {})",
                    (0..axis.values.len())
                        .map(|i| {
                            let vals: Vec<String> =
                                sw.axes.iter().map(|a| a.values[i].to_string()).collect();
                            if zipped {
                                format!("{i} = ({})", vals.join(", "))
                            } else {
                                format!("{i} = {}", vals[0])
                            }
                        })
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ),
        };
        for (stem, title, y_label, metric) in SWEEP_METRICS {
            let series: Vec<plots::SweepSeries> = b0
                .entries
                .iter()
                .enumerate()
                .map(|(k, e)| {
                    let pts = r
                        .blocks
                        .iter()
                        .zip(&xs)
                        .map(|(b, &x)| {
                            let (m, sd) = metric(&b.entries[k]);
                            (x, m, sd)
                        })
                        .collect();
                    (entry_label(e), pts)
                })
                .collect();
            plots::sweep(&out.join(stem), title, &x_label, y_label, &series)?;
            done.push((format!("{stem}.png"), format!("{title} against {keys}")));
        }
    } else if sw.dims() == 2 {
        let (xa, ya) = (&sw.axes[0], &sw.axes[1]);
        let names = |a: &crate::study::scenario::SweepAxis| -> Vec<String> {
            a.values.iter().map(|v| v.to_string()).collect()
        };
        let (xn, yn) = (names(xa), names(ya));
        for (k, e) in b0.entries.iter().enumerate() {
            let values: Vec<Vec<Real>> = (0..xa.values.len())
                .map(|i| {
                    (0..ya.values.len())
                        .map(|j| {
                            r.blocks
                                .get(i * ya.values.len() + j)
                                .map_or(Real::NAN, |b| b.entries[k].validation_after_mm.rms)
                        })
                        .collect()
                })
                .collect();
            let stem = format!("heatmap_{}_{}", file_safe(&e.method), file_safe(&e.poses));
            plots::heatmap(
                &out.join(&stem),
                &format!("Validation RMS after compensation (mm), {}", entry_label(e)),
                (&xa.key, &xn),
                (&ya.key, &yn),
                &values,
            )?;
            done.push((
                format!("{stem}.png"),
                format!(
                    "validation RMS after, {}, over {} and {}",
                    entry_label(e),
                    xa.key,
                    ya.key
                ),
            ));
        }
    }
    Ok(done)
}

/// `s` with every character outside `[A-Za-z0-9._-]` replaced by `_` (a file name part).
fn file_safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Records the PNG `<stem>.png` with its caption.
fn caption(done: &mut Vec<(String, String)>, stem: &str, text: &str) {
    done.push((format!("{stem}.png"), text.to_string()));
}

/// Plots `traces` against the iteration as `<stem>.png` / `.svg` (`names` = stem, title,
/// y label; log scale with `log_y`) and records it with `text`; nothing without traces.
fn trace_plot(
    out: &Path,
    done: &mut Vec<(String, String)>,
    names: (&str, &str, &str),
    traces: &[(String, Vec<Real>)],
    log_y: bool,
    text: &str,
) -> Result<()> {
    if traces.is_empty() {
        return Ok(());
    }
    let (stem, title, y_label) = names;
    plots::traces(&out.join(stem), title, "iteration", y_label, traces, log_y)?;
    caption(done, stem, text);
    Ok(())
}

/// Renders the plots; returns (file name, caption) of each PNG.
pub fn write_plots(r: &RunResult, out: &Path) -> Result<Vec<(String, String)>> {
    let mut done = Vec::new();
    let b0 = &r.blocks[0];
    let info = &b0.info;
    // η per parameter per method × strategy (Guo 2024 fig. 8).
    let (params, series) = eta_by_parameter(b0);
    plots::grouped_bars(
        &out.join("eta"),
        "Identification accuracy per parameter",
        "mean η (%)",
        &params,
        &series,
    )?;
    caption(&mut done, "eta", "η per parameter and method");
    // Validation error per point, trial 0, the first method and strategy (Li 2018 fig. 3).
    if let Some((si, mi, before, after)) = b0.trial0.as_ref().and_then(|t| t.per_point.as_ref()) {
        let title = format!(
            "Validation errors, trial 0, {} on {} poses",
            info.methods[*mi], info.strategies[*si]
        );
        plots::before_after(&out.join("validation_trial0"), &title, before, after)?;
        caption(
            &mut done,
            "validation_trial0",
            "validation error per point before and after compensation, trial 0",
        );
        // Full-pose data: the attitude errors of the same points (Qiao 2021 fig. 6).
        if let Some((b, a)) = b0
            .trial0
            .as_ref()
            .and_then(|t| t.per_point_attitude_deg.as_ref())
        {
            plots::before_after_in(
                &out.join("validation_trial0_attitude"),
                &format!("{title}: attitude"),
                "attitude error (deg)",
                b,
                a,
            )?;
            caption(
                &mut done,
                "validation_trial0_attitude",
                "validation attitude error per point before and after compensation, trial 0",
            );
        }
    }
    // Validation RMS over trials per method × strategy.
    let groups: Vec<(String, Vec<Real>)> = b0
        .entries
        .iter()
        .zip(&b0.after_rms)
        .map(|(e, v)| (entry_label(e), v.clone()))
        .collect();
    plots::box_plot(
        &out.join("validation_rms"),
        "Validation RMS after compensation over trials",
        "RMS (mm)",
        &groups,
    )?;
    caption(&mut done, "validation_rms", "validation RMS over trials");
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
    // … and the metaheuristics' convergence (Qiao 2021 fig. 4).
    let fit = fitness_traces(b0);
    for (names, series, log_y, text) in [
        (
            (
                "objective_trace",
                "Pose-set objective per iteration",
                "objective",
            ),
            &traces,
            false,
            "pose optimisation objective per iteration",
        ),
        (
            (
                "fitness_trace",
                "Best fitness per iteration, trial 0",
                "fitness (eq. 14)",
            ),
            &fit,
            true,
            "metaheuristic convergence, trial 0",
        ),
    ] {
        trace_plot(out, &mut done, names, series, log_y, text)?;
    }
    if let Some(sw) = &r.scenario.sweep {
        done.extend(write_sweep_plots(r, sw, out)?);
    }
    Ok(done)
}

/// Writes every file of a complete run but `trials.csv` (written as the trials finished) and
/// `report.html` ([`super::write_run`]) into the folder `dir`; returns the plots written
/// (file name, caption), as `report.md` lists them.
pub fn write_into(r: &RunResult, dir: &Path) -> Result<Vec<(String, String)>> {
    write_json(&dir.join("summary.json"), &summary(r))?;
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
    write_json(
        &dir.join("timing.json"),
        &json!({"run_seconds": r.seconds, "results": timing}),
    )?;
    let plots = write_plots(r, dir)?;
    write(&dir.join("report.md"), &report_md(r, &plots))?;
    Ok(plots)
}

#[cfg(test)]
mod tests {
    use super::settled_iteration;

    #[test]
    fn settled_iteration_is_where_the_curve_stays_near_its_end() {
        assert_eq!(settled_iteration(&[], 1e-3), None);
        assert_eq!(settled_iteration(&[2.0], 1e-3), Some(1));
        // Within 0.1 % of 2.0 from the fourth value on (1.9985 is 0.075 % away).
        let t = [1.0, 1.5, 1.99, 1.9985, 1.9995, 2.0];
        assert_eq!(settled_iteration(&t, 1e-3), Some(4));
        // A dip after settling counts as not settled yet.
        let t = [1.0, 2.0, 1.0, 2.0];
        assert_eq!(settled_iteration(&t, 1e-3), Some(4));
    }
}
