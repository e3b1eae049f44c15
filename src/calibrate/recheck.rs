//! Identifiability re-checked at the identified robot (docs/formats.md § 2.6.1, "Parameters
//! re-checked at the identified robot").
//!
//! `identify` chooses its parameters at the nominal robot ([`super::cv::Model`]): a parameter
//! whose Jacobian column depends exactly on the others there is left out (the Barrett WAM's
//! joint-7 harmonics and the twist before it, its nominal tracker target lying on joint 7's
//! axis). The identified robot can break such a dependency (its identified target sits off the
//! axis), but so can errors at the noise level, which break every exact dependency a little: a
//! rank test at the identified robot flags them all. The re-check is therefore a bound, not a
//! rank: a left-out parameter c is re-admitted when, at the identified robot and frame, over
//! the calibration poses, with the parameters identified and c,
//!
//! 1. its column has an effect (its norm above 1e-9 of the largest column's, the floor of
//!    [`crate::robot::identifiability::scale_columns`]),
//! 2. the normal matrix `JᵀPJ` has full numerical rank ([`bound_inverse`]), and
//! 3. its Cramér–Rao σ, `σ_c = s · √(JᵀPJ)⁻¹_cc`, is at most `B_c / k`: `B_c` the largest
//!    move a calibration can make of it ([`super::plausibility::bound`]: 5° for an angle or a
//!    harmonic, the larger of 2 % of the reach and 10 mm for a length), k =
//!    [`DETERMINABLE_SIGMAS`] = 3: the largest plausible value can be told from 0. `s` is
//!    the noise of a point of weight 1: the fit's σ0, and with `sigma_mm` in the file the
//!    larger of σ0 and the stated noise; and
//! 4. the data tell its value from 0: the Gauss–Newton step from the identified robot with c
//!    free, `x_c = ((JᵀPJ)⁻¹ JᵀP r)_c` (the other parameters are at their optimum, so this is
//!    Rao's score test), exceeds k σ_c in size.
//!
//! Points 1–3 were fixed before any figure, from the 3σ of a study's determinable errors;
//! point 4 and the convergence guard below were added after cases were seen (docs/formats.md
//! § 2.6.1 says which). A parameter without a plausibility bound (the tool's and the base's
//! angles, a compliance, a gravity-basis coefficient) is not re-admitted. When
//! the identified robot leaves an exact dependency by a parameter δ that lies m of its own σ
//! from nominal, the column of c grows like δ and σ_c ≈ s / (|δ| √n) ≈ (lever arm) / m, so a
//! dependency broken at the noise level (m ≈ 1) gives σ_c of the order of the robot's size
//! and fails point 3; a parameter the data determine but whose value is 0 fails point 4
//! (by chance, 0.27 % of the time). Candidates are taken in order and each is checked with
//! those re-admitted before it. Registration by `svd` or `wsvd` estimates the frame apart: its
//! six degrees of freedom enter the bound as the base parameters. The pipeline then identifies
//! again with them ([`super::pipeline`]), started at the identified robot (at the nominal one
//! their columns vanish and a Gauss–Newton step in them is unbounded), and gives the
//! re-admission up when that identification does not converge although the first did.

use nalgebra::{DMatrix, DVector};

use super::diagnostics::Subject;
use super::Registration;
use crate::error::Result;
use crate::identify::solver::{bound_inverse, by_blocks, BLOCK_POINTS, DETERMINABLE_SIGMAS};
use crate::identify::{CalibrationProblem, Identified, LeastSquares, RobotProblem};
use crate::measurement::Measurements;
use crate::numeric::normal::NormalEquations;
use crate::numeric::{nan, Real};
use crate::robot::{Param, Robot};

/// A parameter re-admitted at the identified robot.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Readmitted {
    /// Its value one Gauss–Newton step from the identified robot (mm, rad): the test of
    /// point 4 of the rule.
    #[serde(deserialize_with = "nan::real")]
    pub estimate: Real,
    /// Its name.
    pub parameter: String,
    /// Its Cramér–Rao σ at the identified robot before it was re-admitted (mm, rad).
    #[serde(deserialize_with = "nan::real")]
    pub sigma: Real,
    /// The largest σ re-admitted: its plausibility bound over [`DETERMINABLE_SIGMAS`].
    #[serde(deserialize_with = "nan::real")]
    pub threshold: Real,
}

