//! Particle swarms (Qiao 2021 §3.1, eq. 12): [`pso`] and Qiao's hybrid [`bas_pso`], with
//! their options.

use rand::Rng as _;
use rayon::prelude::*;

use super::search::{
    check_budget, check_count_at_most, check_iterations, check_target, halton, offset, primes,
    random_direction, reached, sane, sign, Bounds, Fitness, Limit, MetaResult, Schedules,
    HALTON_SKIP, MAX_POPULATION,
};
use crate::error::{finite_non_negative, finite_positive, Error, Result};
use crate::identify::options;
use crate::numeric::rng::Rng;
use crate::numeric::Real;

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
    #[serde(rename = "inertia", deserialize_with = "inertia_weights")]
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
/// from one table: the keys [`BeetleTerm`] declares go to `beetle` (the schedules' keys to
/// its schedules, see [`crate::identify::Metaheuristic`]), every other key to `swarm`.
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
    /// The schedules of eq. 13, keys of their own ([`Schedules`]). Default: width and step
    /// 0.1, decay 0.95, floors 1e-6.
    #[serde(skip)]
    pub schedules: Schedules,
}

impl Default for BeetleTerm {
    fn default() -> Self {
        BeetleTerm {
            c3: 1.0,
            schedules: Schedules::new(0.1, 0.1, 0.95, 1e-6, 1e-6),
        }
    }
}

impl<'de> serde::Deserialize<'de> for BasPsoOptions {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let mut swarm = toml::Table::deserialize(d)?;
        let beetle = options::split::<BeetleTerm>(&mut swarm);
        Ok(BasPsoOptions {
            swarm: PsoOptions::deserialize(toml::Value::Table(swarm)).map_err(|e| {
                D::Error::custom(options::with_taken(e, &[options::fields::<BeetleTerm>()]))
            })?,
            beetle: BeetleTerm::deserialize(toml::Value::Table(beetle))
                .map_err(D::Error::custom)?,
        })
    }
}

fn yes() -> bool {
    true
}

/// `inertia = [start, end]`: the inertia weights of [`Velocity::Inertia`].
fn inertia_weights<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<Velocity, D::Error> {
    let [start, end] = <[Real; 2] as serde::Deserialize>::deserialize(d)?;
    Ok(Velocity::Inertia { start, end })
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

fn check_swarm(s: &Swarm) -> Result<()> {
    check_count_at_most("population", s.population, MAX_POPULATION)?;
    check_iterations(s.iterations)?;
    check_budget(s.max_evaluations, s.population, s.per_iteration())?;
    let c1 = "c1";
    finite_non_negative(c1, s.c1)?;
    finite_non_negative("c2", s.c2)?;
    finite_positive("max_velocity", s.max_velocity)?;
    check_target(s.target)?;
    match s.velocity {
        Velocity::Constriction => {
            if s.c1 + s.c2 <= 4.0 {
                return Err(Error::setting(
                    c1,
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
        b.schedules.check()?;
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
/// unit direction `b` (eq. 13, with the descending sign, see [`bas`](super::bas)), and
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
    let (mut d, mut delta) = s
        .beetle
        .map_or((0.0, 0.0), |bt| (bt.schedules.antenna, bt.schedules.step));
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
            (d, delta) = bt.schedules.next(d, delta);
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
