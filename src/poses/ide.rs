//! Improved differential evolution over a pose set (Guo 2024 §3.2, eqs. 19–26).
//!
//! An individual is a whole set of M poses. From the start set ε (the DETMAX set, or a random
//! subset):
//!
//! 1. **Gaussian initial population** (eq. 19): `population` sets x_p = ε + σ·(q_max − q_min)
//!    ·N(0, 1), element by element, brought inside the limits by the reverse search of
//!    eqs. 23–24 around ε. This population is the fixed library the difference vectors are
//!    drawn from (the paper's "备选测量构型库").
//!
//!    **Changed from the paper:** Guo's eq. 19 is x = ε + ε·Gauss(0, 1), noise proportional
//!    to each joint value with a standard deviation of 100 % of it. A joint at 0 would then
//!    never move, a prismatic joint (mm) and a revolute one (rad) would be perturbed on
//!    unrelated scales, and most values would land past the limits (to be pulled back by
//!    eqs. 23–24). calbench scales the noise by the joint's range, σ·(q_max − q_min), σ =
//!    `sigma` (docs/formats.md; REPRODUCTION.md, Guo 2024).
//! 2. Per generation g = 1..G, with the adaptive factor F = F0 − log2(1 + (g − 1)/G) (eq. 21),
//!    for each of `population` trials:
//!    - **mutation** (eq. 20): e = ε_opt + F (x_r1 − x_r2) + F (x_r3 − x_r4), r1..r4 distinct;
//!    - **second mutation toward the best** (eq. 22): v_t ← v_t + F (ε_opt − v_t)
//!      + F (x_r5 − x_r6), r5 ≠ r6, each trial keeping its own v track (started at x_t);
//!    - **reverse-search limit handling** (eqs. 23–24) of e and v_t around ε_opt: a value past
//!      the upper limit becomes ε_opt + (q_max − ε_opt)·(e − q_max)/(e − ε_opt), past the lower
//!      limit ε_opt − (ε_opt − q_min)·(q_min − e)/(ε_opt − e), so it lands between ε_opt and
//!      the limit it crossed;
//!    - **crossover** (eq. 25): pose i of h is pose i of e with probability cr, else pose i of
//!      ε_opt (one random pose always comes from e, as in classic DE);
//! 3. **greedy selection** (eq. 26): ε_opt becomes the best of itself, every h and every v_t
//!    (a candidate must beat ε_opt strictly; ties keep ε_opt, then the earlier trial).
//!
//! The objective of ε_opt is recorded after each generation, so it never decreases.
//! Random numbers are drawn sequentially; the 2·`population` objective evaluations of a
//! generation run on rayon, so results do not depend on the thread count.

use rand::Rng as _;
use rand_distr::StandardNormal;
use rayon::prelude::*;

use super::{Evaluator, KnownBlocks, Objective, PoseModel, Spectra};
use crate::numeric::rng::Rng;
use crate::numeric::Real;
use crate::Error;

/// Settings of the IDE stage (Guo 2024 eqs. 19–26; the paper gives no values, these
/// defaults are calbench's).
#[derive(Clone, Debug, PartialEq)]
pub struct IdeOptions {
    /// Size of the initial population (the difference-vector library) and number of trials
    /// per generation; at least 6 (eqs. 20 and 22 draw r1..r4 and r5, r6).
    pub population: usize,
    /// Number of generations G.
    pub generations: usize,
    /// Initial mutation factor F0 of eq. 21 (F falls to about F0 − 1 at g = G).
    pub f0: Real,
    /// Crossover rate cr of eq. 25, in [0, 1].
    pub cr: Real,
    /// σ of the initial Gaussian mutation (eq. 19), as a fraction of each joint's range.
    pub sigma: Real,
}

impl Default for IdeOptions {
    /// population 16, 60 generations, F0 = 1, cr = 0.3, σ = 0.05.
    fn default() -> Self {
        IdeOptions {
            population: 16,
            generations: 60,
            f0: 1.0,
            cr: 0.3,
            sigma: 0.05,
        }
    }
}

