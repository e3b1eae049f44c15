//! Simulated instruments beyond the tracker ([`crate::measurement::kind`]): their layout in
//! the cell (pivot, planes, spheres, targets), the touch of a plane or sphere (the robot moves
//! from its commanded pose until the true tool point meets the surface, and the controller
//! records the joint values there), and each instrument's noise.
//!
//! Noise per kind (σ per reading, Gaussian): `noise_um + scale_um_per_m · L` with `L` the
//! measured length (distance) or the range from the tracker position (targets), in metres;
//! for planes and spheres `noise_um` along the surface normal (the probe's trigger and the
//! robot's repeatability at contact).

use rand::Rng as _;
use rand_distr::StandardNormal;
use serde::Deserialize;

use crate::error::{Error, Opt, Result};
use crate::measurement::kind::{model_values, Instrument, Kind, KindData};
use crate::numeric::rng::Rng;
use crate::numeric::{Real, Vec3};
use crate::robot::Robot;

/// How far inside the joint limits (rad or mm) [`touching`] keeps its poses.
pub const TOUCH_MARGIN: Real = 0.05;

/// One `[[measurement]]` entry of a scenario: an instrument and its settings
/// (docs/formats.md, "Measurement kinds").
#[derive(Clone, Debug, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct InstrumentSettings {
    /// The kind: `position`, `distance`, `plane`, `sphere` or `multi-target`.
    pub kind: Kind,
    /// Constant part of σ per reading, µm.
    pub noise_um: Real,
    /// Length- or range-proportional part of σ, µm per m.
    pub scale_um_per_m: Real,
    /// Distance: from a fixed pivot (`true`) or between consecutive poses.
    pub pivot: bool,
    /// Distance: the pivot in the base frame, mm.
    pub pivot_mm: [Real; 3],
    /// Plane: the number of planes (normals along z, x, y in turn).
    pub planes: usize,
    /// Sphere: the number of spheres.
    pub spheres: usize,
    /// Sphere: the radius, mm.
    pub radius_mm: Real,
    /// Socket: the number of sockets.
    pub sockets: usize,
    /// Socket: the distance of each further socket from socket 1, mm.
    pub socket_distance_mm: Real,
    /// Multi-target: the targets' offsets in the tool frame, mm.
    pub targets_mm: Vec<[Real; 3]>,
    /// Targets: the tracker's position in the base frame (mm), for the range in σ.
    pub tracker_mm: [Real; 3],
}

impl Default for InstrumentSettings {
    fn default() -> Self {
        InstrumentSettings {
            kind: Kind::Position,
            noise_um: 7.5,
            scale_um_per_m: 3.0,
            pivot: true,
            pivot_mm: [1200.0, 0.0, 0.0],
            planes: 3,
            spheres: 1,
            radius_mm: 25.4,
            sockets: 2,
            socket_distance_mm: 50.0,
            targets_mm: vec![[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 100.0, 0.0]],
            tracker_mm: [2500.0, 0.0, 500.0],
        }
    }
}

/// The keys of a `[[measurement]]` entry that only some kinds read, with those kinds
/// (docs/formats.md § 4.15); the other keys every kind reads.
const KIND_KEYS: [(&str, &[Kind]); 9] = [
    ("pivot", &[Kind::Distance]),
    ("pivot_mm", &[Kind::Distance]),
    ("planes", &[Kind::Plane]),
    ("spheres", &[Kind::Sphere]),
    ("radius_mm", &[Kind::Sphere]),
    ("sockets", &[Kind::Socket]),
    ("socket_distance_mm", &[Kind::Socket]),
    ("targets_mm", &[Kind::MultiTarget]),
    ("tracker_mm", &[Kind::Position, Kind::MultiTarget]),
];

/// A refusal of [`InstrumentSettings`]' plane or sphere count named as the option
/// ([`Opt::Planes`], [`Opt::Spheres`]) of a caller that takes the counts as its own
/// (`identifiability --planes`, Python's `planes=`), not as a study's key.
pub fn counts_as_options(e: Error) -> Error {
    e.setting_as("measurement.planes", Opt::Planes)
        .setting_as("measurement.spheres", Opt::Spheres)
}

