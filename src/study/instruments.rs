//! The instruments study: which parameters each measurement kind identifies, and to what
//! accuracy, on one robot with one error set (docs/instruments.md).
//!
//! A scenario holding an `[instruments_study]` table (its pose counts, strategies, candidates
//! and validation poses) and `[[measurement]]` (or one `[measurement]`) entries runs it
//! (read by serde, [`crate::study::kind`]): for every
//! instrument, pose count and pose strategy (`random` or `detmax-ide` on the instrument's own
//! information matrix), each trial draws the true robot, measures the poses with the
//! instrument (touching its planes or spheres with the true robot, the instrument's noise),
//! identifies the parameters the instrument can see by `ls` weighted by `1/σ²`, and validates
//! the identified robot by the position error at fresh poses, as a tracker would see it.

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DMatrixViewMut, DVector};
use rand::seq::index::sample;
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::identify::kind::{identifiability, KindProblem};
use crate::identify::{solve, LeastSquares, LsOptions, Termination};
use crate::measurement::kind::{Instrument, KindData};
use crate::numeric::rng::{stream, trial_seed};
use crate::numeric::{Real, Vec3};
use crate::poses::{select, PoseModel, SelectOptions, Strategy};
use crate::robot::{Param, Robot};
use crate::sim::instrument::{measure, touch, touching, InstrumentSettings, Layout};
use crate::sim::settings::ErrorSettings;
use crate::study::scenario::StrategyName;
use crate::study::whole::Head;

mod pool;
mod trial;
pub use trial::Trial;

/// A scenario file running the instruments study.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstrumentsScenario {
    /// The keys every study takes ([`Head::take`]; trials per cell, default 20, at least 2).
    #[serde(skip)]
    pub head: Head,
    /// Built-in robot name or robot file.
    pub robot: String,
    /// Pose counts.
    #[serde(default = "default_counts")]
    pub poses: Vec<usize>,
    /// Pose strategies: `random`, `detmax-ide` (or `detmax`).
    #[serde(default = "default_strategies")]
    pub strategies: Vec<String>,
    /// Candidate poses on each instrument (the pool that random draws from and DETMAX
    /// searches).
    #[serde(default = "default_candidates")]
    pub candidates: usize,
    /// Fresh validation poses per trial.
    #[serde(default = "default_validation")]
    pub validation: usize,
    /// The true robot's errors.
    #[serde(default)]
    pub errors: ErrorSettings,
    /// The instruments: one `[measurement]` table or `[[measurement]]` tables (read by
    /// [`InstrumentsScenario::from_table`], each entry's errors naming its place).
    #[serde(skip)]
    pub measurement: Vec<InstrumentSettings>,
}

/// The robot's joint and tool parameters: what an instrument may identify of it (the base's
/// are the instrument's placement).
fn joint_tool_params(nominal: &Robot) -> Vec<Param> {
    nominal
        .params()
        .into_iter()
        .filter(|p| !matches!(p, Param::Base(_)))
        .collect()
}

fn default_counts() -> Vec<usize> {
    vec![50, 200]
}
fn default_strategies() -> Vec<String> {
    [Strategy::Random, Strategy::DetmaxIde]
        .map(|s| StrategyName::of(s, false).as_str().to_string())
        .into()
}

/// The optimisers an instruments study compares (by their names in
/// [`StrategyName`]).
const STRATEGIES: [Strategy; 3] = [Strategy::Random, Strategy::Detmax, Strategy::DetmaxIde];
fn default_candidates() -> usize {
    400
}
fn default_validation() -> usize {
    50
}

/// The strategy `name` an instruments study compares ([`STRATEGIES`]); `Err`: what is wrong
/// with it, for the caller to place under its key.
pub(crate) fn strategy(name: &str) -> std::result::Result<Strategy, String> {
    let allowed = |s: &Strategy| STRATEGIES.contains(s);
    match name
        .parse::<StrategyName>()
        .ok()
        .and_then(|n| n.selection())
    {
        Some((s, false)) if allowed(&s) => Ok(s),
        _ => Err(format!(
            "unknown strategy \"{name}\"; allowed: {}",
            STRATEGIES
                .map(|s| StrategyName::of(s, false).as_str())
                .join(", ")
        )),
    }
}

