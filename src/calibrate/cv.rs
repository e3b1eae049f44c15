//! Cross-validation and model choice for `calbench identify` (docs/formats.md `identify`,
//! "Cross-validation and model choice"): seeded K-fold splits of a measurement file, the
//! validation error of each held-out fold after calibrating on the others, a held-out split
//! rule ([`Holdout`]), and candidate models ([`Model`]) compared on the same folds.

mod key;
mod model;

use std::str::FromStr;

pub use key::CvKey;
pub use model::Model;

use super::fit::fit_and_readmit;
use super::kernel::{position_errors, KernelResidual};
use super::validation::validate_file;
use super::{calibrate, Registration};
use crate::error::{Error, Result};
use crate::identify::MethodSpec;
use crate::measurement::Measurements;
use crate::numeric::rng::stream;
use crate::numeric::{Frame, Real};
use crate::robot::{Param, Robot};

/// `--holdout LAST/EVERY`: of every `every` consecutive rows, the last `last` are held out
/// for validation (`3/10`: rows whose 0-based index % 10 ≥ 7).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Holdout {
    /// Rows held out of each block.
    pub last: usize,
    /// Rows per block.
    pub every: usize,
}

impl FromStr for Holdout {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let bad = || format!("`{s}` is not LAST/EVERY with 0 < LAST < EVERY, e.g. 3/10");
        let (a, b) = s.split_once('/').ok_or_else(bad)?;
        // A whole number too large for a count is said to be so, not to break the rule.
        let count = |t: &str| match t.trim().parse::<usize>() {
            Ok(n) => Ok(n),
            Err(e) if *e.kind() == std::num::IntErrorKind::PosOverflow => Err(format!(
                "`{s}`: {} is too large for a count of rows (at most {})",
                t.trim(),
                usize::MAX
            )),
            Err(_) => Err(bad()),
        };
        let (last, every) = (count(a)?, count(b)?);
        if last == 0 || last >= every {
            return Err(bad());
        }
        Ok(Holdout { last, every })
    }
}

impl Holdout {
    /// The rows kept for calibration and those held out, of `n` rows.
    pub fn split(&self, n: usize) -> (Vec<usize>, Vec<usize>) {
        (0..n).partition(|i| i % self.every < self.every - self.last)
    }
}

/// The rows `rows` of `m`, in that order.
pub fn subset(m: &Measurements, rows: &[usize]) -> Measurements {
    let pick = |v: &Option<Vec<Real>>| v.as_ref().map(|v| rows.iter().map(|&i| v[i]).collect());
    Measurements {
        qs: rows.iter().map(|&i| m.qs[i].clone()).collect(),
        points: rows.iter().map(|&i| m.points[i]).collect(),
        quats: m
            .quats
            .as_ref()
            .map(|q| rows.iter().map(|&i| q[i]).collect()),
        sigma_mm: pick(&m.sigma_mm),
        payload_kg: pick(&m.payload_kg),
    }
}

/// The fold (0..k) of each of `n` rows: a permutation drawn from `seed` (stream `cv`), dealt
/// round-robin, so the folds differ in size by one at most. The same for every model.
pub fn folds(n: usize, k: usize, seed: u64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    let mut g = stream(seed, "cv");
    for i in (1..n).rev() {
        let j = rand::Rng::random_range(&mut g, 0..=i);
        order.swap(i, j);
    }
    let mut fold = vec![0; n];
    for (pos, &row) in order.iter().enumerate() {
        fold[row] = pos % k;
    }
    fold
}

/// A K-fold cross-validation's result: position errors (mm) of the held-out points.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CrossValidation {
    /// The model's name ([`Model::name`]).
    pub model: String,
    /// Number of folds.
    pub k: usize,
    /// RMS over every held-out point (each point is held out once).
    #[serde(deserialize_with = "crate::numeric::nan::real")]
    pub rms: Real,
    /// The RMS of each fold.
    #[serde(deserialize_with = "crate::numeric::nan::read")]
    pub fold_rms: Vec<Real>,
    /// Mean of the folds' RMS.
    #[serde(deserialize_with = "crate::numeric::nan::real")]
    pub mean: Real,
    /// Standard deviation (sample, K − 1) of the folds' RMS.
    #[serde(deserialize_with = "crate::numeric::nan::real")]
    pub sd: Real,
    /// The number of parameters identified.
    pub parameters: usize,
    /// What it was run on ([`CvKey`]; not written): a cross-validation of an equal key may
    /// take this one's place. `None`: never.
    #[serde(skip)]
    pub key: Option<CvKey>,
}

