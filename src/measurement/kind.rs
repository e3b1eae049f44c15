//! Measurement kinds beyond the laser tracker: what each instrument observes of the tool
//! point, as residual rows with their analytic Jacobian rows.
//!
//! Every kind observes functions of the model's tool frames (position `p_i`, rotation `R_i`)
//! and, for some, of the instrument's own unknowns (the nuisance parameters: a pivot, plane or
//! sphere parameters). Given the tool frames and their Jacobian rows `J_p` (position) and
//! `J_ω` (rotation, world frame) over the robot's parameters, [`rows`] writes each
//! observation's residual `measured − model` and the derivative of the model by the robot's
//! parameters and by the nuisance parameters. The identification problem
//! ([`crate::identify::kind::KindProblem`]) wraps this one function, so every Jacobian method
//! picks every kind up through it.
//!
//! | kind | observation | rows | nuisance |
//! |---|---|---|---|
//! | `position`, `multi-target` | the points `p_i + R_i o_t` of the targets `o_t` (tool frame) | 3 per target | none |
//! | `distance` (pivot) | `|p_i − c|`, the length from a fixed pivot `c` (ballbar, draw-wire) | 1 | `c` (3) |
//! | `distance` (chain) | `|p_{i+1} − p_i|`, the length between consecutive poses (interferometer along a line) | 1 | none |
//! | `plane` | `p_k − (c₀ + c₁ p_u + c₂ p_v) = 0` on plane `l` (axis `k`) | 1 | 3 per plane |
//! | `sphere` | `|p_i − c_l| − ρ_l = 0` on sphere `l` of known radius `ρ_l` | 1 | `c_l` (3 per sphere) |
//! | `socket` | `p_i − s_l = 0` in socket `l`, `s_l = s_1 + d_l u(θ_l, φ_l)` at the known distance `d_l` from socket 1 | 3 | `s_1` (3), `θ_l, φ_l` (2 per further socket) |
//!
//! A socket's direction from socket 1 is `u(θ, φ) = (cos φ cos θ, cos φ sin θ, sin φ)`
//! (azimuth θ, elevation φ in the base frame), so the known distances hold exactly; the
//! parametrisation is singular only for sockets straight above or below socket 1.

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};
use crate::numeric::{skew, Real, Vec3};

/// A measurement kind: what the instrument observes per pose.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "kebab-case")]
pub enum Kind {
    /// The tool point (laser tracker, 3 rows).
    Position,
    /// The tool point and orientation (6-DOF tracker probe, 6 rows).
    Pose,
    /// Lengths: from a fixed pivot, or between consecutive poses' tool points.
    Distance,
    /// Tool points on one of several planes of unknown parameters.
    Plane,
    /// Tool points on spheres of known radius and unknown centre.
    Sphere,
    /// Several tool points per pose (reflectors on one flange).
    MultiTarget,
    /// The tool point held in one of several sockets at known distances apart.
    Socket,
}

impl Kind {
    /// The name used in files and on the command line.
    pub fn as_str(self) -> &'static str {
        self.into()
    }

    /// The kind named `name` (as [`Kind::as_str`] writes it); refused as the setting `key`,
    /// with the names allowed, otherwise.
    pub fn named(key: &str, name: &str) -> crate::error::Result<Kind> {
        name.parse().map_err(|_| {
            let allowed = <Kind as strum::VariantNames>::VARIANTS.join(", ");
            crate::error::Error::setting(
                key,
                format!("\"{name}\" is not a measure; allowed: {allowed}"),
            )
        })
    }
}

