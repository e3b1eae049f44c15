//! The Rust half of the Python module `calbench` (docs/python.md): a thin layer over the
//! library. Arrays come in as float64 numpy arrays (the Python half, `calbench/__init__.py`,
//! converts and checks shapes) and go out as numpy arrays; every library error becomes a
//! `calbench.Error` whose message is the command line's. Rust work runs with the GIL
//! released; a method written in Python takes the GIL for its call, so such methods run one
//! at a time while the rest of each trial runs in parallel.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use nalgebra::DMatrix;
use numpy::ndarray::{Array2, Array3, ShapeBuilder};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use calbench::calibrate::on_data::identify_on_data;
use calbench::calibrate::validation::{residual_vectors, validate_file};
use calbench::calibrate::{ErrorStats, Registration};
use calbench::identify::external::{External, ExternalProblem};
use calbench::identify::MethodSpec;
use calbench::measurement::csv::measurements_from_arrays;
use calbench::measurement::{Measure, Measurements};
use calbench::numeric::{Frame, Real};
use calbench::robot::compliance::CompliancePick;
use calbench::robot::{builtin, Param, Robot};
use calbench::study::run::InMemoryRun;
use calbench::study::scenario::Scenario;
use calbench::study::{trial, RunOptions, Study};

create_exception!(calbench, Error, PyException, "Every error of calbench.");
create_exception!(
    calbench,
    FileError,
    Error,
    "An input file is malformed or holds a value out of range (names the file and the place)."
);
create_exception!(
    calbench,
    SettingError,
    Error,
    "A setting or an argument is out of range (names the key)."
);
create_exception!(
    calbench,
    ComputeError,
    Error,
    "A computation could not be carried out."
);
create_exception!(
    calbench,
    IoError,
    Error,
    "Reading or writing a file failed (names the file)."
);

/// A library error as the Python exception of its kind, with the command line's message.
fn err(e: calbench::Error) -> PyErr {
    let msg = e.to_string();
    match e {
        calbench::Error::File { .. } => FileError::new_err(msg),
        calbench::Error::Setting { .. } => SettingError::new_err(msg),
        calbench::Error::Compute(_) => ComputeError::new_err(msg),
        calbench::Error::Io { .. } => IoError::new_err(msg),
        _ => Error::new_err(msg),
    }
}

/// A refused argument.
fn setting(key: &str, msg: impl Into<String>) -> PyErr {
    err(calbench::Error::setting(key, msg))
}

/// The rows of a (N, k) array.
fn rows(a: &PyReadonlyArray2<'_, f64>) -> Vec<Vec<Real>> {
    a.as_array().outer_iter().map(|r| r.to_vec()).collect()
}

/// The rows of a (N, 3) array as points.
fn points3(key: &str, a: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<[Real; 3]>> {
    let v = a.as_array();
    if v.ncols() != 3 {
        return Err(setting(
            key,
            format!("expected shape (N, 3), got ({}, {})", v.nrows(), v.ncols()),
        ));
    }
    Ok(v.outer_iter().map(|r| [r[0], r[1], r[2]]).collect())
}

/// Orientations as unit quaternions `[qw, qx, qy, qz]`: from an (N, 4) array, or from
/// rotation matrices (N, 3, 3).
fn quaternions(key: &str, a: &Bound<'_, PyAny>) -> PyResult<Vec<[Real; 4]>> {
    if let Ok(q) = a.extract::<PyReadonlyArray2<'_, f64>>() {
        let v = q.as_array();
        if v.ncols() != 4 {
            return Err(setting(
                key,
                format!(
                    "expected unit quaternions (N, 4) [qw, qx, qy, qz] or rotation matrices \
                     (N, 3, 3), got ({}, {})",
                    v.nrows(),
                    v.ncols()
                ),
            ));
        }
        return Ok(v.outer_iter().map(|r| [r[0], r[1], r[2], r[3]]).collect());
    }
    let m: PyReadonlyArray3<'_, f64> = a.extract().map_err(|_| {
        setting(
            key,
            "expected unit quaternions (N, 4) or rotation matrices (N, 3, 3) of floats",
        )
    })?;
    let v = m.as_array();
    if v.shape()[1..] != [3, 3] {
        return Err(setting(
            key,
            format!("expected rotation matrices (N, 3, 3), got {:?}", v.shape()),
        ));
    }
    v.outer_iter()
        .enumerate()
        .map(|(i, r)| {
            let mat = nalgebra::Matrix3::from_fn(|a, b| r[[a, b]]);
            if !mat.iter().all(|x| x.is_finite())
                || (mat.transpose() * mat - nalgebra::Matrix3::identity()).amax() > 1e-6
                || mat.determinant() < 0.0
            {
                return Err(setting(key, format!("row {i}: not a rotation matrix")));
            }
            let q = nalgebra::UnitQuaternion::from_matrix(&mat);
            Ok([q.w, q.i, q.j, q.k])
        })
        .collect()
}

