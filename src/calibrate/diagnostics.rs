//! Diagnostics of an identification on a measurement file (docs/formats.md `identify`,
//! `diagnostics`): each parameter's σ and the correlation matrix with the pairs that trade off
//! (|ρ| > [`CORRELATION_FLAG`], FIGAROH's threshold), each point's leverage and Cook's
//! distance with the most influential points, and the position σ the covariance predicts at
//! the validation (or calibration) poses.
//!
//! With `J` the weighted Jacobian at the solution, `N = JᵀPJ` (plus the priors' precisions)
//! and `C = σ0² N⁻¹`: the hat matrix's block of point `i` is `H_ii = w_i J_i N⁻¹ J_iᵀ`, its
//! leverage `h_i = trace H_ii` (the leverages sum to the number of parameters without priors),
//! and its Cook's distance the block form `D_i = w_i r_iᵀ (I − H_ii)⁻¹ H_ii (I − H_ii)⁻¹ r_i /
//! (t σ0²)` (Cook & Weisberg 1982, §3.5: the change of the fit when the point is left out, in
//! units of the parameters' confidence ellipsoid). When the fit weighed each residual row on
//! its own (IGG3's `per = "coordinate"`, [`crate::identify::Identified::row_weights`]), `w_i`
//! is the diagonal `W_i` of the point's row weights, in the symmetric form
//! `H_ii = W_i^½ J_i N⁻¹ J_iᵀ W_i^½` and `D_i = r_iᵀ W_i^½ (I − H_ii)⁻¹ H_ii (I − H_ii)⁻¹
//! W_i^½ r_i / (t σ0²)`: a coordinate the fit rejected adds neither leverage nor influence.

use nalgebra::{DMatrix, DMatrixView, DVector, Matrix6, Vector6};

use super::Calibrated;
use crate::error::Result;
use crate::identify::solver::by_blocks;
use crate::identify::{standard_error, CalibrationProblem, LeastSquares, RobotProblem};
use crate::measurement::{Measure, Measurements};
use crate::numeric::{nan, Real, Vec3};
use crate::robot::{Param, Robot};

/// Pairs of parameters whose correlation exceeds this in magnitude are flagged.
pub const CORRELATION_FLAG: Real = 0.8;
/// The number of most influential points named.
pub const TOP_POINTS: usize = 10;

/// A flagged pair of parameters.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pair {
    /// The first parameter.
    pub a: String,
    /// The second parameter.
    pub b: String,
    /// Their correlation.
    #[serde(deserialize_with = "nan::real")]
    pub rho: Real,
}

/// An influential point.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Influential {
    /// 0-based data row (as in `residuals.csv`).
    pub row: usize,
    /// Its leverage.
    #[serde(deserialize_with = "nan::real")]
    pub leverage: Real,
    /// Its Cook's distance.
    #[serde(deserialize_with = "nan::real")]
    pub cook: Real,
}

/// The position σ the covariance predicts, against the measured error.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Predicted {
    /// Where: `validation` poses or `calibration` poses.
    pub at: String,
    /// RMS over the poses of the predicted σ of the model's position, `√trace(J_p C J_pᵀ)`
    /// (mm): the parameters' uncertainty only.
    #[serde(deserialize_with = "nan::real")]
    pub rms_mm: Real,
    /// Its largest value (mm).
    #[serde(deserialize_with = "nan::real")]
    pub max_mm: Real,
    /// The measured position RMS at the same poses (validation error, or residual), mm.
    #[serde(deserialize_with = "nan::real")]
    pub measured_rms_mm: Real,
}

/// The diagnostics of an identification.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Diagnostics {
    /// σ of each parameter (√ of the covariance's diagonal), in the parameters' order.
    #[serde(deserialize_with = "nan::read")]
    pub sigma: Vec<Real>,
    /// The correlation matrix.
    #[serde(deserialize_with = "nan::read")]
    pub correlation: Vec<Vec<Real>>,
    /// The pairs with |ρ| > [`CORRELATION_FLAG`], largest first.
    pub flagged_pairs: Vec<Pair>,
    /// Leverage of each point.
    #[serde(deserialize_with = "nan::read")]
    pub leverage: Vec<Real>,
    /// Cook's distance of each point.
    #[serde(deserialize_with = "nan::read")]
    pub cook_distance: Vec<Real>,
    /// The [`TOP_POINTS`] points of largest Cook's distance.
    pub top_points: Vec<Influential>,
    /// The predicted position σ.
    pub predicted: Predicted,
}