/// What the re-check changed: the parameters re-admitted, and the fit before them.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Readmission {
    /// The RMS residual (mm) of the identification before the re-admission (`rms_residual_mm`
    /// is the one after).
    #[serde(deserialize_with = "nan::real")]
    pub before_rms_residual_mm: Real,
    /// The parameters re-admitted, in the order they were.
    pub parameters: Vec<Readmitted>,
}

/// The re-check of an identification: the normal equations at its identified robot of its
/// parameters, the registration's nuisance parameters and the candidates that may be
/// re-admitted, formed in one pass over the rows ([`NormalEquations::both_ways`]), from which
/// [`Recheck::readmit`] and [`Recheck::step`] take each set of parameters they solve, with the
/// bits of its own pass.
pub struct Recheck {
    /// The registration's nuisance parameters that the fit's do not already hold
    /// ([`Recheck::at`]).
    nuisance: Vec<Param>,
    /// The fit's parameters, the nuisance ones, then the candidates in order.
    columns: Vec<Param>,
    /// How many of `columns` are the fit's parameters.
    fitted: usize,
    /// The candidates and their plausibility bounds, in order.
    candidates: Vec<(Param, Real)>,
    sums: NormalEquations,
    /// The noise of a point of weight 1 ([`unit_noise`]).
    noise: Real,
}

impl Recheck {
    /// The re-check of `candidates` (the parameters left out at the nominal robot,
    /// [`super::cv::Model::left_out`]) at the identified robot of the identification `id`
    /// (its priors and validation are not read) registered by `registration`. `None` when
    /// none can be re-admitted: the noise is not finite, or no candidate is outside the fit's
    /// and the registration's parameters with a plausibility bound.
    pub fn at(
        id: &Subject,
        registration: Registration,
        candidates: &[Param],
    ) -> Result<Option<Recheck>> {
        let noise = unit_noise(id.data, id.calibrated.identified.sigma0);
        let nuisance = nuisance(registration, id.params);
        let mut columns: Vec<Param> = id.params.iter().chain(&nuisance).copied().collect();
        let mut bounded = Vec::new();
        for &p in candidates {
            if columns.contains(&p) {
                continue;
            }
            if let Some(bound) = super::plausibility::bound(id.nominal, p) {
                columns.push(p);
                bounded.push((p, bound));
            }
        }
        if !(noise.is_finite() && noise >= 0.0) || bounded.is_empty() {
            return Ok(None);
        }
        let sums = normal(&id.calibrated.robot, &columns, id)?;
        let mut recheck = Recheck {
            nuisance: Vec::new(),
            columns,
            fitted: id.params.len(),
            candidates: bounded,
            sums,
            noise,
        };
        // A frame parameter the fit's already span (θ1 turns the robot about the base's z as
        // base.rz does, d1 moves it along z as base.z does) would make every normal matrix
        // singular, and no candidate could then be re-admitted: each is solved along only
        // where it adds a direction of its own.
        for b in nuisance {
            let mut with: Vec<Param> = id.params.iter().chain(&recheck.nuisance).copied().collect();
            with.push(b);
            if bound_inverse(&recheck.normal(&with).0).is_some() {
                recheck.nuisance.push(b);
            }
        }
        Ok(Some(recheck))
    }

    /// Those of the candidates re-admitted, by the rule of the module, in order, each
    /// checked with the fit's parameters and those re-admitted before it.
    pub fn readmit(&self) -> Vec<(Param, Readmitted)> {
        let params = &self.columns[..self.fitted];
        let nuisance = &self.nuisance;
        let mut current: Vec<Param> = params.to_vec();
        let mut out = Vec::new();
        for &(p, bound) in &self.candidates {
            let all: Vec<Param> = current.iter().chain(nuisance).copied().chain([p]).collect();
            let (n, g) = self.normal(&all);
            let last = all.len() - 1;
            let largest = (0..all.len())
                .map(|i| n[(i, i)].max(0.0).sqrt())
                .fold(0.0, Real::max);
            if n[(last, last)].max(0.0).sqrt() <= 1e-9 * largest + 1e-12 {
                continue;
            }
            let Some(inv) = bound_inverse(&n) else {
                continue;
            };
            let sigma = self.noise * inv[(last, last)].sqrt();
            let estimate = inv.row(last).dot(&g.transpose());
            let threshold = bound / DETERMINABLE_SIGMAS;
            if sigma <= threshold && estimate.abs() > DETERMINABLE_SIGMAS * sigma {
                current.push(p);
                let parameter = p.to_string();
                out.push((
                    p,
                    Readmitted {
                        estimate,
                        parameter,
                        sigma,
                        threshold,
                    },
                ));
            }
        }
        out
    }