impl InstrumentSettings {
    /// Refuses a key of the entry `given` (as written) that its kind does not read: a plane
    /// count on a distance instrument would be believed set and never used.
    pub fn check_keys(&self, given: &toml::Table) -> Result<()> {
        let unread = KIND_KEYS
            .iter()
            .filter(|(_, kinds)| !kinds.contains(&self.kind))
            .map(|(key, kinds)| (*key, *kinds))
            .chain((!self.pivot).then_some(("pivot_mm", &[Kind::Distance][..])));
        for (key, kinds) in unread {
            if given.contains_key(key) {
                let by: Vec<&str> = kinds.iter().map(|k| k.as_str()).collect();
                let msg = match kinds.contains(&self.kind) {
                    true => "is read only with pivot = true".to_string(),
                    false => format!(
                        "is read only by kind = \"{}\" (this entry's kind is \"{}\")",
                        by.join("\" or \""),
                        self.kind.as_str()
                    ),
                };
                return Err(Error::setting(format!("measurement.{key}"), msg));
            }
        }
        Ok(())
    }

    /// The instrument's geometry (kind `pose` is refused: it is the tracker's own path).
    /// A refusal names a study's key (`measurement.planes`); [`counts_as_options`] names
    /// the options of a caller that takes the counts as its own.
    pub fn instrument(&self) -> Result<Instrument> {
        use crate::measurement::kind_csv::MAX_GROUPS;
        for (key, n) in [
            ("planes", self.planes),
            ("spheres", self.spheres),
            ("sockets", self.sockets),
        ] {
            if n > MAX_GROUPS {
                return Err(Error::setting(
                    format!("measurement.{key}"),
                    format!("must be at most {MAX_GROUPS} (the most a measurement file numbers), got {n}"),
                ));
            }
        }
        let inst = match self.kind {
            Kind::Position => Instrument::Targets(vec![Vec3::zeros()]),
            Kind::MultiTarget => {
                Instrument::Targets(self.targets_mm.iter().map(|t| Vec3::from(*t)).collect())
            }
            Kind::Distance => Instrument::Distance { pivot: self.pivot },
            Kind::Plane => Instrument::Planes((0..self.planes).map(|l| [2, 0, 1][l % 3]).collect()),
            Kind::Sphere => Instrument::Spheres(vec![self.radius_mm; self.spheres]),
            Kind::Socket => Instrument::Sockets(
                (0..self.sockets)
                    .map(|l| if l == 0 { 0.0 } else { self.socket_distance_mm })
                    .collect(),
            ),
            Kind::Pose => {
                return Err(Error::setting(
                    "measurement.kind",
                    "`pose` is the tracker's full pose: use [tracker] measure = \"pose\" in a \
                     calibration scenario",
                ))
            }
        };
        inst.check()?;
        // Within a robot file's range of lengths (mm; µm for the noise): beyond it the
        // readings are not finite, and the run fails with no key to blame.
        let most = crate::robot::MAX_LENGTH_MM;
        for (k, v) in [
            ("noise_um", self.noise_um),
            ("scale_um_per_m", self.scale_um_per_m),
        ] {
            if !(0.0..=most * 1e3).contains(&v) {
                let got = crate::error::shown(v);
                let msg = format!(
                    "must be from 0 to {} µm (a robot file's range), got {got}",
                    most * 1e3
                );
                return Err(Error::setting(format!("measurement.{k}"), msg));
            }
        }
        for (k, p) in [("pivot_mm", self.pivot_mm), ("tracker_mm", self.tracker_mm)] {
            crate::error::lengths_within(&format!("measurement.{k}"), &p, most)?;
        }
        Ok(inst)
    }
}

/// The true geometry of an instrument in the cell: the nuisance values (pivot, plane
/// coefficients, sphere centres) and the plane or sphere each candidate touches.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// The instrument.
    pub instrument: Instrument,
    /// The nuisance values (see [`crate::measurement::kind::nuisance_guess`]).
    pub nuisance: Vec<Real>,
}

