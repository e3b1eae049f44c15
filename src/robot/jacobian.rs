//! The analytic identification Jacobian (Li 2018 eqs. 6–12, Ban eqs. 3–11,
//! Guo 2024 eq. 7).
//!
//! Every parameter enters the chain as one elementary operation about or along a local axis
//! ([`crate::robot::Op`]), so its column is a unit twist: for a rotation about the unit
//! axis `w` through the point `o` (both in the world, taken just before the operation), the
//! end point moves by `w × (p − o)` and the end frame turns by `w`; for a translation along `w`
//! the end point moves by `w`. With the base parameters at zero the base columns are exactly
//! Li 2018's base-frame fitting-error columns `[I, −[p]×]` (eqs. 8–11).
//!
//! Rows per pose: 3 (position, mm per unit parameter) or 6 (position, then the small rotation
//! of the tool frame in the world, rad per unit parameter).

use std::mem::MaybeUninit;

use nalgebra::{DMatrix, DVector};

use crate::measurement::Measure;
use crate::numeric::{rotation_vector, so3_right_jacobian_inverse, Mat3, Real, Vec3};
use crate::robot::{
    Chain, ChainVars, Lanes, Op, Param, Robot, GRAVITY_POINTS, HARMONIC_TERMS, MAX_JOINTS,
};

/// Maps flat parameter indices to Jacobian columns, for a chosen parameter list.
#[derive(Clone, Debug)]
pub struct Columns {
    of_param: Vec<Option<usize>>,
    /// Per chain variable: the column of its joint's compliance ([`Param::Compliance`]),
    /// which receives the derivative by that variable (the caller scales it by the joint's
    /// gravity torque, [`crate::identify::RobotProblem`]).
    of_var: [Option<usize>; MAX_JOINTS],
    /// Whether any entry of `of_var` is set.
    any_var: bool,
    /// Per joint, the columns of its harmonic coefficients ([`Param::Harmonic`]); the
    /// derivative by the joint's chain variable is written into `of_var` (its compliance's
    /// column, or else its first harmonic's) and [`Columns::fill_harmonics`] scales it into
    /// each harmonic column.
    harmonic: [[Option<usize>; HARMONIC_TERMS]; MAX_JOINTS],
    /// Per joint, the highest harmonic order among its columns (0: none).
    orders: [usize; MAX_JOINTS],
    /// Whether any entry of `harmonic` is set.
    any_harmonic: bool,
    /// Per joint, the columns of its gravity-basis coefficients ([`Param::Gravity`]), filled
    /// like the harmonics' from the derivative by the joint's chain variable.
    gravity: [[Option<usize>; GRAVITY_POINTS]; MAX_JOINTS],
    /// Whether any entry of `gravity` is set.
    any_gravity: bool,
    params: Vec<Param>,
}

impl Columns {
    /// Columns for `params` (in that order) of a robot with `dof` joints. The column of a
    /// compliance `c_j` holds the derivative by joint `j`'s chain variable, unscaled.
    pub fn new(params: &[Param], dof: usize) -> Columns {
        let mut of_param = vec![None; crate::robot::value_count(dof)];
        let mut of_var = [None; MAX_JOINTS];
        let mut harmonic = [[None; HARMONIC_TERMS]; MAX_JOINTS];
        let mut gravity = [[None; GRAVITY_POINTS]; MAX_JOINTS];
        for (c, p) in params.iter().enumerate() {
            match *p {
                Param::Compliance(j) => of_var[j] = Some(c),
                Param::Harmonic(j, k) => harmonic[j][k] = Some(c),
                Param::Gravity(j, l) => gravity[j][l] = Some(c),
                p => of_param[p.index(dof)] = Some(c),
            }
        }
        for ((v, h), g) in of_var.iter_mut().zip(&harmonic).zip(&gravity) {
            if v.is_none() {
                *v = h.iter().chain(g).flatten().next().copied();
            }
        }
        let mut orders = [0; MAX_JOINTS];
        for (o, h) in orders.iter_mut().zip(&harmonic) {
            if h.iter().any(Option::is_some) {
                *o = crate::robot::harmonics::orders_used(h.iter().map(Option::is_some));
            }
        }
        Columns {
            of_param,
            any_var: of_var.iter().any(Option::is_some),
            of_var,
            any_harmonic: harmonic.iter().flatten().any(Option::is_some),
            harmonic,
            orders,
            any_gravity: gravity.iter().flatten().any(Option::is_some),
            gravity,
            params: params.to_vec(),
        }
    }