/// The model a cross-validation fits in each fold: the robot, the parameters chosen at the
/// nominal robot, those the re-check at the identified robot may re-admit (empty: no
/// re-check), whether a kernel residual follows, and its name.
pub struct CvModel<'a> {
    /// The robot whose parameters are identified.
    pub robot: &'a Robot,
    /// The parameters identified.
    pub params: &'a [Param],
    /// The parameters left out at the nominal robot ([`Model::left_out`]), re-checked at
    /// each fold's identified robot ([`super::fit`]).
    pub candidates: &'a [Param],
    /// A kernel residual fitted on the fold's calibration rows after the parametric model.
    pub kernel: bool,
    /// The model's name ([`Model::name`]).
    pub name: String,
}

/// What one cross-validation runs: the method, the registration, the seeds, and the
/// cross-validations already run that it may take instead of running its own.
pub struct CvSetup<'a> {
    /// The method.
    pub method: &'a MethodSpec,
    /// The registration.
    pub registration: Registration,
    /// Seed of the method's stream (`identify --seed`).
    pub seed: u64,
    /// Seed of the folds (`--cv-seed`).
    pub fold_seed: u64,
    /// Parameters held at their nominal values (`--fix`), left out of every model.
    pub fixed: &'a [Param],
    /// Cross-validations already run: one whose [`CvKey`] equals the one to run is taken
    /// instead (the same figures, to the bit).
    pub done: &'a [CrossValidation],
}

/// K-fold cross-validation of the model `m` on `data`: per fold, identify on the other folds
/// as `identify` does ([`fit_and_readmit`]: the parameters left out at the nominal robot
/// re-checked at the fold's identified robot) and take the position errors of the fold's
/// points ([`validate_file`]); with a kernel, a kernel residual fitted on the fold's
/// calibration rows alone is added to the prediction ([`KernelResidual`]). A
/// cross-validation of `s.done` with the same [`CvKey`] is taken instead of running it.
pub fn cross_validate(
    m: &CvModel,
    data: &Measurements,
    k: usize,
    s: &CvSetup,
) -> Result<CrossValidation> {
    let n = data.len();
    if k < 2 || k > n {
        return Err(Error::option(
            crate::error::Opt::Cv,
            format!("needs 2 ≤ K ≤ the number of points ({n}), got {k}"),
        ));
    }
    let key = CvKey::of(m, data, k, s);
    if let Some(done) = s.done.iter().find(|d| key.is_some() && d.key == key) {
        return Ok(done.clone());
    }
    let (robot, params) = (m.robot, m.params);
    let fold = folds(n, k, s.fold_seed);
    let mut fold_rms = Vec::with_capacity(k);
    let mut sum_sq = 0.0;
    for f in 0..k {
        let (test, train): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| fold[i] == f);
        let (tr, te) = (subset(data, &train), subset(data, &test));
        let on = (robot, &tr, s.registration, s.method.k);
        let mut fit = |p: &[Param], start: &[Real]| {
            let mut rng = stream(s.seed, "identify");
            let started;
            let method = if start.is_empty() {
                s.method
            } else {
                started = MethodSpec {
                    start: start.to_vec(),
                    ..s.method.clone()
                };
                &started
            };
            calibrate(
                robot,
                p,
                &tr,
                s.registration,
                &Frame::identity(),
                method,
                &mut rng,
            )
        };
        let kept = fit_and_readmit(on, params.to_vec(), m.candidates, &mut fit, &|_, _| Ok(()))?;
        let c = kept.calibrated;
        // A fold whose rows do not determine the model scores a robot the data never fixed,
        // whose figure could still steer a model choice: refused, as `identify` refuses it.
        if super::verdict::undetermined(&c) {
            let rows = tr.len() * tr.measure().rows();
            let ended: &str = c.identified.termination.into();
            return Err(Error::option(
                crate::error::Opt::Cv,
                format!(
                    "fold {} of {k}: the model `{}` identified on the other folds' {} points \
                     ({rows} readings for {} parameters) ended {ended}, its parameters not \
                     determined; take fewer folds, or measure more poses",
                    f + 1,
                    m.name,
                    tr.len(),
                    kept.params.len()
                ),
            ));
        }
        let after = if m.kernel {
            let k = KernelResidual::fit(robot, &c, &tr)?;
            super::ErrorStats::of(&position_errors(&c, Some(&k), &te)?).rms
        } else {
            validate_file(robot, &c, &te)?.after_mm.rms
        };
        sum_sq += after * after * te.len() as Real;
        fold_rms.push(after);
    }
    let mean = fold_rms.iter().sum::<Real>() / k as Real;
    let sd = (fold_rms
        .iter()
        .map(|r| (r - mean) * (r - mean))
        .sum::<Real>()
        / (k - 1) as Real)
        .sqrt();
    Ok(CrossValidation {
        model: m.name.clone(),
        k,
        rms: (sum_sq / n as Real).sqrt(),
        fold_rms,
        mean,
        sd,
        parameters: params.len(),
        key,
    })
}