/// The selected poses `chosen` commanded as the simulation measures them: each moved onto its
/// nearest plane or sphere by the nominal robot ([`touching`], inside the joint limits by a
/// margin, as the candidates were made), so that the true robot touches from it. IDE's new
/// poses leave the surfaces, and some cannot be moved back within the limits: those are
/// replaced by the first candidates of `pool` (with their `groups`) not already chosen, so
/// that the set keeps `count` poses. Other kinds keep the poses as they are.
fn on_surfaces(
    nominal: &Robot,
    lay: &Layout,
    chosen: Vec<Vec<Real>>,
    (pool, groups): (&[Vec<Real>], &[usize]),
    count: usize,
) -> (Vec<Vec<Real>>, Vec<usize>) {
    let g: Vec<usize> = chosen
        .iter()
        .map(|q| nearest(lay, &nominal.fk(q).pos))
        .collect();
    let (mut qs, mut g) = touching(nominal, lay, &chosen, &g);
    for (q, k) in pool.iter().zip(groups) {
        if qs.len() >= count {
            break;
        }
        if !qs.contains(q) {
            qs.push(q.clone());
            g.push(*k);
        }
    }
    (qs, g)
}

/// The instrument's information rows of one pose for pose selection: the pose moved onto
/// the nearest plane or sphere first (IDE's mutated poses leave them; the simulation touches
/// from the commanded pose the same way).
struct KindPoseModel<'a> {
    robot: &'a Robot,
    params: Vec<Param>,
    lay: &'a Layout,
    limits: Vec<(Real, Real)>,
    scale: Vec<Real>,
}

impl KindPoseModel<'_> {
    fn rows_of(&self, q: &[Real], out: &mut DMatrixViewMut<Real>) {
        let g = nearest(self.lay, &self.robot.fk(q).pos);
        let q = touch(self.robot, self.lay, g, q, 0.0).unwrap_or_else(|| q.to_vec());
        let qs = [q];
        let data = KindData {
            instrument: self.lay.instrument.clone(),
            group: vec![g],
            values: vec![0.0; self.lay.instrument.rows_per_observation()],
        };
        out.fill(0.0);
        // The instrument's geometry is the layout's (one point cannot fix a first guess).
        let Ok(kp) = KindProblem::with_guess(
            self.robot,
            &self.params,
            &qs,
            &data,
            self.lay.nuisance.clone(),
        ) else {
            return;
        };
        let size = kp.size();
        let mut r = DVector::zeros(size.rows());
        let mut j = DMatrix::zeros(size.rows(), size.params);
        kp.evaluate(&DVector::zeros(size.params), &mut r, &mut j);
        for c in 0..size.params {
            for k in 0..size.rows() {
                out[(k, c)] = j[(k, c)] * self.scale[c];
            }
        }
    }
}

impl PoseModel for KindPoseModel<'_> {
    fn dof(&self) -> usize {
        self.limits.len()
    }
    fn n_params(&self) -> usize {
        self.params.len() + self.lay.instrument.nuisance()
    }
    fn rows_per_pose(&self) -> usize {
        self.lay.instrument.rows_per_observation()
    }
    fn limits(&self) -> &[(Real, Real)] {
        &self.limits
    }
    fn jacobian_block(&self, q: &[Real], out: &mut DMatrixViewMut<Real>) {
        self.rows_of(q, out);
    }
}

