//! Studies from Python: `simulate`, `run` (with methods written in Python, `Problem`), a
//! shard of a run (`run_shard`) for `calbench merge`, and the studies that run whole
//! (`study_kind`, `run_whole`: a registration or instruments study into its folder).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::exceptions::{PyException, PyKeyboardInterrupt};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use calbench::identify::external::{External, ExternalProblem};
use calbench::identify::MethodSpec;
use calbench::measurement::kind::Kind;
use calbench::measurement::Measurements;
use calbench::numeric::Real;
use calbench::report::guard::guard_out;
use calbench::report::run::{checked_outputs, OUTPUTS};
use calbench::report::simulated;
use calbench::robot::Robot;
use calbench::runner::run::{run_study, InMemoryRun};
use calbench::runner::whole::run_cells_study;
use calbench::study::instruments::InstrumentsScenario;
use calbench::study::kind::AnyScenario;
use calbench::study::reporter::Reporter;
use calbench::study::stats::precision::Precision;
use calbench::study::{trial, RunOptions, Shard, Study};

use crate::convert::{any_scenario_of, matrix, scenario_of, DICT};
use crate::errors::{err, setting, ComputeError, Warned};
use crate::robot::PyRobot;

/// Joint values as an (N, n) array in the robot's units.
fn q_array<'py>(py: Python<'py>, robot: &Robot, qs: &[Vec<Real>]) -> Bound<'py, PyAny> {
    let mut q = Array2::<f64>::zeros((qs.len(), robot.dof()));
    for (i, qi) in qs.iter().enumerate() {
        for (j, v) in robot.q_to_user(qi).into_iter().enumerate() {
            q[[i, j]] = v;
        }
    }
    q.into_pyarray(py).into_any()
}

/// A measurement as arrays in the robot's units: (q, points, quaternions or None).
fn measurement_arrays<'py>(
    py: Python<'py>,
    robot: &Robot,
    m: &Measurements,
    prefix: &str,
    out: &Bound<'py, PyDict>,
) -> PyResult<()> {
    let mut p = Array2::<f64>::zeros((m.len(), 3));
    for (i, pi) in m.points.iter().enumerate() {
        for a in 0..3 {
            p[[i, a]] = pi[a];
        }
    }
    out.set_item(format!("{prefix}q"), q_array(py, robot, &m.qs))?;
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

/// The truth of a simulated trial: `truth` (parameter → injected error), the nominal `robot`
/// and the text of `truth.json` (`truth_json`).
fn truth_items<'py>(
    out: &Bound<'py, PyDict>,
    errors: &[(calbench::robot::Param, Real)],
    robot: &Robot,
    truth_json: &serde_json::Value,
) -> PyResult<()> {
    let truth = PyDict::new(out.py());
    for (p, e) in errors {
        truth.set_item(p.to_string(), *e)?;
    }
    out.set_item("truth", truth)?;
    out.set_item(
        "robot",
        PyRobot {
            inner: robot.clone(),
        },
    )?;
    let text =
        serde_json::to_string(truth_json).map_err(|e| ComputeError::new_err(e.to_string()))?;
    out.set_item("truth_json", text)
}

/// The measurements of one trial of a scenario (`calbench simulate`), as a dict of arrays;
/// with `out`, the folder `calbench simulate --out` writes. An instruments study's trial is
/// measured by the instrument of `measure` and needs `out`: its readings are a file.
#[pyfunction]
#[pyo3(signature = (scenario, trial = 0, measure = None, out = None))]
pub(crate) fn simulate<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    trial: usize,
    measure: Option<String>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let measure = measure
        .map(|m| calbench::robot::names::parse::<Kind>("measure", &m))
        .transpose()
        .map_err(err)?;
    let sc = if monte_carlo_dict(scenario)? {
        scenario_of(scenario)?
    } else {
        match any_scenario_of(scenario)? {
            AnyScenario::Instruments(sc) => {
                return simulate_instrument(py, &sc, measure, trial, out)
            }
            AnyScenario::MonteCarlo(sc) => sc,
            // Refused as a calibration scenario refuses it.
            AnyScenario::Registration(_) => scenario_of(scenario)?,
        }
    };
    let path = sc.path.clone().unwrap_or_else(|| PathBuf::from(DICT));
    if measure.is_some() {
        return Err(err(simulated::no_instruments(&path)));
    }
    if let Some(out) = &out {
        guard_out(out, "out", &simulated::FILES, sc.path.as_deref()).map_err(err)?;
    }
    let (study, sim) = py
        .detach(|| {
            let study = Study::new(sc)?;
            let sim = trial::simulate_trial(&study, trial, "trial")?;
            if let Some(out) = &out {
                simulated::trial_folder(out, &study, &sim)?;
            }
            Ok((study, sim))
        })
        .map_err(err)?;
    let dict = PyDict::new(py);
    let robot = &study.nominal;
    measurement_arrays(py, robot, &sim.calibration.data, "", &dict)?;
    measurement_arrays(py, robot, &sim.validation.data, "validation_", &dict)?;
    truth_items(&dict, &sim.errors, robot, &sim.truth_json(&study))?;
    Ok(dict)
}