/// The geometry of one instrument: everything the residual needs besides the tool frames.
#[derive(Clone, Debug, PartialEq)]
pub enum Instrument {
    /// Several targets at known offsets `o_t` in the tool frame (`[0, 0, 0]` alone: the
    /// tracker's position).
    Targets(Vec<Vec3>),
    /// Lengths from one pivot of unknown position (`true`), or between consecutive poses.
    Distance {
        /// A fixed pivot (its position is identified) rather than consecutive pairs.
        pivot: bool,
    },
    /// Planes of unknown parameters; each plane is `p[axis] = c₀ + c₁ p[u] + c₂ p[v]` with
    /// `(u, v)` the other two axes in cyclic order.
    Planes(Vec<usize>),
    /// Spheres of known radius (mm) and unknown centre.
    Spheres(Vec<Real>),
    /// Sockets: each one's known distance (mm) from socket 1 (0 for socket 1 itself); the
    /// position of socket 1 and the directions of the others are unknown.
    Sockets(Vec<Real>),
}

impl Instrument {
    /// The planes or spheres and the points each needs at least for its first guess
    /// ([`nuisance_guess`]); `None` for the other instruments.
    pub fn surfaces(&self) -> Option<(usize, usize)> {
        match self {
            Instrument::Planes(a) => Some((a.len(), 4)),
            Instrument::Spheres(s) => Some((s.len(), 5)),
            _ => None,
        }
    }

    /// The kind of data this instrument delivers.
    pub fn kind(&self) -> Kind {
        match self {
            Instrument::Targets(t) if t.len() == 1 && t[0] == Vec3::zeros() => Kind::Position,
            Instrument::Targets(_) => Kind::MultiTarget,
            Instrument::Distance { .. } => Kind::Distance,
            Instrument::Planes(_) => Kind::Plane,
            Instrument::Spheres(_) => Kind::Sphere,
            Instrument::Sockets(_) => Kind::Socket,
        }
    }

    /// Number of nuisance parameters (the instrument's own unknowns).
    pub fn nuisance(&self) -> usize {
        match self {
            Instrument::Targets(_) | Instrument::Distance { pivot: false } => 0,
            Instrument::Distance { pivot: true } => 3,
            Instrument::Planes(p) => 3 * p.len(),
            Instrument::Spheres(s) => 3 * s.len(),
            Instrument::Sockets(s) => 1 + 2 * s.len(),
        }
    }

    /// Names of the nuisance parameters (`pivot_x`, `plane1_c0`, `sphere2_y`, …).
    pub fn nuisance_names(&self) -> Vec<String> {
        let xyz = |pre: String| ["x", "y", "z"].map(|a| format!("{pre}_{a}"));
        match self {
            Instrument::Targets(_) | Instrument::Distance { pivot: false } => Vec::new(),
            Instrument::Distance { pivot: true } => xyz("pivot".into()).to_vec(),
            Instrument::Planes(p) => (1..=p.len())
                .flat_map(|l| ["c0", "c1", "c2"].map(|c| format!("plane{l}_{c}")))
                .collect(),
            Instrument::Spheres(s) => (1..=s.len())
                .flat_map(|l| xyz(format!("sphere{l}")))
                .collect(),
            Instrument::Sockets(s) => xyz("socket1".into())
                .into_iter()
                .chain(
                    (2..=s.len())
                        .flat_map(|l| ["azimuth", "elevation"].map(|a| format!("socket{l}_{a}"))),
                )
                .collect(),
        }
    }

    /// Rows per observation.
    pub fn rows_per_observation(&self) -> usize {
        match self {
            Instrument::Targets(t) => 3 * t.len(),
            Instrument::Sockets(_) => 3,
            _ => 1,
        }
    }

    /// Observations of `m` poses (one less for consecutive distances).
    pub fn observations(&self, m: usize) -> usize {
        match self {
            Instrument::Distance { pivot: false } => m.saturating_sub(1),
            _ => m,
        }
    }