/// Each model's cross-validation on the same folds, and the index of the best (lowest CV
/// RMS; the first of equals, so list the simpler model first).
pub fn choose_model(
    nominal: &Robot,
    models: &[Model],
    data: &Measurements,
    k: usize,
    s: &CvSetup,
) -> Result<(Vec<CrossValidation>, usize)> {
    let cvs = models
        .iter()
        .map(|m| {
            let (robot, params, candidates) = m.for_cv(nominal, data, s.registration, s.fixed)?;
            let model = CvModel {
                robot: &robot,
                params: &params,
                candidates: &candidates,
                kernel: m.gp,
                name: m.name(),
            };
            cross_validate(&model, data, k, s)
        })
        .collect::<Result<Vec<_>>>()?;
    let best = lowest(&cvs);
    Ok((cvs, best))
}

/// The index of the lowest CV RMS of `cvs` (the first of equals; 0 when empty).
pub fn lowest(cvs: &[CrossValidation]) -> usize {
    lowest_of(cvs.iter().map(|c| c.rms))
}

/// The index of the lowest of `values` by [`Real::total_cmp`] (the first of equals; 0 when
/// empty): the rule of every choice among candidates here, and of its check
/// ([`RepeatedChoice::inconsistency`]).
pub fn lowest_of(values: impl Iterator<Item = Real>) -> usize {
    values
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0, |(i, _)| i)
}

/// The choice among candidate models by repeated K-fold cross-validation: the same
/// candidates on the folds of several fold seeds, the best the lowest mean CV RMS over the
/// seeds, and how stable that choice is (at how many seeds each candidate wins alone).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RepeatedChoice {
    /// Folds per seed.
    pub folds: usize,
    /// The fold seeds (`--cv-seed` of each repetition).
    pub fold_seeds: Vec<u64>,
    /// Per candidate, in the order given.
    pub models: Vec<RepeatedCv>,
    /// The index of the chosen candidate: the lowest mean CV RMS (the first of equals).
    pub best: usize,
    /// The share of the seeds at which the chosen candidate also has the lowest CV RMS.
    #[serde(deserialize_with = "crate::numeric::nan::real")]
    pub stability: Real,
    /// The chosen candidate's whole cross-validation at each fold seed, with its key (not
    /// written: `models` holds its RMS), for the identification of the chosen model to take
    /// when it runs one of the same setup ([`CvSetup::done`]).
    #[serde(skip)]
    pub chosen_cvs: Vec<CrossValidation>,
}