/// Measurements from arrays in the robot's units, checked as a measurement file is.
#[allow(clippy::too_many_arguments)]
fn measurements(
    robot: &Robot,
    what: &str,
    q: &PyReadonlyArray2<'_, f64>,
    points: &PyReadonlyArray2<'_, f64>,
    rotations: Option<&Bound<'_, PyAny>>,
    sigma: Option<&PyReadonlyArray1<'_, f64>>,
    payload: Option<&PyReadonlyArray1<'_, f64>>,
) -> PyResult<Measurements> {
    let quats = rotations
        .map(|r| quaternions(&format!("{what}.rotations"), r))
        .transpose()?;
    let sigma = sigma.map(|s| s.as_array().to_vec());
    let payload = payload.map(|s| s.as_array().to_vec());
    measurements_from_arrays(
        robot,
        what,
        &rows(q),
        &points3(&format!("{what}.points"), points)?,
        quats.as_deref(),
        sigma.as_deref(),
        payload.as_deref(),
    )
    .map_err(err)
}

/// A Python value as a TOML value (scenario dicts, method options).
fn toml_value(key: &str, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(v.extract().map_err(|_| {
            setting(key, "an integer beyond the 64-bit range")
        })?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(toml::Value::Table(toml_table(key, d)?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: Vec<toml::Value> = v
            .try_iter()?
            .enumerate()
            .map(|(i, x)| toml_value(&format!("{key}[{i}]"), &x?))
            .collect::<PyResult<_>>()?;
        return Ok(toml::Value::Array(items));
    }
    // numpy scalars and other numbers.
    if let Ok(f) = v.extract::<f64>() {
        return Ok(toml::Value::Float(f));
    }
    Err(setting(
        key,
        format!(
            "{} is not a TOML value (bool, int, float, str, list or dict)",
            v.get_type().name()?
        ),
    ))
}

/// A Python dict as a TOML table.
fn toml_table(key: &str, d: &Bound<'_, PyDict>) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        let k: String = k
            .extract()
            .map_err(|_| setting(key, "every key must be a string"))?;
        let dotted = if key.is_empty() {
            k.clone()
        } else {
            format!("{key}.{k}")
        };
        t.insert(k, toml_value(&dotted, &v)?);
    }
    Ok(t)
}

/// A scenario: a path to its TOML file, or a dict shaped like the file.
fn scenario_of(scenario: &Bound<'_, PyAny>) -> PyResult<Scenario> {
    if let Ok(d) = scenario.cast::<PyDict>() {
        let table = toml_table("", d)?;
        return Scenario::from_toml_table(table, Path::new("<scenario dict>")).map_err(err);
    }
    let path: PathBuf = scenario
        .extract()
        .map_err(|_| setting("scenario", "expected a path to a scenario file or a dict"))?;
    Scenario::load(&path).map_err(err)
}

/// A robot model with its nominal parameters (lengths in mm, angles in the robot's unit
/// where joint values are concerned, as in the command line).
#[pyclass(name = "Robot", module = "calbench", frozen)]
#[derive(Clone)]
pub struct PyRobot {
    inner: Robot,
}

#[pymethods]
impl PyRobot {
    /// The built-in robot `name` (`calbench robots` lists them).
    #[staticmethod]
    fn builtin(name: &str) -> PyResult<PyRobot> {
        match builtin::builtin(name) {
            Some(b) => Ok(PyRobot { inner: (b.build)() }),
            None => Err(setting(
                "robot",
                format!(
                    "\"{name}\" is not a built-in robot ({})",
                    builtin::BUILTINS
                        .iter()
                        .map(|b| b.name)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )),
        }
    }

    /// A robot file: TOML (docs/formats.md) or URDF.
    #[staticmethod]
    fn from_file(path: PathBuf) -> PyResult<PyRobot> {
        if !path.is_file() {
            return Err(err(calbench::Error::io(
                &path,
                std::io::Error::new(std::io::ErrorKind::NotFound, "no such robot file"),
            )));
        }
        let shown = path.to_string_lossy().into_owned();
        builtin::load(&shown)
            .map(|inner| PyRobot { inner })
            .map_err(err)
    }

    /// The robot's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// The number of joints.
    #[getter]
    fn joint_count(&self) -> usize {
        self.inner.dof()
    }

    /// Every parameter of the model (θ, d, a, α, β per joint, base, tool), in flat-vector
    /// order.
    fn parameter_names(&self) -> Vec<String> {
        self.inner.params().iter().map(|p| p.to_string()).collect()
    }

    /// The nominal value of each parameter (mm, rad), by name.
    fn parameters(&self) -> Vec<(String, Real)> {
        self.inner
            .params()
            .into_iter()
            .map(|p| (p.to_string(), self.inner.get(p)))
            .collect()
    }

    /// Forward kinematics: joint values `q` (N, n) in the robot's units → tool points
    /// (N, 3) in mm, or with `pose=True` homogeneous tool frames (N, 4, 4).
    #[pyo3(signature = (q, pose = false))]
    fn fk<'py>(
        &self,
        py: Python<'py>,
        q: PyReadonlyArray2<'py, f64>,
        pose: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let r = &self.inner;
        let qs: Vec<Vec<Real>> = rows(&q)
            .iter()
            .enumerate()
            .map(|(i, v)| r.q_from_user_checked(v, &format!("q[{i}]")))
            .collect::<calbench::Result<_>>()
            .map_err(err)?;
        let chain = r.chain();
        let frames: Vec<Frame> = qs.iter().map(|v| chain.fk(v)).collect();
        if pose {
            let mut out = Array3::<f64>::zeros((frames.len(), 4, 4));
            for (i, f) in frames.iter().enumerate() {
                for a in 0..3 {
                    for b in 0..3 {
                        out[[i, a, b]] = f.rot[(a, b)];
                    }
                    out[[i, a, 3]] = f.pos[a];
                }
                out[[i, 3, 3]] = 1.0;
            }
            return Ok(out.into_pyarray(py).into_any());
        }
        let mut out = Array2::<f64>::zeros((frames.len(), 3));
        for (i, f) in frames.iter().enumerate() {
            for a in 0..3 {
                out[[i, a]] = f.pos[a];
            }
        }
        Ok(out.into_pyarray(py).into_any())
    }

    /// A copy with errors added to parameters: a dict name → error (mm, rad).
    fn with_errors(&self, errors: &Bound<'_, PyDict>) -> PyResult<PyRobot> {
        let known = self.inner.params();
        let mut list: Vec<(Param, Real)> = Vec::new();
        for (k, v) in errors.iter() {
            let name: String = k
                .extract()
                .map_err(|_| setting("errors", "every key must be a parameter name"))?;
            let p = Param::parse(&name).filter(|p| known.contains(p));
            let Some(p) = p else {
                return Err(setting(
                    "errors",
                    format!(
                        "`{name}` is not a parameter of robot `{}`; its parameters are {}",
                        self.inner.name,
                        self.parameter_names().join(" ")
                    ),
                ));
            };
            let e: Real = v
                .extract()
                .map_err(|_| setting(&format!("errors.{name}"), "must be a number"))?;
            if !e.is_finite() {
                return Err(setting(&format!("errors.{name}"), "must be finite"));
            }
            list.push((p, e));
        }
        Ok(PyRobot {
            inner: self.inner.with_errors(&list),
        })
    }

    /// The robot as a robot file (TOML), as `calbench identify` writes `robot.toml`.
    fn to_toml(&self) -> String {
        calbench::robot::robot_to_toml(&self.inner)
    }

    fn __repr__(&self) -> String {
        format!(
            "calbench.Robot(\"{}\", {} joints)",
            self.inner.name,
            self.inner.dof()
        )
    }
}

/// Statistics of errors as a dict (mean, rms, max, std).
fn stats(py: Python<'_>, s: &ErrorStats) -> PyResult<Py<PyDict>> {
    let d = PyDict::new(py);
    d.set_item("mean", s.mean)?;
    d.set_item("rms", s.rms)?;
    d.set_item("max", s.max)?;
    d.set_item("std", s.std)?;
    Ok(d.unbind())
}

/// A column-major matrix as a (rows, cols) numpy array.
fn matrix<'py>(py: Python<'py>, m: &DMatrix<Real>) -> Bound<'py, PyAny> {
    Array2::from_shape_vec((m.nrows(), m.ncols()).f(), m.as_slice().to_vec())
        .map(|a| a.into_pyarray(py).into_any())
        .unwrap_or_else(|_| PyArray1::<f64>::zeros(py, 0, false).into_any())
}

