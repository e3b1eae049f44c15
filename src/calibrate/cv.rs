//! Cross-validation and model choice for `calbench identify` (docs/formats.md `identify`,
//! "Cross-validation and model choice"): seeded K-fold splits of a measurement file, the
//! validation error of each held-out fold after calibrating on the others, a held-out split
//! rule ([`Holdout`]), and candidate models ([`Model`]) compared on the same folds.

use std::str::FromStr;

use super::kernel::{position_errors, KernelResidual};
use super::validation::validate_file;
use super::{calibrate, Registration};
use crate::error::{Error, Result};
use crate::identify::MethodSpec;
use crate::measurement::Measurements;
use crate::numeric::rng::stream;
use crate::numeric::{Frame, Real};
use crate::robot::compliance::CompliancePick;
use crate::robot::identifiability::identifiable_extension;
use crate::robot::{
    param_sets, Convention, JointType, Param, Robot, MAX_HARMONIC_ORDER, MAX_JOINTS,
};

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
        let (last, every) = (
            a.trim().parse::<usize>().map_err(|_| bad())?,
            b.trim().parse::<usize>().map_err(|_| bad())?,
        );
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
}

/// What one cross-validation runs: the robot and its parameters, the method, the
/// registration, and the seeds.
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
}

/// K-fold cross-validation of the errors of `params` of `robot` (the model `name`) on `data`:
/// per fold, calibrate on the other folds and take the position errors of the fold's points
/// ([`validate_file`]); with `kernel`, a kernel residual fitted on the fold's calibration rows
/// alone is added to the prediction ([`KernelResidual`]).
pub fn cross_validate(
    (robot, params, name, kernel): (&Robot, &[Param], String, bool),
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
    let fold = folds(n, k, s.fold_seed);
    let mut fold_rms = Vec::with_capacity(k);
    let mut sum_sq = 0.0;
    for f in 0..k {
        let (test, train): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| fold[i] == f);
        let (tr, te) = (subset(data, &train), subset(data, &test));
        let c = calibrate(
            robot,
            params,
            &tr,
            s.registration,
            &Frame::identity(),
            s.method,
            &mut stream(s.seed, "identify"),
        )?;
        let after = if kernel {
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
        model: name,
        k,
        rms: (sum_sq / n as Real).sqrt(),
        fold_rms,
        mean,
        sd,
        parameters: params.len(),
    })
}

/// A candidate model of `identify --models`: the kinematic parameters, plus Hayati's β on
/// the joints where it is identifiable (parallel neighbouring axes) and/or the compliances of
/// the joints gravity loads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Model {
    /// β on the joints where it is identifiable (a `dh` robot is read as `dh_beta`, β = 0).
    pub beta: bool,
    /// The compliances of the gravity-loaded joints (needs the robot's link masses).
    pub compliance: bool,
    /// Joint-angle harmonics up to this order (0: none; 1: `sin q`, `cos q`; 2: also
    /// `sin 2q`, `cos 2q`) on every revolute joint, each term kept when it is identifiable
    /// beside the kinematic parameters over generic poses ([`Param::Harmonic`],
    /// [`identifiable_extension`]).
    pub harmonics: u8,
    /// The mass-free gravity basis ([`Param::Gravity`], [`crate::robot::gravity_basis`]):
    /// the joint deflections of unit weights at the elbow, the wrist centre and the tool
    /// point, with free coefficients (no masses needed).
    pub gravity: bool,
    /// Harmonics of chosen orders on chosen joints (`h12q1`: `sin 12q1`, `cos 12q1`): per
    /// joint (0-based), bit `n − 1` for order `n`.
    pub orders: [u16; MAX_JOINTS],
    /// A kernel residual on the joint angles, fitted on the calibration rows after the
    /// parametric terms ([`KernelResidual`]; `gp`).
    pub gp: bool,
}

impl Model {
    /// The plain kinematic model.
    pub const KINEMATIC: Model = Model {
        beta: false,
        compliance: false,
        harmonics: 0,
        gravity: false,
        orders: [0; MAX_JOINTS],
        gp: false,
    };

    /// Whether the model is kinematic only (β included): a task's closed division.
    pub fn is_kinematic(&self) -> bool {
        !self.compliance
            && self.harmonics == 0
            && !self.gravity
            && self.orders == [0; MAX_JOINTS]
            && !self.gp
    }

    /// `kinematic`, or its terms joined by `+` in the order `beta`, `compliance`, `gravity`,
    /// `harmonics`/`harmonics2`, then each `h{n}q{j}` by joint and order, then `gp`
    /// (`beta+compliance`, `gravity+harmonics+h12q1`, `harmonics+gp`).
    pub fn name(&self) -> String {
        let mut terms: Vec<String> = Vec::new();
        if self.beta {
            terms.push("beta".into());
        }
        if self.compliance {
            terms.push("compliance".into());
        }
        if self.gravity {
            terms.push("gravity".into());
        }
        match self.harmonics {
            0 => {}
            1 => terms.push("harmonics".into()),
            _ => terms.push("harmonics2".into()),
        }
        for (j, bits) in self.orders.iter().enumerate() {
            for n in 1..=MAX_HARMONIC_ORDER {
                if bits & (1 << (n - 1)) != 0 {
                    terms.push(format!("h{n}q{}", j + 1));
                }
            }
        }
        if self.gp {
            terms.push("gp".into());
        }
        if terms.is_empty() {
            "kinematic".into()
        } else {
            terms.join("+")
        }
    }

