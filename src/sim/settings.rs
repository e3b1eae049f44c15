//! The scenario sections of the virtual measurement (docs/formats.md: `[errors]`, `[tracker]`,
//! `[outliers]` and the `region` of `[calibration]` / `[validation]`), as serde structs with
//! the documented defaults and a `check` that refuses bad values naming the key. `[tracker]`
//! and `[outliers]` are checked on their fields as the methods' options are
//! ([`crate::numeric::options`]): a value out of range is refused as the scenario is read,
//! at its line, and `check` reads settings built in code the same way.
//!
//! Every struct denies unknown keys, so a typo in a scenario is refused by name.

use std::collections::BTreeMap;

use serde::{Deserialize, Deserializer, Serialize};

use crate::error::{Error, Result};
use crate::measurement::Measure;
use crate::numeric::options::{finite, number, range, recheck_at, share, within};
use crate::numeric::Real;
use crate::robot::{beyond_range, Param};

/// Refuses a non-finite or negative number.
fn non_negative(key: &str, v: Real) -> Result<()> {
    if !v.is_finite() || v < 0.0 {
        return Err(Error::setting(
            key,
            format!("must be ≥ 0, got {}", crate::error::shown(v)),
        ));
    }
    Ok(())
}

/// How the true robot's parameter errors are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ErrorKind {
    /// Guo 2024 §4.2: every length error `+length_mm`, every angle error `+angle_rad`.
    Paper,
    /// Gaussian, σ = `length_mm` for lengths and `angle_rad` for angles.
    Normal,
    /// Uniform in ±`length_mm` / ±`angle_rad`.
    Uniform,
    /// No error: the true robot is the nominal one.
    None,
    /// The errors given by name in `errors.values` (mm or rad), the same in every trial: a
    /// paper's identified errors as the truth (Li 2018 table 2 minus table 1).
    Values,
}

impl ErrorKind {
    /// Whether every trial draws the same errors (`paper`, `none`, `values`): the true robot
    /// is then the same in every trial.
    pub fn is_fixed(self) -> bool {
        matches!(self, ErrorKind::Paper | ErrorKind::None | ErrorKind::Values)
    }

    /// The name used in scenario files.
    pub fn as_str(self) -> &'static str {
        match self {
            ErrorKind::Paper => "paper",
            ErrorKind::Normal => "normal",
            ErrorKind::Uniform => "uniform",
            ErrorKind::None => "none",
            ErrorKind::Values => "values",
        }
    }
}

/// Which parameters carry an injected error: `"identifiable"`, `"all"` or a list of names.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum ParamSelection {
    /// The joint and tool parameters identifiable from the measured quantity (see
    /// [`crate::sim::truth::identifiable_params`]).
    #[default]
    Identifiable,
    /// Every joint and tool parameter of the robot's model (base excluded).
    All,
    /// The named parameters (`theta1`, `d2`, `tool.x`, …).
    List(Vec<String>),
}

impl<'de> Deserialize<'de> for ParamSelection {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            One(String),
            Many(Vec<String>),
        }
        match Raw::deserialize(d).map_err(|_| {
            serde::de::Error::custom(
                "expected \"identifiable\", \"all\" or a list of parameter names",
            )
        })? {
            Raw::One(s) if s == "identifiable" => Ok(ParamSelection::Identifiable),
            Raw::One(s) if s == "all" => Ok(ParamSelection::All),
            Raw::One(s) => Err(serde::de::Error::custom(format!(
                "expected \"identifiable\", \"all\" or a list of parameter names, got \"{s}\""
            ))),
            Raw::Many(v) => Ok(ParamSelection::List(v)),
        }
    }
}

/// The key that names the parameter `name` listed by `key`: a list's own key
/// (`errors.params`), or the name's key in a table whose keys are the names
/// (`errors.values.a9`).
pub fn name_key(key: &str, name: &str) -> String {
    match key {
        "errors.values" if name.contains('.') => format!("{key}.\"{name}\""),
        "errors.values" => format!("{key}.{name}"),
        key => key.to_string(),
    }
}

