//! Whether an identification may be written: data that do not determine every parameter
//! (refused unless [`Opt::AllowRankDeficient`]), and a result that makes the robot worse than
//! the nominal one (refused unless [`Opt::AllowWorse`]), each refusal naming the file, the
//! cause, the option that keeps it (typed: each front end spells it) and, where the residuals
//! point to one, the gross reading likely behind it.

use std::path::Path;

use super::{Calibrated, Registration, RoundsEnd};
use crate::error::{Error, Opt, Result, Said};
use crate::identify::{MethodSpec, Termination};
use crate::measurement::Measurements;
use crate::numeric::Real;
use crate::robot::identifiability::{analyse, Identifiability};
use crate::robot::{Param, Robot};

/// Whether a calibration left parameters undetermined (termination `rank-deficient` or
/// `singular`).
pub fn undetermined(c: &Calibrated) -> bool {
    undetermined_termination(c.identified.termination)
}

/// Whether an identification that ended so left parameters undetermined (`rank-deficient`
/// or `singular`).
pub fn undetermined_termination(t: Termination) -> bool {
    matches!(t, Termination::RankDeficient | Termination::Singular)
}

/// The refusal of a result `c` whose data (`data`, read from `source`) do not determine every
/// parameter: the undetermined parameters and the dependent groups of the kinematic model
/// (`params`: the kinematic parameters, which [`analyse`] can judge, and the number of all
/// identified). The refusal names the option that accepts such a result. When the poses do
/// determine every parameter (a solve made singular by the readings themselves), the
/// message says so and names the gross reading the residuals point to, if any (`point`: the
/// point of a row of `data` in words, by its line of the file it was read from), and what
/// the readings show against the nominal robot's points (`shown`: a unit, a column of one
/// value, two columns swapped; [`super::plausibility::data_causes`]).
pub fn undetermined_error(
    nominal: &Robot,
    params: (&[Param], usize),
    c: &Calibrated,
    (source, data): (&Path, &Measurements),
    spec: &MethodSpec,
    (point, shown): (&dyn Fn(usize) -> String, &dyn Fn() -> Vec<String>),
) -> Error {
    let a = analyse(nominal, params.0, &data.qs, data.measure());
    let ended = format!(
        "{} ended {}, so nothing was written",
        spec.shown_name(),
        c.identified.termination.as_str()
    );
    let ended = match radians_hint(nominal, &data.qs) {
        Some(h) => format!("{h}; {ended}"),
        None => ended,
    };
    let gross = || {
        super::validation::point_residuals(nominal, c, data)
            .ok()
            .and_then(|(before, _)| gross_reading(&before))
            .map_or(String::new(), |(i, ratio)| {
                format!(
                    "; {} lies {ratio:.0} times the median distance from the nominal robot's: \
                     a gross reading is the likely cause",
                    point(i)
                )
            })
    };
    if a.rank >= params.0.len() && c.identified.rank.is_none_or(|k| k >= params.1) {
        let gross = gross();
        let msg = format!(
            "the poses determine all {} parameters, yet the solve did not settle{gross}; \
             {ended}. Check the readings, or pass ",
            params.1
        );
        return Error::file(source, "data", allowing(msg, Opt::AllowRankDeficient));
    }
    if a.rank >= params.0.len() {
        // The poses determine every kinematic parameter, yet the solve's rank fell short: no
        // parameter or group of the analysis to name. What can take rank beside the poses is
        // named where the identification has it; the readings themselves are judged against
        // the nominal robot's points (a unit, a column of one value, two columns swapped).
        let mut beside = Vec::new();
        if data.quats.is_some() {
            beside.push("the orientation weight k");
        }
        if data.sigma_mm.is_some() {
            beside.push("the points' σ");
        }
        if params.1 > params.0.len() {
            beside.push("the parameters beside the kinematic ones");
        }
        let causes = shown();
        let what = match (beside.is_empty(), causes.is_empty()) {
            (_, false) => causes.join("; "),
            (false, true) => format!("{} leave the rest undetermined", beside.join(" or ")),
            (true, true) => "the readings themselves leave it short".to_string(),
        };
        let msg = format!(
            "the poses determine all {} kinematic parameters, yet the solve's rank is {} of \
             the {} identified: {what}{}; {ended}. Check the readings, or pass ",
            params.0.len(),
            c.identified.rank.unwrap_or(a.rank),
            params.1,
            gross(),
        );
        return Error::file(source, "data", allowing(msg, Opt::AllowRankDeficient));
    }
    let (undetermined, groups) = names_and_groups(&a);
    let rows = data.len() * data.measure().rows();
    let msg = format!(
        "the poses determine only {} of the {} parameters (rank {}; undetermined: {}; \
         dependent groups: {}); {ended}. ",
        a.rank,
        params.1,
        c.identified.rank.unwrap_or(a.rank),
        undetermined,
        groups,
    );
    let said = if rows < params.1 {
        Said::from(format!(
            "{msg}{} poses give {rows} readings for {} parameters: measure at least {} poses, \
             or pass ",
            data.len(),
            params.1,
            least_poses(params.1, data.measure().rows())
        ))
    } else {
        // Poses that do not tell the undetermined apart from their groups, or a robot whose
        // groups no poses tell apart well (axes nearly parallel, as a calibrated arm's are):
        // held at their values, the rest is determined.
        let fixed = undetermined.replace(' ', ",");
        Said::from(format!(
            "{msg}Measure poses that move every joint, hold them with "
        ))
        .name(Opt::Fix)
        .text(format!(" {fixed}, or pass "))
    };
    Error::file(source, "data", said.on(Opt::AllowRankDeficient))
}