/// The plane or sphere whose surface is nearest to `p` (the socket nearest to it).
fn nearest(lay: &Layout, p: &Vec3) -> usize {
    let c = &lay.nuisance;
    let dist = |g: usize| match &lay.instrument {
        Instrument::Planes(axes) => {
            let (k, u, v) = crate::measurement::kind::plane_axes(axes[g]);
            (p[k] - (c[3 * g] + c[3 * g + 1] * p[u] + c[3 * g + 2] * p[v])).abs()
        }
        Instrument::Spheres(r) => {
            ((p - Vec3::new(c[3 * g], c[3 * g + 1], c[3 * g + 2])).norm() - r[g]).abs()
        }
        Instrument::Sockets(d) => (p - crate::measurement::kind::socket(d, c, g).0).norm(),
        _ => 0.0,
    };
    let n = lay.instrument.groups();
    (0..n)
        .min_by(|&a, &b| dist(a).total_cmp(&dist(b)))
        .unwrap_or(0)
}

/// One cell's results: an instrument, a pose count and a strategy.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Cell {
    /// The instrument's label: its kind (with `-chain` for lengths between poses).
    pub kind: String,
    /// Measured poses.
    pub poses: usize,
    /// Pose strategy.
    pub strategy: String,
    /// σ settings: constant part (µm) and per metre (µm/m).
    pub noise_um: Real,
    /// See `noise_um`.
    pub scale_um_per_m: Real,
    /// The robot's parameters the instrument identifies on the candidate poses (base
    /// excluded: the error set has none, and the tracker's frame is registered).
    pub identified: Vec<String>,
    /// The joint and tool parameters it cannot see.
    pub unidentifiable: Vec<String>,
    /// The instrument's own unknowns, identified with the robot.
    pub instrument_unknowns: Vec<String>,
    /// Mean η (Guo 2024 eq. 29, %) per parameter with an injected error; a parameter the
    /// instrument cannot see keeps its nominal value (η = 0).
    pub eta: BTreeMap<String, Real>,
    /// Mean over those parameters of the mean η (%).
    pub eta_mean_pct: Real,
    /// Validation RMS position error at fresh poses (mm), mean over trials, before
    /// (nominal robot) and after calibration.
    pub validation_before_mm: Real,
    /// See `validation_before_mm`.
    pub validation_after_mm: Real,
    /// Trace of the empirical covariance of the identified errors over trials divided by the
    /// mean Cramér–Rao trace `(JᵀWJ)⁻¹` (robot parameters); NaN (`null`) under two usable
    /// trials, without the instrument's noise, or where a trial's JᵀWJ is singular.
    pub crb_ratio: Real,
    /// Trials whose identification did not converge or stopped at a local minimum (a residual
    /// beyond the readings' noise, [`FIT_GATE`]), or whose poses the true robot could not
    /// touch.
    pub failures: usize,
}

/// What every cell of one instrument shares: its layout and candidate poses, the robot's
/// parameters it identifies on them and those it cannot see, and the column scale of pose
/// selection.
#[derive(Debug)]
struct Prepared {
    index: usize,
    settings: InstrumentSettings,
    label: String,
    lay: Layout,
    pool: Vec<Vec<Real>>,
    groups: Vec<usize>,
    params: Vec<Param>,
    unidentifiable: Vec<Param>,
    scale: Vec<Real>,
}

/// One cell ready to run its trials: its instrument, pose count, strategy and, for a
/// strategy other than `random`, the pose set it selected.
#[derive(Debug)]
pub struct CellPlan {
    prepared: std::sync::Arc<Prepared>,
    count: usize,
    strategy: String,
    fixed: Option<(Vec<Vec<Real>>, Vec<usize>)>,
}

impl InstrumentsScenario {
    /// The cells: instruments × pose counts × strategies.
    pub fn cells(&self) -> usize {
        self.measurement.len() * self.poses.len() * self.strategies.len()
    }

