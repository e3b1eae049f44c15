//! Registration of the tracker frame to the robot base (Ban eqs. 12–25).
//!
//! Given the nominal target points `b_i` in the robot base frame and the measured points
//! `a_i` in the tracker frame, find the rigid transform `(R, t)` minimising
//! `Σ w_i |R a_i + t − b_i|²` (Ban eq. 12). With weighted centroids `ā`, `b̄` (eqs. 13–15)
//! and `H = Σ w_i (a_i − ā)(b_i − b̄)ᵀ = A W Bᵀ` (eq. 17), the SVD `H = U Λ Vᵀ` (eq. 18)
//! gives `R = V Uᵀ` (eq. 20) and `t = b̄ − R ā` (eq. 21) — Kabsch's / Arun's solution. When
//! `det(V Uᵀ) = −1` (a reflection, which noisy or planar data can produce) the last column
//! of `V` is negated, the proper rotation closest to the reflection (Umeyama's correction,
//! not in Ban).
//!
//! Ban's weighted SVD (eqs. 22–25) first fits with equal weights (`W = I`), takes each
//! point's position error `e_i = |R a_i + t − b_i|` (eq. 22) and their mean `ē` (eq. 23),
//! sets weights that fall with the error (eq. 24), normalises them (eq. 25) and fits again.
//! The extracted text of the paper has lost the formulas of eqs. 22–25; what is implemented
//! is the reading of the surrounding prose: eq. 22 and 23 as written above, and for eq. 24
//! the weight `w_i = 1` for `e_i ≤ ē` and `w_i = (ē / e_i)²` above the mean (points with a
//! larger-than-average error lose weight, the more the larger the error), and for eq. 25 the
//! normalisation `w_i ← m · w_i / Σ w_j` (mean weight 1; the fit itself does not depend on
//! the scale of W).

use nalgebra::Matrix3;

use crate::error::{Error, Result};
use crate::numeric::{Frame, Real, Vec3};

/// The result of a registration.
#[derive(Clone, Debug, PartialEq)]
pub struct Registration {
    /// The transform mapping measured (tracker) coordinates to base coordinates:
    /// `b ≈ frame.apply(a)`. Its inverse is the tracker pose in the base frame.
    pub frame: Frame,
    /// Per point `|frame · a_i − b_i|`, mm.
    pub residuals: Vec<Real>,
    /// The weights used in the (last) fit, normalised to mean 1.
    pub weights: Vec<Real>,
}

impl Registration {
    /// `frame` with its residual at each point and the `weights` it was fitted with.
    fn of(frame: Frame, base: &[Vec3], measured: &[Vec3], weights: Vec<Real>) -> Registration {
        let residuals = measured
            .iter()
            .zip(base)
            .map(|(a, b)| (frame.apply(a) - b).norm())
            .collect();
        Registration {
            frame,
            residuals,
            weights,
        }
    }
}

