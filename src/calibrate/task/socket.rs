//! Socket tasks (docs/formats.md § 9.4): the tool point held in sockets at known distances
//! from socket 1 (the MUKCa data, Franzese et al. 2024), one placement of the sockets
//! calibrating and another placement of the same robot validating, a URDF nominal model
//! with its tip link, and the data's authors' own figures: per socket the spread of the tool
//! points about their mean, and the error of the distance between the sockets' mean points.
//! The task's joint files (one per socket, `q1…qn` a row, no header) are read as one socket
//! file (§ 5.3) per placement; calbench's identified robot, the nominal one and the authors'
//! calibrated model are scored on both placements, beside the authors' `kpis.yaml`.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::head::{TaskFile, TaskHead};
pub use super::record::{Placements, SocketFigures, SocketScores};
use super::socket_figures::{read_kpis, socket_figures, socket_means};
use super::socket_file::read_socket_file;
use super::{Metric, Published, TaskRecord};
use crate::calibrate::on_kind::KindOutcome;
use crate::calibrate::pipeline::IdentifyOutcome;
use crate::calibrate::request::{IdentifyData, IdentifyRequest};
use crate::error::{read_text, Error, Opt, Result};
use crate::identify::MethodSpec;
use crate::measurement::kind::{Instrument, KindData};
use crate::measurement::kind_csv::KindFile;
use crate::measurement::{repeated_readings_named, SAME_JOINT};
use crate::numeric::Real;
use crate::numeric::Vec3;
use crate::robot::urdf::UrdfChain;
use crate::robot::{Param, Robot};

/// The keys of a socket task file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SocketTaskKeys {
    title: String,
    robot: String,
    tip: Option<String>,
    metric: Metric,
    #[serde(default)]
    fix: Vec<String>,
    sockets: SocketKeys,
    authors: Option<AuthorKeys>,
    #[serde(default)]
    published: Vec<Published>,
    unpublished: Option<String>,
}

/// `[sockets]`: each socket's distance from socket 1 and its joint file per placement.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SocketKeys {
    distances_mm: Vec<Real>,
    calibration: Vec<String>,
    validation: Vec<String>,
}

/// `[authors]`: the data's authors' calibrated model and their own figures.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AuthorKeys {
    model: Option<String>,
    kpis: Option<String>,
    source: String,
}

/// How many times farther or nearer than `sockets.distances_mm` says the nominal robot may put
/// two sockets' tool points: a nominal model is off by millimetres, a unit by 10, 25.4 or
/// 1000 times.
pub const SOCKET_SCALE: Real = 2.0;

/// A socket whose distance from socket 1 the nominal robot's tool points put more than
/// [`SOCKET_SCALE`] times farther or nearer than given ([`misplaced_socket`]).
pub struct Misplaced {
    /// The socket, 0-based (socket 1 is 0).
    pub socket: usize,
    /// Its distance from socket 1 as given (mm).
    pub given: Real,
    /// The distance of its mean tool point from socket 1's (mm).
    pub seen: Real,
}

impl Misplaced {
    /// In words: `rows` names where its poses are (`its file`), `distances` what gave the
    /// distance (`these distances`).
    pub fn said(&self, rows: &str, distances: &str) -> String {
        let (factor, way) = match self.seen > self.given {
            true => (self.seen / self.given, "farther"),
            false => (self.given / self.seen, "nearer"),
        };
        let tenth = |v: Real| crate::error::shown((v * 10.0).round() / 10.0);
        format!(
            "socket {} is {} mm from socket 1, where the nominal robot puts the tool points of \
             {rows} {} mm from socket 1's ({} times {way}): are {distances}, or the robot's \
             lengths, in another unit?",
            self.socket + 1,
            crate::error::shown(self.given),
            tenth(self.seen),
            tenth(factor),
        )
    }
}