/// Lays the instrument out for the candidate poses `qs` of `nominal`: the pivot where the
/// settings put it; plane `l` through the median of its candidates' points along its axis,
/// tilted by 0.02 and 0.01; sphere `l` centred at the tool point of its first candidate;
/// socket 1 at the tool point of the first candidate, socket `l` at azimuth `0.7 (l − 1)`
/// rad and elevation 0.05 rad from it. Candidate `i` belongs to plane, sphere or socket
/// `i mod count`.
pub fn layout(s: &InstrumentSettings, nominal: &Robot, qs: &[Vec<Real>]) -> Result<Layout> {
    let instrument = s.instrument()?;
    let chain = nominal.chain();
    let p: Vec<Vec3> = qs.iter().map(|q| chain.fk(q).pos).collect();
    let groups = groups_of(&instrument, qs.len());
    let nuisance = match &instrument {
        Instrument::Distance { pivot: true } => s.pivot_mm.to_vec(),
        Instrument::Planes(axes) => axes
            .iter()
            .enumerate()
            .flat_map(|(l, &a)| {
                let mut v: Vec<Real> = p
                    .iter()
                    .zip(&groups)
                    .filter(|(_, &g)| g == l)
                    .map(|(pt, _)| pt[a])
                    .collect();
                v.sort_by(Real::total_cmp);
                [v.get(v.len() / 2).copied().unwrap_or(0.0), 0.02, 0.01]
            })
            .collect(),
        Instrument::Spheres(r) => (0..r.len())
            .flat_map(|l| p.get(l).map_or([0.0; 3], |v| [v[0], v[1], v[2]]))
            .collect(),
        Instrument::Sockets(d) => {
            let s1 = p.first().copied().unwrap_or_else(Vec3::zeros);
            let mut v = vec![s1.x, s1.y, s1.z];
            for l in 1..d.len() {
                v.extend([0.7 * (l - 1) as Real, 0.05]);
            }
            v
        }
        _ => Vec::new(),
    };
    Ok(Layout {
        instrument,
        nuisance,
    })
}

/// Plane, sphere or socket of each of `m` poses: `i mod count` (0 for the other kinds).
pub fn groups_of(inst: &Instrument, m: usize) -> Vec<usize> {
    let n = inst.groups();
    (0..m).map(|i| i % n).collect()
}

/// Moves `robot` from joint values `q` until its tool point is at `target` (minimum-norm
/// joint steps on the three coordinates, at most 0.2 rad or mm per joint and step): `None`
/// when it does not get there to 1e-9 mm within the joint limits narrowed by `margin` in 100
/// steps.
pub fn reach(robot: &Robot, target: &Vec3, q: &[Real], margin: Real) -> Option<Vec<Real>> {
    let chain = robot.chain();
    let mut q = q.to_vec();
    let h = 1e-6;
    let n = q.len();
    for _ in 0..100 {
        let e = target - chain.fk(&q).pos;
        if e.norm() < 1e-9 {
            return within(robot, &q, margin).then_some(q);
        }
        let mut jac = nalgebra::DMatrix::<Real>::zeros(3, n);
        for k in 0..n {
            let mut qp = q.clone();
            qp[k] += h;
            let mut qm = q.clone();
            qm[k] -= h;
            let d = (chain.fk(&qp).pos - chain.fk(&qm).pos) / (2.0 * h);
            jac.column_mut(k).copy_from(&d);
        }
        let jjt = &jac * jac.transpose();
        let y = jjt.try_inverse()? * nalgebra::DVector::from_column_slice(e.as_slice());
        let mut step: Vec<Real> = (jac.transpose() * y).iter().copied().collect();
        take_step(&mut q, &mut step);
    }
    None
}