/// Rigid registration by SVD (Kabsch/Arun; Ban eqs. 12–21) with the reflection fix:
/// `base[i] ≈ frame.apply(measured[i])`. `weights` (non-negative, not all zero) default to
/// 1. Refuses fewer than 3 points, mismatched lengths, non-finite input and collinear points.
pub fn register_svd(
    base: &[Vec3],
    measured: &[Vec3],
    weights: Option<&[Real]>,
) -> Result<Registration> {
    let m = base.len();
    if measured.len() != m {
        return Err(Error::Compute(format!(
            "registration: {m} base points but {} measured points",
            measured.len()
        )));
    }
    if m < 3 {
        return Err(Error::Singular(format!(
            "registration needs at least 3 points, got {m}"
        )));
    }
    if base
        .iter()
        .chain(measured)
        .any(|p| !p.iter().all(|v| v.is_finite()))
    {
        return Err(Error::Compute("registration: a point is not finite".into()));
    }
    let w: Vec<Real> = match weights {
        Some(w) => {
            if w.len() != m {
                return Err(Error::Compute(format!(
                    "registration: {m} points but {} weights",
                    w.len()
                )));
            }
            check_weights(w)?;
            let s: Real = w.iter().sum();
            if s <= 0.0 {
                return Err(Error::Singular("registration: all weights are zero".into()));
            }
            w.iter().map(|v| v * m as Real / s).collect()
        }
        None => vec![1.0; m],
    };
    let sw: Real = w.iter().sum();
    let mut ca = Vec3::zeros();
    let mut cb = Vec3::zeros();
    for i in 0..m {
        ca += measured[i] * w[i];
        cb += base[i] * w[i];
    }
    ca /= sw;
    cb /= sw;
    let mut h = Matrix3::zeros();
    for i in 0..m {
        h += (measured[i] - ca) * (base[i] - cb).transpose() * w[i];
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Err(Error::Singular("registration: SVD failed".into()));
    };
    // Singular values are sorted in decreasing order by nalgebra.
    let s = svd.singular_values;
    if s[1].is_nan() || s[1] <= 1e-12 * s[0].max(Real::MIN_POSITIVE) {
        return Err(Error::Singular(collinear(base, cb, measured, ca, &w)));
    }
    let mut v = vt.transpose();
    if (v * u.transpose()).determinant() < 0.0 {
        let mut c = v.column_mut(2);
        c.neg_mut();
    }
    let rot = v * u.transpose();
    let frame = Frame {
        rot,
        pos: cb - rot * ca,
    };
    Ok(Registration::of(frame, base, measured, w))
}

/// Which of the two point sets leaves the rotation undetermined, in words: a set of points on
/// one line, or at one point, spreads in fewer than two directions about its centroid `c`
/// (the second singular value of its weighted scatter below 1e-12 of the first, as
/// [`register_svd`] tests `H`). The base points are the model's: a robot of no length puts
/// every pose's point at one place, which the data are not to blame for.
fn collinear(base: &[Vec3], cb: Vec3, measured: &[Vec3], ca: Vec3, w: &[Real]) -> String {
    let flat = |points: &[Vec3], c: Vec3| {
        let scatter = (points.iter().zip(w)).fold(Matrix3::zeros(), |s, (p, w)| {
            s + (p - c) * (p - c).transpose() * *w
        });
        let v = scatter.symmetric_eigenvalues();
        let (hi, mid) = (v.max(), v.sum() - v.max() - v.min());
        hi <= 0.0 || mid <= 1e-24 * hi
    };
    let model = "the model's points (the robot's at these joint values) are (nearly) collinear: \
                 its lengths and offsets put every pose's point on one line or at one place, \
                 whatever was measured";
    match (flat(base, cb), flat(measured, ca)) {
        (true, true) => format!("registration: {model}, and so are the measured points"),
        (true, false) => format!("registration: {model}"),
        _ => "registration: the measured points are (nearly) collinear; the rotation is \
              undetermined"
            .into(),
    }
}

/// Ban's weighted-SVD registration (eqs. 12–25): an equal-weight fit, weights from each
/// point's residual (`1` up to the mean residual `ē`, `(ē/e_i)²` above it — see the module
/// docs for why this form), normalised to mean 1, and a second fit with those weights.
pub fn register_wsvd(base: &[Vec3], measured: &[Vec3]) -> Result<Registration> {
    let first = register_svd(base, measured, None)?;
    let w = ban_weights(&first.residuals);
    register_svd(base, measured, Some(&w))
}

/// A rigid refinement stops when its step moves no measured point by more than this (mm), ...
pub const ROWS_TOLERANCE_MM: Real = 1e-10;
/// ... or after this many Gauss–Newton steps.
pub const ROWS_MAX_STEPS: usize = 50;