/// The parameters of an `errors.params` list, in list order: `param` reads one name (or
/// gives the error for a name it does not know); a name listed twice is refused.
pub(crate) fn listed_params(
    names: &[String],
    param: impl Fn(&str) -> Result<Param>,
) -> Result<Vec<Param>> {
    let mut out: Vec<Param> = Vec::with_capacity(names.len());
    for n in names {
        let p = param(n)?;
        if out.contains(&p) {
            return Err(Error::setting(
                "errors.params",
                format!("\"{n}\" is listed twice"),
            ));
        }
        out.push(p);
    }
    Ok(out)
}

/// `[errors]`: the true robot = nominal + these errors (Guo 2024 §4.2).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ErrorSettings {
    /// How errors are drawn; default `"paper"`.
    pub kind: ErrorKind,
    /// Length error (mm): the value for `paper`, σ for `normal`, half-width for `uniform`;
    /// default 0.5.
    pub length_mm: Real,
    /// Angle error (rad), same meaning; default 0.05.
    pub angle_rad: Real,
    /// Which parameters get an error; default `"identifiable"`. Not used with
    /// `kind = "values"`, whose parameters are the keys of `values`.
    pub params: ParamSelection,
    /// With `kind = "values"`: the error of each named parameter (mm for lengths, rad for
    /// angles); refused with any other kind.
    pub values: BTreeMap<String, Real>,
}

impl Default for ErrorSettings {
    fn default() -> Self {
        ErrorSettings {
            kind: ErrorKind::Paper,
            length_mm: 0.5,
            angle_rad: 0.05,
            params: ParamSelection::Identifiable,
            values: BTreeMap::new(),
        }
    }
}

impl ErrorSettings {
    /// Refuses negative or non-finite sizes, an empty list, names that are not parameter
    /// names and duplicates (keys `errors.length_mm`, `errors.angle_rad`, `errors.params`).
    /// Whether a name exists in a given robot is checked by
    /// [`crate::sim::truth::true_errors`].
    pub fn check(&self) -> Result<()> {
        for (key, v, length) in [
            ("errors.length_mm", self.length_mm, true),
            ("errors.angle_rad", self.angle_rad, false),
        ] {
            non_negative(key, v)?;
            if let Some(msg) = beyond_range(v, length) {
                return Err(Error::setting(key, msg));
            }
        }
        if self.kind == ErrorKind::Values {
            if self.values.is_empty() {
                return Err(Error::setting(
                    "errors.values",
                    "kind = \"values\" needs the errors by parameter name, e.g. \
                     values = { a3 = -0.83, alpha5 = 0.0029 } (mm, rad)",
                ));
            }
            if self.params != ParamSelection::Identifiable {
                return Err(Error::setting(
                    "errors.params",
                    "is not used with kind = \"values\": the parameters are the keys of \
                     errors.values",
                ));
            }
            if let Some((n, v)) = self.values.iter().find(|(_, v)| !v.is_finite()) {
                return Err(Error::setting(
                    name_key("errors.values", n),
                    format!("must be a finite number, got {}", crate::error::shown(*v)),
                ));
            }
            for (n, v) in &self.values {
                let Some(p) = Param::parse(n).filter(|p| p.is_geometric()) else {
                    continue;
                };
                if let Some(msg) = beyond_range(*v, p.is_length()) {
                    return Err(Error::setting(name_key("errors.values", n), msg));
                }
            }
        } else if !self.values.is_empty() {
            return Err(Error::setting(
                "errors.values",
                format!(
                    "is read only with kind = \"values\" (kind is \"{}\")",
                    self.kind.as_str()
                ),
            ));
        }
        let selection = self.selection();
        if let ParamSelection::List(names) = &selection {
            if names.is_empty() {
                return Err(Error::setting(
                    "errors.params",
                    "the list is empty; give parameter names or \"identifiable\"",
                ));
            }
            listed_params(names, |n| {
                Param::parse(n).ok_or_else(|| {
                    Error::setting(
                        name_key(self.key(), n),
                        format!(
                            "unknown parameter \"{n}\" (names are theta1, d1, a1, alpha1, beta1, …, \
                             base.x … base.rz, tool.x … tool.rz)"
                        ),
                    )
                })
            })?;
        }
        Ok(())
    }