/// Refuses `poses` poses of `per_pose` readings each (read from `source`) that give exactly
/// as many readings as the `params` parameters, without priors (`priors`: whether there are
/// any, which add readings of their own): a fit matches each reading whatever the robot and
/// leaves none to check it, as a kind file's is refused (`on_kind::unfixed::too_few`). Fewer
/// end rank-deficient and are refused after the solve, with what they leave undetermined.
pub fn as_many_readings_as_parameters(
    source: &Path,
    (poses, per_pose): (usize, usize),
    params: usize,
    priors: bool,
) -> Result<()> {
    if poses * per_pose != params || priors {
        return Ok(());
    }
    let msg = format!(
        "{poses} poses give {params} readings for {params} parameters: a fit would match every \
         reading and leave none to check it, so nothing was written. Measure at least {} \
         poses, or pass ",
        least_poses(params, per_pose)
    );
    Err(Error::file(
        source,
        "data",
        allowing(msg, Opt::AllowRankDeficient),
    ))
}

/// The fewest poses of `per_pose` readings each that give more readings than `params`.
fn least_poses(params: usize, per_pose: usize) -> usize {
    params / per_pose + 1
}

/// `msg` followed by how the option `allow` is turned on.
pub fn allowing(msg: String, allow: Opt) -> Said {
    Said::from(msg).on(allow)
}

/// The end of a refusal that a front end's option `allow` would let through: `msg`, then
/// `, or pass` the option `to write it with a warning`. A method supplied from outside
/// (`external`) runs only where no option lets its result through (a task's entry; `identify`
/// takes calbench's methods alone), so no way past is offered: `msg.`
pub fn way_past(msg: String, allow: Opt, external: bool) -> Said {
    if external {
        return Said::from(msg + ".");
    }
    allowing(msg + ", or pass ", allow).text(" to write it with a warning")
}