    /// Checks the geometry: at least one target, plane or sphere; plane axes 0–2; offsets,
    /// radii and socket distances within a robot file's range of lengths
    /// ([`crate::measurement::csv::MAX_POINT_MM`]), radii and distances above 0.
    pub fn check(&self) -> Result<()> {
        let bad = |k: &str, m: String| Err(Error::setting(k, m));
        // A robot file's range of lengths (mm), that of a measured coordinate.
        const MOST: Real = crate::measurement::csv::MAX_POINT_MM;
        let length = |v: Real| v > 0.0 && v <= MOST;
        match self {
            Instrument::Targets(t) if t.is_empty() => {
                bad("measurement.targets_mm", "needs at least one target".into())
            }
            Instrument::Targets(t)
                if t.iter()
                    .flatten()
                    .any(|v| !(v.is_finite() && v.abs() <= MOST)) =>
            {
                bad(
                    "measurement.targets_mm",
                    format!("offsets must be finite and within ±{MOST} mm (a robot file's range)"),
                )
            }
            Instrument::Planes(p) if p.is_empty() || p.iter().any(|&a| a > 2) => bad(
                "measurement.planes",
                "needs at least one plane, each with an axis x, y or z".into(),
            ),
            Instrument::Spheres(s) if s.is_empty() => {
                bad("measurement.spheres", "needs at least one sphere".into())
            }
            Instrument::Sockets(s) if s.is_empty() => {
                bad("measurement.sockets", "needs at least one socket".into())
            }
            Instrument::Spheres(s) if s.iter().any(|r| !length(*r)) => bad(
                "measurement.radius_mm",
                format!("each sphere of radius > 0 and ≤ {MOST} mm"),
            ),
            Instrument::Sockets(s) if s[0] != 0.0 || s[1..].iter().any(|d| !length(*d)) => bad(
                "measurement.socket_distance_mm",
                format!(
                    "socket 1 at distance 0 from itself, every other at a distance > 0 and \
                     ≤ {MOST} mm from it"
                ),
            ),
            _ => Ok(()),
        }
    }

    /// The number of planes, spheres or sockets (1 for the other kinds).
    pub fn groups(&self) -> usize {
        match self {
            Instrument::Planes(p) => p.len(),
            Instrument::Spheres(s) => s.len(),
            Instrument::Sockets(s) => s.len(),
            _ => 1,
        }
    }
}

/// What an instrument measured: per observation its value(s) and the plane or sphere it
/// belongs to; the joint values are kept beside it by the caller.
#[derive(Clone, Debug, PartialEq)]
pub struct KindData {
    /// The instrument's geometry.
    pub instrument: Instrument,
    /// Per pose, the plane or sphere it touches (0 for the other kinds).
    pub group: Vec<usize>,
    /// Measured values, [`Instrument::rows_per_observation`] per observation: the targets'
    /// coordinates (mm, base frame) or the lengths (mm); zeros for planes and spheres (the
    /// constraint's value).
    pub values: Vec<Real>,
}

impl KindData {
    /// Checks the lengths against `m` poses and the group indices against the planes or
    /// spheres; every value finite.
    pub fn check(&self, m: usize) -> Result<()> {
        self.instrument.check()?;
        let rows = self.instrument.observations(m) * self.instrument.rows_per_observation();
        if self.values.len() != rows {
            return Err(Error::setting(
                "measurements",
                format!(
                    "{m} poses need {rows} measured values, got {}",
                    self.values.len()
                ),
            ));
        }
        if self.group.len() != m {
            return Err(Error::setting(
                "measurements",
                format!("{m} poses but {} plane or sphere indices", self.group.len()),
            ));
        }
        let groups = self.instrument.groups();
        if let Some(i) = self.group.iter().position(|&g| g >= groups) {
            return Err(Error::setting(
                "measurements",
                format!(
                    "pose {i}: plane or sphere {} of {groups}",
                    self.group[i] + 1
                ),
            ));
        }
        if let Some(i) = self.values.iter().position(|v| !v.is_finite()) {
            return Err(Error::setting(
                "measurements",
                format!("value {i} not finite"),
            ));
        }
        Ok(())
    }