    /// The robot to identify (for β, a `dh` robot as `dh_beta` with β = 0: the same
    /// kinematics) and the parameters: those `identify` takes for measured data
    /// ([`param_sets::identified_params_tool_first`]), plus the gravity joints' compliances
    /// and the identifiable joint-angle harmonics and gravity-basis terms (harmonics first,
    /// then the gravity basis, then the chosen orders), less the `fixed` ones. Fails when a
    /// chosen order names a joint the robot does not have or one that is not revolute, or the
    /// gravity basis is asked of a robot of fewer than four joints.
    pub fn robot_and_params(
        &self,
        nominal: &Robot,
        data: &Measurements,
        registration: Registration,
        fixed: &[Param],
    ) -> Result<(Robot, Vec<Param>)> {
        let robot = self.robot(nominal);
        let with_base = registration == Registration::Identify;
        let mut params =
            param_sets::identified_params_tool_first(&robot, data.measure(), with_base);
        if self.compliance {
            params.extend(
                CompliancePick::Gravity
                    .params(&robot, "models")
                    .map_err(|e| e.of_option(crate::error::Opt::Models))?,
            );
        }
        let extra = self.terms(&robot)?;
        if !extra.is_empty() {
            params.extend(identifiable_extension(
                &robot,
                &params,
                &extra,
                data.measure(),
            ));
        }
        params.retain(|p| !fixed.contains(p));
        Ok((robot, params))
    }

    /// The robot whose parameters the model identifies: `nominal`, a `dh` robot read as
    /// `dh_beta` (β = 0, the same kinematics) for a model with `beta`.
    fn robot(&self, nominal: &Robot) -> Robot {
        let mut robot = nominal.clone();
        if self.beta && robot.convention == Convention::Dh {
            robot.convention = Convention::DhBeta;
        }
        robot
    }

    /// The parameters the model offers that [`Model::robot_and_params`] leaves out of
    /// `params` (its choice at the nominal robot): the kinematic parameters of the robot's
    /// model not chosen (the base's only with the `identify` registration) and the harmonic
    /// and gravity-basis terms not kept, in that order, less the `fixed` ones. Compliances
    /// are never left out. These are the candidates that identifiability re-checked at the
    /// identified robot may re-admit ([`super::recheck`]).
    pub fn left_out(
        &self,
        nominal: &Robot,
        registration: Registration,
        fixed: &[Param],
        params: &[Param],
    ) -> Result<Vec<Param>> {
        let robot = self.robot(nominal);
        let with_base = registration == Registration::Identify;
        let kinematic = robot
            .params()
            .into_iter()
            .filter(|p| with_base || !matches!(p, Param::Base(_)));
        Ok(kinematic
            .chain(self.terms(&robot)?)
            .filter(|p| !params.contains(p) && !fixed.contains(p) && !p.is_compliance())
            .collect())
    }

    /// The harmonic and gravity-basis terms the model offers on `robot`, before the choice
    /// of the identifiable ones: the harmonics of every revolute joint, the gravity basis,
    /// then the chosen orders. Fails when a chosen order names a joint the robot does not
    /// have or one that is not revolute, or the gravity basis is asked of a robot of fewer
    /// than four joints.
    fn terms(&self, robot: &Robot) -> Result<Vec<Param>> {
        // Every revolute joint's terms that the poses of a generic set can tell apart from
        // the kinematic parameters and from each other: joint 1's harmonics although θ1 is
        // left to base.rz (a constant offset is, sin q1 and cos q1 are not), not the last
        // joint's when the tool point lies on its axis.
        let mut extra: Vec<Param> = Vec::new();
        if self.harmonics > 0 {
            let terms = 2 * usize::from(self.harmonics.min(2));
            extra.extend(
                (0..robot.dof())
                    .filter(|&j| robot.joints[j].kind == JointType::Revolute)
                    .flat_map(|j| (0..terms).map(move |k| Param::Harmonic(j, k))),
            );
        }
        if self.gravity {
            let basis = crate::robot::gravity_basis::params(robot);
            if basis.is_empty() {
                return Err(Error::option(
                    crate::error::Opt::Models,
                    format!(
                        "`gravity`: robot \"{}\" has {} joints; the gravity basis needs an \
                         elbow and a wrist centre (at least four joints)",
                        robot.name,
                        robot.dof()
                    ),
                ));
            }
            extra.extend(basis);
        }
        for (j, bits) in self.orders.iter().enumerate() {
            for n in (1..=MAX_HARMONIC_ORDER).filter(|n| bits & (1 << (n - 1)) != 0) {
                if j >= robot.dof() || robot.joints[j].kind != JointType::Revolute {
                    return Err(Error::option(
                        crate::error::Opt::Models,
                        format!(
                            "`h{n}q{}`: robot \"{}\" has no revolute joint {}",
                            j + 1,
                            robot.name,
                            j + 1
                        ),
                    ));
                }
                for k in [2 * (n - 1), 2 * (n - 1) + 1] {
                    if !extra.contains(&Param::Harmonic(j, k)) {
                        extra.push(Param::Harmonic(j, k));
                    }
                }
            }
        }
        Ok(extra)
    }
}

