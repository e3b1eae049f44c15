//! The paired comparisons of a study's entries (docs/formats.md "comparisons"): every pair of
//! entries of one block that share their draws — the same strategy, or the same method —
//! on each trial's validation RMS after compensation and mean η; in `summary.json` all of
//! them, in the reports each entry against its block's baseline (the scenario's
//! `[report] baseline` method, else its first method, on the same strategy; the first
//! strategy with the same method).

use crate::numeric::Real;
use crate::report::markdown::fmt_num;
use crate::study::stats::paired::{adjust, compare, Comparison};
use crate::study::{Block, RunResult};

use super::fmt_ci;

/// The metrics compared: key, index of [`crate::study::Entry::per_trial`], lower is better.
const METRICS: [(&str, usize, bool); 2] = [
    ("validation_after_mm.rms", 0, true),
    ("eta_mean_pct", 1, false),
];

/// How the reports show a pair of entries a before b (in `results` order).
#[derive(Clone, Copy, PartialEq, Eq)]
enum View {
    /// Not shown: neither is the other's baseline.
    Hidden,
    /// Shown as it is: a is b's baseline.
    AsIs,
    /// Shown the other way round: b is a's baseline (a `[report] baseline` after a).
    Flipped,
}

/// The pairs of entries of block `b` that share their draws (indices, a before b), each with
/// how the reports show it; `baseline` is the method the other methods of a strategy are
/// shown against (`None`: the block's first).
fn pairs(b: &Block, baseline: Option<&str>) -> Vec<(usize, usize, View)> {
    let (methods, strategies) = (&b.info.methods, &b.info.strategies);
    let base = baseline.or(methods.first().map(String::as_str));
    let mut out = Vec::new();
    for (i, ea) in b.entries.iter().enumerate() {
        for (j, eb) in b.entries.iter().enumerate().skip(i + 1) {
            let same_poses = ea.poses == eb.poses;
            if !same_poses && ea.method != eb.method {
                continue;
            }
            let view = if same_poses {
                if base == Some(ea.method.as_str()) {
                    View::AsIs
                } else if base == Some(eb.method.as_str()) {
                    View::Flipped
                } else {
                    View::Hidden
                }
            } else if strategies.first() == Some(&ea.poses) {
                View::AsIs
            } else {
                View::Hidden
            };
            out.push((i, j, view));
        }
    }
    out
}

fn label(e: &crate::study::Entry) -> String {
    format!("{} / {}", e.method, e.poses)
}

/// The scenario's `[report] baseline`.
fn baseline(r: &RunResult) -> Option<&str> {
    r.scenario.report.baseline.as_deref()
}

/// Every paired comparison of the run (a before b in `results` order), Holm-adjusted
/// together, with how the reports show each.
fn all(r: &RunResult) -> Vec<(Comparison, View)> {
    let mut out = Vec::new();
    for b in &r.blocks {
        for (i, j, view) in pairs(b, baseline(r)) {
            let (ea, eb) = (&b.entries[i], &b.entries[j]);
            let (la, lb) = (label(ea), label(eb));
            for (metric, k, lower) in METRICS {
                let mut c = compare(
                    (&la, &lb),
                    metric,
                    (&ea.per_trial[k], &eb.per_trial[k]),
                    lower,
                );
                c.sweep_value = ea.sweep_value.clone();
                out.push((c, view));
            }
        }
    }
    let mut adjusted: Vec<Comparison> = out.iter().map(|(c, _)| c.clone()).collect();
    adjust(&mut adjusted);
    adjusted
        .into_iter()
        .zip(out)
        .map(|(c, (_, v))| (c, v))
        .collect()
}

/// Every paired comparison of the run, Holm-adjusted together (`summary.json`'s
/// `comparisons`), with whether the reports show it (one of its entries is the other's
/// baseline).
pub fn comparisons(r: &RunResult) -> Vec<(Comparison, bool)> {
    all(r)
        .into_iter()
        .map(|(c, v)| (c, v != View::Hidden))
        .collect()
}

