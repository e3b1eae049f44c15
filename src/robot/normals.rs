//! One robot in another of its standard DH forms. A link's common normal may point either way:
//! turned over, the link reads θ + π, −a, −α, −β and the next link's θ gains π, with the same
//! frames after it, as Rz(θ + π) Tz(d) Tx(−a) Rx(−α) Ry(−β) = Rz(θ) Tz(d) Tx(a) Rx(α) Ry(β) Rz(π)
//! (a half turn about z reverses x and y). The common-normal construction of a URDF
//! ([`super::urdf`]) points it along z_{i−1} × z_i, whose direction turns over with the sign of
//! the hair's tilt a calibration finds between two parallel axes: read back, an identified URDF
//! can hold a link of its nominal robot turned over (θ moved by π, `a` by twice its length),
//! although it is the same robot.

use super::{Convention, Param, Robot};
use crate::numeric::{nearest_turn, Real};

impl Robot {
    /// The same robot (the same forward kinematics for every joint value) with each link's
    /// common normal turned over where that brings the link's θ, a, α and β nearer `like`'s
    /// (angles to the nearest whole turn, lengths against `like`'s sum of `|a| + |d|`). For
    /// the standard DH conventions (`dh`, `dh_beta`) of robots of the same joint count and no
    /// coupling; the last link is kept (its turn would go into the tool frame). Any other robot
    /// is returned as it is.
    pub fn normals_as(&self, like: &Robot) -> Robot {
        let mut out = self.clone();
        let n = self.dof();
        let standard = |r: &Robot| matches!(r.convention, Convention::Dh | Convention::DhBeta);
        if n != like.dof() || !standard(self) || !standard(like) || self.coupling.is_some() {
            return out;
        }
        let scale = (0..n)
            .map(|j| like.get(Param::A(j)).abs() + like.get(Param::D(j)).abs())
            .sum::<Real>()
            .max(1.0);
        let pi = std::f64::consts::PI;
        for j in 0..n.saturating_sub(1) {
            let params = [
                Param::Theta(j),
                Param::A(j),
                Param::Alpha(j),
                Param::Beta(j),
            ];
            let kept = params.map(|p| out.get(p));
            let [theta, a, alpha, beta] = kept;
            let turned = [theta + pi, -a, -alpha, -beta];
            let w = params.map(|p| like.get(p));
            let distance = |v: [Real; 4]| {
                nearest_turn(v[0] - w[0]).abs()
                    + (v[1] - w[1]).abs() / scale
                    + nearest_turn(v[2] - w[2]).abs()
                    + (v[3] - w[3]).abs()
            };
            if distance(turned) < distance(kept) {
                for (p, v) in params.into_iter().zip(turned) {
                    out.set(p, v);
                }
                let next = Param::Theta(j + 1);
                out.set(next, out.get(next) + pi);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::builtin;

    /// The largest distance (mm) between the tool frames' origins and axes of two robots at
    /// a few joint values.
    fn fk_gap(a: &Robot, b: &Robot) -> Real {
        let mut worst: Real = 0.0;
        for k in 0..7 {
            let q: Vec<Real> = (0..a.dof())
                .map(|j| 0.3 * (k as Real) - 0.7 * (j as Real) + 0.1)
                .collect();
            let (fa, fb) = (a.fk(&q), b.fk(&q));
            worst = worst.max((fa.pos - fb.pos).norm());
            worst = worst.max(1000.0 * (fa.rot - fb.rot).abs().max());
        }
        worst
    }

    /// A robot with link `j` turned over by hand: the same FK, θ moved by π.
    fn turned(r: &Robot, j: usize) -> Robot {
        let mut t = r.clone();
        let pi = std::f64::consts::PI;
        t.set(Param::Theta(j), r.get(Param::Theta(j)) + pi);
        for p in [Param::A(j), Param::Alpha(j), Param::Beta(j)] {
            t.set(p, -r.get(p));
        }
        t.set(Param::Theta(j + 1), r.get(Param::Theta(j + 1)) - pi);
        t
    }

    #[test]
    fn a_turned_over_link_is_the_same_robot_and_is_turned_back() {
        for name in ["irb2600", "tx60"] {
            let nominal = builtin::load(name).unwrap();
            // A calibration's small moves on every parameter, β included where it is one.
            let mut moved = nominal.clone();
            for (i, p) in nominal.params().into_iter().enumerate() {
                let step = if p.is_length() { 0.3 } else { 2e-4 };
                moved.set(p, nominal.get(p) + step * (1.0 + (i % 3) as Real));
            }
            let flipped = turned(&turned(&moved, 1), 3);
            assert!(
                fk_gap(&moved, &flipped) < 1e-9,
                "{name}: not the same robot"
            );
            assert!((flipped.get(Param::Theta(1)) - moved.get(Param::Theta(1))).abs() > 3.0);
            let back = flipped.normals_as(&nominal);
            assert!(fk_gap(&back, &moved) < 1e-9, "{name}: FK changed");
            for p in moved.params() {
                let d = nearest_turn(back.get(p) - moved.get(p));
                assert!(
                    d.abs() < 1e-9,
                    "{name}: {p} is {} not {}",
                    back.get(p),
                    moved.get(p)
                );
            }
            // A robot already in the nominal's form is kept as it is.
            assert_eq!(moved.normals_as(&nominal).values, moved.values);
        }
    }
}
