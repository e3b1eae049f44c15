//! Whether an identified robot can be physically right (docs/formats.md `identify`,
//! "Physical plausibility"): a calibration corrects a robot by millimetres and fractions of a
//! degree, so a result whose lengths moved by a large share of the robot's reach, whose
//! angles turned by degrees, whose readings are scaled against the nominal robot's points
//! (a file in metres or inches), or whose residual lies far below the instrument's stated
//! noise while its parameters moved far, comes from the data, not from the robot. Each such
//! finding is a cause in words, naming the parameter and how far it moved; the refusal adds
//! what in the data likely caused it (a unit, swapped or constant columns, a gross reading).

use std::path::Path;

use super::registration::register_svd;
use crate::error::{Error, Opt, Said};
use crate::measurement::kind::{Instrument, KindData};
use crate::numeric::{nearest_turn, Frame, Real, Vec3};
use crate::robot::sampling::reach_bound_mm;
use crate::robot::{gravity_basis, Param, Robot, GRAVITY_POINTS, MAX_JOINTS};

/// A joint's length or offset (`a`, `d`) may move by at most this share of the robot's reach
/// ([`reach_bound_mm`]: with a sliding joint's travel, so that a gantry has one) …
pub const LENGTH_SHARE: Real = 0.02;

/// … or by this many millimetres, whichever is larger.
pub const LENGTH_FLOOR_MM: Real = 10.0;

/// A joint's angle (`theta`, `alpha`, `beta`) or a joint-angle harmonic may move by at most
/// this many radians (5°).
pub const ANGLE_RAD: Real = 0.087_266_462_599_716_48;

/// The base's and the tool's lengths may move by at most this share of the reach.
pub const FRAME_SHARE: Real = 0.5;

/// The measured points' spread may differ from the nominal robot's tool points' by at most
/// this share.
pub const SCALE_TOLERANCE: Real = 0.1;

/// A residual RMS below this share of the instrument's stated noise (median `sigma_mm`) …
pub const NOISE_SHARE: Real = 0.1;

/// … while a length moved by more than this many times that noise is implausible.
pub const NOISE_MOVES: Real = 100.0;

/// The moves of `identified` from `nominal` beyond the bounds, each in words, for the
/// identified parameters `params` (compliances are not bounded; the base's and the tool's
/// angles neither: an instrument's frame can be anywhere), and the gravity basis's joint
/// deflections at the calibration poses `qs` beyond the angle bound ([`gravity_deflections`]).
pub fn moves(
    nominal: &Robot,
    identified: &Robot,
    params: &[Param],
    qs: &[Vec<Real>],
) -> Vec<String> {
    let reach = reach_bound_mm(nominal);
    let mut out: Vec<(Real, String)> = gravity_deflections(nominal, identified, params, qs);
    for &p in params {
        let mut moved = identified.get(p) - nominal.get(p);
        if matches!(p, Param::Theta(_) | Param::Alpha(_) | Param::Beta(_)) {
            // A whole turn more or less is the same joint: the move is the nearest angle.
            moved = nearest_turn(moved);
        }
        let Some((bound, what)) = bound_of(p, reach) else {
            continue;
        };
        if moved.is_finite() && moved.abs() <= bound {
            continue;
        }
        let text = if p.is_length() {
            format!("{p} moved by {moved:.3} mm (bound {bound:.1} mm: {what})")
        } else {
            format!(
                "{p} moved by {moved:.4} rad ({:.2}°; bound {bound:.4} rad: {what})",
                moved.to_degrees()
            )
        };
        let over = if moved.is_finite() {
            moved.abs() / bound
        } else {
            Real::INFINITY
        };
        out.push((over, text));
    }
    // The moves furthest beyond their bounds first; the rest counted.
    out.sort_by(|a, b| b.0.total_cmp(&a.0));
    let more = out.len().saturating_sub(MOVES_NAMED);
    let mut named: Vec<String> = out.into_iter().take(MOVES_NAMED).map(|m| m.1).collect();
    if more > 0 {
        named.push(match more {
            1 => "1 more parameter beyond its bound".to_string(),
            _ => format!("{more} more parameters beyond their bounds"),
        });
    }
    named
}

