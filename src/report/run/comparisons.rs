//! The reports' table of paired comparisons (docs/formats.md "comparisons"): the comparisons
//! the analysis shows, each entry against its block's baseline
//! ([`crate::analysis::comparisons`]).

use crate::analysis::summary::Comparison;
use crate::analysis::summary::Summary;
use crate::numeric::Real;
use crate::report::markdown::fmt_num;
use crate::study::metric::Metric;

use super::fmt_ci;

/// The verdict of a comparison in words: which entry is better, or none at the Holm level.
pub fn verdict(c: &Comparison) -> &'static str {
    let lower = c.metric.lower_is_better();
    if c.p_holm.is_nan() || c.p_holm >= 0.05 || c.diff_mean == 0.0 {
        "no significant difference"
    } else if (c.diff_mean < 0.0) == lower {
        "b better"
    } else {
        "b worse"
    }
}

/// The reports' comparison table: headers and rows (each entry against its baseline).
pub fn table(s: &Summary) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let sweep = s.sweep_keys.is_some();
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
    let rows = s
        .shown
        .iter()
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
                verdict(c).to_string(),
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

/// The plots of the per-trial differences (stem, title, y label, metric).
pub const DIFF_PLOTS: [(&str, &str, &str, Metric); 2] = [
    (
        "paired_validation_rms",
        "Validation RMS after, b − a per trial (below 0: b better)",
        "b − a (mm)",
        Metric::ValidationAfterRms,
    ),
    (
        "paired_eta",
        "Mean η, b − a per trial (above 0: b better)",
        "b − a (%)",
        Metric::EtaMean,
    ),
];