/// The surface constraint `g(p)` of pose `i`'s plane or sphere (0 on the surface, mm) and its
/// gradient; `None` for the kinds without a surface.
fn surface(lay: &Layout, group: usize, p: &Vec3) -> Option<(Real, Vec3)> {
    let c = &lay.nuisance;
    match &lay.instrument {
        Instrument::Planes(axes) => {
            let (k, u, v) = crate::measurement::kind::plane_axes(axes[group]);
            let cc = &c[3 * group..3 * group + 3];
            let mut grad = Vec3::zeros();
            grad[k] = 1.0;
            grad[u] = -cc[1];
            grad[v] = -cc[2];
            Some((p[k] - (cc[0] + cc[1] * p[u] + cc[2] * p[v]), grad))
        }
        Instrument::Spheres(r) => {
            let d = p - Vec3::new(c[3 * group], c[3 * group + 1], c[3 * group + 2]);
            Some((d.norm() - r[group], d.normalize()))
        }
        _ => None,
    }
}

/// Moves `robot` from joint values `q` until its tool point meets the plane or sphere `group`
/// of `lay` (minimum-norm joint steps on the scalar constraint, at most 0.2 rad or mm per
/// joint and step): `None` when it does not meet it to 1e-9 mm within the joint limits
/// narrowed by `margin` (rad or mm) in 100 steps. Poses of kinds without a surface come back
/// unchanged.
pub fn touch(
    robot: &Robot,
    lay: &Layout,
    group: usize,
    q: &[Real],
    margin: Real,
) -> Option<Vec<Real>> {
    if let Instrument::Sockets(d) = &lay.instrument {
        let (target, _, _) = crate::measurement::kind::socket(d, &lay.nuisance, group);
        return reach(robot, &target, q, margin);
    }
    if !matches!(
        lay.instrument,
        Instrument::Planes(_) | Instrument::Spheres(_)
    ) {
        return Some(q.to_vec());
    }
    let chain = robot.chain();
    let mut q = q.to_vec();
    let h = 1e-6;
    for _ in 0..100 {
        let p = chain.fk(&q).pos;
        let (g, grad) = surface(lay, group, &p)?;
        if g.abs() < 1e-9 {
            return within(robot, &q, margin).then_some(q);
        }
        let mut dg = vec![0.0; q.len()];
        for (k, d) in dg.iter_mut().enumerate() {
            let mut qp = q.clone();
            qp[k] += h;
            let mut qm = q.clone();
            qm[k] -= h;
            *d = grad.dot(&(chain.fk(&qp).pos - chain.fk(&qm).pos)) / (2.0 * h);
        }
        let n2: Real = dg.iter().map(|d| d * d).sum();
        if n2 < 1e-12 {
            return None;
        }
        let mut step: Vec<Real> = dg.iter().map(|d| -g * d / n2).collect();
        take_step(&mut q, &mut step);
    }
    None
}

/// The poses of `qs` that touch their plane or sphere `groups[i]` on `robot` (see
/// [`touch`], [`TOUCH_MARGIN`] inside the joint limits, so that a slightly different robot
/// still touches from there), each moved onto it, with their plane or sphere; the others are
/// dropped. Every pose is kept, unmoved, for the kinds without a surface.
pub fn touching(
    robot: &Robot,
    lay: &Layout,
    qs: &[Vec<Real>],
    groups: &[usize],
) -> (Vec<Vec<Real>>, Vec<usize>) {
    qs.iter()
        .zip(groups)
        .filter_map(|(q, &g)| touch(robot, lay, g, q, TOUCH_MARGIN).map(|q| (q, g)))
        .unzip()
}

