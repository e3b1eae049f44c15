//! Monte-Carlo statistics: identification accuracy η (Guo 2024 eq. 29), validation errors
//! averaged over trials, parameter RMSE and its ratio to the Cramér–Rao bound.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::ops::Deref;

/// The distributions live with the numerics ([`crate::numeric::dist`]), below every layer that
/// takes an interval.
pub use crate::numeric::dist;
pub use eta::{eta, trial_eta_mean};
pub use figure::same_json;
pub mod ecdf;
mod eta;
mod figure;
pub mod location;
mod missing;
pub mod paired;
pub mod precision;
mod sums;

use super::metric::{Metric, PerTrial};
use super::outcome::{Outcome, TrialResult, OPTIONAL_STATS};
use super::spill::{Spill, Spilled};
use crate::calibrate::ErrorStats;
use crate::identify::Termination;
use crate::numeric::{nan, Real};
use sums::{Spread2, StatsSum, Sum};

/// The optional statistics of an entry ([`OPTIONAL_STATS`]): the keys of the entry no other
/// field takes. One that is not an optional statistic (a misspelled `eta_mean_pct`) is refused
/// by its name, where it was refused as "expected struct Figures".
fn optional_stats<'de, D>(d: D) -> Result<BTreeMap<String, Figures>, D::Error>
where
    D: serde::Deserializer<'de>,
{
    use serde::de::Error as _;
    let raw = BTreeMap::<String, serde_json::Value>::deserialize(d)?;
    raw.into_iter()
        .map(|(key, v)| match OPTIONAL_STATS.contains(&key.as_str()) {
            true => Figures::deserialize(v)
                .map(|f| (key.clone(), f))
                .map_err(|e| D::Error::custom(format!("`{key}`: {e}"))),
            false => Err(D::Error::custom(format!("unknown field `{key}`"))),
        })
        .collect()
}

/// Mean, median and standard deviation over trials of one per-trial value: η of one
/// parameter (%), a search's final fitness (`final_fitness`).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrialFigures {
    /// Mean η (%).
    #[serde(deserialize_with = "nan::real")]
    pub mean: Real,
    /// The 95 % t interval of the mean ([`dist::t_interval`]; `null` under 2 trials).
    pub mean_ci95: Option<[Real; 2]>,
    /// Median η (%).
    #[serde(deserialize_with = "nan::real")]
    pub median: Real,
    /// The distribution-free 95 % interval of the median: the order statistics of ranks
    /// [`median_ranks`] (`null` under 6 trials).
    pub median_ci95: Option<[Real; 2]>,
    /// Standard deviation of η (%).
    #[serde(deserialize_with = "nan::real")]
    pub std: Real,
}

impl TrialFigures {
    /// The figures of the finite values of `v`, as each η's: the mean with its t interval,
    /// the median with its distribution-free interval ([`median_ranks`]), the standard
    /// deviation (divisor n); `None` when no value is finite.
    pub fn of(v: &[Real]) -> Option<TrialFigures> {
        let v: Vec<Real> = v.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        let (mean, median) = (location::Located::mean(&v), location::Located::median(&v));
        let std =
            (v.iter().map(|x| (x - mean.estimate).powi(2)).sum::<Real>() / v.len() as Real).sqrt();
        Some(TrialFigures {
            mean: mean.estimate,
            mean_ci95: mean.ci95,
            median: median.estimate,
            median_ci95: median.ci95,
            std,
        })
    }
}

/// Error statistics averaged over trials ([`ErrorStats`]: mean, RMS, max, s.d. of one
/// trial's errors), each with the 95 % t interval of its mean over trials (`null` under 2
/// trials): `mean_ci95` is the interval of `mean`, `rms_ci95` of `rms`, and so on.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(from = "FiguresRead")]
pub struct Figures {
    /// The statistics, each averaged over trials.
    #[serde(flatten)]
    pub stats: ErrorStats,
    /// 95 % interval of `mean`.
    pub mean_ci95: Option<[Real; 2]>,
    /// 95 % interval of `rms`.
    pub rms_ci95: Option<[Real; 2]>,
    /// 95 % interval of `max`.
    pub max_ci95: Option<[Real; 2]>,
    /// 95 % interval of `std`.
    pub std_ci95: Option<[Real; 2]>,
}