impl RepeatedChoice {
    /// What a choice written by hand gets wrong, as (key under `cv_choice`, why): a
    /// candidate's `rms` not one per fold seed, its `mean` not theirs, its `wins` not the
    /// seeds at which its RMS is the lowest (the first of equals), `best` not the lowest mean
    /// (the first of equals), `stability` not the share of the seeds `best` wins; `None`
    /// when it is what [`choose_model_repeated`] writes.
    pub fn inconsistency(&self) -> Option<(String, String)> {
        let n = self.fold_seeds.len();
        let mut wins = vec![0; self.models.len()];
        for (i, m) in self.models.iter().enumerate() {
            if m.rms.len() != n {
                let why = format!("holds {} values for {n} fold seeds", m.rms.len());
                return Some((format!("models[{i}].rms"), why));
            }
            let mean = m.rms.iter().sum::<Real>() / n as Real;
            if mean.to_bits() != m.mean.to_bits() && !(mean.is_nan() && m.mean.is_nan()) {
                return Some((
                    format!("models[{i}].mean"),
                    format!("is {}, but its rms give {mean}", m.mean),
                ));
            }
        }
        for s in (0..n).filter(|_| !self.models.is_empty()) {
            wins[lowest_of(self.models.iter().map(|m| m.rms[s]))] += 1;
        }
        if let Some(i) = (0..wins.len()).find(|&i| wins[i] != self.models[i].wins) {
            let why = format!(
                "is {}, but its rms are the lowest at {} seeds",
                self.models[i].wins, wins[i]
            );
            return Some((format!("models[{i}].wins"), why));
        }
        let best = lowest_of(self.models.iter().map(|m| m.mean));
        if best != self.best {
            let why = format!("is {}, but candidate {best} has the lowest mean", self.best);
            return Some(("best".into(), why));
        }
        let stability = wins.get(best).map_or(Real::NAN, |&w| w as Real / n as Real);
        (stability.to_bits() != self.stability.to_bits()).then(|| {
            let why = format!(
                "is {}, but the chosen candidate wins {stability} of the seeds",
                self.stability
            );
            ("stability".into(), why)
        })
    }
}

/// One candidate's cross-validation at every fold seed of a [`RepeatedChoice`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RepeatedCv {
    /// The model's name ([`Model::name`]).
    pub model: String,
    /// The number of parameters identified.
    pub parameters: usize,
    /// Its CV RMS (mm) at each fold seed.
    #[serde(deserialize_with = "crate::numeric::nan::read")]
    pub rms: Vec<Real>,
    /// Their mean (mm).
    #[serde(deserialize_with = "crate::numeric::nan::real")]
    pub mean: Real,
    /// At how many seeds it has the lowest CV RMS of the candidates.
    pub wins: usize,
}

