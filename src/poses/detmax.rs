//! DETMAX exchange (Guo 2024 §3.2, steps (1)–(3); Mitchell's DETMAX).
//!
//! From a start set of M candidates: (1) add the candidate (not in the set) that maximises
//! the objective of the M + 1 poses; (2) remove the pose of the M + 1 whose removal maximises
//! the objective of the remaining M; (3) if the removed pose is the one just added the
//! exchange rule fails and the search stops, otherwise the new set replaces the old and the
//! steps repeat. Removing the just-added pose restores the current set, so an exchange never
//! lowers the objective; an exchange is made only when it raises the objective by more than a
//! relative 1e-12 (so equal-valued sets cannot cycle).
//!
//! Cost: the Jacobian blocks of all candidates are computed once; the singular values of J are
//! sqrt(eig(JᵀJ)) of the small k × k Gram matrix instead of an SVD of the tall J. Each scan
//! (add, then remove) eigen-decomposes the Gram matrix of the current set once, JᵀJ = QΛQᵀ;
//! the spectrum of JᵀJ ± BᵀB for a candidate block B is then that of Λ ± WWᵀ, W = QᵀBᵀ,
//! found by `rows_per_pose` rank-1 secular-equation steps in O(k²) each ([`super::secular`])
//! instead of an O(k³) eigen-decomposition per candidate. The candidate scan runs on rayon and
//! reduces by (value, index) with ties to the lower index, so the result does not depend on the
//! thread count.

use nalgebra::DMatrix;
use rayon::prelude::*;

use super::secular::SpectrumUpdate;
use super::{objective_of_eigenvalues, objective_of_gram, Objective, PoseModel};
use crate::math::Real;

/// What [`detmax`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct DetmaxResult {
    /// Candidate indices of the chosen set.
    pub set: Vec<usize>,
    /// Objective of the start set, then after each exchange.
    pub trace: Vec<Real>,
    /// Number of exchanges made.
    pub exchanges: usize,
    /// Why the search stopped.
    pub termination: String,
}

/// Adds `s · BᵀB` of candidate `c` (rows `r·c .. r·c + r` of `blocks`) to `a`.
fn add_block(a: &mut DMatrix<Real>, blocks: &DMatrix<Real>, r: usize, c: usize, s: Real) {
    let b = blocks.rows(r * c, r);
    a.gemm_tr(s, &b, &b, 1.0);
}

/// Better of two (value, index) pairs: larger value, ties to the lower index.
fn better(x: (Real, usize), y: (Real, usize)) -> (Real, usize) {
    if x.0 > y.0 || (x.0 == y.0 && x.1 < y.1) {
        x
    } else {
        y
    }
}

/// The eigen-decomposition of a symmetric `a`: eigenvalues ascending, and Q with the matching
/// eigenvectors as columns.
fn sorted_eigen(a: &DMatrix<Real>) -> (Vec<Real>, DMatrix<Real>) {
    let k = a.nrows();
    let e = a.clone().symmetric_eigen();
    let mut idx: Vec<usize> = (0..k).collect();
    idx.sort_by(|&x, &y| e.eigenvalues[x].total_cmp(&e.eigenvalues[y]));
    let lam = idx.iter().map(|&i| e.eigenvalues[i]).collect();
    let q = DMatrix::from_fn(k, k, |r, c| e.eigenvectors[(r, idx[c])]);
    (lam, q)
}

/// Buffers of one rayon worker in a scan.
struct ScanBuf {
    upd: SpectrumUpdate,
    w: DMatrix<Real>,
    ev: Vec<Real>,
}

impl ScanBuf {
    fn new(k: usize, r: usize) -> Self {
        ScanBuf {
            upd: SpectrumUpdate::new(),
            w: DMatrix::zeros(k, r),
            ev: vec![0.0; k],
        }
    }