/// [`Figures`] as `summary.json` holds them, read field by field: `flatten` would read the
/// statistics from a copy of the object, and a refusal of one of them would name the object
/// (`validation_after_mm`) and not its key (`validation_after_mm.mean`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FiguresRead {
    #[serde(deserialize_with = "nan::real")]
    mean: Real,
    #[serde(deserialize_with = "nan::real")]
    rms: Real,
    #[serde(deserialize_with = "nan::real")]
    max: Real,
    #[serde(deserialize_with = "nan::real")]
    std: Real,
    mean_ci95: Option<[Real; 2]>,
    rms_ci95: Option<[Real; 2]>,
    max_ci95: Option<[Real; 2]>,
    std_ci95: Option<[Real; 2]>,
}

impl From<FiguresRead> for Figures {
    fn from(r: FiguresRead) -> Figures {
        Figures {
            stats: ErrorStats {
                mean: r.mean,
                rms: r.rms,
                max: r.max,
                std: r.std,
            },
            mean_ci95: r.mean_ci95,
            rms_ci95: r.rms_ci95,
            max_ci95: r.max_ci95,
            std_ci95: r.std_ci95,
        }
    }
}

impl Figures {
    /// The statistic of metric `m` (its `mean`, `rms` or `max`) with its 95 % interval;
    /// `None` for a metric that is no such statistic.
    pub fn stat(&self, m: Metric) -> Option<(Real, Option<[Real; 2]>)> {
        match m.spec().stat? {
            "mean" => Some((self.mean, self.mean_ci95)),
            "rms" => Some((self.rms, self.rms_ci95)),
            "max" => Some((self.max, self.max_ci95)),
            _ => None,
        }
    }
}

impl Deref for Figures {
    type Target = ErrorStats;
    fn deref(&self) -> &ErrorStats {
        &self.stats
    }
}

/// The 0-based ranks (l, u) of the order statistics that bound a distribution-free
/// interval of the median of `n` values at level 1 − `alpha`: the largest l with
/// P(B ≤ l) ≤ `alpha` / 2 for B ~ Binomial(n, ½), and u = n − 1 − l, so that
/// P(x₍ₗ₎ ≤ median ≤ x₍ᵤ₎) ≥ 1 − `alpha` (Conover, *Practical Nonparametric Statistics*,
/// § 3.2). `None` when even the extreme values do not reach the level (n < 6 at 95 %).
pub fn median_ranks(n: usize, alpha: Real) -> Option<(usize, usize)> {
    if n == 0 {
        return None;
    }
    let nf = n as Real;
    let ln_c = |k: usize| {
        dist::ln_gamma(nf + 1.0)
            - dist::ln_gamma(k as Real + 1.0)
            - dist::ln_gamma(nf - k as Real + 1.0)
    };
    let ln2n = nf * std::f64::consts::LN_2;
    let mut cdf = 0.0;
    let mut l = None;
    for k in 0..n.div_ceil(2) {
        cdf += (ln_c(k) - ln2n).exp();
        if cdf > alpha / 2.0 {
            break;
        }
        l = Some(k);
    }
    l.map(|l| (l, n - 1 - l))
}