impl IdeOptions {
    /// Checks the ranges of the settings.
    pub fn check(&self) -> crate::Result<()> {
        if self.population < 6 {
            return Err(Error::setting(
                "ide.population",
                format!("{}: at least 6 needed", self.population),
            ));
        }
        if !(self.f0.is_finite() && self.f0 > 0.0) {
            return Err(Error::setting("ide.f0", "must be finite and positive"));
        }
        if !(0.0..=1.0).contains(&self.cr) {
            return Err(Error::setting("ide.cr", "must be in [0, 1]"));
        }
        if !(self.sigma.is_finite() && self.sigma >= 0.0) {
            return Err(Error::setting("ide.sigma", "must be finite and ≥ 0"));
        }
        Ok(())
    }
}

/// What [`ide`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct IdeResult {
    /// The best pose set.
    pub poses: Vec<Vec<Real>>,
    /// Candidate index of each pose (kept while a start pose survives unchanged).
    pub indices: Vec<Option<usize>>,
    /// Objective of the start set.
    pub start_value: Real,
    /// Objective of the best set after each generation.
    pub trace: Vec<Real>,
    /// Why the search stopped.
    pub termination: String,
}

/// The adaptive mutation factor F = F0 − log2(1 + (g − 1)/G) (Guo 2024 eq. 21), g = 1..G.
pub fn mutation_factor(f0: Real, g: usize, generations: usize) -> Real {
    f0 - (1.0 + (g as Real - 1.0) / generations.max(1) as Real).log2()
}

/// Reverse-search limit handling (Guo 2024 eqs. 23–24) of value `x` around the in-limit
/// `best`: a value past a limit is mapped between `best` and that limit, in proportion to
/// how far it overshot.
pub fn reverse_search(x: Real, best: Real, lo: Real, hi: Real) -> Real {
    let y = if x > hi {
        let d = x - best;
        if d > 0.0 {
            best + (hi - best).abs() * ((x - hi) / d)
        } else {
            hi
        }
    } else if x < lo {
        let d = best - x;
        if d > 0.0 {
            best - (best - lo).abs() * ((lo - x) / d)
        } else {
            lo
        }
    } else {
        x
    };
    // `best` inside the limits makes y inside too; the clamp guards rounding only.
    y.clamp(lo, hi)
}

fn handle_limits(set: &mut [Real], best: &[Real], limits: &[(Real, Real)]) {
    let dof = limits.len();
    for (i, x) in set.iter_mut().enumerate() {
        let (lo, hi) = limits[i % dof];
        *x = reverse_search(*x, best[i], lo, hi);
    }
}

/// `n` distinct indices below `pop` (n ≤ 6 ≤ pop), by rejection.
fn distinct<const N: usize>(rng: &mut Rng, pop: usize) -> [usize; N] {
    let mut out = [0usize; N];
    let mut i = 0;
    while i < N {
        let c = rng.random_range(0..pop);
        if !out[..i].contains(&c) {
            out[i] = c;
            i += 1;
        }
    }
    out
}

