//! `calbench.Robot`.

use numpy::ndarray::{Array2, Array3};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use calbench::numeric::{Frame, Real};
use calbench::robot::loaded::LoadedFk;
use calbench::robot::{builtin, Coupling, Param, Robot};

use crate::convert::{flag_arg, float_array2, joint_rows, typed_arg};
use crate::errors::{err, nonempty, setting, LimitWarning};

/// Warns (`calbench.LimitWarning`) of the rows of `qs` (internal units) outside the joint
/// limits of `robot`, naming the first three (`q[0], q[4], q[7] and 2 more rows`) and the
/// first row's joint outside, its value and its limits (as `calbench fk` does).
fn warn_outside_limits(py: Python<'_>, robot: &Robot, qs: &[Vec<Real>]) -> PyResult<()> {
    let outside: Vec<usize> = (0..qs.len())
        .filter(|&i| !robot.within_limits(&qs[i]))
        .collect();
    if outside.is_empty() {
        return Ok(());
    }
    let mut rows: Vec<String> = outside.iter().take(3).map(|i| format!("q[{i}]")).collect();
    match outside.len() - rows.len() {
        0 => {}
        1 => rows.push("1 more row".into()),
        more => rows.push(format!("{more} more rows")),
    }
    let last = rows.pop().unwrap_or_default();
    let rows = if rows.is_empty() {
        last
    } else {
        format!("{} and {last}", rows.join(", "))
    };
    // The first row's joint outside, in the words `calbench fk` warns with.
    let first = outside[0];
    let joint = robot.outside_limits(&qs[first]).unwrap_or_default();
    let msg = format!(
        "{} ({rows}): in q[{first}], {joint}",
        calbench::robot::OUTSIDE_LIMITS
    );
    let msg = std::ffi::CString::new(msg).map_err(|e| setting("q", e.to_string()))?;
    PyErr::warn(py, &py.get_type::<LimitWarning>(), &msg, 1)
}

/// A robot model with its nominal parameters (lengths in mm, angles in the robot's unit
/// where joint values are concerned, as in the command line).
#[pyclass(name = "Robot", module = "calbench", frozen)]
#[derive(Clone)]
pub struct PyRobot {
    pub(crate) inner: Robot,
}

