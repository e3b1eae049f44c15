//! Socket tasks (docs/formats.md § 9.4): the tool point held in sockets at known distances
//! from socket 1 (the MUKCa data, Franzese et al. 2024), one placement of the sockets
//! calibrating and another placement of the same robot validating, a URDF nominal model
//! with its tip link, and the data's authors' own figures: per socket the spread of the tool
//! points about their mean, and the error of the distance between the sockets' mean points.
//! The task's joint files (one per socket, `q1…qn` a row, no header) are read as one socket
//! file (§ 5.3) per placement; calbench's identified robot, the nominal one and the authors'
//! calibrated model are scored on both placements, beside the authors' `kpis.yaml`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::head::{TaskFile, TaskHead};
pub use super::record::{Placements, SocketFigures, SocketScores};
use super::socket_file::read_socket_file;
use super::{Metric, Published, TaskRecord};
use crate::calibrate::on_kind::KindOutcome;
use crate::calibrate::pipeline::IdentifyOutcome;
use crate::calibrate::request::{IdentifyData, IdentifyRequest};
use crate::error::{read_text, Error, Opt, Result};
use crate::identify::MethodSpec;
use crate::measurement::kind::{Instrument, KindData};
use crate::measurement::kind_csv::KindFile;
use crate::numeric::Real;
use crate::numeric::Vec3;
use crate::robot::urdf::UrdfChain;
use crate::robot::{Param, Robot, MAX_LENGTH_MM};

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

    /// The model `path` (a URDF's chain to the task's tip). A tip the URDF has no link of, or
    /// no tip where the URDF has more than one leaf link, is refused naming the task file's
    /// `tip`, which gives it.
    pub fn load_model(&self, path: &Path) -> Result<Robot> {
        if crate::robot::urdf::is_urdf(&path.to_string_lossy()) {
            self.check_tip(path)?;
        }
        let chain = UrdfChain {
            base: None,
            tip: self.tip.clone(),
        };
        crate::robot::builtin::load_chain(&path.to_string_lossy(), &chain)
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
        self.load_model(&self.head.robot)
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

    /// The figures of `robot` on the placement `k`: per row the distance of its tool point
    /// from its socket's mean point (mm), and the figures.
    pub fn figures(&self, robot: &Robot, k: &KindFile) -> (Vec<Real>, SocketFigures) {
        let chain = robot.chain();
        let points: Vec<Vec3> = k.qs.iter().map(|q| chain.fk(q).pos).collect();
        socket_figures(&points, &k.data.group, &self.distances_mm)
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
            Some(p) => Some(both(&self.load_model(p)?).1),
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

/// The figures of the tool points `points`, each in the socket `group[i]`, the sockets at
/// `distances` (mm) from socket 1: per row its distance from its socket's mean point, and
/// the figures (the authors' `evaluate_model`: per socket the square root of the summed
/// per-axis population variances; pooled, the rows' RMS distance; the distance error).
pub fn socket_figures(
    points: &[Vec3],
    group: &[usize],
    distances: &[Real],
) -> (Vec<Real>, SocketFigures) {
    let n = distances.len();
    let mut mean = vec![Vec3::zeros(); n];
    let mut count = vec![0usize; n];
    for (p, &g) in points.iter().zip(group) {
        mean[g] += p;
        count[g] += 1;
    }
    for (m, &c) in mean.iter_mut().zip(&count) {
        *m /= c.max(1) as Real;
    }
    let rows: Vec<Real> = points
        .iter()
        .zip(group)
        .map(|(p, &g)| (p - mean[g]).norm())
        .collect();
    let mut sq = vec![0.0; n];
    for (e, &g) in rows.iter().zip(group) {
        sq[g] += e * e;
    }
    let spread_per_socket_mm = sq
        .iter()
        .zip(&count)
        .map(|(s, &c)| (s / c.max(1) as Real).sqrt())
        .collect();
    let spread_mm = (sq.iter().sum::<Real>() / rows.len().max(1) as Real).sqrt();
    let d2: Real = (1..n)
        .map(|l| ((mean[l] - mean[0]).norm() - distances[l]).powi(2))
        .sum();
    let figures = SocketFigures {
        spread_per_socket_mm,
        spread_mm,
        distance_error_mm: (d2 / (n - 1).max(1) as Real).sqrt(),
    };
    (rows, figures)
}

/// The figures of the authors' `kpis.yaml` (m, m²): `var_1`, `var_2` (per-axis variances
/// of each socket's tool points), `fks_1`, `fks_2` (the points, counted) and `distance`
/// (the distance's error, signed), in mm.
pub fn read_kpis(path: &Path) -> Result<SocketFigures> {
    let text = read_text(path)?;
    let mut key = "";
    let mut var = [Vec::new(), Vec::new()];
    let mut count = [0usize; 2];
    let mut distance = None;
    // The line of each key read.
    let mut lines: BTreeMap<&str, usize> = BTreeMap::new();
    for (i, line) in text.lines().enumerate() {
        // A line `key: …` opens the key it names: its own value is read at that key.
        let opened = line
            .split_once(':')
            .filter(|_| !line.starts_with([' ', '-']));
        if let Some((k, _)) = opened {
            key = match k {
                "distance" | "var_1" | "var_2" | "fks_1" | "fks_2" => k,
                _ => "",
            };
        }
        let at = key;
        let bad = |msg: String| Error::file(path, format!("line {}, {at}", i + 1), msg);
        if let (Some((_, rest)), false) = (opened, key.is_empty()) {
            if let Some(first) = lines.insert(key, i + 1) {
                return Err(bad(format!("given twice (first on line {first})")));
            }
            if key != "distance" && !rest.trim().is_empty() {
                let msg = "a list on the key's line is not read: write one `- value` per \
                           line below the key, as the authors' files do";
                return Err(bad(msg.to_string()));
            }
        }
        let num = |s: &str| -> Result<Real> {
            s.trim()
                .parse::<Real>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(format!("\"{}\" is not a number", s.trim())))
        };
        // A figure in m (a variance in m²) that stands for a length of at most 1 km.
        let within = |v: Real, lo: Real, hi: Real, what: &str| -> Result<Real> {
            if (lo..=hi).contains(&v) {
                Ok(v)
            } else {
                let v = crate::error::shown(v);
                Err(bad(format!("must be {what}, got {v}")))
            }
        };
        let (km, km2) = (MAX_LENGTH_MM / 1000.0, (MAX_LENGTH_MM / 1000.0).powi(2));
        if let Some((_, rest)) = opened {
            if key == "distance" {
                let what = "a distance error within ±1000 m (1 km)";
                distance = Some(within(num(rest)?, -km, km, what)?);
            }
        } else if let Some(v) = line.strip_prefix("- - ") {
            match key {
                "fks_1" => count[0] += 1,
                "fks_2" => count[1] += 1,
                _ => {}
            }
            num(v)?;
        } else if let Some(v) = line.strip_prefix("- ") {
            match key {
                "var_1" | "var_2" => {
                    let what = "a variance in [0, 1e6] m² (a spread of at most 1 km)";
                    var[usize::from(key == "var_2")].push(within(num(v)?, 0.0, km2, what)?);
                }
                _ => {}
            }
        }
    }
    let missing = |k: &str| {
        Error::file(path, k, "missing: the authors' kpis.yaml gives var_1, var_2 (3 each), fks_1, fks_2 and distance")
    };
    let distance = distance.ok_or_else(|| missing("distance"))?;
    // A key given with the wrong number of values, at its line.
    let wrong = |k: &str, msg: String| match lines.get(k) {
        Some(n) => Error::file(path, format!("line {n}, {k}"), msg),
        None => missing(k),
    };
    for l in 0..2 {
        if var[l].len() != 3 {
            let msg = format!("{} values where the x, y, z variances are 3", var[l].len());
            return Err(wrong(["var_1", "var_2"][l], msg));
        }
        if count[l] == 0 {
            return Err(wrong(["fks_1", "fks_2"][l], "no point".to_string()));
        }
    }
    let v: Vec<Real> = var.iter().map(|v| v.iter().sum::<Real>()).collect();
    let n = (count[0] + count[1]) as Real;
    Ok(SocketFigures {
        spread_per_socket_mm: v.iter().map(|s| s.sqrt() * 1000.0).collect(),
        spread_mm: ((v[0] * count[0] as Real + v[1] * count[1] as Real) / n).sqrt() * 1000.0,
        distance_error_mm: distance.abs() * 1000.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two sockets 50 mm apart, each point 1 mm (socket 1) or 2 mm (socket 2) from its
    /// socket's mean, the means 50.5 mm apart: the figures in closed form.
    #[test]
    fn figures_in_closed_form() {
        let v = |x, y, z| Vec3::new(x, y, z);
        let points = [
            v(1.0, 0.0, 0.0),
            v(-1.0, 0.0, 0.0),
            v(50.5, 2.0, 0.0),
            v(50.5, -2.0, 0.0),
            v(50.5, 0.0, 2.0),
            v(50.5, 0.0, -2.0),
        ];
        let (rows, f) = socket_figures(&points, &[0, 0, 1, 1, 1, 1], &[0.0, 50.0]);
        assert_eq!(rows, vec![1.0, 1.0, 2.0, 2.0, 2.0, 2.0]);
        assert_eq!(f.spread_per_socket_mm, vec![1.0, 2.0]);
        assert!((f.spread_mm - (18.0 / 6.0 as Real).sqrt()).abs() < 1e-12);
        assert!((f.distance_error_mm - 0.5).abs() < 1e-12);
        // The pooled spread is the metric of the per-row distances.
        assert!((Metric::SocketSpreadMm.of(&rows).0 - f.spread_mm).abs() < 1e-12);
    }

    /// A key given in flow style, twice, or with four variances, and a list of no point,
    /// were each refused as "missing" (the last one naming `var_2`), with no line.
    #[test]
    fn a_key_present_but_malformed_is_named_at_its_line() {
        let dir = crate::test_dir("kpis-malformed");
        let p = dir.join("kpis.yaml");
        let var = |k: &str, n: usize| format!("{k}:\n{}", "- 1.0e-9\n".repeat(n));
        let points = |k: &str| format!("{k}:\n- - 0.4\n  - 0.0\n  - 0.0\n");
        let good = [
            var("var_1", 3),
            var("var_2", 3),
            points("fks_1"),
            points("fks_2"),
        ];
        let head = "distance: -2.9e-06\n";
        for (text, want) in [
            (
                format!(
                    "{head}{}var_2: [1e-9, 2e-9, 3e-9]\n{}{}",
                    good[0], good[2], good[3]
                ),
                "line 6, var_2: a list on the key's line is not read",
            ),
            (
                format!("{head}{}{}", good.concat(), good[0]),
                "line 18, var_1: given twice (first on line 2)",
            ),
            (
                format!("{head}{}{}{}{}", good[0], var("var_2", 4), good[2], good[3]),
                "line 6, var_2: 4 values where the x, y, z variances are 3",
            ),
            (
                format!("{head}{}{}{}fks_2:\n", good[0], good[1], good[2]),
                "line 14, fks_2: no point",
            ),
        ] {
            std::fs::write(&p, text).unwrap();
            let e = read_kpis(&p).unwrap_err().to_string();
            assert!(e.contains(want), "{e}");
        }
        std::fs::write(&p, format!("{head}{}", good.concat())).unwrap();
        assert!(read_kpis(&p).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A malformed `distance:` is refused at its own line and key, not the key before it.
    #[test]
    fn a_malformed_distance_is_named_at_its_key() {
        let dir = crate::test_dir("kpis");
        let p = dir.join("kpis.yaml");
        std::fs::write(&p, "var_1:\n- 1.0e-9\n- 2.0e-9\n- 3.0e-9\ndistance: oops\n").unwrap();
        let e = read_kpis(&p).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(
            e.contains("line 5, distance") && e.contains("\"oops\""),
            "{e}"
        );
        assert!(!e.contains("var_1"), "{e}");
    }

    /// A negative or huge variance (a NaN or infinite spread) and a distance error beyond
    /// 1 km are refused at their line and key, not printed as `NaN` or `inf` and written as
    /// `null` in task.json.
    #[test]
    fn a_variance_or_distance_out_of_range_is_refused_at_its_key() {
        let dir = crate::test_dir("kpis-range");
        let p = dir.join("kpis.yaml");
        let fks = "fks_1:\n- - 0.4\nfks_2:\n- - 0.4\n";
        for (var_1, distance, expected) in [
            (
                "-1.0e-9",
                "1.0e-6",
                "line 7, var_1: must be a variance in [0, 1e6] m²",
            ),
            (
                "1.0e308",
                "1.0e-6",
                "line 7, var_1: must be a variance in [0, 1e6] m²",
            ),
            (
                "1.0e-9",
                "-1.0e308",
                "line 1, distance: must be a distance error within",
            ),
        ] {
            let text = format!(
                "distance: {distance}\n{fks}var_1:\n- {var_1}\n- 2.0e-9\n- 3.0e-9\n\
                 var_2:\n- 1.0e-9\n- 2.0e-9\n- 3.0e-9\n"
            );
            std::fs::write(&p, &text).unwrap();
            let e = read_kpis(&p).unwrap_err().to_string();
            assert!(e.contains(expected), "{e}");
        }
        std::fs::write(&p, "distance: 1.0e-6\nfks_1:\n- - 0.4\nfks_2:\n- - 0.4\nvar_1:\n- 0.0\n- 2.0e-9\n- 3.0e-9\nvar_2:\n- 1.0e-9\n- 2.0e-9\n- 3.0e-9\n").unwrap();
        let ok = read_kpis(&p);
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(ok.unwrap().spread_mm.is_finite());
    }

    /// Panda 6's kpis.yaml: √(5.5 + 9.5 + 13.1)·10⁻⁹ m² = 0.1676 mm, √(7.8 + 23.1 + 18.8)
    /// = 0.2229 mm, 31 points each, distance −2.9294 µm.
    #[test]
    fn the_authors_kpis_read() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/mukca/panda_6/kpis.yaml");
        let f = read_kpis(&p).unwrap();
        assert!((f.spread_per_socket_mm[0] - 28.1e-9f64.sqrt() * 1e3).abs() < 1e-9);
        assert!((f.spread_per_socket_mm[1] - 49.7e-9f64.sqrt() * 1e3).abs() < 1e-9);
        assert!((f.spread_mm - (77.8e-9f64 / 2.0).sqrt() * 1e3).abs() < 1e-9);
        assert!((f.distance_error_mm - 2.9294e-3).abs() < 1e-12);
    }
}