/// The joint deflections the identified gravity-basis coefficients give beyond [`ANGLE_RAD`]
/// (5°, the bound of a joint's angle), each with how far beyond (its ratio to the bound) and
/// in words. A coefficient `k_jl` is rad/(N·m) and bounded by what it does, not by its size:
/// for each joint `j` with coefficients among `params`, the largest `|Σ_l Δk_jl τ_jl(q)|` over
/// the poses `qs` (`Δk` the move from `nominal`, `τ` the basis torques of `identified`'s
/// geometry at `q`, as its forward kinematics apply them). A weight close to a joint's axis
/// has a small torque about it, so its coefficient can be large while its deflection is small;
/// one far from the axis turns the joint by degrees with a small coefficient.
pub fn gravity_deflections(
    nominal: &Robot,
    identified: &Robot,
    params: &[Param],
    qs: &[Vec<Real>],
) -> Vec<(Real, String)> {
    let mut dk = [[0.0; GRAVITY_POINTS]; MAX_JOINTS];
    let mut any = false;
    for &p in params {
        if let Param::Gravity(j, l) = p {
            dk[j][l] = identified.get(p) - nominal.get(p);
            any = true;
        }
    }
    if !any {
        return Vec::new();
    }
    let chain = identified.chain();
    let mut tau = [[0.0; GRAVITY_POINTS]; MAX_JOINTS];
    // Per joint: the largest deflection in size, signed, and the pose it is at.
    let mut largest = [(0.0 as Real, 0usize); MAX_JOINTS];
    for (i, q) in qs.iter().enumerate() {
        gravity_basis::torques(identified, &chain, &chain.variables(q), &mut tau);
        for (j, top) in largest.iter_mut().enumerate().take(identified.dof()) {
            let d: Real = dk[j].iter().zip(&tau[j]).map(|(k, t)| k * t).sum();
            if d.abs() > top.0.abs() || d.is_nan() {
                *top = (d, i);
            }
        }
    }
    let mut out = Vec::new();
    for (j, &(d, i)) in largest.iter().enumerate() {
        if d.is_finite() && d.abs() <= ANGLE_RAD {
            continue;
        }
        let coefficients: Vec<String> = params
            .iter()
            .filter(|p| matches!(p, Param::Gravity(k, _) if *k == j))
            .map(|&p| format!("{p} {:.4}", identified.get(p) - nominal.get(p)))
            .collect();
        let over = if d.is_finite() {
            d.abs() / ANGLE_RAD
        } else {
            Real::INFINITY
        };
        out.push((
            over,
            format!(
                "the gravity basis turns joint {} by {d:.4} rad ({:.2}°; bound {ANGLE_RAD:.4} rad:                  5°, as a joint's angle) at calibration pose {i} ({} rad/(N·m))",
                j + 1,
                d.to_degrees(),
                coefficients.join(", ")
            ),
        ));
    }
    out
}

/// How far a calibration may move parameter `p` of a robot of reach `reach` (mm), in its
/// unit, and the bound in words; `None` for a parameter without a bound (a compliance or a
/// gravity-basis coefficient, whose unit is rad/(N·m), not an angle: the latter's deflection
/// is bounded instead, [`gravity_deflections`]; the base's and the tool's angles).
fn bound_of(p: Param, reach: Real) -> Option<(Real, String)> {
    Some(match p {
        Param::Compliance(_) | Param::Gravity(..) => return None,
        Param::Base(_) | Param::Tool(_) if !p.is_length() => return None,
        Param::Base(_) | Param::Tool(_) => (
            FRAME_SHARE * reach,
            format!("{:.0} % of the robot's reach, {reach:.0} mm", FRAME_SHARE * 100.0),
        ),
        _ if p.is_length() => (
            (LENGTH_SHARE * reach).max(LENGTH_FLOOR_MM),
            format!(
                "the larger of {:.0} % of the robot's reach, {reach:.0} mm, and {LENGTH_FLOOR_MM:.0} mm",
                LENGTH_SHARE * 100.0
            ),
        ),
        _ => (ANGLE_RAD, "5°".to_string()),
    })
}

/// How far a calibration may move parameter `p` of `nominal` (mm, rad; the bound of
/// [`moves`]); `None` for a parameter without a bound.
pub fn bound(nominal: &Robot, p: Param) -> Option<Real> {
    bound_of(p, reach_bound_mm(nominal)).map(|b| b.0)
}

/// The moves a refusal names, furthest beyond their bounds first.
pub const MOVES_NAMED: usize = 3;

