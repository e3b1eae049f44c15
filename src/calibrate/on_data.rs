//! Identification on a measurement (`calbench identify`, and the Python module's `identify`):
//! the parameters a measurement determines, the calibration with a method's default stream,
//! and the refusal of data that do not determine every parameter, in one place so that both
//! give the same numbers and messages.

use std::path::Path;

use super::{calibrate, Calibrated, Registration};
use crate::error::{Error, Result};
use crate::identify::{MethodSpec, Termination};
use crate::measurement::Measurements;
use crate::numeric::Frame;
use crate::robot::compliance::CompliancePick;
use crate::robot::identifiability::analyse;
use crate::robot::{param_sets, Param, Robot};

/// An identification on a measurement and what it identified.
pub struct OnData {
    /// Every identified parameter, in the order of the estimate: the kinematic ones, then
    /// the compliances.
    pub params: Vec<Param>,
    /// The kinematic parameters (those [`analyse`] can judge).
    pub kinematic: Vec<Param>,
    /// The compensated robot and how it was obtained.
    pub calibrated: Calibrated,
}

impl OnData {
    /// Whether the data left parameters undetermined ([`undetermined`]).
    pub fn undetermined(&self) -> bool {
        undetermined(&self.calibrated)
    }

    /// The refusal of this result when its data leave parameters undetermined
    /// ([`undetermined_error`]).
    pub fn undetermined_error(
        &self,
        nominal: &Robot,
        source: &Path,
        data: &Measurements,
        spec: &MethodSpec,
        allow: &str,
    ) -> Error {
        let params = (&self.kinematic[..], self.params.len());
        undetermined_error(
            nominal,
            params,
            &self.calibrated,
            (source, data),
            spec,
            allow,
        )
    }
}

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
/// identified). `allow` names the option that accepts such a result.
pub fn undetermined_error(
    nominal: &Robot,
    params: (&[Param], usize),
    c: &Calibrated,
    (source, data): (&Path, &Measurements),
    spec: &MethodSpec,
    allow: &str,
) -> Error {
    let a = analyse(nominal, params.0, &data.qs, data.measure());
    let (undetermined, groups) = names_and_groups(&a);
    Error::file(
        source,
        "data",
        format!(
            "the poses determine only {} of the {} parameters (rank {}; undetermined: {}; \
             dependent groups: {}); {} ended {}, so nothing was written. Measure poses \
             that move every joint, or pass {allow}",
            a.rank,
            params.1,
            c.identified.rank.unwrap_or(a.rank),
            undetermined,
            groups,
            spec.name(),
            c.identified.termination.as_str(),
        ),
    )
}

/// The undetermined parameters of an analysis, space-separated, and its dependent groups
/// (`[a b] [c d]`), as refusals name them.
pub fn names_and_groups(a: &crate::robot::identifiability::Identifiability) -> (String, String) {
    let names = |v: &[Param]| {
        v.iter()
            .map(|p| p.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    let groups: Vec<String> = a.groups.iter().map(|g| format!("[{}]", names(g))).collect();
    (names(&a.unidentifiable), groups.join(" "))
}

/// Identifies the errors of `nominal` from the measurement `data` with `spec`: the
/// kinematic parameters the measure determines (the base too with `identify`
/// registration), then the joint compliances of `compliance`; the random stream `identify`
/// of `seed`. For real data `known` registration means the points are in the base frame.
pub fn identify_on_data(
    nominal: &Robot,
    data: &Measurements,
    spec: &MethodSpec,
    registration: Registration,
    compliance: Option<&CompliancePick>,
    compliance_key: &str,
    seed: u64,
) -> Result<OnData> {
    let with_base = registration == Registration::Identify;
    let kinematic = param_sets::identified_params_tool_first(nominal, data.measure(), with_base);
    let mut params = kinematic.clone();
    if let Some(c) = compliance {
        params.extend(c.params(nominal, compliance_key)?);
    }
    let calibrated = calibrate(
        nominal,
        &params,
        data,
        registration,
        &Frame::identity(),
        spec,
        &mut crate::numeric::rng::stream(seed, "identify"),
    )?;
    Ok(OnData {
        params,
        kinematic,
        calibrated,
    })
}