/// One `results` entry of `summary.json` (docs/formats.md "summary.json"); a figure an older
/// summary lacks reads as NaN, as a `null` one does (a reader cannot take it for a value),
/// an interval or a map it lacks as none.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default)]
pub struct Entry {
    /// The method's label.
    pub method: String,
    /// The calibration pose strategy.
    pub poses: String,
    /// The swept value, for sweeps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sweep_value: Option<serde_json::Value>,
    /// Every swept key and its value at this entry, for sweeps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sweep: Option<BTreeMap<String, serde_json::Value>>,
    /// Mean over parameters of the mean η (%).
    #[serde(deserialize_with = "nan::real")]
    pub eta_mean_pct: Real,
    /// Its 95 % t interval, from the spread over trials of each trial's mean η over the
    /// parameters (`null` under 2 trials).
    pub eta_mean_pct_ci95: Option<[Real; 2]>,
    /// Mean over parameters of the median η (%): with random errors a draw near zero makes
    /// one trial's η hugely negative, which the mean follows and the median does not.
    #[serde(deserialize_with = "nan::real")]
    pub eta_median_pct: Real,
    /// Its 95 % interval: the mean over parameters of each parameter's distribution-free
    /// interval of the median at level 1 − 0.05 / p (p parameters; Bonferroni, so that all
    /// p hold together with probability ≥ 95 % and so does their mean); `null` when a
    /// parameter has too few trials for its interval.
    pub eta_median_pct_ci95: Option<[Real; 2]>,
    /// η per parameter with a non-zero injected error, over the trials where that error is
    /// determinable (above [`crate::study::crb::DETERMINABLE_SIGMAS`] Cramér–Rao σ); a
    /// parameter determinable in no trial has none. Every η figure above is over these.
    pub eta: BTreeMap<String, TrialFigures>,
    /// Each parameter (base left out) whose non-zero injected error was not determinable in
    /// some usable trial — at most [`crate::study::crb::DETERMINABLE_SIGMAS`] Cramér–Rao σ
    /// of the trial's calibration — with the number of such trials; those trials' η does not
    /// count. Absent when there is none (and in a summary written before it).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub eta_not_determinable: BTreeMap<String, usize>,
    /// Validation position errors before compensation (mm), each statistic averaged over
    /// trials.
    pub validation_before_mm: Figures,
    /// … after compensation.
    pub validation_after_mm: Figures,
    /// Position errors at the calibration poses against their noise-free true points (mm),
    /// nominal robot, each statistic averaged over trials: what a paper that validates on its
    /// calibration points reports (Ban; Qiao 2021's calibration-point figures).
    pub calibration_before_mm: Figures,
    /// … compensated robot.
    pub calibration_after_mm: Figures,
    /// The statistics only some studies have, by name ([`OPTIONAL_STATS`]: orientation and
    /// Qiao's attitude for full-pose data, `validation_before_fitted_mm` with
    /// `validation.before_fitted`, Guo's axis errors with `validation.axis_errors`), each
    /// statistic averaged over trials; a statistic no trial has is absent.
    #[serde(flatten, deserialize_with = "optional_stats")]
    pub optional: BTreeMap<String, Figures>,
    /// Improvement of the mean validation error, % ((before − after) / before).
    #[serde(deserialize_with = "nan::real")]
    pub improvement_pct: Real,
    /// RMSE over trials of each identified parameter error (mm, rad); the base parameters,
    /// which absorb the registration's error, are left out.
    #[serde(deserialize_with = "nan::read")]
    pub param_rmse: BTreeMap<String, Real>,
    /// The 95 % interval of each `param_rmse`: the t interval of the mean squared error,
    /// its bounds' square roots (a negative lower bound taken as 0); `null` under 2 trials.
    pub param_rmse_ci95: BTreeMap<String, Option<[Real; 2]>>,
    /// Mean over trials of each identified parameter's error (identified − true; mm, rad),
    /// base left out as for `param_rmse`: the estimator's bias. Where the truth is the same
    /// in every trial (`errors.kind` `paper` or `values`), the mean identified error is the
    /// injected one plus this.
    #[serde(deserialize_with = "nan::read")]
    pub param_bias: BTreeMap<String, Real>,
    /// Trace of the empirical covariance of the estimates over the mean Cramér–Rao trace
    /// σ²(JᵀWJ)⁻¹ (`null` without tracker noise or with fewer than 2 trials).
    pub crb_ratio: Option<Real>,
    /// Identifications that gave no usable result (diverged, singular, invalid, non-finite).
    pub failures: usize,
    /// How the identifications ended, by termination reason.
    pub terminations: BTreeMap<String, usize>,
    /// Mean iterations.
    #[serde(deserialize_with = "nan::real")]
    pub iterations_mean: Real,
    /// Mean evaluations of the model per identification (residuals for the Jacobian
    /// methods, fitness for BAS, PSO and BAS-PSO): the budget a method spent.
    #[serde(deserialize_with = "nan::real")]
    pub evaluations_mean: Real,
    /// Mean wall time of one registration + identification (s). Machine-dependent, so it
    /// is written as `null` in `summary.json` (which must be the same bytes for a seed
    /// whatever the thread count) and with its value in `timing.json` and `report.md`.
    #[serde(serialize_with = "as_null", deserialize_with = "nan::real")]
    pub seconds_per_identification: Real,
    /// For a search (BAS, PSO, BAS-PSO): its fixed-target runtime ECDFs
    /// ([`ecdf::SearchAcc::ecdf`]); absent for the other methods.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub search_ecdf: Option<ecdf::SearchEcdf>,
    /// For a search: its mean best fitness at each budget of the grid with a 95 % t interval
    /// ([`ecdf::SearchAcc::fixed_budget`]); absent for the other methods.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fixed_budget: Option<Vec<ecdf::BudgetPoint>>,
    /// For a search: its best fitness at the end of its own budget over the usable trials
    /// (metric `final_fitness.mean`); absent for the other methods.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub final_fitness: Option<TrialFigures>,
    /// Spreads over trials (plots only).
    #[serde(skip)]
    pub spread: Spread,
    /// Each trial's value of every per-trial metric ([`Metric::PER_TRIAL`]), in trial order,
    /// NaN where the identification failed: what the paired comparisons and the claims of
    /// the entries of one block compare (not written as such).
    #[serde(skip)]
    pub per_trial: PerTrial,
    /// Each parameter's η per trial (the parameters of `eta`), in trial order, NaN where
    /// the identification failed or the truth was 0: what a claim "for every parameter"
    /// compares (not written).
    #[serde(skip)]
    pub eta_per_trial: BTreeMap<String, Spilled>,
}

