//! `calbench.identify`: the library's identification pipeline
//! ([`calbench::calibrate::request`]) on arrays or on a measurement file (a tracker's or a
//! measurement-kind file), with the command line's options as keyword arguments; returns
//! the record `identified.json` holds, with the compensated robot and the arrays.

use std::path::{Path, PathBuf};

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use calbench::calibrate::cv::{Holdout, Model};
use calbench::calibrate::pipeline::IdentifyOutcome;
use calbench::calibrate::record::unconverged_warning;
use calbench::calibrate::request::{IdentifyData, IdentifyRequest};
use calbench::calibrate::validation::residual_vectors;
use calbench::calibrate::Registration;
use calbench::identify::MethodSpec;
use calbench::measurement::csv::{read_measurements_at_lines, ArrayKeys};
use calbench::measurement::kind_csv::{file_kind, read_kind_file};
use calbench::measurement::Measurements;
use calbench::numeric::Real;
use calbench::robot::compliance::CompliancePick;
use calbench::robot::{Param, Robot};

use crate::convert::{matrix, measurements, toml_table, Validation};

/// The warning of a chosen model with a kernel residual, which the returned robot lacks (as
/// `calbench identify` and `calbench task` warn that their files lack it).
pub(crate) const KERNEL_NOT_IN_ROBOT: &str = "the chosen model's kernel residual `gp` is not in \
    `robot`: its forward kinematics are the parametric model's, without the residual's \
    correction, while the record's validation figures are the model's with it";
use crate::errors::{err, nonempty, setting, ComputeError};
use crate::robot::PyRobot;

/// The measurements of a file (`data`) or of arrays; `q` and `points` are refused beside a
/// file.
struct Readings<'a, 'py> {
    q: Option<&'a PyReadonlyArray2<'py, f64>>,
    points: Option<&'a PyReadonlyArray2<'py, f64>>,
    rotations: Option<&'a Bound<'py, PyAny>>,
    sigma: Option<&'a PyReadonlyArray1<'py, f64>>,
    payload: Option<&'a PyReadonlyArray1<'py, f64>>,
    data: Option<PathBuf>,
}

/// The source the library names for readings given as arrays: its refusals of the readings
/// as a whole (`data` of this source) are the setting `points` ([`arrays_refusal`]).
const ARRAYS: &str = "<arrays>";

/// A refusal of readings given as arrays, which the library places at `data` of the source
/// [`ARRAYS`] (the points collinear, the poses rank deficient), as the setting `points`: a
/// caller who gave `q` and `points` gave no `data`.
fn arrays_refusal(e: calbench::Error) -> calbench::Error {
    match e.as_setting(Path::new(ARRAYS)) {
        calbench::Error::Setting { key, msg } if key == "data" => calbench::Error::Setting {
            key: "points".into(),
            msg,
        },
        e => e,
    }
}

impl Readings<'_, '_> {
    /// The readings, their source (the file, or `<arrays>`) and the line of a tracker's file
    /// of each of its rows.
    fn read(&self, robot: &Robot) -> PyResult<(IdentifyData, PathBuf, Option<Vec<u64>>)> {
        let arrays = [
            ("q", self.q.is_some()),
            ("points", self.points.is_some()),
            ("rotations", self.rotations.is_some()),
            ("sigma", self.sigma.is_some()),
            ("payload", self.payload.is_some()),
        ];
        if let Some(path) = &self.data {
            let path = &nonempty("data", path.clone())?;
            if let Some((name, _)) = arrays.iter().find(|a| a.1) {
                let why = format!("is not taken with `data` (the file {})", path.display());
                return Err(setting(name, why));
            }
            if file_kind(path).is_some() {
                let data = IdentifyData::Kind(read_kind_file(path, robot).map_err(err)?);
                return Ok((data, path.clone(), None));
            }
            let (m, lines) = read_measurements_at_lines(path, robot).map_err(err)?;
            return Ok((IdentifyData::Tracker(m), path.clone(), Some(lines)));
        }
        let (Some(q), Some(points)) = (self.q, self.points) else {
            return Err(setting(
                "data",
                "give q and points, or data (a measurement file)",
            ));
        };
        let m = measurements(
            robot,
            ArrayKeys::Own,
            q,
            points,
            self.rotations,
            self.sigma,
            self.payload,
        )?;
        Ok((IdentifyData::Tracker(m), PathBuf::from(ARRAYS), None))
    }
}

