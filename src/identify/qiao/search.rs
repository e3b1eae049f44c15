//! What the three searches share: the search box ([`Bounds`]), the result ([`MetaResult`]),
//! the evaluation budget, the Halton initial points (Qiao 2021 §3.1), the beetle's random
//! direction and eq. 13's schedules, and the checks of their options.

use rand::Rng as _;

use crate::error::{Error, Result};
use crate::identify::options;
use crate::numeric::rng::Rng;
use crate::numeric::Real;

/// The search box: `lower[i] ≤ x[i] ≤ upper[i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Bounds {
    /// Lower bounds.
    pub lower: Vec<Real>,
    /// Upper bounds.
    pub upper: Vec<Real>,
}

impl Bounds {
    /// The box `[−w_i, w_i]` for half widths `w`.
    pub fn symmetric(half_widths: &[Real]) -> Bounds {
        Bounds {
            lower: half_widths.iter().map(|w| -w).collect(),
            upper: half_widths.to_vec(),
        }
    }

    /// Number of coordinates.
    pub fn dim(&self) -> usize {
        self.lower.len()
    }

    /// Checks that the box is non-empty, finite and not inverted (setting `bounds`).
    pub fn check(&self) -> Result<()> {
        if self.lower.is_empty() {
            return Err(Error::setting("bounds", "no coordinates to search"));
        }
        if self.lower.len() != self.upper.len() {
            return Err(Error::setting(
                "bounds",
                format!(
                    "{} lower bounds but {} upper bounds",
                    self.lower.len(),
                    self.upper.len()
                ),
            ));
        }
        for (i, (l, u)) in self.lower.iter().zip(&self.upper).enumerate() {
            if !l.is_finite() || !u.is_finite() {
                return Err(Error::setting(
                    "bounds",
                    format!("coordinate {i}: bounds must be finite, got [{l}, {u}]"),
                ));
            }
            if l > u {
                return Err(Error::setting(
                    "bounds",
                    format!("coordinate {i}: lower bound {l} is above upper bound {u}"),
                ));
            }
        }
        Ok(())
    }

    /// `x = lower + y ⊙ (upper − lower)`.
    #[inline]
    pub(super) fn to_x(&self, y: &[Real], x: &mut [Real]) {
        for i in 0..y.len() {
            x[i] = self.lower[i] + y[i] * (self.upper[i] - self.lower[i]);
        }
    }
}

/// The outcome of a search. Running out of iterations is the normal end, not an error.
#[derive(Clone, Debug, PartialEq)]
pub struct MetaResult {
    /// The best point found.
    pub x: Vec<Real>,
    /// Its fitness.
    pub fitness: Real,
    /// The best fitness after each iteration.
    pub trace: Vec<Real>,
    /// Number of fitness evaluations.
    pub evaluations: usize,
    /// Number of iterations run.
    pub iterations: usize,
    /// The search stopped because the best fitness reached the target.
    pub reached_target: bool,
    /// The search stopped because its evaluation budget (`max_evaluations`) could not pay
    /// for another iteration.
    pub budget_spent: bool,
}

impl MetaResult {
    /// The result of a search that ended at `x` with fitness `f`, the best fitness per
    /// iteration `trace`, after `evaluations` evaluations, with the target fitness `target`.
    pub(super) fn new(
        x: Vec<Real>,
        f: Real,
        trace: Vec<Real>,
        evaluations: usize,
        target: Real,
        limit: Limit,
    ) -> Self {
        let reached_target = f <= target;
        MetaResult {
            x,
            reached_target,
            budget_spent: !reached_target && limit.by_budget && trace.len() == limit.iterations,
            fitness: f,
            iterations: trace.len(),
            trace,
            evaluations,
        }
    }
}

/// How many iterations a search runs: `iterations`, or fewer when the evaluation budget
/// runs out first (`by_budget`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Limit {
    pub(super) iterations: usize,
    pub(super) by_budget: bool,
}