fn as_null<S: serde::Serializer>(_: &Real, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_none()
}

fn mean(v: &[Real]) -> Real {
    if v.is_empty() {
        Real::NAN
    } else {
        v.iter().sum::<Real>() / v.len() as Real
    }
}

/// What one (strategy, method) pair has gathered so far: running sums (per parameter, the
/// per-trial numbers an exact median and two-pass deviation need, its error and its η, are in
/// the accumulator's [`Spill`]).
#[derive(Clone, Debug, Default)]
struct Cell {
    outs: usize,
    seconds: Sum,
    seconds_sq: Sum,
    terminations: BTreeMap<String, usize>,
    ok: usize,
    crb: Sum,
    before: StatsSum,
    after: StatsSum,
    calibration: [StatsSum; 2],
    after_rms_sq: Sum,
    /// The optional statistics: before / after in deg, in Qiao's attitude deg, then the
    /// fitted "before" in mm.
    deg: [Option<StatsSum>; OPTIONAL_STATS.len()],
    iterations: Sum,
    evaluations: Sum,
    /// Each usable trial's mean η over the parameters.
    eta_trial: Spread2,
    /// Per parameter, the usable trials whose non-zero injected error was not determinable.
    below: Vec<usize>,
    /// The searches' runtime and fixed-budget numbers.
    search: ecdf::SearchAcc,
}

/// The per-trial headline values kept for the paired comparisons and the claims, one value
/// per trial of every cell (NaN where the trial's identification failed), so that the
/// streams of two cells line up trial by trial: every per-trial metric
/// ([`Metric::PER_TRIAL`]) and the wall time of the identification (s).
pub const HEADLINES: usize = Metric::PER_TRIAL.len() + 1;

/// Spreads over trials of the headline metrics (for the sweep plots; not in `summary.json`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Spread {
    /// Standard deviation over trials of the validation RMS after compensation (mm).
    pub after_rms: Real,
    /// Mean over parameters of the standard deviation of η (%).
    pub eta: Real,
    /// Standard deviation of the wall time of one identification (s).
    pub seconds: Real,
}