    /// Instrument `ii` on `nominal`, prepared for its cells.
    fn prepare(&self, nominal: &Robot, ii: usize) -> Result<Prepared> {
        let s = &self.measurement[ii];
        let joint_tool = joint_tool_params(nominal);
        let (lay, pool, groups) = self.pool(nominal, ii)?;
        let rows = lay.instrument.observations(pool.len()) * lay.instrument.rows_per_observation();
        let pool_data = KindData {
            instrument: lay.instrument.clone(),
            group: groups.clone(),
            values: vec![0.0; rows],
        };
        let a = identifiability(nominal, &joint_tool, &pool, &pool_data)?.robot;
        let label = match lay.instrument {
            Instrument::Distance { pivot: false } => "distance-chain".to_string(),
            _ => s.kind.as_str().to_string(),
        };
        // Column scale for pose selection: the pool's column norms.
        let kp = KindProblem::new(nominal, &a.identifiable, &pool, &pool_data)?;
        let size = kp.size();
        let mut r = DVector::zeros(size.rows());
        let mut j = DMatrix::zeros(size.rows(), size.params);
        kp.evaluate(&DVector::zeros(size.params), &mut r, &mut j);
        let scale = (0..size.params)
            .map(|c| 1.0 / j.column(c).norm().max(1e-12))
            .collect();
        Ok(Prepared {
            index: ii,
            settings: s.clone(),
            label,
            lay,
            pool,
            groups,
            params: a.identifiable,
            unidentifiable: a.unidentifiable,
            scale,
        })
    }

    /// Refuses, as (key, message), a pose count too small for an instrument: its readings
    /// at `instruments_study.poses` fewer than the parameters it identifies on `nominal` (the
    /// robot's identifiable ones and the instrument's own), which no strategy's poses could
    /// determine (docs/formats.md § 4.15).
    pub(crate) fn check_readings(
        &self,
        nominal: &Robot,
    ) -> std::result::Result<(), (String, String)> {
        let Some(&fewest) = self.poses.iter().min() else {
            return Ok(());
        };
        // The robot's joint and tool parameters bound what an instrument identifies: an
        // instrument whose readings reach that bound needs no preparation to pass.
        let bound = joint_tool_params(nominal).len();
        for ii in 0..self.measurement.len() {
            let at = |e: Error| (format!("measurement[{ii}]"), e.to_string());
            let ins = self.measurement[ii].instrument().map_err(at)?;
            let readings = |m: usize| ins.observations(m) * ins.rows_per_observation();
            if readings(fewest) >= bound + ins.nuisance() {
                continue;
            }
            let p = self.prepare(nominal, ii).map_err(at)?;
            let params = p.params.len() + ins.nuisance();
            if readings(fewest) < params {
                let need = (fewest..)
                    .find(|&m| readings(m) >= params)
                    .unwrap_or(fewest);
                let msg = format!(
                    "{fewest} poses give {} readings of measurement[{ii}] ({}) for the {params} \
                     parameters it identifies ({} of the robot's, {} of the instrument's): at \
                     least {need} poses are needed",
                    readings(fewest),
                    p.label,
                    p.params.len(),
                    ins.nuisance()
                );
                return Err(("instruments_study.poses".into(), msg));
            }
        }
        Ok(())
    }

    /// Cell `c` (instruments outer, then pose counts, then strategies) on `nominal`, its
    /// instrument's preparation taken from `prev` when it is the same instrument's.
    pub fn plan(&self, nominal: &Robot, c: usize, prev: Option<&CellPlan>) -> Result<CellPlan> {
        let (ns, np) = (self.strategies.len(), self.poses.len());
        let (ii, count, st) = (
            c / (ns * np),
            self.poses[c / ns % np],
            &self.strategies[c % ns],
        );
        let prepared = match prev.filter(|p| p.prepared.index == ii) {
            Some(p) => p.prepared.clone(),
            None => std::sync::Arc::new(self.prepare(nominal, ii)?),
        };
        let strat = strategy(st).map_err(|m| Error::setting("strategies", m))?;
        let fixed = if strat == Strategy::Random {
            None
        } else {
            let p = &prepared;
            let model = KindPoseModel {
                robot: nominal,
                params: p.params.clone(),
                lay: &p.lay,
                limits: nominal.joints.iter().map(|j| j.limits).collect(),
                scale: p.scale.clone(),
            };
            let mut r = stream(self.head.seed, &format!("instruments-select-{ii}-{count}"));
            let sel = select(&model, &p.pool, strat, &SelectOptions::new(count), &mut r)
                .map_err(|e| Error::setting("poses", format!("{}: {e}", p.label)))?;
            let pool = (p.pool.as_slice(), p.groups.as_slice());
            Some(on_surfaces(nominal, &p.lay, sel.poses, pool, count))
        };
        Ok(CellPlan {
            prepared,
            count,
            strategy: st.clone(),
            fixed,
        })
    }