/// The first socket of `distances` (mm from socket 1) whose poses (`qs`, each of the socket
/// `group` names) the nominal robot puts more than [`SOCKET_SCALE`] times farther from socket
/// 1's or nearer: distances in another unit, or a robot file whose lengths are.
pub fn misplaced_socket(
    nominal: &Robot,
    qs: &[Vec<Real>],
    group: &[usize],
    distances: &[Real],
) -> Option<Misplaced> {
    let chain = nominal.chain();
    let points: Vec<Vec3> = qs.iter().map(|q| chain.fk(q).pos).collect();
    let mean = socket_means(&points, group, distances.len()).0;
    (distances.iter().enumerate().skip(1))
        .map(|(socket, &given)| Misplaced {
            socket,
            given,
            seen: (mean[socket] - mean[0]).norm(),
        })
        .find(|m| (m.seen / m.given).max(m.given / m.seen) > SOCKET_SCALE)
}

/// How near the nominal robot may put two sockets' mean tool points before their files are
/// taken for one socket's poses (mm): a tenth of a millimetre shown as 0.
const SAME_PLACE_MM: Real = 0.05;

/// A socket task, read and checked.
#[derive(Clone, Debug)]
pub struct SocketTask {
    /// Its name, file, text, hash, title, nominal robot (a URDF or a robot file), fixed
    /// files (the robot, the joint files, the authors' model and figures) and published
    /// figures on the validation placement.
    pub head: TaskHead,
    /// The URDF's tip link.
    pub tip: Option<String>,
    /// The parameters held at their nominal values.
    pub fix: Vec<Param>,
    /// Each socket's known distance from socket 1 (mm; 0 for socket 1).
    pub distances_mm: Vec<Real>,
    /// The calibration placement's joint files, one per socket.
    pub calibration: Vec<PathBuf>,
    /// The validation placement's joint files, one per socket.
    pub validation: Vec<PathBuf>,
    /// The authors' calibrated model, scored by calbench on both placements.
    pub authors_model: Option<PathBuf>,
    /// The authors' own figures on the calibration placement (their `kpis.yaml`).
    pub authors_kpis: Option<PathBuf>,
    /// Where the authors' model and figures come from.
    pub authors_source: Option<String>,
}

/// An entry of a socket task: its identification, the compensated robot and its
/// `task.json`, every model scored on both placements.
pub struct SocketEntry {
    /// The identification on the calibration placement.
    pub outcome: Box<KindOutcome>,
    /// The compensated robot (`robot.toml`).
    pub robot: Robot,
    /// Its `task.json`, with every model's scores.
    pub record: TaskRecord,
}

/// Reads the task file `path` as a socket task when it has a `[sockets]` table; `None`
/// when it has none (a tracker's task, [`super::Task::load`]).
pub fn load_socket_task(path: &Path) -> Result<Option<SocketTask>> {
    let text = read_text(path)?;
    parse_socket_task(text, path, path.parent().unwrap_or(Path::new(".")))
}

