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
//! sqrt(eig(JᵀJ)) of the small k × k Gram matrix instead of an SVD of the tall J. Eight
//! candidates at a time, the lower triangles of JᵀJ ± BᵀB are formed in the lanes of a
//! per-worker `Spectra` and their eigenvalues found together by the allocation-free
//! Householder + implicit-QL solver of [`crate::numeric::symeig::symmetric_eigenvalues_lanes`] (the
//! same bits as one at a time, and several times faster than nalgebra's generic
//! `symmetric_eigenvalues` at k = 26). The candidate scan runs
//! on rayon and reduces by (value, index) with ties to the lower index, so the result does not
//! depend on the thread count.

use nalgebra::DMatrix;
use rayon::prelude::*;

use super::{add_outer_lower, objective_of_lower, Objective, PoseModel, Spectra};
use crate::numeric::Real;

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

/// Adds `s · BᵀB` of candidate `c` (Bᵀ = columns `r·c .. r·c + r` of `blocks_t`) to the lower
/// triangle of the row-major `g`: the rows of B one after another, as
/// [`super::Evaluator::value`] adds a pose's rows, so that a set's Gram matrix is the same bits
/// here and there.
fn add_block(g: &mut [Real], blocks_t: &DMatrix<Real>, r: usize, c: usize, s: Real) {
    for row in 0..r {
        add_outer_lower(g, blocks_t.column(r * c + row).as_slice(), s);
    }
}

/// Better of two (value, index) pairs: larger value, ties to the lower index.
fn better(x: (Real, usize), y: (Real, usize)) -> (Real, usize) {
    if x.0 > y.0 || (x.0 == y.0 && x.1 < y.1) {
        x
    } else {
        y
    }
}

/// The best (value, key) of `keys` (at most [`Spectra::LANES`]; ties to the lower key): the
/// objective of `gram` + `sign`·BᵀB over `m` poses for candidate c = `cand(key)` (Bᵀ = columns
/// `r·c .. r·c + r` of `blocks_t`), the candidates' eigenvalue problems solved together in
/// `spectra` (only the lower triangles are formed).
#[allow(clippy::too_many_arguments)]
fn scan_best(
    spectra: &mut Spectra,
    gram: &[Real],
    blocks_t: &DMatrix<Real>,
    r: usize,
    keys: &[usize],
    cand: impl Fn(usize) -> usize,
    sign: Real,
    objective: Objective,
    m: usize,
) -> (Real, usize) {
    debug_assert!(!keys.is_empty() && keys.len() <= Spectra::LANES);
    // Candidate c's rows: columns r·c .. r·c + r of the column-major blocks_t.
    let k = blocks_t.nrows();
    let rows = |t: usize| {
        let c = cand(keys[t]);
        &blocks_t.as_slice()[r * c * k..(r * c + r) * k]
    };
    spectra.set_plus_rows(keys.len(), gram, rows, sign);
    let values = spectra.objectives(keys.len(), objective, m);
    keys.iter()
        .zip(values)
        .fold((Real::NEG_INFINITY, usize::MAX), |b, (&key, v)| {
            better(b, (v, key))
        })
}