impl FromStr for Model {
    type Err = String;

    /// `kinematic`, `beta`, `compliance`, `gravity` (the mass-free gravity basis),
    /// `harmonics` (first harmonic), `harmonics2` (first and second), `h{n}q{j}` (the
    /// harmonic of order n, 1 to 16, of joint j), `gp` (a kernel residual on the joint
    /// angles), or terms joined by `+` (`beta+compliance`, `gravity+harmonics+h12q1`,
    /// `harmonics+gp`).
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let mut m = Model::KINEMATIC;
        for term in s.split('+').map(str::trim) {
            match term {
                "kinematic" => {}
                "beta" => m.beta = true,
                "compliance" => m.compliance = true,
                "gravity" => m.gravity = true,
                "harmonics" => m.harmonics = m.harmonics.max(1),
                "harmonics2" => m.harmonics = 2,
                "gp" => m.gp = true,
                other => {
                    let Some((n, j)) = order_term(other) else {
                        return Err(format!(
                            "unknown model term `{other}`; known: kinematic, beta, compliance, \
                             gravity, harmonics, harmonics2, h{{n}}q{{j}} (order n of 1 to \
                             {MAX_HARMONIC_ORDER} on joint j, `h12q1`), gp (a kernel residual); \
                             joined by +)"
                        ));
                    };
                    m.orders[j - 1] |= 1 << (n - 1);
                }
            }
        }
        Ok(m)
    }
}

/// `h{n}q{j}`: the order n (1 to [`MAX_HARMONIC_ORDER`]) and the joint j (1 to
/// [`MAX_JOINTS`]).
fn order_term(term: &str) -> Option<(usize, usize)> {
    let (n, j) = term.strip_prefix('h')?.split_once('q')?;
    let plain =
        |s: &str| !s.is_empty() && !s.starts_with('0') && s.bytes().all(|b| b.is_ascii_digit());
    if !plain(n) || !plain(j) {
        return None;
    }
    let (n, j): (usize, usize) = (n.parse().ok()?, j.parse().ok()?);
    ((1..=MAX_HARMONIC_ORDER).contains(&n) && (1..=MAX_JOINTS).contains(&j)).then_some((n, j))
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
            let (robot, params) = m.robot_and_params(nominal, data, s.registration, s.fixed)?;
            cross_validate((&robot, &params, m.name(), m.gp), data, k, s)
        })
        .collect::<Result<Vec<_>>>()?;
    let best = lowest(&cvs);
    Ok((cvs, best))
}

/// The index of the lowest CV RMS of `cvs` (the first of equals; 0 when empty).
pub fn lowest(cvs: &[CrossValidation]) -> usize {
    (0..cvs.len())
        .min_by(|&a, &b| cvs[a].rms.total_cmp(&cvs[b].rms))
        .unwrap_or(0)
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
    /// The chosen candidate's whole cross-validation at each fold seed (not written: `models`
    /// holds its RMS), for the identification of the chosen model to reuse
    /// ([`RepeatedChoice::chosen_at`]).
    #[serde(skip)]
    pub chosen_cvs: Vec<CrossValidation>,
}

impl RepeatedChoice {
    /// The chosen candidate's cross-validation at `fold_seed` on `folds` folds, when this
    /// choice ran it.
    pub fn chosen_at(&self, folds: usize, fold_seed: u64) -> Option<&CrossValidation> {
        let i = self.fold_seeds.iter().position(|&s| s == fold_seed)?;
        (folds == self.folds)
            .then(|| self.chosen_cvs.get(i))
            .flatten()
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
    let best = (0..out.len())
        .min_by(|&a, &b| out[a].mean.total_cmp(&out[b].mean))
        .unwrap_or(0);
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
    }

    /// Noise-free data of a robot with errors: every fold's held-out points are predicted
    /// exactly, so the CV RMS is ~0; a β model on a dh robot keeps its kinematics.
    #[test]
    fn cross_validation_on_exact_data_is_exact() {
        let nominal = crate::robot::builtin::load("irb2600").unwrap();
        let truth = nominal.with_errors(&[(Param::A(1), 0.4), (Param::Theta(2), 1e-3)]);
        let mut g = stream(3, "cv-test");
        let qs = crate::robot::sampling::uniform_joint_poses(&nominal, 60, &mut g);
        let data = Measurements {
            points: qs.iter().map(|q| truth.fk(q).pos).collect(),
            qs,
            ..Default::default()
        };
        let method = crate::identify::method_by_name("ls").unwrap();
        let s = CvSetup {
            method: &method,
            registration: Registration::Identify,
            seed: 0,
            fold_seed: 1,
            fixed: &[],
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
}
