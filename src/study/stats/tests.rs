//! The unit tests of [`super`]: η, the median ranks, the spill's order statistics and which
//! outcomes count.

use super::*;

#[test]
fn eta_is_guo_eq_29() {
    assert_eq!(eta(0.5, 0.5), Some(100.0));
    assert!((eta(0.5, 0.4).unwrap() - 80.0).abs() < 1e-12);
    assert!((eta(-0.05, -0.06).unwrap() - 80.0).abs() < 1e-12);
    assert_eq!(eta(0.0, 0.1), None);
}

#[test]
fn median_ranks_are_the_binomial_order_statistics() {
    // The largest l with scipy.stats.binom.cdf(l, n, 0.5) <= alpha / 2.
    assert_eq!(median_ranks(5, 0.05), None);
    assert_eq!(median_ranks(6, 0.05), Some((0, 5)));
    assert_eq!(median_ranks(20, 0.05), Some((5, 14)));
    assert_eq!(median_ranks(100, 0.05), Some((39, 60)));
    assert_eq!(median_ranks(1000, 0.05), Some((468, 531)));
    // Bonferroni over 16 parameters.
    assert_eq!(median_ranks(30, 0.05 / 16.0).map(|r| r.0), Some(6));
}

/// A rank-deficient ending expected of the identified list counts, unless the method
/// never started (fewer readings than parameters).
#[test]
fn a_method_that_never_started_is_a_failure() {
    let stats = crate::calibrate::ErrorStats {
        rms: 0.1,
        ..Default::default()
    };
    let o = |iterations| Outcome {
        method: 0,
        strategy: 0,
        identified: vec![0.0; 3],
        before_mm: stats,
        after_mm: stats,
        calibration_before_mm: stats,
        calibration_after_mm: stats,
        optional: Default::default(),
        per_point: None,
        per_point_attitude_deg: None,
        trace: None,
        search: None,
        iterations,
        evaluations: 0,
        termination: Termination::RankDeficient,
        rank_deficient_expected: true,
        seconds: 0.0,
        error: None,
    };
    assert!(usable(&o(4)));
    assert!(!usable(&o(0)));
    // Poses that happen to leave an identifiable list undetermined: a failure, damped or not.
    let unexpected = Outcome {
        rank_deficient_expected: false,
        ..o(4)
    };
    assert!(!usable(&unexpected));
}

#[test]
fn median_and_std_by_hand() {
    let mut s = Spill::new(2);
    for (k, v) in [(0, [3.0, 1.0, 2.0].as_slice()), (1, &[4.0, 1.0, 2.0, 3.0])] {
        v.iter().for_each(|&x| s.push(k, x).expect("push"));
    }
    assert_eq!(s.median(0).unwrap(), 2.0);
    assert_eq!(s.median(1).unwrap(), 2.5);
    assert!((s.std(1).unwrap() - 1.118033988749895).abs() < 1e-12);
}
