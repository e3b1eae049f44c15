//! The identification problem of any measurement kind ([`crate::measurement::kind`]): the
//! robot's parameter errors and the instrument's own unknowns (pivot, planes, spheres) from
//! what the instrument read. Every Jacobian method ([`super::Solver`]) solves it through
//! [`super::solve`], as it solves the tracker's [`super::RobotProblem`].
//!
//! The unknown vector is `[x, δc]`: the errors `x` of the robot's parameters (mm, rad), then
//! the corrections `δc` of the nuisance values from their first guess
//! ([`crate::measurement::kind::nuisance_guess`] over the nominal tool points). The rows come
//! from [`crate::measurement::kind::rows`] over the tool frames and their Jacobian rows
//! ([`crate::robot::jacobian::pose_rows_vars`], full-pose rows so that targets off the tool
//! point see the rotation).

use std::cell::RefCell;

use nalgebra::{DMatrix, DVector};

use super::solver::{LeastSquares, Size};
use crate::error::{Error, Opt, Result, Said};
use crate::measurement::kind::{nuisance_guess, rows, KindData};
use crate::measurement::Measure;
use crate::numeric::{Mat3, Real, Vec3};
use crate::robot::identifiability::Identifiability;
use crate::robot::jacobian::{pose_rows_vars, Columns};
use crate::robot::{Chain, ChainVars, Param, Robot};

/// Buffers of one evaluation: parameter values and chain, tool points, rotations, the
/// stacked full-pose rows, the nuisance values.
#[derive(Debug)]
struct Work {
    values: Vec<Real>,
    chain: Chain,
    p: Vec<Vec3>,
    rot: Vec<Mat3>,
    tool: DMatrix<Real>,
    c: Vec<Real>,
}

/// A [`LeastSquares`] problem over a robot's parameter errors and an instrument's unknowns.
#[derive(Debug)]
pub struct KindProblem<'a> {
    nominal: &'a Robot,
    params: Vec<Param>,
    index: Vec<usize>,
    cols: Columns,
    vars: Vec<ChainVars>,
    data: &'a KindData,
    c0: Vec<Real>,
    prior: Option<&'a [Real]>,
    work: RefCell<Work>,
}

impl<'a> KindProblem<'a> {
    /// The problem of identifying `params` of `nominal` from `data` read at joint values
    /// `qs`. Fails when `params` is empty, repeats a parameter or names one the model lacks
    /// (compliances are not modelled for these kinds), when the data do not match the poses,
    /// or a plane or sphere has too few points for its first guess.
    pub fn new(
        nominal: &'a Robot,
        params: &[Param],
        qs: &[Vec<Real>],
        data: &'a KindData,
    ) -> Result<Self> {
        if params.is_empty() {
            return Err(Error::setting("params", "no parameters to identify"));
        }
        let known = nominal.params();
        for (i, p) in params.iter().enumerate() {
            if !known.contains(p) || params[..i].contains(p) {
                return Err(Error::setting(
                    "params",
                    format!(
                        "`{p}` is not a parameter of robot `{}` or is listed twice",
                        nominal.name
                    ),
                ));
            }
        }
        let dof = nominal.dof();
        if let Some(i) = qs
            .iter()
            .position(|q| q.len() != dof || q.iter().any(|v| !v.is_finite()))
        {
            return Err(Error::joint_count(
                "data",
                format_args!("pose {i}"),
                qs[i].len(),
                dof,
            ));
        }
        data.check(qs.len())?;
        if data.instrument.observations(qs.len()) == 0 {
            return Err(Error::setting("data", "no observations"));
        }
        let chain = nominal.chain();
        let p: Vec<Vec3> = qs.iter().map(|q| chain.fk(q).pos).collect();
        let c0 = nuisance_guess(&data.instrument, &data.group, &p, &data.values)?;
        Self::with_guess(nominal, params, qs, data, c0)
    }