    /// Whether any column is a harmonic coefficient ([`Param::Harmonic`]).
    pub fn has_harmonics(&self) -> bool {
        self.any_harmonic
    }

    /// Whether any column is a gravity-basis coefficient ([`Param::Gravity`]).
    pub fn has_gravity(&self) -> bool {
        self.any_gravity
    }

    /// Turns the rows `row0..row0 + rows` of one pose (written by [`pose_rows_vars`]) into
    /// the columns of every joint term: the harmonics' ([`Columns::fill_harmonics`]) and the
    /// gravity basis', `∂/∂k_jl = (∂p/∂q_j) τ_jl` with `τ` the pose's basis torques
    /// ([`crate::robot::gravity_basis::torques`]), from the derivative by joint `j`'s chain
    /// variable. Call it before a compliance column is scaled by its torque.
    /// Allocation-free.
    pub fn fill_terms(
        &self,
        vars: &ChainVars,
        tau: &crate::robot::gravity_basis::Torques,
        j: &mut DMatrix<Real>,
        row0: usize,
        rows: usize,
    ) {
        if !self.any_gravity {
            return self.fill_harmonics(vars, j, row0, rows);
        }
        for (v, g) in self.gravity.iter().enumerate() {
            let Some(src) = self.of_var[v] else { continue };
            if g.iter().all(Option::is_none) {
                continue;
            }
            // The source column may be one of the terms filled: read it once per row, and
            // the harmonics' from a copy of the derivative when the source is a gravity
            // column.
            let h = &self.harmonic[v];
            let f = crate::robot::harmonics::factors(vars.1[v].0, vars.1[v].1, self.orders[v]);
            for r in row0..row0 + rows {
                let d = j[(r, src)];
                for (col, t) in g.iter().zip(&tau[v]) {
                    if let Some(col) = *col {
                        j[(r, col)] = d * t;
                    }
                }
                for (col, fk) in h.iter().zip(f) {
                    if let Some(col) = *col {
                        j[(r, col)] = d * fk;
                    }
                }
            }
        }
        // Joints with harmonics and no gravity column.
        for (v, h) in self.harmonic.iter().enumerate() {
            let Some(src) = self.of_var[v] else { continue };
            if h.iter().all(Option::is_none) || self.gravity[v].iter().any(Option::is_some) {
                continue;
            }
            let f = crate::robot::harmonics::factors(vars.1[v].0, vars.1[v].1, self.orders[v]);
            for r in row0..row0 + rows {
                let d = j[(r, src)];
                for (col, fk) in h.iter().zip(f) {
                    if let Some(col) = *col {
                        j[(r, col)] = d * fk;
                    }
                }
            }
        }
    }

    /// Turns the rows `row0..row0 + rows` of one pose (written by [`pose_rows_vars`]) into
    /// the harmonic columns: `∂/∂a_j = (∂p/∂q_j) sin q_j`, `∂/∂b_j = (∂p/∂q_j) cos q_j`,
    /// and `sin 2q_j`, `cos 2q_j` for the second harmonic, from the derivative by joint `j`'s
    /// chain variable (its `of_var` column, unscaled) and the pose's undeflected chain
    /// variables `vars`. Call it before a compliance column is scaled by its torque.
    /// Allocation-free.
    pub fn fill_harmonics(
        &self,
        vars: &ChainVars,
        j: &mut DMatrix<Real>,
        row0: usize,
        rows: usize,
    ) {
        if !self.any_harmonic {
            return;
        }
        for (v, h) in self.harmonic.iter().enumerate() {
            let Some(src) = self.of_var[v] else { continue };
            if h.iter().all(Option::is_none) {
                continue;
            }
            let (s, c) = vars.1[v];
            let f = crate::robot::harmonics::factors(s, c, self.orders[v]);
            for r in row0..row0 + rows {
                let d = j[(r, src)];
                for (col, fk) in h.iter().zip(f) {
                    if let Some(col) = *col {
                        j[(r, col)] = d * fk;
                    }
                }
            }
        }
    }

