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

/// Relative tolerance of numerical rank, the one rule of the analysis and the identification
/// ([`crate::identify::solver::RANK_TOLERANCE`] is this constant): a direction of the
/// column-scaled Jacobian whose singular value is below this fraction of the largest is
/// undetermined. Pivoting stops at a column whose remaining norm is below it, and the chosen
/// columns are then cut back until their own scaled singular values all lie above it: the
/// identifiable parameters, identified alone on the same rows, are of full rank.
pub const RANK_TOL: Real = 1e-7;

/// Whether columns whose scaled singular values run from `smallest` to `largest` are all
/// determined by [`RANK_TOL`]: `smallest > RANK_TOL · largest`, the identification's test of
/// full rank (its rank counts the singular values above that floor).
fn determined((largest, smallest): (Real, Real)) -> bool {
    largest.is_finite() && smallest > RANK_TOL * largest
}

/// The largest and smallest scaled singular values of a set of columns, with what was computed
/// to find them.
type Extremes<T> = Option<((Real, Real), T)>;

/// The largest and smallest singular values of an SVD.
fn extremes(svd: &Svd) -> (Real, Real) {
    svd.singular_values
        .iter()
        .fold((0.0, Real::INFINITY), |(a, b), &s| (a.max(s), b.min(s)))
}

/// The columns of `pivots` (in the order chosen), sorted, cut back from the last chosen while
/// `extremes` of the sorted columns, the largest and smallest scaled singular values (`None`
/// when they cannot be computed: then no cut), are not [`determined`]; with what `extremes`
/// gave for the columns kept.
fn cut_to_determined<T>(
    mut pivots: Vec<usize>,
    extremes: impl Fn(&[usize]) -> Extremes<T>,
) -> (Vec<usize>, Extremes<T>) {
    loop {
        let mut kept = pivots.clone();
        kept.sort_unstable();
        let e = if kept.is_empty() {
            None
        } else {
            extremes(&kept)
        };
        match e {
            Some((sv, _)) if !determined(sv) => {
                pivots.pop();
            }
            _ => return (kept, e),
        }
    }
}

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