/// The undetermined parameters of an analysis, space-separated, and its dependent groups
/// (`[a b] [c d]`), as refusals name them.
pub fn names_and_groups(a: &Identifiability) -> (String, String) {
    let names = |v: &[Param]| {
        v.iter()
            .map(|p| p.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    let groups: Vec<String> = a.groups.iter().map(|g| format!("[{}]", names(g))).collect();
    (names(&a.unidentifiable), groups.join(" "))
}

/// A residual this many times the median of all (and the largest) marks its reading as
/// gross.
pub const GROSS_RATIO: Real = 20.0;

/// The reading whose residual (`residuals`, one per reading, magnitudes) stands out: the
/// largest, when it is at least [`GROSS_RATIO`] times the median and the next largest is
/// not (one reading, not a drift); its index and its ratio to the median.
pub fn gross_reading(residuals: &[Real]) -> Option<(usize, Real)> {
    let (top, ratio) = standing_out(residuals.iter().map(|r| r.abs()).collect())?;
    let i = residuals.iter().position(|r| r.abs() == top)?;
    Some((i, ratio))
}

/// The largest of `magnitudes` and its ratio to their median, when it stands out by
/// [`gross_reading`]'s rule; sorts them in place.
fn standing_out(mut magnitudes: Vec<Real>) -> Option<(Real, Real)> {
    if magnitudes.len() < 5 || magnitudes.iter().any(|r| !r.is_finite()) {
        return None;
    }
    magnitudes.sort_by(Real::total_cmp);
    let n = magnitudes.len();
    let (median, top, next) = (magnitudes[n / 2], magnitudes[n - 1], magnitudes[n - 2]);
    let ratio = top / median;
    if median <= 0.0 || ratio < GROSS_RATIO || next >= top / 2.0 {
        return None;
    }
    Some((top, ratio))
}

/// A rise of an RMS error below this (mm, a picometre) is no worsening: the rounding of points
/// metres from the base (about 1e-13 mm for each), which is all that data the nominal robot
/// fits exactly leave before and after a solve, and far below any instrument's noise.
pub const WORSE_FLOOR_MM: Real = 1e-9;

/// One way a result makes the robot worse than the nominal one ([`worse_causes`]); its
/// `Display` is the cause in words.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Worse {
    /// The validation RMS (mm) rose from the first to the second.
    Validation(Real, Real),
    /// The RMS residual (mm) on the readings the robot was identified on rose.
    Residual(Real, Real),
    /// The solve stopped at its iteration limit with a cost that grew: the RMS residual (mm)
    /// at the first evaluation and at the last.
    GrowingCost(Real, Real),
}

impl std::fmt::Display for Worse {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Worse::Validation(before, after) => {
                let (before, after) = apart(before, after);
                write!(
                    f,
                    "the validation RMS is {after} mm after calibration against {before} mm \
                     before"
                )
            }
            Worse::Residual(before, after) => {
                let (before, after) = apart(before, after);
                write!(
                    f,
                    "the RMS residual on the calibration readings is {after} mm after against \
                     {before} mm before"
                )
            }
            Worse::GrowingCost(first, last) => {
                let (first, last) = apart(first, last);
                write!(
                    f,
                    "the solve stopped at its iteration limit with a growing cost (RMS residual \
                     {first} mm at the start, {last} mm at the end)"
                )
            }
        }
    }
}

/// Two RMS figures (mm) written with 4 decimals, or with as many more as tell them apart (up
/// to 12, a thousandth of [`WORSE_FLOOR_MM`]): a rise of half a micrometre reads as one.
fn apart(a: Real, b: Real) -> (String, String) {
    let mut d = 4;
    while d < 12 && format!("{a:.d$}") == format!("{b:.d$}") {
        d += 1;
    }
    (format!("{a:.d$}"), format!("{b:.d$}"))
}

