//! What `calbench identify`'s practice options add to `identified.json` and `report.md`
//! (docs/formats.md `identify`): the held-out split, the cross-validation and model choice,
//! the fixed parameters, how each prior moved its estimate, and the diagnostics.

use serde_json::{json, Value};

use super::identified::{Additions, Block};
use super::markdown::fmt_num;
use crate::calibrate::cv::{CrossValidation, Holdout};
use crate::calibrate::diagnostics::Diagnostics;
use crate::numeric::Real;
use crate::robot::Param;

/// A prior's effect: the estimate without and with it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PriorMove {
    /// The parameter.
    pub parameter: String,
    /// The prior's σ (mm, rad).
    pub sigma: Real,
    /// The estimate without any prior.
    pub without_prior: Real,
    /// The MAP estimate.
    pub with_prior: Real,
}

/// The practice options' results of one identification.
#[derive(Clone, Debug, Default)]
pub struct Practice {
    /// `--holdout`.
    pub holdout: Option<Holdout>,
    /// The cross-validation of the model identified.
    pub cv: Option<CrossValidation>,
    /// `--models`: every model's cross-validation and the index of the best.
    pub models: Option<(Vec<CrossValidation>, usize)>,
    /// `--fix`.
    pub fixed: Vec<Param>,
    /// `--prior`: how each moved its estimate.
    pub priors: Vec<PriorMove>,
    /// The convergence trace: what it holds, and its values.
    pub trace: Option<(&'static str, Vec<Real>)>,
    /// The diagnostics.
    pub diagnostics: Option<Diagnostics>,
}

fn to_value<T: serde::Serialize>(v: &T) -> Value {
    serde_json::to_value(v).unwrap_or(Value::Null)
}

impl Practice {
    /// The keys added to `identified.json` and the section added to `report.md` and `report.html`; nothing
    /// for an option not used.
    pub fn additions(&self) -> Additions<'_> {
        let mut a = Additions::default();
        let j = &mut a.json;
        let md = &mut a.blocks;
        if let Some(h) = self.holdout {
            j.insert("holdout".into(), json!(format!("{}/{}", h.last, h.every)));
        }
        if let Some(cv) = &self.cv {
            j.insert("cv".into(), to_value(cv));
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
        if let Some((cvs, best)) = &self.models {
            j.insert("cv_models".into(), to_value(cvs));
            j.insert("cv_best".into(), json!(cvs[*best].model));
            let rows: Vec<Vec<String>> = cvs
                .iter()
                .enumerate()
                .map(|(i, m)| {
                    vec![
                        format!("{}{}", m.model, if i == *best { " (best)" } else { "" }),
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
        if !self.fixed.is_empty() {
            let names: Vec<String> = self.fixed.iter().map(|p| p.to_string()).collect();
            md.push(Block::Para(format!(
                "Fixed at nominal: {}.",
                names.join(", ")
            )));
            j.insert("fixed".into(), json!(names));
        }
        if !self.priors.is_empty() {
            j.insert("priors".into(), to_value(&self.priors));
            let mut rows = Vec::with_capacity(self.priors.len());
            for p in &self.priors {
                let nums = [p.sigma, p.without_prior, p.with_prior].map(|v| fmt_num(v, 4));
                rows.push(std::iter::once(p.parameter.clone()).chain(nums).collect());
            }
            md.push(Block::Heading("Priors".into()));
            let headers = vec!["parameter", "σ", "without prior", "with prior"];
            md.push(Block::Table(headers, rows));
        }
        if let Some((what, values)) = &self.trace {
            j.insert(
                "convergence_trace".into(),
                json!({"values": what, "trace": values}),
            );
            md.push(Block::Heading("Convergence".into()));
            md.push(Block::Para(format!(
                "{what}: {} values, from {} to {}.",
                values.len(),
                values.first().map_or("—".into(), |v| fmt_num(*v, 6)),
                values.last().map_or("—".into(), |v| fmt_num(*v, 6))
            )));
        }
        if let Some(d) = &self.diagnostics {
            a.diagnostics = Some(d);
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
            let rows: Vec<Vec<String>> = d
                .top_points
                .iter()
                .map(|p| {
                    vec![
                        p.row.to_string(),
                        fmt_num(p.leverage, 4),
                        fmt_num(p.cook, 4),
                    ]
                })
                .collect();
            md.push(Block::Table(
                vec!["row", "leverage", "Cook's distance"],
                rows,
            ));
            let p = &d.predicted;
            md.push(Block::Para(format!(
                "Predicted position σ from the covariance at the {} poses: RMS {} mm, max {} \
                 mm; measured RMS there {} mm.",
                p.at,
                fmt_num(p.rms_mm, 4),
                fmt_num(p.max_mm, 4),
                fmt_num(p.measured_rms_mm, 4)
            )));
        }
        a
    }
}