/// A validation measurement: (q, points, rotations or None).
type Validation<'py> = (
    PyReadonlyArray2<'py, f64>,
    PyReadonlyArray2<'py, f64>,
    Option<Bound<'py, PyAny>>,
);

/// Identification on measured arrays (the Python half documents the arguments); returns a
/// dict of the result's fields.
#[pyfunction]
#[pyo3(signature = (robot, q, points, rotations = None, sigma = None, payload = None,
    method = "lm", options = None, registration = "identify", compliance = None,
    validate = None, seed = 0, allow_rank_deficient = false))]
#[allow(clippy::too_many_arguments)]
fn identify<'py>(
    py: Python<'py>,
    robot: &PyRobot,
    q: PyReadonlyArray2<'py, f64>,
    points: PyReadonlyArray2<'py, f64>,
    rotations: Option<Bound<'py, PyAny>>,
    sigma: Option<PyReadonlyArray1<'py, f64>>,
    payload: Option<PyReadonlyArray1<'py, f64>>,
    method: &str,
    options: Option<Bound<'py, PyDict>>,
    registration: &str,
    compliance: Option<&str>,
    validate: Option<Validation<'py>>,
    seed: u64,
    allow_rank_deficient: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let nominal = &robot.inner;
    let data = measurements(
        nominal,
        "data",
        &q,
        &points,
        rotations.as_ref(),
        sigma.as_ref(),
        payload.as_ref(),
    )?;
    let mut entry = match &options {
        Some(o) => toml_table("options", o)?,
        None => toml::Table::new(),
    };
    entry.insert("name".into(), toml::Value::String(method.into()));
    if data.measure() == Measure::Position && entry.contains_key("k") {
        return Err(setting(
            "options.k",
            "weighs orientation against position errors; the data hold positions only",
        ));
    }
    let spec = MethodSpec::from_table(&entry).map_err(|(k, msg)| {
        let key = if k.is_empty() || k == "name" {
            if k == "name" {
                "method".to_string()
            } else {
                "options".to_string()
            }
        } else {
            format!("options.{k}")
        };
        setting(&key, msg)
    })?;
    let registration: Registration = registration.parse().map_err(|_| {
        setting(
            "registration",
            format!("\"{registration}\" is not one of identify, svd, wsvd, known"),
        )
    })?;
    let pick = compliance.map(CompliancePick::from_arg);
    let val = validate
        .as_ref()
        .map(|(vq, vp, vr)| measurements(nominal, "validate", vq, vp, vr.as_ref(), None, None))
        .transpose()?;
    // The Rust side, timed as a whole: the identification and everything the result holds
    // that `calbench identify` computes too (covariance, condition number, residuals,
    // validation).
    let (on, validation, covariance, condition, residuals, seconds) = py
        .detach(|| {
            let t0 = std::time::Instant::now();
            let on = identify_on_data(
                nominal,
                &data,
                &spec,
                registration,
                pick.as_ref(),
                "compliance",
                seed,
            )?;
            let validation = val
                .as_ref()
                .map(|v| validate_file(nominal, &on.calibrated, v))
                .transpose()?;
            let id = &on.calibrated.identified;
            let (covariance, condition) = (id.covariance(), id.condition_number());
            let residuals = residual_vectors(&on.calibrated, &data)?;
            let seconds = t0.elapsed().as_secs_f64();
            Ok((on, validation, covariance, condition, residuals, seconds))
        })
        .map_err(err)?;
    if on.undetermined() && !allow_rank_deficient {
        return Err(err(on.undetermined_error(
            nominal,
            Path::new("<arrays>"),
            &data,
            &spec,
            "allow_rank_deficient=True",
        )));
    }
    let c = &on.calibrated;
    let id = &c.identified;
    let out = PyDict::new(py);
    let params = PyDict::new(py);
    for (p, x) in on.params.iter().zip(id.x.iter()) {
        params.set_item(p.to_string(), *x)?;
    }
    out.set_item("parameters", params)?;
    out.set_item("covariance", matrix(py, &covariance))?;
    out.set_item("termination", id.termination.as_str())?;
    out.set_item("iterations", id.iterations)?;
    out.set_item("evaluations", id.evaluations)?;
    out.set_item("rank", id.rank)?;
    out.set_item("condition_number", condition)?;
    out.set_item("sigma0", id.sigma0)?;
    out.set_item("rms_residual_mm", id.rms_residual)?;
    out.set_item("weights", PyArray1::from_slice(py, &id.weights))?;
    let flat: Vec<f64> = residuals.iter().flat_map(|v| [v[0], v[1], v[2]]).collect();
    let r = Array2::from_shape_vec((residuals.len(), 3), flat)
        .map_err(|e| ComputeError::new_err(e.to_string()))?;
    out.set_item("residuals", r.into_pyarray(py))?;
    let mut compensated = c.robot.clone();
    compensated.name = format!("{}-calibrated", nominal.name);
    out.set_item("robot", PyRobot { inner: compensated })?;
    let f = &c.frame;
    let mut frame = Array2::<f64>::eye(4);
    for a in 0..3 {
        for b in 0..3 {
            frame[[a, b]] = f.rot[(a, b)];
        }
        frame[[a, 3]] = f.pos[a];
    }
    out.set_item("registration_frame", frame.into_pyarray(py))?;
    out.set_item("registration_rounds", c.rounds.rounds)?;
    out.set_item("seconds", seconds)?;
    match &validation {
        None => out.set_item("validation", py.None())?,
        Some(v) => {
            let d = PyDict::new(py);
            d.set_item("before_mm", stats(py, &v.before_mm)?)?;
            d.set_item("after_mm", stats(py, &v.after_mm)?)?;
            if let Some((b, a)) = &v.deg {
                d.set_item("before_deg", stats(py, b)?)?;
                d.set_item("after_deg", stats(py, a)?)?;
            }
            if let Some((b, a)) = &v.attitude_deg {
                d.set_item("before_attitude_deg", stats(py, b)?)?;
                d.set_item("after_attitude_deg", stats(py, a)?)?;
            }
            out.set_item("validation", d)?;
        }
    }
    Ok(out)
}