/// Why a result makes the robot worse than the nominal one: a validation RMS after above the
/// one before, a residual RMS after above the one before (the readings the robot was
/// identified on), a solve that stopped at its iteration limit with a cost that grew
/// (`trace`: the RMS residual at the first evaluation and the last); each rise by more than
/// [`WORSE_FLOOR_MM`]. Empty: not worse.
pub fn worse_causes(
    validation: Option<(Real, Real)>,
    residual: (Real, Real),
    termination: Termination,
    trace: Option<(Real, Real)>,
) -> Vec<Worse> {
    let growing = trace.filter(|_| termination == Termination::MaxIterations);
    let causes = [
        validation.map(|(b, a)| Worse::Validation(b, a)),
        Some(Worse::Residual(residual.0, residual.1)),
        growing.map(|(first, last)| Worse::GrowingCost(first, last)),
    ];
    let rises = |w: &Worse| match *w {
        Worse::Validation(b, a) | Worse::Residual(b, a) | Worse::GrowingCost(b, a) => rose(b, a),
    };
    causes.into_iter().flatten().filter(rises).collect()
}

/// Whether an RMS error rose from `before` to `after` by more than [`WORSE_FLOOR_MM`].
fn rose(before: Real, after: Real) -> bool {
    after > before + WORSE_FLOOR_MM
}

/// Where the validation rows of an identification came from, as a refusal names them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ValidationRows<'a> {
    /// None, or rows held out of the data identified on: the data's refusal names them.
    OfData,
    /// A validation file.
    File(&'a Path),
    /// Rows given without a file (Python's `validate` arrays): [`Opt::Validate`] names them.
    Given,
}

/// The refusal of a result that makes the robot worse ([`worse_causes`]), read from
/// `source` by `method`; `likely` its likely cause ([`radians_hint`], [`gross_likely`]); the
/// refusal names the option that keeps it ([`Opt::AllowWorse`]). `rows`: where the
/// validation rows came from. From a file of their own: when their RMS rose, both files'
/// readings are to check, and when that is the one cause (the calibration's figures did not
/// rise) the refusal is at the validation file, naming `source` as the file identified on.
/// Given without a file, that one cause is a refusal of [`Opt::Validate`]. A method
/// supplied from outside is named first among what to check: its result, not the readings,
/// is the likelier cause.
pub fn worse_error(
    source: &Path,
    rows: ValidationRows<'_>,
    method: &MethodSpec,
    causes: &[Worse],
    likely: Option<String>,
) -> Error {
    let likely = likely.map_or(String::new(), |l| format!("; {l}"));
    let of_validation = |w: &Worse| matches!(w, Worse::Validation(..));
    let only_validation = causes.iter().all(of_validation);
    let file = match rows {
        ValidationRows::File(f) => Some(f),
        _ => None,
    };
    let validation = file.filter(|_| causes.iter().any(of_validation));
    let at_validation = validation.filter(|_| only_validation);
    let on = at_validation.map_or(String::new(), |_| format!(" on {}", source.display()));
    let of = validation.map_or(String::new(), |v| {
        format!(" of {} and {}", source.display(), v.display())
    });
    let readings = format!("the readings{of} (a column of one value, a unit, a swapped column)");
    let (by, check) = match method.is_external() {
        true => (
            format!(" by the method `{}`, supplied from outside,", method.label),
            format!("the vector the method returns, then {readings}"),
        ),
        false => (String::new(), readings),
    };
    let causes: Vec<String> = causes.iter().map(Worse::to_string).collect();
    let msg = format!(
        "the identification{on}{by} makes the robot worse: {}{likely}; nothing was written. \
         Check {check}",
        causes.join("; ")
    );
    let said = way_past(msg, Opt::AllowWorse, method.is_external());
    match rows {
        ValidationRows::Given if only_validation => Error::option(Opt::Validate, said),
        _ => Error::file(at_validation.unwrap_or(source), "data", said),
    }
}

