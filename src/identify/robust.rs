//! IGG3 robust ridge estimation (Li 2018 §2.2, eqs. 15–18), with Huber and Tukey weights as
//! comparisons.
//!
//! Iteratively reweighted ridge, in one Gauss–Newton loop ([`super::solver`]): the ridge
//! iterations of [`super::ridge`] first run with all points at weight 1 (Li: "第 1 次求解时 P 为
//! 单位权") until the step falls below 0.1; then every iteration gives each point the
//! equivalent weight `p̄_i = p_i ψ(v_i)/v_i` (eq. 16, prior `p_i = 1`) from its residual `v_i`
//! at the current estimate (eq. 15) and takes one step, until the weights have settled (the
//! same points rejected as in the round before, after at least two rounds). A final refit
//! then gives every point the reweighting kept its prior weight and
//! the rejected ones (weight 0, `u > k1`) none, and iterates to `max |dx| < ε`: the robust
//! weights find the gross errors and the estimate is the efficient (least-squares) one on the
//! other points (Hampel et al. 1986 §1.4; Rousseeuw & Leroy 1987 ch. 1 — see
//! [`super::solver`]). On clean data this matches LS, which IGG3's down-weighting of the
//! suspicious band alone does not (about 8 % higher validation RMS).
//!
//! The weight of a point follows from its standardised residual `u_i = |v_i| / (σ0 √r)`:
//! `|v_i|` is the norm of its r = 3 (or 6) residual rows, so `u_i` is the RMS of the point's
//! rows in units of σ0 (about 1 for a normal point). σ0 is either
//! - [`crate::identify::Sigma0::Classical`]: Li's `σ0 = sqrt(vᵀPv / (n − t))` with the weights of the
//!   previous iteration, where n counts each row with its weight, `n = r Σ_i p̄_i` (with n
//!   the plain row count, down-weighted points keep their share of the redundancy while
//!   their residuals leave `vᵀPv`, and σ0 shrinks from one reweighting to the next until
//!   good points are rejected too); or
//! - [`crate::identify::Sigma0::Mad`]: `1.4826 · median |v_k|` over all residual rows (zero-centred MAD).
//!
//! When σ0 falls below `1e-9` times the RMS point residual at the start, or to the rounding
//! floor of the data ([`super::solver::LeastSquares::rounding_floor`]; consistent,
//! noise-free data, also from a start at the truth), every point keeps its weight: its prior
//! weight in the first round, and after a round that rejected gross errors, the weights of
//! that round (the kept points then fit exactly).
//!
//! With `per = "coordinate"` ([`Per::Coordinate`]) every residual row is weighed on its
//! own, as Li weighs each observation (eq. 16): the same three phases run on the problem
//! seen row by row (`Rows`), so `u_k = |v_k| / σ0` for row `k`, σ0 counts rows, and the
//! final refit keeps or rejects single rows; a point with one gross coordinate keeps its
//! other rows. The solution's `weights` are then each point's mean over its rows.
//!
//! Weight functions ([`crate::identify::WeightFn`]):
//! - IGG3 (Li eq. 18): `1` for `u ≤ k0`; `(k0/u)·((k1 − u)/(k1 − k0))²` for `k0 < u ≤ k1`;
//!   `0` for `u > k1`. The paper's text gives `k0 = 1.5`, `k1 = 2.4` (garbled); the defaults
//!   are `k0 = 1.5`, `k1 = 2.5`, both settable.
//! - Huber: `1` for `u ≤ k0`, `k0/u` beyond.
//! - Tukey's biweight with cut-off `c = k1`: `(1 − (u/c)²)²` for `u < c`, `0` beyond.

use nalgebra::DVector;
use serde::Deserialize;

use super::options;
use super::ridge::RidgeOptions;
use super::solver::{gauss_newton, Column, LeastSquares, Matrix, Size, Solver};
use super::weights::{Per, Robustness};
use super::Identified;
use crate::error::Result;
use crate::numeric::Real;

/// Options of `igg3` (docs/formats.md `[[methods]]`): the ridge's options (`xi`, `scale`, `eps`,
/// `max_iter`; here with an iteration limit of 200 over all phases) and the robust weights.
/// Read from one table: the keys [`Robustness`] declares go to `robust`, every other key to
/// `ridge`.
#[derive(Clone, Debug)]
pub struct RobustOptions {
    /// The ridge iterations.
    pub ridge: RidgeOptions,
    /// The weights.
    pub robust: Robustness,
}

impl Default for RobustOptions {
    fn default() -> Self {
        RobustOptions {
            ridge: RidgeOptions {
                max_iter: 200,
                ..Default::default()
            },
            robust: Robustness::default(),
        }
    }
}