/// A measurement as arrays in the robot's units: (q, points, quaternions or None).
fn measurement_arrays<'py>(
    py: Python<'py>,
    robot: &Robot,
    m: &Measurements,
    prefix: &str,
    out: &Bound<'py, PyDict>,
) -> PyResult<()> {
    let n = robot.dof();
    let mut q = Array2::<f64>::zeros((m.len(), n));
    let mut p = Array2::<f64>::zeros((m.len(), 3));
    for (i, (qi, pi)) in m.qs.iter().zip(&m.points).enumerate() {
        for (j, v) in robot.q_to_user(qi).into_iter().enumerate() {
            q[[i, j]] = v;
        }
        for a in 0..3 {
            p[[i, a]] = pi[a];
        }
    }
    out.set_item(format!("{prefix}q"), q.into_pyarray(py))?;
    out.set_item(format!("{prefix}points"), p.into_pyarray(py))?;
    match &m.quats {
        None => out.set_item(format!("{prefix}rotations"), py.None())?,
        Some(qs) => {
            let flat: Vec<f64> = qs.iter().flatten().copied().collect();
            let a = Array2::from_shape_vec((qs.len(), 4), flat)
                .map_err(|e| ComputeError::new_err(e.to_string()))?;
            out.set_item(format!("{prefix}rotations"), a.into_pyarray(py))?;
        }
    }
    if let Some(s) = &m.payload_kg {
        out.set_item(format!("{prefix}payload"), PyArray1::from_slice(py, s))?;
    }
    Ok(())
}

