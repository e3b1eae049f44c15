//! Python values and numpy arrays into the library's types, and back.

use std::path::{Path, PathBuf};

use nalgebra::DMatrix;
use numpy::ndarray::{Array2, ShapeBuilder};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyComplex, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use calbench::measurement::csv::{measurements_from_arrays, ArrayKeys};
use calbench::measurement::Measurements;
use calbench::numeric::Real;
use calbench::robot::Robot;
use calbench::study::kind::AnyScenario;
use calbench::study::scenario::Scenario;

use crate::errors::{err, nonempty, setting};

/// `a` as a 2-D float64 array: a float64 array as it is, anything numpy reads as real
/// numbers converted; bool and complex arrays, and what is not numbers, refused naming `key`.
pub(crate) fn float_array2<'py>(
    key: &str,
    a: &Bound<'py, PyAny>,
) -> PyResult<PyReadonlyArray2<'py, f64>> {
    if let Some(v) = a
        .extract::<PyReadonlyArray2<'py, f64>>()
        .ok()
        .filter(|_| !masked(a))
    {
        return Ok(v);
    }
    float64(key, a)?
        .extract::<PyReadonlyArray2<'py, f64>>()
        .map_err(|_| setting(key, "expected a 2-D array (N, n)"))
}

/// `a` as a float64 numpy array of any shape, anything numpy reads as real numbers converted;
/// bool and complex arrays, and what is not numbers, refused naming `key`.
pub(crate) fn float64<'py>(key: &str, a: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let (raw, unreal) =
        as_numpy(a).map_err(|e| setting(key, format!("not an array of numbers ({e})")))?;
    if let Some((what, _)) = unreal {
        return Err(setting(
            key,
            format!("a {what} array is not taken; give real numbers"),
        ));
    }
    let float = a.py().import("numpy")?.getattr("float64")?;
    let values = missing_as_nan(raw)?
        .call_method1("astype", (float,))
        .map_err(|e| setting(key, format!("not an array of numbers ({e})")))?;
    masked_as_nan(a, values)
}

/// The `values` of a numpy masked array `a` with its masked cells as NaN, which the arrays'
/// checks refuse naming the row and the column, as they refuse a missing value
/// ([`missing_as_nan`]); numpy reads a masked array as the values under its mask, which had
/// been taken as they were. Any other array's `values` as they are.
fn masked_as_nan<'py>(
    a: &Bound<'py, PyAny>,
    values: Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    if !masked(a) {
        return Ok(values);
    }
    let numpy = a.py().import("numpy")?;
    let mask = numpy.getattr("ma")?.call_method1("getmaskarray", (a,))?;
    numpy.call_method1("where", (mask, f64::NAN, values))
}

/// Whether `a` is a numpy masked array, which a float64 array's reader would take as the
/// values under its mask ([`masked_as_nan`]).
pub(crate) fn masked(a: &Bound<'_, PyAny>) -> bool {
    let ma = a.py().import("numpy").and_then(|n| n.getattr("ma"));
    ma.and_then(|ma| ma.call_method1("isMaskedArray", (a,))?.extract::<bool>())
        .unwrap_or(false)
}

/// An object array's missing values (`None`, pandas' `pd.NA` of a nullable column) as NaN,
/// which the arrays' checks refuse naming the row and the column, as they refuse a NaN or a
/// `None` numpy reads as NaN; `pd.NA` had been refused by float conversion, naming neither.
/// Any other array as it is.
fn missing_as_nan<'py>(raw: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    if raw.getattr("dtype")?.getattr("kind")?.extract::<String>()? != "O" {
        return Ok(raw);
    }
    let py = raw.py();
    let nan = PyFloat::new(py, f64::NAN).into_any();
    let cells = raw
        .call_method0("ravel")?
        .try_iter()?
        .map(|v| {
            let v = v?;
            let missing = v.is_none() || v.get_type().name()? == "NAType";
            Ok(if missing { nan.clone() } else { v })
        })
        .collect::<PyResult<Vec<_>>>()?;
    let numpy = py.import("numpy")?;
    let flat = numpy.call_method1(
        "array",
        (PyList::new(py, cells)?, numpy.getattr("object_")?),
    )?;
    flat.call_method1("reshape", (raw.getattr("shape")?,))
}