impl Identifiability {
    /// The analysis of `params` whose columns `ident` are identifiable and `dep` are not.
    fn of(
        params: &[Param],
        ident: &[usize],
        dep: &[usize],
        groups: Vec<Vec<Param>>,
        condition_number: Real,
    ) -> Identifiability {
        Identifiability {
            rank: ident.len(),
            identifiable: ident.iter().map(|&c| params[c]).collect(),
            unidentifiable: dep.iter().map(|&c| params[c]).collect(),
            groups,
            condition_number,
        }
    }
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

/// The next pivot: the column not yet `used` of the largest remaining norm `norm(c)` (ties to
/// the earlier column), with that norm; `None` when every column is used.
fn largest_remaining(used: &[bool], norm: impl Fn(usize) -> Real) -> Option<(usize, Real)> {
    let mut best: Option<(usize, Real)> = None;
    for c in (0..used.len()).filter(|&c| !used[c]) {
        let n = norm(c);
        if best.is_none_or(|(_, bn)| n > bn * (1.0 + 1e-12)) {
            best = Some((c, n));
        }
    }
    best
}

/// Pivoted QR by modified Gram–Schmidt: returns the pivot columns in the order chosen.
/// A column is chosen while its remaining norm exceeds `tol` (columns are unit norm or zero).
fn pivoted_gram_schmidt(a: &DMatrix<Real>, tol: Real) -> Vec<usize> {
    let mut r = a.clone();
    let k = a.ncols();
    let mut chosen = Vec::new();
    let mut used = vec![false; k];
    while let Some((c, n)) = largest_remaining(&used, |c| r.column(c).norm()) {
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

/// The root of `i` in the union-find forest `p`, compressing the path.
fn find_root(p: &mut [usize], i: usize) -> usize {
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

/// The groups of mutually dependent parameters: each dependent column `dep` with the
/// identifiable ones (`ident`) that take part in its combination `combination(d)` (weights
/// above 1e-6; `None`: a column with no effect, a group of its own), overlapping groups merged.
fn dependency_groups(
    params: &[Param],
    ident: &[usize],
    dep: &[usize],
    combination: impl Fn(usize) -> Option<DVector<Real>>,
) -> Vec<Vec<Param>> {
    let (in_group, mut parent) = dependency_forest(params.len(), ident, dep, combination);
    collect_groups(params, &in_group, &mut parent)
}

/// The work of [`dependency_groups`] over `t` columns: which columns take part in a
/// dependency (weights above [`DEPENDENCE_WEIGHT`]), and the union-find forest joining them.
fn dependency_forest(
    t: usize,
    ident: &[usize],
    dep: &[usize],
    combination: impl Fn(usize) -> Option<DVector<Real>>,
) -> (Vec<bool>, Vec<usize>) {
    let mut parent: Vec<usize> = (0..t).collect();
    let mut in_group = vec![false; t];
    for &d in dep {
        in_group[d] = true;
        let Some(x) = combination(d) else {
            continue; // no effect at all: a group of its own
        };
        for (xi, &c) in x.iter().zip(ident) {
            if xi.abs() > DEPENDENCE_WEIGHT {
                in_group[c] = true;
                let (ra, rb) = (find_root(&mut parent, d), find_root(&mut parent, c));
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    (in_group, parent)
}

/// The weight above which an identifiable column takes part in a dependent column's
/// combination (both scaled to unit norm): ten times the scaled columns' rank tolerance
/// [`RANK_TOL`], far above the rounding of a combination solved on a factor the pivoting kept
/// well inside that tolerance.
pub const DEPENDENCE_WEIGHT: Real = 1e-6;

/// The groups of mutually dependent parameters: those `in_group`, one group per root of the
/// union-find forest `parent`, in parameter order.
fn collect_groups(params: &[Param], in_group: &[bool], parent: &mut [usize]) -> Vec<Vec<Param>> {
    let mut groups: Vec<Vec<Param>> = Vec::new();
    let mut root_of_group: Vec<usize> = Vec::new();
    for c in 0..params.len() {
        if !in_group[c] {
            continue;
        }
        let r = find_root(parent, c);
        match root_of_group.iter().position(|&x| x == r) {
            Some(g) => groups[g].push(params[c]),
            None => {
                root_of_group.push(r);
                groups.push(vec![params[c]]);
            }
        }
    }
    groups
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

/// Of `extra`, the parameters that each add a rank to `params` (identifiable among
/// themselves) over the generic poses of [`identifiable_generic`], taken in their order: a
/// parameter is kept when its scaled column keeps more than [`RANK_TOL`] of its norm once
/// projected off the columns of `params` and of the parameters kept before it, and the kept
/// ones are then cut back, the last first, until `params` and they are determined together
/// by [`RANK_TOL`] as the identification judges them (when `params` alone are). Unlike
/// [`identifiable_generic`] over `params` and `extra` together, the choice among `params` is
/// left as it is: a term of a richer model never displaces a kinematic parameter.
pub fn identifiable_extension(
    robot: &Robot,
    params: &[Param],
    extra: &[Param],
    measure: Measure,
) -> Vec<Param> {
    let mut g = crate::numeric::rng::stream(0x1D, "identifiability");
    let qs = crate::robot::sampling::uniform_joint_poses(robot, GENERIC_POSES, &mut g);
    let all: Vec<Param> = params.iter().chain(extra).copied().collect();
    let mut j = jacobian(robot, &Columns::new(&all, robot.dof()), &qs, measure);
    scale_columns(&mut j);
    // Modified Gram-Schmidt, `params` first.
    let mut basis: Vec<DVector<Real>> = Vec::new();
    let mut kept = Vec::new();
    for (c, _) in all.iter().enumerate() {
        let mut v = j.column(c).into_owned();
        for b in &basis {
            let d = b.dot(&v);
            v.axpy(-d, b, 1.0);
        }
        let n = v.norm();
        if n > RANK_TOL {
            basis.push(v / n);
            if c >= params.len() {
                kept.push(c);
            }
        }
    }
    // Cut back the terms kept last while `params` and the terms are not determined together.
    // `params` themselves are not judged here: a cut that reaches into them says they are not
    // determined alone, and the terms then stay as pivoting kept them.
    if !kept.is_empty() {
        let columns = (0..params.len()).chain(kept.iter().copied()).collect();
        let (cols, _) = cut_to_determined(columns, |c| {
            let svd = crate::numeric::linalg::svd(j.select_columns(c), false, false)?;
            Some((extremes(&svd), ()))
        });
        if let Some(terms) = cols.get(params.len()..) {
            kept = terms.to_vec();
        }
    }
    kept.iter().map(|&c| all[c]).collect()
}

/// Pose sets larger than this are analysed from the Gram matrix of the Jacobian, summed
/// block by block ([`analyse_gram`]); smaller ones by the QR and SVD of the Jacobian itself.
/// The studies' sets (a few hundred poses, and the [`GENERIC_POSES`] of
/// [`identifiable_generic`]) always take the exact path.
pub const GRAM_MIN_POSES: usize = 4096;

/// Poses per block of [`analyse_gram`].
const GRAM_BLOCK_POSES: usize = 512;

/// Analyses which of `params` are identifiable from the Jacobian over poses `qs`: by
/// pivoted QR and SVD of the column-scaled Jacobian, or beyond [`GRAM_MIN_POSES`] poses by
/// the same steps on its Gram matrix ([`analyse_gram`]), so that memory does not grow with
/// the poses.
pub fn analyse(
    robot: &Robot,
    params: &[Param],
    qs: &[Vec<Real>],
    measure: Measure,
) -> Identifiability {
    if qs.len() > GRAM_MIN_POSES {
        return analyse_gram(robot, params, qs, measure);
    }
    let cols = Columns::new(params, robot.dof());
    analyse_jacobian(params, jacobian(robot, &cols, qs, measure))
}

/// [`analyse`] of a given identification Jacobian `j`, one column per parameter of `params`
/// (any measurement kind's rows, with the instrument's own unknowns projected out).
pub fn analyse_jacobian(params: &[Param], mut j: DMatrix<Real>) -> Identifiability {
    scale_columns(&mut j);
    let (ident_idx, svd) = determined_scaled(&j);
    let dep_idx: Vec<usize> = (0..params.len())
        .filter(|c| ident_idx.binary_search(c).is_err())
        .collect();

    // Groups: each dependent column as a combination of the identifiable ones.
    let groups = dependency_groups(params, &ident_idx, &dep_idx, |d| {
        let b = j.column(d).into_owned();
        (b.norm() >= RANK_TOL).then(|| {
            svd.as_ref()
                .and_then(|(_, svd)| svd.solve(&b, 1e-12).ok())
                .unwrap_or_else(|| DVector::zeros(ident_idx.len()))
        })
    });

    let (mx, mn) = svd.map_or((0.0, 0.0), |(sv, _)| sv);
    let condition_number = if ident_idx.is_empty() || mn <= 0.0 {
        f64::INFINITY
    } else {
        mx / mn
    };
    Identifiability::of(params, &ident_idx, &dep_idx, groups, condition_number)
}

/// The columns of the column-scaled `j` that [`analyse_jacobian`] keeps as determined, in
/// column order, with the SVD of those columns (`None` when none is kept or it fails).
fn determined_scaled(j: &DMatrix<Real>) -> (Vec<usize>, Extremes<Svd>) {
    cut_to_determined(pivoted_gram_schmidt(j, RANK_TOL), |cols| {
        let svd = crate::numeric::linalg::svd(j.select_columns(cols), true, true)?;
        Some((extremes(&svd), svd))
    })
}

/// The SVD of a dynamic matrix.
type Svd = nalgebra::SVD<Real, nalgebra::Dyn, nalgebra::Dyn>;

/// The columns of `j` (any unknowns, one column each) that the rows determine by the rule of
/// [`analyse_jacobian`] (column-scaled, pivoted, cut back to full rank by [`RANK_TOL`]), in
/// column order; the others depend on them or have no effect.
pub fn determined_columns(mut j: DMatrix<Real>) -> Vec<usize> {
    scale_columns(&mut j);
    determined_scaled(&j).0
}

/// [`analyse`] from the Gram matrix `JᵀJ` of the Jacobian, summed over blocks of
/// 512 poses ([`crate::numeric::normal::NormalEquations`]): the same column
/// scaling (unit diagonal), the pivoted Gram–Schmidt as a pivoted Cholesky factorisation
/// (the remaining norm of a column is the square root of its Schur complement's diagonal),
/// each dependent column's combination of the identifiable ones by their normal equations,
/// and the condition number as the square root of the scaled Gram matrix's eigenvalue ratio.
/// Squaring costs precision: a column's remaining norm is resolved down to about 1e-8
/// (square root of the Gram matrix's rounding), so [`RANK_TOL`] = 1e-7 still separates, with
/// a margin of ten rather than the QR path's 1e8 (docs/performance.md, "Streaming
/// identification").
pub fn analyse_gram(
    robot: &Robot,
    params: &[Param],
    qs: &[Vec<Real>],
    measure: Measure,
) -> Identifiability {
    let t = params.len();
    let cols = Columns::new(params, robot.dof());
    let chain = robot.chain();
    let rows = measure.rows();
    let mut sums = crate::numeric::normal::NormalEquations::new(t, rows * GRAM_BLOCK_POSES);
    let mut j = DMatrix::zeros(rows * GRAM_BLOCK_POSES, t);
    let zeros = vec![0.0; rows * GRAM_BLOCK_POSES];
    for block in qs.chunks(GRAM_BLOCK_POSES) {
        if block.len() < GRAM_BLOCK_POSES {
            j = DMatrix::zeros(rows * block.len(), t);
        }
        for (i, q) in block.iter().enumerate() {
            crate::robot::jacobian::pose_rows(&chain, &cols, q, measure, &mut j, rows * i);
            if cols.has_harmonics() {
                cols.fill_harmonics(&chain.variables(q), &mut j, rows * i, rows);
            }
        }
        sums.add(&j, &zeros[..rows * block.len()], &[1.0]);
    }
    let d = gram_dependence(sums.n());
    let mut parent = d.parent;
    let groups = collect_groups(params, &d.in_group, &mut parent);
    let condition_number = match d.eigenvalues {
        Some((mx, mn)) if mn > 0.0 => (mx / mn).sqrt(),
        _ => Real::INFINITY,
    };
    Identifiability::of(
        params,
        &d.identifiable,
        &d.dependent,
        groups,
        condition_number,
    )
}

/// The dependence analysis of [`analyse_gram`] on a Gram matrix `n = JᵀJ` (or a weighted
/// normal matrix `JᵀWJ`, the Gram matrix of `W^½ J`): which columns pivoted Cholesky of the
/// column-scaled matrix keeps (a column's remaining norm above [`RANK_TOL`], cut back until
/// the kept columns are determined by [`RANK_TOL`] as the identification judges them), which
/// depend on them, and which take part in a dependency (a dependent column, or a kept one
/// whose weight in a dependent column's combination exceeds [`DEPENDENCE_WEIGHT`]).
pub struct GramDependence {
    /// The kept columns, in column order.
    pub identifiable: Vec<usize>,
    /// The other columns, in column order.
    pub dependent: Vec<usize>,
    /// Per column, whether it takes part in a dependency (every dependent column does).
    pub in_group: Vec<bool>,
    /// Per column, 1 / its norm (√ of its diagonal element), or 0 for a column at rounding
    /// level: the column scaling of the analysis.
    pub scale: Vec<Real>,
    /// The union-find forest of the groups.
    parent: Vec<usize>,
    /// The largest and smallest eigenvalues of the scaled matrix over the kept columns;
    /// `None` when there are none or they cannot be computed.
    eigenvalues: Option<(Real, Real)>,
}

/// [`GramDependence`] of the symmetric positive semi-definite `n`.
pub fn gram_dependence(n: &DMatrix<Real>) -> GramDependence {
    let t = n.nrows();
    // Column norms and the scaled Gram matrix (a column at rounding level is zero).
    let norms: Vec<Real> = (0..t).map(|c| n[(c, c)].max(0.0).sqrt()).collect();
    let largest = norms.iter().fold(0.0, |a: Real, &b| a.max(b));
    let floor = 1e-9 * largest + 1e-12;
    let scale: Vec<Real> = norms
        .iter()
        .map(|&v| if v > floor { 1.0 / v } else { 0.0 })
        .collect();
    let s = DMatrix::from_fn(t, t, |i, k| n[(i, k)] * scale[i] * scale[k]);
    // Pivoted Cholesky: the Schur complement of the chosen columns in `a`.
    let mut a = s.clone();
    let mut used = vec![false; t];
    let mut chosen = Vec::new();
    while let Some((c, v)) = largest_remaining(&used, |c| a[(c, c)].max(0.0).sqrt()) {
        if v <= RANK_TOL {
            break;
        }
        used[c] = true;
        chosen.push(c);
        let pivot = a[(c, c)];
        let col: Vec<Real> = (0..t).map(|i| a[(i, c)]).collect();
        for o in (0..t).filter(|&o| !used[o]) {
            for o2 in (0..t).filter(|&o2| !used[o2]) {
                a[(o, o2)] -= col[o] * col[o2] / pivot;
            }
        }
    }
    let (ident_idx, eigenvalues) = cut_to_determined(chosen, |cols| {
        let k = cols.len();
        let mut lower: Vec<Real> = (0..k * k)
            .map(|ik| s[(cols[ik / k], cols[ik % k])])
            .collect();
        let (mut ev, mut scratch) = (vec![0.0; k], vec![0.0; k]);
        crate::numeric::symeig::symmetric_eigenvalues(&mut lower, k, &mut ev, &mut scratch).then(
            || {
                let (mx, mn) = ev.iter().fold((0.0 as Real, Real::INFINITY), |(a, b), &e| {
                    (a.max(e), b.min(e))
                });
                ((mx.max(0.0).sqrt(), mn.max(0.0).sqrt()), (mx, mn))
            },
        )
    });
    let dep_idx: Vec<usize> = (0..t)
        .filter(|c| ident_idx.binary_search(c).is_err())
        .collect();
    let ss = s.select_rows(&ident_idx).select_columns(&ident_idx);
    let chol = ss.clone().cholesky();
    let (in_group, parent) = dependency_forest(t, &ident_idx, &dep_idx, |d| {
        (s[(d, d)].max(0.0).sqrt() >= RANK_TOL).then(|| {
            let b = DVector::from_fn(ident_idx.len(), |i, _| s[(ident_idx[i], d)]);
            chol.as_ref()
                .map_or_else(|| DVector::zeros(ident_idx.len()), |c| c.solve(&b))
        })
    });
    GramDependence {
        identifiable: ident_idx,
        dependent: dep_idx,
        in_group,
        scale,
        parent,
        eigenvalues: eigenvalues.map(|(_, e)| e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Gram path of large pose sets against the QR and SVD of the Jacobian on the same
    /// poses, for position and full-pose data of robots with dependent parameters: the same
    /// rank, identifiable set and groups, the condition number to 1e-6.
    #[test]
    fn gram_analysis_agrees_with_the_qr_of_the_jacobian() {
        for name in ["irb2600", "irb2600-mdh", "tx60", "guo-3t2r"] {
            let robot = crate::robot::builtin::load(name).expect("robot");
            let mut g = crate::numeric::rng::from_seed(8);
            let qs = crate::robot::sampling::uniform_joint_poses(&robot, 700, &mut g);
            for measure in [Measure::Position, Measure::Pose] {
                let params = robot.params();
                let qr = analyse(&robot, &params, &qs, measure);
                let gram = analyse_gram(&robot, &params, &qs, measure);
                assert_eq!(gram.rank, qr.rank, "{name} {measure:?}");
                assert_eq!(gram.identifiable, qr.identifiable, "{name} {measure:?}");
                assert_eq!(gram.groups, qr.groups, "{name} {measure:?}");
                let (a, b) = (gram.condition_number, qr.condition_number);
                assert!((a - b).abs() <= 1e-6 * b, "{name} {measure:?}: {a} vs {b}");
            }
        }
    }
}