    /// The key that names the parameters: `errors.values` or `errors.params`.
    pub fn key(&self) -> &'static str {
        if self.kind == ErrorKind::Values {
            "errors.values"
        } else {
            "errors.params"
        }
    }

    /// The parameters that get an error: `params`, or the keys of `values` (in name order)
    /// with `kind = "values"`.
    pub fn selection(&self) -> ParamSelection {
        if self.kind == ErrorKind::Values {
            ParamSelection::List(self.values.keys().cloned().collect())
        } else {
            self.params.clone()
        }
    }
}

/// What the tracker measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[derive(strum::IntoStaticStr, strum::EnumString, strum::VariantNames, strum::EnumIter)]
#[strum(serialize_all = "lowercase")]
pub enum MeasureSetting {
    /// The target point only.
    Position,
    /// The target point and the orientation of the tool frame (6-DOF probe).
    Pose,
}

impl MeasureSetting {
    /// The matching Jacobian row layout.
    pub fn measure(self) -> Measure {
        match self {
            MeasureSetting::Position => Measure::Position,
            MeasureSetting::Pose => Measure::Pose,
        }
    }
}

/// `[tracker]`: the simulated laser tracker (Li 2018 §3 and Qiao 2021 §4: Leica
/// AT901/AT960, MPE = 15 µm + 6 µm/m).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrackerSettings {
    /// The tracker frame in the robot base frame: x, y, z in mm, rx, ry, rz in degrees
    /// (fixed X-Y-Z, as in robot files); default `[2500, 0, 500, 0, 0, 180]`.
    #[serde(deserialize_with = "tracker_pose")]
    pub pose: [Real; 6],
    /// Constant part of the MPE, µm; default 15.
    #[serde(deserialize_with = "mpe_um")]
    pub mpe_a_um: Real,
    /// Range-proportional part of the MPE, µm per m; default 6.
    #[serde(deserialize_with = "mpe_um")]
    pub mpe_b_um_per_m: Real,
    /// Coverage factor: σ = MPE / coverage, at least 1 (below, σ would exceed the maximum
    /// permissible error); default 2.
    #[serde(deserialize_with = "coverage")]
    pub coverage: Real,
    /// Position or full pose; default position.
    pub measure: MeasureSetting,
    /// Orientation noise per axis (σ, degrees) for `pose`; default 0.
    #[serde(deserialize_with = "angle_sigma_deg")]
    pub angle_noise_deg: Real,
}

impl Default for TrackerSettings {
    fn default() -> Self {
        TrackerSettings {
            pose: [2500.0, 0.0, 500.0, 0.0, 0.0, 180.0],
            mpe_a_um: 15.0,
            mpe_b_um_per_m: 6.0,
            coverage: 2.0,
            measure: MeasureSetting::Position,
            angle_noise_deg: 0.0,
        }
    }
}

/// The first of the lengths `v` beyond a robot file's range ([`beyond_range`]), refused as
/// `what` (a deserializer's error).
fn beyond<E: serde::de::Error>(what: &str, v: &[Real]) -> std::result::Result<(), E> {
    match v.iter().find_map(|x| beyond_range(*x, true)) {
        Some(msg) => Err(E::custom(format!("{what} {msg}"))),
        None => Ok(()),
    }
}

/// The largest MPE term a scenario takes: 1 m (in µm, or µm per m of range), five orders
/// above a laser tracker's. Up to a robot file's largest length (10⁹ µm), the tracker's noise
/// carried measured points beyond the range a measurement file holds, and `simulate` blamed
/// the robot's lengths.
pub const MAX_MPE_UM: Real = 1e6;

/// `[tracker] mpe_a_um`, `mpe_b_um_per_m`: from 0 to [`MAX_MPE_UM`].
fn mpe_um<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Real, D::Error> {
    within(d, MAX_MPE_UM, "µm (1 m, far beyond any tracker's error)")
}

/// `[tracker] coverage`: a finite factor of at least 1. The MPE is a maximum: a factor below 1
/// would make σ exceed it (and 1e-300 a tracker of σ = 1e298 mm).
fn coverage<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Real, D::Error> {
    number(
        d,
        |v| v >= 1.0,
        "at least 1 (σ = MPE / coverage; below 1, σ would exceed the maximum permissible error)",
    )
}

/// `[tracker] angle_noise_deg`: a σ from 0 to one turn.
fn angle_sigma_deg<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Real, D::Error> {
    within(d, crate::robot::MAX_ANGLE_RAD.to_degrees(), "° (one turn)")
}