/// Trial `trial` of an instruments study measured by the instrument of `measure`, written to
/// `out` as `calbench simulate` writes it; the dict holds `kind`, `data` (the readings' file),
/// `q` (the measured poses), the validation poses and the truth.
fn simulate_instrument<'py>(
    py: Python<'py>,
    sc: &InstrumentsScenario,
    measure: Option<Kind>,
    trial: usize,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let out = out.ok_or_else(|| {
        setting(
            "out",
            "an instruments study's readings are a measurement-kind file (docs/formats.md \
             § 5.3): give out=DIR, whose measurements.csv identify(data=...) reads",
        )
    })?;
    guard_out(&out, "out", &simulated::FILES, Some(&sc.head.path)).map_err(err)?;
    let (robot, sim, truth) = py
        .detach(|| simulated::instrument_folder(&out, sc, measure, trial))
        .map_err(err)?;
    let dict = PyDict::new(py);
    dict.set_item("kind", sim.layout.instrument.kind().as_str())?;
    dict.set_item("data", out.join(simulated::FILES[0]))?;
    if let Some((qs, _, _)) = &sim.reading.measured {
        dict.set_item("q", q_array(py, &robot, qs))?;
    }
    let validation = simulated::validation(&sim);
    measurement_arrays(py, &robot, &validation, "validation_", &dict)?;
    truth_items(&dict, &sim.reading.errors, &robot, &truth)?;
    Ok(dict)
}

/// The problem a method written in Python solves (see `calbench.run`): the kinematic least
/// squares of one trial's calibration, weighted as for the built-in methods.
#[pyclass(name = "Problem", module = "calbench", frozen)]
pub struct PyProblem {
    inner: Arc<ExternalProblem>,
}

