//! Fixed-target runtime ECDFs and fixed-budget curves of the searches (BAS, PSO, BAS-PSO),
//! compared as COCO does (Hansen et al., "COCO: performance assessment", 2021; docs/formats.md
//! "search_ecdf" and "fixed_budget").
//!
//! Per trial, each search's best-fitness trace is reduced to a [`SearchRun`] (the evaluations
//! at which it first reached each target, its best fitness at each budget of the grid) and
//! then dropped; the [`SearchAcc`] of a study entry keeps only counts and running sums, in
//! trial order, so its numbers are the same bytes for any thread count, shard split or resume.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::numeric::{nan, Real};

use super::dist;

pub use crate::study::outcome::{SearchRun, BUDGET_FRACTIONS, DELTAS};

/// 97.5 % quantile of the standard normal distribution.
const Z975: Real = 1.959_963_984_540_054;

/// The evaluations spent at the end of iteration `k` (0-based) of a search that spent
/// `evaluations` in `n` iterations: the searches spend the same number per iteration, the
/// initial population's cost is spread over the iterations.
fn evals_at(k: usize, n: usize, evaluations: usize) -> usize {
    ((k + 1) * evaluations).div_ceil(n)
}

impl SearchRun {
    /// The numbers of a search whose best fitness per iteration is `trace`, after
    /// `evaluations` evaluations, against the reference fitness `f_ref` and the budget
    /// `budget`.
    pub fn of(trace: &[Real], evaluations: usize, f_ref: Real, budget: usize) -> SearchRun {
        let n = trace.len();
        let mut hits = [None; DELTAS.len()];
        for (h, d) in hits.iter_mut().zip(DELTAS) {
            let target = f_ref * (1.0 + d);
            *h = trace
                .iter()
                .position(|&f| f <= target)
                .map(|k| evals_at(k, n, evaluations));
        }
        let mut at_budget = [Real::NAN; BUDGET_FRACTIONS.len()];
        for (b, frac) in at_budget.iter_mut().zip(BUDGET_FRACTIONS) {
            let limit = (frac * budget as Real).floor() as usize;
            // The trace is non-increasing: the last iteration within the budget holds the best.
            let done = (0..n)
                .take_while(|&k| evals_at(k, n, evaluations) <= limit)
                .count();
            if done > 0 {
                *b = trace[done - 1];
            }
        }
        SearchRun {
            budget,
            hits,
            at_budget,
            final_fitness: trace.last().copied().unwrap_or(Real::NAN),
        }
    }
}

/// What the searches compared on one trial share: the pose strategy (its index), the
/// orientation weight `k` (its bits) and the fitness's pose-error model (its name).
pub type Group = (usize, u64, &'static str);

/// The [`SearchRun`]s of one trial's searches: `runs[i]` is `(group, trace, evaluations)`
/// for outcome `i` (`None` for an outcome that is not a search or has no trace), where
/// searches of one [`Group`] share their fitness and their draws.
pub fn of_trial(runs: &[Option<(Group, &[Real], usize)>]) -> Vec<Option<SearchRun>> {
    let mut best: BTreeMap<Group, (Real, usize)> = BTreeMap::new();
    for (g, trace, evals) in runs.iter().flatten() {
        let f = trace.last().copied().unwrap_or(Real::NAN);
        let e = best.entry(*g).or_insert((Real::INFINITY, usize::MAX));
        if f < e.0 {
            e.0 = f;
        }
        e.1 = e.1.min(*evals);
    }
    runs.iter()
        .map(|r| {
            r.as_ref().map(|(g, trace, evals)| {
                let (f_ref, budget) = best[g];
                SearchRun::of(trace, *evals, f_ref, budget)
            })
        })
        .collect()
}

/// The Wilson score interval at 95 % of a share of `k` in `n` (Wilson 1927).
pub fn wilson(k: usize, n: usize) -> Option<[Real; 2]> {
    if n == 0 {
        return None;
    }
    let (k, n) = (k as Real, n as Real);
    let p = k / n;
    let z2 = Z975 * Z975;
    let centre = (p + z2 / (2.0 * n)) / (1.0 + z2 / n);
    let half = Z975 / (1.0 + z2 / n) * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    // At k = 0 and k = n the bounds 0 and 1 are exact; rounding must not move them inside.
    let lo = if k == 0.0 { 0.0 } else { centre - half };
    let hi = if k == n { 1.0 } else { centre + half };
    Some([lo.max(0.0), hi.min(1.0)])
}

/// Running numbers of one entry's searches over the trials, in trial order.
#[derive(Clone, Debug, Default)]
pub struct SearchAcc {
    trials: usize,
    /// Per target, how many trials reached it at each evaluation count.
    hits: [BTreeMap<usize, usize>; DELTAS.len()],
    /// Per budget: count, sum, sum of squares of the finite best fitnesses.
    budget: [(usize, Real, Real); BUDGET_FRACTIONS.len()],
    budget_evals: (usize, usize),
}

/// One point of a runtime ECDF.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct EcdfPoint {
    /// Evaluations.
    pub evaluations: usize,
    /// Share of the trials that reached the target within them.
    #[serde(deserialize_with = "nan::real")]
    pub share: Real,
}