    /// The cell `plan`'s results from its `trials`, in trial order.
    pub fn cell_of(&self, plan: &CellPlan, trials: &[Option<Trial>]) -> Cell {
        let p = &plan.prepared;
        let what = (p.label.as_str(), &p.settings, &p.lay);
        let params = (p.params.as_slice(), p.unidentifiable.as_slice());
        self.cell(what, params, plan.count, &plan.strategy, trials)
    }
}

impl InstrumentsScenario {
    /// What trial `seed` reads with instrument `s` laid out as `lay`: the true robot drawn
    /// from `[errors]`, the poses (`fixed`, or `count` drawn from the candidates `pool` with
    /// their planes or spheres), the instrument's readings where the true robot touches, and
    /// the fresh validation poses with the true robot's tool points.
    fn reading(
        &self,
        nominal: &Robot,
        (s, lay): (&InstrumentSettings, &Layout),
        (pool, groups): (&[Vec<Real>], &[usize]),
        fixed: Option<&(Vec<Vec<Real>>, Vec<usize>)>,
        count: usize,
        seed: u64,
    ) -> Result<Reading> {
        let mut rng = stream(seed, "errors");
        let errors = crate::sim::truth::true_errors(
            nominal,
            &self.errors,
            crate::measurement::Measure::Position,
            &mut rng,
        )?;
        let truth = nominal.with_errors(&errors);
        let (qs, g) = match fixed {
            Some((q, g)) => (q.clone(), g.clone()),
            None => {
                let mut r = stream(seed, "poses");
                let idx = sample(&mut r, pool.len(), count).into_vec();
                (
                    idx.iter().map(|&i| pool[i].clone()).collect(),
                    idx.iter().map(|&i| groups[i]).collect(),
                )
            }
        };
        let mut noise = stream(seed, "noise");
        let measured = measure(s, lay, &truth, &qs, &g, &mut noise).ok();
        let mut vr = stream(seed, "validation");
        let vq = crate::robot::sampling::uniform_joint_poses(nominal, self.validation, &mut vr);
        let ct = truth.chain();
        let seen: Vec<Vec3> = vq.iter().map(|q| ct.fk(q).pos).collect();
        Ok(Reading {
            errors,
            truth,
            measured,
            validation: (vq, seen),
        })
    }

    /// Trial `trial` of instrument `entry` (0-based, in file order) as `calbench simulate`
    /// writes it: the first pose count, random poses from the candidates, measured as the
    /// study measures them (the same numbers). Fails when the trial or the entry does not
    /// exist, or the true robot cannot touch a surface from a commanded pose.
    pub fn simulate(&self, nominal: &Robot, entry: usize, trial: usize) -> Result<Simulated> {
        if trial >= self.head.trials {
            return Err(Error::option(
                crate::error::Opt::Trial,
                format!(
                    "{trial} is not below the scenario's trials = {}",
                    self.head.trials
                ),
            ));
        }
        let all = &self.measurement;
        let s = all
            .get(entry)
            .ok_or_else(|| Error::setting("measurement", format!("no entry {entry}")))?;
        let (lay, pool, groups) = self.pool(nominal, entry)?;
        let seed = trial_seed(self.head.seed, trial as u64);
        let count = self.poses[0];
        let reading = self.reading(nominal, (s, &lay), (&pool, &groups), None, count, seed)?;
        if reading.measured.is_none() {
            let key = format!("measurement[{entry}]");
            let text = crate::error::read_text(&self.head.path).unwrap_or_default();
            let msg = format!(
                "trial {trial}: the true robot (the nominal one with the [errors]) does not \
                 touch its {} from one of the commanded poses",
                s.kind.as_str()
            );
            return Err(Error::toml_file(&self.head.path, &text, &key, &key, msg));
        }
        Ok(Simulated {
            settings: s.clone(),
            layout: lay,
            seed,
            reading,
        })
    }

