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
            if w.iter().any(|v| !v.is_finite() || *v < 0.0) {
                return Err(Error::Compute(
                    "registration: weights must be finite and ≥ 0".into(),
                ));
            }
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
        return Err(Error::Singular(
            "registration: the points are (nearly) collinear; the rotation is undetermined".into(),
        ));
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
    let residuals = (0..m)
        .map(|i| (frame.apply(&measured[i]) - base[i]).norm())
        .collect();
    Ok(Registration {
        frame,
        residuals,
        weights: w,
    })
}

/// Ban's weighted-SVD registration (eqs. 12–25): an equal-weight fit, weights from each
/// point's residual (`1` up to the mean residual `ē`, `(ē/e_i)²` above it — see the module
/// docs for why this form), normalised to mean 1, and a second fit with those weights.
pub fn register_wsvd(base: &[Vec3], measured: &[Vec3]) -> Result<Registration> {
    let first = register_svd(base, measured, None)?;
    let w = ban_weights(&first.residuals);
    register_svd(base, measured, Some(&w))
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
}