/// A target's runtime ECDF (`search_ecdf` of an entry).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TargetEcdf {
    /// Δ: the target is f_ref · (1 + Δ).
    #[serde(deserialize_with = "nan::real")]
    pub delta: Real,
    /// The ECDF's steps, evaluations increasing.
    pub points: Vec<EcdfPoint>,
    /// Share of the trials that reached the target by the end.
    #[serde(deserialize_with = "nan::real")]
    pub reached: Real,
    /// Its 95 % Wilson interval.
    pub reached_ci95: Option<[Real; 2]>,
}

/// An entry's `search_ecdf`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SearchEcdf {
    /// Trials with a search trace.
    pub trials: usize,
    /// One ECDF per target.
    pub targets: Vec<TargetEcdf>,
    /// The targets aggregated as COCO aggregates them: the share of the (trial, target)
    /// pairs reached within so many evaluations, evaluations increasing.
    pub all_targets: Vec<EcdfPoint>,
}

/// One budget of an entry's `fixed_budget`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BudgetPoint {
    /// The share of the smallest evaluation count of the searches.
    #[serde(deserialize_with = "nan::real")]
    pub fraction: Real,
    /// The budget in evaluations: the fraction of the budget, the mean over trials.
    #[serde(deserialize_with = "nan::real")]
    pub evaluations_mean: Real,
    /// Trials with a best fitness at this budget.
    pub n: usize,
    /// Mean over trials of the best fitness within the budget.
    #[serde(deserialize_with = "nan::real")]
    pub fitness_mean: Real,
    /// Its 95 % t interval.
    pub fitness_mean_ci95: Option<[Real; 2]>,
}

impl SearchAcc {
    /// Adds one trial's numbers.
    pub fn add(&mut self, r: &SearchRun) {
        self.trials += 1;
        for (m, h) in self.hits.iter_mut().zip(r.hits) {
            if let Some(e) = h {
                *m.entry(e).or_insert(0) += 1;
            }
        }
        for (acc, f) in self.budget.iter_mut().zip(r.at_budget) {
            if f.is_finite() {
                acc.0 += 1;
                acc.1 += f;
                acc.2 += f * f;
            }
        }
        self.budget_evals.0 += 1;
        self.budget_evals.1 += r.budget;
    }

    /// Whether no trial had a search trace.
    pub fn is_empty(&self) -> bool {
        self.trials == 0
    }

    /// The entry's `search_ecdf`.
    pub fn ecdf(&self) -> SearchEcdf {
        let n = self.trials;
        let targets = DELTAS
            .iter()
            .zip(&self.hits)
            .map(|(&delta, m)| {
                let mut k = 0;
                let points = m
                    .iter()
                    .map(|(&evaluations, &c)| {
                        k += c;
                        EcdfPoint {
                            evaluations,
                            share: k as Real / n as Real,
                        }
                    })
                    .collect();
                TargetEcdf {
                    delta,
                    points,
                    reached: k as Real / n as Real,
                    reached_ci95: wilson(k, n),
                }
            })
            .collect();
        let mut all: BTreeMap<usize, usize> = BTreeMap::new();
        for (&e, &c) in self.hits.iter().flatten() {
            *all.entry(e).or_insert(0) += c;
        }
        let pairs = (n * DELTAS.len()) as Real;
        let mut k = 0;
        let all_targets = all
            .into_iter()
            .map(|(evaluations, c)| {
                k += c;
                EcdfPoint {
                    evaluations,
                    share: k as Real / pairs,
                }
            })
            .collect();
        SearchEcdf {
            trials: n,
            targets,
            all_targets,
        }
    }