/// The measurements of one trial of a scenario (`calbench simulate`), as a dict of arrays.
#[pyfunction]
#[pyo3(signature = (scenario, trial = 0))]
fn simulate<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    trial: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let sc = scenario_of(scenario)?;
    let (study, sim) = py
        .detach(|| {
            let study = Study::new(sc)?;
            let sim = trial::simulate_trial(&study, trial, "trial")?;
            Ok((study, sim))
        })
        .map_err(err)?;
    let out = PyDict::new(py);
    let robot = &study.nominal;
    measurement_arrays(py, robot, &sim.calibration.data, "", &out)?;
    measurement_arrays(py, robot, &sim.validation.data, "validation_", &out)?;
    let truth = PyDict::new(py);
    for (p, e) in &sim.errors {
        truth.set_item(p.to_string(), *e)?;
    }
    out.set_item("truth", truth)?;
    out.set_item(
        "robot",
        PyRobot {
            inner: robot.clone(),
        },
    )?;
    let info = serde_json::to_string(&sim.truth_json(&study))
        .map_err(|e| ComputeError::new_err(e.to_string()))?;
    out.set_item("truth_json", info)?;
    Ok(out)
}

/// The problem a method written in Python solves (see `calbench.run`): the kinematic least
/// squares of one trial's calibration, weighted as for the built-in methods.
#[pyclass(name = "Problem", module = "calbench", frozen)]
pub struct PyProblem {
    inner: Arc<ExternalProblem>,
}