/// The method `method` with the `options` dict (the keys of a scenario's `[[methods]]`
/// entry), refused naming `options.KEY`; `k` refused where the data give it no orientation
/// to weigh (`k_refused`: why, [`IdentifyData::k_refusal`]).
pub(crate) fn method_spec(
    method: &str,
    options: Option<&Bound<'_, PyDict>>,
    k_refused: Option<&str>,
) -> PyResult<MethodSpec> {
    let entry = match options {
        Some(o) => toml_table("options", o)?,
        None => toml::Table::new(),
    };
    if let Some(why) = k_refused.filter(|_| entry.contains_key("k")) {
        return Err(setting("options.k", why));
    }
    let named = entry.contains_key("name");
    MethodSpec::with_options(method, entry).map_err(|(k, msg)| {
        let key = match k.as_str() {
            "name" if named => "options.name".to_string(),
            "name" => "method".to_string(),
            "" => "options".to_string(),
            k => format!("options.{k}"),
        };
        setting(&key, msg)
    })
}

/// Parameter names (`key`: the argument), each refused naming it.
fn param_list(key: &str, names: Option<Vec<String>>) -> PyResult<Vec<Param>> {
    names
        .unwrap_or_default()
        .iter()
        .map(|n| {
            Param::parse(n.trim()).ok_or_else(|| {
                setting(
                    key,
                    format!("`{n}` is not a parameter name (a2, theta3, base.x, …)"),
                )
            })
        })
        .collect()
}

/// `prior`: a dict name → σ, or the path of a file of priors (as `--prior FILE`).
fn priors(prior: Option<&Bound<'_, PyAny>>, robot: &Robot) -> PyResult<Vec<(Param, Real)>> {
    let Some(prior) = prior else {
        return Ok(Vec::new());
    };
    let Ok(d) = prior.cast::<PyDict>() else {
        let path: std::path::PathBuf = prior.extract().map_err(|_| {
            setting(
                "prior",
                "expected a dict parameter name → σ, or the path of a file of priors",
            )
        })?;
        return calbench::identify::registry::prior_file(&path, robot).map_err(err);
    };
    d.iter()
        .map(|(k, v)| {
            let name: String = k
                .extract()
                .map_err(|_| setting("prior", "every key must be a parameter name"))?;
            // A bool or a complex is not a standard deviation.
            let sigma: Option<Real> = crate::convert::real_number(&v)?;
            calbench::identify::registry::parse_prior(&name, sigma)
                .map_err(|m| setting(&format!("prior.{name}"), m))
        })
        .collect()
}

/// `validate`: a tracker's file, or arrays (q, points, rotations or None, payload or None);
/// with the line of a file of each of its rows.
fn validation(
    robot: &Robot,
    v: Option<&Bound<'_, PyAny>>,
) -> PyResult<(Option<Measurements>, Option<Vec<u64>>)> {
    let Some(v) = v else {
        return Ok((None, None));
    };
    if v.is_instance_of::<PyString>() {
        let path = nonempty("validate", v.extract()?)?;
        let (m, lines) = read_measurements_at_lines(&path, robot).map_err(err)?;
        return Ok((Some(m), Some(lines)));
    }
    let (vq, vp, vr, vl): Validation<'_> = v.extract().map_err(|_| {
        setting(
            "validate",
            "expected a measurement file or (q, points[, rotations[, payload]])",
        )
    })?;
    let keys = ArrayKeys::All("validate");
    let m = measurements(robot, keys, &vq, &vp, vr.as_ref(), None, vl.as_ref())?;
    Ok((Some(m), None))
}