    /// Trial `t` of the cell `plan` on `nominal` (its own seed, `trial_seed(seed, t)`):
    /// `None` when the true robot could not touch or the identification did not converge or
    /// stopped at a local minimum ([`FIT_GATE`]).
    pub fn run_trial(&self, nominal: &Robot, plan: &CellPlan, t: usize) -> Result<Option<Trial>> {
        let (p, seed) = (&plan.prepared, trial_seed(self.head.seed, t as u64));
        let (pool, fixed, params) = ((&p.pool[..], &p.groups[..]), plan.fixed.as_ref(), &p.params);
        let reading = self.reading(
            nominal,
            (&p.settings, &p.lay),
            pool,
            fixed,
            plan.count,
            seed,
        )?;
        let Some((tq, data, sigma)) = &reading.measured else {
            return Ok(None);
        };
        let w: Option<Vec<Real>> = sigma
            .iter()
            .all(|v| *v > 0.0)
            .then(|| sigma.iter().map(|v| 1.0 / (v * v)).collect());
        let kp = KindProblem::new(nominal, params, tq, data)?.with_prior_weights(w.as_deref())?;
        let out = solve(
            &LsOptions::default(),
            &kp,
            &DVector::zeros(kp.size().params),
        );
        if out.termination != Termination::Converged || !fits(out.rms_residual, sigma) {
            return Ok(None);
        }
        let t = params.len();
        let x: Vec<Real> = out.x.iter().take(t).copied().collect();
        // Cramér–Rao: (JᵀWJ)⁻¹ over the robot's parameters, W = 1/σ² (the normal matrix of
        // the solution is JᵀPJ with the same weights); none without noise, which gives no W.
        let crb = match w {
            Some(_) => out
                .normal
                .clone()
                .try_inverse()
                .map_or(Real::NAN, |inv| (0..t).map(|c| inv[(c, c)]).sum()),
            None => Real::NAN,
        };
        let ident = kp.robot_with(&out.x);
        let (vq, seen) = &reading.validation;
        // The tracker's sense: the model's points registered onto the measured ones (the
        // frame a tracker fits), then the RMS distance.
        let rms = |r: &Robot| -> Result<Real> {
            let d = crate::calibrate::on_kind::registered_distances(r, vq, seen)?;
            Ok((d.iter().map(|r| r * r).sum::<Real>() / vq.len() as Real).sqrt())
        };
        Ok(Some(Trial {
            before: rms(nominal)?,
            after: rms(&ident)?,
            errors: reading.errors,
            x,
            crb,
        }))
    }