impl PyProblem {
    /// `x` as a vector (a numpy array or a sequence of floats).
    fn x(x: &Bound<'_, PyAny>) -> PyResult<Vec<Real>> {
        if let Ok(a) = x.extract::<PyReadonlyArray1<'_, f64>>() {
            return Ok(a.as_array().to_vec());
        }
        x.extract::<Vec<Real>>()
            .map_err(|_| setting("x", "expected a 1-D array of floats"))
    }
}

#[pymethods]
impl PyProblem {
    /// The identified parameters, in the order of the vector.
    #[getter]
    fn parameter_names(&self) -> Vec<String> {
        self.inner.params().iter().map(|p| p.to_string()).collect()
    }

    /// The start: zero errors.
    #[getter]
    fn x0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.inner.x0())
    }

    /// The prior weight of each measured point (1 without standard deviations).
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.inner.weights())
    }

    /// Rows of the residual per point: 3 (positions) or 6 (full poses).
    #[getter]
    fn rows_per_point(&self) -> usize {
        self.inner.size().rows_per_point
    }

    /// The weighted residual √P·(measured − model(x)), one row per coordinate.
    fn residual<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = PyProblem::x(x)?;
        let r = self
            .inner
            .evaluate(&x, |r, _| r.as_slice().to_vec())
            .map_err(err)?;
        Ok(PyArray1::from_vec(py, r))
    }

    /// The derivative of `residual(x)` (rows × parameters): a Gauss–Newton step is
    /// `x - lstsq(J, r)`.
    fn jacobian<'py>(&self, py: Python<'py>, x: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let x = PyProblem::x(x)?;
        let j = self.inner.evaluate(&x, |_, j| j.clone()).map_err(err)?;
        Ok(matrix(py, &j))
    }

    fn __repr__(&self) -> String {
        let s = self.inner.size();
        format!(
            "calbench.Problem({} parameters, {} points)",
            s.params, s.points
        )
    }
}

