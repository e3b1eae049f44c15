//! The one trait of an output file, [`Output`] (its name and how its bytes are written), and
//! the writers that several outputs share: bytes or text already made, a text made from the
//! folder it is written in (a page inlining the figures beside it), a JSON document, a
//! numbered series, the measurement and pose files (through [`crate::measurement`]'s
//! byte-identical writers), a robot file, a figure, and a file streamed as it is produced
//! ([`Stream`]). Every file calbench writes into an output folder is one of these, written
//! by [`write_all`] (and as a whole by [`folder`]): the files of `calbench run`, `merge`,
//! `compare`, `poses`, `simulate`, `compensate` and `identify` (docs/formats.md) are built
//! from results already computed.
//!
//! A run's `trials.csv` and a shard's `records.txt` are streamed: a run's memory must not
//! grow with its trials (the aggregation spills its per-trial numbers to disk for the same
//! reason), so their rows go to a [`Stream`] in the folder as the trials finish, and the
//! finished stream ([`Streamed`]) is an output like the others, written when the folder is.

use std::io::Write as _;
use std::path::{Path, PathBuf};

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
    /// The names of the files it writes in the folder: its name (a figure: `<name>.png` and
    /// `<name>.svg`).
    fn files(&self) -> Vec<String> {
        vec![self.name().to_string()]
    }
}

/// The outputs of a command, in the order they are written.
pub type Outputs<'a> = Vec<Box<dyn Output + 'a>>;

/// Writes `outputs` into the existing folder `dir` in their order (an output that reads the
/// folder, such as a page inlining figures, comes after what it reads), each under its
/// [`Output::name`].
pub fn write_all<'o, O: std::borrow::Borrow<dyn Output + 'o>>(
    dir: &Path,
    outputs: &[O],
) -> Result<()> {
    outputs.iter().try_for_each(|o| {
        let o = o.borrow();
        o.write(&dir.join(o.name()))
    })
}

/// Writes `outputs` into the folder `out` as a whole ([`super::atomically`], [`write_all`]).
pub fn folder(out: &Path, outputs: &[&dyn Output]) -> Result<()> {
    super::atomically(out, |dir| write_all(dir, outputs))
}

/// [`folder`] of outputs held in boxes.
pub fn folder_of(out: &Path, outputs: &Outputs) -> Result<()> {
    super::atomically(out, |dir| write_all(dir, outputs))
}

/// The names of the files `outputs` write ([`Output::files`]), sorted.
pub fn file_names<'o, O: std::borrow::Borrow<dyn Output + 'o>>(outputs: &[O]) -> Vec<String> {
    let mut names: Vec<String> = outputs.iter().flat_map(|o| o.borrow().files()).collect();
    names.sort();
    names
}

/// A [`Text`] output of each (name, text) of `files`.
pub fn texts<'a>(files: &'a [(&str, String)]) -> Outputs<'a> {
    let text = |(name, text): &'a (&str, String)| {
        Box::new(Text {
            name,
            text: text.clone(),
        }) as Box<dyn Output>
    };
    files.iter().map(text).collect()
}

/// Writes `text` at `path`.
pub(crate) fn text(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}

/// Writes the JSON document `v` ([`json_text`]) to the file `path` whole or not at all: into
/// a temporary file beside it, then renamed over it.
pub fn json_file(path: &Path, v: &Value) -> Result<()> {
    let tmp = super::partial_path(path, std::process::id());
    // Any failure is the file's, not the temporary one's the user never named.
    let done = std::fs::write(&tmp, json_text(v)?)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| match path.parent() {
            Some(p) if !p.as_os_str().is_empty() && !p.is_dir() => Error::io(
                path,
                std::io::Error::new(
                    e.kind(),
                    match p.exists() {
                        true => format!("{} is not a folder", p.display()),
                        false => format!("its folder {} does not exist", p.display()),
                    },
                ),
            ),
            _ => Error::io(path, e),
        });
    if done.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    done
}

/// Writes `path` through a buffer with `body`, naming the file in any error.
pub(crate) fn buffered(
    path: &Path,
    body: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<()> {
    let file = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    let mut w = std::io::BufWriter::new(file);
    body(&mut w)
        .and_then(|()| w.flush())
        .map_err(|e| Error::io(path, e))
}

/// A file whose text is already made (`summary.json`, `report.md`, a page).
pub struct Text<'a> {
    /// The file's name.
    pub name: &'a str,
    /// Its text.
    pub text: String,
}

impl Output for Text<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        text(path, &self.text)
    }
}

/// A function of a path: the folder a text is made from, the stem a figure is drawn at.
pub type FromDir<'a, T> = Box<dyn Fn(&Path) -> Result<T> + 'a>;

/// A function that writes a file's bytes to a writer.
pub type Body<'a> = Box<dyn Fn(&mut dyn std::io::Write) -> std::io::Result<()> + 'a>;