    /// The Gauss–Newton step from the identification in `params` (its own followed by
    /// re-admitted ones, at 0), the registration's nuisance parameters solved along and
    /// dropped: where the fit with the re-admitted errors starts, each at its estimate
    /// together with the errors it is correlated with. Started at its estimate alone, a
    /// damped method (`lm`) moves it back, as its damping costs the correlated errors' larger
    /// moves more. `None` where the normal matrix cannot be inverted.
    pub fn step(&self, params: &[Param]) -> Option<Vec<Real>> {
        let all: Vec<Param> = params
            .iter()
            .copied()
            .chain(self.nuisance.iter().copied())
            .collect();
        let (n, g) = self.normal(&all);
        bound_inverse(&n).map(|inv| (inv * g).iter().take(params.len()).copied().collect())
    }

    /// `JᵀPJ` and `JᵀP r` of `params` (each one of the columns), in their order.
    fn normal(&self, params: &[Param]) -> (DMatrix<Real>, DVector<Real>) {
        let at: Vec<usize> = params
            .iter()
            .map(|p| {
                let i = self.columns.iter().position(|c| c == p);
                i.expect("a parameter of the re-check's columns")
            })
            .collect();
        let t = at.len();
        let n = DMatrix::from_fn(t, t, |k, l| self.sums.cross(at[k.max(l)], at[k.min(l)]));
        (n, DVector::from_fn(t, |k, _| self.sums.g()[at[k]]))
    }
}

/// The base parameters a registration by `registration` solves outside the fit of `params`,
/// which the re-check solves along with them.
fn nuisance(registration: Registration, params: &[Param]) -> Vec<Param> {
    match registration {
        Registration::Svd | Registration::Wsvd => (0..6)
            .map(Param::Base)
            .filter(|p| !params.contains(p))
            .collect(),
        Registration::Identify | Registration::Known => Vec::new(),
    }
}

/// The noise (mm) of a point of weight 1: the fit's unit-weight σ0 and, when the file states
/// each point's σ (`sigma_mm`, weighed 1/σ² scaled to a mean weight of 1), the larger of σ0
/// and the stated σ of a point of weight 1, `(mean 1/σ²)^(-1/2)`.
fn unit_noise(data: &Measurements, sigma0: Real) -> Real {
    match &data.sigma_mm {
        Some(s) if !s.is_empty() => {
            let mean = s.iter().map(|v| 1.0 / (v * v)).sum::<Real>() / s.len() as Real;
            sigma0.max(1.0 / mean.sqrt())
        }
        _ => sigma0,
    }
}

/// Each residual row's weight in the re-check, point after point (`rows` rows per point):
/// the weight the fit gave it, so that `JᵀPJ` is the fit's own with the candidate's column
/// added. That is the row's own weight when the fit weighed each row on its own (IGG3 with
/// `per = "coordinate"`: a gross coordinate at 0, its point's other rows kept), else its
/// point's: the file's weight times a robust method's. A fit that reports no weights of its
/// own ([`Identified::own_weights`] false: the searches, external methods) weighed the rows
/// by the file's weights (1 without `sigma_mm`).
fn row_weights(data: &Measurements, fitted: &Identified, rows: usize) -> Vec<Real> {
    if let Some(w) = &fitted.row_weights {
        if w.len() == data.len() * rows {
            return w.clone();
        }
    }
    let point = if fitted.own_weights && fitted.weights.len() == data.len() {
        fitted.weights.clone()
    } else {
        data.weights().unwrap_or_else(|| vec![1.0; data.len()])
    };
    point
        .iter()
        .flat_map(|&w| std::iter::repeat_n(w, rows))
        .collect()
}