/// What the diagnostics are taken of.
pub struct Subject<'a> {
    /// The nominal robot the errors were added to.
    pub nominal: &'a Robot,
    /// The parameters identified.
    pub params: &'a [Param],
    /// The calibration data.
    pub data: &'a Measurements,
    /// The calibration.
    pub calibrated: &'a Calibrated,
    /// Orientation weight (mm per rad).
    pub k: Real,
    /// The priors' precisions (empty: none).
    pub priors: &'a [Real],
    /// The validation data and its position RMS after calibration (mm), if any.
    pub validation: Option<(&'a Measurements, Real)>,
}

/// The fit without its most influential point (largest Cook's distance), to first order:
/// leaving point `i` out moves the parameters by `δ = N⁻¹ J_iᵀ w_i (I − H_ii)⁻¹ r_i` (the
/// Sherman–Morrison–Woodbury form of the refit), and each residual to `r_j + J_j δ`; point
/// `i`'s own becomes `(I − H_ii)⁻¹ r_i`, its distance from the fit of the others. A fit of
/// few points per unknown spreads one gross reading's error over the rest, so that among
/// the residuals it stands out only a few times above the median; without it the others
/// are back to the noise ([`super::verdict::gross_left_out`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LeftOut {
    /// The point left out (0-based row).
    pub point: usize,
    /// Per point, the position residual of the fit without `point` (mm); at `point`, its
    /// distance from that fit.
    pub residuals_mm: Vec<Real>,
}

