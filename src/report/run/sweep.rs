//! The sweep section of `report.md` and the sweep plots (docs/formats.md `run`).

use super::{columns, entry_label, entry_table, fmt_num, plots, table, Figure};
use crate::analysis::summary::{Profile, Summary};
use crate::numeric::Real;
use crate::study::scenario::Sweep;
use crate::study::stats::Entry;
use crate::study::RunResult;
use std::fmt::Write as _;

/// The sweep section of `report.md`: the headline metrics per sweep point, and for a
/// two-axis grid the validation RMS after compensation of each method and strategy as a
/// table of the first axis (rows) against the second (columns).
pub(super) fn sweep_tables(r: &RunResult, summary: &Summary, sw: &Sweep) -> String {
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
    if let Some(p) = &summary.performance_profile {
        let _ = writeln!(
            s,
            "\nPerformance profile (Dolan & Moré): the share of sweep points where the \
             validation RMS after compensation is within a factor τ of the point's best.\n"
        );
        let mut h = vec!["method / poses".to_string()];
        h.extend(p.tau.iter().map(|t| format!("τ = {t}")));
        let h: Vec<&str> = h.iter().map(String::as_str).collect();
        let rows: Vec<Vec<String>> = p
            .profiles
            .iter()
            .map(|prof| {
                let mut row = vec![format!("{} / {}", prof.method, prof.poses)];
                row.extend(prof.share.iter().map(|&v| fmt_num(v, 3)));
                row
            })
            .collect();
        s += &table(&h, &rows);
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
        "Validation RMS after compensation (95 % interval of the mean)",
        "RMS (mm)",
        |e| {
            let half = e
                .validation_after_mm
                .rms_ci95
                .map_or(Real::NAN, |[lo, hi]| 0.5 * (hi - lo));
            (e.validation_after_mm.rms, half)
        },
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
pub(super) fn sweep_figures<'a>(
    r: &'a RunResult,
    summary: &Summary,
    sw: &'a Sweep,
) -> Vec<Figure<'a>> {
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
            let x_label = x_label.clone();
            done.push(Figure::new(
                stem,
                format!("{title} against {keys}"),
                move |p| plots::sweep(p, title, &x_label, y_label, &series),
            ));
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
            let title = format!("Validation RMS after compensation (mm), {}", entry_label(e));
            let (xn, yn) = (xn.clone(), yn.clone());
            done.push(Figure::new(
                stem,
                format!(
                    "validation RMS after, {}, over {} and {}",
                    entry_label(e),
                    xa.key,
                    ya.key
                ),
                move |p| plots::heatmap(p, &title, (&xa.key, &xn), (&ya.key, &yn), &values),
            ));
        }
    }
    done.extend(summary.performance_profile.as_ref().map(profile_figure));
    done
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

/// The plot of the performance profile ([`Profile`]): the share of sweep points within τ of
/// the best against τ, one line per method × strategy (`performance_profile.png`).
fn profile_figure(p: &Profile) -> Figure<'static> {
    let series: Vec<plots::SweepSeries> = p
        .profiles
        .iter()
        .map(|prof| {
            let pts = p.tau.iter().zip(&prof.share);
            let pts = pts.map(|(&tau, &s)| (tau.log10(), s, Real::NAN)).collect();
            (format!("{} / {}", prof.method, prof.poses), pts)
        })
        .collect();
    let stem = "performance_profile";
    let title = "Performance profile: share of sweep points within τ of the best validation RMS";
    Figure::new(stem, title, move |p| {
        plots::sweep(
            p,
            title,
            "log10 τ (validation RMS after over the point's best)",
            "share of sweep points",
            &series,
        )
    })
}
