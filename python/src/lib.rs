//! The Rust half of the Python module `calbench` (docs/python.md): a thin layer over the
//! library. Arrays come in as float64 numpy arrays (the Python half, `calbench/__init__.py`,
//! converts and checks shapes) and go out as numpy arrays; every library error becomes a
//! `calbench.Error` whose message is the command line's. Rust work runs with the GIL
//! released; a method written in Python takes the GIL for its call, so such methods run one
//! at a time while the rest of each trial runs in parallel.

mod compare;
mod convert;
mod errors;
mod identify;
mod robot;
mod study;
mod task;

use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use calbench::measurement::kind::Kind;
use calbench::measurement::Measure;
use calbench::robot::{builtin, Param};
use calbench::sim::instrument::InstrumentSettings;

use errors::{
    setting, ComputeError, ConvergenceWarning, Error, FileError, IoError, LimitWarning,
    SettingError,
};
use robot::PyRobot;

/// Rank, identifiable parameters and dependent groups of every parameter of `robot` over
/// the poses `q` (the robot's units) for `measure`: the tracker's `position` or `pose`, or
/// another instrument's kind (`distance`, `plane`, `sphere`, `multi-target`, read with
/// `between_poses`, `planes`, `spheres` as `calbench identifiability --poses-file` reads
/// them); joint values outside the limits are refused naming the row and the column.
#[pyfunction]
#[pyo3(signature = (robot, q, measure = "position", between_poses = false, planes = 3, spheres = 1))]
fn identifiability<'py>(
    py: Python<'py>,
    robot: &PyRobot,
    q: PyReadonlyArray2<'py, f64>,
    measure: &str,
    between_poses: bool,
    planes: usize,
    spheres: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let r = &robot.inner;
    let kind = Kind::named("measure", measure).map_err(errors::err)?;
    // Refused as `calbench identifiability --poses-file` refuses them: the row, the column.
    let qs = calbench::measurement::csv::joint_rows_from_arrays(r, "q", &convert::rows(&q))
        .map_err(errors::err)?;
    if qs.is_empty() {
        return Err(setting("q", "no poses"));
    }
    let out = PyDict::new(py);
    let (a, nuisance) = match kind {
        Kind::Position | Kind::Pose => {
            let measure = if kind == Kind::Pose {
                Measure::Pose
            } else {
                Measure::Position
            };
            let a = py
                .detach(|| calbench::robot::identifiability::analyse(r, &r.params(), &qs, measure));
            (a, None)
        }
        kind => {
            let s = InstrumentSettings {
                kind,
                pivot: !between_poses,
                planes,
                spheres,
                ..InstrumentSettings::default()
            };
            let a = py
                .detach(|| calbench::identify::kind::identifiability_at(r, &qs, &s))
                .map_err(errors::err)?;
            (a.robot, Some((a.unknowns, a.undetermined)))
        }
    };
    let names = |v: &[Param]| v.iter().map(|p| p.to_string()).collect::<Vec<_>>();
    out.set_item("rank", a.rank)?;
    out.set_item("parameters", r.params().len())?;
    out.set_item("identifiable", names(&a.identifiable))?;
    out.set_item("unidentifiable", names(&a.unidentifiable))?;
    let groups: Vec<Vec<String>> = a.groups.iter().map(|g| names(g)).collect();
    out.set_item("groups", groups)?;
    out.set_item("condition_number", a.condition_number)?;
    if let Some((unknowns, undetermined)) = nuisance {
        out.set_item("measure", kind.as_str())?;
        out.set_item("instrument_unknowns", unknowns)?;
        out.set_item("undetermined_instrument_unknowns", undetermined)?;
    }
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
    // numpy's C API, loaded now: loaded by the first array a function returns, it ran Python
    // code where a pending Ctrl-C raised, and the numpy crate panics on that error
    // (`PanicException` where `KeyboardInterrupt` belongs).
    numpy::PyArray1::<f64>::zeros(py, 0, false);
    m.add("Error", py.get_type::<Error>())?;
    m.add("FileError", py.get_type::<FileError>())?;
    m.add("SettingError", py.get_type::<SettingError>())?;
    m.add("ComputeError", py.get_type::<ComputeError>())?;
    m.add("IoError", py.get_type::<IoError>())?;
    m.add("LimitWarning", py.get_type::<LimitWarning>())?;
    m.add("ConvergenceWarning", py.get_type::<ConvergenceWarning>())?;
    // The most trials a study runs, so that a count beyond 64 bits is refused with that range.
    m.add("MAX_TRIALS", calbench::study::scenario::MAX_TRIALS)?;
    m.add_class::<robot::PyRobot>()?;
    m.add_class::<study::PyProblem>()?;
    m.add_class::<study::PyRun>()?;
    m.add_function(wrap_pyfunction!(identify::identify, m)?)?;
    m.add_function(wrap_pyfunction!(study::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(study::run, m)?)?;
    m.add_function(wrap_pyfunction!(study::run_shard, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_kind, m)?)?;
    m.add_function(wrap_pyfunction!(study::run_whole, m)?)?;
    m.add_function(wrap_pyfunction!(identifiability, m)?)?;
    m.add_function(wrap_pyfunction!(compare::compare, m)?)?;
    m.add_function(wrap_pyfunction!(catalogue, m)?)?;
    m.add_function(wrap_pyfunction!(task::task, m)?)?;
    m.add_function(wrap_pyfunction!(convert::real_array, m)?)?;
    Ok(())
}
