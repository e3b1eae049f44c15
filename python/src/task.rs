//! `calbench.task`: one entry of a fixed real-data task (docs/formats.md § 9), by a calbench
//! method or by a method written in Python (the open division), through the identify
//! pipeline; the entry's `task.json` text, and its folder when `out` is given.

use std::path::{Path, PathBuf};

use pyo3::prelude::*;
use pyo3::types::PyDict;

use calbench::calibrate::cv::Model;
use calbench::calibrate::pipeline::IdentifyOutcome;
use calbench::calibrate::task::record::{OUTPUTS, SOCKET_OUTPUTS};
use calbench::calibrate::task::socket::{load_socket_task, SocketTask};
use calbench::calibrate::task::{task_file, unconverged_warning, Task, TaskEntry};
use calbench::identify::MethodSpec;
use calbench::report::identified::IdentifyRecord;
use calbench::report::practice::additions;
use calbench::report::write_identified_with;

use crate::errors::{err_spelled, setting, task_spell};
use crate::identify::method_spec;
use crate::robot::PyRobot;
use crate::study::Interrupted;
use calbench::robot::Robot;

/// A library error as `calbench.task` raises it: its options spelled by [`task_spell`].
fn task_err(e: calbench::Error) -> PyErr {
    err_spelled(e, task_spell)
}

/// Runs the task `task` (a name under `tasks/` or a task file) with `method`: a method's
/// name, or a Python function given a `Problem` (as `run`'s `methods`), entered as
/// `python:<name>`; `options` the method's options (the keys of a scenario's `[[methods]]`
/// entry, as `calbench task --set`), for a calbench method. Returns `task` (the text of
/// `task.json`), `record` (of `identified.json`), the compensated `robot` and `warning` (what
/// `calbench task` warns of an unconverged identification, or None); writes the folder `out`
/// if given.
#[pyfunction]
#[pyo3(signature = (task, method, models = None, name = None, out = None, options = None))]
pub(crate) fn task<'py>(
    py: Python<'py>,
    task: PathBuf,
    method: Bound<'py, PyAny>,
    models: Option<Vec<String>>,
    name: Option<String>,
    out: Option<PathBuf>,
    options: Option<Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    if task.as_os_str().is_empty() {
        let why = "is empty: give a task's name (`tasks/NAME.toml`) or the path of a task file";
        return Err(setting("task", why));
    }
    let path = task_file(&task).map_err(task_err)?;
    if let Some(t) = load_socket_task(&path).map_err(task_err)? {
        return socket_task(py, &t, (method, options.as_ref()), models, out);
    }
    let t = Task::load(&path).map_err(task_err)?;
    if let Some(out) = &out {
        guard(out, &OUTPUTS, t.head.inputs(), t.data_files())?;
    }
    let stop = Interrupted::default();
    let (spec, method_name, entrant) = if let Ok(m) = method.extract::<String>() {
        let spec = method_spec(&m, options.as_ref(), None)?;
        (spec, m, "calbench".to_string())
    } else if options.is_some() {
        let why = "a method written in Python takes no options (its own arguments are its own)";
        return Err(setting("options", why));
    } else if method.is_callable() {
        // Its name as `task.json` enters it (`python:NAME`): given, or the function's own.
        let own = method
            .getattr("__name__")
            .and_then(|n| n.extract::<String>());
        let label = match (name, own) {
            (Some(n), _) | (None, Ok(n)) => n,
            (None, Err(_)) => {
                let why = "the method has no `__name__` (a functools.partial, a callable \
                           object): give it a name with `name=`";
                return Err(setting("name", why));
            }
        };
        if label.trim().is_empty() {
            return Err(setting("name", "the method's name is empty"));
        }
        if let Some(why) = calbench::identify::registry::hidden_label(&label) {
            return Err(setting("name", format!("{label:?} {why}")));
        }
        let f = crate::study::python_method(&label, method.unbind(), &stop);
        let spec = MethodSpec::external(&label, f);
        (spec, label.clone(), format!("python:{label}"))
    } else {
        return Err(setting(
            "method",
            "expected a method's name or a Python function",
        ));
    };
    let given = models
        .unwrap_or_default()
        .iter()
        .map(|m| m.parse::<Model>().map_err(|e| setting("models", e)))
        .collect::<PyResult<Vec<_>>>()?;
    let entry = py
        .detach(|| {
            // The candidates as `calbench task` decides them: the caller's, else the task's
            // own `[models]` (docs/formats.md § 9.1), else `kinematic`.
            let (request, val, mut models) = t.entry_request(spec, &given)?;
            if !given.is_empty() {
                models.fixed_by = "caller";
            }
            let IdentifyOutcome::Tracker(o) = request.run()? else {
                return Err(calbench::Error::Compute(
                    "a task's data are a tracker's measurements".into(),
                ));
            };
            let entry = TaskEntry {
                task: &t,
                method: method_name,
                models: &models,
                entrant,
            };
            let j = entry.json(&o, &val)?;
            let files = t.head.entry_files(&j.to_value(), &o)?;
            let text = files[0].1.clone();
            if let Some(out) = &out {
                let rec = IdentifyRecord::of(&o, None);
                write_identified_with(out, &rec, &additions(&o), &files)?;
            }
            let record = serde_json::to_string(&o.record)
                .map_err(|e| calbench::Error::Compute(e.to_string()))?;
            let warning = unconverged_warning(&o.record);
            let mut kept = spelled(o.warnings());
            if o.kernel.is_some() {
                kept.push(crate::identify::KERNEL_NOT_IN_ROBOT.into());
            }
            Ok(((text, record, o.compensated()), (warning, kept)))
        })
        .map_err(task_err);
    let (entry, warning) = stop.raise(entry)?;
    result(py, entry, warning)
}

