//! The `[report]` section of a scenario (docs/formats.md § 4.16): how the study's reports
//! present it. Nothing here changes what a trial computes or `summary.json`.

use serde::Deserialize;

use crate::identify::MethodSpec;

/// The `[report]` section, checked.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReportSettings {
    /// The method (its label) each other method is compared against in the reports' table
    /// of paired comparisons; `None`: the scenario's first method.
    pub baseline: Option<String>,
}

impl ReportSettings {
    /// Refuses a `baseline` that is not the label of one of `methods`: the key and the
    /// accepted labels.
    pub(super) fn check(&self, methods: &[MethodSpec]) -> Result<(), (String, String)> {
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