    /// The parameters, one per column.
    pub fn params(&self) -> &[Param] {
        &self.params
    }

    /// Number of columns.
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// Whether there are no columns.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }
}

/// The orientation rows of one full pose, rows `row..row + 3`: writes the residual
/// `k·φ`, `φ = log(R_m Rᵀ)` (the rotation in the world from the model orientation `model` to
/// the measured one `measured`) into `r`, and turns the rotation rows `J_ω` that
/// [`pose_rows`] wrote into `j` into `k·J_r⁻¹(φ)J_ω`, the exact derivative of the model side:
/// `R → exp([ω]×)R` turns `R_m Rᵀ` into `R_m Rᵀ exp(−[ω]×)`, whose logarithm is
/// `φ − J_r⁻¹(φ)ω` to first order ([`crate::numeric::so3_right_jacobian_inverse`]).
/// Allocation-free.
pub fn log_orientation_rows(
    measured: &Mat3,
    model: &Mat3,
    k: Real,
    r: &mut DVector<Real>,
    j: &mut DMatrix<Real>,
    row: usize,
) {
    let phi = rotation_vector(&(measured * model.transpose()));
    for i in 0..3 {
        r[row + i] = k * phi[i];
    }
    let g = so3_right_jacobian_inverse(&phi) * k;
    for c in 0..j.ncols() {
        let w = g * Vec3::new(j[(row, c)], j[(row + 1, c)], j[(row + 2, c)]);
        for i in 0..3 {
            j[(row + i, c)] = w[i];
        }
    }
}

/// Writes the Jacobian rows of one pose at joint values `q` into `out` starting at row `row0`
/// and returns the tool frame. Allocation-free.
pub fn pose_rows(
    chain: &Chain,
    cols: &Columns,
    q: &[Real],
    measure: Measure,
    out: &mut DMatrix<Real>,
    row0: usize,
) -> crate::numeric::Frame {
    record_rows(cols, measure, out, row0, |rec| {
        chain.walk_at(q, |op, f| rec.visit(op, f))
    })
    .frame(0)
}

/// [`pose_rows`] from the precomputed chain variables of a pose ([`Chain::variables`]), for
/// repeated evaluations at the same joint values (see [`Chain::walk_vars`]). Allocation-free.
pub fn pose_rows_vars(
    chain: &Chain,
    cols: &Columns,
    vars: &ChainVars,
    measure: Measure,
    out: &mut DMatrix<Real>,
    row0: usize,
) -> crate::numeric::Frame {
    pose_rows_lanes(chain, cols, [vars], measure, out, row0).frame(0)
}

/// [`pose_rows_vars`] of the first [`LANES`] poses of `vars` at once, each pose's rows below
/// the previous one's from row `row0`, returning their tool frames ([`Lanes`]): the same bits
/// as one pose at a time, in about a third of the time (four-wide vectors where the processor
/// has AVX2). Allocation-free. Panics when `vars` holds fewer than [`LANES`] poses.
pub fn pose_rows4(
    chain: &Chain,
    cols: &Columns,
    vars: &[ChainVars],
    measure: Measure,
    out: &mut DMatrix<Real>,
    row0: usize,
) -> Lanes<LANES> {
    let vars: &[ChainVars; LANES] = vars[..LANES].try_into().expect("LANES poses");
    crate::numeric::simd::dispatch(
        #[inline(always)]
        |_| pose_rows_lanes(chain, cols, vars.each_ref(), measure, out, row0),
    )
}

