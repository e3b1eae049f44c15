//! The files of a run: `summary.json`, `trials.csv`, `report.md` and the plots (FORMATS.md
//! `run`). Writers only read results that are already computed.

use std::fmt::Write as _;
use std::path::Path;

use serde_json::{json, Value};

use super::markdown::{fmt_num, table};
use super::plots;
use crate::error::{Error, Result};
use crate::math::Real;
use crate::montecarlo::stats::{eta, Entry};
use crate::montecarlo::{toml_to_json, Block, RunResult};

fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}

/// Writes `v` as pretty-printed JSON with a final newline.
fn write_json(path: &Path, v: &Value) -> Result<()> {
    let s = serde_json::to_string_pretty(v).map_err(|e| Error::Compute(e.to_string()))?;
    write(path, &(s + "\n"))
}

/// The metaheuristics' best fitness per iteration in trial 0 (Qiao 2021 fig. 4), labelled
/// `method / poses`.
fn fitness_traces(b: &Block) -> Vec<(String, Vec<Real>)> {
    let sc = &b.study.scenario;
    b.trials
        .first()
        .map(|t| {
            t.outcomes
                .iter()
                .filter_map(|o| {
                    o.trace.as_ref().map(|tr| {
                        let label = format!(
                            "{} / {}",
                            sc.methods[o.method].label,
                            sc.calibration.strategies[o.strategy].name()
                        );
                        (label, tr.clone())
                    })
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

/// `summary.json` as a JSON value.
pub fn summary(r: &RunResult) -> Value {
    let sc = &r.scenario;
    let first = &r.blocks[0].study;
    let mut optimised = serde_json::Map::new();
    for (si, s) in first.scenario.calibration.strategies.iter().enumerate() {
        if let Some(set) = &first.fixed[si] {
            optimised.insert(
                s.name().to_string(),
                json!({"poses": set.poses.len(), "iterations": set.trace.len(),
                       "final_objective": set.trace.last(), "scores": set.scores}),
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
        "robot": first.nominal.name,
        "trials": sc.trials,
        "seed": sc.seed,
        "measure": match first.measure { crate::jacobian::Measure::Position => "position", crate::jacobian::Measure::Pose => "pose" },
        "registration": sc.registration.as_str(),
        "parameters": first.params.iter().map(|p| p.to_string()).collect::<Vec<_>>(),
        "error_parameters": first.error_params.iter().map(|p| p.to_string()).collect::<Vec<_>>(),
        "fixed_pose_sets": optimised,
        "fitness_trace_trial0": convergence,
        "timing": "timing.json",
        "results": results,
    });
    if let Some(sw) = &sc.sweep {
        s["sweep_key"] = json!(sw.key);
        s["sweep_values"] = Value::Array(sw.values.iter().map(toml_to_json).collect());
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
        fmt_num(e.validation_before_deg.map_or(Real::NAN, |d| d.mean), 4)
    });
    /// Mean orientation error after compensation (full pose).
    pub const AFTER_DEG: Column = ("after mean °", |e| {
        fmt_num(e.validation_after_deg.map_or(Real::NAN, |d| d.mean), 4)
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

/// The headers and rows of a table with one row per results entry: the swept value (for
/// sweeps), the method, the poses, then `columns`.
pub fn entry_table(r: &RunResult, columns: &[Column]) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let mut headers = Vec::new();
    if r.scenario.sweep.is_some() {
        headers.push("swept value");
    }
    headers.extend(["method", "poses"]);
    headers.extend(columns.iter().map(|c| c.0));
    let mut rows = Vec::new();
    for b in &r.blocks {
        for e in &b.entries {
            let mut row = Vec::new();
            if let Some(v) = &b.sweep_value {
                row.push(v.to_string());
            }
            row.extend([e.method.clone(), e.poses.clone()]);
            row.extend(columns.iter().map(|c| (c.1)(e)));
            rows.push(row);
        }
    }
    (headers, rows)
}

/// `trials.csv`: one row per trial × strategy × method (× swept value).
pub fn trials_csv(r: &RunResult) -> String {
    let first = &r.blocks[0].study;
    let names: Vec<String> = first.params.iter().map(|p| p.to_string()).collect();
    let pose = first.measure == crate::jacobian::Measure::Pose;
    let mut head = vec!["trial".to_string()];
    if r.scenario.sweep.is_some() {
        head.push("sweep_value".into());
    }
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
    if pose {
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
    head.extend(names.iter().map(|n| format!("true_{n}")));
    head.extend(names.iter().map(|n| format!("identified_{n}")));
    let mut out = head.join(",") + "\n";
    for b in &r.blocks {
        let sc = &b.study.scenario;
        for t in &b.trials {
            for o in &t.outcomes {
                let mut row = vec![t.index.to_string()];
                if let Some(v) = &b.sweep_value {
                    row.push(v.to_string().replace(',', ";"));
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
                row.push(sc.methods[o.method].label.clone());
                row.push(sc.calibration.strategies[o.strategy].name().into());
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
                if pose {
                    let (bd, ad) = (
                        o.before_deg.unwrap_or_default(),
                        o.after_deg.unwrap_or_default(),
                    );
                    for v in [bd.mean, bd.rms, ad.mean, ad.rms] {
                        row.push(num(v));
                    }
                }
                row.push(o.iterations.to_string());
                row.push(o.termination.as_str().into());
                row.extend(t.truth.iter().map(|&v| num(v)));
                row.extend(o.identified.iter().map(|&v| num(v)));
                out += &row.join(",");
                out.push('\n');
            }
        }
    }
    out
}

/// `report.md`: the tables a paper would print, and the plots.
pub fn report_md(r: &RunResult, plots_written: &[(String, String)]) -> String {
    let sc = &r.scenario;
    let first = &r.blocks[0].study;
    let mut s = String::new();
    let _ = writeln!(s, "# {}\n\n{}\n", sc.name, sc.description);
    let _ = writeln!(
        s,
        "Robot `{}`, {} trials from seed {}, {} measurement, registration `{}`, {} calibration and {} validation poses per trial. Identified parameters: {}.\n",
        first.nominal.name,
        sc.trials,
        sc.seed,
        if first.measure == crate::jacobian::Measure::Pose { "full-pose" } else { "position" },
        sc.registration.as_str(),
        sc.calibration.count,
        sc.validation.count,
        first.params.iter().map(|p| format!("`{p}`")).collect::<Vec<_>>().join(", ")
    );
    let pose = first.measure == crate::jacobian::Measure::Pose;
    use columns::*;
    let mut cols = vec![
        ETA_MEAN,
        ETA_MEDIAN,
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
    cols.extend([CRB_RATIO, FAILURES, EVALUATIONS, MS_PER_IDENTIFICATION]);
    let (headers, rows) = entry_table(r, &cols);
    s += "## Validation errors and identification accuracy\n\n";
    s += "Validation errors are against the true (sagging) arm at fresh poses, free of tracker noise; each statistic is averaged over trials.\n\n";
    s += &table(&headers, &rows);
    s += "\n## Identification accuracy η per parameter (mean %, Guo 2024 eq. 29)\n\n";
    let (params, series) = eta_by_parameter(&r.blocks[0]);
    let mut h: Vec<&str> = vec!["parameter"];
    h.extend(series.iter().map(|(label, _)| label.as_str()));
    let eta_rows: Vec<Vec<String>> = params
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut row = vec![format!("`{p}`")];
            row.extend(series.iter().map(|(_, eta)| fmt_num(eta[i], 4)));
            row
        })
        .collect();
    s += &table(&h, &eta_rows);
    if r.blocks.len() > 1 {
        s += "\n(η table of the first swept value.)\n";
    }
    s += "\n## Plots\n\n";
    for (file, caption) in plots_written {
        let _ = writeln!(s, "![{caption}]({file})\n");
    }
    s += "## What the metrics mean\n\n";
    s += "- **η** = (1 − |x − x̂| / |x|) · 100 % per parameter with a non-zero injected error x (Guo 2024 eq. 29); 100 % is exact recovery.\n";
    s += "- **before / after**: position error |Δp| at the validation poses of the nominal and of the compensated robot; mean (MAE), RMS, max.\n";
    s += "- **improvement** = (before − after) / before of the mean error.\n";
    s += "- **CRB ratio**: trace of the empirical covariance of the identified errors over trials divided by the mean Cramér–Rao trace (JᵀWJ)⁻¹ of the tracker noise; ≈ 1 for an efficient estimator under Gaussian noise, above 1 with outliers and sag.\n";
    s +=
        "- **failures**: identifications that diverged, were singular or gave non-finite values.\n";
    s += "- **evaluations**: model evaluations per identification, mean over trials (residuals for the Jacobian methods, fitness eq. 14 for BAS, PSO and BAS-PSO): the budget each method spent.\n";
    s
}

/// Renders the plots; returns (file name, caption) of each PNG.
pub fn write_plots(r: &RunResult, out: &Path) -> Result<Vec<(String, String)>> {
    let mut done = Vec::new();
    let b0 = &r.blocks[0];
    // η per parameter per method × strategy (Guo 2024 fig. 8).
    let (params, series) = eta_by_parameter(b0);
    plots::grouped_bars(
        &out.join("eta"),
        "Identification accuracy per parameter",
        "mean η (%)",
        &params,
        &series,
    )?;
    done.push(("eta.png".into(), "η per parameter and method".into()));
    // Validation error per point, trial 0, the first method and strategy (Li 2018 fig. 3).
    if let Some(o) = b0.trials.first().and_then(|t| t.outcomes.first()) {
        if let Some((before, after)) = &o.per_point {
            let sc = &b0.study.scenario;
            let title = format!(
                "Validation errors, trial 0, {} on {} poses",
                sc.methods[o.method].label,
                sc.calibration.strategies[o.strategy].name()
            );
            plots::before_after(&out.join("validation_trial0"), &title, before, after)?;
            done.push((
                "validation_trial0.png".into(),
                "validation error per point before and after compensation, trial 0".into(),
            ));
        }
    }
    // Validation RMS over trials per method × strategy.
    let groups: Vec<(String, Vec<Real>)> = b0
        .entries
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let (si, mi) = (
                k / b0.study.scenario.methods.len(),
                k % b0.study.scenario.methods.len(),
            );
            let v = b0
                .trials
                .iter()
                .flat_map(|t| {
                    t.outcomes
                        .iter()
                        .filter(|o| o.strategy == si && o.method == mi)
                        .map(|o| o.after_mm.rms)
                })
                .collect();
            (entry_label(e), v)
        })
        .collect();
    plots::box_plot(
        &out.join("validation_rms"),
        "Validation RMS after compensation over trials",
        "RMS (mm)",
        &groups,
    )?;
    done.push((
        "validation_rms.png".into(),
        "validation RMS over trials".into(),
    ));
    // Objective traces of the optimised pose sets (Guo 2024 fig. 9).
    let traces: Vec<(String, Vec<Real>)> = b0
        .study
        .scenario
        .calibration
        .strategies
        .iter()
        .zip(&b0.study.fixed)
        .filter_map(|(s, f)| {
            f.as_ref()
                .filter(|f| !f.trace.is_empty())
                .map(|f| (s.name().to_string(), f.trace.clone()))
        })
        .collect();
    if !traces.is_empty() {
        plots::traces(
            &out.join("objective_trace"),
            "Pose-set objective per iteration",
            "iteration",
            "objective",
            &traces,
            false,
        )?;
        done.push((
            "objective_trace.png".into(),
            "pose optimisation objective per iteration".into(),
        ));
    }
    // Metaheuristics' convergence (Qiao 2021 fig. 4).
    let fit = fitness_traces(b0);
    if !fit.is_empty() {
        plots::traces(
            &out.join("fitness_trace"),
            "Best fitness per iteration, trial 0",
            "iteration",
            "fitness (eq. 14)",
            &fit,
            true,
        )?;
        done.push((
            "fitness_trace.png".into(),
            "metaheuristic convergence, trial 0".into(),
        ));
    }
    // Sweeps: validation RMS after compensation against the swept value.
    if let Some(sw) = &r.scenario.sweep {
        let xs: Vec<Option<Real>> = r
            .blocks
            .iter()
            .map(|b| {
                b.sweep_value
                    .as_ref()
                    .and_then(|v| v.as_float().or(v.as_integer().map(|i| i as Real)))
            })
            .collect();
        if xs.iter().all(Option::is_some) {
            let mut series: Vec<plots::SweepSeries> = Vec::new();
            for (k, e) in b0.entries.iter().enumerate() {
                let pts = r
                    .blocks
                    .iter()
                    .zip(&xs)
                    .map(|(b, x)| {
                        let e = &b.entries[k];
                        (
                            x.unwrap_or(0.0),
                            e.validation_after_mm.rms,
                            e.validation_after_mm.std,
                        )
                    })
                    .collect();
                series.push((entry_label(e), pts));
            }
            plots::sweep(
                &out.join("sweep"),
                "Validation RMS after compensation",
                &sw.key,
                "RMS (mm)",
                &series,
            )?;
            done.push((
                "sweep.png".into(),
                format!("validation RMS against {}", sw.key),
            ));
        }
    }
    Ok(done)
}

/// Writes every output file of a run into its folder.
pub fn write_all(r: &RunResult) -> Result<()> {
    super::atomically(&r.out, |dir| write_into(r, dir))
}

/// Writes every file of a run into the folder `dir`.
fn write_into(r: &RunResult, dir: &Path) -> Result<()> {
    write_json(&dir.join("summary.json"), &summary(r))?;
    write(&dir.join("trials.csv"), &trials_csv(r))?;
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
    Ok(())
}