/// The diagnostics of `s`, and the fit without its most influential point ([`LeftOut`];
/// `None` when no point's Cook's distance is finite, or the fit weighed each residual row
/// on its own). The entries depending on `N⁻¹` are NaN when `N` is singular.
pub fn diagnose(s: &Subject) -> Result<(Diagnostics, Option<LeftOut>)> {
    let id = &s.calibrated.identified;
    let t = s.params.len();
    let cov = id.covariance();
    let sigma: Vec<Real> = (0..t).map(|i| standard_error(&cov, i)).collect();
    let correlation: Vec<Vec<Real>> = (0..t)
        .map(|i| {
            (0..t)
                .map(|k| cov[(i, k)] / (sigma[i] * sigma[k]))
                .collect()
        })
        .collect();
    let mut flagged_pairs: Vec<Pair> = Vec::new();
    for (i, row) in correlation.iter().enumerate() {
        for (k, &rho) in row.iter().enumerate().skip(i + 1) {
            if rho.abs() > CORRELATION_FLAG {
                flagged_pairs.push(Pair {
                    a: s.params[i].to_string(),
                    b: s.params[k].to_string(),
                    rho,
                });
            }
        }
    }
    flagged_pairs.sort_by(|a, b| b.rho.abs().total_cmp(&a.rho.abs()));
    let n_inv = id
        .normal
        .clone()
        .cholesky()
        .map(|c| c.inverse())
        .unwrap_or_else(|| DMatrix::from_element(t, t, Real::NAN));
    let mut problem = CalibrationProblem::new(s.nominal, s.params, s.data, s.calibrated.frame, s.k);
    problem.priors = s.priors.to_vec();
    let rp = RobotProblem::of(&problem)?;
    let m = s.data.len();
    let s0sq = id.sigma0 * id.sigma0;
    let mut leverage = Vec::with_capacity(m);
    let mut cook_distance = Vec::with_capacity(m);
    // The most influential point so far: its row, Cook's distance, distance from the fit
    // of the others (mm), and the parameters' move without it (δ).
    let mut suspect: Option<(usize, Real, Real)> = None;
    let mut delta = DVector::zeros(t);
    // Per point, H_ii = w_i J_i N⁻¹ J_iᵀ and (I − H_ii)⁻¹ r_i on the stack (at most 6 rows a
    // point, padded with the identity). With a weight per row (IGG3's `per = "coordinate"`),
    // H_ii = D_i J_i N⁻¹ J_iᵀ D_i and r_i scaled by D_i, D_i = diag(√w_ik): the point's block
    // of the hat matrix of the fit as it weighed the rows.
    let rows = rp.size().rows_per_point;
    let row_weights = id.row_weights.as_deref().filter(|w| w.len() == m * rows);
    by_points(&rp, &id.x, &n_inv, |i, ri, h, a_i| {
        let (h, ri, w) = match row_weights {
            Some(rw) => {
                let mut d = Vector6::zeros();
                for (k, w) in rw[i * rows..(i + 1) * rows].iter().enumerate() {
                    d[k] = w.sqrt();
                }
                let d = Matrix6::from_diagonal(&d);
                (d * h * d, d * ri, 1.0)
            }
            None => {
                let w = id.weights.get(i).copied().unwrap_or(1.0);
                (h.scale(w), ri, w)
            }
        };
        leverage.push(h.trace());
        let deleted = (Matrix6::identity() - h).lu().solve(&ri);
        let cook = deleted.map_or(Real::NAN, |v| w * v.dot(&(h * v)) / (t as Real * s0sq));
        cook_distance.push(cook);
        let above = suspect.is_none_or(|(_, c, _)| cook > c);
        if let (Some(v), true, None) = (deleted, cook.is_finite() && above, row_weights) {
            delta.gemv_tr(w, &a_i, &v.rows(0, rows), 0.0);
            suspect = Some((i, cook, v.fixed_rows::<3>(0).norm()));
        }
    });
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| {
        let key = |i: usize| -> Real {
            let c = cook_distance[i];
            if c.is_nan() {
                Real::NEG_INFINITY
            } else {
                c
            }
        };
        key(b).total_cmp(&key(a)).then(a.cmp(&b))
    });
    let top_points = order
        .iter()
        .take(TOP_POINTS)
        .map(|&row| Influential {
            row,
            leverage: leverage[row],
            cook: cook_distance[row],
        })
        .collect();
    // The order's memory (a word a point) serves the pass without the suspect.
    drop(order);
    let left_out = suspect.map(|(point, _, distance)| {
        let mut residuals_mm = Vec::with_capacity(m);
        let mut moved = DVector::zeros(0);
        by_blocks(&rp, &id.x, |points, r, j| {
            if moved.len() != r.len() {
                moved = DVector::zeros(r.len());
            }
            moved.copy_from(r);
            moved.gemv(1.0, j, &delta, 1.0);
            for k in 0..points.len() {
                let at = moved.rows(k * rows, rows.min(3));
                residuals_mm.push(at.norm());
            }
        });
        residuals_mm[point] = distance;
        LeftOut {
            point,
            residuals_mm,
        }
    });
    let predicted = predicted_sigma(s, &cov)?;
    let diagnostics = Diagnostics {
        sigma,
        correlation,
        flagged_pairs,
        leverage,
        cook_distance,
        top_points,
        predicted,
    };
    Ok((diagnostics, left_out))
}

/// Calls `f(i, r_i, H_i, A_i)` for each point `i` of `p` at `x`, in order, with its residual
/// rows and `H_i = J_i M J_iᵀ`, both padded to 6 rows with zeros, and its rows `A_i = J_i M`.
/// The rows are evaluated block by block ([`by_blocks`]), and `J M` is formed once a block:
/// memory stays bounded for files of millions of rows, and nothing is allocated per point.
fn by_points(
    p: &dyn LeastSquares,
    x: &DVector<Real>,
    m: &DMatrix<Real>,
    mut f: impl FnMut(usize, Vector6<Real>, Matrix6<Real>, DMatrixView<Real>),
) {
    let rows = p.size().rows_per_point;
    let mut a = DMatrix::zeros(0, m.ncols());
    by_blocks(p, x, |points, r, j| {
        if a.nrows() != r.len() {
            a = DMatrix::zeros(r.len(), m.ncols());
        }
        j.mul_to(m, &mut a);
        for (i, point) in points.enumerate() {
            let mut ri = Vector6::zeros();
            ri.rows_mut(0, rows).copy_from(&r.rows(i * rows, rows));
            f(
                point,
                ri,
                point_block(&a, j, i * rows, rows),
                a.rows(i * rows, rows),
            );
        }
    });
}