impl PyProblem {
    /// `x` as a vector: anything numpy reads as a 1-D array of real numbers (a bool or
    /// complex array is refused, not taken as 0 and 1 or cut to its real part).
    fn x(x: &Bound<'_, PyAny>) -> PyResult<Vec<Real>> {
        if let Some(a) = x
            .extract::<PyReadonlyArray1<'_, f64>>()
            .ok()
            .filter(|_| !crate::convert::masked(x))
        {
            return Ok(a.as_array().to_vec());
        }
        crate::convert::float64("x", x)?
            .extract::<PyReadonlyArray1<'_, f64>>()
            .map(|a| a.as_array().to_vec())
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

/// What a method written in Python returns.
const RETURNS: &str = "a 1-D float array (or a tuple of it and a termination name)";

/// Set when the run was interrupted (Ctrl-C while it ran, or a method written in Python
/// that raised what is no `Exception`: `KeyboardInterrupt`, `SystemExit` from `sys.exit`):
/// the rest of the run's calls of Python methods return at once, the run stops taking trials
/// ([`InMemoryRun::run_until`]), and the front end raises the interrupt, or the method's own
/// exception, instead of the run's results ([`Interrupted::raise`]).
#[derive(Clone, Default)]
pub(crate) struct Interrupted {
    flag: Arc<AtomicBool>,
    /// The first exception of a method that stopped the run, raised again as it was.
    raised: Arc<Mutex<Option<PyErr>>>,
}

impl Interrupted {
    /// `result`, or, when the run was interrupted, the method's exception that stopped it
    /// or a `KeyboardInterrupt`.
    pub(crate) fn raise<T>(&self, result: PyResult<T>) -> PyResult<T> {
        if self.flag.load(Ordering::SeqCst) {
            let kept = self.raised.lock().unwrap_or_else(|e| e.into_inner()).take();
            return Err(
                kept.unwrap_or_else(|| PyKeyboardInterrupt::new_err("the run was interrupted"))
            );
        }
        result
    }

    /// Stops the run on `e`, a method's exception, when it is no `Exception` (a
    /// `KeyboardInterrupt`, a `SystemExit`): it ends the run rather than fails the trial.
    fn stop_on(&self, py: Python<'_>, e: &PyErr) {
        if e.is_instance_of::<PyException>(py) {
            return;
        }
        let mut kept = self.raised.lock().unwrap_or_else(|e| e.into_inner());
        kept.get_or_insert_with(|| e.clone_ref(py));
        self.flag.store(true, Ordering::SeqCst);
    }
}

/// A Python callable as the external method `label`: called with a `Problem` under the GIL;
/// returns the vector, or (vector, termination name). An exception is the method's failure,
/// and so is a vector numpy reads as bools or complex numbers (named with its dtype), which
/// a float conversion would take as 0 and 1 or cut to its real part. An exception that is no
/// `Exception` (`KeyboardInterrupt`, `SystemExit`) stops the run instead
/// ([`Interrupted::stop_on`]): it is not a failure of the trial.
pub(crate) fn python_method(label: &str, f: Py<PyAny>, stop: &Interrupted) -> External {
    let label = label.to_string();
    let stop = stop.clone();
    External {
        name: label.clone(),
        run: Arc::new(move |p: Arc<ExternalProblem>| {
            if stop.flag.load(Ordering::SeqCst) {
                return Err("interrupted".to_string());
            }
            Python::attach(|py| {
                let text = |e: PyErr| {
                    let name = e
                        .get_type(py)
                        .name()
                        .map_or_else(|_| "Exception".to_string(), |n| n.to_string());
                    format!("{name}: {}", e.value(py))
                };
                let problem = Py::new(py, PyProblem { inner: p }).map_err(text)?;
                let out = f.bind(py).call1((problem,)).map_err(|e| {
                    stop.stop_on(py, &e);
                    text(e)
                })?;
                let (x, name) = match out.cast::<PyTuple>() {
                    Ok(t) if t.len() == 2 => {
                        let name: String =
                            t.get_item(1).and_then(|n| n.extract()).map_err(|_| {
                                format!("the method `{label}`'s termination must be a string")
                            })?;
                        (t.get_item(0).map_err(text)?, Some(name))
                    }
                    _ => (out, None),
                };
                if let Ok((_, Some((what, dtype)))) = crate::convert::as_numpy(&x) {
                    return Err(format!(
                        "the method `{label}` returned a {what} array (dtype {dtype}), not real \
                         numbers; it must return {RETURNS}"
                    ));
                }
                // A masked array's masked cells are missing (NaN, refused as a non-finite
                // value), not the values under the mask.
                let x = match crate::convert::masked(&x) {
                    true => crate::convert::float64("x", &x).map_err(text)?,
                    false => x,
                };
                let x: Vec<Real> = match x.extract::<PyReadonlyArray1<'_, f64>>() {
                    Ok(a) => a.as_array().to_vec(),
                    Err(_) => x
                        .extract()
                        .map_err(|_| format!("the method `{label}` must return {RETURNS}"))?,
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

    /// Writes the folder `out` as `calbench run --out` does, refusing what it refuses.
    fn write(&self, py: Python<'_>, out: PathBuf) -> PyResult<()> {
        let input = self.inner.result.scenario.path.as_deref();
        calbench::report::guard::guard_out(&out, "out", &OUTPUTS, input).map_err(err)?;
        py.detach(|| self.inner.write(&out)).map_err(err)
    }
}

/// Runs a study (the Python half documents the arguments).
#[pyfunction]
#[pyo3(signature = (scenario, trials = None, seed = None, threads = None, methods = None,
    progress = false, precision = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    trials: Option<usize>,
    seed: Option<u64>,
    threads: Option<usize>,
    methods: Option<Bound<'_, PyDict>>,
    progress: bool,
    precision: Option<String>,
) -> PyResult<PyRun> {
    let precision = precision
        .map(|p| {
            Precision::parse(&p).map_err(|e| match e {
                calbench::Error::Setting { msg, .. } => {
                    setting("precision", msg.spell(crate::errors::spell))
                }
                e => err(e),
            })
        })
        .transpose()?;
    let opts = folder_options(None, threads, progress, None, precision)?;
    let mut sc = scenario_of(scenario)?
        .with_run_overrides(trials, seed)
        .map_err(err)?;
    let stop = Interrupted::default();
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
                .with_method(MethodSpec::external(
                    &label,
                    python_method(&label, f.unbind(), &stop),
                ))
                .map_err(err)?;
        }
    }
    let warned = Warned::new(opts.progress);
    let reporter: &dyn Reporter = &warned;
    let flag = &*stop.flag;
    // The run in a thread of its own; this thread looks for Ctrl-C (Python's signal handlers
    // run on the main thread only) and stops the run when it comes.
    let inner = py.detach(|| {
        std::thread::scope(|s| {
            let (done, result) = std::sync::mpsc::channel();
            let run = s.spawn(move || {
                let _ = done.send(InMemoryRun::run_until(sc, &opts, reporter, flag));
            });
            let wait = std::time::Duration::from_millis(50);
            loop {
                match result.recv_timeout(wait) {
                    Ok(r) => break r,
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                        if Python::attach(|py| py.check_signals()).is_err() {
                            flag.store(true, Ordering::SeqCst);
                        }
                    }
                    // The run panicked before it sent: the panic goes on here.
                    Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                        let panic = run.join().expect_err("a run that sent nothing panicked");
                        std::panic::resume_unwind(panic)
                    }
                }
            }
        })
    });
    warned.raise(py)?;
    let inner = stop.raise(inner.map_err(err))?;
    Ok(PyRun { inner })
}

/// Runs shard `shard` ((i, n)) of a Monte-Carlo study into the shard folder `out`, the folder
/// `calbench run --shard I/N --out DIR` writes, for `calbench merge` (the Python half
/// documents the arguments). Returns the run's wall time (s).
#[pyfunction]
#[pyo3(signature = (scenario, out, trials = None, seed = None, threads = None, progress = false,
    shard = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_shard(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    out: PathBuf,
    trials: Option<usize>,
    seed: Option<u64>,
    threads: Option<usize>,
    progress: bool,
    shard: Option<(usize, usize)>,
) -> PyResult<f64> {
    if shard.is_none() {
        return Err(setting("shard", "a shard folder is a shard's: give (i, n)"));
    }
    let sc = scenario_of(scenario)?
        .with_run_overrides(trials, seed)
        .map_err(err)?;
    let folder = Folder {
        out,
        outputs: checked_outputs(true, true),
        input: sc.path.as_deref(),
    };
    let opts = folder_options(Some(folder), threads, progress, shard, None)?;
    let warned = Warned::new(progress);
    let r = py.detach(|| run_study(sc, &opts, &warned));
    warned.raise(py)?;
    Ok(r.map_err(err)?.seconds)
}

/// The output folder of a run, with the files it writes there and its scenario file.
struct Folder<'a> {
    out: PathBuf,
    outputs: &'a [&'a str],
    input: Option<&'a std::path::Path>,
}

