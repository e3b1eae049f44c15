//! Identifiability of the kinematic parameters (Li 2018 §2).
//!
//! Over a rich set of random poses, the identification Jacobian is column-scaled (each column
//! to unit norm, so mm and rad columns compare) and factorised by QR with column pivoting
//! (modified Gram–Schmidt, largest remaining column first, ties to the earlier parameter).
//! Columns whose remaining norm falls below a tolerance depend on the ones chosen before
//! them: they are unidentifiable and are removed (or fixed) before identification. Each such
//! column is then written as a combination of the identifiable ones; the parameters taking
//! part form a group of mutually dependent parameters, and overlapping groups are merged.

use nalgebra::{DMatrix, DVector};

use crate::robot::jacobian::{jacobian, Columns};

use crate::measurement::Measure;
use crate::numeric::Real;
use crate::robot::{Param, Robot};

/// Relative tolerance below which a scaled column counts as dependent.
pub const RANK_TOL: Real = 1e-7;

/// The result of an identifiability analysis.
#[derive(Clone, Debug)]
pub struct Identifiability {
    /// Numerical rank of the column-scaled Jacobian.
    pub rank: usize,
    /// Identifiable parameters, in parameter order.
    pub identifiable: Vec<Param>,
    /// Parameters removed as dependent on the identifiable ones (or without any effect).
    pub unidentifiable: Vec<Param>,
    /// Groups of mutually dependent parameters (each holds at least one unidentifiable one).
    pub groups: Vec<Vec<Param>>,
    /// Condition number of the column-scaled Jacobian over the identifiable parameters.
    pub condition_number: Real,
}

/// Scales each column of `j` to unit norm in place and returns the norms. A column whose
/// norm is at rounding level (below 1e-9 of the largest column norm, plus 1e-12) is a
/// parameter with no effect: it is set to zero rather than blown up to unit norm, so it
/// counts as unidentifiable.
pub fn scale_columns(j: &mut DMatrix<Real>) -> Vec<Real> {
    let largest = j.column_iter().map(|c| c.norm()).fold(0.0, Real::max);
    let floor = 1e-9 * largest + 1e-12;
    let mut norms = Vec::with_capacity(j.ncols());
    for mut c in j.column_iter_mut() {
        let n = c.norm();
        if n > floor {
            c /= n;
        } else {
            c.fill(0.0);
        }
        norms.push(n);
    }
    norms
}

/// Pivoted QR by modified Gram–Schmidt: returns the pivot columns in the order chosen.
/// A column is chosen while its remaining norm exceeds `tol` (columns are unit norm or zero).
fn pivoted_gram_schmidt(a: &DMatrix<Real>, tol: Real) -> Vec<usize> {
    let mut r = a.clone();
    let k = a.ncols();
    let mut chosen = Vec::new();
    let mut used = vec![false; k];
    loop {
        let mut best: Option<(usize, Real)> = None;
        for (c, _) in used.iter().enumerate().filter(|(_, u)| !**u) {
            let n = r.column(c).norm();
            if best.is_none_or(|(_, bn)| n > bn * (1.0 + 1e-12)) {
                best = Some((c, n));
            }
        }
        let Some((c, n)) = best else { break };
        if n <= tol {
            break;
        }
        used[c] = true;
        chosen.push(c);
        let qv: DVector<Real> = r.column(c) / n;
        for (o, _) in used.iter().enumerate().filter(|(_, u)| !**u) {
            let d = qv.dot(&r.column(o));
            r.column_mut(o).axpy(-d, &qv, 1.0);
        }
    }
    chosen
}

/// Poses in the fixed random set of [`identifiable_generic`].
pub const GENERIC_POSES: usize = 200;

/// The identifiable subset of `candidates` (in their order) for a generic pose set:
/// [`analyse`] over [`GENERIC_POSES`] joint configurations drawn uniformly within the limits
/// from a fixed seed (Li 2018 §2: QR removal of dependent columns). The answer depends on
/// the robot, the candidates and the measure only, so every study of a robot agrees.
pub fn identifiable_generic(robot: &Robot, candidates: &[Param], measure: Measure) -> Vec<Param> {
    let mut g = crate::numeric::rng::stream(0x1D, "identifiability");
    let qs = crate::robot::sampling::uniform_joint_poses(robot, GENERIC_POSES, &mut g);
    analyse(robot, candidates, &qs, measure).identifiable
}

/// Analyses which of `params` are identifiable from the Jacobian over poses `qs`.
pub fn analyse(
    robot: &Robot,
    params: &[Param],
    qs: &[Vec<Real>],
    measure: Measure,
) -> Identifiability {
    let cols = Columns::new(params, robot.dof());
    analyse_jacobian(params, jacobian(robot, &cols, qs, measure))
}

/// [`analyse`] of a given identification Jacobian `j`, one column per parameter of `params`
/// (any measurement kind's rows, with the instrument's own unknowns projected out).
pub fn analyse_jacobian(params: &[Param], mut j: DMatrix<Real>) -> Identifiability {
    scale_columns(&mut j);
    let pivots = pivoted_gram_schmidt(&j, RANK_TOL);
    let mut is_pivot = vec![false; params.len()];
    for &p in &pivots {
        is_pivot[p] = true;
    }
    let ident_idx: Vec<usize> = (0..params.len()).filter(|&c| is_pivot[c]).collect();
    let dep_idx: Vec<usize> = (0..params.len()).filter(|&c| !is_pivot[c]).collect();

    // Groups: each dependent column as a combination of the identifiable ones.
    let a = j.select_columns(&ident_idx);
    let svd = a.clone().svd(true, true);
    let mut parent: Vec<usize> = (0..params.len()).collect();
    fn find(p: &mut [usize], i: usize) -> usize {
        let mut r = i;
        while p[r] != r {
            r = p[r];
        }
        let mut c = i;
        while p[c] != r {
            let n = p[c];
            p[c] = r;
            c = n;
        }
        r
    }
    let mut in_group = vec![false; params.len()];
    for &d in &dep_idx {
        in_group[d] = true;
        let b = j.column(d).into_owned();
        if b.norm() < RANK_TOL {
            continue; // no effect at all: a group of its own
        }
        let x = svd
            .solve(&b, 1e-12)
            .unwrap_or_else(|_| DVector::zeros(ident_idx.len()));
        for (xi, &c) in x.iter().zip(&ident_idx) {
            if xi.abs() > 1e-6 {
                in_group[c] = true;
                let (ra, rb) = (find(&mut parent, d), find(&mut parent, c));
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    let mut groups: Vec<Vec<Param>> = Vec::new();
    let mut root_of_group: Vec<usize> = Vec::new();
    for c in 0..params.len() {
        if !in_group[c] {
            continue;
        }
        let r = find(&mut parent, c);
        match root_of_group.iter().position(|&x| x == r) {
            Some(g) => groups[g].push(params[c]),
            None => {
                root_of_group.push(r);
                groups.push(vec![params[c]]);
            }
        }
    }

    let sv = svd.singular_values;
    let (mx, mn) = sv
        .iter()
        .fold((0.0f64, f64::INFINITY), |(a, b), &s| (a.max(s), b.min(s)));
    let condition_number = if ident_idx.is_empty() || mn <= 0.0 {
        f64::INFINITY
    } else {
        mx / mn
    };
    Identifiability {
        rank: ident_idx.len(),
        identifiable: ident_idx.iter().map(|&c| params[c]).collect(),
        unidentifiable: dep_idx.iter().map(|&c| params[c]).collect(),
        groups,
        condition_number,
    }
}