/// Reads `text`, the task file `path`, as a socket task when it has a `[sockets]` table, the
/// files it names taken from `dir` (`None` without the table).
pub fn parse_socket_task(text: String, path: &Path, dir: &Path) -> Result<Option<SocketTask>> {
    let tf = TaskFile::new(text, path, dir)?;
    if !tf.table.contains_key("sockets") {
        return Ok(None);
    }
    let keys: SocketTaskKeys = tf.keys()?;
    let bad = |key: &str, msg: String| tf.bad(key, msg);
    let file = |key: &str, rel: &str| tf.file(key, rel);
    if keys.metric != Metric::SocketSpreadMm {
        return Err(bad(
            "metric",
            format!(
                "`{}`: a socket task is scored by `socket_spread_mm`",
                keys.metric.as_str()
            ),
        ));
    }
    let s = &keys.sockets;
    let d = &s.distances_mm;
    if d.is_empty() || d[0] != 0.0 || d[1..].iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(bad(
            "sockets.distances_mm",
            "one distance (mm) per socket from socket 1: 0 for socket 1, every other finite \
             and > 0"
                .into(),
        ));
    }
    if d.len() < 2 {
        return Err(bad(
            "sockets.distances_mm",
            "a single socket has no distance to score: at least two sockets".into(),
        ));
    }
    let files = |key: &str, rel: &[String]| -> Result<Vec<PathBuf>> {
        if rel.len() != d.len() {
            return Err(bad(
                key,
                format!(
                    "{} files for the {} sockets of sockets.distances_mm: one file per socket",
                    rel.len(),
                    d.len()
                ),
            ));
        }
        let paths: Vec<PathBuf> = rel.iter().map(|r| file(key, r)).collect::<Result<_>>()?;
        // One file for two sockets would make them one: a distance of 0 measured as another.
        let same = |p: &PathBuf| std::fs::canonicalize(p).unwrap_or_else(|_| p.clone());
        let real: Vec<PathBuf> = paths.iter().map(same).collect();
        let first_twice =
            (1..real.len()).find_map(|j| Some((real[..j].iter().position(|p| *p == real[j])?, j)));
        if let Some((i, j)) = first_twice {
            let why = format!(
                "{key}[{j}]: `{}` is given twice ({key}[{i}]): each socket has its own file",
                rel[j]
            );
            return Err(bad(key, why));
        }
        Ok(paths)
    };
    let calibration = files("sockets.calibration", &s.calibration)?;
    let validation = files("sockets.validation", &s.validation)?;
    if calibration.iter().any(|c| validation.contains(c)) {
        return Err(bad(
            "sockets.validation",
            "a file of the calibration placement: a validation row must not calibrate".into(),
        ));
    }
    let mut fix = Vec::with_capacity(keys.fix.len());
    for (i, f) in keys.fix.iter().enumerate() {
        let p = Param::parse(f.trim()).ok_or_else(|| {
            bad(
                "fix",
                format!("fix[{i}]: `{f}` is not a parameter name (a2, theta7, …)"),
            )
        })?;
        if let Some(j) = fix.iter().position(|q| *q == p) {
            return Err(bad(
                "fix",
                format!("fix[{i}]: `{p}` is given twice (fix[{j}])"),
            ));
        }
        fix.push(p);
    }
    let robot = file("robot", &keys.robot)?;
    let (authors_model, authors_kpis, authors_source) = match &keys.authors {
        None => (None, None, None),
        // A source of nothing would be hashed and printed, yet score nothing.
        Some(a) if a.model.is_none() && a.kpis.is_none() => {
            let msg = "names neither `model` nor `kpis`: give the authors' model or figures, \
                       or leave [authors] out";
            return Err(bad("authors", msg.into()));
        }
        Some(a) => (
            a.model
                .as_deref()
                .map(|m| file("authors.model", m))
                .transpose()?,
            a.kpis
                .as_deref()
                .map(|k| file("authors.kpis", k))
                .transpose()?,
            Some(a.source.clone()),
        ),
    };
    let mut fixed: Vec<(String, PathBuf)> = Vec::new();
    for (key, list) in [
        ("sockets.calibration", &calibration),
        ("sockets.validation", &validation),
    ] {
        let keyed = list.iter().enumerate();
        fixed.extend(keyed.map(|(i, p)| (format!("{key}[{i}]"), p.clone())));
    }
    fixed.extend(authors_model.clone().map(|p| ("authors.model".into(), p)));
    fixed.extend(authors_kpis.clone().map(|p| ("authors.kpis".into(), p)));
    let distances_mm = d.clone();
    let published = (keys.published, keys.unpublished);
    Ok(Some(SocketTask {
        head: tf.head(keys.title, robot, fixed, published)?,
        tip: keys.tip,
        fix,
        distances_mm,
        calibration,
        validation,
        authors_model,
        authors_kpis,
        authors_source,
    }))
}

impl SocketTask {
    /// The joint files of both placements (what its outputs must not lie beside).
    pub fn data_files(&self) -> Vec<&Path> {
        self.calibration
            .iter()
            .chain(&self.validation)
            .map(PathBuf::as_path)
            .collect()
    }

    /// The model `path`, given by the task file's `key` (a URDF's chain to the task's tip). A
    /// tip the URDF has no link of, or no tip where the URDF has more than one leaf link, is
    /// refused naming the task file's `tip`, which gives it; a tip given for a model that is
    /// not a URDF, naming `key`.
    pub fn load_model(&self, key: &str, path: &Path) -> Result<Robot> {
        if crate::robot::urdf::is_urdf(path) {
            self.check_tip(path)?;
        } else if self.tip.is_some() {
            let msg = format!(
                "{} is not a URDF, and `tip` names a link of a URDF: give the URDF, or no tip",
                path.display()
            );
            let h = &self.head;
            return Err(Error::toml_file(&h.path, &h.text, key, key, msg));
        }
        let chain = UrdfChain {
            base: None,
            tip: self.tip.clone(),
        };
        crate::robot::builtin::load_chain(path, &chain)
    }