/// `JᵀPJ` and `JᵀP r` of `params` at `robot` (the identified robot: errors 0) in the
/// calibration's frame, over the calibration rows weighed as the fit weighed them
/// ([`row_weights`]), summed [`BLOCK_POINTS`] points at a time both ways
/// ([`NormalEquations::both_ways`]).
fn normal(robot: &Robot, params: &[Param], id: &Subject) -> Result<NormalEquations> {
    let problem = CalibrationProblem::new(robot, params, id.data, id.calibrated.frame, id.k);
    let rp = RobotProblem::of(&problem)?;
    let rows = rp.size().rows_per_point;
    let weights = row_weights(id.data, &id.calibrated.identified, rows);
    let mut sums = NormalEquations::both_ways(params.len(), rows * BLOCK_POINTS);
    by_blocks(&rp, &DVector::zeros(params.len()), |points, r, j| {
        sums.add(
            j,
            r.as_slice(),
            &weights[points.start * rows..points.end * rows],
        );
    });
    Ok(sums)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::calibrate;
    use crate::identify::{MethodSpec, Termination};
    use crate::numeric::rng::stream;
    use crate::numeric::Frame;
    use crate::robot::{builtin, sampling::uniform_joint_poses};
    use rand::Rng as _;

    /// The identified parameters and the candidate whose column the re-check adds.
    const PARAMS: [Param; 4] = [Param::A(1), Param::Theta(2), Param::D(3), Param::Alpha(2)];
    const CANDIDATE: Param = Param::D(4);
    /// The point and the coordinate (0 x, 1 y, 2 z) displaced by 2 mm.
    const BAD: (usize, usize) = (7, 1);

    /// 40 poses of the irb2600 with errors in `PARAMS`, measured in its base frame with
    /// uniform noise of ±5 µm per coordinate; `gross` mm added to the bad coordinate.
    fn data(gross: Real) -> Measurements {
        let robot = builtin::irb2600();
        let truth = robot.with_errors(&[
            (PARAMS[0], 0.5),
            (PARAMS[1], 1e-3),
            (PARAMS[2], 0.3),
            (PARAMS[3], 5e-4),
        ]);
        let chain = truth.chain();
        let mut g = stream(5, "recheck-rows");
        let qs = uniform_joint_poses(&robot, 40, &mut g);
        let mut points: Vec<_> = qs
            .iter()
            .map(|q| {
                let mut p = chain.fk(q).pos;
                for k in 0..3 {
                    p[k] += g.random_range(-0.005..0.005);
                }
                p
            })
            .collect();
        points[BAD.0][BAD.1] += gross;
        Measurements {
            points,
            qs,
            ..Default::default()
        }
    }

    /// `d` with standard deviations of 0.01 to 0.04 mm (`sigma_mm`): weights 1/σ² unlike.
    fn with_sigma(mut d: Measurements) -> Measurements {
        d.sigma_mm = Some((0..d.len()).map(|i| 0.01 * (1 + i % 4) as Real).collect());
        d
    }

    fn fit(d: &Measurements, method: &str) -> crate::calibrate::Calibrated {
        let spec = MethodSpec::from_table(&toml::from_str(method).unwrap()).unwrap();
        let mut rng = stream(0, "identify");
        let nominal = builtin::irb2600();
        let c = calibrate(
            &nominal,
            &PARAMS,
            d,
            Registration::Known,
            &Frame::identity(),
            &spec,
            &mut rng,
        )
        .unwrap();
        assert_eq!(
            c.identified.termination,
            crate::identify::Termination::Converged
        );
        c
    }

    /// `JᵀPJ` and `JᵀPr` of the fit's parameters and the candidate at the identified robot,
    /// built densely from the whole Jacobian with the row weights `p`: the independent build.
    fn dense(
        c: &crate::calibrate::Calibrated,
        d: &Measurements,
        p: &[Real],
    ) -> (DMatrix<Real>, DVector<Real>) {
        let all: Vec<Param> = PARAMS.iter().copied().chain([CANDIDATE]).collect();
        let problem = CalibrationProblem::new(&c.robot, &all, d, c.frame, 1.0);
        let rp = RobotProblem::of(&problem).unwrap();
        let rows = rp.size().rows();
        assert_eq!(rows, p.len());
        let (mut r, mut j) = (DVector::zeros(rows), DMatrix::zeros(rows, all.len()));
        rp.evaluate(&DVector::zeros(all.len()), &mut r, &mut j);
        let pj = DMatrix::from_fn(rows, all.len(), |i, k| p[i] * j[(i, k)]);
        (j.transpose() * &pj, pj.transpose() * r)
    }

    /// The re-check's `JᵀPJ`, `JᵀPr` of the fit `c` on `d`.
    fn rechecked(
        c: &crate::calibrate::Calibrated,
        d: &Measurements,
    ) -> (DMatrix<Real>, DVector<Real>) {
        let nominal = builtin::irb2600();
        let on = Subject {
            nominal: &nominal,
            params: &PARAMS,
            data: d,
            calibrated: c,
            k: 1.0,
            priors: &[],
            validation: None,
        };
        let all: Vec<Param> = PARAMS.iter().copied().chain([CANDIDATE]).collect();
        let sums = normal(&c.robot, &all, &on).unwrap();
        (sums.n().clone(), sums.g().clone())
    }

    fn close(a: &DMatrix<Real>, b: &DMatrix<Real>) -> bool {
        (a - b).amax() <= 1e-9 * b.amax()
    }

    /// IGG3 per coordinate rejects the one displaced coordinate and keeps its point's other
    /// two rows; the re-check weighs the rows so: its `JᵀPJ` and `JᵀPr` equal a dense build
    /// with that row at 0 and every other at 1, not the build that drops the whole point (the
    /// point's mean weight, 2/3, or the points at full weight only), and its block of the
    /// fit's parameters is the fit's own normal matrix.
    #[test]
    fn a_gross_coordinate_is_left_out_of_the_re_check_and_its_points_other_rows_kept() {
        let d = data(2.0);
        let c = fit(&d, "name = \"igg3\"\nxi = 0.0\nper = \"coordinate\"");
        let bad = 3 * BAD.0 + BAD.1;
        let rows = c.identified.row_weights.clone().expect("row weights");
        for (i, &w) in rows.iter().enumerate() {
            assert_eq!(w, if i == bad { 0.0 } else { 1.0 }, "row {i}");
        }
        assert!((c.identified.weights[BAD.0] - 2.0 / 3.0).abs() < 1e-12);
        let p: Vec<Real> = (0..rows.len()).map(|i| Real::from(i != bad)).collect();
        let (n, g) = rechecked(&c, &d);
        let (want_n, want_g) = dense(&c, &d, &p);
        assert!(close(&n, &want_n), "{n} against {want_n}");
        assert!(
            (&g - &want_g).amax() <= 1e-9 * want_g.amax().max(1.0),
            "{g} {want_g}"
        );
        let t = PARAMS.len();
        let fitted = &c.identified.normal;
        assert!(
            (n.view((0, 0), (t, t)) - fitted).amax() <= 1e-6 * fitted.amax(),
            "{n} against the fit's {fitted}"
        );
        // The point's other rows matter: without them, or at its mean weight, another matrix.
        for other in [
            (0..rows.len())
                .map(|i| Real::from(i / 3 != BAD.0))
                .collect(),
            (0..rows.len())
                .map(|i| if i / 3 == BAD.0 { 2.0 / 3.0 } else { 1.0 })
                .collect::<Vec<Real>>(),
        ] {
            let (o, _) = dense(&c, &d, &other);
            assert!((&o - &want_n).amax() > 1e-6 * want_n.amax());
        }
    }

    /// With the file's standard deviations (`sigma_mm`) a least-squares fit weighs each point
    /// by its prior weight, and so does the re-check: every row of a point at its point's
    /// weight, those below 1 too.
    #[test]
    fn the_files_weights_are_the_re_checks_under_a_method_that_does_not_reweigh() {
        let d = with_sigma(data(0.0));
        let c = fit(&d, "name = \"lm\"");
        let w = d.weights().unwrap();
        assert!(w.iter().any(|&v| v < 0.5) && w.iter().any(|&v| v > 1.0));
        let p: Vec<Real> = w.iter().flat_map(|&v| [v; 3]).collect();
        let (n, _) = rechecked(&c, &d);
        let (want, _) = dense(&c, &d, &p);
        assert!(close(&n, &want), "{n} against {want}");
    }

    /// The fit says whose its point weights are ([`Identified::own_weights`]); the re-check no
    /// longer guesses it from whether any weight differs from 1. A fit that weighed every
    /// point alike on a file with `sigma_mm` (own weights, all 1) is re-checked with those,
    /// where the guess took the file's; a fit that reports no weights of its own (a search:
    /// `weights` all 1) is re-checked with the file's.
    #[test]
    fn the_fit_says_whether_its_point_weights_are_its_own() {
        let d = with_sigma(data(0.0));
        let mut c = fit(&d, "name = \"lm\"");
        assert!(c.identified.own_weights);
        let file: Vec<Real> = d.weights().unwrap().iter().flat_map(|&v| [v; 3]).collect();
        let ones = vec![1.0; file.len()];
        c.identified.weights = vec![1.0; d.len()];
        for (own, p) in [(true, &ones), (false, &file)] {
            c.identified.own_weights = own;
            let (n, _) = rechecked(&c, &d);
            let (want, _) = dense(&c, &d, p);
            assert!(close(&n, &want), "own {own}: {n} against {want}");
            let (other, _) = dense(&c, &d, if own { &file } else { &ones });
            assert!(!close(&n, &other), "own {own}");
        }
    }

    /// The second fit's start: joint 6's harmonics, whose columns vanish at the nominal robot
    /// (its tool point on joint 6's axis: their `JᵀPJ` diagonal is at the rounding level)
    /// but not at a robot whose tool sits 5.8 mm off that axis. From the nominal robot the
    /// robust ridge's first Gauss–Newton step in them is unbounded (neither the data nor the
    /// ridge, scaled there, hold it) and its iterations do not settle within their limit; from
    /// the first fit's estimate (the identified robot, the harmonics at 0), where the
    /// re-check found them determined, they converge to the injected values within 3σ, per
    /// point and per coordinate alike.
    #[test]
    fn a_second_fit_from_the_identified_robot_settles_what_one_from_nominal_cannot() {
        let (hs, hc) = (0.01, -0.005);
        let robot = builtin::irb2600();
        let tool = [Param::Tool(0), Param::Tool(1), Param::Tool(2)];
        let mut errors: Vec<(Param, Real)> =
            PARAMS.iter().copied().zip([0.5, 1e-3, 0.3, 5e-4]).collect();
        errors.extend([(tool[0], 5.0), (tool[1], -3.0)]);
        errors.extend([(Param::Harmonic(5, 0), hs), (Param::Harmonic(5, 1), hc)]);
        let truth = robot.with_errors(&errors);
        let chain = truth.chain();
        let mut g = stream(6, "recheck-start");
        let qs = uniform_joint_poses(&robot, 100, &mut g);
        let points = qs
            .iter()
            .map(|q| {
                let mut p = crate::robot::loaded::loaded_fk(&truth, &chain, q, 0.0)
                    .unwrap()
                    .pos;
                for k in 0..3 {
                    p[k] += g.random_range(-0.005..0.005);
                }
                p
            })
            .collect();
        let d = Measurements {
            points,
            qs,
            ..Default::default()
        };
        let first: Vec<Param> = PARAMS.iter().chain(&tool).copied().collect();
        let second: Vec<Param> = first
            .iter()
            .copied()
            .chain([Param::Harmonic(5, 0), Param::Harmonic(5, 1)])
            .collect();
        for per in ["point", "coordinate"] {
            let toml = format!("name = \"igg3\"\nper = \"{per}\"");
            let mut spec = MethodSpec::from_table(&toml::from_str(&toml).unwrap()).unwrap();
            let run = |params: &[Param], spec: &MethodSpec| {
                let mut rng = stream(0, "identify");
                let (known, frame) = (Registration::Known, Frame::identity());
                calibrate(&robot, params, &d, known, &frame, spec, &mut rng).unwrap()
            };
            let c1 = run(&first, &spec);
            assert_eq!(c1.identified.termination, Termination::Converged, "{per}");
            // At the nominal robot the harmonics' columns are 0 to rounding.
            let nominal = CalibrationProblem::new(&robot, &second, &d, Frame::identity(), 1.0);
            let rp = RobotProblem::of(&nominal).unwrap();
            let (mut r, mut j) = (
                DVector::zeros(rp.size().rows()),
                DMatrix::zeros(rp.size().rows(), second.len()),
            );
            rp.evaluate(&DVector::zeros(second.len()), &mut r, &mut j);
            let t = second.len();
            assert!(j.column(t - 1).norm() < 1e-9 * j.column(0).norm(), "{per}");
            let from_nominal = run(&second, &spec);
            assert_eq!(
                from_nominal.identified.termination,
                Termination::MaxIterations,
                "{per}"
            );
            spec.start = c1.identified.x.iter().copied().chain([0.0, 0.0]).collect();
            let c2 = run(&second, &spec);
            let id = &c2.identified;
            assert_eq!(id.termination, Termination::Converged, "{per}");
            let cov = id.covariance();
            for (k, want) in [(t - 2, hs), (t - 1, hc)] {
                let sigma = cov[(k, k)].sqrt();
                assert!(sigma < 1e-3, "{per}: σ {sigma}");
                assert!(
                    (id.x[k] - want).abs() <= 3.0 * sigma,
                    "{per}: {} against {want} (σ {sigma})",
                    id.x[k]
                );
            }
            assert!(id.rms_residual < 0.5 * c1.identified.rms_residual, "{per}");
        }
    }
}