/// The lower triangle of the Gram matrix JᵀJ of the candidates in `set`, row-major.
fn gram(blocks_t: &DMatrix<Real>, r: usize, set: &[usize], out: &mut [Real]) {
    out.fill(0.0);
    for &c in set {
        add_block(out, blocks_t, r, c, 1.0);
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
    let blocks_t = blocks.transpose();
    let m = start.len();
    let mut set = start;
    let mut in_set = vec![false; n];
    for &c in &set {
        in_set[c] = true;
    }
    let mut a = vec![0.0; k * k];
    gram(&blocks_t, r, &set, &mut a);
    let mut value = objective_of_lower(&a, k, objective, m);
    let mut trace = vec![value];
    let positions: Vec<usize> = (0..m).collect();
    let mut outside = Vec::with_capacity(n);
    let mut exchanges = 0;
    let termination = loop {
        if exchanges >= max_exchanges {
            break format!("detmax: {max_exchanges} exchanges (limit)");
        }
        // (1) Add the best candidate.
        outside.clear();
        outside.extend((0..n).filter(|&c| !in_set[c]));
        let (_, added) = outside
            .par_chunks(Spectra::LANES)
            .map(|cands| {
                Spectra::with(k, |sp| {
                    scan_best(sp, &a, &blocks_t, r, cands, |c| c, 1.0, objective, m + 1)
                })
            })
            .reduce(|| (Real::NEG_INFINITY, usize::MAX), better);
        if added == usize::MAX {
            break "detmax: no candidate left to add".to_string();
        }
        let mut a_plus = a.clone();
        add_block(&mut a_plus, &blocks_t, r, added, 1.0);
        // (2) Remove the pose whose removal leaves the best set; removing the one just
        // added restores the current set and its value exactly, and wins ties.
        let (best_other, removed_pos) = positions
            .par_chunks(Spectra::LANES)
            .map(|pos| {
                Spectra::with(k, |sp| {
                    scan_best(
                        sp,
                        &a_plus,
                        &blocks_t,
                        r,
                        pos,
                        |p| set[p],
                        -1.0,
                        objective,
                        m,
                    )
                })
            })
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
        gram(&blocks_t, r, &set, &mut a);
        value = objective_of_lower(&a, k, objective, m);
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
    use crate::numeric::Real;

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
        let (model, cands) = tool_model(120, 2);
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

    #[test]
    fn fast_scan_values_match_the_dense_eigen_path() {
        let (robot, ident) = tool_robot();
        for measure in [
            crate::measurement::Measure::Position,
            crate::measurement::Measure::Pose,
        ] {
            let model = super::super::RobotPoseModel::new(&robot, &ident, measure);
            let (r, k) = (model.rows_per_pose(), model.n_params());
            let cands = crate::robot::sampling::uniform_joint_poses(
                &robot,
                150,
                &mut crate::numeric::rng::from_seed(4),
            );
            let mut blocks = DMatrix::zeros(r * cands.len(), k);
            for (i, q) in cands.iter().enumerate() {
                model.jacobian_block(q, &mut blocks.rows_mut(r * i, r));
            }
            let blocks_t = blocks.transpose();
            // Sets of 10 (barely above k rows, ill-conditioned) and 60 poses.
            for m in [10, 60] {
                let set: Vec<usize> = (0..m).collect();
                let mut a = DMatrix::zeros(k, k);
                dense_gram(&blocks, r, &set, &mut a);
                let mut buf = Spectra::new(k);
                for o in [Objective::Composite, Objective::O1, Objective::O6] {
                    // The lanes' values are those of the one-matrix path to the bit, eight
                    // candidates at a time (the best of them) as well as one.
                    let mut g = vec![0.0; k * k];
                    gram(&blocks_t, r, &set, &mut g);
                    let outside: Vec<usize> = (m..m + 40).collect();
                    for keys in outside.chunks(Spectra::LANES) {
                        let one_by_one = keys.iter().map(|&c| {
                            let mut plus = g.clone();
                            add_block(&mut plus, &blocks_t, r, c, 1.0);
                            let v = objective_of_lower(&plus, k, o, m + 1);
                            let alone =
                                scan_best(&mut buf, &g, &blocks_t, r, &[c], |c| c, 1.0, o, m + 1);
                            assert_eq!(alone.0.to_bits(), v.to_bits(), "{c}, {o:?}, m {m}");
                            (v, c)
                        });
                        let want = one_by_one.fold((Real::NEG_INFINITY, usize::MAX), better);
                        let got = scan_best(&mut buf, &g, &blocks_t, r, keys, |c| c, 1.0, o, m + 1);
                        assert_eq!((got.0.to_bits(), got.1), (want.0.to_bits(), want.1));
                    }
                    // One candidate's value with `sign` over `poses` poses.
                    let one = |buf: &mut Spectra, c: usize, sign: Real, poses: usize| {
                        scan_best(buf, a.as_slice(), &blocks_t, r, &[c], |c| c, sign, o, poses).0
                    };
                    for c in m..cands.len() {
                        let fast = one(&mut buf, c, 1.0, m + 1);
                        let mut b = a.clone();
                        dense_add_block(&mut b, &blocks, r, c, 1.0);
                        let want = nalgebra_objective(&b, o, m + 1);
                        assert!(
                            (fast - want).abs() <= 1e-7 * want.abs(),
                            "add {c}, {o:?}, m {m}: {fast} vs {want}"
                        );
                    }
                    for &c in &set {
                        let fast = one(&mut buf, c, -1.0, m - 1);
                        let mut b = a.clone();
                        dense_add_block(&mut b, &blocks, r, c, -1.0);
                        let dense = nalgebra_objective(&b, o, m - 1);
                        let rest: Vec<usize> = set.iter().copied().filter(|&x| x != c).collect();
                        dense_gram(&blocks, r, &rest, &mut b);
                        let want = nalgebra_objective(&b, o, m - 1);
                        // The truth is the Gram matrix of the remaining poses. Eigenvalues
                        // carry an absolute error of a few ε·λmax after a downdate, so on an
                        // ill-conditioned remainder (m = 10) the objective is only good to
                        // about ε·λmax/λmin, in the dense path as much as in the fast one.
                        let ev = b.symmetric_eigenvalues();
                        let (lmax, lmin) = (ev.max(), ev.min());
                        let tol = (1e-7 as Real).max(1e3 * Real::EPSILON * lmax / lmin);
                        assert!(
                            (fast - want).abs() <= tol * want.abs()
                                && (dense - want).abs() <= tol * want.abs(),
                            "remove {c}, {o:?}, m {m}: fast {fast}, dense {dense}, want {want}"
                        );
                    }
                }
            }
        }
    }

    /// Adds `s · BᵀB` of candidate `c` (rows `r·c .. r·c + r` of `blocks`) to `a` (nalgebra's
    /// product: the path independent of [`add_block`]).
    fn dense_add_block(a: &mut DMatrix<Real>, blocks: &DMatrix<Real>, r: usize, c: usize, s: Real) {
        let b = blocks.rows(r * c, r);
        a.gemm_tr(s, &b, &b, 1.0);
    }

    /// The Gram matrix JᵀJ of the candidates in `set`, by [`dense_add_block`].
    fn dense_gram(blocks: &DMatrix<Real>, r: usize, set: &[usize], out: &mut DMatrix<Real>) {
        out.fill(0.0);
        for &c in set {
            dense_add_block(out, blocks, r, c, 1.0);
        }
    }

    /// The objective of a Gram matrix through nalgebra's eigenvalues: the path independent of
    /// [`crate::numeric::symeig`].
    fn nalgebra_objective(a: &DMatrix<Real>, o: Objective, m: usize) -> Real {
        let mut ev = a.symmetric_eigenvalues();
        crate::poses::spectra::objective_of_eigenvalues(ev.as_mut_slice(), o, m)
    }

    /// The former DETMAX scans (a nalgebra eigen-decomposition of each candidate's Gram
    /// matrix), sequentially: the exchange sequence must be the same. Returns the set, the
    /// trace and the condition number λmax/λmin of JᵀJ at each trace entry.
    fn reference_detmax(
        model: &dyn PoseModel,
        cands: &[Vec<Real>],
        mut set: Vec<usize>,
        o: Objective,
    ) -> (Vec<usize>, Vec<Real>, Vec<Real>) {
        let (r, k, n, m) = (
            model.rows_per_pose(),
            model.n_params(),
            cands.len(),
            set.len(),
        );
        let mut blocks = DMatrix::zeros(r * n, k);
        for (i, q) in cands.iter().enumerate() {
            model.jacobian_block(q, &mut blocks.rows_mut(r * i, r));
        }
        let mut a = DMatrix::zeros(k, k);
        dense_gram(&blocks, r, &set, &mut a);
        let cond = |a: &DMatrix<Real>| {
            let ev = a.symmetric_eigenvalues();
            ev.max() / ev.min()
        };
        let mut trace = vec![nalgebra_objective(&a, o, m)];
        let mut conds = vec![cond(&a)];
        loop {
            let mut best = (Real::NEG_INFINITY, usize::MAX);
            for c in (0..n).filter(|c| !set.contains(c)) {
                let mut b = a.clone();
                dense_add_block(&mut b, &blocks, r, c, 1.0);
                best = better(best, (nalgebra_objective(&b, o, m + 1), c));
            }
            let mut plus = a.clone();
            dense_add_block(&mut plus, &blocks, r, best.1, 1.0);
            let mut rm = (Real::NEG_INFINITY, usize::MAX);
            for (pos, &c) in set.iter().enumerate() {
                let mut b = plus.clone();
                dense_add_block(&mut b, &blocks, r, c, -1.0);
                rm = better(rm, (nalgebra_objective(&b, o, m), pos));
            }
            let value = trace[trace.len() - 1];
            if !(rm.0 > value && rm.0 - value > 1e-12 * value.abs().max(1e-300)) {
                return (set, trace, conds);
            }
            set[rm.1] = best.1;
            dense_gram(&blocks, r, &set, &mut a);
            trace.push(nalgebra_objective(&a, o, m));
            conds.push(cond(&a));
        }
    }

    #[test]
    fn same_exchanges_as_the_dense_eigen_path() {
        let (model, cands) = tool_model(150, 3);
        for o in [Objective::Composite, Objective::O1, Objective::O6] {
            let res = detmax(&model, &cands, (0..20).collect(), o, 1000);
            let (set, trace, conds) = reference_detmax(&model, &cands, (0..20).collect(), o);
            assert!(res.exchanges > 3, "{o:?}");
            assert_eq!(res.set, set, "{o:?}");
            // The two eigenvalue solvers are each backward stable; the smallest eigenvalues
            // carry an absolute error of a few ε·λmax, so the objectives (which weigh the
            // smallest singular values) agree to about ε·λmax/λmin.
            for ((x, y), c) in res.trace.iter().zip(&trace).zip(&conds) {
                let tol = (1e-12 as Real).max(100.0 * Real::EPSILON * c);
                assert!(
                    (x - y).abs() <= tol * y.abs(),
                    "{o:?}: {x} vs {y}, cond {c:e}"
                );
            }
        }
    }

    /// The IRB2600 with a target point off the flange axis (so θ6 acts on the position) and
    /// its position-identifiable parameters.
    fn tool_robot() -> (crate::robot::Robot, Vec<crate::robot::Param>) {
        let mut robot = crate::robot::builtin::irb2600();
        robot.set(crate::robot::Param::Tool(0), 80.0);
        robot.set(crate::robot::Param::Tool(2), 120.0);
        let ident = crate::robot::identifiability::analyse(
            &robot,
            &robot.params(),
            &crate::robot::sampling::uniform_joint_poses(
                &robot,
                60,
                &mut crate::numeric::rng::from_seed(1),
            ),
            crate::measurement::Measure::Position,
        )
        .identifiable;
        (robot, ident)
    }

    /// The position model of [`tool_robot`] and `n` uniform candidate poses from `seed`.
    fn tool_model(n: usize, seed: u64) -> (super::super::RobotPoseModel, Vec<Vec<Real>>) {
        let (robot, ident) = tool_robot();
        let model = super::super::RobotPoseModel::new(
            &robot,
            &ident,
            crate::measurement::Measure::Position,
        );
        let cands = crate::robot::sampling::uniform_joint_poses(
            &robot,
            n,
            &mut crate::numeric::rng::from_seed(seed),
        );
        (model, cands)
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
