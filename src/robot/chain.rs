//! The chain of elementary operations behind forward kinematics and the Jacobian.

use super::{Convention, JointType, Param, Robot, MAX_JOINTS};
use crate::numeric::{Frame, Mat3, Real, Vec3};

/// An elementary operation: a rotation about, or a translation along, one local axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpKind {
    /// Rotation about local x.
    Rx,
    /// Rotation about local y.
    Ry,
    /// Rotation about local z.
    Rz,
    /// Translation along local x.
    Tx,
    /// Translation along local y.
    Ty,
    /// Translation along local z.
    Tz,
}

impl OpKind {
    /// The local axis (0 = x, 1 = y, 2 = z).
    pub fn axis(self) -> usize {
        match self {
            OpKind::Rx | OpKind::Tx => 0,
            OpKind::Ry | OpKind::Ty => 1,
            OpKind::Rz | OpKind::Tz => 2,
        }
    }

    /// Whether the operation is a rotation.
    pub fn is_rotation(self) -> bool {
        matches!(self, OpKind::Rx | OpKind::Ry | OpKind::Rz)
    }
}

/// One operation of the chain with the parameter that sets its constant part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Op {
    /// What the operation does.
    pub kind: OpKind,
    /// The constant part (mm or rad): the parameter's value.
    pub value: Real,
    /// Index of the chain variable added to the constant, if any (a joint variable).
    pub var: Option<usize>,
    /// Index of the parameter in the flat vector.
    pub param: usize,
    /// Precomputed (sin, cos) of `value` for rotations ((0, 1) for translations, which do not
    /// read it).
    sc: (Real, Real),
}

/// The (sin, cos) an operation keeps of its value: a rotation's, or (0, 1) for a translation.
fn rotation_sc(kind: OpKind, value: Real) -> (Real, Real) {
    if kind.is_rotation() {
        value.sin_cos()
    } else {
        (0.0, 1.0)
    }
}

/// The chain variables of one pose and their (sin, cos), from [`Chain::variables`].
pub type ChainVars = ([Real; MAX_JOINTS], [(Real, Real); MAX_JOINTS]);

/// Most operations a chain has: base and tool (six each) and five per joint, for the 16
/// joints of [`ChainVars`].
pub const MAX_OPS: usize = 12 + 5 * 16;

/// Every operation's constant part for other parameter values, with its (sin, cos)
/// ([`Chain::op_values`]): what [`Chain::set_values`] would set, kept beside the chain so that
/// one chain serves walks with different parameter values at once (the searches evaluate
/// their fitness in parallel, [`Chain::walk_lanes_values`]). On the stack: making and walking
/// it allocate nothing.
#[derive(Clone, Copy, Debug)]
pub struct OpValues {
    value: [Real; MAX_OPS],
    sc: [(Real, Real); MAX_OPS],
}

/// A robot compiled into elementary operations for one set of parameter values.
#[derive(Clone, Debug)]
pub struct Chain {
    ops: Vec<Op>,
    dof: usize,
    coupling: Option<super::Coupling>,
}

/// The frames of `L` poses walked together ([`Chain::walk_lanes`]), as a structure of
/// arrays: lane `l` of every entry belongs to pose `l`, so that the same operation applied
/// to all lanes compiles to vector instructions. Every lane sees exactly the arithmetic of a
/// walk of its pose alone, in the same order: the result is the same to the bit whatever `L`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lanes<const L: usize> {
    /// Rotation, `r[row][column]`.
    pub r: [[[Real; L]; 3]; 3],
    /// Origin.
    pub p: [[Real; L]; 3],
}

impl<const L: usize> Lanes<L> {
    /// `L` identity frames.
    fn identity() -> Self {
        let mut r = [[[0.0; L]; 3]; 3];
        for (k, row) in r.iter_mut().enumerate() {
            row[k] = [1.0; L];
        }
        Lanes {
            r,
            p: [[0.0; L]; 3],
        }
    }

    /// Column `a` of the rotations (the local axis `a` in the world).
    #[inline(always)]
    pub fn axis(&self, a: usize) -> [[Real; L]; 3] {
        [self.r[0][a], self.r[1][a], self.r[2][a]]
    }

