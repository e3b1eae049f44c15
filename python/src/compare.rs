//! `calbench.compare(a, b)`: run B against run A by the rules of `calbench check`, through
//! the library's comparison (the one `calbench compare` writes its pages from).

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use calbench::report::html::compare::{Comparison, Side};

use crate::errors::{err, nonempty};

/// The comparison of run `b` with run `a` (folders or `summary.json` files) at `tolerance`:
/// a dict with `metrics` (one dict per compared metric, in A's order), `only_in_a`,
/// `only_in_b`, `regressions`, `verdict` and `scenario_note`.
#[pyfunction]
#[pyo3(signature = (a, b, tolerance = 0.05))]
pub(crate) fn compare<'py>(
    py: Python<'py>,
    a: PathBuf,
    b: PathBuf,
    tolerance: f64,
) -> PyResult<Bound<'py, PyDict>> {
    calbench::analysis::regression::checked_tolerance(tolerance, "tolerance").map_err(err)?;
    let (a, b) = (nonempty("a", a)?, nonempty("b", b)?);
    let c = py
        .detach(|| -> calbench::Result<Comparison> {
            Comparison::new(Side::read(&a)?, Side::read(&b)?, tolerance)
        })
        .map_err(err)?;
    let metrics = PyList::empty(py);
    for m in c.all() {
        let row = PyDict::new(py);
        let r = &m.metric;
        row.set_item("entry", &r.entry)?;
        row.set_item("metric", &r.metric)?;
        row.set_item("a", r.baseline)?;
        row.set_item("b", r.value)?;
        row.set_item("diff", r.value - r.baseline)?;
        row.set_item("status", m.status.as_str())?;
        let [lo, hi] = m.diff_ci.unwrap_or([f64::NAN; 2]);
        row.set_item("diff_ci_lo", lo)?;
        row.set_item("diff_ci_hi", hi)?;
        row.set_item("p_value", m.p_value)?;
        row.set_item("p_holm", m.p_holm)?;
        row.set_item("paired", m.paired)?;
        row.set_item("trials_needed", m.trials_needed)?;
        row.set_item("higher_is_better", m.higher_is_better)?;
        metrics.append(row)?;
    }
    let out = PyDict::new(py);
    out.set_item("metrics", metrics)?;
    out.set_item("only_in_a", c.only_in(0))?;
    out.set_item("only_in_b", c.only_in(1))?;
    out.set_item("regressions", c.regressions())?;
    out.set_item("verdict", c.verdict())?;
    out.set_item("scenario_note", c.scenario_note())?;
    Ok(out)
}