/// Rigid registration with a weight per coordinate: the `(R, t)` minimising
/// `Σ_i Σ_c w_ic ((R a_i + t − b_i)_c)²`, `c` the base frame's x, y and z (the rows of the
/// identification's residual, which is formed in the base frame). `row_weights` holds
/// `rows ≥ 3` weights per point, point after point, of which the first three are x, y, z (the
/// orientation rows of a full pose, when `rows = 6`, do not enter a point registration).
///
/// When every point's three weights are equal this is [`register_svd`] with those weights,
/// to the bit. Otherwise the cost has no closed-form minimiser (Kabsch's solution needs one
/// weight per point), and Gauss–Newton on the six rigid coordinates refines the SVD solution
/// with each point's mean weight: each step `R ← exp([φ]×) R`, rotating about the weighted
/// centroid `c`, and `t` moved by `τ` solves the 6 × 6 normal equations of the residuals
/// linearised as `e_i + φ × (R a_i + t − c) + τ`; a step that does not lower the cost is
/// halved, and the steps stop when one moves no point by more than [`ROWS_TOLERANCE_MM`]
/// (`|τ| + |φ| max_i |R a_i + t − c|`), when halving cannot lower the cost (its change is
/// below rounding), or after [`ROWS_MAX_STEPS`] steps. Each step allocates nothing.
/// `weights` of the result are each point's mean over its three weights, normalised to mean 1.
pub fn register_rows(
    base: &[Vec3],
    measured: &[Vec3],
    row_weights: &[Real],
    rows: usize,
) -> Result<Registration> {
    let m = base.len();
    if rows < 3 || row_weights.len() != m * rows {
        return Err(Error::Compute(format!(
            "registration: {m} points but {} row weights at {rows} rows a point",
            row_weights.len()
        )));
    }
    check_weights(row_weights)?;
    let xyz = |i: usize| -> [Real; 3] {
        let r = &row_weights[i * rows..i * rows + 3];
        [r[0], r[1], r[2]]
    };
    let isotropic = (0..m).all(|i| {
        let w = xyz(i);
        w[0] == w[1] && w[1] == w[2]
    });
    let point: Vec<Real> = (0..m)
        .map(|i| {
            let w = xyz(i);
            if isotropic {
                w[0]
            } else {
                (w[0] + w[1] + w[2]) / 3.0
            }
        })
        .collect();
    let start = register_svd(base, measured, Some(&point))?;
    if isotropic {
        return Ok(start);
    }
    let frame = refine(base, measured, &xyz, start.frame)?;
    Ok(Registration::of(frame, base, measured, start.weights))
}

/// The weighted cost `Σ_i Σ_c w_ic ((R a_i + t − b_i)_c)²` of `frame`.
fn rows_cost(
    base: &[Vec3],
    measured: &[Vec3],
    w: &impl Fn(usize) -> [Real; 3],
    frame: &Frame,
) -> Real {
    let mut cost = 0.0;
    for (i, (a, b)) in measured.iter().zip(base).enumerate() {
        let (e, wi) = (frame.apply(a) - b, w(i));
        cost += wi[0] * e.x * e.x + wi[1] * e.y * e.y + wi[2] * e.z * e.z;
    }
    cost
}

/// Gauss–Newton on the six rigid coordinates from `frame` ([`register_rows`]).
fn refine(
    base: &[Vec3],
    measured: &[Vec3],
    w: &impl Fn(usize) -> [Real; 3],
    mut frame: Frame,
) -> Result<Frame> {
    use nalgebra::{Matrix6, Rotation3, Vector6};
    let mut cost = rows_cost(base, measured, w, &frame);
    for _ in 0..ROWS_MAX_STEPS {
        // The rotation's centre: the weighted centroid of the registered points.
        let (mut c, mut sw) = (Vec3::zeros(), 0.0);
        for (i, a) in measured.iter().enumerate() {
            let wi = w(i);
            let p = frame.apply(a);
            for k in 0..3 {
                c[k] += wi[k] * p[k];
                sw += wi[k];
            }
        }
        c *= 3.0 / sw.max(Real::MIN_POSITIVE);
        let mut n = Matrix6::<Real>::zeros();
        let mut g = Vector6::<Real>::zeros();
        let mut reach: Real = 0.0;
        for (i, (a, b)) in measured.iter().zip(base).enumerate() {
            let wi = w(i);
            let p = frame.apply(a);
            let q = p - c;
            let e = p - b;
            reach = reach.max(q.norm());
            // Row k of the point's Jacobian: e moves by φ × q + τ, so ∂e_k/∂φ is row k of
            // −[q]× and ∂e_k/∂τ the unit vector k.
            let rows = [
                [0.0, q.z, -q.y, 1.0, 0.0, 0.0],
                [-q.z, 0.0, q.x, 0.0, 1.0, 0.0],
                [q.y, -q.x, 0.0, 0.0, 0.0, 1.0],
            ];
            for k in 0..3 {
                if wi[k] == 0.0 {
                    continue;
                }
                let jk = Vector6::from_row_slice(&rows[k]);
                n += jk * jk.transpose() * wi[k];
                g += jk * (wi[k] * e[k]);
            }
        }
        let Some(ch) = n.cholesky() else {
            return Err(Error::Singular(
                "registration: the weighted coordinates do not determine the frame".into(),
            ));
        };
        let mut step = -ch.solve(&g);
        let mut next = None;
        for _ in 0..30 {
            let phi = Vec3::new(step[0], step[1], step[2]);
            let tau = Vec3::new(step[3], step[4], step[5]);
            let turn = Rotation3::new(phi).into_inner();
            let trial = Frame {
                rot: turn * frame.rot,
                pos: turn * (frame.pos - c) + c + tau,
            };
            let trial_cost = rows_cost(base, measured, w, &trial);
            if trial_cost <= cost {
                next = Some((trial, trial_cost, tau.norm() + phi.norm() * reach));
                break;
            }
            step *= 0.5;
        }
        let Some((trial, trial_cost, moved)) = next else {
            break;
        };
        frame = trial;
        cost = trial_cost;
        if moved <= ROWS_TOLERANCE_MM {
            break;
        }
    }
    Ok(frame)
}

