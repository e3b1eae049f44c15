//! The reports' table of paired comparisons (docs/formats.md "comparisons"): the comparisons
//! the analysis shows, each entry against its block's baseline
//! ([`crate::analysis::comparisons`]).

use crate::analysis::summary::Comparison;
use crate::analysis::summary::Summary;
use crate::numeric::Real;
use crate::report::markdown::fmt_num;
use crate::study::metric::Metric;
use crate::study::stats::location::Test;

use super::fmt_ci;

/// The verdict of a comparison in words: its margin verdict (better, worse, equivalent,
/// unresolved: b against a); for a summary written before verdicts, which entry is better at
/// the Holm level.
pub fn verdict(c: &Comparison) -> String {
    if let Some(v) = c.verdict {
        return match c.trials_to_resolve {
            Some(t) => format!("{} (about {t} trials would resolve it)", v.as_str()),
            None => v.as_str().to_string(),
        };
    }
    let lower = c.metric.lower_is_better();
    if c.p_holm.is_nan() || c.p_holm >= 0.05 || c.diff_mean == 0.0 {
        "no significant difference".into()
    } else if (c.diff_mean < 0.0) == lower {
        "b better".into()
    } else {
        "b worse".into()
    }
}

/// A paired test as the reports name it: what it locates, and how.
pub fn test(t: Test) -> &'static str {
    match t {
        Test::T => "mean (t)",
        Test::Sign => "median (sign)",
    }
}

/// The reports' comparison table: headers and rows (each entry against its baseline). The
/// estimate and interval are those of the test the verdict is judged on (the mean and its t
/// interval, or the median and its sign-test interval), as `calbench check` prints them; a
/// summary written before verdicts has the mean and its t interval.
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
        "test",
        "b − a",
        "95 % CI",
        "ratio b/a",
        "b wins %",
        "p (Wilcoxon)",
        "p Holm",
        "margin",
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
                c.verdict
                    .map_or(String::new(), |_| test(c.test).to_string()),
                fmt_num(c.estimate.unwrap_or(c.diff_mean), 4),
                fmt_ci(c.estimate.and(c.ci95).or(c.diff_ci95), 4),
                fmt_num(c.ratio.unwrap_or(Real::NAN), 4),
                fmt_num(100.0 * c.win_rate, 3),
                fmt_num(c.p_value, 3),
                fmt_num(c.p_holm, 3),
                c.margin.map_or(String::new(), |m| fmt_num(m, 3)),
                verdict(c),
            ]);
            row
        })
        .collect();
    (h, rows)
}

/// What the comparison table says, for the reports.
pub const NOTE: &str = "Every method of a study runs on the same trials, so two entries are \
    compared trial by trial: b − a per trial, the estimate and 95 % interval of the test the \
    verdict is judged on, the ratio of the means (errors), the share of trials where b is better, the two-sided Wilcoxon \
    signed-rank p-value and its Holm adjustment over every comparison of the study \
    (summary.json `comparisons` holds all pairs; this table each entry against the baseline \
    method on its strategy — the scenario's `[report] baseline`, else its first method — and \
    against the first strategy of its method). The verdict is against the metric's margin \
    of practical relevance m (docs/formats.md \"Tests and margins\"; `[report.margins]` \
    overrides it): better or worse when the 95 % interval of b − a lies wholly beyond ± m, \
    equivalent when it lies inside ± m (two one-sided tests), unresolved otherwise, with the \
    trials that would resolve it; the interval is that of the mean (t), or of the median \
    (sign test) when the differences are heavy-tailed (excess kurtosis above 3).";

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