    /// Lane `l`'s rotation.
    #[inline(always)]
    pub fn rot(&self, l: usize) -> Mat3 {
        let r = &self.r;
        Mat3::new(
            r[0][0][l], r[0][1][l], r[0][2][l], r[1][0][l], r[1][1][l], r[1][2][l], r[2][0][l],
            r[2][1][l], r[2][2][l],
        )
    }

    /// Lane `l`'s origin.
    #[inline(always)]
    pub fn pos(&self, l: usize) -> Vec3 {
        Vec3::new(self.p[0][l], self.p[1][l], self.p[2][l])
    }

    /// Lane `l`'s frame.
    #[inline(always)]
    pub fn frame(&self, l: usize) -> Frame {
        Frame {
            rot: self.rot(l),
            pos: self.pos(l),
        }
    }
}

/// Applies an operation of kind `kind` with total values `v` and (sin, cos) `(s, c)` (used by
/// rotations), one per lane, to the frames `f`.
#[inline(always)]
fn apply<const L: usize>(
    kind: OpKind,
    v: &[Real; L],
    s: &[Real; L],
    c: &[Real; L],
    f: &mut Lanes<L>,
) {
    match kind {
        OpKind::Tx | OpKind::Ty | OpKind::Tz => {
            let a = kind.axis();
            for k in 0..3 {
                let (p, r) = (f.p[k], f.r[k][a]);
                f.p[k] = std::array::from_fn(|l| p[l] + r[l] * v[l]);
            }
        }
        OpKind::Rx => rotate_cols(&mut f.r, 1, 2, s, c),
        OpKind::Ry => rotate_cols(&mut f.r, 2, 0, s, c),
        OpKind::Rz => rotate_cols(&mut f.r, 0, 1, s, c),
    }
}

/// `R ← R · Rot`, for a rotation about the axis completing (i, j) to a right-handed triple:
/// column i ← c·i + s·j, column j ← −s·i + c·j.
#[inline(always)]
fn rotate_cols<const L: usize>(
    r: &mut [[[Real; L]; 3]; 3],
    i: usize,
    j: usize,
    s: &[Real; L],
    c: &[Real; L],
) {
    for row in r.iter_mut() {
        for l in 0..L {
            let a = row[i][l];
            let b = row[j][l];
            row[i][l] = c[l] * a + s[l] * b;
            row[j][l] = -s[l] * a + c[l] * b;
        }
    }
}

/// An operation's values, sines and cosines in `L` lanes.
type LaneValues<const L: usize> = ([Real; L], [Real; L], [Real; L]);

/// The values and (sin, cos) per lane of an operation with constant part `a`, (sin a, cos a),
/// driven by chain variable `v`, from each lane's chain variables: `a + v`, and
/// `sin(a + v) = sin a cos v + cos a sin v`, `cos(a + v) = cos a cos v − sin a sin v`.
#[inline(always)]
fn driven_by<const L: usize>(
    vars: [&ChainVars; L],
) -> impl Fn(Real, (Real, Real), usize) -> LaneValues<L> + '_ {
    #[inline(always)]
    move |a, (sa, ca), v| {
        let mut t = [0.0; L];
        let mut s = [0.0; L];
        let mut c = [0.0; L];
        for l in 0..L {
            let (sv, cv) = vars[l].1[v];
            t[l] = a + vars[l].0[v];
            s[l] = sa * cv + ca * sv;
            c[l] = ca * cv - sa * sv;
        }
        (t, s, c)
    }
}

