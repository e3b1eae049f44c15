//! The `[report]` section of a scenario (docs/formats.md § 4.16): how the study's reports
//! present it. Nothing here changes what a trial computes or `summary.json`.

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::identify::MethodSpec;
use crate::study::metric::{Margin, Metric};

/// The `[report]` section, checked.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReportSettings {
    /// The method (its label) each other method is compared against in the reports' table
    /// of paired comparisons; `None`: the scenario's first method.
    pub baseline: Option<String>,
    /// The margins of practical relevance of the paired comparisons, by metric key, where
    /// not the metric's default ([`Metric::default_margin`]).
    #[serde(default)]
    pub margins: BTreeMap<String, Margin>,
}

impl ReportSettings {
    /// The margin of `metric`'s comparisons: `[report.margins]`'s, else the metric's default.
    pub fn margin(&self, metric: Metric) -> Margin {
        self.margins
            .get(&metric.key())
            .copied()
            .unwrap_or_else(|| metric.default_margin())
    }

    /// Refuses a margin of an unknown metric or out of range, and a `baseline` that is not the label of one of `methods`: the key and the
    /// accepted labels.
    pub(super) fn check(&self, methods: &[MethodSpec]) -> Result<(), (String, String)> {
        for (k, m) in &self.margins {
            let key = format!("report.margins.{k}");
            if Metric::from_key(k).is_none_or(|m| m.per_trial_index().is_none()) {
                let all: Vec<String> = Metric::PER_TRIAL.iter().map(|m| m.key()).collect();
                return Err((
                    key,
                    format!(
                        "unknown metric \"{k}\"; per-trial metrics are {}",
                        all.join(", ")
                    ),
                ));
            }
            m.check().map_err(|e| (key, e))?;
        }
        let Some(name) = &self.baseline else {
            return Ok(());
        };
        if methods.iter().any(|m| &m.label == name) {
            return Ok(());
        }
        let labels: Vec<&str> = methods.iter().map(|m| m.label.as_str()).collect();
        Err((
            "report.baseline".into(),
            format!(
                "\"{name}\" is not a method of the scenario; accepted: {}",
                labels.join(", ")
            ),
        ))
    }
}