/// What the instrument reads on the `truth` robot at the commanded joint values `qs` of
/// poses on planes or spheres `group`: the joints where the true robot touches (the
/// commanded ones for the other kinds) and the noisy readings (`s`'s noise, drawn from
/// `rng`), with the σ of each observation (mm). Fails when the true robot cannot touch a
/// surface from a commanded pose.
pub fn measure(
    s: &InstrumentSettings,
    lay: &Layout,
    truth: &Robot,
    qs: &[Vec<Real>],
    group: &[usize],
    rng: &mut Rng,
) -> Result<(Vec<Vec<Real>>, KindData, Vec<Real>)> {
    if let Instrument::Sockets(d) = &lay.instrument {
        return measure_sockets(s, lay, d, truth, qs, group, rng);
    }
    let mut touched = Vec::with_capacity(qs.len());
    for (i, (q, &g)) in qs.iter().zip(group).enumerate() {
        touched.push(touch(truth, lay, g, q, 0.0).ok_or_else(|| {
            Error::Compute(format!(
                "pose {i}: the true robot does not touch its surface"
            ))
        })?);
    }
    let chain = truth.chain();
    let frames: Vec<_> = touched.iter().map(|q| chain.fk(q)).collect();
    let p: Vec<Vec3> = frames.iter().map(|f| f.pos).collect();
    let rot: Vec<_> = frames.iter().map(|f| f.rot).collect();
    let mut values = Vec::new();
    model_values(&lay.instrument, group, &p, &rot, &lay.nuisance, &mut values);
    let tracker = Vec3::from(s.tracker_mm);
    let per = lay.instrument.rows_per_observation();
    let surface_kind = matches!(
        lay.instrument,
        Instrument::Planes(_) | Instrument::Spheres(_)
    );
    let mut sigma = vec![0.0; values.len() / per];
    for (k, v) in values.iter_mut().enumerate() {
        let range_m = match &lay.instrument {
            Instrument::Distance { .. } => *v * 1e-3,
            Instrument::Targets(_) => (p[k / per] - tracker).norm() * 1e-3,
            _ => 0.0,
        };
        let sigma_mm = (s.noise_um + s.scale_um_per_m * range_m) * 1e-3;
        sigma[k / per] = sigma_mm;
        let z: Real = rng.sample(StandardNormal);
        // A surface's reading is its constraint, 0 by definition: the contact error (the
        // touched point off the surface by σ along its normal) shows as a reading of −g.
        *v = if surface_kind {
            sigma_mm * z
        } else {
            *v + sigma_mm * z
        };
    }
    let data = KindData {
        instrument: lay.instrument.clone(),
        group: group.to_vec(),
        values,
    };
    data.check(touched.len())?;
    Ok((touched, data, sigma))
}

/// [`measure`] of sockets: the true robot holds its tool point in socket `group[i]` off the
/// socket's centre by `noise_um` per coordinate (the ball's seat and the robot's
/// repeatability), from the commanded joint values; the readings are the sockets' zeros.
fn measure_sockets(
    s: &InstrumentSettings,
    lay: &Layout,
    d: &[Real],
    truth: &Robot,
    qs: &[Vec<Real>],
    group: &[usize],
    rng: &mut Rng,
) -> Result<(Vec<Vec<Real>>, KindData, Vec<Real>)> {
    let sigma_mm = s.noise_um * 1e-3;
    let mut touched = Vec::with_capacity(qs.len());
    for (i, (q, &g)) in qs.iter().zip(group).enumerate() {
        let (centre, _, _) = crate::measurement::kind::socket(d, &lay.nuisance, g);
        let z = Vec3::from_fn(|_, _| rng.sample::<Real, _>(StandardNormal));
        let q = reach(truth, &(centre + sigma_mm * z), q, 0.0).ok_or_else(|| {
            Error::Compute(format!(
                "pose {i}: the true robot does not reach its socket"
            ))
        })?;
        touched.push(q);
    }
    let data = KindData {
        instrument: lay.instrument.clone(),
        group: group.to_vec(),
        values: vec![0.0; 3 * qs.len()],
    };
    data.check(touched.len())?;
    Ok((touched, data, vec![sigma_mm; qs.len()]))
}

/// Noise-free readings of `robot` at poses `qs` on planes or spheres `group`, with nuisance
/// values `nuisance`: the data of an identifiability analysis or a recovery test.
pub fn noise_free(
    inst: &Instrument,
    robot: &Robot,
    qs: &[Vec<Real>],
    group: &[usize],
    nuisance: &[Real],
) -> KindData {
    let chain = robot.chain();
    let frames: Vec<_> = qs.iter().map(|q| chain.fk(q)).collect();
    let p: Vec<Vec3> = frames.iter().map(|f| f.pos).collect();
    let rot: Vec<_> = frames.iter().map(|f| f.rot).collect();
    let mut values = Vec::new();
    model_values(inst, group, &p, &rot, nuisance, &mut values);
    if matches!(
        inst,
        Instrument::Planes(_) | Instrument::Spheres(_) | Instrument::Sockets(_)
    ) {
        values.iter_mut().for_each(|v| *v = 0.0);
    }
    KindData {
        instrument: inst.clone(),
        group: group.to_vec(),
        values,
    }
}