    /// [`KindProblem::new`] with the first guess `c0` of the nuisance values given (the
    /// instrument's layout, e.g. for the rows of a single pose).
    pub fn with_guess(
        nominal: &'a Robot,
        params: &[Param],
        qs: &[Vec<Real>],
        data: &'a KindData,
        c0: Vec<Real>,
    ) -> Result<Self> {
        if c0.len() != data.instrument.nuisance() || c0.iter().any(|v| !v.is_finite()) {
            return Err(Error::setting(
                "nuisance",
                format!("{} finite values needed", data.instrument.nuisance()),
            ));
        }
        let chain = nominal.chain();
        let p: Vec<Vec3> = qs.iter().map(|q| chain.fk(q).pos).collect();
        let dof = nominal.dof();
        let m = qs.len();
        let cols = Columns::new(params, dof);
        Ok(KindProblem {
            nominal,
            params: params.to_vec(),
            index: params.iter().map(|p| p.index(dof)).collect(),
            vars: chain.variables_of(qs),
            work: RefCell::new(Work {
                values: nominal.values.clone(),
                chain,
                p,
                rot: vec![Mat3::identity(); m],
                tool: DMatrix::zeros(6 * m, params.len()),
                c: c0.clone(),
            }),
            cols,
            data,
            c0,
            prior: None,
        })
    }

    /// Gives observation `i` the prior weight `w[i]` (`1/σ_i²`, normalised or not); `None`:
    /// every observation weighs 1. Fails unless there is one finite, positive weight per
    /// observation.
    pub fn with_prior_weights(mut self, w: Option<&'a [Real]>) -> Result<Self> {
        if let Some(w) = w {
            crate::measurement::check_weights(w, self.size().points)?;
        }
        self.prior = w;
        Ok(self)
    }

    /// The nuisance values at the unknowns `x` (first guess plus correction).
    pub fn nuisance_at(&self, x: &DVector<Real>) -> Vec<Real> {
        let t = self.params.len();
        self.c0
            .iter()
            .enumerate()
            .map(|(k, c)| c + x[t + k])
            .collect()
    }

    /// The compensated robot: the nominal robot with the errors `x[..t]` added.
    pub fn robot_with(&self, x: &DVector<Real>) -> Robot {
        self.nominal
            .with_added(&self.index, &x.as_slice()[..self.params.len()])
    }
}

impl LeastSquares for KindProblem<'_> {
    fn size(&self) -> Size {
        let inst = &self.data.instrument;
        Size::new(
            self.params.len() + inst.nuisance(),
            inst.observations(self.vars.len()),
            inst.rows_per_observation(),
        )
    }

    fn prior(&self) -> Option<&[Real]> {
        self.prior
    }

    /// Forward kinematics and the full-pose Jacobian rows at `nominal + x` (one chain walk
    /// per pose), then the kind's rows. Allocation-free.
    fn evaluate(&self, x: &DVector<Real>, r: &mut DVector<Real>, j: &mut DMatrix<Real>) {
        let t = self.params.len();
        let mut guard = self.work.borrow_mut();
        let w = &mut *guard;
        self.nominal.set_chain_with_added(
            &self.index,
            &x.as_slice()[..t],
            &mut w.values,
            &mut w.chain,
        );
        for (i, v) in self.vars.iter().enumerate() {
            let f = pose_rows_vars(&w.chain, &self.cols, v, Measure::Pose, &mut w.tool, 6 * i);
            w.p[i] = f.pos;
            w.rot[i] = f.rot;
        }
        for (k, c) in w.c.iter_mut().enumerate() {
            *c = self.c0[k] + x[t + k];
        }
        rows(self.data, &w.p, &w.rot, &w.tool, &w.c, r, j);
    }
}

/// What the readings of an instrument determine ([`identifiability`]).
#[derive(Clone, Debug)]
pub struct KindAnalysis {
    /// The robot's parameters, the instrument's own unknowns projected out.
    pub robot: Identifiability,
    /// The instrument's own unknowns ([`crate::measurement::kind::Instrument::nuisance_names`]).
    pub unknowns: Vec<String>,
    /// Those of them the readings leave free whatever the robot (a plane's points on one
    /// line or at one point, a sphere's on one great circle): a solve then ends singular.
    pub undetermined: Vec<String>,
}