/// Values numpy reads that are not real numbers, though it would convert them: what they are
/// and the dtype's name (`("bool", "bool")`, `("complex", "complex128")`, `("text", "str64")`).
pub(crate) type Unreal = Option<(&'static str, String)>;

/// `a` as numpy reads it (`numpy.asarray`) and whether its values are not real numbers
/// ([`Unreal`]): bools, complex numbers, dates and text (`"10"` would convert to 10, a
/// column of names to an error about one of them), whether the array is of them or only holds
/// one among numbers: an object array (a DataFrame with a bool column), or nested lists that
/// numpy would read as numbers (`[[True, 0.5]]` as `[[1.0, 0.5]]`). A Python error when numpy
/// cannot read it.
pub(crate) fn as_numpy<'py>(a: &Bound<'py, PyAny>) -> PyResult<(Bound<'py, PyAny>, Unreal)> {
    let numpy = a.py().import("numpy")?;
    let raw = numpy.call_method1("asarray", (a,))?;
    let dtype = raw.getattr("dtype")?;
    let kind = dtype.getattr("kind")?.extract::<String>()?;
    let what = match kind.as_str() {
        "b" => Some("bool"),
        "c" => Some("complex"),
        "U" | "S" => Some("text"),
        "M" | "m" => Some("date or time"),
        "O" => held(&raw)?,
        // Lists and tuples numpy read as numbers, each item as it was given.
        _ if a.is_instance_of::<PyList>() || a.is_instance_of::<PyTuple>() => {
            let object = numpy.getattr("object_")?;
            held(&numpy.call_method1("asarray", (a, object))?)?
        }
        _ => None,
    };
    let Some(what) = what else {
        return Ok((raw, None));
    };
    let name: String = dtype.getattr("name")?.extract()?;
    Ok((raw, Some((what, name))))
}

/// What an object array holds anywhere that is no real number: text (a string or bytes), a
/// bool (Python's or numpy's) or a complex number.
fn held(raw: &Bound<'_, PyAny>) -> PyResult<Option<&'static str>> {
    let complex = raw.py().import("numpy")?.getattr("complexfloating")?;
    for v in raw.call_method0("ravel")?.try_iter()? {
        let v = v?;
        if v.is_instance_of::<PyString>() || v.is_instance_of::<pyo3::types::PyBytes>() {
            return Ok(Some("text"));
        }
        if is_bool(&v)? {
            return Ok(Some("bool"));
        }
        if v.is_instance_of::<PyComplex>() || v.is_instance(&complex)? {
            return Ok(Some("complex"));
        }
    }
    Ok(None)
}

/// `value` as a float64 numpy array (the Python half's `_numbers`): [`float64`].
#[pyfunction]
#[pyo3(name = "_real_array")]
pub(crate) fn real_array<'py>(
    name: &str,
    value: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    float64(name, value)
}

/// The rows of a (N, k) array.
pub(crate) fn rows(a: &PyReadonlyArray2<'_, f64>) -> Vec<Vec<Real>> {
    a.as_array().outer_iter().map(|r| r.to_vec()).collect()
}

