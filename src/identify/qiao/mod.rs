//! Derivative-free identification: BAS, PSO and BAS-PSO (Qiao 2021, §3,
//! eqs. 12–14).
//!
//! The three searches minimise a fitness `f(x)` over a box ([`Bounds`]); for kinematic
//! calibration `x` holds the errors of a list of parameters and `f` is Qiao's eq. 14
//! ([`MetaProblem::fitness`], [`qiao_fitness`]).
//!
//! - [`bas`]: beetle antennae search (Jiang & Li 2017, Qiao ref. 19): one beetle smells the
//!   fitness at two antennae `x ± d·b` along a random unit direction `b` and steps by `δ`
//!   towards the better one; `d` and `δ` follow Qiao's eq. 13 schedules.
//! - [`pso`]: particle swarm with Clerc's constriction factor `K` (Qiao eq. 12 with `c3 = 0`),
//!   or with a linearly decreasing inertia weight.
//! - [`bas_pso`]: Qiao's hybrid (eq. 12): every particle's velocity gets, besides the
//!   cognitive and social terms, the beetle step `c3·B` of eq. 13.
//!
//! Every population starts from a Halton sequence (Qiao §3.1, after Maaranen et al., ref. 20).
//!
//! ## Conventions of this implementation
//!
//! The search runs in coordinates normalised to the box: `y = (x − lower) / (upper − lower)`
//! in `[0, 1]` per coordinate. Antenna widths, steps and velocity limits are therefore
//! fractions of each coordinate's range, so that a parameter vector mixing mm and rad is
//! searched evenly (Qiao gives no units for `d` and `δ`). Positions leaving the box are
//! clamped to it and the velocity component that pushed them out is zeroed. A fitness that
//! is NaN counts as `+∞`.
//!
//! Randomness comes only from the `&mut Rng` passed in, drawn in a fixed order; fitness
//! values of a swarm may be computed in parallel (rayon) but every update is sequential, so a
//! result depends on the seed alone, not on the number of threads.
//!
//! ## Layout
//!
//! - `search.rs`: what the searches share ([`Bounds`], [`MetaResult`], the Halton points, the
//!   beetle's direction and eq. 13's schedules);
//! - `bas.rs`: [`bas`] and [`BasOptions`]; `pso.rs`: [`pso`], [`bas_pso`] and their options;
//! - `fitness.rs`: eq. 14 ([`qiao_term`], [`qiao_fitness`]) and [`MetaProblem`];
//! - [`error_models`]: Qiao's three pose-error models (§2.2–2.3, §4.2);
//! - [`method`] and [`pose_error`]: the searches and the pose-error models as
//!   [`crate::identify::Method`]s.

mod bas;
pub mod error_models;
mod fitness;
pub mod method;
pub mod pose_error;
mod pso;
mod search;

pub use bas::{bas, BasOptions, BasStart};
pub use fitness::{check_k, qiao_fitness, qiao_term, MetaProblem, DEFAULT_K, MAX_K};
pub use pso::{bas_pso, pso, BasPsoOptions, BeetleTerm, PsoOptions, Velocity};
pub use search::{
    halton, halton_population, halton_population_at, Bounds, Fitness, MetaResult, Schedules,
};

use crate::error::{Error, Result};
use crate::numeric::rng::Rng;
use crate::numeric::Real;
use crate::robot::sampling::poses_in_box;
use crate::robot::Robot;

/// Joint configurations of `robot` whose tool point lies in the cube centred at `centre` with
/// edge `edge` (mm): Qiao 2021 §4's calibration points "in a 1000 mm cube centred at (550,
/// 0, 550)", drawn by [`crate::robot::sampling::poses_in_box`]. Fails with
/// [`Error::Compute`] if fewer than `n` are found in `max_draws` draws.
pub fn poses_in_cube(
    robot: &Robot,
    n: usize,
    centre: [Real; 3],
    edge: Real,
    max_draws: usize,
    rng: &mut Rng,
) -> Result<Vec<Vec<Real>>> {
    let out = poses_in_box(robot, n, centre, [edge; 3], (max_draws, max_draws), rng);
    if out.len() < n {
        return Err(Error::Compute(format!(
            "only {} of {n} poses found in the {edge} mm cube at {centre:?} after \
             {max_draws} draws",
            out.len()
        )));
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