/// The warning of a fit that kept a gross reading: the reading that stands out
/// ([`gross_reading`], above [`WORSE_FLOOR_MM`], the rounding of an exact fit) among the
/// residuals (one per reading) after calibration, or else before it (a fit of few readings
/// per unknown spreads one reading's error over the rest), while the fit `id` gave it a
/// weight (0 for one a robust method rejected; a method that reports no weights weighed
/// every reading); `named` names the reading in words (`the point on line 55 of grid.csv`).
pub fn gross_kept(
    (before, after): (&[Real], &[Real]),
    id: &crate::identify::Identified,
    named: impl Fn(usize) -> String,
) -> Option<String> {
    let stands_out = |residuals: &[Real], at: &'static str| {
        gross_reading(residuals)
            .filter(|&(i, _)| residuals[i].abs() > WORSE_FLOOR_MM)
            .map(|(i, ratio)| (i, ratio, residuals[i].abs(), at))
    };
    let (i, ratio, residual, at) =
        stands_out(after, "after").or_else(|| stands_out(before, "before"))?;
    kept_by(id, i).then(|| {
        format!(
            "{} has a residual of {residual:.3} mm {at} calibration, {ratio:.0} times the \
             median, and the fit kept it: {GROSS_PULLS}",
            named(i),
        )
    })
}

/// What a gross reading the fit kept does, and what to do.
const GROSS_PULLS: &str = "one gross reading pulls a least-squares fit towards it. Check that \
     reading and leave it out, or identify with a robust method (igg3), which rejects it";

/// Whether the fit `id` gave reading `i` a weight: 0 for one a robust method rejected; a
/// method that reports no weights weighed every reading.
fn kept_by(id: &crate::identify::Identified, i: usize) -> bool {
    !id.own_weights || id.weights.get(i).copied().unwrap_or(1.0) != 0.0
}

/// The warning of a gross reading the fit kept and spread, where [`gross_kept`] finds none:
/// the most influential reading left out of the fit (`left_out`, to first order:
/// [`crate::calibrate::diagnostics::LeftOut`]) stands out by the same rule
/// ([`gross_reading`]) among the residuals of the fit without it, its own distance from
/// that fit in its place. A fit of few readings per unknown moves towards one far reading
/// until its residual is a few times the others', whose residuals it raises. `named` names
/// the reading. The residuals are sorted in place: a file of millions of points holds them
/// once.
pub fn gross_left_out(
    left_out: crate::calibrate::diagnostics::LeftOut,
    id: &crate::identify::Identified,
    named: impl Fn(usize) -> String,
) -> Option<String> {
    let (i, distance) = (left_out.point, left_out.residuals_mm[left_out.point]);
    let (top, ratio) = standing_out(left_out.residuals_mm)?;
    (top == distance && distance > WORSE_FLOOR_MM && kept_by(id, i)).then(|| {
        format!(
            "{} lies {distance:.3} mm from the fit of the other readings, {ratio:.0} times the \
             median residual of that fit, and the fit kept it: {GROSS_PULLS}",
            named(i),
        )
    })
}

/// `reading` (a reading the residuals point to, in words) as the likely cause of a refusal.
pub fn gross_likely(reading: String) -> String {
    format!("{reading}: a gross reading is the likely cause")
}

/// The likely cause of a refusal when every revolute joint value of the readings `qs`
/// (internal units) lies within its joint's limits scaled by π/180, for a `robot` that takes
/// degrees: joint values in radians read as degrees, so that the poses differ by a few degrees
/// at most (a nearly singular solve, or one that makes the robot worse). In words; `None`
/// otherwise.
pub fn radians_hint(robot: &Robot, qs: &[Vec<Real>]) -> Option<String> {
    let revolute: Vec<(usize, Real)> = (0..robot.dof())
        .filter(|&j| robot.joints[j].kind == crate::robot::JointType::Revolute)
        .map(|j| {
            let (lo, hi) = robot.joints[j].limits;
            (j, lo.abs().max(hi.abs()))
        })
        .filter(|&(_, reach)| reach > 0.0)
        .collect();
    if robot.units.angle != crate::robot::AngleUnit::Deg || revolute.is_empty() || qs.is_empty() {
        return None;
    }
    // The largest share of a joint's limit a value takes: unit-free, so internal units serve.
    let share = qs
        .iter()
        .flat_map(|q| revolute.iter().map(move |&(j, reach)| q[j].abs() / reach))
        .fold(0.0, Real::max);
    let radians = std::f64::consts::PI / 180.0;
    (share <= radians * (1.0 + 1e-9)).then(|| {
        format!(
            "every revolute joint value lies within {:.2} % of its joint's limit (π/180 is \
             1.75 %): the joint values are likely in radians, and robot \"{}\" takes \
             degrees (its file's `angle_unit`)",
            100.0 * share,
            robot.name
        )
    })
}

