//! Derivative-free identification: BAS, PSO and BAS-PSO (Qiao 2021,
//! `papers/qiao2021-bas-pso-tx60.txt`, §3, eqs. 12–14).
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

pub mod error_models;
pub mod method;
pub mod pose_error;

use rand::Rng as _;
use rayon::prelude::*;

use crate::error::{check_count, finite_non_negative, finite_positive, Error, Result};
use crate::measurement::Measure;
use crate::numeric::rng::Rng;
use crate::numeric::{Frame, Mat3, Real, Vec3};
use crate::robot::{Chain, OpKind, Param, Robot, MAX_JOINTS};

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
    fn to_x(&self, y: &[Real], x: &mut [Real]) {
        for i in 0..y.len() {
            x[i] = self.lower[i] + y[i] * (self.upper[i] - self.lower[i]);
        }
    }
}

/// How PSO and BAS-PSO damp the velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Velocity {
    /// Clerc's constriction factor `K = 2 / |2 − C − √(C² − 4C)|`, `C = c1 + c2 > 4`, which
    /// multiplies the whole update (Qiao eq. 12).
    Constriction,
    /// Inertia weight `w` decreasing linearly from `start` to `end` over the iterations
    /// (Shi & Eberhart): `v ← w·v + c1 r1 (x_b − x) + c2 r2 (x_g − x) [+ c3 B]`.
    Inertia {
        /// Weight at the first iteration.
        start: Real,
        /// Weight at the last iteration.
        end: Real,
    },
}

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
    /// Initial antenna width `d` (eq. 13). Default 0.05.
    pub antenna: Real,
    /// Initial step `δ` (eq. 13). Default 0.05.
    pub step: Real,
    /// Decay factor of both schedules (eq. 13: 0.95). Default 0.95.
    pub decay: Real,
    /// `d0` of eq. 13: the width tends to `d0 / (1 − decay)`. Default 1e-4.
    pub antenna_floor: Real,
    /// `δ0` of eq. 13: the step tends to `δ0 / (1 − decay)`. Default 1e-4.
    pub step_floor: Real,
    /// Stop as soon as the best fitness is at or below this. Default −∞ (never).
    pub target: Real,
    /// Where the beetle starts. Default [`BasStart::Centre`].
    pub start: BasStart,
}

/// The starting point of [`bas`] (`start = "centre"` or `"halton"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BasStart {
    /// The centre of the search box: the nominal parameters for [`MetaProblem::bounds`].
    #[serde(alias = "center")]
    Centre,
    /// A Halton point with a random index (Qiao's initialisation of the swarms).
    Halton,
}

impl BasOptions {
    /// Checks the option values (keys as in the scenario).
    pub fn check(&self) -> Result<()> {
        check_count("iterations", self.iterations)?;
        check_budget(self.max_evaluations, 1, 3)?;
        check_schedules(
            self.antenna,
            self.step,
            self.decay,
            self.antenna_floor,
            self.step_floor,
        )?;
        check_target("target", self.target)
    }
}

impl Default for BasOptions {
    fn default() -> Self {
        BasOptions {
            iterations: 2000,
            max_evaluations: None,
            antenna: 0.05,
            step: 0.05,
            decay: 0.95,
            antenna_floor: 1e-4,
            step_floor: 1e-4,
            target: Real::NEG_INFINITY,
            start: BasStart::Centre,
        }
    }
}

/// Options of [`pso`]. Velocities are fractions of each coordinate's range.
#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PsoOptions {
    /// Number of particles. Default 40.
    pub population: usize,
    /// Iterations (one evaluation per particle each). Default 500.
    pub iterations: usize,
    /// Budget of fitness evaluations, the initial population's included: the search stops
    /// before an iteration that would exceed it (and after `iterations` at the latest).
    /// Default none.
    pub max_evaluations: Option<usize>,
    /// Cognitive learning factor `c1` (Qiao eq. 12). Default 2.05 (Clerc).
    pub c1: Real,
    /// Social learning factor `c2` (Qiao eq. 12). Default 2.05 (Clerc), so `K ≈ 0.7298`.
    pub c2: Real,
    /// Velocity damping. Default [`Velocity::Constriction`] (Qiao eq. 12); the key
    /// `inertia = [start, end]` selects [`Velocity::Inertia`].
    #[serde(rename = "inertia", deserialize_with = "inertia")]
    pub velocity: Velocity,
    /// Largest velocity component. Default 0.5.
    pub max_velocity: Real,
    /// Evaluate the swarm's fitness values in parallel (results do not change). Default true.
    #[serde(skip, default = "yes")]
    pub parallel: bool,
    /// Stop as soon as the best fitness is at or below this. Default −∞ (never).
    pub target: Real,
}

impl Default for PsoOptions {
    fn default() -> Self {
        PsoOptions {
            population: 40,
            iterations: 500,
            max_evaluations: None,
            c1: 2.05,
            c2: 2.05,
            velocity: Velocity::Constriction,
            max_velocity: 0.5,
            parallel: true,
            target: Real::NEG_INFINITY,
        }
    }
}

/// Options of [`bas_pso`] (Qiao eqs. 12–13): the swarm's options (the keys of `pso`) and the
/// beetle term. Widths and velocities are fractions of each coordinate's range. Qiao gives
/// the form of the update and the 0.95 decay but no values of `c1`, `c2`, `c3`, `d`, `δ`: the
/// defaults are Clerc's `c1 = c2 = 2.05` and this implementation's choice for the rest. Read
/// from one table: the keys of [`BeetleTerm`] go to `beetle`, every other key to `swarm`.
#[derive(Clone, Debug, Default)]
pub struct BasPsoOptions {
    /// The swarm (population, iterations — three evaluations per particle each —,
    /// max_evaluations, c1, c2, velocity, max_velocity, target).
    pub swarm: PsoOptions,
    /// The beetle velocity `B` of eq. 12 and its schedules (eq. 13).
    pub beetle: BeetleTerm,
}