/// Streaming aggregation of a block's trials into one [`Entry`] per strategy × method
///: trials are pushed in trial order and dropped; what stays is running sums and
/// the per-parameter numbers of each cell, spilled to a scratch file in chunks ([`Spill`]) so
/// that memory does not grow with the trials. The sums run in trial order, so the entries are
/// the same bytes whichever way the trials were split among threads or shards.
#[derive(Debug)]
pub struct Accumulator {
    names: Vec<String>,
    methods: usize,
    cells: Vec<Cell>,
    spill: Spill,
}

/// Whether an outcome counts (not a failure). A `rank-deficient` ending counts when the
/// identified list is known to hold undetermined parameters (`identification.params`): it is
/// then the expected outcome of a damped method, unless the method never started (fewer
/// readings than parameters: no iteration).
fn usable(o: &Outcome) -> bool {
    let undetermined_ok = o.rank_deficient_expected
        && o.termination == Termination::RankDeficient
        && o.iterations > 0;
    (undetermined_ok
        || !(o.termination.gives_nothing() || o.termination == Termination::RankDeficient))
        && o.identified.iter().all(|x| x.is_finite())
        && o.after_mm.rms.is_finite()
}

impl Accumulator {
    /// An empty accumulator for `strategies` × `methods` outcomes over the parameters `names`.
    pub fn new(names: &[String], strategies: usize, methods: usize) -> Accumulator {
        let cells = strategies * methods;
        Accumulator {
            names: names.to_vec(),
            methods,
            cells: vec![
                Cell {
                    below: vec![0; names.len()],
                    ..Cell::default()
                };
                cells
            ],
            spill: Spill::new(cells * (names.len() * 3 + HEADLINES)),
        }
    }

    /// The spill streams of cell `c`'s parameter `k`: its errors and its η values.
    fn streams(&self, c: usize, k: usize) -> (usize, usize) {
        let s = (c * self.names.len() + k) * 3;
        (s, s + 1)
    }

    /// The spill stream of cell `c`'s parameter `k`'s η per trial, NaN where there is none.
    fn eta_stream(&self, c: usize, k: usize) -> usize {
        (c * self.names.len() + k) * 3 + 2
    }

    /// The spill stream of cell `c`'s headline value `h` (see [`HEADLINES`]).
    fn headline(&self, c: usize, h: usize) -> usize {
        self.cells.len() * self.names.len() * 3 + c * HEADLINES + h
    }

    /// Each cell's figure of `m` so far, in cell order (strategy × method): a statistic of
    /// the validation errors after compensation ([`precision::HEADLINE`]) and its 95 %
    /// interval, as `summary.json` would write them now; NaN without an interval for a metric
    /// of another key.
    pub fn headlines(&self, m: Metric) -> Vec<(Real, Option<[Real; 2]>)> {
        let after = m.spec().field == Metric::ValidationAfterMean.spec().field;
        self.cells
            .iter()
            .map(|c| {
                let f = after.then(|| c.after.average());
                f.and_then(|f| f.stat(m)).unwrap_or((Real::NAN, None))
            })
            .collect()
    }

