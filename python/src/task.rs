//! `calbench.task`: one entry of a fixed real-data task (docs/formats.md § 9), by a calbench
//! method or by a method written in Python (the open division), through the identify
//! pipeline; the entry's `task.json` text, and its folder when `out` is given.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use calbench::calibrate::cv::Model;
use calbench::calibrate::pipeline::IdentifyOutcome;
use calbench::calibrate::task::{task_path, Task, TaskEntry};
use calbench::identify::{method_by_name, MethodSpec};
use calbench::report::identified::IdentifyRecord;
use calbench::report::practice::additions;
use calbench::report::write_identified_with;

use crate::errors::{err, setting, ComputeError};
use crate::robot::PyRobot;

/// Runs the task `task` (a name under `tasks/` or a task file) with `method`: a method's
/// name, or a Python function given a `Problem` (as `run`'s `methods`), entered as
/// `python:<name>`. Returns `task` (the text of `task.json`), `record` (of
/// `identified.json`) and the compensated `robot`; writes the folder `out` if given.
#[pyfunction]
#[pyo3(signature = (task, method, models = None, name = None, out = None))]
pub(crate) fn task<'py>(
    py: Python<'py>,
    task: &str,
    method: Bound<'py, PyAny>,
    models: Option<Vec<String>>,
    name: Option<String>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let path = task_path(task);
    let t = Task::load(&path).map_err(err)?;
    if let Some(out) = &out {
        calbench::report::guard::guard_out(
            out,
            "out",
            &["identified.json", "task.json"],
            t.inputs(),
        )
        .map_err(err)?;
        calbench::report::guard::guard_data_folder(out, "out", t.data_files()).map_err(err)?;
    }
    let (spec, method_name, entrant) = if let Ok(m) = method.extract::<String>() {
        (method_by_name(&m).map_err(err)?, m, "calbench".to_string())
    } else if method.is_callable() {
        let label = match name {
            Some(n) => n,
            None => method.getattr("__name__")?.extract()?,
        };
        let f = crate::study::python_method(method.unbind());
        let spec = MethodSpec::external(&label, f);
        (spec, label.clone(), format!("python:{label}"))
    } else {
        return Err(setting(
            "method",
            "expected a method's name or a Python function",
        ));
    };
    let candidates = match models {
        None => vec![Model::KINEMATIC],
        Some(v) if v.is_empty() => vec![Model::KINEMATIC],
        Some(v) => v
            .iter()
            .map(|m| m.parse::<Model>().map_err(|e| setting("models", e)))
            .collect::<PyResult<Vec<_>>>()?,
    };
    let (json, record, robot) = py
        .detach(|| {
            let (request, val) = t.request(spec, &candidates)?;
            let IdentifyOutcome::Tracker(o) = request.run()? else {
                return Err(calbench::Error::Compute(
                    "a task's data are a tracker's measurements".into(),
                ));
            };
            let entry = TaskEntry {
                task: &t,
                method: method_name,
                candidates: &candidates,
                entrant,
                origin: None,
            };
            let j = entry.json(&o, &val)?;
            let files = entry.files(&j)?;
            let text = files[0].1.clone();
            if let Some(out) = &out {
                let rec = IdentifyRecord::of(&o, None);
                write_identified_with(out, &rec, &additions(&o), &files)?;
            }
            let record = serde_json::to_string(&o.record)
                .map_err(|e| calbench::Error::Compute(e.to_string()))?;
            Ok((text, record, o.compensated()))
        })
        .map_err(|e: calbench::Error| match e {
            calbench::Error::Compute(m) => ComputeError::new_err(m),
            e => err(e),
        })?;
    let d = PyDict::new(py);
    d.set_item("task", json)?;
    d.set_item("record", record)?;
    d.set_item("robot", PyRobot { inner: robot })?;
    Ok(d)
}
