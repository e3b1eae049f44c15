//! The searches compared as COCO does (docs/formats.md "Searches compared"): the table of
//! `report.md` and `report.html` and the plots `search_ecdf` and `fixed_budget`, read from
//! the entries' `search_ecdf` and `fixed_budget` (the first block of a sweep).

use crate::numeric::Real;
use crate::report::markdown::fmt_num;
use crate::report::plots;
use crate::study::stats::ecdf::DELTAS;
use crate::study::stats::Entry;
use crate::study::RunResult;

use super::{entry_label, fmt_ci, Figure};

/// What the table and the plots show.
pub const NOTE: &str = "Each search (BAS, PSO, BAS-PSO) is compared with the searches of \
    the same fitness on the same trials, as COCO compares optimisers: target Δ is reached \
    when the best fitness is within a factor 1 + Δ of the lowest final fitness of those \
    searches on the trial; the share of trials reached gets its 95 % Wilson interval. The \
    fitness at the full budget (the smallest evaluation count of the compared searches) is \
    the mean over trials with its 95 % t interval. The runtime ECDF aggregates the four \
    targets: the share of (trial, target) pairs reached against the evaluations spent.";

/// The entries of the first block that are searches.
fn searches(r: &RunResult) -> impl Iterator<Item = &Entry> {
    r.blocks[0]
        .entries
        .iter()
        .filter(|e| e.search_ecdf.is_some())
}

/// The table: per search, its trials, the share reached of each target with its interval,
/// and the mean best fitness at the full budget with its interval. No rows without
/// searches.
pub fn table(r: &RunResult) -> (Vec<String>, Vec<Vec<String>>) {
    let mut h = vec!["method / poses".to_string(), "trials".to_string()];
    h.extend(DELTAS.iter().map(|d| format!("reached Δ = {d}")));
    h.extend(["fitness at full budget".into(), "95 % CI".into()]);
    let rows = searches(r)
        .map(|e| {
            let ecdf = e.search_ecdf.as_ref().expect("a search");
            let mut row = vec![entry_label(e), ecdf.trials.to_string()];
            row.extend(
                ecdf.targets
                    .iter()
                    .map(|t| format!("{} {}", fmt_num(t.reached, 3), fmt_ci(t.reached_ci95, 3))),
            );
            let full = e.fixed_budget.as_ref().and_then(|b| b.last());
            row.push(full.map_or(String::new(), |b| fmt_num(b.fitness_mean, 4)));
            row.push(full.map_or(String::new(), |b| fmt_ci(b.fitness_mean_ci95, 4)));
            row
        })
        .collect();
    (h, rows)
}

/// The figures `search_ecdf` and `fixed_budget` when the run has searches.
pub fn figures(r: &RunResult) -> Vec<Figure<'_>> {
    let entries: Vec<&Entry> = searches(r).collect();
    if entries.is_empty() {
        return Vec::new();
    }
    let ecdfs: Vec<plots::EcdfSeries> = entries
        .iter()
        .map(|e| {
            let ecdf = e.search_ecdf.as_ref().expect("a search");
            let steps = ecdf
                .all_targets
                .iter()
                .map(|p| (p.evaluations as Real, p.share))
                .collect();
            (entry_label(e), steps)
        })
        .collect();
    let budgets: Vec<plots::BudgetSeries> = entries
        .iter()
        .map(|e| {
            let points = e
                .fixed_budget
                .iter()
                .flatten()
                .map(|b| (b.evaluations_mean, b.fitness_mean, b.fitness_mean_ci95))
                .collect();
            (entry_label(e), points)
        })
        .collect();
    vec![
        Figure::new(
            "search_ecdf",
            "runtime ECDF of the searches: share of (trial, target) pairs reached against evaluations",
            move |p| {
                plots::runtime_ecdf(p, "Runtime ECDF of the searches, targets aggregated", &ecdfs)
            },
        ),
        Figure::new(
            "fixed_budget",
            "mean best fitness of the searches at 10, 25, 50 and 100 % of the budget, with 95 % intervals",
            move |p| plots::fixed_budget(p, "Best fitness at fixed budgets", &budgets),
        ),
    ]
}