    /// A refusal of the parameters held (what `identify` calls `--fix`) as one of the task
    /// file's `fix`, which gives them (a name the robot's model does not have, every
    /// parameter held); any other error as it is.
    fn of_fix(&self, e: Error) -> Error {
        match e {
            Error::Option {
                option: Opt::Fix,
                msg,
            } => {
                let h = &self.head;
                Error::toml_file(&h.path, &h.text, "fix", "fix", msg)
            }
            e => e,
        }
    }

    /// Refuses, naming the task file's `tip`, a tip the URDF `path` has no link of, or no tip
    /// where the URDF has more than one leaf link.
    fn check_tip(&self, path: &Path) -> Result<()> {
        let urdf = crate::robot::urdf::read(path)?;
        let msg = match &self.tip {
            Some(tip) if !urdf.links.iter().any(|l| &l.name == tip) => {
                format!("no link \"{tip}\" in {}", path.display())
            }
            Some(_) => return Ok(()),
            None => match crate::robot::urdf::leaf_links(&urdf).as_slice() {
                [_] => return Ok(()),
                leaves => format!(
                    "{} has {} leaf links ({}): calbench takes a serial chain to one tip link; \
                     name it with tip = \"LINK\"",
                    path.display(),
                    leaves.len(),
                    leaves.join(", ")
                ),
            },
        };
        let h = &self.head;
        Err(Error::toml_file(&h.path, &h.text, "tip", "tip", msg))
    }

    /// The nominal robot.
    pub fn load_robot(&self) -> Result<Robot> {
        self.load_model("robot", &self.head.robot)
    }

    /// The placement of `files` as one socket file for `robot`: the i-th file's rows are
    /// socket i + 1 at its distance from socket 1. A refusal names the file and its own line
    /// (`read_socket_file`).
    pub fn placement(&self, files: &[PathBuf], robot: &Robot) -> Result<KindFile> {
        let mut out = KindFile {
            qs: Vec::new(),
            data: KindData {
                instrument: Instrument::Sockets(self.distances_mm.clone()),
                group: Vec::new(),
                values: Vec::new(),
            },
            sigma_mm: None,
            lines: Vec::new(),
            files: Vec::new(),
        };
        for (s, f) in files.iter().enumerate() {
            let one = read_socket_file(f, robot)?;
            out.files.push((f.clone(), one.lines.len()));
            out.data.group.extend(std::iter::repeat_n(s, one.qs.len()));
            out.data.values.extend(one.data.values);
            out.qs.extend(one.qs);
            out.lines.extend(one.lines);
        }
        out.data.check(out.qs.len())?;
        Ok(out)
    }

    /// Refuses, at the task file's `sockets.validation`, a validation placement with a row
    /// of the calibration placement's joint values (each within [`SAME_JOINT`]): a socket
    /// reading is its joint values alone, so such a row is the same reading, and the
    /// validation figure would be the fit's (files copied under other names; two placements
    /// reach no pose alike to a micro-radian).
    fn check_disjoint(&self, cal: &KindFile, val: &KindFile) -> Result<()> {
        let same = |a: &[Real], b: &[Real]| crate::measurement::within(a, b, SAME_JOINT);
        let rows: Vec<(usize, usize)> = (val.qs.iter().enumerate())
            .filter_map(|(v, q)| cal.qs.iter().position(|c| same(c, q)).map(|c| (c, v)))
            .collect();
        if rows.is_empty() {
            return Ok(());
        }
        let (c, v) = (|r| cal.row_named(r), |r| val.row_named(r));
        let numbered = "each by its file's line";
        let msg = repeated_readings_named(&rows, "the same joint values", numbered, [&c, &v]);
        Err(Error::file(&self.head.path, "sockets.validation", msg).at_key_line(&self.head.text))
    }

    /// The figures of `robot` on the placement `k`: per row the distance of its tool point
    /// from its socket's mean point (mm), and the figures.
    pub fn figures(&self, robot: &Robot, k: &KindFile) -> (Vec<Real>, SocketFigures) {
        let chain = robot.chain();
        let points: Vec<Vec3> = k.qs.iter().map(|q| chain.fk(q).pos).collect();
        socket_figures(&points, &k.data.group, &self.distances_mm)
    }