    /// The entry's `fixed_budget`.
    pub fn fixed_budget(&self) -> Vec<BudgetPoint> {
        let mean_budget = self.budget_evals.1 as Real / self.budget_evals.0.max(1) as Real;
        BUDGET_FRACTIONS
            .iter()
            .zip(&self.budget)
            .map(|(&fraction, &(n, s, s2))| {
                let m = s / n as Real;
                let var = (s2 - n as Real * m * m).max(0.0) / (n as Real - 1.0);
                BudgetPoint {
                    fraction,
                    evaluations_mean: (fraction * mean_budget).floor(),
                    n,
                    fitness_mean: m,
                    fitness_mean_ci95: dist::t_interval(m, var.sqrt(), n),
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_and_budgets_by_hand() {
        // 4 iterations of 10 evaluations each.
        let trace = [8.0, 4.0, 2.02, 2.0];
        let r = SearchRun::of(&trace, 40, 2.0, 40);
        // Targets 4, 2.2, 2.02, 2.002.
        assert_eq!(r.hits, [Some(20), Some(30), Some(30), Some(40)]);
        // Budgets 4, 10, 20, 40 evaluations.
        assert!(r.at_budget[0].is_nan());
        assert_eq!(r.at_budget[1..], [8.0, 4.0, 2.0]);
        // The end of its own budget: the last iteration's best fitness.
        assert_eq!(r.final_fitness, 2.0);
        assert!(SearchRun::of(&[], 0, 2.0, 40).final_fitness.is_nan());
    }

    #[test]
    fn reference_is_the_best_of_the_group() {
        let a = [3.0, 1.0];
        let b = [2.0, 2.0];
        let (g, other) = ((0, 1, "direct_fk"), (0, 1, "differential"));
        let c = [0.5];
        let runs = vec![
            Some((g, &a[..], 20)),
            None,
            Some((g, &b[..], 10)),
            Some((other, &c[..], 5)),
        ];
        let out = of_trial(&runs);
        assert!(out[1].is_none());
        let (ra, rb) = (out[0].clone().unwrap(), out[2].clone().unwrap());
        assert_eq!(ra.budget, 10);
        assert_eq!(ra.hits[0], Some(20));
        assert_eq!(rb.hits, [Some(5), None, None, None]);
        // Another fitness is its own reference: it reaches every target.
        assert_eq!(out[3].clone().unwrap().hits, [Some(5); 4]);
    }

    #[test]
    fn the_targets_aggregate_into_shares_of_trial_target_pairs() {
        let mut acc = SearchAcc::default();
        for hits in [
            [Some(10), Some(20), Some(20), None],
            [Some(20), Some(20), None, None],
        ] {
            acc.add(&SearchRun {
                budget: 40,
                hits,
                at_budget: [1.0; 4],
                final_fitness: 1.0,
            });
        }
        let e = acc.ecdf();
        let all: Vec<(usize, Real)> = e
            .all_targets
            .iter()
            .map(|p| (p.evaluations, p.share))
            .collect();
        // 8 pairs: 1 reached by 10 evaluations, 5 by 20.
        assert_eq!(all, [(10, 1.0 / 8.0), (20, 5.0 / 8.0)]);
        // The aggregate at the end is the mean of the targets' shares reached.
        let mean = e.targets.iter().map(|t| t.reached).sum::<Real>() / 4.0;
        assert_eq!(all[1].1, mean);
    }

    #[test]
    fn wilson_matches_a_known_value() {
        // 8 of 10, by hand: centre 0.71674, half-width 0.22657.
        let [lo, hi] = wilson(8, 10).unwrap();
        assert!((lo - 0.4902).abs() < 1e-4 && (hi - 0.9433).abs() < 1e-4);
        // All or none reached: the interval reaches 1 or 0 exactly (300 rounds just below).
        assert_eq!(wilson(300, 300).unwrap()[1], 1.0);
        assert_eq!(wilson(0, 300).unwrap()[0], 0.0);
    }
}
