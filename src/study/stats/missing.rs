//! What a reader of `summary.json` gets for a figure the file lacks (a summary written before
//! the figure existed, or edited): NaN, as a `null` figure reads, so that no reader takes
//! it for a value — `check` counts a baseline's figure missing from the summary as a
//! regression (docs/formats.md § 8.4); an interval or a map it lacks is none.

use std::collections::BTreeMap;

use super::{Entry, Figures, Spread};
use crate::calibrate::ErrorStats;
use crate::numeric::Real;
use crate::study::metric::PerTrial;

/// Figures a summary lacks: every statistic NaN (as `null` reads), no interval.
impl Default for Figures {
    fn default() -> Self {
        let nan = Real::NAN;
        Figures {
            stats: ErrorStats {
                mean: nan,
                rms: nan,
                max: nan,
                std: nan,
            },
            mean_ci95: None,
            rms_ci95: None,
            max_ci95: None,
            std_ci95: None,
        }
    }
}

impl Default for Entry {
    fn default() -> Self {
        let nan = Real::NAN;
        Entry {
            method: String::new(),
            poses: String::new(),
            sweep_value: None,
            sweep: None,
            eta_mean_pct: nan,
            eta_mean_pct_ci95: None,
            eta_median_pct: nan,
            eta_median_pct_ci95: None,
            eta: BTreeMap::new(),
            validation_before_mm: Figures::default(),
            validation_after_mm: Figures::default(),
            calibration_before_mm: Figures::default(),
            calibration_after_mm: Figures::default(),
            optional: BTreeMap::new(),
            improvement_pct: nan,
            param_rmse: BTreeMap::new(),
            param_rmse_ci95: BTreeMap::new(),
            param_bias: BTreeMap::new(),
            crb_ratio: None,
            failures: 0,
            terminations: BTreeMap::new(),
            iterations_mean: nan,
            evaluations_mean: nan,
            seconds_per_identification: nan,
            search_ecdf: None,
            fixed_budget: None,
            final_fitness: None,
            spread: Spread::default(),
            per_trial: PerTrial::default(),
            eta_per_trial: BTreeMap::new(),
            eta_not_determinable: BTreeMap::new(),
        }
    }
}