/// `A_i J_iᵀ` for the point whose `rows` rows start at `row` of `a` and `j`, padded to 6 × 6
/// with zeros.
fn point_block(a: &DMatrix<Real>, j: &DMatrix<Real>, row: usize, rows: usize) -> Matrix6<Real> {
    let mut h = Matrix6::zeros();
    // Column by column: the point's rows are contiguous in each (column-major) column.
    let n = a.nrows();
    for (ac, jc) in a
        .as_slice()
        .chunks_exact(n)
        .zip(j.as_slice().chunks_exact(n))
    {
        let (ac, jc) = (&ac[row..row + rows], &jc[row..row + rows]);
        for (u, au) in ac.iter().enumerate() {
            for (v, jv) in jc.iter().enumerate() {
                h[(u, v)] += au * jv;
            }
        }
    }
    h
}

/// `√trace(J_p C J_pᵀ)` at the validation poses (else the calibration poses), the position
/// Jacobian `J_p` of the identified model.
fn predicted_sigma(s: &Subject, cov: &DMatrix<Real>) -> Result<Predicted> {
    let id = &s.calibrated.identified;
    let (at, data, measured) = match s.validation {
        Some((v, rms)) => ("validation", v, rms),
        None => ("calibration", s.data, id.rms_residual),
    };
    let zeros = vec![Vec3::zeros(); data.len()];
    let rp = RobotProblem::new(
        s.nominal,
        s.params,
        &data.qs,
        &zeros,
        None,
        Measure::Position,
    )?
    .with_payloads(data.payload_kg.as_deref())?;
    let mut sigmas = Vec::with_capacity(data.len());
    by_points(&rp, &id.x, cov, |_, _, h, _| {
        // NaN without a covariance (a search's): no σ is predicted, where `max` gave 0.
        let trace = h.trace();
        sigmas.push(if trace.is_nan() {
            trace
        } else {
            trace.max(0.0).sqrt()
        })
    });
    let stats = super::ErrorStats::of(&sigmas);
    Ok(Predicted {
        at: at.into(),
        rms_mm: stats.rms,
        max_mm: stats.max,
        measured_rms_mm: measured,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::{calibrate, Registration};
    use crate::numeric::rng::stream;

    /// Leverages sum to the number of parameters (trace of the hat matrix), Cook's distance
    /// singles out a gross error, and correlations are ±1 on the diagonal.
    #[test]
    fn leverage_sums_to_the_parameters_and_cook_finds_the_outlier() {
        let nominal = crate::robot::builtin::load("irb2600").unwrap();
        let (data, params) = one_gross_point(&nominal, &nominal);
        let method = crate::identify::method_by_name("ls").unwrap();
        let (_, d, _) = fit_and_diagnose(&nominal, &params, &data, &method, 100.0);
        let sum: Real = d.leverage.iter().sum();
        assert!((sum - params.len() as Real).abs() < 1e-6, "{sum}");
        assert_eq!(d.top_points[0].row, 13);
        for i in 0..params.len() {
            assert!((d.correlation[i][i] - 1.0).abs() < 1e-9);
        }
        assert!(d.predicted.rms_mm > 0.0 && d.predicted.at == "calibration");
    }

    /// 40 uniform poses of `nominal` measured on `arm` with a noise of up to 0.05 mm, point 13
    /// 3 mm off along x; and the parameters a position fit in a known frame identifies.
    fn one_gross_point(nominal: &Robot, arm: &Robot) -> (Measurements, Vec<Param>) {
        let mut g = stream(5, "diag-test");
        let qs = crate::robot::sampling::uniform_joint_poses(nominal, 40, &mut g);
        let mut points: Vec<Vec3> = qs
            .iter()
            .enumerate()
            .map(|(i, q)| {
                let n = 0.01 * ((i * 7 % 11) as Real - 5.0);
                arm.fk(q).pos + Vec3::new(n, -n, 0.5 * n)
            })
            .collect();
        points[13] += Vec3::new(3.0, 0.0, 0.0);
        let data = Measurements {
            qs,
            points,
            ..Default::default()
        };
        let params = crate::robot::param_sets::identified_params_tool_first(
            nominal,
            Measure::Position,
            false,
        );
        (data, params)
    }

    /// `data` calibrated by `method` in a known frame, and its diagnostics at orientation
    /// weight `k` with the fit without its most influential point ([`diagnose`]).
    fn fit_and_diagnose(
        nominal: &Robot,
        params: &[Param],
        data: &Measurements,
        method: &crate::identify::MethodSpec,
        k: Real,
    ) -> (Calibrated, Diagnostics, Option<LeftOut>) {
        let frame = crate::numeric::Frame::identity();
        let c = calibrate(
            nominal,
            params,
            data,
            Registration::Known,
            &frame,
            method,
            &mut stream(0, "identify"),
        )
        .unwrap();
        let d = diagnose(&Subject {
            nominal,
            params,
            data,
            calibrated: &c,
            k,
            priors: &[],
            validation: None,
        })
        .unwrap();
        (c, d.0, d.1)
    }

    /// The fit without its most influential point, from one fit, against the fit without
    /// it: 40 noisy poses of an arm with errors, one of them 3 mm off, fitted by `ls` in a
    /// known frame. The first-order values agree with the refit to a few per cent of its
    /// residuals (the model is not linear in its parameters): the gross point's distance from
    /// the others' fit, which the fit of all shrinks, and every other point's residual.
    #[test]
    fn the_fit_without_the_most_influential_point_is_the_refit_without_it() {
        let nominal = crate::robot::builtin::load("irb2600").unwrap();
        let truth = nominal.with_errors(&[(Param::A(1), 0.4), (Param::D(3), -0.3)]);
        let (data, params) = one_gross_point(&nominal, &truth);
        let method = crate::identify::method_by_name("ls").unwrap();
        let (c, _, left_out) = fit_and_diagnose(&nominal, &params, &data, &method, 1.0);
        let left_out = left_out.unwrap();
        assert_eq!(left_out.point, 13);
        let mut without = data.clone();
        without.qs.remove(13);
        without.points.remove(13);
        let (refit, _, _) = fit_and_diagnose(&nominal, &params, &without, &method, 1.0);
        let residual =
            |c: &Calibrated, i: usize| (data.points[i] - c.robot.fk(&data.qs[i]).pos).norm();
        for i in 0..data.len() {
            let (got, want) = (left_out.residuals_mm[i], residual(&refit, i));
            assert!(
                (got - want).abs() <= 0.05 * want + 1e-3,
                "point {i}: {got} against {want}"
            );
        }
        let gross = left_out.residuals_mm[13];
        assert!(gross > 2.5 && residual(&c, 13) < gross, "{gross}");
        let others = left_out
            .residuals_mm
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != 13);
        assert!(others.clone().all(|(_, &r)| r < 0.1), "{left_out:?}");
    }

    /// IGG3 per coordinate on 40 poses with one coordinate moved by 2 mm: the leverage and
    /// Cook's distance of every point are those of the fit as it weighed the rows, built
    /// densely apart — leverage `trace(W_i J_i N⁻¹ J_iᵀ)`, Cook's distance from the refit
    /// without the point, `Δ = (N − J_iᵀ W_i J_i)⁻¹ J_iᵀ W_i r_i`, `Δᵀ N Δ / (t σ0²)` — the
    /// leverages sum to the parameters, and the bad point, whose bad coordinate the fit
    /// rejected, is not the most influential, as it would be at its mean weight 2/3.
    #[test]
    fn row_weights_give_the_fits_own_leverage_and_influence() {
        use crate::identify::MethodSpec;
        use crate::robot::Param;
        use rand::Rng as _;
        let params = [Param::A(1), Param::Theta(2), Param::D(3), Param::Alpha(2)];
        let (bad, axis) = (7, 1);
        let nominal = crate::robot::builtin::irb2600();
        let truth = nominal.with_errors(&[
            (params[0], 0.5),
            (params[1], 1e-3),
            (params[2], 0.3),
            (params[3], 5e-4),
        ]);
        let mut g = stream(5, "diag-rows");
        let qs = crate::robot::sampling::uniform_joint_poses(&nominal, 40, &mut g);
        let mut points: Vec<Vec3> = qs
            .iter()
            .map(|q| truth.fk(q).pos + Vec3::from_fn(|_, _| g.random_range(-0.005..0.005)))
            .collect();
        points[bad][axis] += 2.0;
        let data = Measurements {
            qs,
            points,
            ..Default::default()
        };
        let spec = MethodSpec::from_table(
            &toml::from_str("name = \"igg3\"\nxi = 0.0\nper = \"coordinate\"").unwrap(),
        )
        .unwrap();
        let frame = crate::numeric::Frame::identity();
        let (c, d, _) = fit_and_diagnose(&nominal, &params, &data, &spec, 1.0);
        let id = &c.identified;
        let w = id.row_weights.clone().expect("row weights");
        assert_eq!(w.iter().filter(|&&v| v == 0.0).count(), 1);
        assert_eq!(w[3 * bad + axis], 0.0);
        // The dense build.
        let problem = CalibrationProblem::new(&nominal, &params, &data, frame, 1.0);
        let rp = RobotProblem::of(&problem).unwrap();
        let (n_rows, t) = (rp.size().rows(), params.len());
        let (mut r, mut j) = (DVector::zeros(n_rows), DMatrix::zeros(n_rows, t));
        rp.evaluate(&id.x, &mut r, &mut j);
        let wj = DMatrix::from_fn(n_rows, t, |i, k| w[i] * j[(i, k)]);
        let n = j.transpose() * &wj;
        assert!((&n - &id.normal).amax() <= 1e-6 * n.amax());
        let n_inv = n.clone().try_inverse().unwrap();
        let s0sq = id.sigma0 * id.sigma0;
        let cook_at = |i: usize, weights: &[Real]| -> Real {
            let ji = j.rows(3 * i, 3).into_owned();
            let wi = DMatrix::from_diagonal(&DVector::from_row_slice(&weights[3 * i..3 * i + 3]));
            let ri = r.rows(3 * i, 3).into_owned();
            let jw = ji.transpose() * &wi;
            let delta = (&n - &jw * &ji).try_inverse().unwrap() * (jw * ri);
            (delta.transpose() * &n * &delta)[(0, 0)] / (t as Real * s0sq)
        };
        for i in 0..data.len() {
            let ji = j.rows(3 * i, 3);
            let mut h = 0.0;
            for k in 0..3 {
                h += w[3 * i + k] * (ji.row(k) * &n_inv * ji.row(k).transpose())[(0, 0)];
            }
            assert!(
                (d.leverage[i] - h).abs() <= 1e-6 * h.abs().max(1e-6),
                "point {i}"
            );
            let cook = cook_at(i, &w);
            assert!(
                (d.cook_distance[i] - cook).abs() <= 1e-6 * cook.abs().max(1e-9),
                "point {i}: {} against {cook}",
                d.cook_distance[i]
            );
        }
        let sum: Real = d.leverage.iter().sum();
        assert!((sum - t as Real).abs() < 1e-6, "{sum}");
        assert_ne!(d.top_points[0].row, bad);
        // At its mean weight the bad point, its 2 mm included, would lead the influence.
        let mean: Vec<Real> = w
            .iter()
            .enumerate()
            .map(|(k, _)| if k / 3 == bad { 2.0 / 3.0 } else { 1.0 })
            .collect();
        let most = (0..data.len())
            .max_by(|&a, &b| cook_at(a, &mean).total_cmp(&cook_at(b, &mean)))
            .unwrap();
        assert_eq!(most, bad);
    }
}