/// [`choose_model`] at each of `fold_seeds` (the setup's own fold seed ignored), and the
/// candidate with the lowest mean CV RMS over them. Fails on an empty list of seeds.
pub fn choose_model_repeated(
    nominal: &Robot,
    models: &[Model],
    data: &Measurements,
    k: usize,
    fold_seeds: &[u64],
    s: &CvSetup,
) -> Result<RepeatedChoice> {
    if fold_seeds.is_empty() || models.is_empty() {
        return Err(Error::setting(
            "fold_seeds",
            "a repeated cross-validation needs at least one fold seed and one model",
        ));
    }
    let mut out: Vec<RepeatedCv> = Vec::with_capacity(models.len());
    let mut each: Vec<Vec<CrossValidation>> = Vec::with_capacity(fold_seeds.len());
    for &fold_seed in fold_seeds {
        let setup = CvSetup {
            fold_seed,
            fixed: s.fixed,
            method: s.method,
            registration: s.registration,
            seed: s.seed,
            done: s.done,
        };
        let (cvs, best) = choose_model(nominal, models, data, k, &setup)?;
        each.push(cvs.clone());
        for (i, cv) in cvs.into_iter().enumerate() {
            if out.len() <= i {
                out.push(RepeatedCv {
                    model: cv.model.clone(),
                    parameters: cv.parameters,
                    rms: Vec::new(),
                    mean: 0.0,
                    wins: 0,
                });
            }
            out[i].rms.push(cv.rms);
        }
        out[best].wins += 1;
    }
    for m in &mut out {
        m.mean = m.rms.iter().sum::<Real>() / m.rms.len() as Real;
    }
    let best = lowest_of(out.iter().map(|m| m.mean));
    Ok(RepeatedChoice {
        folds: k,
        fold_seeds: fold_seeds.to_vec(),
        stability: out[best].wins as Real / fold_seeds.len() as Real,
        models: out,
        best,
        chosen_cvs: each.into_iter().map(|mut c| c.swap_remove(best)).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holdout_and_folds_split_every_row_once() {
        let h: Holdout = "3/10".parse().unwrap();
        let (cal, val) = h.split(25);
        assert_eq!(val, vec![7, 8, 9, 17, 18, 19]);
        assert_eq!(cal.len() + val.len(), 25);
        assert!("0/10".parse::<Holdout>().is_err());
        assert!("10/10".parse::<Holdout>().is_err());
        assert!("3-10".parse::<Holdout>().is_err());
        let f = folds(23, 5, 1);
        assert_eq!(f, folds(23, 5, 1), "seeded");
        assert_ne!(f, folds(23, 5, 2));
        for k in 0..5 {
            let size = f.iter().filter(|&&x| x == k).count();
            assert!(size == 4 || size == 5, "fold {k}: {size}");
        }
    }

    #[test]
    fn models_parse_and_refuse_unknown_terms() {
        assert_eq!("kinematic".parse::<Model>().unwrap(), Model::KINEMATIC);
        let m: Model = "beta+compliance".parse().unwrap();
        assert!(m.beta && m.compliance);
        assert_eq!(m.name(), "beta+compliance");
        assert!("harmonic".parse::<Model>().is_err());
        let m: Model = "gravity+h12q1+harmonics+h3q2".parse().unwrap();
        assert!(m.gravity && m.harmonics == 1 && !m.is_kinematic());
        assert_eq!(m.name(), "gravity+harmonics+h12q1+h3q2");
        let m: Model = "gp+harmonics".parse().unwrap();
        assert!(m.gp && !m.is_kinematic());
        assert_eq!(m.name(), "harmonics+gp");
        assert_eq!(m.name().parse::<Model>().unwrap(), m);
        for bad in ["h0q1", "h17q1", "h12q0", "h12q17", "h12", "hq1", "h012q1"] {
            assert!(bad.parse::<Model>().is_err(), "{bad}");
        }
        // A term given twice is refused, not merged into another model's name.
        for (twice, term) in [
            ("beta+beta", "beta"),
            ("kinematic+kinematic", "kinematic"),
            ("h3q2+gp+ h3q2", "h3q2"),
        ] {
            let e = twice.parse::<Model>().unwrap_err();
            assert_eq!(e, format!("`{term}` is given twice in `{twice}`"));
        }
        // An order that `harmonics` or `harmonics2` gives already is merged into it, as
        // `harmonics` is into `harmonics2`; a higher one is kept.
        for (given, name) in [
            ("harmonics+h1q2", "harmonics"),
            ("harmonics2+h2q2+h1q5", "harmonics2"),
            ("harmonics+h2q2", "harmonics+h2q2"),
            ("harmonics2+harmonics", "harmonics2"),
        ] {
            let m: Model = given.parse().unwrap();
            assert_eq!(m.name(), name, "{given}");
            assert_eq!(name.parse::<Model>().unwrap(), m);
        }
    }

    /// irb2600 and `n` noise-free points (uniform poses of stream `seed`) of it with an
    /// error in a2 and θ3, measured in a frame shifted by `shift`.
    fn exact_data(seed: u64, n: usize, shift: crate::numeric::Vec3) -> (Robot, Measurements) {
        let nominal = crate::robot::builtin::load("irb2600").unwrap();
        let truth = nominal.with_errors(&[(Param::A(1), 0.4), (Param::Theta(2), 1e-3)]);
        let mut g = stream(seed, "cv-test");
        let qs = crate::robot::sampling::uniform_joint_poses(&nominal, n, &mut g);
        let data = Measurements {
            points: qs.iter().map(|q| truth.fk(q).pos + shift).collect(),
            qs,
            ..Default::default()
        };
        (nominal, data)
    }

    /// Noise-free data of a robot with errors: every fold's held-out points are predicted
    /// exactly, so the CV RMS is ~0; a β model on a dh robot keeps its kinematics.
    #[test]
    fn cross_validation_on_exact_data_is_exact() {
        let (nominal, data) = exact_data(3, 60, crate::numeric::Vec3::zeros());
        let method = crate::identify::method_by_name("ls").unwrap();
        let s = CvSetup {
            method: &method,
            registration: Registration::Identify,
            seed: 0,
            fold_seed: 1,
            fixed: &[],
            done: &[],
        };
        let (cvs, best) = choose_model(&nominal, &[Model::KINEMATIC], &data, 4, &s).unwrap();
        let cv = &cvs[best];
        assert!(cv.rms < 1e-8, "{cv:?}");
        assert_eq!(cv.fold_rms.len(), 4);
        let (robot, _) = Model {
            beta: true,
            ..Model::KINEMATIC
        }
        .robot_and_params(&nominal, &data, Registration::Identify, &[])
        .unwrap();
        let q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
        assert!((robot.fk(&q).pos - nominal.fk(&q).pos).norm() < 1e-9);
        assert!(choose_model(&nominal, &[Model::KINEMATIC], &data, 1, &s).is_err());
    }

    /// A cross-validation already run stands for another only on the same setup: marked by
    /// an RMS no computation gives, it is taken on an equal setup and not when the fold seed,
    /// the method's seed, a method setting, the fixed parameters, the re-check's candidates or
    /// one row differ.
    #[test]
    fn a_done_cross_validation_is_taken_only_on_the_same_setup() {
        let (nominal, data) = exact_data(4, 40, crate::numeric::Vec3::new(0.01, 0.0, 0.0));
        let lm = crate::identify::method_by_name("lm").unwrap();
        let mut table = toml::Table::new();
        table.insert("name".into(), "lm".into());
        table.insert("max_iter".into(), 7.into());
        let lm7 = crate::identify::MethodSpec::from_table(&table).unwrap();
        let setup = |method, seed, fold_seed, fixed| CvSetup {
            method,
            registration: Registration::Identify,
            seed,
            fold_seed,
            fixed,
            done: &[],
        };
        let run = |data: &Measurements, s: &CvSetup, recheck: bool, done: &[CrossValidation]| {
            let (robot, params, candidates) = Model::KINEMATIC
                .for_cv(&nominal, data, s.registration, s.fixed)
                .unwrap();
            assert!(!candidates.is_empty());
            let m = CvModel {
                robot: &robot,
                params: &params,
                candidates: if recheck { &candidates } else { &[] },
                kernel: false,
                name: "kinematic".into(),
            };
            let s = CvSetup {
                done,
                fixed: s.fixed,
                ..*s
            };
            cross_validate(&m, data, 4, &s).unwrap()
        };
        let base = setup(&lm, 0, 0, &[]);
        let mut marked = run(&data, &base, true, &[]);
        assert!(marked.key.is_some());
        marked.rms = -1.0;
        let done = [marked];
        assert_eq!(run(&data, &base, true, &done).rms, -1.0, "the same setup");
        let mut moved = data.clone();
        moved.points[17].x += 1e-9;
        let fixed = [Param::D(3)];
        let others = [
            (setup(&lm, 0, 1, &[]), &data, true, "fold seed"),
            (setup(&lm, 1, 0, &[]), &data, true, "seed"),
            (setup(&lm7, 0, 0, &[]), &data, true, "max_iter"),
            (setup(&lm, 0, 0, &fixed), &data, true, "fixed"),
            (setup(&lm, 0, 0, &[]), &moved, true, "one row"),
            (setup(&lm, 0, 0, &[]), &data, false, "no re-check"),
        ];
        for (s, d, recheck, what) in others {
            let cv = run(d, &s, recheck, &done);
            assert!(cv.rms > 0.0, "{what}");
            assert_eq!(cv, run(d, &s, recheck, &[]), "{what}");
        }
    }
}