/// The comparisons the reports show, each as baseline (a) against entry (b): a pair whose
/// baseline comes second in `results` is computed the other way round, with the same
/// Wilcoxon p-value and Holm adjustment (the signed-rank test is symmetric).
pub fn shown(r: &RunResult) -> Vec<Comparison> {
    let mut out = Vec::new();
    let mut it = all(r).into_iter();
    for b in &r.blocks {
        for (i, j, view) in pairs(b, baseline(r)) {
            for (metric, k, lower) in METRICS {
                let Some((c, _)) = it.next() else {
                    return out;
                };
                match view {
                    View::Hidden => {}
                    View::AsIs => out.push(c),
                    View::Flipped => {
                        let (ea, eb) = (&b.entries[i], &b.entries[j]);
                        let mut f = compare(
                            (&label(eb), &label(ea)),
                            metric,
                            (&eb.per_trial[k], &ea.per_trial[k]),
                            lower,
                        );
                        f.sweep_value = c.sweep_value;
                        f.p_holm = c.p_holm;
                        out.push(f);
                    }
                }
            }
        }
    }
    out
}

/// The verdict of a comparison in words: which entry is better, or none at the Holm level.
pub fn verdict(c: &Comparison) -> &'static str {
    let lower = c.ratio.is_some() || c.metric.starts_with("validation");
    if c.p_holm.is_nan() || c.p_holm >= 0.05 || c.diff_mean == 0.0 {
        "no significant difference"
    } else if (c.diff_mean < 0.0) == lower {
        "b better"
    } else {
        "b worse"
    }
}

/// The reports' comparison table: headers and rows (each entry against its baseline).
pub fn table(r: &RunResult) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let sweep = r.scenario.sweep.is_some();
    let mut h = Vec::new();
    if sweep {
        h.push("sweep value");
    }
    h.extend([
        "a",
        "b",
        "metric",
        "trials",
        "b − a",
        "95 % CI",
        "ratio b/a",
        "b wins %",
        "p (Wilcoxon)",
        "p Holm",
        "verdict",
    ]);
    let rows = shown(r)
        .into_iter()
        .map(|c| {
            let mut row = Vec::new();
            if sweep {
                row.push(
                    c.sweep_value
                        .as_ref()
                        .map_or(String::new(), |v| v.to_string()),
                );
            }
            row.extend([
                c.a.clone(),
                c.b.clone(),
                c.metric.to_string(),
                c.n.to_string(),
                fmt_num(c.diff_mean, 4),
                fmt_ci(c.diff_ci95, 4),
                fmt_num(c.ratio.unwrap_or(Real::NAN), 4),
                fmt_num(100.0 * c.win_rate, 3),
                fmt_num(c.p_value, 3),
                fmt_num(c.p_holm, 3),
                verdict(&c).to_string(),
            ]);
            row
        })
        .collect();
    (h, rows)
}

/// What the comparison table says, for the reports.
pub const NOTE: &str = "Every method of a study runs on the same trials, so two entries are \
    compared trial by trial: b − a per trial, its mean and 95 % t interval, the ratio of the \
    means (errors), the share of trials where b is better, the two-sided Wilcoxon \
    signed-rank p-value and its Holm adjustment over every comparison of the study \
    (summary.json `comparisons` holds all pairs; this table each entry against the baseline \
    method on its strategy — the scenario's `[report] baseline`, else its first method — and \
    against the first strategy of its method). Verdict at Holm p < 0.05.";

/// The plots of the per-trial differences (stem, title, y label, index of
/// [`crate::study::Entry::per_trial`]).
pub const DIFF_PLOTS: [(&str, &str, &str, usize); 2] = [
    (
        "paired_validation_rms",
        "Validation RMS after, b − a per trial (below 0: b better)",
        "b − a (mm)",
        0,
    ),
    (
        "paired_eta",
        "Mean η, b − a per trial (above 0: b better)",
        "b − a (%)",
        1,
    ),
];

/// The per-trial differences b − a of value `k` of each shown pair of block `b` (a the
/// baseline of `r`'s reports), labelled `b vs a`, on the trials usable in both: where zero
/// lies in each distribution is the comparison's verdict.
pub fn differences(r: &RunResult, b: &Block, k: usize) -> Vec<(String, Vec<Real>)> {
    pairs(b, baseline(r))
        .into_iter()
        .filter_map(|(i, j, view)| match view {
            View::Hidden => None,
            View::AsIs => Some((i, j)),
            View::Flipped => Some((j, i)),
        })
        .map(|(i, j)| {
            let (ea, eb) = (&b.entries[i], &b.entries[j]);
            let d = ea.per_trial[k]
                .iter()
                .zip(&eb.per_trial[k])
                .map(|(x, y)| y - x)
                .filter(|d| d.is_finite())
                .collect();
            (format!("{} vs {}", label(eb), label(ea)), d)
        })
        .collect()
}