    /// For targets on one flange, the pair the readings contradict most: two targets' points
    /// are as far apart as their offsets at every pose, whatever the robot's errors. Per
    /// pair, the median over the poses of their points' distance (a gross reading moves no
    /// median) against their offsets'; `(a, b, by offsets, read)` of the pair furthest
    /// beyond `tolerance(by offsets)` (mm), `None` when every pair is within it or the
    /// instrument is not targets.
    pub fn contradicted_targets(
        &self,
        tolerance: impl Fn(Real) -> Real,
    ) -> Option<(usize, usize, Real, Real)> {
        let Instrument::Targets(t) = &self.instrument else {
            return None;
        };
        let n = t.len();
        let poses = self.values.len() / (3 * n).max(1);
        let point =
            |i: usize, k: usize| Vec3::from_column_slice(&self.values[3 * (n * i + k)..][..3]);
        let mut worst: Option<(Real, (usize, usize, Real, Real))> = None;
        for a in 0..n {
            for b in a + 1..n {
                let by_offsets = (t[a] - t[b]).norm();
                let mut read: Vec<Real> = (0..poses)
                    .map(|i| (point(i, a) - point(i, b)).norm())
                    .collect();
                read.sort_by(Real::total_cmp);
                let &median = read.get(poses / 2)?;
                let beyond = (median - by_offsets).abs() - tolerance(by_offsets);
                if beyond > 0.0 && worst.is_none_or(|w| beyond > w.0) {
                    worst = Some((beyond, (a, b, by_offsets, median)));
                }
            }
        }
        worst.map(|w| w.1)
    }
}

/// The model's value of observation `i` for tool points `p` (and rotations `rot`, for
/// targets) and nuisance values `c`: what a noise-free instrument reads.
pub fn model_values(
    inst: &Instrument,
    group: &[usize],
    p: &[Vec3],
    rot: &[crate::numeric::Mat3],
    c: &[Real],
    out: &mut Vec<Real>,
) {
    out.clear();
    let m = p.len();
    for i in 0..inst.observations(m) {
        match inst {
            Instrument::Targets(t) => {
                for o in t {
                    out.extend((p[i] + rot[i] * o).iter());
                }
            }
            Instrument::Distance { pivot: true } => out.push((p[i] - centre(c, 0)).norm()),
            Instrument::Distance { pivot: false } => out.push((p[i + 1] - p[i]).norm()),
            Instrument::Planes(axes) => {
                let g = group[i];
                let (k, u, v) = plane_axes(axes[g]);
                let cc = &c[3 * g..3 * g + 3];
                out.push(p[i][k] - (cc[0] + cc[1] * p[i][u] + cc[2] * p[i][v]));
            }
            Instrument::Spheres(r) => {
                let g = group[i];
                out.push((p[i] - centre(c, g)).norm() - r[g]);
            }
            Instrument::Sockets(d) => {
                let (s, _, _) = socket(d, c, group[i]);
                out.extend((p[i] - s).iter());
            }
        }
    }
}

fn centre(c: &[Real], g: usize) -> Vec3 {
    Vec3::new(c[3 * g], c[3 * g + 1], c[3 * g + 2])
}

/// Socket `g`'s centre `s_g = s_1 + d_g u(θ_g, φ_g)` from the nuisance values `c`
/// (`s_1`, then `θ, φ` per further socket) and the known distances `d`, with its derivatives
/// by `θ_g` and `φ_g` (zero for socket 1).
pub fn socket(d: &[Real], c: &[Real], g: usize) -> (Vec3, Vec3, Vec3) {
    let s1 = centre(c, 0);
    if g == 0 {
        return (s1, Vec3::zeros(), Vec3::zeros());
    }
    let (th, ph) = (c[1 + 2 * g], c[2 + 2 * g]);
    let (st, ct, sp, cp) = (th.sin(), th.cos(), ph.sin(), ph.cos());
    let u = Vec3::new(cp * ct, cp * st, sp);
    let du_th = Vec3::new(-cp * st, cp * ct, 0.0);
    let du_ph = Vec3::new(-sp * ct, -sp * st, cp);
    (s1 + d[g] * u, d[g] * du_th, d[g] * du_ph)
}