/// The warnings `calbench task` prints, the options spelled as keywords.
fn spelled(warnings: Vec<calbench::error::Said>) -> Vec<String> {
    warnings
        .into_iter()
        .map(|w| w.spell(crate::errors::spell))
        .collect()
}

/// The dict `calbench.task` returns: with `warning` (an unconverged identification's) and
/// `kept` (the other warnings `calbench task` prints).
fn result(
    py: Python<'_>,
    (task, record, robot): (String, String, Robot),
    (warning, kept): (Option<String>, Vec<String>),
) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("task", task)?;
    d.set_item("record", record)?;
    d.set_item("robot", PyRobot { inner: robot })?;
    d.set_item("warning", warning)?;
    d.set_item("kept", kept)?;
    Ok(d)
}

/// Refuses an output folder `out` that would destroy a task's `inputs` (under one of the
/// `names` its entry writes) or lie beside its data files.
fn guard(
    out: &Path,
    names: &[&str],
    inputs: Vec<&Path>,
    data: impl IntoIterator<Item = impl AsRef<Path>>,
) -> PyResult<()> {
    calbench::report::guard::guard_out(out, "out", names, inputs).map_err(task_err)?;
    calbench::report::guard::guard_data_folder(out, "out", data).map_err(task_err)
}

/// [`task`] on a socket task (docs/formats.md § 9.4): the entry `calbench task` runs
/// ([`SocketTask::entry`]), its folder the command line's, byte for byte. A socket task
/// identifies the kinematic model with a calbench method by name.
fn socket_task<'py>(
    py: Python<'py>,
    t: &SocketTask,
    (method, options): (Bound<'py, PyAny>, Option<&Bound<'py, PyDict>>),
    models: Option<Vec<String>>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let path = t.head.path.display();
    let Ok(name) = method.extract::<String>() else {
        let why = format!("{path} is a socket task, identified by a calbench method by name");
        return Err(setting("method", why));
    };
    if models.is_some_and(|m| !m.is_empty()) {
        let why = format!("{path} is a socket task, which identifies the kinematic model only");
        return Err(setting("models", why));
    }
    if let Some(out) = &out {
        guard(out, &SOCKET_OUTPUTS, t.head.inputs(), t.data_files())?;
    }
    let spec = method_spec(&name, options, None)?;
    let (entry, warning) = py
        .detach(|| {
            let e = t.entry(spec, &name)?;
            let files = t.head.files(&e.record.to_value())?;
            if let Some(out) = &out {
                calbench::report::write_kind(out, &e.outcome.record, &e.robot, &files)?;
            }
            let record = serde_json::to_string(&e.outcome.record)
                .map_err(|e| calbench::Error::Compute(e.to_string()))?;
            let [(_, json), _] = files;
            let warning = unconverged_warning(&e.outcome.record);
            Ok((
                (json, record, e.robot),
                (warning, spelled(e.outcome.warnings())),
            ))
        })
        .map_err(task_err)?;
    result(py, entry, warning)
}