/// The weights of Ban eqs. 23–25 from the residuals of the equal-weight fit.
fn ban_weights(e: &[Real]) -> Vec<Real> {
    let m = e.len() as Real;
    let mean = e.iter().sum::<Real>() / m;
    let w: Vec<Real> = e
        .iter()
        .map(|&ei| if ei <= mean { 1.0 } else { (mean / ei).powi(2) })
        .collect();
    let s: Real = w.iter().sum();
    w.iter().map(|v| v * m / s).collect()
}

/// Refuses weights that are not finite or are negative.
fn check_weights(w: &[Real]) -> Result<()> {
    if w.iter().any(|v| !v.is_finite() || *v < 0.0) {
        return Err(Error::Compute(
            "registration: weights must be finite and ≥ 0".into(),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::stream;
    use approx::assert_relative_eq;
    use rand::Rng as _;

    fn known() -> Frame {
        Frame::from_xyz_rpy([2500.0, 300.0, 400.0], [0.2, -0.4, 2.9])
    }

    fn cloud(n: usize, seed: u64) -> Vec<Vec3> {
        let mut rng = stream(seed, "cloud");
        (0..n)
            .map(|_| {
                Vec3::new(
                    rng.random_range(-1000.0..1000.0),
                    rng.random_range(-1000.0..1000.0),
                    rng.random_range(0.0..1500.0),
                )
            })
            .collect()
    }

    #[test]
    fn recovers_a_known_transform_exactly() {
        let f = known();
        let base = cloud(30, 1);
        let measured: Vec<Vec3> = base.iter().map(|b| f.apply_inverse(b)).collect();
        for r in [
            register_svd(&base, &measured, None).unwrap(),
            register_wsvd(&base, &measured).unwrap(),
        ] {
            assert_relative_eq!(r.frame.rot, f.rot, epsilon = 1e-9);
            assert_relative_eq!(r.frame.pos, f.pos, epsilon = 1e-9);
            assert!(r.residuals.iter().all(|e| *e < 1e-9));
        }
    }

    /// Coplanar points (a degenerate direction: `det(V Uᵀ)` can come out −1) and a
    /// mirrored point set: the result is always a proper rotation, and for the coplanar
    /// set the exact one.
    #[test]
    fn reflection_prone_data_give_a_rotation() {
        let f = known();
        // Coplanar: all on the plane z = 100 of the base frame.
        let base: Vec<Vec3> = cloud(12, 2)
            .iter()
            .map(|p| Vec3::new(p.x, p.y, 100.0))
            .collect();
        let measured: Vec<Vec3> = base.iter().map(|b| f.apply_inverse(b)).collect();
        let r = register_svd(&base, &measured, None).unwrap();
        assert_relative_eq!(r.frame.rot.determinant(), 1.0, epsilon = 1e-12);
        assert_relative_eq!(r.frame.rot, f.rot, epsilon = 1e-9);
        assert_relative_eq!(r.frame.pos, f.pos, epsilon = 1e-9);
        // Three points: the smallest data set, plane through all of them.
        let r = register_svd(&base[..3], &measured[..3], None).unwrap();
        assert_relative_eq!(r.frame.rot, f.rot, epsilon = 1e-9);
        // A mirror image cannot be reached by a rotation: the fix must keep det = +1.
        let base = cloud(20, 3);
        let mirror: Vec<Vec3> = base.iter().map(|p| Vec3::new(-p.x, p.y, p.z)).collect();
        let r = register_svd(&base, &mirror, None).unwrap();
        assert_relative_eq!(r.frame.rot.determinant(), 1.0, epsilon = 1e-12);
        assert_relative_eq!(
            r.frame.rot * r.frame.rot.transpose(),
            Matrix3::identity(),
            epsilon = 1e-12
        );
    }

    #[test]
    fn bad_input_is_refused() {
        let a = cloud(5, 4);
        assert!(register_svd(&a, &a[..4], None).is_err());
        assert!(register_svd(&a[..2], &a[..2], None).is_err());
        let line: Vec<Vec3> = (0..5)
            .map(|i| Vec3::new(i as Real, 2.0 * i as Real, 0.0))
            .collect();
        assert!(register_svd(&line, &line, None).is_err());
        // The refusal names the set that is collinear: a robot of no length puts every
        // model point at one place, and the measured points are then not to blame.
        let said = |base: &[Vec3], measured: &[Vec3]| {
            register_svd(base, measured, None).unwrap_err().to_string()
        };
        let one_place = vec![Vec3::new(1.0, 2.0, 3.0); 5];
        let model = "the model's points (the robot's at these joint values) are (nearly) collinear";
        assert!(
            said(&one_place, &a).contains(model),
            "{}",
            said(&one_place, &a)
        );
        assert!(!said(&one_place, &a).contains("measured points"));
        assert!(said(&line, &a).contains(model));
        assert!(said(&a, &line).contains("the measured points are (nearly) collinear"));
        assert!(said(&line, &line).contains("and so are the measured points"));
        assert!(register_svd(&a, &a, Some(&[0.0; 5])).is_err());
        assert!(register_svd(&a, &a, Some(&[1.0, -1.0, 1.0, 1.0, 1.0])).is_err());
        let mut nan = a.clone();
        nan[0].x = Real::NAN;
        assert!(register_wsvd(&a, &nan).is_err());
    }

    #[test]
    fn weights_select_the_fit() {
        // Zero weight on a displaced point: the fit ignores it exactly.
        let f = known();
        let base = cloud(10, 5);
        let mut measured: Vec<Vec3> = base.iter().map(|b| f.apply_inverse(b)).collect();
        measured[3] += Vec3::new(5.0, -3.0, 1.0);
        let mut w = vec![1.0; 10];
        w[3] = 0.0;
        let r = register_svd(&base, &measured, Some(&w)).unwrap();
        assert_relative_eq!(r.frame.pos, f.pos, epsilon = 1e-9);
        assert_relative_eq!(r.weights.iter().sum::<Real>(), 10.0, epsilon = 1e-12);
    }

    /// Noisy points (±0.05 mm per coordinate) of the known transform.
    fn noisy(n: usize, seed: u64) -> (Vec<Vec3>, Vec<Vec3>) {
        let f = known();
        let base = cloud(n, seed);
        let mut rng = stream(seed, "noise");
        let measured = base
            .iter()
            .map(|b| {
                let d = Vec3::new(
                    rng.random_range(-0.05..0.05),
                    rng.random_range(-0.05..0.05),
                    rng.random_range(-0.05..0.05),
                );
                f.apply_inverse(b) + d
            })
            .collect();
        (base, measured)
    }

    fn random_rows(n: usize, rows: usize, seed: u64) -> Vec<Real> {
        let mut rng = stream(seed, "row-weights");
        (0..n * rows).map(|_| rng.random_range(0.0..1.0)).collect()
    }

    fn frames_close(a: &Frame, b: &Frame, rot: Real, pos: Real) -> bool {
        (a.rot - b.rot).amax() <= rot && (a.pos - b.pos).amax() <= pos
    }

    /// Equal weights in every point's three rows: the SVD with those weights, to the bit
    /// (rows 4–6 of a full pose do not count); and the Gauss–Newton refinement itself,
    /// started 2 mm and 1 mrad away, comes back to the SVD's frame within 1e-12.
    #[test]
    fn equal_weights_per_point_give_the_svd() {
        let (base, measured) = noisy(25, 6);
        let mut rng = stream(6, "point-weights");
        let point: Vec<Real> = (0..25).map(|_| rng.random_range(0.1..2.0)).collect();
        let svd = register_svd(&base, &measured, Some(&point)).unwrap();
        for rows in [3, 6] {
            let w: Vec<Real> = point
                .iter()
                .flat_map(|&p| (0..rows).map(move |k| if k < 3 { p } else { 7.0 * k as Real }))
                .collect();
            assert_eq!(register_rows(&base, &measured, &w, rows).unwrap(), svd);
        }
        let off = Frame {
            rot: nalgebra::Rotation3::new(Vec3::new(1e-3, -5e-4, 2e-4)).into_inner()
                * svd.frame.rot,
            pos: svd.frame.pos + Vec3::new(2.0, -1.0, 0.5),
        };
        let xyz = |i: usize| [point[i]; 3];
        let refined = refine(&base, &measured, &xyz, off).unwrap();
        assert!(
            frames_close(&refined, &svd.frame, 1e-12, 1e-12 * svd.frame.pos.amax()),
            "{refined:?} against {:?}",
            svd.frame
        );
    }

    /// Noise-free points: any weights per coordinate give the transform back exactly.
    #[test]
    fn a_noise_free_transform_is_recovered_with_anisotropic_weights() {
        let f = known();
        let base = cloud(20, 7);
        let measured: Vec<Vec3> = base.iter().map(|b| f.apply_inverse(b)).collect();
        for seed in 0..5 {
            let w = random_rows(20, 3, seed);
            let r = register_rows(&base, &measured, &w, 3).unwrap();
            assert!(frames_close(&r.frame, &f, 1e-12, 1e-9), "seed {seed}");
            assert!(r.residuals.iter().all(|e| *e < 1e-9));
        }
    }

    /// At the solution on noisy data the weighted cost is stationary: its gradient by central
    /// differences along each of the six rigid coordinates (rotations about the base axes
    /// through the origin, translations) is zero to the differences' accuracy, where the
    /// point-mean-weight SVD's is not; and the cost is below the SVD's.
    #[test]
    fn the_weighted_cost_is_stationary_at_the_solution() {
        let (base, measured) = noisy(30, 8);
        let w = random_rows(30, 3, 8);
        let xyz = |i: usize| [w[3 * i], w[3 * i + 1], w[3 * i + 2]];
        let cost = |f: &Frame| rows_cost(&base, &measured, &xyz, f);
        let gradient = |f: &Frame| -> [Real; 6] {
            let mut g = [0.0; 6];
            for (k, gk) in g.iter_mut().enumerate() {
                let moved = |h: Real| {
                    let mut v = [0.0; 6];
                    v[k] = h;
                    let turn = nalgebra::Rotation3::new(Vec3::new(v[0], v[1], v[2])).into_inner();
                    Frame {
                        rot: turn * f.rot,
                        pos: turn * f.pos + Vec3::new(v[3], v[4], v[5]),
                    }
                };
                // Steps of 1e-7 rad (≈ 0.3 mm at the points) and 1e-4 mm.
                let h = if k < 3 { 1e-7 } else { 1e-4 };
                *gk = (cost(&moved(h)) - cost(&moved(-h))) / (2.0 * h);
            }
            g
        };
        let r = register_rows(&base, &measured, &w, 3).unwrap();
        let point: Vec<Real> = (0..30).map(|i| xyz(i).iter().sum::<Real>() / 3.0).collect();
        let mean = register_svd(&base, &measured, Some(&point)).unwrap();
        let (g, g_mean) = (gradient(&r.frame), gradient(&mean.frame));
        // Scale: the gradient a 1 µm shift of every point would give, 2 Σw · |e| · 1e-3.
        let scale = 2.0 * w.iter().sum::<Real>() * 0.05 * 1e-3;
        for (k, gk) in g.iter().enumerate() {
            let lever = if k < 3 { 2500.0 } else { 1.0 };
            assert!(gk.abs() < 1e-3 * scale * lever, "coordinate {k}: {gk}");
        }
        assert!(
            (0..6).any(|k| g_mean[k].abs() > 10.0 * scale * if k < 3 { 2500.0 } else { 1.0 }),
            "{g_mean:?}"
        );
        assert!(cost(&r.frame) < cost(&mean.frame));
    }

    /// The frame of `measured` onto `base` on the coordinates `keep` (point, axis), by an
    /// independent dense Gauss–Newton: roll–pitch–yaw and translation as unknowns, the
    /// Jacobian by central differences, each step a least-squares solve (SVD) of all rows.
    fn dense_fit(base: &[Vec3], measured: &[Vec3], keep: &[(usize, usize)], from: &Frame) -> Frame {
        let frame = |x: &nalgebra::DVector<Real>| {
            Frame::from_xyz_rpy([x[0], x[1], x[2]], [x[3], x[4], x[5]])
        };
        let residual = |x: &nalgebra::DVector<Real>| {
            let f = frame(x);
            nalgebra::DVector::from_iterator(
                keep.len(),
                keep.iter()
                    .map(|&(i, c)| (f.apply(&measured[i]) - base[i])[c]),
            )
        };
        let (xyz, rpy) = from.to_xyz_rpy();
        let mut x = nalgebra::DVector::from_iterator(6, xyz.into_iter().chain(rpy));
        for _ in 0..20 {
            let e = residual(&x);
            let mut j = nalgebra::DMatrix::zeros(keep.len(), 6);
            for k in 0..6 {
                let h = if k < 3 { 1e-4 } else { 1e-7 };
                let (mut up, mut down) = (x.clone(), x.clone());
                up[k] += h;
                down[k] -= h;
                j.set_column(k, &((residual(&up) - residual(&down)) / (2.0 * h)));
            }
            let Some(Ok(step)) =
                crate::numeric::linalg::svd(j, true, true).map(|s| s.solve(&(-e), 1e-14))
            else {
                break;
            };
            x += step;
        }
        frame(&x)
    }

    /// One coordinate of one point moved by 2 mm and weighed 0: the fit is the fit without
    /// that coordinate (an independent dense solve), and not the fit weighing that point by
    /// its mean weight 2/3, which the 2 mm pull.
    #[test]
    fn a_zero_weight_coordinate_is_left_out() {
        let (base, mut measured) = noisy(20, 9);
        let bad = (4, 1);
        measured[bad.0][bad.1] += 2.0;
        let mut w = vec![1.0; 60];
        w[3 * bad.0 + bad.1] = 0.0;
        let r = register_rows(&base, &measured, &w, 3).unwrap();
        let keep: Vec<(usize, usize)> = (0..20)
            .flat_map(|i| (0..3).map(move |c| (i, c)))
            .filter(|&k| k != bad)
            .collect();
        let dense = dense_fit(&base, &measured, &keep, &known());
        assert!(
            frames_close(&r.frame, &dense, 1e-11, 1e-8),
            "{:?} against {dense:?}",
            r.frame
        );
        let mut point = vec![1.0; 20];
        point[bad.0] = 2.0 / 3.0;
        let mean = register_svd(&base, &measured, Some(&point)).unwrap();
        let moved = (0..20)
            .map(|i| (mean.frame.apply(&measured[i]) - r.frame.apply(&measured[i])).norm())
            .fold(0.0, Real::max);
        assert!(moved > 0.02, "{moved}");
        assert_relative_eq!(r.weights[bad.0] / r.weights[0], 2.0 / 3.0, epsilon = 1e-12);
    }
}