impl Limit {
    /// At most `iterations` iterations of `per_iteration` evaluations each, after `initial`
    /// evaluations, within `max_evaluations` evaluations in all.
    pub(super) fn of(
        iterations: usize,
        max_evaluations: Option<usize>,
        initial: usize,
        per_iteration: usize,
    ) -> Limit {
        match max_evaluations {
            Some(budget) => {
                let affordable = budget.saturating_sub(initial) / per_iteration.max(1);
                Limit {
                    iterations: iterations.min(affordable),
                    by_budget: affordable < iterations,
                }
            }
            None => Limit {
                iterations,
                by_budget: false,
            },
        }
    }
}

/// Checks that the budget `max_evaluations` pays for the `initial` evaluations and at least
/// one iteration of `per_iteration` evaluations.
pub(super) fn check_budget(
    max_evaluations: Option<usize>,
    initial: usize,
    per_iteration: usize,
) -> Result<()> {
    match max_evaluations {
        Some(b) if b < initial + per_iteration => Err(Error::setting(
            "max_evaluations",
            format!(
                "must pay for the {initial} initial evaluations and one iteration of \
                 {per_iteration}: at least {}, got {b}",
                initial + per_iteration
            ),
        )),
        _ => Ok(()),
    }
}

/// The fitness to minimise.
pub type Fitness<'f> = dyn Fn(&[Real]) -> Real + Sync + 'f;

/// Checks the `target` fitness of a search: below +∞.
pub(super) fn check_target(v: Real) -> Result<()> {
    if v.is_nan() || v == Real::INFINITY {
        Err(Error::setting(
            "target",
            format!("must be below +∞, got {}", crate::error::shown(v)),
        ))
    } else {
        Ok(())
    }
}

/// A fitness value with NaN mapped to `+∞`.
#[inline]
pub(super) fn sane(v: Real) -> Real {
    if v.is_nan() {
        Real::INFINITY
    } else {
        v
    }
}

/// The antenna width and step schedules of eq. 13, `d ← decay·d + d0`, `δ ← decay·δ + δ0`,
/// of BAS and of BAS-PSO's beetle term (each with its own defaults). Widths and steps are
/// fractions of each coordinate's range. The checks are on the fields: a bad value is
/// refused as it is read, and [`Schedules::check`] reads values set in code the same way.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Schedules {
    /// Initial antenna width `d`, > 0.
    #[serde(deserialize_with = "options::positive")]
    pub antenna: Real,
    /// Initial step `δ`, > 0.
    #[serde(deserialize_with = "options::positive")]
    pub step: Real,
    /// Decay factor of both schedules (Qiao: 0.95), in [0, 1).
    #[serde(deserialize_with = "options::fraction")]
    pub decay: Real,
    /// `d0`: the width tends to `d0 / (1 − decay)`, ≥ 0.
    #[serde(rename = "antenna_floor", deserialize_with = "options::non_negative")]
    pub d0: Real,
    /// `δ0`: the step tends to `δ0 / (1 − decay)`, ≥ 0.
    #[serde(rename = "step_floor", deserialize_with = "options::non_negative")]
    pub delta0: Real,
}

impl Schedules {
    /// Width and step `d`, `δ` from `antenna`, `step`, decaying by `decay` towards the
    /// floors `d0 / (1 − decay)`, `δ0 / (1 − decay)`.
    pub const fn new(antenna: Real, step: Real, decay: Real, d0: Real, delta0: Real) -> Self {
        Schedules {
            antenna,
            step,
            decay,
            d0,
            delta0,
        }
    }

    /// Checks the values (as a scenario's are checked); the error names the key.
    pub fn check(&self) -> Result<()> {
        options::recheck(self)
    }

    /// One step of eq. 13: the next `(d, δ)`.
    #[inline]
    pub(super) fn next(&self, d: Real, delta: Real) -> (Real, Real) {
        eq13(d, delta, self.decay, self.d0, self.delta0)
    }
}

/// The options key of a search's iteration count, checked here for every search.
pub(super) fn check_iterations(n: usize) -> Result<()> {
    check_count_at_most("iterations", n, MAX_ITERATIONS)
}

/// The most iterations a search may run (Qiao's longest is 20 000): more would run until
/// killed, and the trace kept per iteration could not be allocated.
pub const MAX_ITERATIONS: usize = 10_000_000;

/// The most particles a swarm may have (Qiao's 40).
pub const MAX_POPULATION: usize = 1_000_000;