    /// The objective of QΛQᵀ + `sign`·BᵀB over `m` poses, for candidate `c` (Bᵀ = columns
    /// `r·c .. r·c + r` of `blocks_t`).
    #[allow(clippy::too_many_arguments)]
    fn value(
        &mut self,
        lam: &[Real],
        q: &DMatrix<Real>,
        blocks_t: &DMatrix<Real>,
        r: usize,
        c: usize,
        sign: Real,
        objective: Objective,
        m: usize,
    ) -> Real {
        self.w.gemm_tr(1.0, q, &blocks_t.columns(r * c, r), 0.0);
        self.upd
            .eigenvalues(lam, self.w.as_slice(), sign, &mut self.ev);
        objective_of_eigenvalues(&mut self.ev, objective, m)
    }
}

/// The Gram matrix JᵀJ of the candidates in `set`.
fn gram(blocks: &DMatrix<Real>, r: usize, set: &[usize], out: &mut DMatrix<Real>) {
    out.fill(0.0);
    for &c in set {
        add_block(out, blocks, r, c, 1.0);
    }
}

/// DETMAX from the candidate indices `start` (distinct, within `candidates`), maximising
/// `objective`, with at most `max_exchanges` exchanges (Guo 2024 §3.2).
pub fn detmax(
    model: &dyn PoseModel,
    candidates: &[Vec<Real>],
    start: Vec<usize>,
    objective: Objective,
    max_exchanges: usize,
) -> DetmaxResult {
    let (r, k) = (model.rows_per_pose(), model.n_params());
    let n = candidates.len();
    let mut blocks = DMatrix::zeros(r * n, k);
    for (i, q) in candidates.iter().enumerate() {
        let mut v = blocks.rows_mut(r * i, r);
        model.jacobian_block(q, &mut v);
    }
    let blocks = blocks;
    let blocks_t = blocks.transpose();
    let m = start.len();
    let mut set = start;
    let mut in_set = vec![false; n];
    for &c in &set {
        in_set[c] = true;
    }
    let mut a = DMatrix::zeros(k, k);
    gram(&blocks, r, &set, &mut a);
    let mut value = objective_of_gram(&a, objective, m);
    let mut trace = vec![value];
    let mut exchanges = 0;
    let termination = loop {
        if exchanges >= max_exchanges {
            break format!("detmax: {max_exchanges} exchanges (limit)");
        }
        // (1) Add the best candidate.
        let (lam, q) = sorted_eigen(&a);
        let (_, added) = (0..n)
            .into_par_iter()
            .filter(|&c| !in_set[c])
            .map_init(
                || ScanBuf::new(k, r),
                |buf, c| {
                    let v = buf.value(&lam, &q, &blocks_t, r, c, 1.0, objective, m + 1);
                    (v, c)
                },
            )
            .reduce(|| (Real::NEG_INFINITY, usize::MAX), better);
        if added == usize::MAX {
            break "detmax: no candidate left to add".to_string();
        }
        let mut a_plus = a.clone();
        add_block(&mut a_plus, &blocks, r, added, 1.0);
        // (2) Remove the pose whose removal leaves the best set; removing the one just
        // added restores the current set and its value exactly, and wins ties.
        let (lam, q) = sorted_eigen(&a_plus);
        let (best_other, removed_pos) = (0..m)
            .into_par_iter()
            .map_init(
                || ScanBuf::new(k, r),
                |buf, pos| {
                    let v = buf.value(&lam, &q, &blocks_t, r, set[pos], -1.0, objective, m);
                    (v, pos)
                },
            )
            .reduce(|| (Real::NEG_INFINITY, usize::MAX), better);
        // (3) The exchange rule.
        let improves = removed_pos != usize::MAX
            && best_other > value
            && best_other - value > 1e-12 * value.abs().max(1e-300);
        if !improves {
            break "detmax: exchange rule (the removed pose is the one just added)".to_string();
        }
        in_set[set[removed_pos]] = false;
        in_set[added] = true;
        set[removed_pos] = added;
        exchanges += 1;
        // Rebuild the Gram matrix from scratch: no drift from repeated add/subtract.
        gram(&blocks, r, &set, &mut a);
        value = objective_of_gram(&a, objective, m);
        trace.push(value);
    };
    DetmaxResult {
        set,
        trace,
        exchanges,
        termination,
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_models::TableModel;
    use super::super::{indices, Objective};
    use super::*;
    use crate::math::Real;

    /// Brute-force objective of a candidate subset via SVD of the stacked J.
    fn brute(model: &TableModel, set: &[usize], o: Objective) -> Real {
        let qs: Vec<Vec<Real>> = set.iter().map(|&i| vec![i as Real]).collect();
        let j = indices::stacked_jacobian(model, &qs);
        indices::objective_value(o, &indices::singular_values(&j), set.len())
    }

    #[test]
    fn hand_built_d_optimal_exchange() {
        // k = 2, one row per pose. Candidates: e1, e1, 2·e2, e1 + e2 (small), e2.
        // Start {0, 1} is singular (O1 = 0); adding 2 (2·e2) gives the largest O1; removing
        // 0 or 1 (duplicates) ties, and the lower position goes. Next round: adding 0 and
        // removing either e1 ties with the current value, so the exchange rule stops.
        let rows: [[Real; 2]; 5] = [[1.0, 0.0], [1.0, 0.0], [0.0, 2.0], [0.1, 0.1], [0.0, 1.0]];
        let blocks = rows
            .iter()
            .map(|r| DMatrix::from_row_slice(1, 2, r))
            .collect();
        let model = TableModel::new(blocks);
        let res = detmax(&model, &model.candidates(), vec![0, 1], Objective::O1, 100);
        let mut set = res.set.clone();
        set.sort_unstable();
        assert_eq!(set, vec![1, 2]);
        assert_eq!(res.exchanges, 1);
        assert!(res.termination.contains("exchange rule"));
        // O1 of {e1, 2 e2}: σ = (2, 1) → sqrt(2)/sqrt(2) = 1.
        assert!((res.trace[1] - 1.0).abs() < 1e-12);
        assert!((brute(&model, &res.set, Objective::O1) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn never_lowers_the_objective_and_ends_at_a_local_optimum() {
        let mut robot = crate::robots::irb2600();
        // A target point off the flange axis, so θ6 acts on the position.
        robot.set(crate::kinematics::Param::Tool(0), 80.0);
        robot.set(crate::kinematics::Param::Tool(2), 120.0);
        let ident = crate::identifiability::analyse(
            &robot,
            &robot.params(),
            &crate::sampling::uniform_joint_poses(&robot, 60, &mut crate::rng::from_seed(1)),
            crate::jacobian::Measure::Position,
        )
        .identifiable;
        let model =
            super::super::RobotPoseModel::new(&robot, &ident, crate::jacobian::Measure::Position);
        let cands =
            crate::sampling::uniform_joint_poses(&robot, 120, &mut crate::rng::from_seed(2));
        let m = 15;
        let res = detmax(&model, &cands, (0..m).collect(), Objective::Composite, 1000);
        assert!(res.exchanges > 0);
        assert_eq!(res.trace.len(), res.exchanges + 1);
        for w in res.trace.windows(2) {
            assert!(w[1] > w[0], "{w:?}");
        }
        assert!(res.termination.contains("exchange rule"));
        // At the end, no single add-then-remove exchange improves (checked by brute force
        // with the independent SVD path).
        let f_end = brute_robot(&model, &cands, &res.set);
        assert!((f_end - res.trace[res.exchanges]).abs() < 1e-9);
        let mut in_set = vec![false; cands.len()];
        for &c in &res.set {
            in_set[c] = true;
        }
        let best_add = (0..cands.len())
            .filter(|&c| !in_set[c])
            .map(|c| {
                let mut s = res.set.clone();
                s.push(c);
                (brute_robot(&model, &cands, &s), c)
            })
            .fold(
                (Real::NEG_INFINITY, 0),
                |a, b| if b.0 > a.0 { b } else { a },
            );
        let mut plus = res.set.clone();
        plus.push(best_add.1);
        for pos in 0..m {
            let mut s = plus.clone();
            s.remove(pos);
            assert!(brute_robot(&model, &cands, &s) <= f_end + 1e-9);
        }
    }

    fn brute_robot(
        model: &super::super::RobotPoseModel,
        cands: &[Vec<Real>],
        set: &[usize],
    ) -> Real {
        let qs: Vec<Vec<Real>> = set.iter().map(|&i| cands[i].clone()).collect();
        super::super::score(model, &qs).composite
    }
}