/// `n` poses of `nominal` on the instrument of `s`: joint values drawn uniformly within the
/// limits from `rng` ([`crate::robot::sampling::uniform_joint_poses`]), laid out by [`layout`]
/// on the first draw, moved onto their planes or spheres by [`touching`] (those that do not
/// reach theirs are dropped and more are drawn); with each pose's plane or sphere. Fails
/// when 20 draws of `4n` candidates do not give `n` poses, or when a plane, sphere or
/// socket has none of them (one the arm does not reach: its readings would be missing from
/// the file, which no identification could then read).
pub fn instrument_poses(
    s: &InstrumentSettings,
    nominal: &Robot,
    n: usize,
    rng: &mut Rng,
) -> Result<(Layout, Vec<Vec<Real>>, Vec<usize>)> {
    let batch = 4 * n.max(1);
    let first = crate::robot::sampling::uniform_joint_poses(nominal, batch, rng);
    let lay = layout(s, nominal, &first)?;
    let (mut qs, mut groups) = touching(nominal, &lay, &first, &groups_of(&lay.instrument, batch));
    let mut drawn = batch;
    for _ in 1..20 {
        if qs.len() >= n {
            break;
        }
        drawn += batch;
        let more = crate::robot::sampling::uniform_joint_poses(nominal, batch, rng);
        let (q, g) = touching(nominal, &lay, &more, &groups_of(&lay.instrument, batch));
        qs.extend(q);
        groups.extend(g);
    }
    // A plane, sphere or socket that no pose reaches would be missing from the readings
    // (the only one unreached is said below, as too few poses).
    let (kind, count) = (s.kind.as_str(), lay.instrument.groups());
    let grouped = count > 1
        && matches!(
            lay.instrument,
            Instrument::Planes(_) | Instrument::Spheres(_) | Instrument::Sockets(_)
        );
    let missing = |g: &[usize]| (0..count).find(|l| grouped && !g.contains(l));
    if let Some(l) = missing(&groups) {
        return Err(Error::Compute(format!(
            "{kind} {} of {count} is reached by none of the {} candidate poses drawn for it \
             ({drawn} in all): the arm does not reach it within its joint limits",
            l + 1,
            drawn / count
        )));
    }
    if qs.len() < n {
        return Err(Error::Compute(format!(
            "only {} of {n} poses reach their {}",
            qs.len(),
            s.kind.as_str()
        )));
    }
    qs.truncate(n);
    groups.truncate(n);
    if let Some(l) = missing(&groups) {
        return Err(Error::Compute(format!(
            "{kind} {} of {count} has none of the {n} poses: too few of the candidates drawn \
             for it reach it to be among the first {n} that reach theirs",
            l + 1
        )));
    }
    Ok((lay, qs, groups))
}

/// Moves the joint values `q` by `step` (rad), scaled down so that no joint moves by more than
/// 0.2 rad at once (a damped step of the pose searches above).
fn take_step(q: &mut [Real], step: &mut [Real]) {
    let big = step.iter().fold(0.0, |a: Real, s| a.max(s.abs()));
    let limit = 0.2;
    if big > limit {
        step.iter_mut().for_each(|s| *s *= limit / big);
    }
    q.iter_mut().zip(step.iter()).for_each(|(v, s)| *v += s);
}

/// Whether every joint value of `q` lies at least `margin` inside its limits.
fn within(robot: &Robot, q: &[Real], margin: Real) -> bool {
    robot
        .joints
        .iter()
        .zip(q)
        .all(|(j, v)| *v >= j.limits.0 + margin && *v <= j.limits.1 - margin)
}