/// The ratio of the spread of `seen` (the RMS distance from their centroid) to that of
/// `model`; `None` when either is degenerate.
fn spread_ratio(model: &[Vec3], seen: &[Vec3]) -> Option<Real> {
    let spread = |v: &[Vec3]| {
        let c = v.iter().fold(Vec3::zeros(), |s, p| s + p) / v.len() as Real;
        (v.iter().map(|p| (p - c).norm_squared()).sum::<Real>() / v.len() as Real).sqrt()
    };
    if model.len() < 3 || model.len() != seen.len() {
        return None;
    }
    let (m, s) = (spread(model), spread(seen));
    (m > 0.0 && s.is_finite() && m.is_finite()).then(|| s / m)
}

/// The unit a spread ratio of `ratio` points to, when it is one (within 10 %).
fn unit_of(ratio: Real) -> Option<&'static str> {
    [
        (1e-3, "metres"),
        (1.0 / 25.4, "inches"),
        (0.1, "centimetres"),
        (1e3, "micrometres"),
    ]
    .into_iter()
    .find(|(r, _)| (ratio / r - 1.0).abs() <= 0.1)
    .map(|(_, u)| u)
}

/// A frame fitted to points alone must bring them within this share of how far the nominal
/// robot misses them in the frame they are taken in, for them to count as measured in another
/// frame ([`misfit`]).
pub const OTHER_FRAME_SHARE: Real = 0.2;

/// How measured points fail the nominal robot's tool points as a whole, before any fit
/// ([`misfit`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Misfit {
    /// They spread `ratio` times as far (beyond [`SCALE_TOLERANCE`]); `unit` the unit that
    /// ratio points to, when it is one.
    Scale {
        /// The ratio of the spreads.
        ratio: Real,
        /// The unit, when the ratio points to one.
        unit: Option<&'static str>,
    },
    /// The nominal robot misses them by `given` mm RMS in the frame they are taken in, and
    /// by `own` in a frame fitted to them alone.
    Frame {
        /// The RMS miss in the frame given (mm).
        given: Real,
        /// The RMS miss in their own frame (mm).
        own: Real,
    },
}

impl Misfit {
    /// In words: `points` names them (`the validation points`), `frame` the frame they are
    /// taken in (`the calibration's frame`).
    pub fn words(&self, points: &str, frame: &str) -> String {
        match *self {
            Misfit::Scale { ratio, unit } => {
                let unit = unit.map_or(String::new(), |u| {
                    format!(": they are likely in {u}, not millimetres")
                });
                format!(
                    "{points} spread {ratio:.4} times as far as the nominal robot's tool points \
                     (bound ±{:.0} %){unit}",
                    SCALE_TOLERANCE * 100.0
                )
            }
            Misfit::Frame { given, own } => format!(
                "the nominal robot misses {points} by {given:.1} mm RMS in {frame}, but by \
                 {own:.1} mm in a frame fitted to them alone"
            ),
        }
    }
}

/// How the measured points `seen` (mm, the instrument's frame; `frame` takes them into the
/// base frame) fail the nominal robot's tool points `model` at the same poses as a whole: a
/// spread beyond [`SCALE_TOLERANCE`], or an RMS miss above [`LENGTH_FLOOR_MM`] that a frame
/// fitted to the points alone cuts below [`OTHER_FRAME_SHARE`] of itself. `reference` is how
/// far the nominal robot misses the points `frame` was fitted to (RMS, mm; 0 for none): the
/// miss must also exceed it divided by that share, so that a nominal robot far from the
/// truth misses both alike. A calibration moves points by millimetres; a rigid motion of the
/// whole set is the frame's.
pub fn misfit(model: &[Vec3], seen: &[Vec3], frame: &Frame, reference: Real) -> Option<Misfit> {
    if let Some(ratio) = spread_ratio(model, seen).filter(|r| (r - 1.0).abs() > SCALE_TOLERANCE) {
        let unit = unit_of(ratio);
        return Some(Misfit::Scale { ratio, unit });
    }
    let given = miss_rms(model, seen, frame);
    // (A NaN miss is no finding: non-finite points are refused where they are read, and no
    // points give no miss.)
    if given.is_nan() || given <= LENGTH_FLOOR_MM.max(reference / OTHER_FRAME_SHARE) {
        return None;
    }
    let own = super::verdict::rms(&register_svd(model, seen, None).ok()?.residuals);
    (own < OTHER_FRAME_SHARE * given).then_some(Misfit::Frame { given, own })
}