/// The beetle term of BAS-PSO (Qiao eqs. 12–13).
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BeetleTerm {
    /// Weight `c3` of the beetle velocity `B` (eq. 12). Default 1.0.
    pub c3: Real,
    /// Initial antenna width `d` (eq. 13). Default 0.1.
    pub antenna: Real,
    /// Initial beetle step `δ` (eq. 13). Default 0.1.
    pub step: Real,
    /// Decay factor of both schedules (eq. 13: 0.95). Default 0.95.
    pub decay: Real,
    /// `d0` of eq. 13 (the width tends to `d0 / (1 − decay)`). Default 1e-6.
    pub antenna_floor: Real,
    /// `δ0` of eq. 13 (the step tends to `δ0 / (1 − decay)`). Default 1e-6.
    pub step_floor: Real,
}

impl Default for BeetleTerm {
    fn default() -> Self {
        BeetleTerm {
            c3: 1.0,
            antenna: 0.1,
            step: 0.1,
            decay: 0.95,
            antenna_floor: 1e-6,
            step_floor: 1e-6,
        }
    }
}

impl<'de> serde::Deserialize<'de> for BasPsoOptions {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let mut swarm = toml::Table::deserialize(d)?;
        let beetle = crate::robot::names::take_keys(
            &mut swarm,
            &[
                "c3",
                "antenna",
                "step",
                "decay",
                "antenna_floor",
                "step_floor",
            ],
        );
        Ok(BasPsoOptions {
            swarm: PsoOptions::deserialize(toml::Value::Table(swarm)).map_err(D::Error::custom)?,
            beetle: BeetleTerm::deserialize(toml::Value::Table(beetle))
                .map_err(D::Error::custom)?,
        })
    }
}

fn yes() -> bool {
    true
}