    fn cell(
        &self,
        (label, s, lay): (&str, &InstrumentSettings, &Layout),
        (params, unident): (&[Param], &[Param]),
        count: usize,
        st: &str,
        trials: &[Option<Trial>],
    ) -> Cell {
        let ok: Vec<&Trial> = trials.iter().flatten().collect();
        // With no trial left every mean is NaN (`null` in summary.json, "—" in the reports).
        let n = ok.len() as Real;
        let mut eta = BTreeMap::new();
        if let Some(first) = ok.first() {
            for (k, (p, _)) in first.errors.iter().enumerate() {
                let sum: Real = ok
                    .iter()
                    .map(|tr| {
                        let e = tr.errors[k].1;
                        let est = params.iter().position(|q| q == p).map_or(0.0, |c| tr.x[c]);
                        if e == 0.0 {
                            Real::NAN
                        } else {
                            (1.0 - (e - est).abs() / e.abs()) * 100.0
                        }
                    })
                    .sum();
                if sum.is_finite() {
                    eta.insert(p.to_string(), sum / n);
                }
            }
        }
        let eta_mean_pct = eta.values().sum::<Real>() / eta.len() as Real;
        // Empirical covariance trace of the estimation errors of the identified parameters.
        let t = params.len();
        let err = |tr: &Trial, c: usize| {
            let truth = tr
                .errors
                .iter()
                .find(|(p, _)| *p == params[c])
                .map_or(0.0, |e| e.1);
            tr.x[c] - truth
        };
        let trace: Real = (0..t)
            .map(|c| {
                let mean = ok.iter().map(|tr| err(tr, c)).sum::<Real>() / n;
                ok.iter()
                    .map(|tr| (err(tr, c) - mean).powi(2))
                    .sum::<Real>()
                    / (n - 1.0).max(1.0)
            })
            .sum();
        let crb = ok.iter().map(|tr| tr.crb).sum::<Real>() / n;
        Cell {
            kind: label.to_string(),
            poses: count,
            strategy: st.to_string(),
            noise_um: s.noise_um,
            scale_um_per_m: s.scale_um_per_m,
            identified: params.iter().map(|p| p.to_string()).collect(),
            unidentifiable: unident.iter().map(|p| p.to_string()).collect(),
            instrument_unknowns: lay.instrument.nuisance_names(),
            eta,
            eta_mean_pct,
            validation_before_mm: ok.iter().map(|tr| tr.before).sum::<Real>() / n,
            validation_after_mm: ok.iter().map(|tr| tr.after).sum::<Real>() / n,
            // As a run's (docs/formats.md `crb_ratio`): none under two trials, without noise
            // or where a trial's bound is missing.
            crb_ratio: match ok.len() >= 2 && ok.iter().all(|tr| tr.crb.is_finite()) {
                true => trace / crb,
                false => Real::NAN,
            },
            failures: trials.len() - ok.len(),
        }
    }
}

/// A converged solve whose residual RMS exceeds this many times the readings' RMS σ (plus
/// [`FIT_FLOOR_MM`]) stopped at a local minimum, not at the readings' fit: the readings come
/// from the model itself with Gaussian noise σ, whose residual RMS is about σ per coordinate
/// (√3 σ for a point), so the fit it stopped at is not the least-squares one.
pub const FIT_GATE: Real = 10.0;

/// … the floor of that bound (mm), for noise-free readings: far above the 1e-9 mm of an exact
/// solve, far below any figure a study reports.
pub const FIT_FLOOR_MM: Real = 1e-6;

/// Whether a solve's residual RMS `rms` (mm, per reading) is what readings of standard
/// deviations `sigma` (mm) leave ([`FIT_GATE`]). A sphere's readings on a 7-axis arm with
/// errors near the sphere's radius stopped at 2 mm on noise-free data, and the study had
/// counted the 41 mm after it as a success.
fn fits(rms: Real, sigma: &[Real]) -> bool {
    let n = sigma.len().max(1) as Real;
    let s = (sigma.iter().map(|v| v * v).sum::<Real>() / n).sqrt();
    rms <= FIT_GATE * s + FIT_FLOOR_MM
}

/// What one trial reads with an instrument.
#[derive(Clone, Debug)]
pub struct Reading {
    /// The true robot's errors.
    pub errors: Vec<(Param, Real)>,
    /// The true robot.
    pub truth: Robot,
    /// The joints where the true robot touched (the commanded ones for the kinds without a
    /// surface), the readings and each observation's σ (mm); `None` when the true robot
    /// could not touch a surface from a commanded pose.
    pub measured: Option<(Vec<Vec<Real>>, KindData, Vec<Real>)>,
    /// Fresh validation poses and the true robot's tool points there (base frame, mm).
    pub validation: (Vec<Vec<Real>>, Vec<Vec3>),
}

/// One trial of one instrument, as `calbench simulate` writes it.
#[derive(Clone, Debug)]
pub struct Simulated {
    /// The instrument's entry.
    pub settings: InstrumentSettings,
    /// Its true geometry in the cell.
    pub layout: Layout,
    /// The trial's seed.
    pub seed: u64,
    /// What the trial read (`measured` is `Some`).
    pub reading: Reading,
}