    /// Adds one trial (trials must come in trial order). Fails only when the scratch file
    /// cannot be written.
    pub fn push(&mut self, t: &TrialResult) -> crate::error::Result<()> {
        for o in &t.outcomes {
            let ci = o.strategy * self.methods + o.method;
            let c = &mut self.cells[ci];
            c.outs += 1;
            c.seconds.add(o.seconds);
            c.seconds_sq.add(o.seconds * o.seconds);
            *c.terminations
                .entry(o.termination.as_str().to_string())
                .or_insert(0) += 1;
            if let Some(r) = &o.search {
                c.search.add(r);
            }
            let ok = usable(o);
            let hs = self.headline(ci, Metric::PER_TRIAL.len());
            self.spill.push(hs, o.seconds)?;
            if !ok {
                for h in 0..Metric::PER_TRIAL.len() {
                    let s = self.headline(ci, h);
                    self.spill.push(s, Real::NAN)?;
                }
                for k in 0..self.names.len() {
                    let s = self.eta_stream(ci, k);
                    self.spill.push(s, Real::NAN)?;
                }
                continue;
            }
            self.cells[ci].ok += 1;
            let below = t.not_determinable_on(o.strategy);
            for k in 0..self.names.len() {
                // Base parameters absorb the registration's error: nuisance, not compared.
                if self.names[k].starts_with("base.") {
                    continue;
                }
                let (se, sn) = self.streams(ci, k);
                self.spill.push(se, o.identified[k] - t.truth[k])?;
                let determinable = !below.contains(&k);
                if !determinable {
                    self.cells[ci].below[k] += 1;
                }
                let e = eta(t.truth[k], o.identified[k]).filter(|_| determinable);
                self.spill
                    .push(self.eta_stream(ci, k), e.unwrap_or(Real::NAN))?;
                if let Some(e) = e {
                    self.spill.push(sn, e)?;
                }
            }
            let eta_trial = trial_eta_mean(&self.names, (&t.truth, &o.identified), below);
            for (h, m) in Metric::PER_TRIAL.iter().enumerate() {
                let s = self.headline(ci, h);
                let of_trial = m.spec().of_trial.unwrap_or(|_, _| Real::NAN);
                self.spill.push(s, of_trial(o, eta_trial))?;
            }
            let c = &mut self.cells[ci];
            if !eta_trial.is_nan() {
                c.eta_trial.add(eta_trial);
            }
            if let Some(x) = t.crb_trace[o.strategy] {
                c.crb.add(x);
            }
            c.before.add(&o.before_mm);
            c.after.add(&o.after_mm);
            c.calibration[0].add(&o.calibration_before_mm);
            c.calibration[1].add(&o.calibration_after_mm);
            c.after_rms_sq.add(o.after_mm.rms * o.after_mm.rms);
            for (acc, d) in c.deg.iter_mut().zip(o.optional.values()) {
                if let Some(d) = d {
                    acc.get_or_insert_with(StatsSum::default).add(&d);
                }
            }
            c.iterations.add(o.iterations as Real);
            c.evaluations.add(o.evaluations as Real);
        }
        Ok(())
    }