/// A Python callable as an external method: called with a `Problem` under the GIL; returns
/// the vector, or (vector, termination name). An exception is the method's failure.
fn python_method(f: Py<PyAny>) -> External {
    External {
        run: Arc::new(move |p: Arc<ExternalProblem>| {
            Python::attach(|py| {
                let text = |e: PyErr| {
                    let name = e
                        .get_type(py)
                        .name()
                        .map_or_else(|_| "Exception".to_string(), |n| n.to_string());
                    format!("{name}: {}", e.value(py))
                };
                let problem = Py::new(py, PyProblem { inner: p }).map_err(text)?;
                let out = f.bind(py).call1((problem,)).map_err(text)?;
                let (x, name) = match out.cast::<PyTuple>() {
                    Ok(t) if t.len() == 2 => {
                        let name: String = t
                            .get_item(1)
                            .and_then(|n| n.extract())
                            .map_err(|_| "the termination must be a string".to_string())?;
                        (t.get_item(0).map_err(text)?, Some(name))
                    }
                    _ => (out, None),
                };
                let x: Vec<Real> = match x.extract::<PyReadonlyArray1<'_, f64>>() {
                    Ok(a) => a.as_array().to_vec(),
                    Err(_) => x.extract().map_err(|_| {
                        "the method must return a 1-D float array (or a tuple of it and a \
                         termination name)"
                            .to_string()
                    })?,
                };
                Ok((x, name))
            })
        }),
    }
}

/// A finished run held in memory (the Python half's `Study` wraps it).
#[pyclass(name = "_Run", module = "calbench", frozen)]
pub struct PyRun {
    inner: InMemoryRun,
}

#[pymethods]
impl PyRun {
    /// The text of `summary.json`.
    fn summary_json(&self) -> PyResult<String> {
        self.inner.summary_json().map_err(err)
    }

    /// The bytes of `trials.csv`.
    fn trials_csv<'py>(&self, py: Python<'py>) -> Bound<'py, pyo3::types::PyBytes> {
        pyo3::types::PyBytes::new(py, &self.inner.trials_csv)
    }

    /// Wall time of the run (s).
    #[getter]
    fn seconds(&self) -> f64 {
        self.inner.result.seconds
    }

    /// Writes the folder `out` as `calbench run --out` does.
    fn write(&self, py: Python<'_>, out: PathBuf) -> PyResult<()> {
        py.detach(|| self.inner.write(&out)).map_err(err)
    }
}

/// Runs a study (the Python half documents the arguments).
#[pyfunction]
#[pyo3(signature = (scenario, trials = None, seed = None, threads = None, methods = None,
    progress = false))]