/// The options of a run: `threads` (or the environment's), into the folder `out` (checked as
/// the command line checks `--out`: it must not destroy an input) or held in memory, its
/// share `shard` ((i, n)).
fn folder_options(
    out: Option<Folder<'_>>,
    threads: Option<usize>,
    progress: bool,
    shard: Option<(usize, usize)>,
    precision: Option<Precision>,
) -> PyResult<RunOptions> {
    let env = |k: &str| std::env::var(k).ok();
    let threads = calbench::runner::threads::requested("threads", threads, &env).map_err(err)?;
    if let Some(f) = &out {
        calbench::report::guard::guard_out(&f.out, "out", f.outputs, f.input).map_err(err)?;
    }
    let shard = shard
        .map(|(i, n)| Shard::parse(&format!("{i}/{n}")))
        .transpose()
        .map_err(err)?;
    Ok(RunOptions {
        threads,
        out: out.map(|f| f.out),
        progress,
        shard,
        precision,
    })
}

/// Whether `scenario` is the dict of a Monte-Carlo study, one without a
/// `[registration_study]` or `[instruments_study]` section: read by [`scenario_of`], without
/// [`any_scenario_of`]'s round trip through TOML text.
fn monte_carlo_dict(scenario: &Bound<'_, PyAny>) -> PyResult<bool> {
    match scenario.cast::<PyDict>() {
        Ok(d) => Ok(!(d.contains("registration_study")? || d.contains("instruments_study")?)),
        Err(_) => Ok(false),
    }
}

/// The kind of study a scenario is: `monte-carlo`, `registration` (`[registration_study]`)
/// or `instruments` (`[instruments_study]`), as its sections say (docs/formats.md § 4).
#[pyfunction]
pub(crate) fn study_kind(scenario: &Bound<'_, PyAny>) -> PyResult<&'static str> {
    if monte_carlo_dict(scenario)? {
        return Ok("monte-carlo");
    }
    Ok(match any_scenario_of(scenario)? {
        AnyScenario::MonteCarlo(_) => "monte-carlo",
        AnyScenario::Registration(_) => "registration",
        AnyScenario::Instruments(_) => "instruments",
    })
}

/// Runs a registration or instruments study (or its share `shard`, (i, n)) into the folder
/// `out`, the files `calbench run SCENARIO --out DIR` writes (the Python half documents the
/// arguments).
#[pyfunction]
#[pyo3(signature = (scenario, out, trials = None, seed = None, threads = None, progress = false,
    shard = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_whole(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    out: PathBuf,
    trials: Option<usize>,
    seed: Option<u64>,
    threads: Option<usize>,
    progress: bool,
    shard: Option<(usize, usize)>,
) -> PyResult<()> {
    let sc = any_scenario_of(scenario)?
        .with_run_overrides(trials, seed)
        .map_err(err)?;
    let folder = Folder {
        out,
        outputs: checked_outputs(false, shard.is_some()),
        input: sc.path(),
    };
    let opts = folder_options(Some(folder), threads, progress, shard, None)?;
    let warned = Warned::new(progress);
    let r = py.detach(|| run_cells_study(&sc, &opts, &warned));
    warned.raise(py)?;
    r.map_err(err)?;
    Ok(())
}
