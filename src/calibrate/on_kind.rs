//! Identification on a measurement-kind file (`calbench identify` on a `distance`, `plane` or
//! `sphere` file, docs/formats.md § 5.3): the robot's parameters and the instrument's own
//! unknowns (pivot, plane coefficients, sphere centres) by any Jacobian method through
//! [`KindProblem`], the parameters the readings cannot determine named, and the compensated
//! robot validated, when asked, on a tracker's file.

use std::path::Path;

use nalgebra::DVector;

use super::plausibility;
use super::record::{names, FrameRecord, IdentifiedRecord};
use super::registration::register_svd;
use super::request::IdentifyRequest;
use super::validation::ErrorStats;
use super::verdict::{
    allowing, check_names, gross_likely, gross_reading, radians_hint, worse_causes, worse_error,
    worse_warning,
};
use super::Registration;
use crate::error::{Error, Opt, Result, Said};
use crate::identify::kind::{identifiability, KindAnalysis, KindProblem};
use crate::identify::{solve, Identified, LeastSquares, Solver};
use crate::measurement::kind::Kind;
use crate::measurement::kind::{choose_plane_axes, nuisance_guess, Instrument, KindData};
use crate::measurement::kind_csv::KindFile;
use crate::measurement::Measurements;
use crate::numeric::{Frame, Real, Vec3};
use crate::robot::identifiability::Identifiability;
use crate::robot::{Param, Robot};
use crate::sim::instrument::{touch, Layout};
use unfixed::{misplaced_sockets, repeated, too_few, undetermined, unknowns_free};

mod unfixed;

/// What the parameters to identify are: the identifiable set, or the user's.
#[derive(Clone, Copy, Debug)]
pub enum Chosen<'a> {
    /// Every parameter of the robot (base and tool first) that the readings determine.
    Identifiable,
    /// These parameters (`--params`), refused when the readings do not determine them all
    /// unless the flag is set (`--allow-rank-deficient`).
    Given(&'a [Param], bool),
}

/// The identification on a kind file and what it found.
#[derive(Debug)]
pub struct KindFit {
    /// The readings as identified (plane axes chosen; targets' points in the base frame).
    pub data: KindData,
    /// Targets: the frame that took the measured points into the base frame (SVD onto the
    /// nominal robot's target points), after which the base parameters are identified.
    pub registration: Option<Frame>,
    /// The identified robot parameters, in the order of the estimate.
    pub params: Vec<Param>,
    /// The analysis of the candidates on the file's poses (the instrument's unknowns
    /// projected out).
    pub analysis: Identifiability,
    /// The instrument's own unknowns the readings leave free ([`KindAnalysis::undetermined`]).
    pub undetermined_unknowns: Vec<String>,
    /// The solver's result: robot errors, then the corrections of the instrument's unknowns.
    pub identified: Identified,
    /// The compensated robot.
    pub robot: Robot,
    /// The instrument's unknowns at the solution (names:
    /// [`crate::measurement::kind::Instrument::nuisance_names`]).
    pub nuisance: Vec<Real>,
    /// The RMS residual per reading (mm) of the nominal robot with the instrument's first
    /// guess, and at the solution.
    pub rms: (Real, Real),
    /// Each reading's residual (mm; the norm of its rows) as for [`KindFit::rms`]: before,
    /// at the solution.
    pub residuals: (Vec<Real>, Vec<Real>),
}