/// The rows of `q` (N, n) as joint values of `robot` in its internal units: refused naming `q`
/// and its shape when n is not the robot's joint count, and each value checked
/// ([`Robot::q_internal`]; an error names `q`, the row and the column, as the other arrays').
pub(crate) fn joint_rows(robot: &Robot, q: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<Vec<Real>>> {
    let (n, k) = q.as_array().dim();
    if k != robot.dof() {
        let dof = robot.dof();
        return Err(setting(
            "q",
            format!("expected shape (N, {dof}), got ({n}, {k})"),
        ));
    }
    rows(q)
        .iter()
        .enumerate()
        .map(|(i, v)| {
            v.iter()
                .enumerate()
                .map(|(j, &x)| {
                    robot
                        .q_internal(j, x)
                        .map_err(|m| setting("q", format!("row {i}, column q{}: {m}", j + 1)))
                })
                .collect()
        })
        .collect()
}

/// The rows of a (N, 3) array as points.
pub(crate) fn points3(key: &str, a: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<[Real; 3]>> {
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
pub(crate) fn quaternions(key: &str, a: &Bound<'_, PyAny>) -> PyResult<Vec<[Real; 4]>> {
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
pub(crate) fn measurements(
    robot: &Robot,
    keys: ArrayKeys<'_>,
    q: &PyReadonlyArray2<'_, f64>,
    points: &PyReadonlyArray2<'_, f64>,
    rotations: Option<&Bound<'_, PyAny>>,
    sigma: Option<&PyReadonlyArray1<'_, f64>>,
    payload: Option<&PyReadonlyArray1<'_, f64>>,
) -> PyResult<Measurements> {
    // An array's shape is refused naming the argument, or its place in the one that gave it.
    let key = |array: &str| keys.of(array);
    let quats = rotations
        .map(|r| quaternions(&key("rotations"), r))
        .transpose()?;
    let sigma = sigma.map(|s| s.as_array().to_vec());
    let payload = payload.map(|s| s.as_array().to_vec());
    measurements_from_arrays(
        robot,
        keys,
        &rows(q),
        &points3(&key("points"), points)?,
        quats.as_deref(),
        sigma.as_deref(),
        payload.as_deref(),
    )
    .map_err(err)
}

/// Whether `v` is a bool: Python's, or numpy's `bool_` (which is not a Python `bool`).
pub(crate) fn is_bool(v: &Bound<'_, PyAny>) -> PyResult<bool> {
    if v.is_instance_of::<PyBool>() {
        return Ok(true);
    }
    let numpy = v.py().import("numpy")?;
    v.is_instance(&numpy.getattr("bool_")?)
}

/// `v` as a `T` (a string, a path: a `str` or an `os.PathLike`), refused naming `key` and
/// saying `what` it should be otherwise (where PyO3 would raise a bare `TypeError`).
pub(crate) fn typed_arg<'a, 'py, T>(key: &str, v: &'a Bound<'py, PyAny>, what: &str) -> PyResult<T>
where
    T: FromPyObject<'a, 'py>,
{
    v.extract().map_err(|_| {
        // A str refused only for a lone surrogate says so; any other value, what it should be.
        match v.cast::<PyString>().map(|s| utf8(key, s)) {
            Ok(Err(e)) => e,
            _ => setting(key, format!("expected {what}, got {}", type_name(v))),
        }
    })
}

/// `s` as a Rust string, refused naming `key` when UTF-8 cannot hold it: a lone surrogate,
/// as `os.listdir` or `sys.argv` give for a name that is not UTF-8 (it had surfaced as a
/// bare `UnicodeEncodeError`).
fn utf8(key: &str, s: &Bound<'_, PyString>) -> PyResult<String> {
    s.extract::<String>().map_err(|_| {
        let shown = s.repr().map_or_else(|_| "it".into(), |r| r.to_string());
        setting(
            key,
            format!(
                "{shown} holds a lone surrogate UTF-8 cannot hold (a name read from bytes that \
                 are not UTF-8?)"
            ),
        )
    })
}

/// `v` as a bool (Python's or numpy's), refused naming `key` otherwise rather than read by
/// its truth value.
pub(crate) fn flag_arg(key: &str, v: &Bound<'_, PyAny>) -> PyResult<bool> {
    if is_bool(v)? {
        return v.is_truthy();
    }
    Err(setting(
        key,
        format!("expected True or False, got {}", type_name(v)),
    ))
}

/// The name of `v`'s type, for a refusal.
fn type_name(v: &Bound<'_, PyAny>) -> String {
    v.get_type()
        .name()
        .map_or_else(|_| "an object".into(), |n| n.to_string())
}

/// `v` as a real number (a Python or numpy float or integer); `None` for a bool (`True`
/// would read as 1), a complex, Python's or numpy's (whose `float` drops the imaginary part
/// with only a warning), and any other object. An integer beyond a float's range (`10**400`)
/// is the infinity of its sign, so that its refusal says it is not finite rather than not a
/// number.
pub(crate) fn real_number(v: &Bound<'_, PyAny>) -> PyResult<Option<f64>> {
    let complex = v.is_instance_of::<PyComplex>()
        || v.is_instance(&v.py().import("numpy")?.getattr("complexfloating")?)?;
    if is_bool(v)? || complex {
        return Ok(None);
    }
    if let Ok(f) = v.extract::<f64>() {
        return Ok(Some(f));
    }
    if v.is_instance_of::<PyInt>() {
        let sign = if v.lt(0)? { -1.0 } else { 1.0 };
        return Ok(Some(sign * f64::INFINITY));
    }
    Ok(None)
}

/// The deepest nesting of lists and dicts a scenario dict or the options may have: a TOML
/// file of calbench's nests a few levels; a list or dict that contains itself, or one nested
/// thousands deep, overflowed the stack (a segmentation fault, no exception).
const MAX_DEPTH: usize = 64;

/// A Python value `depth` lists or dicts down as a TOML value (scenario dicts, method
/// options). numpy's scalars are the TOML values of their Python twins: an integer
/// (`np.int64`) stays an integer, a `np.bool_` a boolean; a numpy array is the list of its
/// values; a path (`pathlib.Path`) its text.
fn nested_value(key: &str, v: &Bound<'_, PyAny>, depth: usize) -> PyResult<toml::Value> {
    if depth > MAX_DEPTH {
        let msg = format!(
            "nests lists or dicts more than {MAX_DEPTH} deep (a list or dict that contains \
             itself?)"
        );
        return Err(setting(key.split('[').next().unwrap_or(key), msg));
    }
    if is_bool(v)? {
        return Ok(toml::Value::Boolean(v.is_truthy()?));
    }
    if v.is_instance(&v.py().import("numpy")?.getattr("ndarray")?)? {
        return nested_value(key, &v.call_method0("tolist")?, depth);
    }
    // Python's int, and what stands for one (`__index__`: numpy's integers).
    if v.is_instance_of::<PyInt>() || (!v.is_instance_of::<PyFloat>() && v.hasattr("__index__")?) {
        return Ok(toml::Value::Integer(v.extract().map_err(|_| {
            setting(
                key,
                "must be from -2^63 to 2^63 - 1, the integers a scenario file holds",
            )
        })?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(toml::Value::String(utf8(key, s)?));
    }
    // A path (`pathlib.Path`, any `os.PathLike` of text) is the string a file would hold.
    if v.is_instance(&v.py().import("os")?.getattr("PathLike")?)? {
        let text = v.py().import("os")?.getattr("fspath")?.call1((v,))?;
        if let Ok(s) = text.cast::<PyString>() {
            return Ok(toml::Value::String(utf8(key, s)?));
        }
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(toml::Value::Table(nested_table(key, d, depth + 1)?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: Vec<toml::Value> = v
            .try_iter()?
            .enumerate()
            .map(|(i, x)| nested_value(&format!("{key}[{i}]"), &x?, depth + 1))
            .collect::<PyResult<_>>()?;
        return Ok(toml::Value::Array(items));
    }
    // numpy scalars and other numbers.
    if let Some(f) = real_number(v)? {
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

/// A Python dict as a TOML table ([`nested_value`]).
pub(crate) fn toml_table(key: &str, d: &Bound<'_, PyDict>) -> PyResult<toml::Table> {
    nested_table(key, d, 0)
}

/// [`toml_table`] of a dict `depth` lists or dicts down.
fn nested_table(key: &str, d: &Bound<'_, PyDict>, depth: usize) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        // A scenario dict's own keys have no path yet: the setting is the scenario.
        let whose = if key.is_empty() { "scenario" } else { key };
        let k: String = if let Ok(k) = k.cast::<PyString>() {
            utf8(whose, k)?
        } else {
            let got = k.repr().map_or_else(|_| "?".into(), |r| r.to_string());
            return Err(setting(
                whose,
                format!("every key must be a string, got {got}"),
            ));
        };
        let dotted = if key.is_empty() {
            k.clone()
        } else {
            format!("{key}.{k}")
        };
        t.insert(k, nested_value(&dotted, &v, depth)?);
    }
    Ok(t)
}

/// How the refusals of a scenario dict's values would name it as a file.
pub(crate) const DICT: &str = "<scenario dict>";

/// A refusal of a scenario dict's value as a `SettingError` naming its key (docs/python.md
/// § The API: a dict is no file); any other error (of a robot file it names) as it is.
fn dict_err(e: calbench::Error) -> PyErr {
    err(e.as_setting(Path::new(DICT)))
}

/// A scenario: a path to its TOML file, or a dict shaped like the file.
pub(crate) fn scenario_of(scenario: &Bound<'_, PyAny>) -> PyResult<Scenario> {
    if let Ok(d) = scenario.cast::<PyDict>() {
        let table = toml_table("", d)?;
        return Scenario::from_toml_table(table, Path::new(DICT)).map_err(dict_err);
    }
    let path: PathBuf = scenario
        .extract()
        .map_err(|_| setting("scenario", "expected a path to a scenario file or a dict"))?;
    Scenario::load(&nonempty("scenario", path)?).map_err(err)
}

/// A scenario of any kind ([`AnyScenario`]): a path to a scenario file, or a dict shaped like
/// one.
pub(crate) fn any_scenario_of(scenario: &Bound<'_, PyAny>) -> PyResult<AnyScenario> {
    if let Ok(d) = scenario.cast::<PyDict>() {
        let text = toml::to_string(&toml_table("", d)?)
            .map_err(|e| setting("scenario", format!("cannot be written as TOML: {e}")))?;
        return AnyScenario::parse(&text, Some(Path::new(DICT))).map_err(dict_err);
    }
    let path: PathBuf = scenario
        .extract()
        .map_err(|_| setting("scenario", "expected a path to a scenario file or a dict"))?;
    AnyScenario::load(&nonempty("scenario", path)?).map_err(err)
}

/// A column-major matrix as a (rows, cols) numpy array.
pub(crate) fn matrix<'py>(py: Python<'py>, m: &DMatrix<Real>) -> Bound<'py, PyAny> {
    Array2::from_shape_vec((m.nrows(), m.ncols()).f(), m.as_slice().to_vec())
        .map(|a| a.into_pyarray(py).into_any())
        .unwrap_or_else(|_| PyArray1::<f64>::zeros(py, 0, false).into_any())
}

/// A validation measurement: (q, points, rotations or None, payload or None).
pub(crate) type Validation<'py> = (
    PyReadonlyArray2<'py, f64>,
    PyReadonlyArray2<'py, f64>,
    Option<Bound<'py, PyAny>>,
    Option<PyReadonlyArray1<'py, f64>>,
);