/// Refuses joint values read from `path` (a program, a pose list) that look like radians for
/// a `robot` in degrees ([`radians_hint`]), naming the file: read as degrees they are poses a
/// few degrees from the zero pose, which a program corrected or an analysis would take as
/// given. A list of fewer than [`crate::measurement::csv::MIN_DISTINCT_POSES`] distinct poses
/// is no evidence (a program of the zero pose) and is taken.
pub fn radians_refused(path: &Path, robot: &Robot, qs: &[Vec<Real>]) -> Result<()> {
    if crate::measurement::csv::distinct_poses(qs, &[], robot.dof()).is_err() {
        return Ok(());
    }
    match radians_hint(robot, qs) {
        Some(why) => Err(Error::file(path, "joint values", why)),
        None => Ok(()),
    }
}

/// The root mean square of `v` (NaN when empty).
pub fn rms(v: &[Real]) -> Real {
    (v.iter().map(|x| x * x).sum::<Real>() / v.len() as Real).sqrt()
}

/// The warning of a result kept although it makes the robot worse (`causes`), if any.
pub fn worse_warning(causes: &[String]) -> Option<Said> {
    (!causes.is_empty()).then(|| {
        let msg = format!(
            "the identification makes the robot worse ({}); kept because of ",
            causes.join("; ")
        );
        Said::from(msg).on(Opt::AllowWorse)
    })
}

/// The warning for an alternation of registration and identification that did not settle;
/// `None` when it settled or did not alternate.
pub fn registration_warning(c: &Calibrated, registration: Registration) -> Option<String> {
    matches!(
        c.rounds.termination,
        RoundsEnd::MaxRounds | RoundsEnd::Stalled
    )
    .then(|| {
        format!(
            "{} registration and identification did not settle within {} mm in {} rounds ({}; \
             the smallest frame step was {:.3e} mm, and that round is the result)",
            registration.as_str(),
            super::ROUND_TOLERANCE_MM,
            c.rounds.rounds,
            c.rounds.termination.as_str(),
            c.rounds.last_step_mm
        )
    })
}

/// Refuses a name of the fixed or the given parameters (`option`: [`Opt::Fix`] or
/// [`Opt::Params`], the latter given) the robot's model does not have, a given compliance
/// (the compliance model adds those) and a name given twice.
pub fn check_names(option: Opt, nominal: &Robot, names: &[Param]) -> Result<()> {
    let known = nominal.params();
    let given = option == Opt::Params;
    let bad = |p: &Param| match (known.contains(p), p.is_compliance()) {
        (_, true) if given => Some(
            Said::from("is a joint compliance: the compliance model adds those (")
                .name(Opt::Compliance)
                .text("), not a list of parameters"),
        ),
        (false, false) => Some(format!("is not a parameter of robot `{}`", nominal.name).into()),
        _ => None,
    };
    for (i, p) in names.iter().enumerate() {
        let why = bad(p).or(names[..i].contains(p).then(|| "is given twice".into()));
        if let Some(why) = why {
            return Err(Error::option(
                option,
                Said::from(format!("`{p}` ")).then(why),
            ));
        }
    }
    Ok(())
}

