//! Points no calibration can be scored or fitted on as given (docs/formats.md § 2.6 "Points
//! in another unit or frame"): validation rows in another unit than the robot's, or in
//! another frame than the calibration's, and calibration rows under `known` that are not in
//! the base frame. A validation file's points in another unit are its own fault, and refused
//! naming it and its rows; two files in two frames are refused without blame.

use std::path::Path;

use super::plausibility::{self, misfit, Misfit};
use super::verdict::gross_reading;
use super::Registration;
use crate::error::{Error, Opt, Result};
use crate::measurement::Measurements;
use crate::numeric::{Frame, Real, Vec3};
use crate::robot::Robot;

/// Validation rows as a refusal of them names them.
pub(super) struct Validation<'a> {
    /// The rows.
    pub rows: &'a Measurements,
    /// The option that gives them (`--validate`, `--holdout`).
    pub opt: Opt,
    /// The file they were read from, named by a refusal of its points; `None` for rows held
    /// out of the data and for arrays.
    pub file: Option<&'a Path>,
    /// Row `i`'s point in words (`the point on line 5 of val.csv`).
    pub point: &'a dyn Fn(usize) -> String,
}

/// Refuses points that no calibration can be scored or fitted on as given ([`misfit`]): the
/// validation rows `val` against the calibration's first frame, and the calibration rows `d`
/// under [`Registration::Known`], which takes them in the base frame as they are. Validation
/// points in another unit (or with one that stands out) are refused at their file, when they
/// have one.
pub(super) fn check_frames(
    nominal: &Robot,
    d: &Measurements,
    val: Option<Validation<'_>>,
    registration: Registration,
) -> Result<()> {
    if registration != Registration::Known && val.is_none() {
        return Ok(());
    }
    // The nominal robot's points at the calibration poses, once for both checks.
    let model = plausibility::tool_points(nominal, &d.qs);
    if registration == Registration::Known {
        match misfit(&model, &d.points, &Frame::identity(), 0.0) {
            Some(m @ Misfit::Frame { .. }) => {
                let why = format!(
                    "`known` takes the points in the robot's base frame as they are, and {}: \
                     they are in another frame; leave the registration to `identify`, which \
                     registers them",
                    m.words("them", "the base frame")
                );
                return Err(Error::option(Opt::Registration, why));
            }
            // A unit is the identification's plausibility check's to name.
            Some(Misfit::Scale { .. }) | None => {}
        }
    }
    let Some(v) = val else {
        return Ok(());
    };
    let found = validation_misfit(nominal, (d, &model), v.rows, registration, Some(v.point));
    match (found, v.file) {
        (Some((Misfit::Scale { .. }, why)), Some(file)) => Err(Error::file(file, "data", why)),
        (Some((_, why)), _) => Err(Error::option(v.opt, why)),
        (None, _) => Ok(()),
    }
}

/// Why the validation rows `v` cannot score a calibration of `nominal` on the rows `d` (with
/// `model`, the nominal robot's tool points at their poses) under `registration`: the misfit
/// and its words, their points against the nominal robot's in the calibration's first frame
/// ([`misfit`]), beside how far it misses the calibration's own there; `None` when they can,
/// and when the calibration rows fail as a whole themselves or give no frame (theirs to
/// refuse), unless the validation points are in another unit (a spread ratio that names one:
/// a spread off by no unit's ratio, a tool the nominal robot lacks or joint values in
/// radians, is the calibration rows' finding too, which `--allow-implausible` takes). Two
/// files that do not lie in one frame are refused without blame: either may be the one
/// moved, or distorted (a column scaled about the tracker's origin moves the rows as a
/// whole). Given `point` (row `i`'s point in words), a spread's words say which rows:
/// all of them, or the one that stands out ([`spread_outlier`]).
pub(crate) fn validation_misfit(
    nominal: &Robot,
    (d, model): (&Measurements, &[Vec3]),
    v: &Measurements,
    registration: Registration,
    point: Option<&dyn Fn(usize) -> String>,
) -> Option<(Misfit, String)> {
    let own = plausibility::tool_points(nominal, &v.qs);
    let rows = |m: &Misfit| match (point, m) {
        (None, _) | (_, Misfit::Frame { .. }) => String::new(),
        (Some(point), Misfit::Scale { unit, .. }) => {
            match spread_outlier(&own, &v.points).filter(|_| unit.is_none()) {
                Some((i, ratio)) => format!(
                    "; {} stands out: its distance from the points' centroid differs from \
                     the nominal robot's by {ratio:.0} times the median row's difference (a \
                     gross reading, or a row in another unit)",
                    point(i)
                ),
                None => format!(" (all {} rows)", v.len()),
            }
        }
    };
    // Points in another unit than the robot's score no robot, whatever the calibration rows
    // are (a unit is no frame's: the spread is compared).
    let unit = || match misfit(&own, &v.points, &Frame::identity(), 0.0) {
        Some(m @ Misfit::Scale { unit: Some(_), .. }) => Some((
            m,
            format!(
                "{}{}; so do the calibration points, but a validation scores the robot on \
                 points in its units",
                m.words("the validation points", ""),
                rows(&m)
            ),
        )),
        _ => None,
    };
    let Ok(frame) = super::frame_onto(model, d, registration, &Frame::identity()) else {
        return unit();
    };
    if misfit(model, &d.points, &frame, 0.0).is_some() {
        return unit();
    }
    let reference = plausibility::miss_rms(model, &d.points, &frame);
    let m = misfit(&own, &v.points, &frame, reference)?;
    let why = m.words("the validation points", "the calibration's frame");
    Some((
        m,
        match m {
            Misfit::Scale { .. } => format!(
                "{why}{}; validate on points measured as the calibration's were",
                rows(&m)
            ),
            Misfit::Frame { .. } => format!(
                "{why} (and the calibration's by {reference:.1} mm in theirs): the calibration \
                 and validation rows do not lie in one frame; one file was measured from \
                 another placement of the instrument, or has a column scaled or shifted"
            ),
        },
    ))
}

/// The row of the measured points `seen` that stands out of their spread against `model`
/// (the nominal robot's tool points at the same poses): the one whose distance from the
/// points' centroid is off the nominal robot's point's from theirs ([`gross_reading`] of
/// those differences, which no frame changes); its index and ratio to the median row's. The
/// centroids leave out the row furthest off at first: a row metres away moves the centroid
/// of a few rows so far that every row's distance changes, and none stood out.
pub fn spread_outlier(model: &[Vec3], seen: &[Vec3]) -> Option<(usize, Real)> {
    let off = |skip: Option<usize>| -> Vec<Real> {
        let kept = |v: &[Vec3]| {
            let sum = (v.iter().enumerate())
                .filter(|&(i, _)| Some(i) != skip)
                .fold(Vec3::zeros(), |s, (_, p)| s + p);
            sum / (v.len() - usize::from(skip.is_some())).max(1) as Real
        };
        let (cm, cs) = (kept(model), kept(seen));
        (model.iter().zip(seen))
            .map(|(m, s)| (s - cs).norm() - (m - cm).norm())
            .collect()
    };
    let first = off(None);
    let furthest = (0..first.len()).max_by(|&a, &b| first[a].abs().total_cmp(&first[b].abs()))?;
    gross_reading(&off(Some(furthest)))
}