#[pymethods]
impl PyRobot {
    /// The built-in robot `name` (`calbench robots` lists them).
    #[staticmethod]
    fn builtin(name: &Bound<'_, PyAny>) -> PyResult<PyRobot> {
        let name: String = typed_arg("name", name, "a built-in robot's name")?;
        match builtin::builtin(&name) {
            Some(b) => Ok(PyRobot { inner: (b.build)() }),
            None => Err(setting(
                "name",
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

    /// A robot file: TOML (docs/formats.md) or URDF; `tip` and `base`: the links a URDF's
    /// chain ends and starts at (`--tip`, `--base`).
    #[staticmethod]
    #[pyo3(signature = (path, tip = None, base = None))]
    fn from_file(
        path: &Bound<'_, PyAny>,
        tip: Option<&Bound<'_, PyAny>>,
        base: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyRobot> {
        let path = nonempty("path", typed_arg("path", path, "the path of a robot file")?)?;
        let link = |key: &str, v: Option<&Bound<'_, PyAny>>| {
            v.filter(|t| !t.is_none())
                .map(|t| typed_arg::<String>(key, t, "the name of a URDF link"))
                .transpose()
        };
        let (tip, base) = (link("tip", tip)?, link("base", base)?);
        if !path.is_file() {
            // A folder is refused as the command line refuses it (reading it fails: "Is a
            // directory"); only a path that is not there is "no such robot file".
            let why = match std::fs::metadata(&path) {
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                    std::io::Error::new(e.kind(), "no such robot file")
                }
                Err(e) => e,
                Ok(m) if m.is_dir() => std::fs::read(&path)
                    .err()
                    .unwrap_or_else(|| std::io::Error::other("a folder, not a robot file")),
                Ok(_) => std::io::Error::other("not a regular file, so not a robot file"),
            };
            return Err(err(calbench::Error::io(&path, why)));
        }
        let chain = calbench::robot::urdf::UrdfChain { base, tip };
        builtin::load_chain(&path, &chain)
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

    /// The nominal value of each parameter (mm, rad): `(name, value)` pairs in flat-vector
    /// order, as `parameter_names()` lists them; `dict(robot.parameters())` maps them by name.
    fn parameters(&self) -> Vec<(String, Real)> {
        self.inner
            .params()
            .into_iter()
            .map(|p| (p.to_string(), self.inner.get(p)))
            .collect()
    }

    /// Forward kinematics: joint values `q` (N, n) in the robot's units → tool points
    /// (N, 3) in mm, or with `pose=True` homogeneous tool frames (N, 4, 4), of the robot's
    /// whole model with no payload (its joint-angle harmonics, gravity basis and compliances
    /// under its own weight included, as `calbench fk`). Rows outside the
    /// joint limits are computed and warned of (`calbench.LimitWarning`, naming them), as
    /// `calbench fk` warns.
    #[pyo3(signature = (q, pose = None))]
    fn fk<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        pose: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let pose = pose.map(|p| flag_arg("pose", p)).transpose()? == Some(true);
        let q = float_array2("q", q)?;
        let r = &self.inner;
        let qs = joint_rows(r, &q)?;
        warn_outside_limits(py, r, &qs)?;
        let model = LoadedFk::new(r);
        let frames: Vec<Frame> = qs
            .iter()
            .map(|v| model.at(v, 0.0))
            .collect::<calbench::error::Result<_>>()
            .map_err(err)?;
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
    fn with_errors(&self, errors: &Bound<'_, PyAny>) -> PyResult<PyRobot> {
        let errors = errors
            .cast::<PyDict>()
            .map_err(|_| setting("errors", "expected a dict parameter name → error (mm, rad)"))?;
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
            let e: Real = crate::convert::real_number(&v)?
                .ok_or_else(|| setting(&format!("errors.{name}"), "must be a number"))?;
            if !e.is_finite() {
                return Err(setting(&format!("errors.{name}"), "must be finite"));
            }
            list.push((p, e));
        }
        // The robot with its errors must stay a robot model (lengths within 1 km, angles
        // within a turn), as a robot file must.
        let inner = self.inner.with_errors(&list);
        if let Err(issue) = inner.check() {
            let why = format!("gives {}: {}", issue.place, issue.msg);
            return Err(setting("errors", why));
        }
        Ok(PyRobot { inner })
    }

    /// The robot as a robot file (TOML), as `calbench identify` writes `robot.toml`.
    fn to_toml(&self) -> String {
        calbench::robot::robot_to_toml(&self.inner)
    }

    /// The robot of a robot file's text (TOML, docs/formats.md § 3), as `to_toml` writes
    /// it; a refusal names the line and key as for a file, the file called `text`.
    #[staticmethod]
    fn from_toml(text: &Bound<'_, PyAny>) -> PyResult<PyRobot> {
        let text: String = typed_arg("text", text, "a robot file's text (TOML)")?;
        calbench::robot::parse_robot_file(&text, std::path::Path::new("text"))
            .map(|inner| PyRobot { inner })
            .map_err(err)
    }

    /// Two robots are equal when every part of their models is: name, convention, joints
    /// and limits, parameter values to the bit, units, coupling, β joints and link masses.
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyRobot>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    /// The hash of its name and parameter values (−0 as 0): equal robots hash alike (a robot
    /// is frozen).
    fn __hash__(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        self.inner.name.hash(&mut h);
        for v in &self.inner.values {
            (v + 0.0).to_bits().hash(&mut h);
        }
        h.finish()
    }

    /// Pickled (and copied) as its robot file with the numbers it holds to the bit
    /// ([`exact_numbers`]), which read back to the same robot.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Pickled<'py>> {
        let restore = py.get_type::<PyRobot>().getattr("_from_pickle")?;
        Ok((restore, (self.to_toml(), exact_numbers(&self.inner))))
    }

    /// The robot of a pickle: the robot file's text and its numbers to the bit
    /// ([`exact_numbers`]), each of which must be the file's value up to its last digits.
    #[staticmethod]
    fn _from_pickle(text: &str, numbers: Vec<Real>) -> PyResult<PyRobot> {
        let file =
            calbench::robot::parse_robot_file(text, std::path::Path::new("text")).map_err(err)?;
        with_exact_numbers(file, &numbers)
            .map(|inner| PyRobot { inner })
            .ok_or_else(|| setting("numbers", "are not the robot file's values"))
    }

    fn __repr__(&self) -> String {
        format!(
            "calbench.Robot(\"{}\", {} joints)",
            self.inner.name,
            self.inner.dof()
        )
    }
}

/// What a robot pickles as: the function that restores it, with the robot file's text and
/// its [`exact_numbers`].
type Pickled<'py> = (Bound<'py, PyAny>, (String, Vec<Real>));

/// Every number of `robot`'s model in its internal units (mm, rad), in a fixed order: the
/// parameter values, each joint's limits, the coupling's L1. A robot file holds them in its
/// own units, from which not every value converts back to the bit (degrees reach only about
/// nine radian values in ten: their spacing times π/180 exceeds the radians' where an angle
/// in degrees has one more binary digit), so a pickle carries them beside the file.
fn exact_numbers(robot: &Robot) -> Vec<Real> {
    let mut numbers = robot.values.clone();
    numbers.extend(robot.joints.iter().flat_map(|j| [j.limits.0, j.limits.1]));
    numbers.extend(robot.coupling.map(|Coupling::Differential { l1_mm }| l1_mm));
    numbers
}

/// `robot` (read from its file) with the [`exact_numbers`] `numbers` in place of the file's
/// values; `None` when they are not as many, or one is not the file's value up to its last
/// digits (1e-12 of its size).
fn with_exact_numbers(mut robot: Robot, numbers: &[Real]) -> Option<Robot> {
    let file = exact_numbers(&robot);
    let close = |(a, b): (&Real, &Real)| (a - b).abs() <= 1e-12 * a.abs().max(b.abs());
    if file.len() != numbers.len() || !file.iter().zip(numbers).all(close) {
        return None;
    }
    let (values, rest) = numbers.split_at(robot.values.len());
    robot.values.copy_from_slice(values);
    for (j, l) in robot.joints.iter_mut().zip(rest.chunks_exact(2)) {
        j.limits = (l[0], l[1]);
    }
    if let Some(Coupling::Differential { l1_mm }) = &mut robot.coupling {
        *l1_mm = *rest.last()?;
    }
    Some(robot)
}