impl Chain {
    /// Compiles `robot` with its current parameter values.
    pub fn new(robot: &Robot) -> Chain {
        let n = robot.dof();
        let mut ops = Vec::with_capacity(5 * n + 12);
        let mut push = |kind: OpKind, p: Param, var: Option<usize>| {
            let i = p.index(n);
            let value = robot.values[i];
            ops.push(Op {
                kind,
                value,
                var,
                param: i,
                sc: rotation_sc(kind, value),
            });
        };
        // Base: Trans(x, y, z) · Rz · Ry · Rx.
        for (c, k) in [(0, OpKind::Tx), (1, OpKind::Ty), (2, OpKind::Tz)] {
            push(k, Param::Base(c), None);
        }
        for (c, k) in [(5, OpKind::Rz), (4, OpKind::Ry), (3, OpKind::Rx)] {
            push(k, Param::Base(c), None);
        }
        for (j, joint) in robot.joints.iter().enumerate() {
            let (tv, dv) = match joint.kind {
                JointType::Revolute => (Some(j), None),
                JointType::Prismatic => (None, Some(j)),
            };
            match robot.convention {
                Convention::Dh | Convention::DhBeta => {
                    push(OpKind::Rz, Param::Theta(j), tv);
                    push(OpKind::Tz, Param::D(j), dv);
                    push(OpKind::Tx, Param::A(j), None);
                    push(OpKind::Rx, Param::Alpha(j), None);
                    if robot.convention == Convention::DhBeta {
                        push(OpKind::Ry, Param::Beta(j), None);
                    }
                }
                Convention::Mdh => {
                    push(OpKind::Rx, Param::Alpha(j), None);
                    push(OpKind::Tx, Param::A(j), None);
                    push(OpKind::Rz, Param::Theta(j), tv);
                    push(OpKind::Tz, Param::D(j), dv);
                    push(OpKind::Ry, Param::Beta(j), None);
                }
            }
        }
        for (c, k) in [(0, OpKind::Tx), (1, OpKind::Ty), (2, OpKind::Tz)] {
            push(k, Param::Tool(c), None);
        }
        for (c, k) in [(5, OpKind::Rz), (4, OpKind::Ry), (3, OpKind::Rx)] {
            push(k, Param::Tool(c), None);
        }
        Chain {
            ops,
            dof: n,
            coupling: robot.coupling,
        }
    }

    /// Sets every operation's constant part from the flat parameter vector `values` (the
    /// layout of [`Robot::values`] for the robot the chain was compiled from), in place and
    /// without allocating: the same chain as [`Chain::new`] of that robot with those values.
    /// Only the sines and cosines of the operations whose value changed are recomputed.
    ///
    /// `values` shorter than the chain's largest parameter index leaves the chain unchanged.
    pub fn set_values(&mut self, values: &[Real]) {
        if self.ops.iter().any(|op| op.param >= values.len()) {
            return;
        }
        for op in &mut self.ops {
            let v = values[op.param];
            if v.to_bits() != op.value.to_bits() {
                op.value = v;
                op.sc = rotation_sc(op.kind, v);
            }
        }
    }

    /// The operations' constant parts with `errors[op.param]` added to each (`errors` in the
    /// layout of [`Robot::values`]): the values of [`Chain::set_values`] of the chain's values
    /// plus `errors`, to the bit, without changing the chain. As there, only the rotations
    /// whose value changed get a new `sin_cos`. `errors` shorter than the chain's largest
    /// parameter index adds nothing.
    ///
    /// # Panics
    ///
    /// If the chain has more than [`MAX_OPS`] operations (more than 16 joints).
    pub fn op_values(&self, errors: &[Real]) -> OpValues {
        assert!(self.ops.len() <= MAX_OPS, "more than {MAX_OPS} operations");
        let mut out = OpValues {
            value: [0.0; MAX_OPS],
            sc: [(0.0, 1.0); MAX_OPS],
        };
        let add = self.ops.iter().all(|op| op.param < errors.len());
        for ((op, value), sc) in self.ops.iter().zip(&mut out.value).zip(&mut out.sc) {
            let v = if add {
                op.value + errors[op.param]
            } else {
                op.value
            };
            *value = v;
            *sc = if v.to_bits() == op.value.to_bits() {
                op.sc
            } else {
                rotation_sc(op.kind, v)
            };
        }
        out
    }