/// The text of a file made when it is written, from the folder it is written in: a page that
/// inlines the figures written before it.
pub struct FromFolder<'a> {
    /// The file's name.
    pub name: &'a str,
    /// Its text, made from the folder.
    pub make: FromDir<'a, String>,
}

impl Output for FromFolder<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        let dir = path.parent().unwrap_or(Path::new("."));
        text(path, &(self.make)(dir)?)
    }
}

/// A file written through a buffer by a function of its writer (an `identified.json` or a
/// `residuals.csv` too long to hold as one text).
pub struct Buffered<'a> {
    /// The file's name.
    pub name: &'a str,
    /// Writes the file's bytes.
    pub body: Body<'a>,
}

impl Output for Buffered<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        buffered(path, |w| (self.body)(w))
    }
}

/// A figure drawn as `<stem>.png` and `<stem>.svg` (by the report's plots), with the caption
/// the reports give it.
pub struct Figure<'a> {
    /// The files' stem.
    pub stem: String,
    /// The caption (`report.md`, `report.html`).
    pub caption: String,
    /// Draws the figure at a stem.
    pub draw: FromDir<'a, ()>,
}

impl<'a> Figure<'a> {
    /// The figure `stem` with `caption`, drawn by `draw`.
    pub fn new(
        stem: impl Into<String>,
        caption: impl Into<String>,
        draw: impl Fn(&Path) -> Result<()> + 'a,
    ) -> Figure<'a> {
        Figure {
            stem: stem.into(),
            caption: caption.into(),
            draw: Box::new(draw),
        }
    }

    /// The PNG's file name and the caption, as `report.md` lists a figure.
    pub fn listed(&self) -> (String, String) {
        (format!("{}.png", self.stem), self.caption.clone())
    }
}

/// The file names of a figure of stem `stem`.
pub fn figure_files(stem: &str) -> Vec<String> {
    vec![format!("{stem}.png"), format!("{stem}.svg")]
}

impl Output for Figure<'_> {
    fn name(&self) -> &str {
        &self.stem
    }
    fn write(&self, path: &Path) -> Result<()> {
        (self.draw)(path)
    }
    fn files(&self) -> Vec<String> {
        figure_files(&self.stem)
    }
}

/// A file written as it is produced (a run's `trials.csv`, a shard's `records.txt`): its
/// bytes go to `.<name>.partial` in the output folder; [`Stream::finish`] gives the
/// [`Streamed`] output that puts it under its name.
pub struct Stream {
    name: String,
    partial: PathBuf,
    out: std::io::BufWriter<std::fs::File>,
}

impl Stream {
    /// Starts the file `name` in the folder `dir`.
    pub fn create(dir: &Path, name: &str) -> Result<Stream> {
        let partial = dir.join(format!(".{name}.partial"));
        let file = std::fs::File::create(&partial).map_err(|e| Error::io(&partial, e))?;
        Ok(Stream {
            name: name.to_string(),
            partial,
            out: std::io::BufWriter::new(file),
        })
    }

    /// Appends `bytes`, naming the file in an error.
    pub fn append(&mut self, bytes: &[u8]) -> Result<()> {
        self.out
            .write_all(bytes)
            .map_err(|e| Error::io(self.partial.with_file_name(&self.name), e))
    }

    /// Flushes the bytes: the finished file, to be written under its name.
    pub fn finish(mut self) -> Result<Streamed> {
        let path = self.partial.with_file_name(&self.name);
        self.out.flush().map_err(|e| Error::io(&path, e))?;
        Ok(Streamed {
            name: self.name,
            partial: self.partial,
        })
    }
}

/// A finished [`Stream`]: writing it moves its bytes under its name.
pub struct Streamed {
    name: String,
    partial: PathBuf,
}

impl Streamed {
    /// Replaces the finished bytes by what `f` writes to its second argument while it reads
    /// them from its first (once, through a second partial file beside the first).
    pub fn rewrite(
        self,
        f: impl FnOnce(&mut dyn std::io::Read, &mut dyn std::io::Write) -> Result<()>,
    ) -> Result<Streamed> {
        let path = self.partial.with_file_name(&self.name);
        let again = self
            .partial
            .with_file_name(format!(".{}.rewrite.partial", self.name));
        let from = std::fs::File::open(&self.partial).map_err(|e| Error::io(&path, e))?;
        let to = std::fs::File::create(&again).map_err(|e| Error::io(&path, e))?;
        let mut to = std::io::BufWriter::new(to);
        f(&mut std::io::BufReader::new(from), &mut to)?;
        to.flush().map_err(|e| Error::io(&path, e))?;
        drop(to);
        std::fs::rename(&again, &self.partial).map_err(|e| Error::io(&path, e))?;
        Ok(self)
    }
}

impl Output for Streamed {
    fn name(&self) -> &str {
        &self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        std::fs::rename(&self.partial, path).map_err(|e| Error::io(path, e))
    }
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

pub use crate::error::json_text;

/// A JSON document, pretty-printed with a final newline ([`json_text`]).
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
        text(path, &json_text(self.value)?)
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