/// Identifies `nominal`'s parameters (`chosen`, without `fixed`) and the instrument's
/// unknowns from the readings of `file` (read from `source`, named in refusals) with
/// `solver`, observation `i` weighted by `1/σ_i²` (normalised to a mean of 1) when the file
/// has `sigma_mm`; targets' points are first registered into the base frame when `register`
/// (SVD onto the nominal robot's target points; otherwise they are taken as in the base frame
/// and the base is not a candidate). Refuses parameters the readings cannot determine when they were given and
/// not allowed, and readings too few for the instrument's first guess (naming the file).
pub fn identify_kind(
    nominal: &Robot,
    file: &KindFile,
    source: &Path,
    (chosen, fixed, register): (Chosen, &[Param], bool),
    solver: &dyn Solver,
) -> Result<KindFit> {
    // The readings' refusal is the file's: the library's name for them (the setting
    // `measurements`) is not repeated after the file's.
    let in_file = |e: Error| match e {
        Error::Setting { msg, .. } => Error::file(source, "data", msg),
        e => Error::file(source, "data", e.to_string()),
    };
    let (data, registration, p) = prepared(nominal, file, register).map_err(in_file)?;
    let targets = matches!(data.instrument, Instrument::Targets(_));
    let mut candidates: Vec<Param> = match chosen {
        Chosen::Given(ps, _) => ps.to_vec(),
        Chosen::Identifiable => candidates(nominal, targets && !register),
    };
    candidates.retain(|p| !fixed.contains(p));
    super::verdict::check_some_left(&candidates, fixed)?;
    let (qs, on) = on_first_guess(nominal, &file.qs, &data, &p).map_err(in_file)?;
    let KindAnalysis {
        robot: analysis,
        undetermined: undetermined_unknowns,
        ..
    } = identifiability(nominal, &candidates, &qs, &on).map_err(in_file)?;
    let params = match chosen {
        Chosen::Given(_, allow) => {
            if !analysis.unidentifiable.is_empty() && !allow {
                return Err(undetermined(source, &data, &analysis, candidates.len()));
            }
            candidates
        }
        Chosen::Identifiable => {
            let mut ps = analysis.identifiable.clone();
            ps.sort_by_key(|p| p.index(nominal.dof()));
            ps
        }
    };
    let weights = file.sigma_mm.as_ref().map(|s| {
        let inv: Vec<Real> = s.iter().map(|v| 1.0 / (v * v)).collect();
        let mean = inv.iter().sum::<Real>() / inv.len().max(1) as Real;
        inv.iter().map(|w| w / mean).collect::<Vec<Real>>()
    });
    let kp = KindProblem::new(nominal, &params, &file.qs, &data)
        .and_then(|k| k.with_prior_weights(weights.as_deref()))
        .map_err(in_file)?;
    let identified = solve(solver, &kp, &DVector::zeros(kp.size().params));
    let robot = kp.robot_with(&identified.x);
    let nuisance = kp.nuisance_at(&identified.x);
    let before = reading_residuals(&kp, None, &data.instrument);
    let after = reading_residuals(&kp, Some(&identified.x), &data.instrument);
    let rms = (super::verdict::rms(&before), super::verdict::rms(&after));
    let residuals = (before, after);
    Ok(KindFit {
        registration,
        data,
        params,
        analysis,
        undetermined_unknowns,
        identified,
        robot,
        nuisance,
        rms,
        residuals,
    })
}

/// The readings of `file` as the identification reads them, with the nominal robot's tool
/// points at its poses: each plane's normal axis chosen from its points, and multi-target
/// points registered into the base frame when `register` (with that registration's frame).
fn prepared(
    nominal: &Robot,
    file: &KindFile,
    register: bool,
) -> Result<(KindData, Option<Frame>, Vec<Vec3>)> {
    let mut data = file.data.clone();
    let chain = nominal.chain();
    let p: Vec<Vec3> = file.qs.iter().map(|q| chain.fk(q).pos).collect();
    choose_plane_axes(&mut data, &p);
    let targets = matches!(data.instrument, Instrument::Targets(_));
    let registration = match targets && register {
        true => Some(register_targets(nominal, &file.qs, &mut data)?),
        false => None,
    };
    Ok((data, registration, p))
}

/// The parameters a kind file's identification chooses from, base and tool first: every one
/// but the compliances, and but the base's when it is `fixed_base` (targets in the base frame
/// leave the base as it is, as the tracker's `known` registration does).
fn candidates(nominal: &Robot, fixed_base: bool) -> Vec<Param> {
    let all: Vec<Param> = nominal
        .params()
        .into_iter()
        .filter(|p| !p.is_compliance())
        .filter(|p| !(fixed_base && matches!(p, Param::Base(_))))
        .collect();
    let first = |p: &Param| matches!(p, Param::Base(_) | Param::Tool(_));
    let head = all.iter().copied().filter(first);
    head.chain(all.iter().copied().filter(|p| !first(p)))
        .collect()
}

