//! [`analyse`]: a run's result into its [`Summary`], once per run, merge or resume.

use std::collections::BTreeMap;

use super::claims::evaluations;
use super::comparisons::comparisons;
use super::summary::{EntryProfile, FixedPoseSet, Profile, Summary, FORMAT};
use crate::numeric::Real;
use crate::study::metric::Metric;
use crate::study::{toml_to_json, Block, RunResult};

/// The relative distance from the final objective within which a pose optimisation counts
/// as settled (`settled_iteration` in `summary.json`).
pub const SETTLED: Real = 1e-3;

/// The first iteration (1-based) from which the objective `trace` stays within `rel` of
/// its final value (relative to it): the iteration count at which an objective curve such
/// as Guo 2024 fig. 6 flattens. `None` for an empty trace.
pub fn settled_iteration(trace: &[Real], rel: Real) -> Option<usize> {
    let last = *trace.last()?;
    let tol = rel * last.abs();
    let outside = trace.iter().rposition(|v| (v - last).abs() > tol);
    Some(outside.map_or(1, |i| i + 2))
}

/// The factors τ of the performance profiles ([`performance_profile`]).
pub const PROFILE_TAUS: [Real; 12] = [
    1.0, 1.01, 1.02, 1.05, 1.1, 1.2, 1.5, 2.0, 3.0, 5.0, 10.0, 100.0,
];

/// The performance profiles of a sweep (Dolan & Moré 2002, *Math. Program.* 91): at every
/// sweep point, each entry's validation RMS after compensation over the best of the point's
/// entries (the ratio r; `null`, never within any τ, where the entry failed), and for each
/// entry the share of points where r ≤ τ for τ in [`PROFILE_TAUS`]. `None` without a sweep
/// of two or more points.
pub fn performance_profile(r: &RunResult) -> Option<Profile> {
    r.scenario.sweep.as_ref()?;
    if r.blocks.len() < 2 {
        return None;
    }
    let entries = r.blocks[0].entries.len();
    let metric = |b: &Block, k: usize| {
        b.entries
            .get(k)
            .map_or(Real::NAN, |e| e.validation_after_mm.rms)
    };
    let best: Vec<Real> = r
        .blocks
        .iter()
        .map(|b| {
            (0..entries)
                .map(|k| metric(b, k))
                .filter(|m| m.is_finite())
                .fold(Real::INFINITY, Real::min)
        })
        .collect();
    let profiles = (0..entries)
        .map(|k| {
            let ratio: Vec<Option<Real>> = r
                .blocks
                .iter()
                .zip(&best)
                .map(|(b, &best)| {
                    let m = metric(b, k);
                    let ratio = if m == best { 1.0 } else { m / best };
                    ratio.is_finite().then_some(ratio)
                })
                .collect();
            let share = PROFILE_TAUS
                .iter()
                .map(|&tau| {
                    let within = ratio.iter().filter(|x| x.is_some_and(|x| x <= tau));
                    within.count() as Real / ratio.len() as Real
                })
                .collect();
            let e = &r.blocks[0].entries[k];
            let (method, poses) = (e.method.clone(), e.poses.clone());
            EntryProfile {
                method,
                poses,
                ratio,
                share,
            }
        })
        .collect();
    Some(Profile {
        metric: Metric::ValidationAfterRms,
        tau: PROFILE_TAUS.to_vec(),
        profiles,
    })
}

/// What a run's trials say: its entries with their intervals, every paired comparison
/// Holm-adjusted together, the claims' verdicts, the searches' ECDFs and fixed-budget curves
/// (in the entries), the performance profile of a sweep and the stopping record. Fails only
/// when the per-trial values cannot be read back from the study's scratch file.
pub fn analyse(r: &RunResult) -> crate::error::Result<Summary> {
    let sc = &r.scenario;
    let first = &r.blocks[0].info;
    let mut fixed_pose_sets = BTreeMap::new();
    for (s, set) in first.strategies.iter().zip(&first.fixed) {
        if let Some(set) = set {
            let settled = settled_iteration(&set.trace, SETTLED);
            fixed_pose_sets.insert(
                s.clone(),
                FixedPoseSet {
                    poses: set.poses,
                    iterations: set.trace.len(),
                    final_objective: set.trace.last().copied(),
                    scores: set.scores.clone(),
                    trace: set.trace.clone(),
                    settled_iteration: settled,
                },
            );
        }
    }
    let (comparisons, shown, differences) = comparisons(r)?;
    let sweep = sc.sweep.as_ref();
    let axis = sweep.and_then(|sw| match sw.axes.as_slice() {
        [axis] => Some(axis),
        _ => None,
    });
    Ok(Summary {
        format: FORMAT,
        scenario: sc.name.clone(),
        description: sc.description.clone(),
        robot: first.robot.clone(),
        trials: Some(sc.trials),
        seed: Some(sc.seed),
        measure: Summary::MEASURES[usize::from(first.full_pose)].into(),
        registration: sc.registration.as_str().into(),
        parameters: first.params.clone(),
        error_parameters: first.error_params.clone(),
        fixed_pose_sets,
        fitness_trace_trial0: r.blocks[0].fitness_traces().into_iter().collect(),
        timing: "timing.json".into(),
        results: r.blocks.iter().flat_map(|b| b.entries.clone()).collect(),
        comparisons,
        claims: if sc.claims.is_empty() {
            None
        } else {
            Some(evaluations(r)?)
        },
        performance_profile: performance_profile(r),
        stopping: r.stopping.clone(),
        separation: first.separation.clone(),
        // The simulated arm's compliances, from the first sweep point that sags.
        true_compliance: r.blocks.iter().find_map(|b| b.info.true_compliance.clone()),
        sweep_key: axis.map(|a| a.key.clone()),
        sweep_values: axis.map(|a| a.values.iter().map(toml_to_json).collect()),
        sweep_keys: sweep.map(|sw| sw.keys().into_iter().map(String::from).collect()),
        sweep_zip: sweep.map(|sw| sw.zip),
        shown,
        differences,
    })
}

#[cfg(test)]
mod tests {
    use super::settled_iteration;

    #[test]
    fn settled_iteration_is_where_the_curve_stays_near_its_end() {
        assert_eq!(settled_iteration(&[], 1e-3), None);
        assert_eq!(settled_iteration(&[2.0], 1e-3), Some(1));
        // Within 0.1 % of 2.0 from the fourth value on (1.9985 is 0.075 % away).
        let t = [1.0, 1.5, 1.99, 1.9985, 1.9995, 2.0];
        assert_eq!(settled_iteration(&t, 1e-3), Some(4));
        // A dip after settling counts as not settled yet.
        let t = [1.0, 2.0, 1.0, 2.0];
        assert_eq!(settled_iteration(&t, 1e-3), Some(4));
    }
}