/// IDE (Guo 2024 eqs. 19–26) from the pose set `start` (within the limits) whose candidate
/// indices are `start_indices`, maximising `objective`. `opts` must pass
/// [`IdeOptions::check`].
pub fn ide(
    model: &dyn PoseModel,
    start: &[Vec<Real>],
    start_indices: &[Option<usize>],
    objective: Objective,
    opts: &IdeOptions,
    rng: &mut Rng,
) -> IdeResult {
    let dof = model.dof();
    let limits = model.limits().to_vec();
    let m = start.len();
    let len = m * dof;
    let np = opts.population.max(6);
    let g_total = opts.generations;
    let mut best: Vec<Real> = start.iter().flatten().copied().collect();
    let mut best_idx: Vec<Option<usize>> = start_indices.to_vec();
    let mut ev = Evaluator::new(model);
    let mut best_val = ev.value(model, &best, objective);
    // The best set's Jacobian blocks: the crossover copies most of its poses into each trial.
    let mut known = KnownBlocks::new(model, &best);
    let start_value = best_val;

    // Eq. 19: the Gaussian population around the start set.
    let mut library = vec![0.0; np * len];
    for x in library.chunks_exact_mut(len) {
        for (i, v) in x.iter_mut().enumerate() {
            let (lo, hi) = limits[i % dof];
            let z: Real = rng.sample(StandardNormal);
            *v = best[i] + opts.sigma * (hi - lo) * z;
        }
        handle_limits(x, &best, &limits);
    }
    let mut tracks = library.clone();
    // Trial sets: h_t then v_t for each trial, evaluated together.
    let mut trials = vec![0.0; 2 * np * len];
    let mut from_e = vec![false; np * m];
    let mut values = vec![0.0; 2 * np];
    let mut trace = Vec::with_capacity(g_total);

    for g in 1..=g_total {
        let f = mutation_factor(opts.f0, g, g_total);
        for t in 0..np {
            let [r1, r2, r3, r4] = distinct::<4>(rng, np);
            let [r5, r6] = distinct::<2>(rng, np);
            let x = |r: usize, i: usize| library[r * len + i];
            // Eq. 20 into the h slot, then eq. 25 crossover against ε_opt.
            let (h_slot, v_slot) = trials[2 * t * len..2 * (t + 1) * len].split_at_mut(len);
            for i in 0..len {
                h_slot[i] = best[i] + f * (x(r1, i) - x(r2, i)) + f * (x(r3, i) - x(r4, i));
            }
            handle_limits(h_slot, &best, &limits);
            let forced = rng.random_range(0..m);
            for p in 0..m {
                let take = p == forced || rng.random::<Real>() <= opts.cr;
                from_e[t * m + p] = take;
                if !take {
                    h_slot[p * dof..(p + 1) * dof].copy_from_slice(&best[p * dof..(p + 1) * dof]);
                }
            }
            // Eq. 22: the second mutation of this trial's track toward the best.
            let track = &mut tracks[t * len..(t + 1) * len];
            for i in 0..len {
                track[i] += f * (best[i] - track[i]) + f * (x(r5, i) - x(r6, i));
            }
            handle_limits(track, &best, &limits);
            v_slot.copy_from_slice(track);
        }
        // The trials' eigenvalue problems are solved several at once ([`Evaluator::values`]).
        let lanes = Spectra::LANES;
        trials
            .par_chunks(lanes * len)
            .zip(values.par_chunks_mut(lanes))
            .for_each_init(
                || Evaluator::new(model),
                |e, (sets, vals)| {
                    let v = e.values(model, sets, len, objective, &known);
                    vals.copy_from_slice(&v[..vals.len()]);
                },
            );
        // Eq. 26: greedy selection, strict improvement, earliest wins ties.
        let mut winner = None;
        for (s, &v) in values.iter().enumerate() {
            if v > best_val {
                best_val = v;
                winner = Some(s);
            }
        }
        if let Some(s) = winner {
            best.copy_from_slice(&trials[s * len..(s + 1) * len]);
            known = KnownBlocks::new(model, &best);
            let t = s / 2;
            for p in 0..m {
                if s % 2 == 1 || from_e[t * m + p] {
                    best_idx[p] = None;
                }
            }
        }
        trace.push(best_val);
    }
    IdeResult {
        poses: best.chunks_exact(dof).map(|c| c.to_vec()).collect(),
        indices: best_idx,
        start_value,
        trace,
        termination: format!("ide: {g_total} generations"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn mutation_factor_follows_eq_21() {
        assert_relative_eq!(mutation_factor(1.0, 1, 50), 1.0, epsilon = 1e-15);
        // g − 1 = G/2 → log2(1.5).
        assert_relative_eq!(
            mutation_factor(0.8, 26, 50),
            0.8 - 1.5f64.log2(),
            epsilon = 1e-15
        );
    }

    #[test]
    fn reverse_search_lands_between_best_and_the_crossed_limit() {
        // best 2, limit 10, x = 14: overshoot 4 of a step 12 → 2 + 8·4/12.
        assert_relative_eq!(
            reverse_search(14.0, 2.0, -10.0, 10.0),
            2.0 + 8.0 * 4.0 / 12.0,
            epsilon = 1e-12
        );
        // best 2, limit −10, x = −16: overshoot 6 of a step 18 → 2 − 12·6/18.
        assert_relative_eq!(
            reverse_search(-16.0, 2.0, -10.0, 10.0),
            2.0 - 12.0 * 6.0 / 18.0,
            epsilon = 1e-12
        );
        assert_eq!(reverse_search(3.0, 2.0, -10.0, 10.0), 3.0);
        assert_eq!(reverse_search(1e300, 10.0, -10.0, 10.0), 10.0);
    }
}