/// `[tracker] pose`: six finite numbers, x, y, z within a robot file's range and rx, ry, rz
/// within one turn ([`beyond_turn`]).
fn tracker_pose<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<[Real; 6], D::Error> {
    let pose: [Real; 6] = finite(d)?;
    beyond("x, y, z", &pose[..3])?;
    match beyond_turn(&pose[3..]) {
        Some(msg) => Err(serde::de::Error::custom(format!("rx, ry, rz {msg}"))),
        None => Ok(pose),
    }
}

/// The first of the angles `deg` (degrees) beyond one turn, as a robot file's angles are
/// bounded, in words: a tracker's rotation of 1e300° is no placement, and its sine is noise.
pub(crate) fn beyond_turn(deg: &[Real]) -> Option<String> {
    let most = crate::robot::MAX_ANGLE_RAD.to_degrees();
    let v = deg.iter().find(|v| v.abs() > most)?;
    Some(format!(
        "must be within ±{most}° (one turn), got {}",
        crate::error::shown(*v)
    ))
}

/// `[outliers] magnitude_mm`: a range ([`range`]) within a robot file's range.
fn magnitudes<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<[Real; 2], D::Error> {
    let r = range(d)?;
    beyond("the magnitudes", &r).map(|()| r)
}

impl TrackerSettings {
    /// Settings built in code checked as a scenario's are read, on their fields: refuses a
    /// non-finite pose, negative MPE terms or angle noise, and a coverage below 1. Refuses
    /// also an orientation noise with `measure = "position"`, which measures no orientation:
    /// it would be believed applied and never be.
    pub fn check(&self) -> Result<()> {
        recheck_at("tracker", self)?;
        if self.measure == MeasureSetting::Position && self.angle_noise_deg != 0.0 {
            return Err(Error::setting(
                "tracker.angle_noise_deg",
                "is read only with measure = \"pose\" (measure is \"position\", which \
                 measures no orientation)",
            ));
        }
        Ok(())
    }
}

/// `[outliers]`: gross errors added to some measured points (Ban §3: 2..16 of 50
/// points, magnitudes 0–0.2 … 0–1.0 mm).
#[serde_with::skip_serializing_none]
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutlierSettings {
    /// Number of displaced points (exclusive with `fraction`); default none (0 outliers).
    pub count: Option<usize>,
    /// Fraction of displaced points in [0, 1], rounded to the nearest count.
    #[serde(deserialize_with = "share")]
    pub fraction: Option<Real>,
    /// Range of the displacement magnitude, mm; default `[0.5, 1.0]`.
    #[serde(deserialize_with = "magnitudes")]
    pub magnitude_mm: [Real; 2],
}

impl Default for OutlierSettings {
    fn default() -> Self {
        OutlierSettings {
            count: None,
            fraction: None,
            magnitude_mm: [0.5, 1.0],
        }
    }
}

impl OutlierSettings {
    /// Refuses `count` together with `fraction`; and, on the fields (as a scenario's are
    /// read), a fraction outside [0, 1] and a magnitude range that is not `0 ≤ lo ≤ hi`
    /// (finite).
    pub fn check(&self) -> Result<()> {
        if self.count.is_some() && self.fraction.is_some() {
            return Err(Error::setting(
                "outliers.fraction",
                "give either outliers.count or outliers.fraction, not both",
            ));
        }
        recheck_at("outliers", self)
    }

    /// The number of outliers among `n` measured points; a count larger than `n` is refused
    /// (key `outliers.count`).
    pub fn count_for(&self, n: usize) -> Result<usize> {
        self.check()?;
        match (self.count, self.fraction) {
            (Some(c), _) if c > n => Err(Error::setting(
                "outliers.count",
                format!("{c} outliers asked for but only {n} poses are measured"),
            )),
            (Some(c), _) => Ok(c),
            (None, Some(f)) => Ok(((f * n as Real).round() as usize).min(n)),
            (None, None) => Ok(0),
        }
    }
}