    /// The entry of `(strategy, method)`, labelled `(method, poses)`. Fails only when the
    /// scratch file cannot be read.
    pub fn entry(
        &self,
        strategy: usize,
        method: usize,
        labels: (&str, &str),
        sweep_value: Option<serde_json::Value>,
        sweep: Option<BTreeMap<String, serde_json::Value>>,
    ) -> crate::error::Result<Entry> {
        let ci = strategy * self.methods + method;
        let c = &self.cells[ci];
        let failures = c.outs - c.ok;
        let mut eta_map = BTreeMap::new();
        let mut rmse = BTreeMap::new();
        let mut bias = BTreeMap::new();
        let mut rmse_ci = BTreeMap::new();
        let mut emp_trace = 0.0;
        let with_eta = self
            .names
            .iter()
            .enumerate()
            .filter(|(k, n)| {
                !n.starts_with("base.") && !self.spill.is_empty(self.streams(ci, *k).1)
            })
            .count();
        let mut median_bounds = Some([-0.0, -0.0]);
        for (k, name) in self.names.iter().enumerate() {
            if name.starts_with("base.") {
                continue;
            }
            let (errs, etas) = self.streams(ci, k);
            let sp = &self.spill;
            let mse = sp.mean_of(errs, |e| e * e)?;
            rmse.insert(name.clone(), mse.sqrt());
            let n = sp.len(errs);
            let sd_sq = (sp.mean_of(errs, |e| (e * e - mse).powi(2))? * n as Real
                / (n as Real - 1.0))
                .sqrt();
            rmse_ci.insert(
                name.clone(),
                dist::t_interval(mse, sd_sq, n).map(|[lo, hi]| [lo.max(0.0).sqrt(), hi.sqrt()]),
            );
            bias.insert(name.clone(), sp.mean(errs)?);
            emp_trace += sp.std(errs)?.powi(2);
            if !sp.is_empty(etas) {
                let n = sp.len(etas);
                let std = sp.std(etas)?;
                let m = sp.mean(etas)?;
                let order = |r: Option<(usize, usize)>| -> crate::error::Result<Option<[Real; 2]>> {
                    match r {
                        Some((l, u)) => Ok(Some([sp.select(etas, l)?, sp.select(etas, u)?])),
                        None => Ok(None),
                    }
                };
                let joint = order(median_ranks(n, 0.05 / with_eta as Real))?;
                median_bounds = match (median_bounds, joint) {
                    (Some([a, b]), Some([l, u])) => Some([a + l, b + u]),
                    _ => None,
                };
                eta_map.insert(
                    name.clone(),
                    TrialFigures {
                        mean: m,
                        mean_ci95: dist::t_interval(
                            m,
                            std * (n as Real / (n as Real - 1.0)).sqrt(),
                            n,
                        ),
                        median: sp.median(etas)?,
                        median_ci95: order(median_ranks(n, 0.05))?,
                        std,
                    },
                );
            }
        }
        let mut eta_per_trial = BTreeMap::new();
        for (k, name) in self.names.iter().enumerate() {
            if eta_map.contains_key(name) {
                eta_per_trial.insert(name.clone(), self.spill.stream(self.eta_stream(ci, k)));
            }
        }
        let eta_mean_pct = mean(&eta_map.values().map(|e| e.mean).collect::<Vec<_>>());
        let eta_median_pct = mean(&eta_map.values().map(|e| e.median).collect::<Vec<_>>());
        let eta_median_pct_ci95 = median_bounds
            .filter(|_| with_eta > 0)
            .map(|[a, b]| [a / with_eta as Real, b / with_eta as Real]);
        let eta_mean_pct_ci95 = c.eta_trial.interval(eta_mean_pct);
        let ok = c.ok;
        let crb_ratio = (ok >= 2 && c.crb.n == ok)
            .then(|| emp_trace * ok as Real / (ok - 1) as Real / c.crb.mean());
        let before = c.before.average();
        let after = c.after.average();
        let spread_of = |s: &Sum, sq: &Sum| (sq.mean() - s.mean().powi(2)).max(0.0).sqrt();
        Ok(Entry {
            method: labels.0.to_string(),
            poses: labels.1.to_string(),
            sweep_value,
            sweep,
            eta_mean_pct,
            eta_mean_pct_ci95,
            eta_median_pct,
            eta_median_pct_ci95,
            eta: eta_map.clone(),
            eta_not_determinable: self
                .names
                .iter()
                .zip(&c.below)
                .filter(|(n, &b)| b > 0 && !n.starts_with("base."))
                .map(|(n, &b)| (n.clone(), b))
                .collect(),
            validation_before_mm: before,
            validation_after_mm: after,
            calibration_before_mm: c.calibration[0].average(),
            calibration_after_mm: c.calibration[1].average(),
            optional: OPTIONAL_STATS
                .iter()
                .zip(&c.deg)
                .filter_map(|(k, d)| Some((k.to_string(), d.as_ref()?.average())))
                .collect(),
            improvement_pct: (before.mean - after.mean) / before.mean * 100.0,
            param_rmse: rmse,
            param_rmse_ci95: rmse_ci,
            param_bias: bias,
            crb_ratio,
            failures,
            terminations: c.terminations.clone(),
            iterations_mean: c.iterations.mean(),
            evaluations_mean: c.evaluations.mean(),
            seconds_per_identification: c.seconds.mean(),
            search_ecdf: (!c.search.is_empty()).then(|| c.search.ecdf()),
            fixed_budget: (!c.search.is_empty()).then(|| c.search.fixed_budget()),
            final_fitness: match (c.search.is_empty(), Metric::FinalFitness.per_trial_index()) {
                (false, Some(h)) => {
                    TrialFigures::of(&self.spill.stream(self.headline(ci, h)).values()?)
                }
                _ => None,
            },
            per_trial: PerTrial::new(
                (0..Metric::PER_TRIAL.len())
                    .map(|h| self.spill.stream(self.headline(ci, h)))
                    .collect(),
            ),
            eta_per_trial,
            spread: Spread {
                after_rms: spread_of(&c.after.0[1], &c.after_rms_sq),
                eta: mean(&eta_map.values().map(|e| e.std).collect::<Vec<_>>()),
                seconds: spread_of(&c.seconds, &c.seconds_sq),
            },
        })
    }
}

#[cfg(test)]
mod tests;
