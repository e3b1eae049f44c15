//! The files of `calbench poses` (docs/formats.md): `poses.csv` (the chosen poses,
//! [`super::output::PoseList`]), `scores.json` ([`Scores`]), `trace.csv` (the objective per
//! iteration) and, with `--curve`, `curve.csv` and the figure `curve` (the objective against
//! the pose count, Guo 2024 fig. 7).

use std::path::Path;

use serde_json::json;

use super::output::{Json, Output, Series};
use super::plots::SweepFigure;
use crate::error::{Error, Result};
use crate::numeric::Real;
use crate::poses::{Selection, Separation};
use crate::robot::Param;

/// The files always written (`curve.*` only with a curve).
pub const FILES: [&str; 3] = ["poses.csv", "scores.json", "trace.csv"];

/// `scores.json`: the indices of the chosen set, the strategy, the number of poses, the
/// parameters the objective is over, why the search stopped and, after a separation, its
/// GCN tables.
pub struct Scores<'a> {
    /// The strategy's name.
    pub strategy: &'a str,
    /// The chosen set.
    pub selection: &'a Selection,
    /// The parameters the objective is over.
    pub params: &'a [Param],
    /// The ill-conditioned parameter separation, when one was made.
    pub separation: Option<&'a Separation>,
}

impl Scores<'_> {
    /// The document.
    fn json(&self) -> Result<serde_json::Value> {
        let sel = self.selection;
        let mut scores =
            serde_json::to_value(sel.scores).map_err(|e| Error::Compute(e.to_string()))?;
        scores["strategy"] = json!(self.strategy);
        scores["count"] = json!(sel.poses.len());
        scores["parameters"] = json!(self
            .params
            .iter()
            .map(|p| p.to_string())
            .collect::<Vec<_>>());
        scores["termination"] = json!(sel.termination);
        if let Some(s) = self.separation {
            let mut j = s.to_json();
            // The earlier form of the table, kept for scripts that read it.
            j["gcn"] = json!(s
                .table
                .iter()
                .map(|r| json!({"block": r.label, "gcn": r.gcn}))
                .collect::<Vec<_>>());
            scores["separation"] = j;
        }
        Ok(scores)
    }
}

impl Output for Scores<'_> {
    fn name(&self) -> &str {
        FILES[1]
    }
    fn write(&self, path: &Path) -> Result<()> {
        let value = self.json()?;
        Json {
            name: FILES[1],
            value: &value,
        }
        .write(path)
    }
}

/// `trace.csv`: the objective after each iteration of the search.
pub fn trace(selection: &Selection) -> Series<'static> {
    Series {
        name: FILES[2],
        header: "iteration,objective",
        points: selection.trace.iter().copied().enumerate().collect(),
    }
}

/// `curve.csv`: the objective (named `objective`, e.g. `composite`) against the pose count.
pub fn curve(points: &[(usize, Real)]) -> Series<'static> {
    Series {
        name: "curve.csv",
        header: "count,objective",
        points: points.to_vec(),
    }
}

/// The figure `curve`: the objective named `objective` against the pose count.
pub fn curve_figure(objective: &str, points: &[(usize, Real)]) -> SweepFigure<'static> {
    let pts = points.iter().map(|&(n, f)| (n as Real, f, 0.0)).collect();
    SweepFigure {
        name: "curve",
        title: "Objective against pose count (Guo 2024 fig. 7)",
        axes: ("pose count", "objective"),
        series: vec![(format!("{objective} objective"), pts)],
    }
}