    /// Refuses, naming the task file's `sockets.distances_mm`, a distance between sockets
    /// that the nominal robot's tool points on the placement `k` put at another scale (more
    /// than [`SOCKET_SCALE`] times farther or nearer): distances in metres, or a robot file
    /// whose lengths are, which the identification would take for the robot's errors and
    /// refuse as a robot that cannot be right, blaming the joint files. Two files whose mean
    /// tool points are within [`SAME_PLACE_MM`] are refused by the second one's name: one
    /// socket's poses given twice, not a unit.
    fn check_scale(&self, nominal: &Robot, k: &KindFile) -> Result<()> {
        let distances = &self.distances_mm;
        let Some(m) = misplaced_socket(nominal, &k.qs, &k.data.group, distances) else {
            return Ok(());
        };
        if m.seen < SAME_PLACE_MM {
            let msg = format!(
                "the nominal robot puts the tool points of this file's poses where it puts those \
                 of socket 1's file {} (under {SAME_PLACE_MM} mm apart), where \
                 sockets.distances_mm puts socket {} {} mm from socket 1: do the two files hold \
                 the same socket's poses?",
                self.calibration[0].display(),
                m.socket + 1,
                crate::error::shown(m.given),
            );
            return Err(Error::file(&self.calibration[m.socket], "every row", msg));
        }
        let (h, key) = (&self.head, "sockets.distances_mm");
        let msg = m.said("its file", "these distances");
        Err(Error::toml_file(&h.path, &h.text, key, key, msg))
    }

    /// The placement's name: the folder of its first file.
    pub fn placement_name(files: &[PathBuf]) -> String {
        files
            .first()
            .and_then(|f| f.parent())
            .and_then(|d| d.file_name())
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
    }

    /// The authors' own figures (their `kpis.yaml`), when the task names them.
    pub fn kpis(&self) -> Result<Option<SocketFigures>> {
        self.authors_kpis.as_deref().map(read_kpis).transpose()
    }

    /// The entry of `method`, named `name`: the calibration placement's joint files
    /// identified as one socket file (the task's `fix` held at their nominal values), then
    /// calbench's robot, the nominal one and the authors' calibrated model scored on both
    /// placements, beside the authors' own figures.
    pub fn entry(&self, method: MethodSpec, name: &str) -> Result<SocketEntry> {
        let nominal = self.load_robot()?;
        let cal = self.placement(&self.calibration, &nominal)?;
        let val = self.placement(&self.validation, &nominal)?;
        self.check_disjoint(&cal, &val)?;
        self.check_scale(&nominal, &cal)?;
        let data = IdentifyData::Kind(cal.clone());
        let source = self.calibration[0].clone();
        let request = IdentifyRequest {
            fix: self.fix.clone(),
            ..IdentifyRequest::new(nominal.clone(), data, source, method)
        };
        let IdentifyOutcome::Kind(outcome) = request.run().map_err(|e| self.of_fix(e))? else {
            return Err(Error::Compute(
                "a socket task's data are socket readings".into(),
            ));
        };
        let robot = outcome.compensated();
        let both = |robot: &Robot| -> (Vec<Real>, Placements) {
            let (_, calibration) = self.figures(robot, &cal);
            let (rows, validation) = self.figures(robot, &val);
            let p = Placements {
                calibration,
                validation,
            };
            (rows, p)
        };
        let (errors, calbench) = both(&robot);
        let authors_model = match &self.authors_model {
            Some(p) => Some(both(&self.load_model("authors.model", p)?).1),
            None => None,
        };
        let scores = SocketScores {
            placements: [&self.calibration, &self.validation].map(|f| Self::placement_name(f)),
            calbench,
            nominal: both(&nominal).1,
            authors_model,
            authors_kpis: self.kpis()?,
        };
        let record = TaskRecord {
            socket: Some(scores),
            ..self.head.record(Metric::SocketSpreadMm, name, errors)
        };
        Ok(SocketEntry {
            outcome,
            robot,
            record,
        })
    }
}