/// The plane's normal axis and the two others in cyclic order.
pub fn plane_axes(axis: usize) -> (usize, usize, usize) {
    (axis, (axis + 1) % 3, (axis + 2) % 3)
}

/// Gives each plane of `data` the normal axis its points `p` (the nominal tool points, one
/// per pose) call for: the axis along which the plane's normal has its largest component
/// (the normal of the least-squares plane through the group's centred points), so that
/// `p[axis] = c₀ + c₁ p[u] + c₂ p[v]` is a graph over the other two axes with small slopes.
/// A plane of fewer than three points keeps its axis. Other kinds are left as they are.
pub fn choose_plane_axes(data: &mut KindData, p: &[Vec3]) {
    let Instrument::Planes(axes) = &mut data.instrument else {
        return;
    };
    for (g, axis) in axes.iter_mut().enumerate() {
        let pts: Vec<&Vec3> = p
            .iter()
            .zip(&data.group)
            .filter(|(_, &gi)| gi == g)
            .map(|(pt, _)| pt)
            .collect();
        if pts.len() < 3 {
            continue;
        }
        let mean = pts.iter().fold(Vec3::zeros(), |a, b| a + *b) / pts.len() as Real;
        let mut cov = crate::numeric::Mat3::zeros();
        for pt in &pts {
            let d = *pt - mean;
            cov += d * d.transpose();
        }
        let eig = cov.symmetric_eigen();
        let k = eig.eigenvalues.imin();
        let n = eig.eigenvectors.column(k);
        *axis = n.iamax();
    }
}

/// The residual and Jacobian rows of every observation.
///
/// `tool` holds, per pose `i`, rows `6i..6i+3` = `J_p` and `6i+3..6i+6` = `J_ω` over the
/// robot's `t` parameters (the first `t` columns of `j`); `c` are the nuisance values (the
/// last `c.len()` columns of `j`). Writes `r = values − model` and `j = ∂model/∂(x, c)`.
/// Allocation-free.
#[allow(clippy::too_many_arguments)]
pub fn rows(
    data: &KindData,
    p: &[Vec3],
    rot: &[crate::numeric::Mat3],
    tool: &DMatrix<Real>,
    c: &[Real],
    r: &mut DVector<Real>,
    j: &mut DMatrix<Real>,
) {
    let t = tool.ncols();
    let m = p.len();
    let inst = &data.instrument;
    let jp = |i: usize, k: usize, col: usize| tool[(6 * i + k, col)];
    let jw = |i: usize, k: usize, col: usize| tool[(6 * i + 3 + k, col)];
    j.fill(0.0);
    for i in 0..inst.observations(m) {
        match inst {
            Instrument::Targets(targets) => {
                let nt = targets.len();
                for (ti, o) in targets.iter().enumerate() {
                    let ro = rot[i] * o;
                    let pt = p[i] + ro;
                    // δ(p + R o) = J_p δx + ω × (R o) = J_p δx − [R o]× J_ω δx.
                    let s = skew(&ro);
                    let row = 3 * (nt * i + ti);
                    for k in 0..3 {
                        r[row + k] = data.values[row + k] - pt[k];
                        for col in 0..t {
                            let w = Vec3::new(jw(i, 0, col), jw(i, 1, col), jw(i, 2, col));
                            j[(row + k, col)] = jp(i, k, col) - (s * w)[k];
                        }
                    }
                }
            }
            Instrument::Distance { pivot } => {
                let (a, b) = if *pivot { (i, None) } else { (i + 1, Some(i)) };
                let other = match b {
                    Some(b) => p[b],
                    None => centre(c, 0),
                };
                let d = p[a] - other;
                let len = d.norm();
                let u = d / len;
                r[i] = data.values[i] - len;
                for col in 0..t {
                    let mut v = 0.0;
                    for k in 0..3 {
                        let db = b.map_or(0.0, |b| jp(b, k, col));
                        v += u[k] * (jp(a, k, col) - db);
                    }
                    j[(i, col)] = v;
                }
                if *pivot {
                    for k in 0..3 {
                        j[(i, t + k)] = -u[k];
                    }
                }
            }
            Instrument::Planes(axes) => {
                let g = data.group[i];
                let (k, u, v) = plane_axes(axes[g]);
                let cc = &c[3 * g..3 * g + 3];
                r[i] = data.values[i] - (p[i][k] - (cc[0] + cc[1] * p[i][u] + cc[2] * p[i][v]));
                for col in 0..t {
                    j[(i, col)] = jp(i, k, col) - cc[1] * jp(i, u, col) - cc[2] * jp(i, v, col);
                }
                j[(i, t + 3 * g)] = -1.0;
                j[(i, t + 3 * g + 1)] = -p[i][u];
                j[(i, t + 3 * g + 2)] = -p[i][v];
            }
            Instrument::Spheres(radius) => {
                let g = data.group[i];
                let d = p[i] - centre(c, g);
                let len = d.norm();
                let u = d / len;
                r[i] = data.values[i] - (len - radius[g]);
                for col in 0..t {
                    j[(i, col)] = (0..3).map(|k| u[k] * jp(i, k, col)).sum();
                }
                for k in 0..3 {
                    j[(i, t + 3 * g + k)] = -u[k];
                }
            }
            Instrument::Sockets(d) => {
                let g = data.group[i];
                let (s, ds_th, ds_ph) = socket(d, c, g);
                for k in 0..3 {
                    let row = 3 * i + k;
                    r[row] = data.values[row] - (p[i][k] - s[k]);
                    for col in 0..t {
                        j[(row, col)] = jp(i, k, col);
                    }
                    j[(row, t + k)] = -1.0;
                    if g > 0 {
                        j[(row, t + 1 + 2 * g)] = -ds_th[k];
                        j[(row, t + 2 + 2 * g)] = -ds_ph[k];
                    }
                }
            }
        }
    }
}