/// Where measurement poses are drawn (`region` of `[calibration]` and `[validation]`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Region {
    /// Uniformly within the joint limits (the default). A variant with no fields rather than
    /// a unit one, which serde would let take any key unread.
    Joint {},
    /// Joint configurations whose tool point lies in an axis-aligned box of the base frame
    /// (Qiao 2021 §4: a 1000 mm cube centred at (550, 0, 550) mm; Ban: an 800 mm cube).
    Box {
        /// Centre of the box, mm.
        center_mm: [Real; 3],
        /// Edge lengths of the box, mm.
        size_mm: [Real; 3],
    },
    /// Tool points in a box with the tool axis in a cone, joints by inverse kinematics
    /// ([`WorkspaceRegion`]).
    Workspace(WorkspaceRegion),
    /// A regular grid of `per_joint` values per joint (cell centres of the joint ranges);
    /// the poses are drawn without repetition from the grid.
    Grid {
        /// Values per joint (≥ 1).
        per_joint: usize,
    },
}

impl Default for Region {
    fn default() -> Self {
        Region::Joint {}
    }
}

impl Region {
    /// Refuses a non-finite centre, box sizes ≤ 0 and a grid of 0 values per joint; `key`
    /// names the setting (`calibration.region` or `validation.region`).
    pub fn check(&self, key: &str) -> Result<()> {
        match self {
            Region::Joint {} => Ok(()),
            Region::Box { center_mm, size_mm } => check_box(key, center_mm, size_mm),
            Region::Workspace(w) => w.check(key),
            Region::Grid { per_joint } => {
                if *per_joint == 0 {
                    return Err(Error::setting(key, "per_joint must be ≥ 1, got 0"));
                }
                Ok(())
            }
        }
    }
}

/// `kind = "workspace"`: tool points drawn uniformly in an axis-aligned box of the base frame,
/// each with its tool z axis drawn uniformly within `cone_deg` of `axis`; the joints solved by
/// inverse kinematics on the nominal robot, a target it cannot reach within its joint limits
/// drawn again (a tracker-visible region: Li 2018 §3).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorkspaceRegion {
    /// Centre of the box, mm.
    pub center_mm: [Real; 3],
    /// Edge lengths of the box, mm.
    pub size_mm: [Real; 3],
    /// Axis of the orientation cone, base frame (normalised; not zero).
    pub axis: [Real; 3],
    /// Half-angle of the cone, degrees, in [0, 180].
    pub cone_deg: Real,
    /// Start of the inverse kinematics, one value per joint in the robot's units (deg, mm);
    /// `None`: zero clamped into each joint's range.
    pub start: Option<Vec<Real>>,
}

impl WorkspaceRegion {
    /// Refuses a bad box, a zero or non-finite axis, a cone outside [0, 180]° and a
    /// non-finite start, naming `key`.
    pub fn check(&self, key: &str) -> Result<()> {
        check_box(key, &self.center_mm, &self.size_mm)?;
        let norm = self.axis.iter().map(|v| v * v).sum::<Real>().sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(Error::setting(
                key,
                format!("axis must be finite and not zero, got {:?}", self.axis),
            ));
        }
        if !(0.0..=180.0).contains(&self.cone_deg) {
            return Err(Error::setting(
                key,
                format!("cone_deg must be in [0, 180], got {}", self.cone_deg),
            ));
        }
        if let Some(s) = &self.start {
            if s.iter().any(|v| !v.is_finite()) {
                return Err(Error::setting(
                    key,
                    format!("start must be finite, got {s:?}"),
                ));
            }
        }
        Ok(())
    }
}

/// Refuses a non-finite box centre and edges ≤ 0, naming `key`.
/// The bound of a box's centre coordinates and edges, mm (1 km, the bound of a robot file's
/// lengths): beyond it the draws and the inverse kinematics leave the range where their
/// arithmetic is meaningful.
const BOX_BOUND_MM: Real = 1e6;

fn check_box(key: &str, center_mm: &[Real; 3], size_mm: &[Real; 3]) -> Result<()> {
    if center_mm
        .iter()
        .any(|v| !v.is_finite() || v.abs() > BOX_BOUND_MM)
    {
        return Err(Error::setting(
            key,
            format!("center_mm must be finite and within ±1e6 mm, got {center_mm:?}"),
        ));
    }
    if size_mm
        .iter()
        .any(|v| !v.is_finite() || *v <= 0.0 || *v > 2.0 * BOX_BOUND_MM)
    {
        return Err(Error::setting(
            key,
            format!("size_mm must be > 0 and at most 2e6 mm, got {size_mm:?}"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
