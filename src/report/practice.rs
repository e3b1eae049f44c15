//! What `calbench identify`'s practice options add to `report.md` and `report.html`
//! (docs/formats.md `identify`), rendered from the identification record: the
//! cross-validation and model choice, the fixed parameters, how each prior moved its
//! estimate, the convergence trace and the diagnostics.

use super::identified::{Additions, Block};
use super::markdown::fmt_num;
use crate::calibrate::pipeline::TrackerOutcome;
pub use crate::calibrate::record::IdentifiedRecord;
use crate::numeric::Real;

/// A table row: `name`, then `values` to `digits` significant digits.
fn named_row<const N: usize>(name: String, values: [Real; N], digits: usize) -> Vec<String> {
    std::iter::once(name)
        .chain(values.map(|v| fmt_num(v, digits)))
        .collect()
}

impl IdentifiedRecord {
    /// The section the practice options add to `report.md` and `report.html`; nothing for
    /// an option not used.
    pub fn additions(&self) -> Additions {
        let mut a = Additions::default();
        let md = &mut a.blocks;
        if let Some(cv) = &self.cv {
            md.push(Block::Heading("Cross-validation".into()));
            md.push(Block::Para(format!(
                "{}-fold ({} model, {} parameters): RMS {} mm over the held-out points; per fold \
                 {} ± {} mm.",
                cv.k,
                cv.model,
                cv.parameters,
                fmt_num(cv.rms, 4),
                fmt_num(cv.mean, 4),
                fmt_num(cv.sd, 4)
            )));
        }
        if let (Some(cvs), Some(best)) = (&self.cv_models, self.best_model()) {
            let rows: Vec<Vec<String>> = cvs
                .iter()
                .enumerate()
                .map(|(i, m)| {
                    vec![
                        format!("{}{}", m.model, if i == best { " (best)" } else { "" }),
                        m.parameters.to_string(),
                        fmt_num(m.rms, 4),
                        format!("{} ± {}", fmt_num(m.mean, 4), fmt_num(m.sd, 4)),
                    ]
                })
                .collect();
            md.push(Block::Heading("Model choice".into()));
            let headers = vec!["model", "parameters", "CV RMS (mm)", "folds (mm)"];
            md.push(Block::Table(headers, rows));
        }
        if let Some(r) = &self.readmitted {
            let rows = r
                .parameters
                .iter()
                .map(|p| named_row(p.parameter.clone(), [p.estimate, p.sigma, p.threshold], 6));
            md.push(Block::Heading("Re-admitted at the identified robot".into()));
            md.push(Block::Para(format!(
                "Left out at the nominal robot, determined at the identified one (Cramér–Rao σ \
                 at most a third of the parameter's plausibility bound, one Gauss–Newton step \
                 beyond 3σ) and identified with the rest: RMS residual {} mm before, {} mm \
                 after.",
                fmt_num(r.before_rms_residual_mm, 4),
                fmt_num(self.rms_residual_mm, 4)
            )));
            md.push(Block::Table(
                vec!["parameter", "step", "σ", "threshold"],
                rows.collect(),
            ));
        }
        if !self.fixed.is_empty() {
            md.push(Block::Para(format!(
                "Fixed at nominal: {}.",
                self.fixed.join(", ")
            )));
        }
        if !self.priors.is_empty() {
            let rows = self.priors.iter().map(|p| {
                named_row(
                    p.parameter.clone(),
                    [p.sigma, p.without_prior, p.with_prior],
                    4,
                )
            });
            md.push(Block::Heading("Priors".into()));
            let headers = vec!["parameter", "σ", "without prior", "with prior"];
            md.push(Block::Table(headers, rows.collect()));
        }
        if let Some(t) = &self.convergence_trace {
            let (what, values) = (&t.values, &t.trace);
            md.push(Block::Heading("Convergence".into()));
            md.push(Block::Para(format!(
                "{what}: {} values, from {} to {}.",
                values.len(),
                values.first().map_or("—".into(), |v| fmt_num(*v, 6)),
                values.last().map_or("—".into(), |v| fmt_num(*v, 6))
            )));
        }
        if let Some(d) = &self.diagnostics {
            md.push(Block::Heading("Diagnostics".into()));
            let pairs: Vec<String> = d
                .flagged_pairs
                .iter()
                .map(|p| format!("{}–{} ({})", p.a, p.b, fmt_num(p.rho, 3)))
                .collect();
            md.push(Block::Para(format!(
                "Correlated pairs (|ρ| > 0.8): {}.",
                if pairs.is_empty() {
                    "none".to_string()
                } else {
                    pairs.join(", ")
                }
            )));
            let rows = d
                .top_points
                .iter()
                .map(|p| named_row(p.row.to_string(), [p.leverage, p.cook], 4));
            md.push(Block::Table(
                vec!["row", "leverage", "Cook's distance"],
                rows.collect(),
            ));
            let p = &d.predicted;
            let predicted = match p.rms_mm.is_nan() {
                true => "none, as there is no covariance".to_string(),
                false => format!(
                    "RMS {} mm, max {} mm",
                    fmt_num(p.rms_mm, 4),
                    fmt_num(p.max_mm, 4)
                ),
            };
            md.push(Block::Para(format!(
                "Predicted position σ from the covariance at the {} poses: {predicted}; \
                 measured RMS there {} mm.",
                p.at,
                fmt_num(p.measured_rms_mm, 4)
            )));
        }
        a
    }
}

/// What an identification on a tracker's file adds to the reports: the practice options'
/// section, and a result kept worse than the nominal robot (a warning section).
pub fn additions(o: &TrackerOutcome) -> Additions {
    let mut a = o.record.additions();
    let implausible =
        crate::calibrate::plausibility::implausible_warning(&o.record.allowed_implausible);
    if let Some(w) = implausible {
        a.blocks.insert(0, Block::Para(format!("Warning: {w}.")));
        a.blocks
            .insert(0, Block::Heading("Cannot be physically right".into()));
    }
    if let Some(w) = o.worse_warning() {
        a.blocks.insert(0, Block::Para(format!("Warning: {w}.")));
        a.blocks
            .insert(0, Block::Heading("Worse than the nominal robot".into()));
    }
    a
}