/// A first guess of the nuisance values from (nominal) tool points `p` and the readings
/// `values`: the plane through each group's points (least squares in the graph form), the
/// sphere centre (algebraic fit: `|p|² − 2 p·c + |c|² − ρ² = 0` is linear in `c` and
/// `|c|² − ρ²`), and the pivot by trilateration (`|p_i|² − 2 p_i·c + |c|² = L_i²`, linear in
/// `c` and `|c|²`). Fails when a group has too few points to fix its parameters.
pub fn nuisance_guess(
    inst: &Instrument,
    group: &[usize],
    p: &[Vec3],
    values: &[Real],
) -> Result<Vec<Real>> {
    let groups = match inst {
        Instrument::Targets(_) | Instrument::Distance { pivot: false } => return Ok(Vec::new()),
        Instrument::Sockets(d) => return socket_guess(d, group, p),
        Instrument::Distance { pivot: true } => 1,
        Instrument::Planes(a) => a.len(),
        Instrument::Spheres(s) => s.len(),
    };
    let mut out = Vec::with_capacity(3 * groups);
    for g in 0..groups {
        let pts: Vec<&Vec3> = p
            .iter()
            .zip(group)
            .filter(|(_, &gi)| gi == g || matches!(inst, Instrument::Distance { .. }))
            .map(|(pt, _)| pt)
            .collect();
        let (a, b): (Vec<[Real; 4]>, Vec<Real>) = match inst {
            Instrument::Planes(axes) => {
                let (k, u, v) = plane_axes(axes[g]);
                pts.iter()
                    .map(|pt| ([1.0, pt[u], pt[v], 0.0], pt[k]))
                    .unzip()
            }
            Instrument::Distance { .. } => pts
                .iter()
                .zip(values)
                .map(|(pt, l)| {
                    (
                        [2.0 * pt[0], 2.0 * pt[1], 2.0 * pt[2], -1.0],
                        pt.norm_squared() - l * l,
                    )
                })
                .unzip(),
            _ => pts
                .iter()
                .map(|pt| {
                    (
                        [2.0 * pt[0], 2.0 * pt[1], 2.0 * pt[2], 1.0],
                        pt.norm_squared(),
                    )
                })
                .unzip(),
        };
        // Pivot: 4 unknowns, as a sphere's centre and radius term.
        let need = inst.surfaces().map_or(5, |s| s.1);
        let cols = need - 1;
        if a.len() < need {
            return Err(Error::setting(
                "measurements",
                format!(
                    "{} {} has {} points; it needs at least {}",
                    inst.kind().as_str(),
                    g + 1,
                    a.len(),
                    need
                ),
            ));
        }
        let am = DMatrix::from_fn(a.len(), cols, |i, c| a[i][c]);
        let bv = DVector::from_vec(b);
        // Points that do not fix the surface (a plane's on one line or at one point) give
        // the least-norm fit through them: directions below 1e-12 of the largest are left
        // out, relative so that coordinates of metres do not make rounding a direction.
        let svd = crate::numeric::linalg::svd(am, true, true)
            .ok_or_else(|| Error::Compute("the SVD of a non-finite system".into()))?;
        let floor = 1e-12 * svd.singular_values.max();
        let x = svd
            .solve(&bv, floor)
            .map_err(|e| Error::Compute(e.to_string()))?;
        out.extend(x.iter().take(3));
    }
    Ok(out)
}