/// What the readings of the kind file `file` determine of `nominal`'s parameters (every one
/// but the compliances), judged as `identify` judges them (docs/formats.md § 2.12): the same
/// poses, moved into the instrument's first guess (`on_first_guess`), the instrument's
/// unknowns projected out.
pub fn file_identifiability(nominal: &Robot, file: &KindFile) -> Result<KindAnalysis> {
    let (data, _, p) = prepared(nominal, file, true)?;
    let (qs, on) = on_first_guess(nominal, &file.qs, &data, &p)?;
    identifiability(nominal, &candidates(nominal, false), &qs, &on)
}

/// Each reading's residual (mm, the norm of its rows) of `kp` at `x` (`None`: zero errors,
/// the instrument's first guess).
fn reading_residuals(kp: &KindProblem, x: Option<&DVector<Real>>, inst: &Instrument) -> Vec<Real> {
    let size = kp.size();
    let zero = DVector::zeros(size.params);
    let mut r = DVector::zeros(size.rows());
    let mut j = nalgebra::DMatrix::zeros(size.rows(), size.params);
    kp.evaluate(x.unwrap_or(&zero), &mut r, &mut j);
    // A pose of targets holds a point (3 rows) per target: one reading each.
    let rows = match inst {
        Instrument::Targets(_) => 3,
        _ => size.rows_per_point.max(1),
    };
    r.as_slice()
        .chunks(rows)
        .map(|c| c.iter().map(|v| v * v).sum::<Real>().sqrt())
        .collect()
}

/// The file's poses moved, by the nominal robot, onto the planes, spheres or sockets of the
/// first guess of the instrument's unknowns from the nominal tool points `p`
/// ([`nuisance_guess`], [`touch`]), with their readings: where the model's points lie on its
/// own surfaces or in its own sockets, so that the identifiability is the structure's. At
/// the file's poses themselves the nominal points lie off the fitted planes, or apart from
/// their socket, by the robot's errors, and a parameter that the instrument's unknowns absorb
/// exactly (a base rotation, which turns the planes or the sockets with it) would look
/// determined by the direction of those gaps: a socket fit then turned the base by a degree
/// or two, 40 mm at the tool, at no cost to its residuals. Poses that cannot be moved so are
/// left out; the other kinds keep every pose.
fn on_first_guess(
    nominal: &Robot,
    qs: &[Vec<Real>],
    data: &KindData,
    p: &[Vec3],
) -> Result<(Vec<Vec<Real>>, KindData)> {
    let inst = &data.instrument;
    let moved_kinds = matches!(
        inst,
        Instrument::Planes(_) | Instrument::Spheres(_) | Instrument::Sockets(_)
    );
    if !moved_kinds {
        return Ok((qs.to_vec(), data.clone()));
    }
    let lay = first_guess(data, p)?;
    let mut on = data.clone();
    on.group.clear();
    on.values.clear();
    let mut moved = Vec::with_capacity(qs.len());
    let per = inst.rows_per_observation();
    for ((q, &g), v) in qs.iter().zip(&data.group).zip(data.values.chunks(per)) {
        if let Some(t) = touch(nominal, &lay, g, q, 0.0) {
            moved.push(t);
            on.group.push(g);
            on.values.extend_from_slice(v);
        }
    }
    // A surface whose poses mostly cannot be moved onto it: its first guess is not a
    // surface through its points.
    if let Some((surfaces, need)) = inst.surfaces() {
        for g in 0..surfaces {
            let count = |of: &[usize]| of.iter().filter(|&&x| x == g).count();
            let (held, kept) = (count(&data.group), count(&on.group));
            if kept < need && held >= need {
                let kind = inst.kind().as_str();
                let of = match inst {
                    Instrument::Spheres(r) => format!(" of the file's radius {} mm", r[g]),
                    _ => String::new(),
                };
                return Err(Error::setting(
                    "measurements",
                    format!(
                        "{kept} of the {held} poses of {kind} {} reach the {kind} fitted to \
                         their nominal tool points (its first guess), and it needs at least \
                         {need}: the points lie far from one {kind}{of} (a length in another \
                         unit, a {kind} column that mixes surfaces)",
                        g + 1
                    ),
                ));
            }
        }
    }
    Ok((moved, on))
}