/// How far the nominal robot's tool points `model` miss the measured points `seen` taken
/// into the base frame by `frame`: the RMS distance (mm); NaN for no points.
pub fn miss_rms(model: &[Vec3], seen: &[Vec3], frame: &Frame) -> Real {
    let squares: Real = (model.iter().zip(seen))
        .map(|(m, s)| (frame.apply(s) - m).norm_squared())
        .sum();
    (squares / model.len().min(seen.len()) as Real).sqrt()
}

/// What the measured points `seen` (the instrument's frame) say against the nominal robot's
/// points `model` at the same poses: a scale beyond [`SCALE_TOLERANCE`] (a finding, with the
/// unit it points to as a cause when it is one), a column of one value, or mirrored points
/// (two columns swapped or one's sign flipped: the points fit the nominal robot's much
/// closer mirrored back; a rigid fit cannot tell which two). The finding, and the causes in
/// words.
pub fn data_causes(model: &[Vec3], seen: &[Vec3]) -> (Option<String>, Vec<String>) {
    let mut causes = Vec::new();
    let ratio = spread_ratio(model, seen).filter(|r| (r - 1.0).abs() > SCALE_TOLERANCE);
    let scale = ratio.map(|r| {
        format!(
            "the measured points spread {r:.4} times as far as the nominal robot's tool points \
             (bound ±{:.0} %)",
            SCALE_TOLERANCE * 100.0
        )
    });
    if let Some(u) = ratio.and_then(unit_of) {
        causes.push(format!(
            "the file is likely in {u}, not millimetres (or the robot's lengths are not in \
             the unit its file declares)"
        ));
    }
    let axis = ["x", "y", "z"];
    for (c, name) in axis.iter().enumerate() {
        let first = seen.first().map(|p| p[c]);
        if seen.len() >= 3 && seen.iter().all(|p| Some(p[c]) == first) {
            causes.push(format!(
                "column {name} holds one value ({}) in every row",
                first.unwrap_or(Real::NAN)
            ));
        }
    }
    if causes.is_empty() {
        let rms = |r: &[Real]| (r.iter().map(|v| v * v).sum::<Real>() / r.len() as Real).sqrt();
        let fit = |pts: &[Vec3]| {
            register_svd(model, pts, None)
                .ok()
                .map(|r| rms(&r.residuals))
        };
        let mirrored: Vec<Vec3> = seen.iter().map(|p| Vec3::new(p.y, p.x, p.z)).collect();
        if let (Some(plain), Some(back)) = (fit(seen), fit(&mirrored)) {
            if plain > LENGTH_FLOOR_MM && back < plain / 5.0 {
                causes.push(format!(
                    "the points are a mirror image of the robot's: two columns look swapped \
                     (x and y, say) or one has its sign flipped (they fit the nominal robot's \
                     within {back:.1} mm RMS mirrored back, {plain:.1} mm as given)"
                ));
            }
        }
    }
    (scale, causes)
}

/// A residual RMS (`rms`, mm) below [`NOISE_SHARE`] of the instrument's stated noise
/// (`sigma`, the median of its per-reading σ) while a length moved by more than
/// [`NOISE_MOVES`] times that noise (`largest`: the largest move of a length, mm).
pub fn below_noise(rms: Real, sigma: Option<&[Real]>, largest: Real) -> Option<String> {
    let mut s: Vec<Real> = sigma?.iter().copied().filter(|v| v.is_finite()).collect();
    if s.is_empty() {
        return None;
    }
    s.sort_by(Real::total_cmp);
    let noise = s[s.len() / 2];
    (noise > 0.0 && rms < NOISE_SHARE * noise && largest > NOISE_MOVES * noise).then(|| {
        format!(
            "the residual RMS {rms:.5} mm lies far below the instrument's stated noise \
             ({noise:.4} mm) while a length moved by {largest:.3} mm: the data cannot hold \
             that much information (a unit or a copied column)"
        )
    })
}

/// The largest move of an identified length (mm) of `identified` from `nominal`.
pub fn largest_length_move(nominal: &Robot, identified: &Robot, params: &[Param]) -> Real {
    params
        .iter()
        .filter(|p| p.is_length())
        .map(|&p| (identified.get(p) - nominal.get(p)).abs())
        .fold(0.0, Real::max)
}