/// Poses per call of [`pose_rows4`].
pub const LANES: usize = 4;

/// The rows of `L` consecutive poses walked together ([`Chain::walk_lanes`]).
#[inline(always)]
fn pose_rows_lanes<const L: usize>(
    chain: &Chain,
    cols: &Columns,
    vars: [&ChainVars; L],
    measure: Measure,
    out: &mut DMatrix<Real>,
    row0: usize,
) -> Lanes<L> {
    record_rows(
        cols,
        measure,
        out,
        row0,
        #[inline(always)]
        |rec| {
            chain.walk_lanes(
                vars,
                #[inline(always)]
                |op, f| rec.visit(op, f),
            )
        },
    )
}

/// Writes the rows of `L` poses while `walk` walks the chain with the writer it is given, and
/// returns the tool frames the walk ends at (shared by [`pose_rows`] and [`pose_rows_lanes`]).
/// The rotation columns are recorded in an uninitialised array (zeroing [`MAX_OPS`] entries
/// per pose cost a fifth of the evaluation).
#[inline(always)]
fn record_rows<const L: usize>(
    cols: &Columns,
    measure: Measure,
    out: &mut DMatrix<Real>,
    row0: usize,
    walk: impl FnOnce(&mut Rows<'_, L>) -> Lanes<L>,
) -> Lanes<L> {
    let mut rotations = [const { MaybeUninit::<Recorded<L>>::uninit() }; MAX_OPS];
    let mut rec = Rows {
        stride: out.nrows(),
        cols,
        rows: measure.rows(),
        out,
        row0,
        rotations: &mut rotations,
        n: 0,
    };
    let end = walk(&mut rec);
    rec.finish(&end.p);
    end
}

/// Most rotation columns of a pose: three rotation operations per joint ([`MAX_JOINTS`]
/// joints), six for base and tool, and one compliance column per joint.
const MAX_OPS: usize = 4 * MAX_JOINTS + 6;

/// A rotation column waiting for the end point: axis `w` and origin `o` in the world (one
/// lane per pose), and the column.
type Recorded<const L: usize> = ([[Real; L]; 3], [[Real; L]; 3], usize);

/// Writes the rows of `L` poses during a chain walk. Translation columns are written on the
/// way out; a rotation column's `w × (pe − o)` needs the end point, so its axis `w`, origin `o`
/// and column are recorded (in an array of the caller's stack frame) and the column written
/// by [`Rows::finish`].
struct Rows<'a, const L: usize> {
    /// Rows of `out` (the distance between the starts of two columns).
    stride: usize,
    cols: &'a Columns,
    /// Rows per pose: 3, or 6 with the orientation.
    rows: usize,
    out: &'a mut DMatrix<Real>,
    row0: usize,
    rotations: &'a mut [MaybeUninit<Recorded<L>>],
    n: usize,
}