impl<'de> Deserialize<'de> for RobustOptions {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let mut ridge = toml::Table::deserialize(d)?;
        let robust = options::split::<Robustness>(&mut ridge);
        Ok(RobustOptions {
            ridge: options::with_defaults(&RobustOptions::default().ridge, ridge).map_err(|e| {
                D::Error::custom(options::with_taken(e, &[options::fields::<Robustness>()]))
            })?,
            robust: Robustness::deserialize(toml::Value::Table(robust))
                .map_err(D::Error::custom)?,
        })
    }
}

impl Solver for RobustOptions {
    fn tolerates_rank_deficiency(&self) -> bool {
        true
    }

    fn check(&self) -> Result<()> {
        self.robust.check()?;
        self.ridge.check()
    }

    fn run(&self, p: &dyn LeastSquares, x0: &DVector<Real>) -> Identified {
        self.run_from(p, (x0, x0))
    }

    fn run_from(&self, p: &dyn LeastSquares, from: (&Column, &Column)) -> Identified {
        let r = &self.ridge;
        match self.robust.per {
            Per::Point => gauss_newton(
                p,
                from,
                r.eps,
                r.max_iter,
                Some(r.cfg()),
                Some(&self.robust),
            ),
            Per::Coordinate => {
                let rows = Rows::of(p);
                let out = gauss_newton(
                    &rows,
                    from,
                    r.eps,
                    r.max_iter,
                    Some(r.cfg()),
                    Some(&self.robust),
                );
                rows.per_point(out)
            }
        }
    }
}

/// A problem seen row by row: every residual row of `inner` is a point of one row, so that
/// the robust weights, σ0 and the refit's rejection of [`gauss_newton`] act on each coordinate
/// on its own (`per = "coordinate"`, Li 2018 eq. 16). The residual, the Jacobian and the
/// normal equations are those of `inner`, in the same order.
struct Rows<'a> {
    inner: &'a dyn LeastSquares,
    /// Rows per point of `inner`.
    rows: usize,
    /// The prior weight of each row: its point's.
    prior: Option<Vec<Real>>,
}

impl<'a> Rows<'a> {
    fn of(inner: &'a dyn LeastSquares) -> Rows<'a> {
        let rows = inner.size().rows_per_point;
        let prior = inner.prior().map(|p| {
            p.iter()
                .flat_map(|&w| std::iter::repeat_n(w, rows))
                .collect()
        });
        Rows { inner, rows, prior }
    }

    /// The solution as one of `inner`: each point's weight is the mean of its rows' weights
    /// (1 when every row kept its weight, 0 when every row was rejected), the rows' own
    /// weights are kept ([`Identified::row_weights`]: what the fit weighed each row by), and
    /// the RMS residual is per point again.
    fn per_point(&self, mut out: Identified) -> Identified {
        let r = self.rows.max(1);
        let rows = std::mem::take(&mut out.weights);
        out.weights = rows
            .chunks(r)
            .map(|c| c.iter().sum::<Real>() / r as Real)
            .collect();
        out.row_weights = Some(rows);
        out.rms_residual *= (r as Real).sqrt();
        out
    }
}

impl LeastSquares for Rows<'_> {
    fn size(&self) -> Size {
        let s = self.inner.size();
        Size::new(s.params, s.rows(), 1)
    }

    fn prior(&self) -> Option<&[Real]> {
        self.prior.as_deref()
    }

    fn evaluate(&self, x: &Column, r: &mut Column, j: &mut Matrix) {
        self.inner.evaluate(x, r, j);
    }

    fn tikhonov(&self) -> Option<&[Real]> {
        self.inner.tikhonov()
    }

    /// The inner problem's floor shared among a point's rows.
    fn rounding_floor(&self) -> Real {
        self.inner.rounding_floor() / self.rows.max(1) as Real
    }

    /// The inner problem's blocks, in rows: they start and end on its points.
    fn block_points(&self) -> Option<usize> {
        self.inner.block_points().map(|b| b * self.rows)
    }

    fn evaluate_points(&self, x: &Column, i: usize, r: &mut Column, j: &mut Matrix) {
        if i.is_multiple_of(self.rows) && r.len().is_multiple_of(self.rows) {
            self.inner.evaluate_points(x, i / self.rows, r, j);
        } else {
            // Not on a point's boundary (never with the blocks above): the whole problem.
            let size = self.inner.size();
            let mut rw = Column::zeros(size.rows());
            let mut jw = Matrix::zeros(size.rows(), size.params);
            self.inner.evaluate(x, &mut rw, &mut jw);
            r.copy_from(&rw.rows(i, r.len()));
            j.copy_from(&jw.rows(i, r.len()));
        }
    }
}