/// Identifiability of `params` of `robot` for the instrument of `data` read at poses `qs`
/// ([`crate::robot::identifiability::analyse_jacobian`]): the kind's Jacobian at the nominal
/// robot with the instrument's own unknowns projected out (a parameter counts as identifiable
/// when the data separate it from the pivot, planes or spheres as well as from the other
/// parameters), and which of those unknowns the readings leave free by the same rule
/// ([`crate::robot::identifiability::determined_columns`] of their own columns).
pub fn identifiability(
    robot: &Robot,
    params: &[Param],
    qs: &[Vec<Real>],
    data: &KindData,
) -> Result<KindAnalysis> {
    let kp = KindProblem::new(robot, params, qs, data)?;
    let size = kp.size();
    let mut r = DVector::zeros(size.rows());
    let mut j = DMatrix::zeros(size.rows(), size.params);
    kp.evaluate(&DVector::zeros(size.params), &mut r, &mut j);
    if !j.iter().all(|v| v.is_finite()) {
        return Err(Error::Compute(format!(
            "the {} readings' Jacobian at the nominal robot is not finite: a reading has no \
             direction there (a tool point on the instrument's pivot, a robot of zero length)",
            data.instrument.kind().as_str()
        )));
    }
    let t = params.len();
    let unknowns = data.instrument.nuisance_names();
    let mut jr = j.columns(0, t).into_owned();
    let mut undetermined = Vec::new();
    if size.params > t {
        // Remove the part of each robot column that the nuisance columns explain.
        let n = j.columns(t, size.params - t).into_owned();
        let kept = crate::robot::identifiability::determined_columns(n.clone());
        undetermined = (0..n.ncols())
            .filter(|c| kept.binary_search(c).is_err())
            .map(|c| unknowns[c].clone())
            .collect();
        let svd = crate::numeric::linalg::svd(n, true, false)
            .ok_or_else(|| Error::Compute("the SVD of the instrument's columns".into()))?;
        let u = svd.u.as_ref().ok_or_else(|| Error::Compute("SVD".into()))?;
        let big = svd.singular_values.max();
        let keep: Vec<usize> = (0..svd.singular_values.len())
            .filter(|&k| svd.singular_values[k] > 1e-10 * big)
            .collect();
        let q = u.select_columns(&keep);
        jr -= &q * (q.transpose() * &jr);
    }
    Ok(KindAnalysis {
        robot: crate::robot::identifiability::analyse_jacobian(params, jr),
        unknowns,
        undetermined,
    })
}

/// How many of `params` of `robot` the readings of the instrument laid out as `lay` determine
/// at poses spread over the workspace: [`identifiability`] at the fixed random poses of
/// [`crate::robot::identifiability::identifiable_generic`], dealt to the planes, spheres or
/// sockets in turn and moved onto them ([`crate::sim::instrument::touching`]; those that do
/// not reach theirs are dropped). What a file of that instrument determines when it holds
/// enough poses.
pub fn generic_rank(
    robot: &Robot,
    params: &[Param],
    lay: &crate::sim::instrument::Layout,
) -> Result<usize> {
    use crate::robot::identifiability::GENERIC_POSES;
    use crate::sim::instrument::{groups_of, touching};
    let mut g = crate::numeric::rng::stream(0x1D, "identifiability");
    let pool = crate::robot::sampling::uniform_joint_poses(robot, GENERIC_POSES, &mut g);
    let (qs, group) = touching(robot, lay, &pool, &groups_of(&lay.instrument, pool.len()));
    let inst = &lay.instrument;
    let data = KindData {
        instrument: inst.clone(),
        group,
        values: vec![0.0; inst.observations(qs.len()) * inst.rows_per_observation()],
    };
    Ok(identifiability(robot, params, &qs, &data)?.robot.rank)
}

/// Identifiability of every parameter of `robot` for the instrument `s` read at the poses
/// `qs`, taken as they are (they touch it, or its fitted planes or spheres are the
/// instrument's, assigned in turn): [`identifiability`] of every parameter. `calbench
/// identifiability --measure KIND --poses-file` and Python's `identifiability` call it.
pub fn identifiability_at(
    robot: &Robot,
    qs: &[Vec<Real>],
    s: &crate::sim::instrument::InstrumentSettings,
) -> Result<KindAnalysis> {
    let instrument = s
        .instrument()
        .map_err(crate::sim::instrument::counts_as_options)?;
    let group = crate::sim::instrument::groups_of(&instrument, qs.len());
    identifiability_of(robot, qs, instrument, group)
}