impl<const L: usize> Rows<'_, L> {
    #[inline(always)]
    fn visit(&mut self, op: &Op, f: &Lanes<L>) {
        if self.cols.any_var {
            if let Some(c) = op.var.and_then(|v| self.cols.of_var[v]) {
                self.write(c, op, f);
            }
        }
        if let Some(c) = self.cols.of_param[op.param] {
            self.write(c, op, f);
        }
    }

    /// Writes (or, for a rotation, records) column `c` of the operation `op`.
    #[inline(always)]
    fn write(&mut self, c: usize, op: &Op, f: &Lanes<L>) {
        let w = f.axis(op.kind.axis());
        let at = c * self.stride + self.row0;
        let rows = self.rows;
        let out = &mut self.out.as_mut_slice()[at..at + rows * L];
        if op.kind.is_rotation() {
            if rows == 6 {
                for l in 0..L {
                    for k in 0..3 {
                        out[6 * l + 3 + k] = w[k][l];
                    }
                }
            }
            self.rotations[self.n].write((w, f.p, c));
            self.n += 1;
        } else {
            for l in 0..L {
                for k in 0..3 {
                    out[rows * l + k] = w[k][l];
                }
                if rows == 6 {
                    out[6 * l + 3..6 * l + 6].fill(0.0);
                }
            }
        }
    }

    /// Writes the recorded rotation columns `w × (pe − o)`, `pe` the end points.
    #[inline(always)]
    fn finish(self, pe: &[[Real; L]; 3]) {
        let rows = self.rows;
        let out = self.out.as_mut_slice();
        for slot in &self.rotations[..self.n] {
            // SAFETY: `write` has set the first `n` entries.
            let (w, o, c) = unsafe { slot.assume_init_ref() };
            let at = c * self.stride + self.row0;
            let out = &mut out[at..at + rows * L];
            for l in 0..L {
                let d = [pe[0][l] - o[0][l], pe[1][l] - o[1][l], pe[2][l] - o[2][l]];
                let w = [w[0][l], w[1][l], w[2][l]];
                out[rows * l] = w[1] * d[2] - w[2] * d[1];
                out[rows * l + 1] = w[2] * d[0] - w[0] * d[2];
                out[rows * l + 2] = w[0] * d[1] - w[1] * d[0];
            }
        }
    }
}

/// The stacked identification Jacobian of `robot` over poses `qs` (internal units) for the
/// parameters of `cols`: `rows(measure) · m` × `cols.len()`. Harmonic and gravity-basis
/// columns ([`Columns::fill_terms`]) are those of the chain at `robot`'s geometry, its own
/// offsets left out (the nominal robot's, zero, for identifiability).
pub fn jacobian(
    robot: &Robot,
    cols: &Columns,
    qs: &[Vec<Real>],
    measure: Measure,
) -> DMatrix<Real> {
    let chain = robot.chain();
    let rows = measure.rows();
    let mut j = DMatrix::zeros(rows * qs.len(), cols.len());
    for (i, q) in qs.iter().enumerate() {
        pose_rows(&chain, cols, q, measure, &mut j, rows * i);
        if cols.has_harmonics() || cols.has_gravity() {
            let vars = chain.variables(q);
            let mut tau = [[0.0; GRAVITY_POINTS]; MAX_JOINTS];
            if cols.has_gravity() {
                crate::robot::gravity_basis::torques(robot, &chain, &vars, &mut tau);
            }
            cols.fill_terms(&vars, &tau, &mut j, rows * i, rows);
        }
    }
    j
}

/// The same Jacobian by central finite differences of forward kinematics (step `h` in mm or
/// rad): the independent check of [`jacobian`]. Orientation rows use the rotation vector of
/// `R(x+h) · R(x−h)ᵀ / 2h`.
pub fn jacobian_fd(
    robot: &Robot,
    cols: &Columns,
    qs: &[Vec<Real>],
    measure: Measure,
    h: Real,
) -> DMatrix<Real> {
    let rows = measure.rows();
    let n = robot.dof();
    let mut j = DMatrix::zeros(rows * qs.len(), cols.len());
    for (c, p) in cols.params().iter().enumerate() {
        let mut plus = robot.clone();
        plus.values[p.index(n)] += h;
        let mut minus = robot.clone();
        minus.values[p.index(n)] -= h;
        let (cp, cm) = (plus.chain(), minus.chain());
        for (i, q) in qs.iter().enumerate() {
            let (fp, fm) = (cp.fk(q), cm.fk(q));
            let dp = (fp.pos - fm.pos) / (2.0 * h);
            for k in 0..3 {
                j[(rows * i + k, c)] = dp[k];
            }
            if measure == Measure::Pose {
                let dw =
                    crate::numeric::rotation_vector(&(fp.rot * fm.rot.transpose())) / (2.0 * h);
                for k in 0..3 {
                    j[(rows * i + 3 + k, c)] = dw[k];
                }
            }
        }
    }
    j
}