/// Refuses the count `n` of `key` below 1 or above `most`.
pub(super) fn check_count_at_most(key: &str, n: usize, most: usize) -> Result<()> {
    crate::error::check_count(key, n)?;
    if n > most {
        return Err(Error::setting(
            key,
            format!("must be at most {most}, got {n}"),
        ));
    }
    Ok(())
}

/// The `index`-th element of the van der Corput sequence in `base` (the radical inverse of
/// `index`): the coordinate of the Halton sequence for that base (Qiao §3.1). `halton(0, b)`
/// is 0; bases below 2 give 0.
pub fn halton(index: usize, base: u32) -> Real {
    if base < 2 {
        return 0.0;
    }
    let b = base as usize;
    let inv = 1.0 / base as Real;
    let mut f = inv;
    let mut r = 0.0;
    let mut i = index;
    while i > 0 {
        r += f * (i % b) as Real;
        i /= b;
        f *= inv;
    }
    r
}

/// The first `n` primes.
pub(super) fn primes(n: usize) -> Vec<u32> {
    let mut out: Vec<u32> = Vec::with_capacity(n);
    let mut c = 2u32;
    while out.len() < n {
        if out
            .iter()
            .take_while(|p| *p * *p <= c)
            .all(|p| !c.is_multiple_of(*p))
        {
            out.push(c);
        }
        c += 1;
    }
    out
}

/// `n` points of the Halton sequence scaled into `bounds`: point `i` has coordinate `d` equal
/// to `halton(i + 1, p_d)` with `p_d` the `d`-th prime (Qiao §3.1's quasi-random initial
/// population). Same as [`halton_population_at`] with `start = 0`.
pub fn halton_population(n: usize, bounds: &Bounds) -> Vec<Vec<Real>> {
    halton_population_at(0, n, bounds)
}

/// `n` points of the Halton sequence from index `start + 1` on, scaled into `bounds`. The
/// searches start from a random `start` (drawn from their generator) so that repeated runs,
/// as in Qiao §4.2, begin from different, still evenly spread, populations.
pub fn halton_population_at(start: usize, n: usize, bounds: &Bounds) -> Vec<Vec<Real>> {
    let ps = primes(bounds.dim());
    (0..n)
        .map(|i| {
            let y: Vec<Real> = ps.iter().map(|&p| halton(start + i + 1, p)).collect();
            let mut x = vec![0.0; y.len()];
            bounds.to_x(&y, &mut x);
            x
        })
        .collect()
}

/// Largest Halton start offset drawn by the searches.
pub(super) const HALTON_SKIP: usize = 4096;

/// A random unit direction (components uniform in [−1, 1], normalised; Jiang & Li's BAS).
pub(super) fn random_direction(rng: &mut Rng, b: &mut [Real]) {
    let mut n2 = 0.0;
    for v in b.iter_mut() {
        *v = rng.random_range(-1.0..=1.0);
        n2 += *v * *v;
    }
    let n = n2.sqrt();
    if n > 1e-12 {
        b.iter_mut().for_each(|v| *v /= n);
    } else {
        b.iter_mut().for_each(|v| *v = 0.0);
        b[0] = 1.0;
    }
}

/// `out = clamp(y + s·b, 0, 1)`.
#[inline]
pub(super) fn offset(y: &[Real], b: &[Real], s: Real, out: &mut [Real]) {
    for i in 0..y.len() {
        out[i] = (y[i] + s * b[i]).clamp(0.0, 1.0);
    }
}

/// The schedules of Qiao's eq. 13: `d ← decay·d + d0`, `δ ← decay·δ + δ0`.
#[inline]
pub(super) fn eq13(d: Real, delta: Real, decay: Real, d0: Real, delta0: Real) -> (Real, Real) {
    (decay * d + d0, decay * delta + delta0)
}

/// True once the best fitness of the last iteration is at or below `target`.
#[inline]
pub(super) fn reached(trace: &[Real], target: Real) -> bool {
    trace.last().is_some_and(|&f| f <= target)
}

/// `sign(fr − fl)` with infinities handled and 0 for ties.
#[inline]
pub(super) fn sign(fr: Real, fl: Real) -> Real {
    if fr < fl {
        -1.0
    } else if fr > fl {
        1.0
    } else {
        0.0
    }
}
