//! The paired comparisons of a study's entries (docs/formats.md "comparisons"): every pair of
//! entries of one block that share their draws — the same strategy, or the same method —
//! on each trial's validation RMS after compensation and mean η; in `summary.json` all of
//! them, in the reports each entry against its block's baseline (the scenario's
//! `[report] baseline` method, else its first method, on the same strategy; the first
//! strategy with the same method).

use crate::error::Result;
use crate::numeric::Real;
use crate::study::metric::Metric;
use crate::study::stats::paired::{adjust, compare_with, Comparison};
use crate::study::{Block, Entry, RunResult};

/// The metrics compared.
pub const METRICS: [Metric; 2] = [Metric::ValidationAfterRms, Metric::EtaMean];

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

/// The label of an entry in the comparisons: `method / poses`.
pub fn label(e: &Entry) -> String {
    format!("{} / {}", e.method, e.poses)
}

/// The per-trial differences b − a of one metric between an entry b and its baseline a, on
/// the trials usable in both (the reports' box plots: where zero lies is the verdict).
#[derive(Clone, Debug)]
pub struct Differences {
    /// The metric.
    pub metric: Metric,
    /// `b vs a`.
    pub label: String,
    /// b − a per trial.
    pub values: Vec<Real>,
    /// The estimate and 95 % interval of the test of the comparison's verdict (the mean and
    /// its t interval, or the median and its sign-test interval), where it has one.
    pub mark: Option<(Real, [Real; 2])>,
}

/// The run's comparisons: all of them (a before b in `results` order), Holm-adjusted
/// together, and the ones the reports show, each as baseline (a) against entry (b): a pair
/// whose baseline comes second in `results` is computed the other way round, with the same
/// Wilcoxon p-value and Holm adjustment (the signed-rank test is symmetric). With the
/// per-trial differences of the shown pairs of the first block. Each pair's per-trial values
/// are read from the study's scratch file while the pair is compared, one pair at a time;
/// fails only when that file cannot be read.
pub fn comparisons(r: &RunResult) -> Result<(Vec<Comparison>, Vec<Comparison>, Vec<Differences>)> {
    let baseline = r.scenario.report.baseline.as_deref();
    let mut all = Vec::new();
    let mut views = Vec::new();
    for b in &r.blocks {
        for (i, j, view) in pairs(b, baseline) {
            let (ea, eb) = (&b.entries[i], &b.entries[j]);
            for metric in METRICS {
                let (va, vb) = (ea.per_trial.values(metric)?, eb.per_trial.values(metric)?);
                let margin = r.scenario.report.margin(metric);
                let mut c = compare_with((&label(ea), &label(eb)), metric, (&va, &vb), margin);
                c.sweep_value = ea.sweep_value.clone();
                all.push(c);
                views.push((b, i, j, view));
            }
        }
    }
    adjust(&mut all);
    let mut shown = Vec::new();
    for (c, (b, i, j, view)) in all.iter().zip(views) {
        match view {
            View::Hidden => {}
            View::AsIs => shown.push(c.clone()),
            View::Flipped => {
                let (ea, eb) = (&b.entries[i], &b.entries[j]);
                let m = c.metric;
                let (va, vb) = (ea.per_trial.values(m)?, eb.per_trial.values(m)?);
                let mut f = compare_with(
                    (&label(eb), &label(ea)),
                    m,
                    (&vb, &va),
                    r.scenario.report.margin(m),
                );
                f.sweep_value.clone_from(&c.sweep_value);
                f.p_holm = c.p_holm;
                shown.push(f);
            }
        }
    }
    let mut differences = Vec::new();
    if let Some(b) = r.blocks.first() {
        for metric in METRICS {
            for (i, j, view) in pairs(b, baseline) {
                let (i, j) = match view {
                    View::Hidden => continue,
                    View::AsIs => (i, j),
                    View::Flipped => (j, i),
                };
                let (ea, eb) = (&b.entries[i], &b.entries[j]);
                let values = ea
                    .per_trial
                    .values(metric)?
                    .iter()
                    .zip(&eb.per_trial.values(metric)?)
                    .map(|(x, y)| y - x)
                    .filter(|d| d.is_finite())
                    .collect();
                let (la, lb) = (label(ea), label(eb));
                let mark = shown
                    .iter()
                    .find(|c| {
                        c.metric == metric
                            && c.a == la
                            && c.b == lb
                            && c.sweep_value == ea.sweep_value
                    })
                    .and_then(|c| Some((c.estimate?, c.ci95?)));
                differences.push(Differences {
                    metric,
                    label: format!("{lb} vs {la}"),
                    values,
                    mark,
                });
            }
        }
    }
    Ok((all, shown, differences))
}