    /// The operations, base first.
    pub fn ops(&self) -> &[Op] {
        &self.ops
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// Chain variables (the value each joint adds to θ or d) from joint values `q`
    /// (internal units; `q` itself without a coupling); `q.len()` ≤ [`MAX_JOINTS`].
    #[inline]
    fn vars(&self, q: &[Real]) -> [Real; MAX_JOINTS] {
        let mut c = [0.0; MAX_JOINTS];
        c[..q.len()].copy_from_slice(q);
        if let Some(super::Coupling::Differential { l1_mm }) = self.coupling {
            c[0] = ((q[0] - q[1]) / l1_mm).atan();
            c[1] = 0.5 * (q[0] + q[1]);
        }
        c
    }

    /// Walks the chain at joint values `q` (internal units), calling `visit(op, frame_before)`
    /// for every operation with the frame just before it (rotation, origin), and returns the
    /// final frame. Allocation-free.
    #[inline]
    pub fn walk(&self, q: &[Real], mut visit: impl FnMut(&Op, &Mat3, &Vec3)) -> Frame {
        self.walk_at(q, |op, f| visit(op, &f.rot(0), &f.pos(0)))
            .frame(0)
    }

    /// [`Chain::walk`] visiting with the one-lane frame of [`Chain::walk_lanes`].
    #[inline(always)]
    pub fn walk_at(&self, q: &[Real], visit: impl FnMut(&Op, &Lanes<1>)) -> Lanes<1> {
        debug_assert_eq!(q.len(), self.dof);
        let c = self.vars(q);
        self.walk_with(
            |_, op| (op.value, op.sc),
            |value, _, v| {
                let t = value + c[v];
                let (s, cs) = crate::numeric::sin_cos(t);
                ([t], [s], [cs])
            },
            visit,
        )
    }

    /// The chain variables of joint values `q` (internal units, `q.len()` ≤ [`MAX_JOINTS`])
    /// and their sines and cosines ([`crate::numeric::sin_cos_slice`]), for
    /// [`Chain::walk_vars`]: with fixed joint values these are computed once and reused
    /// whatever the parameter values.
    pub fn variables(&self, q: &[Real]) -> ChainVars {
        let c = self.vars(q);
        let mut sc = [(0.0, 1.0); MAX_JOINTS];
        crate::numeric::sin_cos_slice(&c[..q.len()], &mut sc[..q.len()]);
        (c, sc)
    }

    /// [`Chain::variables`] of every pose of `qs`, the same bits: all the poses' sines and
    /// cosines in one [`crate::numeric::sin_cos_slice`] (sixteen at a time, with no lane left
    /// empty between poses).
    pub fn variables_of<Q: AsRef<[Real]>>(&self, qs: &[Q]) -> Vec<ChainVars> {
        let mut out: Vec<ChainVars> = qs
            .iter()
            .map(|q| (self.vars(q.as_ref()), [(0.0, 1.0); MAX_JOINTS]))
            .collect();
        let values: Vec<Real> = out
            .iter()
            .zip(qs)
            .flat_map(|(v, q)| v.0[..q.as_ref().len()].iter().copied())
            .collect();
        let mut sc = vec![(0.0, 0.0); values.len()];
        crate::numeric::sin_cos_slice(&values, &mut sc);
        let mut at = 0;
        for (v, q) in out.iter_mut().zip(qs) {
            let n = q.as_ref().len();
            v.1[..n].copy_from_slice(&sc[at..at + n]);
            at += n;
        }
        out
    }

    /// [`Chain::walk`] from precomputed chain variables ([`Chain::variables`]): a rotation
    /// driven by a variable uses `sin(a + v) = sin a cos v + cos a sin v` and
    /// `cos(a + v) = cos a cos v − sin a sin v` with the operation's own (sin a, cos a)
    /// instead of a new `sin_cos` (equal to rounding, ~1e-16). Allocation-free.
    #[inline]
    pub fn walk_vars(&self, vars: &ChainVars, mut visit: impl FnMut(&Op, &Mat3, &Vec3)) -> Frame {
        self.walk_lanes([vars], |op, f| visit(op, &f.rot(0), &f.pos(0)))
            .frame(0)
    }

    /// [`Chain::walk_vars`] of `L` poses at once (see [`Lanes`]), each from its chain
    /// variables: `visit(op, frames_before)` for every operation. The same bits as `L` walks
    /// one by one. Allocation-free.
    #[inline(always)]
    pub fn walk_lanes<const L: usize>(
        &self,
        vars: [&ChainVars; L],
        visit: impl FnMut(&Op, &Lanes<L>),
    ) -> Lanes<L> {
        self.walk_with(|_, op| (op.value, op.sc), driven_by(vars), visit)
    }

    /// [`Chain::walk_lanes`] of the chain with the operations' constant parts `values`
    /// ([`Chain::op_values`]) in place of its own: the same bits as a walk of the chain after
    /// [`Chain::set_values`] with those values. Allocation-free.
    #[inline(always)]
    pub fn walk_lanes_values<const L: usize>(
        &self,
        values: &OpValues,
        vars: [&ChainVars; L],
        visit: impl FnMut(&Op, &Lanes<L>),
    ) -> Lanes<L> {
        self.walk_with(
            #[inline(always)]
            |o, _| (values.value[o], values.sc[o]),
            driven_by(vars),
            visit,
        )
    }

    /// The walk of [`Chain::walk_at`], [`Chain::walk_lanes`] and [`Chain::walk_lanes_values`]:
    /// operation `o` has the constant part and (sin, cos) `constant(o, op)`; one driven by
    /// chain variable `v` takes its values and (sin, cos) per lane from
    /// `driven(constant, (sin, cos), v)`, a fixed one its constant in every lane.
    #[inline(always)]
    fn walk_with<const L: usize>(
        &self,
        constant: impl Fn(usize, &Op) -> (Real, (Real, Real)),
        driven: impl Fn(Real, (Real, Real), usize) -> LaneValues<L>,
        mut visit: impl FnMut(&Op, &Lanes<L>),
    ) -> Lanes<L> {
        let mut f = Lanes::identity();
        for (o, op) in self.ops.iter().enumerate() {
            visit(op, &f);
            let (value, sc) = constant(o, op);
            let (t, s, c) = match op.var {
                // A fixed rotation or translation by zero (the base and tool of most robots,
                // rows with d = 0, a = 0 or α = 0) leaves the frame as it is: R·Rot(±0) = R and
                // p + R·0 = p exactly (c = 1, s = ±0), up to the sign of a zero entry.
                None if value == 0.0 => continue,
                None => ([value; L], [sc.0; L], [sc.1; L]),
                Some(v) => driven(value, sc, v),
            };
            apply(op.kind, &t, &s, &c, &mut f);
        }
        f
    }

    /// Forward kinematics: the tool frame in the world at joint values `q` (rad / mm).
    #[inline]
    pub fn fk(&self, q: &[Real]) -> Frame {
        self.walk(q, |_, _, _| {})
    }

    /// The world frames of the joint axes at `q`: for each joint, the frame just before the
    /// operation its variable drives (its local z is the joint axis, its origin on the axis).
    /// Used by the compliance models.
    pub fn joint_frames(&self, q: &[Real]) -> Vec<Frame> {
        let mut out = vec![Frame::identity(); self.dof];
        self.walk(q, |op, r, p| {
            if let Some(v) = op.var {
                out[v] = Frame { rot: *r, pos: *p };
            }
        });
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::{rot_x, rot_y, rot_z};
    use approx::assert_relative_eq;

    /// All poses' chain variables at once are each pose's alone, to the bit.
    #[test]
    fn variables_of_are_the_variables_of_each_pose() {
        for name in ["irb2600", "tx60", "guo-3t2r"] {
            let robot = crate::robot::builtin::load(name).expect("robot");
            let chain = robot.chain();
            let qs: Vec<Vec<Real>> = (0..7)
                .map(|i| {
                    (0..robot.dof())
                        .map(|k| 0.9 * (i as Real) - 0.31 * k as Real)
                        .collect()
                })
                .collect();
            for (q, (c, sc)) in qs.iter().zip(chain.variables_of(&qs)) {
                let (c1, sc1) = chain.variables(q);
                assert_eq!(c.map(Real::to_bits), c1.map(Real::to_bits), "{name}");
                let bits =
                    |v: [(Real, Real); MAX_JOINTS]| v.map(|(s, c)| (s.to_bits(), c.to_bits()));
                assert_eq!(bits(sc), bits(sc1), "{name}");
            }
        }
    }

    #[test]
    fn walk_vars_matches_walk() {
        for name in ["irb2600", "irb2600-mdh", "tx60", "guo-3t2r"] {
            let robot = crate::robot::builtin::load(name).expect("robot");
            let chain = robot.chain();
            let q: Vec<Real> = (0..robot.dof()).map(|k| 0.3 - 0.17 * k as Real).collect();
            let (v, sc) = chain.variables(&q);
            let (a, b) = (chain.fk(&q), chain.walk_vars(&(v, sc), |_, _, _| {}));
            assert_relative_eq!(a.pos, b.pos, epsilon = 1e-10);
            assert_relative_eq!(a.rot, b.rot, epsilon = 1e-14);
        }
    }

    /// The walk with other operation values is the walk of the chain set to those values, to
    /// the bit, in one lane and in four.
    #[test]
    fn walk_lanes_values_is_the_walk_after_set_values() {
        let bits = |f: &Lanes<1>| {
            (
                f.r.map(|r| r.map(|c| c[0].to_bits())),
                f.p.map(|p| p[0].to_bits()),
            )
        };
        for name in ["irb2600", "irb2600-mdh", "tx60", "guo-3t2r"] {
            let robot = crate::robot::builtin::load(name).expect("robot");
            let chain = robot.chain();
            // Some errors zero, so that both keep some operations' own values.
            let errors: Vec<Real> = (0..robot.values.len())
                .map(|k| 1e-3 * ((k * 7 % 5) as Real - 2.0))
                .collect();
            let mut set = chain.clone();
            let sum: Vec<Real> = robot
                .values
                .iter()
                .zip(&errors)
                .map(|(a, e)| a + e)
                .collect();
            set.set_values(&sum);
            let values = chain.op_values(&errors);
            let qs: Vec<Vec<Real>> = (0..4)
                .map(|i| {
                    (0..robot.dof())
                        .map(|k| 0.7 * i as Real - 0.23 * k as Real)
                        .collect()
                })
                .collect();
            let vars = chain.variables_of(&qs);
            let four = chain.walk_lanes_values(
                &values,
                std::array::from_fn::<_, 4, _>(|l| &vars[l]),
                |_, _| {},
            );
            for (l, v) in vars.iter().enumerate() {
                let a = chain.walk_lanes_values(&values, [v], |_, _| {});
                let b = set.walk_lanes([v], |_, _| {});
                assert_eq!(bits(&a), bits(&b), "{name}");
                assert_eq!(four.frame(l), a.frame(0), "{name}");
            }
            // Too short an error vector adds nothing.
            let none = chain.op_values(&[1.0; 3]);
            let (a, b) = (
                chain.walk_lanes_values(&none, [&vars[0]], |_, _| {}),
                chain.walk_lanes([&vars[0]], |_, _| {}),
            );
            assert_eq!(bits(&a), bits(&b), "{name}");
        }
    }

    #[test]
    fn set_values_equals_a_fresh_chain() {
        let nominal = crate::robot::builtin::irb2600();
        let mut chain = nominal.chain();
        let mut other = nominal.clone();
        for (k, v) in other.values.iter_mut().enumerate() {
            *v += 0.01 * (k as Real + 1.0);
        }
        chain.set_values(&other.values);
        let fresh = other.chain();
        assert_eq!(chain.ops(), fresh.ops());
        let q = [0.1, -0.4, 0.3, 1.0, -0.7, 0.2];
        assert_eq!(chain.fk(&q).pos, fresh.fk(&q).pos);
        assert_ne!(chain.fk(&q).pos, nominal.fk(&q).pos);
        // Too short a vector changes nothing.
        chain.set_values(&[0.0; 3]);
        assert_eq!(chain.ops(), fresh.ops());
    }

    #[test]
    fn elementary_ops_match_rotation_matrices() {
        let r0 = rot_z(0.3) * rot_x(-0.4);
        for (kind, m) in [
            (OpKind::Rx, rot_x(0.7)),
            (OpKind::Ry, rot_y(0.7)),
            (OpKind::Rz, rot_z(0.7)),
        ] {
            let mut f = Lanes::<1>::identity();
            for (i, row) in f.r.iter_mut().enumerate() {
                for (k, e) in row.iter_mut().enumerate() {
                    *e = [r0[(i, k)]];
                }
            }
            let (s, c) = 0.7f64.sin_cos();
            apply(kind, &[0.7], &[s], &[c], &mut f);
            assert_relative_eq!(f.rot(0), r0 * m, epsilon = 1e-14);
        }
    }
}