/// The instrument of `data` at its first guess from the nominal tool points `p`
/// ([`nuisance_guess`]).
fn first_guess(data: &KindData, p: &[Vec3]) -> Result<Layout> {
    let inst = &data.instrument;
    Ok(Layout {
        instrument: inst.clone(),
        nuisance: nuisance_guess(inst, &data.group, p, &data.values)?,
    })
}

/// Registers the targets' points of `data` (the instrument's frame) onto the nominal robot's
/// target points at `qs` (SVD, every point weighing 1) and puts them into the base frame;
/// the registration's frame. The base parameters, identified with the others, then take up
/// what the nominal robot's errors left in this frame, as with the tracker's `identify`
/// registration.
fn register_targets(nominal: &Robot, qs: &[Vec<Real>], data: &mut KindData) -> Result<Frame> {
    let Instrument::Targets(targets) = &data.instrument else {
        return Ok(Frame::identity());
    };
    let chain = nominal.chain();
    let mut model = Vec::with_capacity(targets.len() * qs.len());
    for q in qs {
        let f = chain.fk(q);
        model.extend(targets.iter().map(|o| f.pos + f.rot * o));
    }
    let seen: Vec<Vec3> = data
        .values
        .chunks(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    let frame = register_svd(&model, &seen, None)?.frame;
    data.values = seen
        .iter()
        .flat_map(|p| frame.apply(p).iter().copied().collect::<Vec<_>>())
        .collect();
    Ok(frame)
}

/// The validation of `nominal` and `compensated` on a tracker's file `v`
/// (docs/formats.md § 5.1): each robot's tool points at the file's poses registered onto the
/// measured points (SVD, every point weighing 1), and the distances left (before, after), mm.
pub fn validate_positions(
    nominal: &Robot,
    compensated: &Robot,
    v: &Measurements,
) -> Result<(ErrorStats, ErrorStats)> {
    let stats = |r: &Robot| -> Result<ErrorStats> {
        Ok(ErrorStats::of(&registered_distances(r, &v.qs, &v.points)?))
    };
    Ok((stats(nominal)?, stats(compensated)?))
}

/// The distances (mm) between `seen` points and `robot`'s tool points at `qs` registered onto
/// them (SVD): the position error as a tracker sees it, in its own frame.
pub fn registered_distances(robot: &Robot, qs: &[Vec<Real>], seen: &[Vec3]) -> Result<Vec<Real>> {
    let c = robot.chain();
    let model: Vec<Vec3> = qs.iter().map(|q| c.fk(q).pos).collect();
    Ok(register_svd(seen, &model, None)?.residuals)
}

/// An identification on a measurement-kind file.
pub struct KindOutcome {
    /// The nominal robot.
    pub nominal: Robot,
    /// The readings' kind.
    pub kind: Kind,
    /// The number of readings.
    pub readings: usize,
    /// Whether the parameters were the identifiable set (the undetermined ones left at their
    /// nominal values) rather than given.
    pub identifiable: bool,
    /// The identification.
    pub fit: KindFit,
    /// The position errors on a tracker's validation file, before and after (mm).
    pub validation: Option<(ErrorStats, ErrorStats)>,
    /// `identified.json`, with why the result makes the robot worse (kept with
    /// `allow_worse`) among the rest.
    pub record: IdentifiedRecord,
    /// The warning of a gross reading the fit kept ([`super::verdict::gross_kept`]).
    pub gross: Option<String>,
}

impl KindOutcome {
    /// The compensated robot, named `<nominal>-calibrated`, as `robot.toml` holds it.
    pub fn compensated(&self) -> Robot {
        let mut r = self.fit.robot.clone();
        r.name = format!("{}-calibrated", self.nominal.name);
        r
    }

    /// The warnings of a result kept worse than the nominal robot or although it cannot be
    /// physically right, and of a gross reading the fit kept.
    pub fn warnings(&self) -> Vec<Said> {
        let worse = worse_warning(&self.record.allowed_worse);
        let implausible = plausibility::implausible_warning(&self.record.allowed_implausible);
        let gross = self.gross.clone().map(Said::from);
        worse.into_iter().chain(implausible).chain(gross).collect()
    }
}

/// Two targets' points may be further from their offsets' distance than this many mm …
const TARGETS_APART_MM: Real = 5.0;

/// … plus this share of it, before the offsets count as contradicted.
const TARGETS_APART_SHARE: Real = 0.05;

/// A multi-target file whose readings contradict its target offsets
/// ([`KindData::contradicted_targets`]), as a plausibility finding and its cause in words:
/// the identification cannot fit such a file, and would end "converged" far from it.
fn contradicted_offsets(data: &KindData) -> Option<(String, String)> {
    let tolerance = |d: Real| TARGETS_APART_MM + TARGETS_APART_SHARE * d;
    let (a, b, by_offsets, read) = data.contradicted_targets(tolerance)?;
    let found = format!(
        "targets {} and {} are {by_offsets:.3} mm apart by their offsets but {read:.3} mm \
         apart in the readings (the median over the poses), where targets on one flange keep \
         their distance",
        a + 1,
        b + 1
    );
    let cause = "the offsets (target_x_mm, target_y_mm, target_z_mm) are not those of the \
                 targets measured"
        .to_string();
    Some((found, cause))
}

/// The keys of `identified.json` that a kind file adds to those of every identification:
/// the kind, the readings, the instrument's unknowns and standard errors, and what describes
/// the instrument (targets' offsets and registration, the pivot, the planes' axes).
fn kind_keys(
    record: IdentifiedRecord,
    fit: &KindFit,
    (kind, readings): (Kind, usize),
    registration: Registration,
) -> IdentifiedRecord {
    let (inst, r) = (&fit.data.instrument, &fit.identified);
    let cov = r.covariance();
    let sigma = |k: usize| cov.get((k, k)).map_or(Real::NAN, |v| v.sqrt());
    let nuisance = inst.nuisance_names();
    let all = record.parameters.iter().chain(&nuisance).cloned();
    let mut record = IdentifiedRecord {
        kind: Some(kind),
        readings: Some(readings),
        instrument_unknowns: Some(nuisance.iter().cloned().zip(fit.nuisance.clone()).collect()),
        standard_errors: Some(all.enumerate().map(|(k, n)| (n, sigma(k))).collect()),
        unidentifiable: Some(names(&fit.analysis.unidentifiable)),
        ..record
    };
    match inst {
        Instrument::Targets(offsets) => {
            record.targets_mm = Some(offsets.iter().map(|o| [o.x, o.y, o.z]).collect());
            record.registration = Some(registration);
            record.registration_frame = fit.registration.as_ref().map(FrameRecord::from);
        }
        Instrument::Distance { pivot } => record.pivot = Some(*pivot),
        Instrument::Planes(axes) => {
            record.plane_axes = Some(axes.iter().map(|&a| ["x", "y", "z"][a].into()).collect());
        }
        Instrument::Spheres(_) | Instrument::Sockets(_) => {}
    }
    record
}

/// The options of a request that a kind file does not take: each with whether it was given.
fn tracker_only(q: &IdentifyRequest) -> [(Opt, bool); 6] {
    [
        (Opt::Holdout, q.holdout.is_some()),
        (Opt::Cv, q.cv.is_some()),
        (Opt::Models, !q.models.is_empty()),
        (Opt::Compliance, q.compliance.is_some()),
        (
            Opt::Prior,
            !q.priors.is_empty() || !q.method.priors.is_empty(),
        ),
        (Opt::K, q.k.is_some()),
    ]
}

/// The option a kind file (of targets or not) refuses and why, if any: the tracker's
/// options, a registration the kind does not take, a method that is not a Jacobian one
/// (`solver`: it is).
fn refusal(q: &IdentifyRequest, targets: bool, solver: bool) -> Option<(Opt, String)> {
    if let Some((option, _)) = tracker_only(q).into_iter().find(|o| o.1) {
        let why = "it applies to the tracker's measurement file (§ 5.1) only";
        return Some((option, why.to_string()));
    }
    let registration = q.registration;
    if registration != Registration::Identify && !(targets && registration == Registration::Known) {
        let why = if targets {
            "multi-target points are registered by SVD onto the nominal robot with the base \
             identified after (identify), or taken in the base frame (known)"
        } else {
            "the instrument is placed by its own unknowns, identified with the robot"
        };
        return Some((
            Opt::Registration,
            format!("{} is not taken: {why}", registration.as_str()),
        ));
    }
    (!solver).then(|| {
        let why = format!(
            "{} is not one of the Jacobian methods (ls, ridge, igg3, lm) that identify them",
            q.method.shown_name()
        );
        (Opt::Method, why)
    })
}

/// The refusal, by file, of an option `option` a kind file does not take (`why`).
pub fn kind_refusal(q: &IdentifyRequest, kind: Kind, option: Opt, why: &str) -> Error {
    let msg = format!(
        "{} holds {} readings (docs/formats.md § 5.3): {why}",
        q.source.display(),
        kind.as_str()
    );
    Error::option(option, msg)
}

/// The identification of request `q` on the kind file `file` ([`identify_kind`]), with its
/// refusals: options the kind does not take, undetermined data, a worse robot.
pub(super) fn kind_outcome(q: &IdentifyRequest, file: &KindFile) -> Result<KindOutcome> {
    let nominal = &q.robot;
    let kind = file.data.instrument.kind();
    let targets = matches!(file.data.instrument, Instrument::Targets(_));
    if let Some((option, why)) = refusal(q, targets, q.method.method.solver().is_some()) {
        return Err(kind_refusal(q, kind, option, &why));
    }
    let solver = q
        .method
        .method
        .solver()
        .unwrap_or_else(|| unreachable!("refusal() refuses the methods that are not solvers"));
    check_names(Opt::Params, nominal, &q.params)?;
    check_names(Opt::Fix, nominal, &q.fix)?;
    repeated(q, file)?;
    misplaced_sockets(q, file)?;
    let chosen = if q.params.is_empty() {
        Chosen::Identifiable
    } else {
        Chosen::Given(&q.params, q.allow_rank_deficient)
    };
    let register = q.registration == Registration::Identify;
    if matches!(chosen, Chosen::Identifiable) && !q.allow_rank_deficient {
        let mut among = candidates(nominal, targets && !register);
        among.retain(|p| !q.fix.contains(p));
        too_few(q, file, &among, register)?;
    }
    let fit = identify_kind(nominal, file, &q.source, (chosen, &q.fix, register), solver)?;
    if !fit.undetermined_unknowns.is_empty() && !q.allow_rank_deficient {
        return Err(unknowns_free(q, kind, &fit.undetermined_unknowns));
    }
    let r = &fit.identified;
    let readings = fit.data.instrument.observations(file.qs.len());
    // The file row of reading `i` (a step of distances is read at its second row).
    let line = |i: usize| match &fit.data.instrument {
        Instrument::Targets(t) => {
            let (pose, target) = (i / t.len().max(1), i % t.len().max(1) + 1);
            file.lines.get(pose).map_or(format!("reading {i}"), |l| {
                format!("target {target} of the pose that starts on line {l}")
            })
        }
        _ => file
            .line_named(i + file.qs.len() - readings)
            .unwrap_or_else(|| format!("reading {i}")),
    };
    let gross = || {
        let (before, after) = &fit.residuals;
        let (at, (i, ratio)) = gross_reading(after)
            .map(|g| ("after", g))
            .or_else(|| gross_reading(before).map(|g| ("before", g)))?;
        Some(format!(
            "the reading of {} has a residual {ratio:.0} times the median {at} calibration",
            line(i)
        ))
    };
    if super::verdict::undetermined_termination(r.termination) && !q.allow_rank_deficient {
        // The parameters and the instrument's unknowns are determined at its first guess
        // (the others were refused above): the solve went where they are not.
        let total = r.x.len();
        let cause = match r.rank {
            Some(k) if k < total => format!("yet the solve's rank fell to {k}"),
            Some(_) => "yet the solve did not settle".to_string(),
            None => "yet the solve is not finite".to_string(),
        };
        let hint = gross().map_or(String::new(), |g| {
            format!("; {g}: a gross reading is the likely cause")
        });
        let msg = format!(
            "the {} readings determine all {total} unknowns at the instrument's first guess \
             (the robot's {} parameters and the instrument's {}), {cause}{hint}; {} ended {}, \
             so nothing was written. Check the readings (a radius, length or offset in \
             another unit, a plane or sphere column that mixes surfaces, a step file's rows \
             out of their measured order, a gross reading), or pass ",
            kind.as_str(),
            fit.params.len(),
            total - fit.params.len(),
            q.method.shown_name(),
            r.termination.as_str(),
        );
        return Err(Error::file(
            &q.source,
            "data",
            allowing(msg, Opt::AllowRankDeficient),
        ));
    }
    let validation = q
        .validate
        .as_ref()
        .map(|v| validate_positions(nominal, &fit.robot, v))
        .transpose()?;
    let validated = validation.as_ref().map(|(b, a)| (b.rms, a.rms));
    let worse = worse_causes(validated, fit.rms, r.termination, None);
    if !worse.is_empty() && !q.allow_worse {
        // Offsets the readings contradict are a cause the fit cannot undo, and spread the
        // readings' error over the rest like a gross reading.
        let offsets = || {
            contradicted_offsets(&file.data)
                .map(|(found, cause)| format!("{found}; likely cause: {cause}"))
        };
        let likely = radians_hint(nominal, &file.qs)
            .or_else(offsets)
            .or_else(|| gross().map(gross_likely));
        let rows = q.validation_rows();
        return Err(worse_error(&q.source, rows, &q.method, &worse, likely));
    }
    let points = plausibility::target_points(nominal, &file.qs, &file.data);
    let mut findings = plausibility::judge(
        (nominal, &fit.robot, &fit.params, &file.qs),
        points.as_ref().map(|(m, s)| (&m[..], &s[..])),
        (fit.rms.1, file.sigma_mm.as_deref()),
        || gross().into_iter().map(plausibility::gross_cause).collect(),
    );
    if let Some((found, cause)) = contradicted_offsets(&file.data) {
        findings.found.push(found);
        findings.causes.push(cause);
    }
    let implausible = plausibility::verdict(
        findings,
        &q.source,
        (q.allow_implausible, q.method.is_external()),
    )?;
    let residuals = (&fit.residuals.0[..], &fit.residuals.1[..]);
    let gross = super::verdict::gross_kept(residuals, r, |i| format!("the reading of {}", line(i)));
    let mut record =
        IdentifiedRecord::of(&nominal.name, &q.source, q.method.name(), &fit.params, r);
    if let Some((before, after)) = validation {
        record = record.validated(before, after);
    }
    let record = IdentifiedRecord {
        fixed: names(&q.fix),
        allowed_implausible: implausible,
        allowed_worse: worse.iter().map(ToString::to_string).collect(),
        ..kind_keys(record, &fit, (kind, readings), q.registration)
    };
    Ok(KindOutcome {
        nominal: nominal.clone(),
        kind,
        readings,
        identifiable: matches!(chosen, Chosen::Identifiable),
        fit,
        validation,
        record,
        gross,
    })
}
