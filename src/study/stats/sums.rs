//! Running sums over trials in trial order: a sum, a spread (Welford) and the four error
//! statistics of [`ErrorStats`] with their spreads, the state of an [`super::Accumulator`]
//! cell.

use super::{dist, Figures};
use crate::calibrate::ErrorStats;
use crate::numeric::Real;

/// The sum of `v` in order (as `Iterator::sum`, from −0), streamed one value at a time.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sum {
    total: Real,
    pub(super) n: usize,
}

impl Default for Sum {
    fn default() -> Self {
        Sum { total: -0.0, n: 0 }
    }
}

impl Sum {
    pub(super) fn add(&mut self, x: Real) {
        self.total += x;
        self.n += 1;
    }
    pub(super) fn mean(&self) -> Real {
        if self.n == 0 {
            Real::NAN
        } else {
            self.total / self.n as Real
        }
    }
}

/// The running spread of values in trial order (Welford's update): the sample standard
/// deviation of an interval without keeping the values.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Spread2 {
    n: usize,
    mean: Real,
    m2: Real,
}

impl Spread2 {
    pub(super) fn add(&mut self, x: Real) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as Real;
        self.m2 += d * (x - self.mean);
    }
    /// The sample standard deviation (divisor n − 1; NaN under 2 values).
    pub(super) fn sd(&self) -> Real {
        if self.n < 2 {
            Real::NAN
        } else {
            (self.m2 / (self.n - 1) as Real).sqrt()
        }
    }
    /// The 95 % t interval around `mean` (the in-order mean of the same values).
    pub(super) fn interval(&self, mean: Real) -> Option<[Real; 2]> {
        dist::t_interval(mean, self.sd(), self.n)
    }
}

/// Running sums of the four statistics of [`ErrorStats`] over trials, with their spreads.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct StatsSum(pub(super) [Sum; 4], pub(super) [Spread2; 4]);

impl StatsSum {
    pub(super) fn add(&mut self, s: &ErrorStats) {
        for ((a, v), x) in self
            .0
            .iter_mut()
            .zip(&mut self.1)
            .zip([s.mean, s.rms, s.max, s.std])
        {
            a.add(x);
            v.add(x);
        }
    }
    pub(super) fn average(&self) -> Figures {
        let stats = ErrorStats {
            mean: self.0[0].mean(),
            rms: self.0[1].mean(),
            max: self.0[2].mean(),
            std: self.0[3].mean(),
        };
        let ci = |i: usize, m: Real| self.1[i].interval(m);
        Figures {
            mean_ci95: ci(0, stats.mean),
            rms_ci95: ci(1, stats.rms),
            max_ci95: ci(2, stats.max),
            std_ci95: ci(3, stats.std),
            stats,
        }
    }
}
