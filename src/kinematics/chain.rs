//! The chain of elementary operations behind forward kinematics and the Jacobian.

use super::{Convention, JointType, Param, Robot};
use crate::math::{Frame, Mat3, Real, Vec3};

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
    /// Precomputed (sin, cos) of `value` for rotations without a variable.
    sc: (Real, Real),
}

/// The chain variables of one pose and their (sin, cos), from [`Chain::variables`].
pub type ChainVars = ([Real; 16], [(Real, Real); 16]);

/// A robot compiled into elementary operations for one set of parameter values.
#[derive(Clone, Debug)]
pub struct Chain {
    ops: Vec<Op>,
    dof: usize,
    coupling: Option<super::Coupling>,
}

/// Applies `op` (with total value `v`, sin/cos `sc` for rotations) to the frame `(r, p)`.
#[inline(always)]
fn apply(kind: OpKind, v: Real, sc: (Real, Real), r: &mut Mat3, p: &mut Vec3) {
    let (s, c) = sc;
    match kind {
        OpKind::Tx | OpKind::Ty | OpKind::Tz => {
            let a = kind.axis();
            *p += r.column(a) * v;
        }
        OpKind::Rx => rotate_cols(r, 1, 2, s, c),
        OpKind::Ry => rotate_cols(r, 2, 0, s, c),
        OpKind::Rz => rotate_cols(r, 0, 1, s, c),
    }
}

/// `R ← R · Rot`, for a rotation about the axis completing (i, j) to a right-handed triple:
/// column i ← c·i + s·j, column j ← −s·i + c·j.
#[inline(always)]
fn rotate_cols(r: &mut Mat3, i: usize, j: usize, s: Real, c: Real) {
    for k in 0..3 {
        let a = r[(k, i)];
        let b = r[(k, j)];
        r[(k, i)] = c * a + s * b;
        r[(k, j)] = -s * a + c * b;
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
                sc: value.sin_cos(),
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
                op.sc = v.sin_cos();
            }
        }
    }

    /// The operations, base first.
    pub fn ops(&self) -> &[Op] {
        &self.ops
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// Chain variables from joint values (see [`Robot::chain_values`]); `q.len()` ≤ 16.
    #[inline]
    fn vars(&self, q: &[Real]) -> [Real; 16] {
        let mut c = [0.0; 16];
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
    pub fn walk(&self, q: &[Real], visit: impl FnMut(&Op, &Mat3, &Vec3)) -> Frame {
        debug_assert_eq!(q.len(), self.dof);
        let c = self.vars(q);
        self.walk_with(
            |op, v| {
                let t = op.value + c[v];
                (t, t.sin_cos())
            },
            visit,
        )
    }

    /// The chain variables of joint values `q` (internal units, `q.len()` ≤ 16) and their
    /// sines and cosines, for [`Chain::walk_vars`]: with fixed joint values these are computed
    /// once and reused whatever the parameter values.
    pub fn variables(&self, q: &[Real]) -> ChainVars {
        let c = self.vars(q);
        let mut sc = [(0.0, 1.0); 16];
        for (k, v) in c.iter().take(q.len()).enumerate() {
            sc[k] = v.sin_cos();
        }
        (c, sc)
    }

    /// [`Chain::walk`] from precomputed chain variables ([`Chain::variables`]): a rotation
    /// driven by a variable uses `sin(a + v) = sin a cos v + cos a sin v` and
    /// `cos(a + v) = cos a cos v − sin a sin v` with the operation's own (sin a, cos a)
    /// instead of a new `sin_cos` (equal to rounding, ~1e-16). Allocation-free.
    #[inline]
    pub fn walk_vars(
        &self,
        vars: &[Real; 16],
        sc: &[(Real, Real); 16],
        visit: impl FnMut(&Op, &Mat3, &Vec3),
    ) -> Frame {
        self.walk_with(
            |op, v| {
                let (sa, ca) = op.sc;
                let (sv, cv) = sc[v];
                (op.value + vars[v], (sa * cv + ca * sv, ca * cv - sa * sv))
            },
            visit,
        )
    }

    /// The walk of [`Chain::walk`] and [`Chain::walk_vars`]: an operation driven by chain
    /// variable `v` takes its value and (sin, cos) from `driven(op, v)`, a fixed one its own.
    #[inline(always)]
    fn walk_with(
        &self,
        driven: impl Fn(&Op, usize) -> (Real, (Real, Real)),
        mut visit: impl FnMut(&Op, &Mat3, &Vec3),
    ) -> Frame {
        let mut r = Mat3::identity();
        let mut p = Vec3::zeros();
        for op in &self.ops {
            visit(op, &r, &p);
            let (t, sc) = match op.var {
                None => (op.value, op.sc),
                Some(v) => driven(op, v),
            };
            apply(op.kind, t, sc, &mut r, &mut p);
        }
        Frame { rot: r, pos: p }
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
    use crate::math::{rot_x, rot_y, rot_z};
    use approx::assert_relative_eq;

    #[test]
    fn walk_vars_matches_walk() {
        for name in ["irb2600", "irb2600-mdh", "tx60", "guo-3t2r"] {
            let robot = crate::robots::load(name).expect("robot");
            let chain = robot.chain();
            let q: Vec<Real> = (0..robot.dof()).map(|k| 0.3 - 0.17 * k as Real).collect();
            let (v, sc) = chain.variables(&q);
            let (a, b) = (chain.fk(&q), chain.walk_vars(&v, &sc, |_, _, _| {}));
            assert_relative_eq!(a.pos, b.pos, epsilon = 1e-10);
            assert_relative_eq!(a.rot, b.rot, epsilon = 1e-14);
        }
    }

    #[test]
    fn set_values_equals_a_fresh_chain() {
        let nominal = crate::robots::irb2600();
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
            let mut r = r0;
            let mut p = Vec3::zeros();
            apply(kind, 0.7, 0.7f64.sin_cos(), &mut r, &mut p);
            assert_relative_eq!(r, r0 * m, epsilon = 1e-14);
        }
    }
}
