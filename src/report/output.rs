//! The one trait of an output file, [`Output`] (its name and how its bytes are written), and
//! the writers that several outputs share: bytes already made, a JSON document, a numbered
//! series, the measurement and pose files (through [`crate::measurement`]'s byte-identical
//! writers), a robot file and a figure. The files of `calbench poses`, `simulate`,
//! `compensate` and `identify` on a measurement-kind file (docs/formats.md) are built from results already computed and handed to [`folder`], which
//! writes them as a whole.

use std::path::Path;

use serde_json::Value;

use crate::error::{Error, Result};
use crate::measurement::kind::KindData;
use crate::measurement::{JointSpace, Measurements};
use crate::numeric::Real;

/// One output file: its name in the output folder and how its bytes are written.
pub trait Output {
    /// The file's name in the output folder (a figure's stem: it writes `<name>.png` and
    /// `<name>.svg`).
    fn name(&self) -> &str;
    /// Writes the file at `path` (a figure: at `path` with `.png` and `.svg` added).
    fn write(&self, path: &Path) -> Result<()>;
}

/// Writes `outputs` into the folder `out` as a whole ([`super::atomically`]), each under its
/// [`Output::name`].
pub fn folder(out: &Path, outputs: &[&dyn Output]) -> Result<()> {
    super::atomically(out, |dir| {
        outputs
            .iter()
            .try_for_each(|o| o.write(&dir.join(o.name())))
    })
}

/// Writes `text` at `path`.
pub(crate) fn text(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}

/// A file whose bytes are already made (e.g. `trials.csv` of a run held in memory).
pub struct Bytes<'a> {
    /// The file's name.
    pub name: &'a str,
    /// Its bytes.
    pub bytes: &'a [u8],
}

impl Output for Bytes<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        std::fs::write(path, self.bytes).map_err(|e| Error::io(path, e))
    }
}

/// A JSON document, pretty-printed with a final newline ([`super::run::json_text`]).
pub struct Json<'a> {
    /// The file's name.
    pub name: &'a str,
    /// The document.
    pub value: &'a Value,
}

impl Output for Json<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        text(path, &super::run::json_text(self.value)?)
    }
}

/// A robot file ([`crate::robot::robot_to_toml`], docs/formats.md § 3.1).
pub struct RobotToml<'a> {
    /// The file's name.
    pub name: &'a str,
    /// The robot.
    pub robot: &'a crate::robot::Robot,
}

impl Output for RobotToml<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        text(path, &crate::robot::robot_to_toml(self.robot))
    }
}

/// A CSV of numbered values: the `header` line (two column names), then a line `n,value` per
/// point, the value as Rust prints it (the shortest text that reads back the same number).
pub struct Series<'a> {
    /// The file's name.
    pub name: &'a str,
    /// The header line, without its line end.
    pub header: &'a str,
    /// The points: number, value.
    pub points: Vec<(usize, Real)>,
}

impl Output for Series<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        use std::fmt::Write as _;
        let mut s = format!("{}\n", self.header);
        for (n, v) in &self.points {
            let _ = writeln!(s, "{n},{v}");
        }
        text(path, &s)
    }
}

/// Rows whose joint values a file writes in a robot's units: a pose list or a tracker's
/// measurements.
pub trait JointRows {
    /// Writes the rows to `path` with `robot`'s units.
    fn write_rows<R: JointSpace + ?Sized>(&self, path: &Path, robot: &R) -> Result<()>;
}

impl JointRows for [Vec<Real>] {
    fn write_rows<R: JointSpace + ?Sized>(&self, path: &Path, robot: &R) -> Result<()> {
        crate::measurement::csv::write_pose_list(path, robot, self)
    }
}

impl JointRows for Measurements {
    fn write_rows<R: JointSpace + ?Sized>(&self, path: &Path, robot: &R) -> Result<()> {
        crate::measurement::csv::write_measurements(path, robot, self)
    }
}

/// A file of joint values in a robot's units: a pose list (columns q1..qn,
/// [`PoseList`]) or a tracker's measurement file (docs/formats.md § 2.5, [`MeasurementFile`]).
pub struct JointFile<'a, R: JointSpace + ?Sized, T: JointRows + ?Sized> {
    /// The file's name.
    pub name: &'a str,
    /// The robot whose units the joints are written in.
    pub robot: &'a R,
    /// The rows (internal units).
    pub rows: &'a T,
}

/// A pose list.
pub type PoseList<'a, R> = JointFile<'a, R, [Vec<Real>]>;

/// A tracker's measurement file.
pub type MeasurementFile<'a, R> = JointFile<'a, R, Measurements>;

impl<R: JointSpace + ?Sized, T: JointRows + ?Sized> Output for JointFile<'_, R, T> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        self.rows.write_rows(path, self.robot)
    }
}

/// The readings of a distance, plane, sphere or multi-target instrument (docs/formats.md
/// § 5.3).
pub struct KindFile<'a, R: JointSpace + ?Sized> {
    /// The file's name.
    pub name: &'a str,
    /// The robot whose units the joints are written in.
    pub robot: &'a R,
    /// The joint values of the poses (internal units).
    pub qs: &'a [Vec<Real>],
    /// The readings.
    pub data: &'a KindData,
    /// Each reading's σ (mm), when every reading has one.
    pub sigma_mm: Option<&'a [Real]>,
}

impl<R: JointSpace + ?Sized> Output for KindFile<'_, R> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        let (qs, data) = (self.qs, self.data);
        crate::measurement::kind_csv::write_kind_file(path, self.robot, qs, data, self.sigma_mm)
    }
}

/// A metric against a swept setting ([`super::plots::sweep`]), as `<name>.png` and
/// `<name>.svg`.
pub struct SweepFigure<'a> {
    /// The figure's stem.
    pub name: &'a str,
    /// Its title.
    pub title: &'a str,
    /// The labels of the x and y axes.
    pub axes: (&'a str, &'a str),
    /// The series drawn.
    pub series: Vec<super::SweepSeries>,
}

impl Output for SweepFigure<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        let (x, y) = self.axes;
        super::plots::sweep(path, self.title, x, y, &self.series)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An output whose writing fails.
    struct Broken;

    impl Output for Broken {
        fn name(&self) -> &str {
            "broken.csv"
        }
        fn write(&self, _: &Path) -> Result<()> {
            Err(Error::Compute("disk full".into()))
        }
    }

    #[test]
    fn a_folder_of_outputs_is_written_whole_or_not_at_all() {
        let root = std::env::temp_dir().join(format!("calbench-outputs-{}", std::process::id()));
        let out = root.join("poses");
        let _ = std::fs::remove_dir_all(&root);
        let value = serde_json::json!({"count": 2});
        let json = Json {
            name: "scores.json",
            value: &value,
        };
        let trace = Series {
            name: "trace.csv",
            header: "iteration,objective",
            points: vec![(0, 1.5), (1, 0.25)],
        };
        let e = folder(&out, &[&json, &trace, &Broken]).unwrap_err();
        assert!(e.to_string().contains("disk full"), "{e}");
        assert!(!out.exists());
        folder(&out, &[&json, &trace]).unwrap();
        let read = |name: &str| std::fs::read_to_string(out.join(name)).unwrap();
        assert_eq!(read("trace.csv"), "iteration,objective\n0,1.5\n1,0.25\n");
        assert_eq!(read("scores.json"), "{\n  \"count\": 2\n}\n");
        std::fs::remove_dir_all(&root).unwrap();
    }
}