/// Identification (the Python half documents the arguments): the dict of `record` (the
/// text of `identified.json`), `robot` (compensated), `seconds`, and for a tracker's data
/// `covariance`, `weights`, `residuals` and `registration_matrix`.
#[pyfunction]
#[pyo3(signature = (robot, q = None, points = None, rotations = None, sigma = None,
    payload = None, data = None, method = "ls", options = None, registration = "identify",
    compliance = None, validate = None, holdout = None, cv = None, cv_seed = None, models = None,
    params = None, fix = None, prior = None, seed = 0, allow_rank_deficient = false,
    allow_worse = false, allow_implausible = false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn identify<'py>(
    py: Python<'py>,
    robot: &PyRobot,
    q: Option<PyReadonlyArray2<'py, f64>>,
    points: Option<PyReadonlyArray2<'py, f64>>,
    rotations: Option<Bound<'py, PyAny>>,
    sigma: Option<PyReadonlyArray1<'py, f64>>,
    payload: Option<PyReadonlyArray1<'py, f64>>,
    data: Option<PathBuf>,
    method: &str,
    options: Option<Bound<'py, PyDict>>,
    registration: &str,
    compliance: Option<&str>,
    validate: Option<Bound<'py, PyAny>>,
    holdout: Option<&str>,
    cv: Option<usize>,
    cv_seed: Option<u64>,
    models: Option<Vec<String>>,
    params: Option<Vec<String>>,
    fix: Option<Vec<String>>,
    prior: Option<Bound<'py, PyAny>>,
    seed: u64,
    allow_rank_deficient: bool,
    allow_worse: bool,
    allow_implausible: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let nominal = &robot.inner;
    let readings = Readings {
        q: q.as_ref(),
        points: points.as_ref(),
        rotations: rotations.as_ref(),
        sigma: sigma.as_ref(),
        payload: payload.as_ref(),
        data,
    };
    // An empty list is refused as `--params ""` is: left out, the identifiable set is
    // identified.
    if params.as_ref().is_some_and(Vec::is_empty) {
        let why = "names no parameter: leave it out to identify the identifiable set";
        return Err(setting("params", why));
    }
    let (data, source, data_lines) = readings.read(nominal)?;
    let from_arrays = source == Path::new(ARRAYS);
    let spec = method_spec(method, options.as_ref(), data.k_refusal())?;
    let registration: Registration = registration.parse().map_err(|_| {
        setting(
            "registration",
            format!("\"{registration}\" is not one of identify, svd, wsvd, known"),
        )
    })?;
    let holdout = holdout
        .map(|h| h.parse::<Holdout>().map_err(|m| setting("holdout", m)))
        .transpose()?;
    let models = models
        .unwrap_or_default()
        .iter()
        .map(|m| m.parse::<Model>().map_err(|e| setting("models", e)))
        .collect::<PyResult<Vec<_>>>()?;
    // The priors are refused before the validation is read.
    let priors = priors(prior.as_ref(), nominal)?;
    let (validated, validate_lines) = validation(nominal, validate.as_ref())?;
    let request = IdentifyRequest {
        registration,
        priors,
        validate: validated,
        validate_lines,
        validate_source: validate
            .as_ref()
            .filter(|v| v.is_instance_of::<PyString>())
            .map(|v| v.extract::<PathBuf>())
            .transpose()?,
        holdout,
        cv,
        cv_seed,
        models,
        params: param_list("params", params)?,
        fix: param_list("fix", fix)?,
        compliance: compliance.map(CompliancePick::from_arg),
        seed,
        allow_rank_deficient,
        allow_worse,
        allow_implausible,
        data_lines,
        ..IdentifyRequest::new(nominal.clone(), data, source, spec)
    };
    // The Rust side, timed as a whole: the identification and everything its record holds.
    let (outcome, record, seconds) = py
        .detach(|| {
            let t0 = std::time::Instant::now();
            let outcome = request.run()?;
            let record = serde_json::to_string(&outcome)
                .map_err(|e| calbench::Error::Compute(e.to_string()))?;
            Ok((outcome, record, t0.elapsed().as_secs_f64()))
        })
        .map_err(|e| err(if from_arrays { arrays_refusal(e) } else { e }))?;
    let out = PyDict::new(py);
    out.set_item("record", record)?;
    out.set_item("seconds", seconds)?;
    let r = outcome.record();
    out.set_item("warning", unconverged_warning(r))?;
    // The warnings `calbench identify` prints (a registration that did not settle, a result
    // kept although it makes the robot worse or cannot be physically right), the options
    // spelled as keywords; and that `robot` lacks a chosen kernel residual, as the command
    // says its files do.
    let mut kept: Vec<String> = outcome
        .warnings()
        .into_iter()
        .map(|w| w.spell(crate::errors::spell))
        .collect();
    if matches!(&outcome, IdentifyOutcome::Tracker(o) if o.kernel.is_some()) {
        kept.push(KERNEL_NOT_IN_ROBOT.into());
    }
    out.set_item("kept", kept)?;
    match &outcome {
        IdentifyOutcome::Kind(o) => out.set_item(
            "robot",
            PyRobot {
                inner: o.compensated(),
            },
        )?,
        IdentifyOutcome::Tracker(o) => {
            out.set_item(
                "robot",
                PyRobot {
                    inner: o.compensated(),
                },
            )?;
            let c = &o.calibrated;
            let id = &c.identified;
            out.set_item("covariance", matrix(py, &id.covariance()))?;
            out.set_item("weights", PyArray1::from_slice(py, &id.weights))?;
            let residuals = residual_vectors(c, &o.data).map_err(err)?;
            let flat: Vec<f64> = residuals.iter().flat_map(|v| [v[0], v[1], v[2]]).collect();
            let r = Array2::from_shape_vec((residuals.len(), 3), flat)
                .map_err(|e| ComputeError::new_err(e.to_string()))?;
            out.set_item("residuals", r.into_pyarray(py))?;
            let f = &c.frame;
            let mut frame = Array2::<f64>::eye(4);
            for a in 0..3 {
                for b in 0..3 {
                    frame[[a, b]] = f.rot[(a, b)];
                }
                frame[[a, 3]] = f.pos[a];
            }
            out.set_item("registration_matrix", frame.into_pyarray(py))?;
        }
    }
    Ok(out)
}