/// The first guess of the sockets' unknowns: socket 1 at the mean of its tool points; each
/// further socket's direction from socket 1 towards the mean of its own points. Fails when a
/// socket has no point.
fn socket_guess(d: &[Real], group: &[usize], p: &[Vec3]) -> Result<Vec<Real>> {
    let mut means = Vec::with_capacity(d.len());
    for g in 0..d.len() {
        let pts: Vec<&Vec3> = p
            .iter()
            .zip(group)
            .filter(|(_, &gi)| gi == g)
            .map(|(pt, _)| pt)
            .collect();
        if pts.is_empty() {
            return Err(Error::setting(
                "measurements",
                format!("socket {} has no pose", g + 1),
            ));
        }
        means.push(pts.iter().fold(Vec3::zeros(), |a, b| a + *b) / pts.len() as Real);
    }
    let mut out = vec![means[0].x, means[0].y, means[0].z];
    for m in &means[1..] {
        let v = m - means[0];
        out.push(v.y.atan2(v.x));
        out.push(v.z.atan2(v.x.hypot(v.y)));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two targets 100 mm apart on a flange at five poses: read 100 mm apart (one pose
    /// misread by a metre, which moves no median) they agree; read 150 mm apart they are
    /// named with both distances; within the tolerance they agree.
    #[test]
    fn the_pair_the_readings_contradict_is_named_by_its_median() {
        let offsets = vec![Vec3::zeros(), Vec3::new(100.0, 0.0, 0.0)];
        let data = |apart: Real| KindData {
            instrument: Instrument::Targets(offsets.clone()),
            group: vec![0; 5],
            values: (0..5)
                .flat_map(|i| {
                    let p = Vec3::new(500.0 + i as Real, 20.0, 30.0);
                    let far = if i == 2 { 1000.0 } else { apart };
                    let q = p + Vec3::new(0.0, far, 0.0);
                    [p.x, p.y, p.z, q.x, q.y, q.z]
                })
                .collect(),
        };
        let tolerance = |d: Real| 5.0 + 0.05 * d;
        assert_eq!(data(100.0).contradicted_targets(tolerance), None);
        assert_eq!(data(109.0).contradicted_targets(tolerance), None);
        assert_eq!(
            data(150.0).contradicted_targets(tolerance),
            Some((0, 1, 100.0, 150.0))
        );
    }
}