/// What [`judge`] judges: the nominal robot, the identified one, the parameters identified and
/// the calibration poses.
pub type Judged<'a> = (&'a Robot, &'a Robot, &'a [Param], &'a [Vec<Real>]);

/// What makes an identification implausible (`found`: empty when nothing does) and what in
/// the data likely caused it (`causes`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Findings {
    /// The moves beyond the bounds, a scale beyond its tolerance, a residual below the noise.
    pub found: Vec<String>,
    /// A unit, a column of one value, swapped columns, a gross reading.
    pub causes: Vec<String>,
}

/// Judges the identified robot `identified` (parameters `params`, calibration poses `qs`)
/// against `nominal`: its moves ([`moves`]), the measured points against the nominal robot's (`points`: model,
/// seen; [`data_causes`]), its residual RMS `rms` against the stated noise `sigma`
/// ([`below_noise`]); `found_causes` what the caller finds in the data, causes in words
/// ([`gross_cause`], the orientations' convention), asked only when something is found.
pub fn judge(
    (nominal, identified, params, qs): Judged,
    points: Option<(&[Vec3], &[Vec3])>,
    (rms, sigma): (Real, Option<&[Real]>),
    found_causes: impl FnOnce() -> Vec<String>,
) -> Findings {
    let mut found = moves(nominal, identified, params, qs);
    let largest = largest_length_move(nominal, identified, params);
    found.extend(below_noise(rms, sigma, largest));
    let (scale, mut causes) = points.map_or((None, vec![]), |(m, s)| data_causes(m, s));
    if let Some(scale) = scale {
        found.push(scale);
    }
    if found.is_empty() {
        return Findings::default();
    }
    causes.extend(found_causes());
    Findings { found, causes }
}

/// A gross reading the residuals point to (`reading`, in words) as a cause for [`judge`].
pub fn gross_cause(reading: String) -> String {
    format!("{reading} (a gross reading)")
}