/// `inertia = [start, end]`: the inertia weights of [`Velocity::Inertia`].
fn inertia<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Velocity, D::Error> {
    let [start, end] = <[Real; 2] as serde::Deserialize>::deserialize(d)?;
    Ok(Velocity::Inertia { start, end })
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
    fn new(
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
struct Limit {
    iterations: usize,
    by_budget: bool,
}

impl Limit {
    /// At most `iterations` iterations of `per_iteration` evaluations each, after `initial`
    /// evaluations, within `max_evaluations` evaluations in all.
    fn of(
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
fn check_budget(
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

fn check_decay(key: &str, v: Real) -> Result<()> {
    if v.is_finite() && (0.0..1.0).contains(&v) {
        Ok(())
    } else {
        Err(Error::setting(key, format!("must be in [0, 1), got {v}")))
    }
}

fn check_target(key: &str, v: Real) -> Result<()> {
    if v.is_nan() || v == Real::INFINITY {
        Err(Error::setting(key, format!("must be below +∞, got {v}")))
    } else {
        Ok(())
    }
}

/// A fitness value with NaN mapped to `+∞`.
#[inline]
fn sane(v: Real) -> Real {
    if v.is_nan() {
        Real::INFINITY
    } else {
        v
    }
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
fn primes(n: usize) -> Vec<u32> {
    let mut out: Vec<u32> = Vec::with_capacity(n);
    let mut c = 2u32;
    while out.len() < n {
        if out.iter().take_while(|p| *p * *p <= c).all(|p| c % p != 0) {
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
const HALTON_SKIP: usize = 4096;

/// A random unit direction (components uniform in [−1, 1], normalised; Jiang & Li's BAS).
fn random_direction(rng: &mut Rng, b: &mut [Real]) {
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
fn offset(y: &[Real], b: &[Real], s: Real, out: &mut [Real]) {
    for i in 0..y.len() {
        out[i] = (y[i] + s * b[i]).clamp(0.0, 1.0);
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
    let (mut d, mut delta) = (o.antenna, o.step);
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
        (d, delta) = eq13(d, delta, o.decay, o.antenna_floor, o.step_floor);
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

/// The schedules of Qiao's eq. 13: `d ← decay·d + d0`, `δ ← decay·δ + δ0`.
#[inline]
fn eq13(d: Real, delta: Real, decay: Real, d0: Real, delta0: Real) -> (Real, Real) {
    (decay * d + d0, decay * delta + delta0)
}

/// True once the best fitness of the last iteration is at or below `target`.
#[inline]
fn reached(trace: &[Real], target: Real) -> bool {
    trace.last().is_some_and(|&f| f <= target)
}

/// `sign(fr − fl)` with infinities handled and 0 for ties.
#[inline]
fn sign(fr: Real, fl: Real) -> Real {
    if fr < fl {
        -1.0
    } else if fr > fl {
        1.0
    } else {
        0.0
    }
}

/// Common settings of the two swarms.
struct Swarm {
    population: usize,
    iterations: usize,
    max_evaluations: Option<usize>,
    c1: Real,
    c2: Real,
    velocity: Velocity,
    max_velocity: Real,
    parallel: bool,
    target: Real,
    /// The beetle term of BAS-PSO.
    beetle: Option<BeetleTerm>,
}

/// Checks the settings of eq. 13's schedules: initial width and step positive, decay in
/// [0, 1), floors at least 0.
fn check_schedules(antenna: Real, step: Real, decay: Real, d0: Real, delta0: Real) -> Result<()> {
    finite_positive("antenna", antenna)?;
    finite_positive("step", step)?;
    check_decay("decay", decay)?;
    finite_non_negative("antenna_floor", d0)?;
    finite_non_negative("step_floor", delta0)
}

fn check_swarm(s: &Swarm) -> Result<()> {
    check_count("population", s.population)?;
    check_count("iterations", s.iterations)?;
    check_budget(s.max_evaluations, s.population, s.per_iteration())?;
    finite_non_negative("c1", s.c1)?;
    finite_non_negative("c2", s.c2)?;
    finite_positive("max_velocity", s.max_velocity)?;
    check_target("target", s.target)?;
    match s.velocity {
        Velocity::Constriction => {
            if s.c1 + s.c2 <= 4.0 {
                return Err(Error::setting(
                    "c1",
                    format!(
                        "the constriction factor needs c1 + c2 > 4, got {}",
                        s.c1 + s.c2
                    ),
                ));
            }
        }
        Velocity::Inertia { start, end } => {
            finite_non_negative("inertia[0]", start)?;
            finite_non_negative("inertia[1]", end)?;
        }
    }
    if let Some(b) = s.beetle {
        finite_non_negative("c3", b.c3)?;
        check_schedules(b.antenna, b.step, b.decay, b.antenna_floor, b.step_floor)?;
    }
    Ok(())
}

/// Evaluates `f` at every point of `xs` into `out` (in parallel if asked; same values).
fn evaluate(f: &Fitness, xs: &[Vec<Real>], out: &mut [Real], parallel: bool) {
    if parallel {
        xs.par_iter()
            .zip(out.par_iter_mut())
            .for_each(|(x, o)| *o = sane(f(x)));
    } else {
        for (x, o) in xs.iter().zip(out.iter_mut()) {
            *o = sane(f(x));
        }
    }
}

/// Particle swarm optimisation (Qiao 2021 §3.1, eq. 12 without the beetle term):
/// `v ← K[v + c1 r1 (x_b − x) + c2 r2 (x_g − x)]`, `x ← x + v`, with `r1`, `r2` uniform in
/// [0, 1] per coordinate, `x_b` the particle's best and `x_g` the swarm's best; Halton
/// initial population, zero initial velocities.
pub fn pso(f: &Fitness, b: &Bounds, o: &PsoOptions, rng: &mut Rng) -> Result<MetaResult> {
    let s = Swarm::of(o, None);
    b.check()?;
    check_swarm(&s)?;
    swarm(f, b, &s, rng)
}

impl PsoOptions {
    /// Checks the option values (keys as in the scenario).
    pub fn check(&self) -> Result<()> {
        check_swarm(&Swarm::of(self, None))
    }
}

impl Swarm {
    /// Fitness evaluations per iteration: one per particle, three with the beetle term
    /// (its two antennae).
    fn per_iteration(&self) -> usize {
        if self.beetle.is_some() {
            3 * self.population
        } else {
            self.population
        }
    }

    /// The iterations the swarm runs within its budget.
    fn limit(&self) -> Limit {
        Limit::of(
            self.iterations,
            self.max_evaluations,
            self.population,
            self.per_iteration(),
        )
    }

    /// The swarm of `o`, with the beetle term of BAS-PSO if given.
    fn of(o: &PsoOptions, beetle: Option<BeetleTerm>) -> Swarm {
        Swarm {
            population: o.population,
            iterations: o.iterations,
            max_evaluations: o.max_evaluations,
            c1: o.c1,
            c2: o.c2,
            velocity: o.velocity,
            max_velocity: o.max_velocity,
            parallel: o.parallel,
            target: o.target,
            beetle,
        }
    }
}

/// Qiao 2021's BAS-PSO (§3.1, eqs. 12–13): each particle `i` updates
/// `v ← K[v + c1 r1 (x_b − x) + c2 r2 (x_g − x) + c3 B]`, `x ← x + v`, where
/// `B = −δ·b·sign(f(x + d·b) − f(x − d·b))` is the step its beetle would take along a random
/// unit direction `b` (eq. 13, with the descending sign, see [`bas`]), and
/// `d ← decay·d + d0`, `δ ← decay·δ + δ0` after every iteration. Halton initial population.
/// The antenna points count as evaluations and may become the best point.
pub fn bas_pso(f: &Fitness, b: &Bounds, o: &BasPsoOptions, rng: &mut Rng) -> Result<MetaResult> {
    b.check()?;
    o.check()?;
    swarm(f, b, &Swarm::of(&o.swarm, Some(o.beetle)), rng)
}

impl BasPsoOptions {
    /// Checks the option values (keys as in the scenario).
    pub fn check(&self) -> Result<()> {
        check_swarm(&Swarm::of(&self.swarm, Some(self.beetle)))
    }
}

fn swarm(f: &Fitness, b: &Bounds, s: &Swarm, rng: &mut Rng) -> Result<MetaResult> {
    let n = b.dim();
    let m = s.population;
    let ps = primes(n);
    let start = rng.random_range(0..HALTON_SKIP) + 1;
    let mut y: Vec<Vec<Real>> = (0..m)
        .map(|i| ps.iter().map(|&p| halton(start + i, p)).collect())
        .collect();
    let mut v = vec![vec![0.0; n]; m];
    let mut xs = vec![vec![0.0; n]; m];
    let mut fit = vec![0.0; m];
    // Antenna points (right, left) in real coordinates, their fitness and directions.
    let beetle = s.beetle.is_some();
    let (nb, mb) = if beetle { (n, m) } else { (0, 0) };
    let mut dirs = vec![vec![0.0; nb]; mb];
    let mut ya = vec![0.0; nb];
    let mut xa = vec![vec![0.0; nb]; 2 * mb];
    let mut fa = vec![0.0; 2 * mb];

    for (yi, xi) in y.iter().zip(xs.iter_mut()) {
        b.to_x(yi, xi);
    }
    evaluate(f, &xs, &mut fit, s.parallel);
    let mut evaluations = m;
    let mut pbest_y = y.clone();
    let mut pbest_f = fit.clone();
    let mut g = 0;
    for i in 1..m {
        if fit[i] < fit[g] {
            g = i;
        }
    }
    let mut gbest_y = y[g].clone();
    let mut gbest_f = fit[g];
    let mut gbest_x = xs[g].clone();

    let k = match s.velocity {
        Velocity::Constriction => {
            let c = s.c1 + s.c2;
            2.0 / (2.0 - c - (c * c - 4.0 * c).sqrt()).abs()
        }
        Velocity::Inertia { .. } => 1.0,
    };
    let (mut d, mut delta) = s.beetle.map_or((0.0, 0.0), |bt| (bt.antenna, bt.step));
    let limit = s.limit();
    let mut trace = Vec::with_capacity(limit.iterations);
    while trace.len() < limit.iterations && !reached(&trace, s.target) {
        let it = trace.len();
        let w = match s.velocity {
            Velocity::Constriction => 1.0,
            Velocity::Inertia { start, end } => {
                let t = if limit.iterations > 1 {
                    it as Real / (limit.iterations - 1) as Real
                } else {
                    0.0
                };
                start + (end - start) * t
            }
        };
        if let Some(BeetleTerm { c3, .. }) = s.beetle {
            // Directions drawn in particle order, then the antennae evaluated.
            for i in 0..m {
                random_direction(rng, &mut dirs[i]);
                offset(&y[i], &dirs[i], d, &mut ya);
                b.to_x(&ya, &mut xa[2 * i]);
                offset(&y[i], &dirs[i], -d, &mut ya);
                b.to_x(&ya, &mut xa[2 * i + 1]);
            }
            evaluate(f, &xa, &mut fa, s.parallel);
            evaluations += 2 * m;
            for i in 0..m {
                let sg = sign(fa[2 * i], fa[2 * i + 1]);
                // Store c3·B in the direction buffer.
                for dv in dirs[i].iter_mut() {
                    *dv *= -c3 * delta * sg;
                }
                for (j, fv) in [(2 * i, fa[2 * i]), (2 * i + 1, fa[2 * i + 1])] {
                    if fv < gbest_f {
                        gbest_f = fv;
                        gbest_x.copy_from_slice(&xa[j]);
                        for c in 0..n {
                            gbest_y[c] = if (b.upper[c] - b.lower[c]) > 0.0 {
                                (xa[j][c] - b.lower[c]) / (b.upper[c] - b.lower[c])
                            } else {
                                0.0
                            };
                        }
                    }
                }
            }
        }
        for i in 0..m {
            for c in 0..n {
                let r1: Real = rng.random();
                let r2: Real = rng.random();
                let mut vc = w * v[i][c]
                    + s.c1 * r1 * (pbest_y[i][c] - y[i][c])
                    + s.c2 * r2 * (gbest_y[c] - y[i][c]);
                if beetle {
                    vc += dirs[i][c];
                }
                vc = (k * vc).clamp(-s.max_velocity, s.max_velocity);
                let mut yc = y[i][c] + vc;
                if !(0.0..=1.0).contains(&yc) {
                    yc = yc.clamp(0.0, 1.0);
                    vc = 0.0;
                }
                v[i][c] = vc;
                y[i][c] = yc;
            }
            b.to_x(&y[i], &mut xs[i]);
        }
        evaluate(f, &xs, &mut fit, s.parallel);
        evaluations += m;
        for i in 0..m {
            if fit[i] < pbest_f[i] {
                pbest_f[i] = fit[i];
                pbest_y[i].copy_from_slice(&y[i]);
            }
            if fit[i] < gbest_f {
                gbest_f = fit[i];
                gbest_y.copy_from_slice(&y[i]);
                gbest_x.copy_from_slice(&xs[i]);
            }
        }
        if let Some(bt) = s.beetle {
            (d, delta) = eq13(d, delta, bt.decay, bt.antenna_floor, bt.step_floor);
        }
        trace.push(gbest_f);
    }
    Ok(MetaResult::new(
        gbest_x,
        gbest_f,
        trace,
        evaluations,
        s.target,
        limit,
    ))
}

/// One pose's term of Qiao's fitness (eq. 14): `k(|Δn| + |Δo| + |Δa|) + |Δp|`, where n, o, a
/// are the columns of the rotation and p the position of the measured and the model frame.
#[inline]
pub fn qiao_term(measured: &Frame, model: &Frame, k: Real) -> Real {
    let dr = measured.rot - model.rot;
    k * (dr.column(0).norm() + dr.column(1).norm() + dr.column(2).norm())
        + (measured.pos - model.pos).norm()
}

/// Qiao 2021's fitness (eq. 14): `Σ_j [k(|Δn_j| + |Δo_j| + |Δa_j|) + |Δp_j|]` over the poses,
/// between measured frames and model frames (in pairs; extra frames of the longer list are
/// ignored). `k` (mm) weighs the dimensionless orientation terms against the position in mm;
/// Qiao gives no value.
pub fn qiao_fitness(measured: &[Frame], model: &[Frame], k: Real) -> Real {
    measured
        .iter()
        .zip(model)
        .map(|(m, t)| qiao_term(m, t, k))
        .sum()
}

/// Default `k` of eq. 14 (mm per unit of `|Δn| + |Δo| + |Δa|`). Qiao gives no value; with
/// 100 mm, an orientation error of 0.001 rad (whose three column differences sum to about
/// 0.002–0.003) weighs like 0.2–0.3 mm, the order of the position errors of Qiao's TX60.
pub const DEFAULT_K: Real = 100.0;

/// Largest flat parameter vector handled by [`MetaProblem`] ([`MAX_JOINTS`] joints).
const MAX_VALUES: usize = 6 * MAX_JOINTS + 12;

/// Joint-variable values of one pose and their (sin, cos).
#[derive(Clone, Debug)]
struct PoseVars {
    c: [Real; MAX_JOINTS],
    sc: [(Real, Real); MAX_JOINTS],
}

/// Direct identification on the forward kinematics with Qiao's fitness (eq. 14, §4.2 "error
/// model 3"): the unknowns are errors `x` of `params` added to the nominal robot, and
/// `fitness(x) = Σ_j [k(|Δn| + |Δo| + |Δa|) + |Δp|]` between the measured frames and the
/// forward kinematics of the corrected robot (position-only data: `Σ_j |Δp|`).
///
/// The measured frames are in the robot's world (base-frame) coordinates. The fitness is
/// allocation-free: it walks the nominal chain's operations with the errors added, using
/// per-pose precomputed sines and cosines of the joint variables (angle-addition formulas), so
/// no robot or chain is built per call.
#[derive(Clone, Debug)]
pub struct MetaProblem<'a> {
    nominal: &'a Robot,
    /// The nominal robot's compiled chain, whose operations the fitness walks.
    chain: Chain,
    params: Vec<Param>,
    qs: Vec<Vec<Real>>,
    points: Vec<Vec3>,
    rotations: Option<Vec<Mat3>>,
    /// The weight of eq. 14 (mm per unit of orientation error).
    k: Real,
    flat: Vec<usize>,
    vars: Vec<PoseVars>,
    /// `√w_j` of each pose's prior weight, if any.
    point_scale: Option<Vec<Real>>,
    /// Whether the model has joint compliances (searched, or in the nominal robot): the
    /// fitness then uses the elasto-geometric forward kinematics.
    compliant: bool,
    /// The payload of each pose (kg), for the elasto-geometric model.
    loads: Option<Vec<Real>>,
}

impl<'a> MetaProblem<'a> {
    /// A problem over the errors of `params` of `nominal`, with joint values `qs` (internal
    /// units), measured tool points (mm, world) and optionally measured tool rotations, and
    /// the weight `k` of eq. 14.
    pub fn new(
        nominal: &'a Robot,
        params: Vec<Param>,
        qs: Vec<Vec<Real>>,
        points: Vec<Vec3>,
        rotations: Option<Vec<Mat3>>,
        k: Real,
    ) -> Result<MetaProblem<'a>> {
        let dof = nominal.dof();
        if dof > MAX_JOINTS {
            return Err(Error::setting(
                "robot",
                format!("at most {MAX_JOINTS} joints are supported"),
            ));
        }
        if params.is_empty() {
            return Err(Error::setting("params", "no parameters to identify"));
        }
        let all = nominal.params();
        let mut flat = Vec::with_capacity(params.len());
        for p in &params {
            let compliance_ok = matches!(*p, Param::Compliance(j)
                if j < dof && nominal.joints[j].kind == crate::robot::JointType::Revolute);
            if !(all.contains(p) || compliance_ok) {
                return Err(Error::setting(
                    "params",
                    format!("{p} is not a parameter of robot {}", nominal.name),
                ));
            }
            let i = p.index(dof);
            if flat.contains(&i) {
                return Err(Error::setting("params", format!("{p} is listed twice")));
            }
            flat.push(i);
        }
        if qs.is_empty() {
            return Err(Error::setting("poses", "no poses"));
        }
        if points.len() != qs.len() {
            return Err(Error::setting(
                "measurements",
                format!("{} poses but {} measured points", qs.len(), points.len()),
            ));
        }
        if let Some(r) = &rotations {
            if r.len() != qs.len() {
                return Err(Error::setting(
                    "measurements",
                    format!("{} poses but {} measured rotations", qs.len(), r.len()),
                ));
            }
        }
        if !(k.is_finite() && k >= 0.0) {
            return Err(Error::setting(
                "k",
                format!("must be finite and non-negative, got {k}"),
            ));
        }
        let mut vars = Vec::with_capacity(qs.len());
        for (i, q) in qs.iter().enumerate() {
            if q.len() != dof || q.iter().any(|v| !v.is_finite()) {
                return Err(Error::setting(
                    "poses",
                    format!("pose {i}: expected {dof} finite joint values"),
                ));
            }
            if !points[i].iter().all(|v| v.is_finite()) {
                return Err(Error::setting(
                    "measurements",
                    format!("pose {i}: non-finite point"),
                ));
            }
            let mut c = [0.0; MAX_JOINTS];
            nominal.chain_values(q, &mut c[..dof]);
            let mut sc = [(0.0, 1.0); MAX_JOINTS];
            for j in 0..dof {
                sc[j] = c[j].sin_cos();
            }
            vars.push(PoseVars { c, sc });
        }
        let compliant = params.iter().any(|p| p.is_compliance())
            || crate::robot::compliance::is_compliant(nominal);
        Ok(MetaProblem {
            nominal,
            params,
            qs,
            points,
            rotations,
            k,
            chain: nominal.chain(),
            flat,
            vars,
            point_scale: None,
            compliant,
            loads: None,
        })
    }

    /// Sets the payload of each pose (kg; `None`: no payload), under which an
    /// elasto-geometric model deflects the arm. Fails unless there is one finite payload ≥ 0
    /// per pose.
    pub fn with_payloads(mut self, loads: Option<&[Real]>) -> Result<Self> {
        if let Some(w) = loads {
            crate::robot::compliance::check_payloads(w, self.qs.len())?;
        }
        self.loads = loads.map(<[Real]>::to_vec);
        Ok(self)
    }

    /// Weighs pose `j`'s term of the fitness by `√w_j` (the weights `w_j ∝ 1/σ_j²` of
    /// [`crate::measurement::Measurements::weights`]: a sum of norms divided by each point's
    /// σ). `None` leaves every term at 1. Fails unless there is one finite, positive weight
    /// per pose.
    pub fn with_weights(mut self, w: Option<&[Real]>) -> Result<Self> {
        if let Some(w) = w {
            if w.len() != self.qs.len() || w.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(Error::setting(
                    "weights",
                    format!(
                        "need {} finite positive weights, got {}",
                        self.qs.len(),
                        w.len()
                    ),
                ));
            }
        }
        self.point_scale = w.map(|w| w.iter().map(|v| v.sqrt()).collect());
        Ok(self)
    }

    /// A problem from measured frames (full pose: position and rotation).
    pub fn from_frames(
        nominal: &'a Robot,
        params: Vec<Param>,
        qs: Vec<Vec<Real>>,
        measured: &[Frame],
        k: Real,
    ) -> Result<MetaProblem<'a>> {
        let points = measured.iter().map(|f| f.pos).collect();
        let rots = measured.iter().map(|f| f.rot).collect();
        MetaProblem::new(nominal, params, qs, points, Some(rots), k)
    }

    /// The parameters whose errors are searched, in the order of `x`.
    pub fn params(&self) -> &[Param] {
        &self.params
    }

    /// The nominal robot.
    pub fn nominal(&self) -> &Robot {
        self.nominal
    }

    /// The joint values of the poses.
    pub fn poses(&self) -> &[Vec<Real>] {
        &self.qs
    }

    /// What the data measure: position, or full pose.
    pub fn measure(&self) -> Measure {
        if self.rotations.is_some() {
            Measure::Pose
        } else {
            Measure::Position
        }
    }

    /// The nominal robot with the errors `x` added (the identified robot).
    pub fn robot(&self, x: &[Real]) -> Result<Robot> {
        if x.len() != self.params.len() {
            return Err(Error::setting(
                "x",
                format!("expected {} values, got {}", self.params.len(), x.len()),
            ));
        }
        let errs: Vec<(Param, Real)> = self.params.iter().copied().zip(x.iter().copied()).collect();
        Ok(self.nominal.with_errors(&errs))
    }

    /// Bounds of half width `length_mm` on length parameters, `angle_rad` on angles and
    /// `compliance` (rad/(N·m)) on joint compliances.
    pub fn bounds(&self, length_mm: Real, angle_rad: Real, compliance: Real) -> Bounds {
        let w: Vec<Real> = self
            .params
            .iter()
            .map(|p| {
                if p.is_compliance() {
                    compliance
                } else if p.is_length() {
                    length_mm
                } else {
                    angle_rad
                }
            })
            .collect();
        Bounds::symmetric(&w)
    }

    /// Pose `j`'s term of the fitness for the model frame `(r, p)`.
    #[inline(always)]
    fn term(&self, j: usize, r: &Mat3, p: &Vec3) -> Real {
        let position = (self.points[j] - p).norm();
        let orientation = self.rotations.as_ref().map_or(0.0, |rots| {
            let dr = rots[j] - r;
            self.k * (dr.column(0).norm() + dr.column(1).norm() + dr.column(2).norm())
        });
        match &self.point_scale {
            None => position + orientation,
            Some(s) => s[j] * (position + orientation),
        }
    }

    /// The fitness of an elasto-geometric model: the corrected robot's forward kinematics
    /// under each pose's payload ([`crate::robot::compliance::loaded_fk`]). Builds the robot (this
    /// path allocates); `+∞` when a pose cannot be evaluated.
    fn fitness_loaded(&self, x: &[Real]) -> Real {
        let Ok(robot) = self.robot(x) else {
            return Real::INFINITY;
        };
        let chain = robot.chain();
        let mut total = 0.0;
        for (j, q) in self.qs.iter().enumerate() {
            let load = self.loads.as_ref().map_or(0.0, |l| l[j]);
            match crate::robot::compliance::loaded_fk(&robot, &chain, q, load) {
                Ok(f) => total += self.term(j, &f.rot, &f.pos),
                Err(_) => return Real::INFINITY,
            }
        }
        total
    }

    /// Qiao's fitness (eq. 14) of the errors `x`; `+∞` if `x` has the wrong length.
    /// Allocation-free.
    pub fn fitness(&self, x: &[Real]) -> Real {
        if x.len() != self.flat.len() {
            return Real::INFINITY;
        }
        if self.compliant {
            return self.fitness_loaded(x);
        }
        let ops = self.chain.ops();
        if ops.len() > MAX_VALUES {
            return Real::INFINITY;
        }
        let mut delta = [0.0; MAX_VALUES];
        for (&i, &v) in self.flat.iter().zip(x) {
            delta[i] = v;
        }
        // Per operation: total constant value and, for rotations, its (sin, cos).
        let mut val = [0.0; MAX_VALUES];
        let mut sc = [(0.0, 1.0); MAX_VALUES];
        for (o, op) in ops.iter().enumerate() {
            let v = op.value + delta[op.param];
            val[o] = v;
            if op.kind.is_rotation() {
                sc[o] = v.sin_cos();
            }
        }
        let mut total = 0.0;
        for (j, pv) in self.vars.iter().enumerate() {
            let mut r = Mat3::identity();
            let mut p = Vec3::zeros();
            for (o, op) in ops.iter().enumerate() {
                match op.kind {
                    OpKind::Tx | OpKind::Ty | OpKind::Tz => {
                        let t = match op.var {
                            Some(vi) => val[o] + pv.c[vi],
                            None => val[o],
                        };
                        p += r.column(op.kind.axis()) * t;
                    }
                    _ => {
                        let (s, c) = match op.var {
                            Some(vi) => {
                                let (s1, c1) = sc[o];
                                let (s2, c2) = pv.sc[vi];
                                (s1 * c2 + c1 * s2, c1 * c2 - s1 * s2)
                            }
                            None => sc[o],
                        };
                        let (a, b) = match op.kind {
                            OpKind::Rx => (1, 2),
                            OpKind::Ry => (2, 0),
                            _ => (0, 1),
                        };
                        for row in 0..3 {
                            let u = r[(row, a)];
                            let w = r[(row, b)];
                            r[(row, a)] = c * u + s * w;
                            r[(row, b)] = -s * u + c * w;
                        }
                    }
                }
            }
            total += self.term(j, &r, &p);
        }
        total
    }

    /// The model frames of the corrected robot at every pose (for reports; allocates).
    pub fn frames(&self, x: &[Real]) -> Result<Vec<Frame>> {
        let r = self.robot(x)?;
        let chain = r.chain();
        Ok(self.qs.iter().map(|q| chain.fk(q)).collect())
    }
}

/// Joint configurations of `robot` whose tool point lies in the axis-aligned box centred at
/// `centre` with edge `edge` (mm), by rejection sampling of uniform joint values — Qiao
/// 2021 §4's calibration points "in a 1000 mm cube centred at (550, 0, 550)". Fails with
/// [`Error::Compute`] if fewer than `n` are found in `max_draws` draws.
pub fn poses_in_cube(
    robot: &Robot,
    n: usize,
    centre: [Real; 3],
    edge: Real,
    max_draws: usize,
    rng: &mut Rng,
) -> Result<Vec<Vec<Real>>> {
    let chain = robot.chain();
    let h = 0.5 * edge;
    let mut out = Vec::with_capacity(n);
    let mut q = vec![0.0; robot.dof()];
    for _ in 0..max_draws {
        if out.len() == n {
            break;
        }
        for (v, j) in q.iter_mut().zip(&robot.joints) {
            *v = j.limits.0 + (j.limits.1 - j.limits.0) * rng.random::<Real>();
        }
        let p = chain.fk(&q).pos;
        if (0..3).all(|i| (p[i] - centre[i]).abs() <= h) {
            out.push(q.clone());
        }
    }
    if out.len() < n {
        return Err(Error::Compute(format!(
            "only {} of {n} poses found in the {edge} mm cube at {centre:?} after {max_draws} draws",
            out.len()
        )));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::stream;
    use approx::assert_relative_eq;

    fn sphere(x: &[Real]) -> Real {
        let c = [1.0, -2.0, 0.5, 3.0, -1.0];
        x.iter().zip(c).map(|(a, b)| (a - b) * (a - b)).sum()
    }

    fn rosenbrock(x: &[Real]) -> Real {
        (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2)
    }

    fn dist(x: &[Real], c: &[Real]) -> Real {
        x.iter()
            .zip(c)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<Real>()
            .sqrt()
    }

    #[test]
    fn halton_matches_radical_inverse_by_hand() {
        assert_relative_eq!(halton(0, 2), 0.0);
        assert_relative_eq!(halton(1, 2), 0.5);
        assert_relative_eq!(halton(2, 2), 0.25);
        assert_relative_eq!(halton(3, 2), 0.75);
        assert_relative_eq!(halton(6, 2), 0.375, epsilon = 1e-15); // 110b → .011b
        assert_relative_eq!(halton(1, 3), 1.0 / 3.0, epsilon = 1e-15);
        assert_relative_eq!(halton(5, 3), 7.0 / 9.0, epsilon = 1e-15); // 12₃ → .21₃
        assert_eq!(primes(6), vec![2, 3, 5, 7, 11, 13]);
        let b = Bounds {
            lower: vec![-1.0, 10.0, 0.0],
            upper: vec![1.0, 20.0, 5.0],
        };
        let pop = halton_population(4, &b);
        assert_eq!(pop.len(), 4);
        // Point 0 is (h(1,2), h(1,3), h(1,5)) = (1/2, 1/3, 1/5) scaled.
        assert_relative_eq!(pop[0][0], 0.0, epsilon = 1e-15);
        assert_relative_eq!(pop[0][1], 10.0 + 10.0 / 3.0, epsilon = 1e-12);
        assert_relative_eq!(pop[0][2], 1.0, epsilon = 1e-12);
        assert_relative_eq!(pop[1][0], -0.5, epsilon = 1e-15);
        for p in &pop {
            for (i, v) in p.iter().enumerate() {
                assert!(*v >= b.lower[i] && *v <= b.upper[i]);
            }
        }
    }

    #[test]
    fn swarms_find_the_sphere_minimum() {
        let b = Bounds::symmetric(&[5.0; 5]);
        let c = [1.0, -2.0, 0.5, 3.0, -1.0];
        let o = PsoOptions {
            iterations: 300,
            ..Default::default()
        };
        let r = pso(&sphere, &b, &o, &mut stream(3, "pso")).unwrap();
        assert!(dist(&r.x, &c) < 1e-4, "pso {:?}", r.x);
        let o = hybrid(300);
        let r = bas_pso(&sphere, &b, &o, &mut stream(3, "bas_pso")).unwrap();
        assert!(dist(&r.x, &c) < 1e-4, "bas_pso {:?}", r.x);
        assert_eq!(r.evaluations, 40 + 300 * 3 * 40);
        assert_eq!(r.trace.len(), 300);
        assert!(r.trace.windows(2).all(|w| w[1] <= w[0]));
        let o = BasOptions {
            iterations: 3000,
            ..Default::default()
        };
        let r = bas(&sphere, &b, &o, &mut stream(3, "bas")).unwrap();
        assert!(dist(&r.x, &c) < 1e-2, "bas {:?}", r.x);
        assert_relative_eq!(r.fitness, sphere(&r.x));
    }

    /// BAS-PSO with `iterations` and the other options at their defaults.
    fn hybrid(iterations: usize) -> BasPsoOptions {
        BasPsoOptions {
            swarm: PsoOptions {
                iterations,
                ..Default::default()
            },
            ..Default::default()
        }
    }

    #[test]
    fn swarms_find_the_rosenbrock_minimum() {
        let b = Bounds::symmetric(&[2.0, 2.0]);
        let o = PsoOptions {
            iterations: 400,
            ..Default::default()
        };
        let r = pso(&rosenbrock, &b, &o, &mut stream(4, "pso")).unwrap();
        assert!(dist(&r.x, &[1.0, 1.0]) < 1e-3, "pso {:?}", r.x);
        let o = hybrid(400);
        let r = bas_pso(&rosenbrock, &b, &o, &mut stream(4, "bas_pso")).unwrap();
        assert!(dist(&r.x, &[1.0, 1.0]) < 1e-3, "bas_pso {:?}", r.x);
        let o = BasOptions {
            iterations: 5000,
            ..Default::default()
        };
        let r = bas(&rosenbrock, &b, &o, &mut stream(4, "bas")).unwrap();
        assert!(dist(&r.x, &[1.0, 1.0]) < 0.1, "bas {:?} {}", r.x, r.fitness);
    }

    #[test]
    fn results_depend_on_the_seed_only() {
        let b = Bounds::symmetric(&[5.0; 5]);
        let o = BasPsoOptions {
            swarm: PsoOptions {
                iterations: 50,
                ..Default::default()
            },
            ..Default::default()
        };
        let a = bas_pso(&sphere, &b, &o, &mut stream(9, "x")).unwrap();
        let seq = BasPsoOptions {
            swarm: PsoOptions {
                parallel: false,
                ..o.swarm.clone()
            },
            ..o.clone()
        };
        let s = bas_pso(&sphere, &b, &seq, &mut stream(9, "x")).unwrap();
        assert_eq!(a, s);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let t = pool.install(|| bas_pso(&sphere, &b, &o, &mut stream(9, "x")).unwrap());
        assert_eq!(a, t);
        let other = bas_pso(&sphere, &b, &o, &mut stream(10, "x")).unwrap();
        assert_ne!(a.x, other.x);
        // Same seed, same result: PSO and BAS too.
        let same = |run: &dyn Fn() -> MetaResult| assert_eq!(run(), run());
        let (po, bo) = (hybrid(50).swarm, BasOptions::default());
        same(&|| pso(&sphere, &b, &po, &mut stream(9, "x")).unwrap());
        same(&|| bas(&sphere, &b, &bo, &mut stream(9, "x")).unwrap());
    }

    fn key(e: Error) -> String {
        e.key()
            .unwrap_or_else(|| panic!("not a setting error: {e}"))
            .into()
    }

    /// The key named when the default options, edited by `edit`, are run by `run`.
    fn refused<O: Default>(
        edit: impl FnOnce(&mut O),
        run: impl FnOnce(&O) -> Result<MetaResult>,
    ) -> String {
        let mut o = O::default();
        edit(&mut o);
        key(run(&o).unwrap_err())
    }

    #[test]
    fn bad_options_are_refused_by_name() {
        let b = Bounds::symmetric(&[1.0; 3]);
        let mut rng = stream(1, "x");
        let mut r = stream(1, "y");
        assert_eq!(
            refused(
                |o: &mut PsoOptions| o.population = 0,
                |o| pso(&sphere, &b, o, &mut r)
            ),
            "population"
        );
        assert_eq!(
            refused(
                |o: &mut PsoOptions| o.c1 = Real::NAN,
                |o| pso(&sphere, &b, o, &mut r)
            ),
            "c1"
        );
        // The constriction factor needs c1 + c2 > 4.
        let weak = |o: &mut PsoOptions| (o.c1, o.c2) = (1.0, 1.0);
        assert_eq!(refused(weak, |o| pso(&sphere, &b, o, &mut r)), "c1");
        let hybrid = |o: &BasPsoOptions| bas_pso(&sphere, &b, o, &mut stream(2, "y"));
        assert_eq!(
            refused(|o: &mut BasPsoOptions| o.swarm.population = 0, hybrid),
            "population"
        );
        assert_eq!(
            refused(
                |o: &mut BasPsoOptions| o.beetle.antenna = Real::INFINITY,
                hybrid
            ),
            "antenna"
        );
        let beetle = |o: &BasOptions| bas(&sphere, &b, o, &mut stream(3, "y"));
        assert_eq!(refused(|o: &mut BasOptions| o.decay = 1.0, beetle), "decay");
        assert_eq!(
            refused(|o: &mut BasOptions| o.iterations = 0, beetle),
            "iterations"
        );
        let inverted = Bounds {
            lower: vec![0.0, 1.0],
            upper: vec![1.0, 0.0],
        };
        let r = pso(&sphere, &inverted, &PsoOptions::default(), &mut rng);
        assert_eq!(key(r.unwrap_err()), "bounds");
        let nan = Bounds {
            lower: vec![Real::NAN],
            upper: vec![1.0],
        };
        let r = bas(&sphere, &nan, &BasOptions::default(), &mut rng);
        assert_eq!(key(r.unwrap_err()), "bounds");
        let ragged = Bounds {
            lower: vec![0.0],
            upper: vec![1.0, 2.0],
        };
        let r = bas_pso(&sphere, &ragged, &BasPsoOptions::default(), &mut rng);
        assert_eq!(key(r.unwrap_err()), "bounds");
    }

    #[test]
    fn nan_fitness_counts_as_worst() {
        let b = Bounds::symmetric(&[2.0; 2]);
        let f = |x: &[Real]| if x[0] < 0.0 { Real::NAN } else { sphere(x) };
        let o = PsoOptions {
            iterations: 100,
            ..Default::default()
        };
        let r = pso(&f, &b, &o, &mut stream(2, "x")).unwrap();
        assert!(r.fitness.is_finite() && r.x[0] >= 0.0);
    }

    #[test]
    fn qiao_term_by_hand() {
        let m = Frame::from_xyz_rpy([1.0, 2.0, 3.0], [0.0, 0.0, 0.0]);
        let t = Frame {
            rot: crate::numeric::rot_z(0.1),
            pos: Vec3::new(4.0, 6.0, 3.0),
        };
        // |Δp| = 5; Rz(0.1) moves n and o each by 2 sin(0.05), a not at all.
        let expect = 5.0 + 10.0 * 2.0 * (2.0 * (0.05 as Real).sin());
        assert_relative_eq!(qiao_term(&m, &t, 10.0), expect, epsilon = 1e-12);
        assert_relative_eq!(qiao_fitness(&[m, m], &[t, t], 10.0), 2.0 * expect);
    }

    fn random_x(n: usize, rng: &mut Rng, scale: Real) -> Vec<Real> {
        (0..n)
            .map(|_| scale * rng.random_range(-1.0..1.0))
            .collect()
    }

    #[test]
    fn problem_fitness_matches_forward_kinematics() {
        // Independent truth: the robot with the errors applied, through Chain::fk.
        let mut rng = stream(5, "t");
        for name in ["tx60", "irb2600-mdh", "guo-3t2r"] {
            let nominal = crate::robot::builtin::load(name).unwrap();
            let params = nominal.params();
            let qs = crate::robot::sampling::uniform_joint_poses(&nominal, 7, &mut rng);
            let x_true = random_x(params.len(), &mut rng, 0.05);
            let p0 = MetaProblem::new(
                &nominal,
                params.clone(),
                qs.clone(),
                vec![Vec3::zeros(); qs.len()],
                None,
                1.0,
            )
            .unwrap();
            let truth = p0.frames(&x_true).unwrap();
            let full = MetaProblem::from_frames(&nominal, params.clone(), qs.clone(), &truth, 37.0)
                .unwrap();
            let points = truth.iter().map(|f| f.pos).collect();
            let pos =
                MetaProblem::new(&nominal, params.clone(), qs.clone(), points, None, 37.0).unwrap();
            assert!(full.fitness(&x_true) < 1e-9, "{name}");
            for _ in 0..3 {
                let x = random_x(params.len(), &mut rng, 0.05);
                let model = full.frames(&x).unwrap();
                assert_relative_eq!(
                    full.fitness(&x),
                    qiao_fitness(&truth, &model, 37.0),
                    max_relative = 1e-10
                );
                let by_points: Real = truth
                    .iter()
                    .zip(&model)
                    .map(|(t, m)| (t.pos - m.pos).norm())
                    .sum();
                assert_relative_eq!(pos.fitness(&x), by_points, max_relative = 1e-10);
            }
            assert_eq!(full.fitness(&[0.0]), Real::INFINITY);
        }
    }

    #[test]
    fn problem_refuses_bad_inputs() {
        let nominal = crate::robot::builtin::load("tx60").unwrap();
        let q = vec![vec![0.0; 6]];
        let pts = vec![Vec3::zeros()];
        let mk = |params: Vec<Param>, qs: Vec<Vec<Real>>, pts: Vec<Vec3>, k: Real| {
            key(MetaProblem::new(&nominal, params, qs, pts, None, k).unwrap_err())
        };
        assert_eq!(mk(vec![], q.clone(), pts.clone(), 1.0), "params");
        assert_eq!(
            mk(vec![Param::A(0), Param::A(0)], q.clone(), pts.clone(), 1.0),
            "params"
        );
        assert_eq!(mk(vec![Param::A(9)], q.clone(), pts.clone(), 1.0), "params");
        assert_eq!(
            mk(vec![Param::A(0)], q.clone(), vec![], 1.0),
            "measurements"
        );
        assert_eq!(
            mk(vec![Param::A(0)], vec![vec![0.0; 5]], pts.clone(), 1.0),
            "poses"
        );
        assert_eq!(mk(vec![Param::A(0)], q.clone(), pts.clone(), -1.0), "k");
    }
}