/// [`identifiability_at`] for an instrument laid out already, each pose's plane or sphere
/// given (`group`).
pub fn identifiability_of(
    robot: &Robot,
    qs: &[Vec<Real>],
    instrument: crate::measurement::kind::Instrument,
    group: Vec<usize>,
) -> Result<KindAnalysis> {
    // Each plane or sphere needs the points of its first guess.
    if let Some((n, need)) = instrument.surfaces() {
        let mut held = vec![0; n];
        group.iter().filter(|&&g| g < n).for_each(|&g| held[g] += 1);
        if let Some((g, c)) = held.iter().enumerate().find(|(_, &c)| c < need) {
            let (kind, opt) = match instrument.kind() {
                crate::measurement::kind::Kind::Plane => ("plane", Opt::Planes),
                _ => ("sphere", Opt::Spheres),
            };
            let why = Said::from(format!(
                "{kind} {} of {n} holds {c} of the {} poses, and each needs at least {need}: \
                 give more poses, or fewer {kind}s (",
                g + 1,
                qs.len()
            ))
            .name(opt)
            .text(")");
            return Err(Error::option(opt, why));
        }
    }
    let observations = instrument.observations(qs.len());
    if observations == 0 {
        let (n, kind) = (qs.len(), instrument.kind().as_str());
        let gives = if n == 1 { "pose gives" } else { "poses give" };
        let msg = format!("{n} {gives} no {kind} reading: give more poses");
        return Err(Error::option(Opt::Q, msg));
    }
    // The Jacobian does not depend on the readings: zeros of the right length.
    let values = vec![0.0; observations * instrument.rows_per_observation()];
    let data = KindData {
        instrument,
        group,
        values,
    };
    // Too few poses for the instrument's own unknowns (a pivot's five) are the poses' fault.
    identifiability(robot, &robot.params(), qs, &data)
        .map_err(|e| e.setting_as("measurements", Opt::Q))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::{solve, LmOptions, LsOptions, RidgeOptions, RobustOptions, Solver};
    use crate::measurement::kind::Kind;
    use crate::robot::builtin::irb2600;
    use crate::sim::instrument::{groups_of, layout, noise_free, touching, InstrumentSettings};

    /// A kind, its poses, their planes or spheres, and its layout.
    type Setup = (
        Kind,
        Vec<Vec<Real>>,
        Vec<usize>,
        crate::sim::instrument::Layout,
    );

    /// Every kind but `pose` (the tracker's own path): a short pool of poses on the
    /// instrument (touching the planes or spheres), its layout and its joint and tool
    /// parameters.
    fn setups() -> Vec<Setup> {
        let robot = irb2600();
        let mut rng = crate::numeric::rng::stream(5, "kinds");
        let pool = crate::robot::sampling::uniform_joint_poses(&robot, 90, &mut rng);
        let kinds = [
            Kind::Position,
            Kind::Distance,
            Kind::Plane,
            Kind::Sphere,
            Kind::MultiTarget,
            Kind::Socket,
        ];
        let mut out = Vec::new();
        for kind in kinds {
            let mut pivots = vec![true];
            if kind == Kind::Distance {
                pivots.push(false);
            }
            for pivot in pivots {
                let s = InstrumentSettings {
                    kind,
                    pivot,
                    ..InstrumentSettings::default()
                };
                let lay = layout(&s, &robot, &pool).unwrap();
                let (qs, g) = touching(&robot, &lay, &pool, &groups_of(&lay.instrument, 90));
                assert!(qs.len() > 30, "{kind:?}: {} of 90 poses touch", qs.len());
                out.push((kind, qs, g, lay));
            }
        }
        out
    }

    fn candidates(robot: &Robot) -> Vec<Param> {
        robot.params()
    }

    #[test]
    fn jacobian_rows_agree_with_finite_differences() {
        let robot = irb2600();
        let params = candidates(&robot);
        for (kind, qs, g, lay) in setups() {
            let data = noise_free(&lay.instrument, &robot, &qs, &g, &lay.nuisance);
            let kp = KindProblem::new(&robot, &params, &qs, &data).unwrap();
            let size = kp.size();
            // The robot's columns are exact at the nominal values (Li 2018 eqs. 6–12); the
            // nuisance values away from their first guess.
            let t = params.len();
            let x = DVector::from_fn(size.params, |k, _| {
                if k < t {
                    0.0
                } else {
                    1e-2 * ((k % 7) as Real - 3.0)
                }
            });
            let mut r = DVector::zeros(size.rows());
            let mut j = DMatrix::zeros(size.rows(), size.params);
            kp.evaluate(&x, &mut r, &mut j);
            let (mut rp, mut rm) = (r.clone(), r.clone());
            let mut scratch = j.clone();
            let h = 1e-5;
            let largest = j.column_iter().map(|c| c.norm()).fold(0.0, Real::max);
            for c in 0..size.params {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[c] += h;
                xm[c] -= h;
                kp.evaluate(&xp, &mut rp, &mut scratch);
                kp.evaluate(&xm, &mut rm, &mut scratch);
                // r = measured − model, so ∂model/∂x = −∂r/∂x.
                let fd = -(&rp - &rm) / (2.0 * h);
                let scale = fd.norm().max(j.column(c).norm()).max(1e-6 * largest);
                let diff = (&fd - j.column(c)).norm();
                let err = diff / scale;
                // A column that is zero (θ1 for lengths: rotations about the base axis change
                // none) is compared with the rounding of the differences instead.
                let err = if diff < 1e-10 * largest { 0.0 } else { err };
                let name = params.get(c).map_or("nuisance".into(), |p| p.to_string());
                assert!(
                    err < 1e-6,
                    "{kind:?} column {c} ({name}): relative error {err:e}"
                );
            }
        }
    }

    #[test]
    fn noise_free_data_recover_the_identifiable_parameters_by_every_jacobian_method() {
        let nominal = irb2600();
        let params = candidates(&nominal);
        let solvers: [(&str, Box<dyn Solver>); 4] = [
            ("ls", Box::new(LsOptions::default())),
            ("ridge", Box::new(RidgeOptions::default())),
            ("igg3", Box::new(RobustOptions::default())),
            (
                "lm",
                Box::new(LmOptions {
                    adaptive: true,
                    eps: 1e-12,
                    max_iter: 200,
                    ..LmOptions::default()
                }),
            ),
        ];
        for (kind, qs, g, lay) in setups() {
            let data0 = noise_free(&lay.instrument, &nominal, &qs, &g, &lay.nuisance);
            let a = identifiability(&nominal, &params, &qs, &data0)
                .unwrap()
                .robot;
            let ident = a.identifiable.clone();
            let errors: Vec<(Param, Real)> = ident
                .iter()
                .enumerate()
                .map(|(k, &p)| {
                    (
                        p,
                        if p.is_length() { 0.1 } else { 1e-3 } * (1.0 + 0.1 * (k % 5) as Real),
                    )
                })
                .collect();
            let truth = nominal.with_errors(&errors);
            // The true robot touches its surfaces at slightly moved joints.
            let (tq, tg) = touching(&truth, &lay, &qs, &g);
            assert_eq!(tq.len(), qs.len(), "{kind:?}");
            let data = noise_free(&lay.instrument, &truth, &tq, &tg, &lay.nuisance);
            let kp = KindProblem::new(&nominal, &ident, &tq, &data).unwrap();
            for (name, solver) in &solvers {
                let out = solve(solver.as_ref(), &kp, &DVector::zeros(kp.size().params));
                for (k, (p, e)) in errors.iter().enumerate() {
                    assert!(
                        (out.x[k] - e).abs() < 1e-6,
                        "{kind:?} {name}: {p} {} against {e} ({:?})",
                        out.x[k],
                        out.termination
                    );
                }
                let c = kp.nuisance_at(&out.x);
                for (k, v) in lay.nuisance.iter().enumerate() {
                    assert!((c[k] - v).abs() < 1e-6, "{kind:?} {name}: nuisance {k}");
                }
            }
        }
    }

    /// Cramér–Rao (Gaussian noise alone, the same σ on every reading): the trace of the
    /// empirical covariance of `ls`'s robot-parameter estimates over 400 noise draws against
    /// σ² trace((JᵀJ)⁻¹) of the robot's block, per kind, at most 1.05. σ = 2 µm keeps every
    /// kind in its linear range: one 25.4 mm sphere seen from 30 poses is so weakly
    /// conditioned that at σ = 10 µm the estimate's spread is 1.34 times the bound. Two
    /// sockets held at 15 poses each leave one weak direction that dominates the trace, whose
    /// estimate over 400 draws then spreads by about 7 % (it read 1.19): 1600 draws for them.
    #[test]
    fn ls_meets_the_cramer_rao_bound_for_every_kind() {
        use rand::Rng as _;
        let nominal = irb2600();
        let params = candidates(&nominal);
        for (kind, qs, g, lay) in setups() {
            let sigma = 0.002;
            let draws = if kind == Kind::Socket { 1600 } else { 400 };
            let (qs, g) = (&qs[..30], &g[..30]);
            let data0 = noise_free(&lay.instrument, &nominal, qs, g, &lay.nuisance);
            let ident = identifiability(&nominal, &params, qs, &data0)
                .unwrap()
                .robot
                .identifiable;
            let errors: Vec<(Param, Real)> = ident
                .iter()
                .map(|&p| (p, if p.is_length() { 0.1 } else { 1e-3 }))
                .collect();
            let truth = nominal.with_errors(&errors);
            let (tq, tg) = touching(&truth, &lay, qs, g);
            let clean = noise_free(&lay.instrument, &truth, &tq, &tg, &lay.nuisance);
            let t = ident.len();
            let ls = LsOptions::default();
            let kp = KindProblem::new(&nominal, &ident, &tq, &clean).unwrap();
            let exact = solve(&ls, &kp, &DVector::zeros(kp.size().params));
            let inv = exact.normal.clone().try_inverse().unwrap();
            let crb: Real = (0..t).map(|c| sigma * sigma * inv[(c, c)]).sum();
            let mut rng = crate::numeric::rng::stream(36, kind.as_str());
            let mut est = Vec::with_capacity(draws);
            for _ in 0..draws {
                let mut data = clean.clone();
                for v in &mut data.values {
                    let z: Real = rng.sample(rand_distr::StandardNormal);
                    *v += sigma * z;
                }
                let kp = KindProblem::new(&nominal, &ident, &tq, &data).unwrap();
                let out = solve(&ls, &kp, &DVector::zeros(kp.size().params));
                est.push(out.x.rows(0, t).into_owned());
            }
            let n = draws as Real;
            let mean = est.iter().fold(DVector::zeros(t), |a, e| a + e) / n;
            let trace: Real =
                est.iter().map(|e| (e - &mean).norm_squared()).sum::<Real>() / (n - 1.0);
            let ratio = trace / crb;
            eprintln!("{kind:?}: CRB ratio {ratio:.4}");
            assert!(ratio <= 1.05 && ratio > 0.9, "{kind:?}: CRB ratio {ratio}");
        }
    }

    /// The simulated socket study: a robot with errors injected in every parameter the
    /// sockets identify holds its ball in two sockets 50 mm apart, off their centres by
    /// 5 µm per coordinate, from 60 poses; `ls` on the nominal robot recovers every injected
    /// error to within 4 of its standard errors (σ² (JᵀJ)⁻¹), and the sockets' place too.
    #[test]
    fn a_simulated_socket_study_recovers_the_injected_errors_within_its_noise() {
        use crate::sim::instrument::{instrument_poses, measure};
        let nominal = irb2600();
        let s = InstrumentSettings {
            kind: Kind::Socket,
            noise_um: 5.0,
            ..InstrumentSettings::default()
        };
        let mut rng = crate::numeric::rng::stream(54, "socket study");
        let (lay, qs, g) = instrument_poses(&s, &nominal, 60, &mut rng).unwrap();
        let data0 = noise_free(&lay.instrument, &nominal, &qs, &g, &lay.nuisance);
        let ident = identifiability(&nominal, &nominal.params(), &qs, &data0)
            .unwrap()
            .robot
            .identifiable;
        assert!(ident.len() >= 15, "{} identifiable", ident.len());
        let errors: Vec<(Param, Real)> = ident
            .iter()
            .enumerate()
            .map(|(k, &p)| {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                (p, sign * if p.is_length() { 0.5 } else { 2e-3 })
            })
            .collect();
        let truth = nominal.with_errors(&errors);
        let (tq, data, sigma) = measure(&s, &lay, &truth, &qs, &g, &mut rng).unwrap();
        assert!(sigma.iter().all(|v| (*v - 0.005).abs() < 1e-15));
        let kp = KindProblem::new(&nominal, &ident, &tq, &data).unwrap();
        let lm = LmOptions {
            adaptive: true,
            eps: 1e-12,
            max_iter: 200,
            ..LmOptions::default()
        };
        let out = solve(&lm, &kp, &DVector::zeros(kp.size().params));
        let cov = out.normal.clone().try_inverse().unwrap() * 0.005 * 0.005;
        let mut worst: Real = 0.0;
        for (k, (p, e)) in errors.iter().enumerate() {
            let z = (out.x[k] - e) / cov[(k, k)].sqrt();
            worst = worst.max(z.abs());
            assert!(z.abs() < 4.0, "{p}: {} against {e}, {z:.2} σ", out.x[k]);
        }
        // Without the fit, the injected errors would be many standard errors away.
        let far = errors
            .iter()
            .enumerate()
            .filter(|(k, (_, e))| e.abs() / cov[(*k, *k)].sqrt() > 10.0)
            .count();
        assert!(far > errors.len() / 2, "{far} of {} far", errors.len());
        let t = ident.len();
        let c = kp.nuisance_at(&out.x);
        for (k, v) in lay.nuisance.iter().enumerate() {
            let z = (c[k] - v) / cov[(t + k, t + k)].sqrt();
            assert!(
                z.abs() < 4.0,
                "nuisance {k}: {} against {v}, {z:.2} σ",
                c[k]
            );
        }
        eprintln!("socket study: {t} parameters, worst {worst:.2} σ");
    }

    #[test]
    fn distance_cannot_see_the_base_frame() {
        let robot = irb2600();
        let (_, qs, g, lay) = setups()
            .into_iter()
            .find(|(k, _, _, _)| *k == Kind::Distance)
            .unwrap();
        let data = noise_free(&lay.instrument, &robot, &qs, &g, &lay.nuisance);
        let a = identifiability(&robot, &robot.params(), &qs, &data)
            .unwrap()
            .robot;
        let base: Vec<_> = a
            .unidentifiable
            .iter()
            .filter(|p| matches!(p, Param::Base(_)))
            .collect();
        assert_eq!(base.len(), 6, "{:?}", a.unidentifiable);
    }

    /// The rank at poses spread over the workspace is the rank at the poses that touch the
    /// instrument; a plane touched at one point leaves its tilt free, and nothing else.
    #[test]
    fn generic_rank_and_free_unknowns() {
        let robot = irb2600();
        for (kind, qs, g, lay) in setups() {
            let data = noise_free(&lay.instrument, &robot, &qs, &g, &lay.nuisance);
            let a = identifiability(&robot, &robot.params(), &qs, &data).unwrap();
            let generic = generic_rank(&robot, &robot.params(), &lay).unwrap();
            assert_eq!(generic, a.robot.rank, "{kind:?}");
            assert!(a.undetermined.is_empty(), "{kind:?}: {:?}", a.undetermined);
            if kind != Kind::Plane {
                continue;
            }
            // Every pose of plane 1 moved to its first one: one point.
            let first = g.iter().position(|&p| p == 0).unwrap();
            let qs: Vec<Vec<Real>> = (0..qs.len())
                .map(|i| match g[i] {
                    0 => qs[first].clone(),
                    _ => qs[i].clone(),
                })
                .collect();
            let data = noise_free(&lay.instrument, &robot, &qs, &g, &lay.nuisance);
            let a = identifiability(&robot, &robot.params(), &qs, &data).unwrap();
            assert_eq!(a.undetermined.len(), 2, "{:?}", a.undetermined);
            assert!(a.undetermined.iter().all(|n| n.starts_with("plane1_")));
        }
    }
}