fn run(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    trials: Option<usize>,
    seed: Option<u64>,
    threads: Option<usize>,
    methods: Option<Bound<'_, PyDict>>,
    progress: bool,
) -> PyResult<PyRun> {
    let mut sc = scenario_of(scenario)?
        .with_run_overrides(trials, seed)
        .map_err(err)?;
    if threads == Some(0) {
        return Err(setting("threads", "must be at least 1"));
    }
    if let Some(m) = methods {
        for (label, f) in m.iter() {
            let label: String = label
                .extract()
                .map_err(|_| setting("methods", "every key must be a label (a string)"))?;
            if !f.is_callable() {
                return Err(setting(
                    &format!("methods.{label}"),
                    "must be a function of a calbench.Problem",
                ));
            }
            sc = sc
                .with_method(MethodSpec::external(&label, python_method(f.unbind())))
                .map_err(err)?;
        }
    }
    let opts = RunOptions {
        threads,
        out: None,
        progress,
        shard: None,
    };
    let inner = py.detach(|| InMemoryRun::run(sc, &opts)).map_err(err)?;
    Ok(PyRun { inner })
}

/// Rank, identifiable parameters and dependent groups of every parameter of `robot` over
/// the poses `q` (the robot's units) for `measure` ("position" or "pose").
#[pyfunction]
#[pyo3(signature = (robot, q, measure = "position"))]
fn identifiability<'py>(
    py: Python<'py>,
    robot: &PyRobot,
    q: PyReadonlyArray2<'py, f64>,
    measure: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let r = &robot.inner;
    let measure = match measure {
        "position" => Measure::Position,
        "pose" => Measure::Pose,
        other => {
            return Err(setting(
                "measure",
                format!("\"{other}\" is not a measure; allowed: position, pose"),
            ))
        }
    };
    let qs: Vec<Vec<Real>> = rows(&q)
        .iter()
        .enumerate()
        .map(|(i, v)| r.q_from_user_checked(v, &format!("q[{i}]")))
        .collect::<calbench::Result<_>>()
        .map_err(err)?;
    if qs.is_empty() {
        return Err(setting("q", "no poses"));
    }
    let a = py.detach(|| calbench::robot::identifiability::analyse(r, &r.params(), &qs, measure));
    let names = |v: &[Param]| v.iter().map(|p| p.to_string()).collect::<Vec<_>>();
    let out = PyDict::new(py);
    out.set_item("rank", a.rank)?;
    out.set_item("parameters", r.params().len())?;
    out.set_item("identifiable", names(&a.identifiable))?;
    out.set_item("unidentifiable", names(&a.unidentifiable))?;
    let groups: Vec<Vec<String>> = a.groups.iter().map(|g| names(g)).collect();
    out.set_item("groups", groups)?;
    out.set_item("condition_number", a.condition_number)?;
    Ok(out)
}

/// The names of the built-in robots and of the identification methods.
#[pyfunction]
fn catalogue(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);
    let robots: Vec<&str> = builtin::BUILTINS.iter().map(|b| b.name).collect();
    let methods: Vec<&str> = calbench::identify::METHODS.iter().map(|m| m.name).collect();
    out.set_item("robots", robots)?;
    out.set_item("methods", methods)?;
    Ok(out)
}

/// The compiled part of `calbench`.
#[pymodule]
fn _calbench(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("FileError", py.get_type::<FileError>())?;
    m.add("SettingError", py.get_type::<SettingError>())?;
    m.add("ComputeError", py.get_type::<ComputeError>())?;
    m.add("IoError", py.get_type::<IoError>())?;
    m.add_class::<PyRobot>()?;
    m.add_class::<PyProblem>()?;
    m.add_class::<PyRun>()?;
    m.add_function(wrap_pyfunction!(identify, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(identifiability, m)?)?;
    m.add_function(wrap_pyfunction!(catalogue, m)?)?;
    Ok(())
}