/// A multi-target file's points (`data`, at the poses `qs`) beside the nominal robot's
/// target points at those poses (model, seen), for [`judge`]; `None` for the other kinds.
pub fn target_points(
    nominal: &Robot,
    qs: &[Vec<Real>],
    data: &KindData,
) -> Option<(Vec<Vec3>, Vec<Vec3>)> {
    let Instrument::Targets(targets) = &data.instrument else {
        return None;
    };
    let chain = nominal.chain();
    let model: Vec<Vec3> = qs
        .iter()
        .flat_map(|q| {
            let f = chain.fk(q);
            targets.iter().map(move |o| f.pos + f.rot * o)
        })
        .collect();
    let seen: Vec<Vec3> = data
        .values
        .chunks(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    Some((model, seen))
}

/// The refusal of an identification that cannot be physically right, read from `source`:
/// `found` the implausible moves and findings, `causes` what in the data likely caused them;
/// it names the option that writes it with a warning ([`Opt::AllowImplausible`]), unless
/// `external`, a method supplied from outside ([`super::verdict::way_past`]).
pub fn implausible_error(
    source: &Path,
    found: &[String],
    causes: &[String],
    external: bool,
) -> Error {
    let cause = if causes.is_empty() {
        "no single cause was found in the data: check the units, the columns, a gross reading \
         and the robot model"
            .to_string()
    } else {
        format!("likely cause: {}", causes.join("; "))
    };
    let msg = format!(
        "the identified robot cannot be physically right: {}; {cause}; nothing was written. \
         Fix the data",
        found.join("; ")
    );
    let msg = super::verdict::way_past(msg, Opt::AllowImplausible, external);
    Error::file(source, "data", msg)
}

/// The findings `f` of an identification read from `source`: refused
/// ([`implausible_error`]) unless `allow`, when they find anything; what was found
/// otherwise, its likely cause last (kept with a warning). `external`: the result is a
/// method's supplied from outside ([`implausible_error`]).
pub fn verdict(
    f: Findings,
    source: &Path,
    (allow, external): (bool, bool),
) -> crate::Result<Vec<String>> {
    if f.found.is_empty() {
        return Ok(Vec::new());
    }
    if allow {
        let mut kept = f.found;
        if !f.causes.is_empty() {
            kept.push(format!("likely cause: {}", f.causes.join("; ")));
        }
        return Ok(kept);
    }
    Err(implausible_error(source, &f.found, &f.causes, external))
}

/// [`verdict`] of [`judge`]: the findings on `subject`, refused (read from `source`) unless
/// `allow`, offering no way past for a method supplied from outside (`external`).
pub fn check(
    subject: Judged,
    points: Option<(&[Vec3], &[Vec3])>,
    noise: (Real, Option<&[Real]>),
    found_causes: impl FnOnce() -> Vec<String>,
    (source, allow, external): (&Path, bool, bool),
) -> crate::Result<Vec<String>> {
    verdict(
        judge(subject, points, noise, found_causes),
        source,
        (allow, external),
    )
}

/// The tool points of `robot` at the poses `qs`.
pub fn tool_points(robot: &Robot, qs: &[Vec<Real>]) -> Vec<Vec3> {
    let chain = robot.chain();
    qs.iter().map(|q| chain.fk(q).pos).collect()
}

/// The warning of a result kept although it cannot be physically right (`found`), if any.
pub fn implausible_warning(found: &[String]) -> Option<Said> {
    (!found.is_empty()).then(|| {
        let msg = format!(
            "the identified robot cannot be physically right ({}); kept because of ",
            found.join("; ")
        );
        Said::from(msg)
            .on(Opt::AllowImplausible)
            .text(": do not load it into a controller before checking the data")
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::builtin;

    #[test]
    fn moves_beyond_the_bounds_are_named_and_within_are_not() {
        let nominal = builtin::load("irb2600").unwrap();
        let reach = reach_bound_mm(&nominal);
        assert!(reach > 1500.0 && reach < 3000.0, "{reach}");
        let params = [Param::A(1), Param::Theta(2), Param::Tool(0), Param::Tool(4)];
        let small = nominal.with_errors(&[(Param::A(1), 1.0), (Param::Theta(2), 0.01)]);
        assert!(moves(&nominal, &small, &params, &[]).is_empty());
        let a2 = nominal.get(Param::A(1));
        let metres = nominal.with_errors(&[(Param::A(1), a2 / 1000.0 - a2)]);
        let m = moves(&nominal, &metres, &params, &[]);
        assert_eq!(m.len(), 1, "{m:?}");
        assert!(m[0].starts_with("a2 moved by -"), "{m:?}");
        let turned = nominal.with_errors(&[(Param::Theta(2), 0.2), (Param::Tool(4), 3.0)]);
        let m = moves(&nominal, &turned, &params, &[]);
        assert_eq!(m.len(), 1, "the tool's angle is not bounded: {m:?}");
        assert!(m[0].contains("theta3") && m[0].contains("11.46°"), "{m:?}");
        // A whole turn more is the same joint: the move is what is left of it.
        let tau = std::f64::consts::TAU;
        // A gravity-basis coefficient is rad/(N·m), not an angle: not bounded by 5°.
        let g = [Param::Gravity(1, 0)];
        let sagging = nominal.with_errors(&[(g[0], -0.2123)]);
        assert!(moves(&nominal, &sagging, &g, &[]).is_empty());
        let whole = nominal.with_errors(&[(Param::Theta(2), -tau - 0.01)]);
        assert!(moves(&nominal, &whole, &params, &[]).is_empty());
        let whole = nominal.with_errors(&[(Param::Theta(2), tau + 0.2)]);
        let m = moves(&nominal, &whole, &params, &[]);
        assert!(m.len() == 1 && m[0].contains("11.46°"), "{m:?}");
    }

    /// The gravity basis is bounded by the deflection it gives at the calibration poses, not
    /// by its coefficient: on the irb2600 a small `gt2` (0.1 rad/(N·m); a unit weight at the tool
    /// point has a lever of over a metre about joint 2) turns joint 2 by more than 5° and is
    /// named with its largest deflection, the torque taken independently from the joint frames;
    /// a large `gw4` (0.9) loads joint 4 by a weight at the wrist centre, which lies on joint
    /// 4's axis, and turns it by nothing.
    #[test]
    fn gravity_coefficients_are_bounded_by_their_deflection_at_the_poses() {
        let nominal = builtin::load("irb2600").unwrap();
        let mut g = crate::numeric::rng::stream(2, "plausibility-gravity");
        let qs = crate::robot::sampling::uniform_joint_poses(&nominal, 50, &mut g);
        let gt2 = Param::Gravity(1, 2);
        let small = nominal.with_errors(&[(gt2, 0.1)]);
        let chain = small.chain();
        let tau2 = |q: &[Real]| {
            let frames = chain.joint_frames(q);
            let r = (chain.fk(q).pos - frames[1].pos) * 1e-3;
            frames[1]
                .rot
                .column(2)
                .dot(&r.cross(&Vec3::new(0.0, 0.0, -1.0)))
        };
        let (mut want, mut at) = (0.0, 0);
        for (i, q) in qs.iter().enumerate() {
            if (0.1 * tau2(q)).abs() > Real::abs(want) {
                (want, at) = (0.1 * tau2(q), i);
            }
        }
        assert!(Real::abs(want) > ANGLE_RAD, "{want}");
        let found = gravity_deflections(&nominal, &small, &[gt2], &qs);
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(
            (found[0].0 - Real::abs(want) / ANGLE_RAD).abs() < 1e-9,
            "{found:?} {want}"
        );
        let text = &found[0].1;
        let words = format!("turns joint 2 by {want:.4} rad");
        assert!(text.contains(&words), "{text}");
        assert!(
            text.contains(&format!("pose {at}")) && text.contains("gt2 0.1000"),
            "{text}"
        );
        let m = moves(&nominal, &small, &[gt2], &qs);
        assert!(m.len() == 1 && m[0] == *text, "{m:?}");
        // The same coefficient at the poses where it turns joint 2 by less: nothing found.
        let within: Vec<Vec<Real>> = qs
            .iter()
            .filter(|q| (0.1 * tau2(q)).abs() <= ANGLE_RAD)
            .cloned()
            .collect();
        assert!(
            within.len() >= 5 && within.len() < qs.len(),
            "{}",
            within.len()
        );
        assert!(gravity_deflections(&nominal, &small, &[gt2], &within).is_empty());
        // A large coefficient on a weight near the joint's axis: no deflection to speak of.
        let gw4 = Param::Gravity(3, 1);
        let large = nominal.with_errors(&[(gw4, 0.9)]);
        assert!(gravity_deflections(&nominal, &large, &[gw4], &qs).is_empty());
        assert!(moves(&nominal, &large, &[gw4], &qs).is_empty());
        let mut tau = [[0.0; GRAVITY_POINTS]; MAX_JOINTS];
        let chain = large.chain();
        for q in &qs {
            gravity_basis::torques(&large, &chain, &chain.variables(q), &mut tau);
            assert!((0.9 * tau[3][1]).abs() < 1e-3 * ANGLE_RAD, "{}", tau[3][1]);
        }
    }

    fn cloud() -> Vec<Vec3> {
        (0..30)
            .map(|i| {
                let t = i as Real;
                Vec3::new(
                    800.0 + 300.0 * (t * 0.7).sin(),
                    200.0 * (t * 1.3).cos(),
                    50.0 * t,
                )
            })
            .collect()
    }

    #[test]
    fn units_swaps_and_constant_columns_are_told_from_the_points() {
        let model = cloud();
        assert_eq!(data_causes(&model, &model), (None, vec![]));
        let metres: Vec<Vec3> = model.iter().map(|p| p / 1000.0).collect();
        let (scale, c) = data_causes(&model, &metres);
        assert!(scale.unwrap().contains("0.0010 times"));
        assert!(c[0].contains("metres"), "{c:?}");
        let inches: Vec<Vec3> = model.iter().map(|p| p / 25.4).collect();
        assert!(data_causes(&model, &inches).1[0].contains("inches"));
        let swapped: Vec<Vec3> = model.iter().map(|p| Vec3::new(p.x, p.z, p.y)).collect();
        let (_, c) = data_causes(&model, &swapped);
        assert!(
            c.len() == 1 && c[0].contains("two columns look swapped"),
            "{c:?}"
        );
        let flat: Vec<Vec3> = model.iter().map(|p| Vec3::new(0.0, p.y, p.z)).collect();
        let (_, c) = data_causes(&model, &flat);
        assert!(c[0].contains("column x holds one value"), "{c:?}");
    }

    #[test]
    fn a_residual_below_the_noise_counts_only_with_far_moves() {
        let sigma = [0.01, 0.02, 0.015];
        assert!(below_noise(0.0001, Some(&sigma), 600.0).is_some());
        assert!(below_noise(0.0001, Some(&sigma), 0.5).is_none());
        assert!(below_noise(0.02, Some(&sigma), 600.0).is_none());
        assert!(below_noise(0.0001, None, 600.0).is_none());
    }
}