/// Refuses fixed parameters (`fixed`) that leave nothing of `params` to identify, naming the
/// option that fixed them, where the solver would name the parameters' list.
pub fn check_some_left(params: &[Param], fixed: &[Param]) -> Result<()> {
    if params.is_empty() && !fixed.is_empty() {
        let why = "leaves no parameter to identify: every one to be identified is held";
        return Err(Error::option(Opt::Fix, why));
    }
    Ok(())
}

/// Refuses a prior given to the identification (`--prior`, `priors`) on a parameter it does
/// not identify (`params`), or twice, naming that option, where the method's solve would name
/// its own `priors.NAME` key.
pub fn check_priors_identified(priors: &[(Param, Real)], params: &[Param]) -> Result<()> {
    for (i, (p, sigma)) in priors.iter().enumerate() {
        let why = if !params.contains(p) {
            "is not among the identified parameters (fixed, or not in the model)".to_string()
        } else if let Some((_, first)) = priors[..i].iter().find(|(q, _)| q == p) {
            let [first, then] = [first, sigma].map(|s| crate::error::shown(*s));
            format!("is given twice (σ = {first}, then σ = {then}): one prior per parameter")
        } else {
            continue;
        };
        return Err(Error::option(Opt::Prior, format!("`{p}` {why}")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rise the fourth decimal cannot show is written with the decimals that show it; one it
    /// can show keeps four.
    #[test]
    fn a_worsening_is_written_with_the_decimals_that_show_it() {
        let small = Worse::Validation(0.494438, 0.494438 + 4.8e-7).to_string();
        assert_eq!(
            small,
            "the validation RMS is 0.4944385 mm after calibration against 0.4944380 mm before"
        );
        let large = Worse::Residual(3.038, 1418.41749).to_string();
        assert!(
            large.contains("1418.4175 mm after against 3.0380 mm"),
            "{large}"
        );
    }

    /// A refusal of an implausible result offers the option that writes it, except for a
    /// method supplied from outside, which runs where no option does (a task's entry).
    #[test]
    fn a_method_supplied_from_outside_is_offered_no_way_past() {
        use crate::calibrate::plausibility::implausible_error;
        let found = ["a2 moved 900 mm".to_string()];
        let said = |external| {
            let e = implausible_error(Path::new("d.csv"), &found, &[], external);
            e.spelled(|_, _| "OPTION".to_string())
        };
        assert!(said(false).ends_with("Fix the data, or pass OPTION to write it with a warning"));
        assert!(
            said(true).ends_with("nothing was written. Fix the data."),
            "{}",
            said(true)
        );
    }

    #[test]
    fn a_gross_reading_stands_out_and_a_drift_does_not() {
        let mut r: Vec<Real> = (0..20).map(|i| 0.1 + 0.01 * i as Real).collect();
        assert_eq!(gross_reading(&r), None);
        r[7] = 999.0;
        assert_eq!(gross_reading(&r).map(|g| g.0), Some(7));
        r[8] = 900.0;
        assert_eq!(gross_reading(&r), None, "two large ones: not one reading");
    }

    #[test]
    fn worse_names_each_cause() {
        let w = worse_causes(
            Some((2.9, 1327.7)),
            (0.1, 0.05),
            Termination::Converged,
            None,
        );
        assert_eq!(w.len(), 1);
        assert_eq!(w, [Worse::Validation(2.9, 1327.7)]);
        assert!(w[0].to_string().contains("1327.7000 mm after"), "{w:?}");
        let w = worse_causes(
            None,
            (0.1, 0.2),
            Termination::MaxIterations,
            Some((1.0, 2.0)),
        );
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(
            worse_causes(Some((2.0, 1.0)), (1.0, 1.0), Termination::Converged, None).is_empty()
        );
        // Data the nominal robot fits exactly: rounding before and after is no worsening.
        let rounding = (1.2e-13, 5.8e-13);
        let w = worse_causes(
            Some(rounding),
            rounding,
            Termination::MaxIterations,
            Some(rounding),
        );
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(
            worse_causes(None, (0.0, 2e-9), Termination::Converged, None).len(),
            1
        );
    }
}
