//! Beetle antennae search (Jiang & Li 2017; Qiao 2021 §3.1, eq. 13): [`bas`] and its
//! options.

use rand::Rng as _;

use super::search::{
    check_budget, check_iterations, check_target, halton, offset, primes, random_direction,
    reached, sane, sign, Bounds, Fitness, Limit, MetaResult, Schedules, HALTON_SKIP,
};
use crate::error::Result;
use crate::numeric::rng::Rng;
use crate::numeric::Real;

/// Options of [`bas`]. Lengths are fractions of each coordinate's range (see the module docs).
///
/// Qiao 2021 gives the schedules of eq. 13 (`d ← 0.95·d + d0`, `δ ← 0.95·δ + δ0`) but no
/// values for the widths or the start; the defaults here are this implementation's choice,
/// tuned on the TX60 problem of the tests (24 parameters, ±2 mm / ±0.02 rad box, ACPE
/// 0.92 mm before): a beetle starting at the nominal parameters with steps of 5 % of the
/// range, falling to a floor of 0.2 % (`δ0 / (1 − decay)`), keeps moving through its 2000
/// iterations and ends at 0.02–0.05 mm. With a floor of 0.02 % it freezes after about 150
/// iterations; from a random Halton start in 24 dimensions it ends worse than the nominal
/// model (2.2–2.8 mm).
#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BasOptions {
    /// Iterations (3 fitness evaluations each). Default 2000.
    pub iterations: usize,
    /// Budget of fitness evaluations: the search stops before an iteration that would
    /// exceed it (and after `iterations` at the latest), so that searches of different
    /// cost per iteration can be compared at equal budgets. Default none.
    pub max_evaluations: Option<usize>,
    /// Stop as soon as the best fitness is at or below this. Default −∞ (never).
    pub target: Real,
    /// Where the beetle starts. Default [`BasStart::Centre`].
    pub start: BasStart,
    /// The schedules of eq. 13, keys of their own ([`Schedules`]). Default: width and step
    /// 0.05, decay 0.95, floors 1e-4.
    #[serde(skip)]
    pub schedules: Schedules,
}

/// The starting point of [`bas`] (`start = "centre"` or `"halton"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BasStart {
    /// The centre of the search box: the nominal parameters for
    /// [`MetaProblem::bounds`](super::MetaProblem::bounds).
    #[serde(alias = "center")]
    Centre,
    /// A Halton point with a random index (Qiao's initialisation of the swarms).
    Halton,
}

impl BasOptions {
    /// Checks the option values (keys as in the scenario).
    pub fn check(&self) -> Result<()> {
        check_iterations(self.iterations)?;
        check_budget(self.max_evaluations, 1, 3)?;
        self.schedules.check()?;
        check_target(self.target)
    }
}

impl Default for BasOptions {
    fn default() -> Self {
        BasOptions {
            iterations: 2000,
            max_evaluations: None,
            target: Real::NEG_INFINITY,
            start: BasStart::Centre,
            schedules: Schedules::new(0.05, 0.05, 0.95, 1e-4, 1e-4),
        }
    }
}

/// Beetle antennae search (Jiang & Li 2017; Qiao 2021 §3.1, eq. 13 with its schedules).
///
/// One beetle at `y` (normalised coordinates) draws a random unit direction `b`, compares
/// the fitness at its antennae `y ± d·b` and moves by `δ` towards the better one:
/// `y ← y − δ·b·sign(f(y + d·b) − f(y − d·b))`; then `d ← decay·d + d0`,
/// `δ ← decay·δ + δ0`. The best point seen is returned. The beetle starts at the centre of
/// the box or at a Halton point with a random index ([`BasOptions::start`]).
///
/// Qiao's eq. 13 as printed reads `+δ·b·sign(…)`, which climbs; the minus sign of Jiang &
/// Li's minimising BAS is used here.
pub fn bas(f: &Fitness, b: &Bounds, o: &BasOptions, rng: &mut Rng) -> Result<MetaResult> {
    b.check()?;
    o.check()?;

    let n = b.dim();
    let mut y: Vec<Real> = match o.start {
        BasStart::Centre => vec![0.5; n],
        BasStart::Halton => {
            let start = rng.random_range(0..HALTON_SKIP) + 1;
            primes(n).iter().map(|&p| halton(start, p)).collect()
        }
    };
    let mut x = vec![0.0; n];
    let mut dir = vec![0.0; n];
    let mut yl = vec![0.0; n];
    let mut yr = vec![0.0; n];
    b.to_x(&y, &mut x);
    let mut best_f = sane(f(&x));
    let mut best_x = x.clone();
    let mut evaluations = 1;
    let (mut d, mut delta) = (o.schedules.antenna, o.schedules.step);
    let limit = Limit::of(o.iterations, o.max_evaluations, 1, 3);
    let mut trace = Vec::with_capacity(limit.iterations);
    while trace.len() < limit.iterations && !reached(&trace, o.target) {
        random_direction(rng, &mut dir);
        offset(&y, &dir, d, &mut yr);
        offset(&y, &dir, -d, &mut yl);
        b.to_x(&yr, &mut x);
        let fr = sane(f(&x));
        b.to_x(&yl, &mut x);
        let fl = sane(f(&x));
        let s = sign(fr, fl);
        for i in 0..n {
            y[i] = (y[i] - delta * dir[i] * s).clamp(0.0, 1.0);
        }
        b.to_x(&y, &mut x);
        let fy = sane(f(&x));
        evaluations += 3;
        for (v, xv) in [(fr, &yr), (fl, &yl)] {
            if v < best_f {
                best_f = v;
                b.to_x(xv, &mut best_x);
            }
        }
        if fy < best_f {
            best_f = fy;
            best_x.copy_from_slice(&x);
        }
        (d, delta) = o.schedules.next(d, delta);
        trace.push(best_f);
    }
    Ok(MetaResult::new(
        best_x,
        best_f,
        trace,
        evaluations,
        o.target,
        limit,
    ))
}
