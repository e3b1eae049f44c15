//! Fixed real-data tasks (docs/formats.md § 9): a task file names the data, the mapping that
//! reads them, the nominal robot, the split (a committed file of row indices, or a
//! calibration file and a validation file), the metric and the data's authors' published
//! figures. [`Task::entry_request`] turns it into the one identification pipeline's request
//! ([`IdentifyRequest`]); [`TaskEntry::json`] is the entry's `task.json`.

mod canonical;
mod entry;
mod head;
pub mod record;
pub mod sha256;
pub mod socket;
mod socket_figures;
mod socket_file;
pub mod split;
mod written;

pub use crate::calibrate::record::unconverged_warning;
pub use entry::EntryModels;
pub use head::TaskHead;
pub use record::{TaskRecord, TASK_FILE};

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::cv::Model;
use super::frames::validation_misfit;
use super::pipeline::TrackerOutcome;
use super::request::{IdentifyData, IdentifyRequest};
use crate::error::{read_text, Error, Result};
use crate::identify::MethodSpec;
use crate::measurement::csv::{distinct_poses, read_measurements_text, MIN_DISTINCT_POSES};
use crate::measurement::import::{import_text, Mapping};
use crate::measurement::Measurements;
use crate::numeric::Real;
use crate::robot::Robot;
use head::TaskFile;
pub use split::Split;

/// The head and the metric of `text`, the task file `path` with the files it names taken
/// from `dir`, a socket task's or a tracker's, with the candidate models of its `[models]`
/// (`None` without one; a socket task has none).
pub fn head_of(
    text: &str,
    path: &Path,
    dir: &Path,
) -> Result<(TaskHead, Metric, Option<Vec<String>>)> {
    Ok(
        match socket::parse_socket_task(text.to_string(), path, dir)? {
            Some(t) => (t.head, Metric::SocketSpreadMm, None),
            None => {
                let t = Task::parse(text.to_string(), path, dir)?;
                let names = |m: &TaskModels| m.candidates.iter().map(Model::name).collect();
                let models = t.models.as_ref().map(names);
                (t.head, t.metric, models)
            }
        },
    )
}

/// The number of validation rows of the task file `text` (read from `path`, its files
/// beside it in `dir`): a split's validation rows, the validation file's rows as the mapping
/// reads them, or a socket task's validation placement's rows: one error each in an entry's
/// `validation_errors_mm`.
pub fn validation_rows(text: &str, path: &Path, dir: &Path) -> Result<usize> {
    if let Some(t) = socket::parse_socket_task(text.to_string(), path, dir)? {
        let robot = t.load_robot()?;
        return Ok(t.placement(&t.validation, &robot)?.qs.len());
    }
    let t = Task::parse(text.to_string(), path, dir)?;
    match &t.data {
        TaskData::Split { split, .. } => Ok(split.validation.len()),
        TaskData::Files { .. } => Ok(t.measurements(&t.load_robot()?)?.1.qs.len()),
    }
}

/// The `format` of `task.json`.
pub const TASK_FORMAT: &str = "calbench-task-1";

/// A task's ranking metric, on its validation rows; lower is better.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Metric {
    /// The mean position error (mm).
    ValidationMeanMm,
    /// The RMS position error (mm).
    ValidationRmsMm,
    /// A socket task's: the RMS distance of the tool points from their socket's mean (mm).
    SocketSpreadMm,
}

impl Metric {
    /// The name in task files and `task.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            Metric::ValidationMeanMm => "validation_mean_mm",
            Metric::ValidationRmsMm => "validation_rms_mm",
            Metric::SocketSpreadMm => "socket_spread_mm",
        }
    }

    /// The metric of the per-point errors `e` (mm) and its 95 % interval: Student's t on the
    /// errors (mean) or on their squares (RMS, the interval's ends square-rooted); `None`
    /// below two points.
    pub fn of(self, e: &[Real]) -> (Real, Option<[Real; 2]>) {
        let n = e.len() as Real;
        let sq: Vec<Real>;
        let x: &[Real] = match self {
            Metric::ValidationMeanMm => e,
            Metric::ValidationRmsMm | Metric::SocketSpreadMm => {
                sq = e.iter().map(|v| v * v).collect();
                &sq
            }
        };
        let mean = x.iter().sum::<Real>() / n;
        let ci = (e.len() >= 2).then(|| {
            let sd = (x.iter().map(|v| (v - mean).powi(2)).sum::<Real>() / (n - 1.0)).sqrt();
            let h = crate::numeric::dist::t_quantile(0.975, n - 1.0) * sd / n.sqrt();
            [mean - h, mean + h]
        });
        match self {
            Metric::ValidationMeanMm => (mean, ci),
            Metric::ValidationRmsMm | Metric::SocketSpreadMm => (
                mean.sqrt(),
                ci.map(|[lo, hi]| [lo.max(0.0).sqrt(), hi.sqrt()]),
            ),
        }
    }
}

/// A division of the leaderboard.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Division {
    /// Kinematic models only: DH, β, tool, base.
    Closed,
    /// Any model: compliance, harmonics, a Python method.
    Open,
}

impl Division {
    /// Its name in task files and `task.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            Division::Closed => "closed",
            Division::Open => "open",
        }
    }
}

/// One of the data's authors' figures on the task, with its source.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Published {
    /// What was calibrated, as the source names it.
    pub label: String,
    /// The figure, in the task's metric (mm).
    pub value: Real,
    /// Where it is published.
    pub source: String,
    /// The division its model belongs to.
    pub division: Division,
}

/// The keys of a task file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TaskKeys {
    title: String,
    robot: String,
    mapping: String,
    metric: Metric,
    data: DataKeys,
    #[serde(default)]
    published: Vec<Published>,
    unpublished: Option<String>,
    models: Option<ModelKeys>,
}

/// `[models]`: the candidate models a task fixes before any entry sees its validation rows.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelKeys {
    candidates: Vec<String>,
    folds: Option<usize>,
    fold_seeds: Option<Vec<u64>>,
}

/// The candidate models a task fixes (`[models]`, docs/formats.md § 9.1) and the repeated
/// K-fold cross-validation on its calibration rows that chooses among them.
#[derive(Clone, Debug, PartialEq)]
pub struct TaskModels {
    /// The candidates, in the task file's order (the first of equals wins).
    pub candidates: Vec<Model>,
    /// Folds per repetition (default 5).
    pub folds: usize,
    /// The fold seeds, one repetition each (default 0 to 7).
    pub fold_seeds: Vec<u64>,
}

/// `[data]`: one file and a split, or a calibration file and a validation file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DataKeys {
    file: Option<String>,
    split: Option<String>,
    calibration: Option<String>,
    validation: Option<String>,
}

/// Where a task's calibration and validation rows come from.
#[derive(Clone, Debug)]
pub enum TaskData {
    /// Rows of one file, split by a committed split file.
    Split {
        /// The data file.
        file: PathBuf,
        /// The split file.
        split_path: PathBuf,
        /// Its rows.
        split: Split,
    },
    /// A calibration file and a validation file, every row of each.
    Files {
        /// The calibration file.
        calibration: PathBuf,
        /// The validation file.
        validation: PathBuf,
    },
}

/// A task, read and checked.
#[derive(Clone, Debug)]
pub struct Task {
    /// Its name, file, text, hash, title, robot, fixed files and published figures (the
    /// files fixed: robot, mapping, data, split).
    pub head: TaskHead,
    /// The mapping that reads the data files (docs/formats.md § 6).
    pub mapping: PathBuf,
    /// The ranking metric.
    pub metric: Metric,
    /// The data and the split.
    pub data: TaskData,
    /// The candidate models the task fixes, if it does.
    pub models: Option<TaskModels>,
}

/// The option a task takes for the library's option `opt`, as its front ends spell a refusal:
/// `Ok` its own (`method`, `models`, `out`; the K-fold choice among the candidate models, `cv`, is
/// `models`, whose folds they are), `Err(opt)` one a task does not take, which a front end
/// names as identify's (a task's entry has no way past its checks).
pub fn task_option(
    opt: crate::error::Opt,
) -> std::result::Result<crate::error::Opt, crate::error::Opt> {
    use crate::error::Opt;
    match opt {
        Opt::Method | Opt::Models | Opt::Out => Ok(opt),
        Opt::Cv => Ok(Opt::Models),
        _ => Err(opt),
    }
}

/// `NAME` (a task under `tasks/`) or the path of a task file.
pub fn task_path(name_or_path: impl AsRef<Path>) -> PathBuf {
    let p = name_or_path.as_ref();
    if p.extension().is_some_and(|e| e == "toml") || p.components().count() > 1 {
        p.to_path_buf()
    } else {
        let mut file = p.as_os_str().to_owned();
        file.push(".toml");
        Path::new("tasks").join(file)
    }
}

/// [`task_path`] of a task to run: a name whose file is not under `tasks/` of the current
/// folder is refused saying where names are looked up (a path is read, and refused, as given).
pub fn task_file(name_or_path: impl AsRef<Path>) -> Result<PathBuf> {
    let given = name_or_path.as_ref();
    let path = task_path(given);
    if path != given && !path.is_file() {
        let why = format!(
            "no task named \"{}\": {} is not a file (a task's name is looked up \
             under tasks/ of the current folder, which calbench's repository holds: run from \
             its root, or give the task file's path)",
            given.display(),
            path.display()
        );
        return Err(Error::setting("task", why));
    }
    Ok(path)
}

impl TaskData {
    /// The data files with their keys in the task file: `data.file` and `data.split`, or
    /// `data.calibration` and `data.validation`.
    pub fn files(&self) -> [(&'static str, &Path); 2] {
        match self {
            TaskData::Split {
                file, split_path, ..
            } => [("data.file", file), ("data.split", split_path)],
            TaskData::Files {
                calibration,
                validation,
            } => [
                ("data.calibration", calibration),
                ("data.validation", validation),
            ],
        }
    }
}

impl Task {
    /// The task's data: its data file and split, or its calibration and validation files
    /// (what its outputs must not lie beside, [`crate::report::guard::guard_data_folder`]).
    pub fn data_files(&self) -> [&Path; 2] {
        self.data.files().map(|(_, p)| p)
    }

    /// Reads and checks the task file `path`: its keys (an unknown or missing key refused,
    /// naming the file, line and key), the files it names (relative to its folder), the
    /// split, and the published figures (or the `unpublished` note, not both).
    pub fn load(path: &Path) -> Result<Task> {
        let text = read_text(path)?;
        Task::parse(text, path, path.parent().unwrap_or(Path::new(".")))
    }

    /// [`Task::load`] of the task file's `text`, read from `path`, whose files are named
    /// relative to the folder `dir`: a task file an entry's folder carries ([`TASK_FILE`]),
    /// whose files lie beside the task file it was copied from.
    pub fn parse(text: String, path: &Path, dir: &Path) -> Result<Task> {
        let tf = TaskFile::new(text, path, dir)?;
        let keys: TaskKeys = tf.keys()?;
        let bad = |key: &str, msg: String| tf.bad(key, msg);
        let file = |key: &str, rel: &str| tf.file(key, rel);
        let d = &keys.data;
        let data = match (&d.file, &d.split, &d.calibration, &d.validation) {
            (Some(f), Some(s), None, None) => {
                let (file, split_path) = (file("data.file", f)?, file("data.split", s)?);
                TaskData::Split {
                    split: Split::load(&split_path, &file)?,
                    file,
                    split_path,
                }
            }
            (None, None, Some(c), Some(v)) => TaskData::Files {
                calibration: file("data.calibration", c)?,
                validation: file("data.validation", v)?,
            },
            _ => {
                return Err(bad(
                    "data",
                    "takes `file` and `split` (rows of one file), or `calibration` and \
                     `validation` (two files), and nothing else"
                        .into(),
                ))
            }
        };
        if keys.metric == Metric::SocketSpreadMm {
            let msg = "`socket_spread_mm` scores a socket task ([sockets], § 9.4)";
            return Err(bad("metric", msg.into()));
        }
        let models = match &keys.models {
            None => None,
            Some(m) => {
                if m.candidates.is_empty() {
                    return Err(bad("models.candidates", "lists no model".into()));
                }
                let mut candidates = Vec::with_capacity(m.candidates.len());
                for (i, c) in m.candidates.iter().enumerate() {
                    let key = format!("models.candidates[{i}]");
                    let model: Model = c
                        .parse()
                        .map_err(|e: String| bad("models.candidates", format!("{key}: {e}")))?;
                    if candidates.contains(&model) {
                        return Err(bad(
                            "models.candidates",
                            format!("{key}: `{c}` is listed twice"),
                        ));
                    }
                    candidates.push(model);
                }
                // One candidate is identified without a cross-validation: its folds and
                // seeds would be read and hashed, yet change nothing.
                if candidates.len() == 1 {
                    let given = [
                        ("models.folds", m.folds.is_some()),
                        ("models.fold_seeds", m.fold_seeds.is_some()),
                    ];
                    if let Some((key, _)) = given.into_iter().find(|g| g.1) {
                        let why = "is read only with two or more candidates: one candidate is \
                                   identified without a cross-validation";
                        return Err(bad(key, why.into()));
                    }
                }
                let folds = m.folds.unwrap_or(5);
                if folds < 2 {
                    return Err(bad("models.folds", format!("{folds}: at least 2 folds")));
                }
                let fold_seeds = m.fold_seeds.clone().unwrap_or_else(|| (0..8).collect());
                if fold_seeds.is_empty() {
                    return Err(bad("models.fold_seeds", "lists no seed".into()));
                }
                for (i, seed) in fold_seeds.iter().enumerate() {
                    if fold_seeds[..i].contains(seed) {
                        return Err(bad(
                            "models.fold_seeds",
                            format!(
                                "models.fold_seeds[{i}]: seed {seed} is listed twice (a \
                                 repetition of the same folds)"
                            ),
                        ));
                    }
                }
                Some(TaskModels {
                    candidates,
                    folds,
                    fold_seeds,
                })
            }
        };
        let robot = file("robot", &keys.robot)?;
        let mapping = file("mapping", &keys.mapping)?;
        let mut fixed = vec![("mapping".to_string(), mapping.clone())];
        fixed.extend(data.files().map(|(k, p)| (k.to_string(), p.to_path_buf())));
        let published = (keys.published, keys.unpublished);
        Ok(Task {
            head: tf.head(keys.title, robot, fixed, published)?,
            mapping,
            metric: keys.metric,
            data,
            models,
        })
    }

    /// The nominal robot.
    pub fn load_robot(&self) -> Result<Robot> {
        crate::robot::builtin::load(&self.head.robot)
    }

    /// The calibration and the validation measurements, read through the mapping, and the
    /// line of the calibration's export (the data file's under a split) of each of its rows;
    /// the split is checked against the data's row count.
    pub fn measurements(&self, robot: &Robot) -> Result<(Measurements, Measurements, Vec<u64>)> {
        let mapping = Mapping::load(&self.mapping)?;
        if mapping.joints.columns.len() != robot.dof() {
            let text = crate::error::read_text(&self.mapping)?;
            let msg = format!(
                "{} joint columns for the {}-joint robot {}",
                mapping.joints.columns.len(),
                robot.dof(),
                self.head.robot.display()
            );
            let key = "joints.columns";
            return Err(Error::toml_file(&self.mapping, &text, key, key, msg));
        }
        match &self.data {
            TaskData::Split {
                file,
                split_path,
                split,
            } => {
                let (all, lines) = self.read(file, robot)?;
                split.check_rows(split_path, file, all.len())?;
                let (cal, val) = (
                    super::cv::subset(&all, &split.calibration),
                    super::cv::subset(&all, &split.validation),
                );
                let shared = cal.shared_rows(&val);
                if !shared.is_empty() {
                    let rows: Vec<(usize, usize)> = shared
                        .iter()
                        .map(|&(c, v)| (split.calibration[c], split.validation[v]))
                        .collect();
                    return Err(self.overlap(&rows, file, file));
                }
                // A validation row repeated would weigh its point twice, named by the data
                // file's rows as the pipeline would name them by the validation's.
                let repeated = val.repeated_rows();
                if !repeated.is_empty() {
                    let rows: Vec<(usize, usize)> = repeated
                        .iter()
                        .map(|&(a, b)| (split.validation[a], split.validation[b]))
                        .collect();
                    let msg = crate::measurement::repeated_rows_refusal(
                        &rows,
                        crate::measurement::SAME_MEASUREMENT,
                        crate::measurement::REPEATED_VALIDATION,
                    );
                    return Err(self.at_validation(format!("{}: {msg}", file.display())));
                }
                // Each part is refused as a file of its rows would be.
                for (part, m, rows) in [
                    ("calibration", &cal, &split.calibration),
                    ("validation", &val, &split.validation),
                ] {
                    if distinct_poses(&m.qs, &[], robot.dof()).is_err() {
                        let msg = format!(
                            "the {part} rows of {} ({} of the {} data rows of {}) hold fewer \
                             than {MIN_DISTINCT_POSES} distinct poses: a {part}, as a {part} \
                             file, needs at least {MIN_DISTINCT_POSES} (rows of distinct joint \
                             values)",
                            split_path.display(),
                            rows.len(),
                            all.len(),
                            file.display()
                        );
                        return Err(self.at_validation(msg));
                    }
                }
                Ok((cal, val, lines))
            }
            TaskData::Files {
                calibration,
                validation,
            } => {
                let ((cal, lines), (val, _)) = (
                    self.read(calibration, robot)?,
                    self.read(validation, robot)?,
                );
                let shared = cal.shared_rows(&val);
                if !shared.is_empty() {
                    return Err(self.overlap(&shared, calibration, validation));
                }
                Ok((cal, val, lines))
            }
        }
    }

    /// The refusal of a task whose calibration and validation share the measurements `rows`
    /// (each a calibration row of `cal` and a validation row of `val`, 0-based data rows), at
    /// the line of the key that gives the validation rows (`data.validation`, `data.split`).
    fn overlap(&self, rows: &[(usize, usize)], cal: &Path, val: &Path) -> Error {
        let numbered = format!("data rows of {} and {}", cal.display(), val.display());
        self.at_validation(crate::measurement::shared_rows_refusal(rows, &numbered))
    }

    /// The refusal `msg` of the validation rows, at the line of the key that gives them.
    fn at_validation(&self, msg: String) -> Error {
        let [_, (validation, _)] = self.data.files();
        Error::toml_file(&self.head.path, &self.head.text, validation, "data", msg)
    }

    /// The data file `raw` read through the mapping, with the line of `raw` of each row; a
    /// refusal names both files.
    fn read(&self, raw: &Path, robot: &Robot) -> Result<(Measurements, Vec<u64>)> {
        let named = PathBuf::from(format!(
            "{} as mapped by {}",
            raw.display(),
            self.mapping.display()
        ));
        let (text, lines) = import_text(raw, &self.mapping, Some(robot)).map_err(|e| match e {
            Error::File { file, place, msg } if file == raw => Error::File {
                file: named.clone(),
                place,
                msg,
            },
            e => e,
        })?;
        Ok((read_measurements_text(&named, text, robot)?, lines))
    }

    /// The identification request of an entry on the task's nominal `robot`, calibration rows
    /// `cal` (at `lines` of the calibration's export) and validation rows `val`
    /// ([`Task::load_robot`], [`Task::measurements`]), with the method and the candidate models
    /// (several: chosen by 5-fold cross-validation on the calibration rows alone; one: given).
    /// Also returns the validation rows.
    fn request(
        &self,
        (robot, cal, val, lines): (Robot, Measurements, Measurements, Vec<u64>),
        method: MethodSpec,
        models: &[Model],
    ) -> Result<(IdentifyRequest, Measurements)> {
        let source = match &self.data {
            TaskData::Split { file, .. } => file.clone(),
            TaskData::Files { calibration, .. } => calibration.clone(),
        };
        let mut q = IdentifyRequest::new(robot, IdentifyData::Tracker(cal), source, method);
        if let IdentifyData::Tracker(cal) = &q.data {
            let model = super::plausibility::tool_points(&q.robot, &cal.qs);
            let calibration = (cal, model.as_slice());
            if let Some((_, why)) =
                validation_misfit(&q.robot, calibration, &val, q.registration, None)
            {
                return Err(self.at_validation(why));
            }
        }
        q.validate = Some(val.clone());
        q.data_lines = Some(lines);
        // A refusal of a calibration row names its line of the data file.
        if let TaskData::Split { split, .. } = &self.data {
            q.data_rows = Some(split.calibration.clone());
        }
        if models != [Model::KINEMATIC] {
            q.models = models.to_vec();
        }
        if models.len() > 1 {
            q.cv = Some(5);
        }
        Ok((q, val))
    }
}

/// Who ran an entry and with what: for `task.json`.
pub struct TaskEntry<'a> {
    /// The task.
    pub task: &'a Task,
    /// The method's name.
    pub method: String,
    /// The candidate models, where they come from and the repeated choice among a task's
    /// own ([`Task::entry_request`]).
    pub models: &'a EntryModels,
    /// `calbench`, or `python:<name>` for a Python method.
    pub entrant: String,
}

impl TaskEntry<'_> {
    /// The terms of the model identified: `kinematic`, then each term added.
    pub fn model_terms(outcome: &TrackerOutcome, candidates: &[Model]) -> (Vec<String>, bool) {
        let chosen = match outcome.record.best_model() {
            Some(best) => candidates.get(best).copied(),
            None => candidates.first().copied(),
        }
        .unwrap_or(Model::KINEMATIC);
        let mut terms = vec!["kinematic".to_string()];
        terms.extend(
            chosen
                .name()
                .split('+')
                .filter(|t| *t != "kinematic")
                .map(str::to_string),
        );
        (terms, chosen.is_kinematic())
    }

    /// `task.json` of the entry whose identification is `outcome`, scored on the validation
    /// rows `val` (docs/formats.md § 9.3): its figure and interval the task's metric of their
    /// position errors (with the kernel residual's prediction where the entry has one), in the
    /// open division for a model beyond the kinematic one or a method not calbench's.
    pub fn json(&self, outcome: &TrackerOutcome, val: &Measurements) -> Result<TaskRecord> {
        let errors =
            super::kernel::position_errors(&outcome.calibrated, outcome.kernel.as_ref(), val)?;
        let considered = &self.models.candidates;
        let (models, kinematic) = match &self.models.choice {
            // The task's candidates, chosen before the request: the request holds one.
            Some(c) => Self::model_terms(outcome, &[considered[c.best]]),
            None => Self::model_terms(outcome, considered),
        };
        let open = !kinematic || self.entrant != "calbench";
        let t = self.task;
        Ok(TaskRecord {
            division: if open {
                Division::Open
            } else {
                Division::Closed
            },
            models,
            chosen_by: if considered.len() > 1 { "cv" } else { "given" }.into(),
            candidates: considered.iter().map(Model::name).collect(),
            candidates_fixed_by: Some(self.models.fixed_by.into()),
            cv_choice: self.models.choice.clone(),
            entrant: self.entrant.to_string(),
            ..t.head.record(t.metric, &self.method, errors)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metric_and_interval() {
        let e = [1.0, 2.0, 3.0, 4.0];
        let (m, ci) = Metric::ValidationMeanMm.of(&e);
        assert_eq!(m, 2.5);
        let [lo, hi] = ci.unwrap();
        // t(0.975, 3) = 3.182446; sd = 1.290994
        assert!(
            (hi - 2.5 - 3.182446 * 1.290994 / 2.0).abs() < 1e-5 && (lo + hi - 5.0).abs() < 1e-12
        );
        let (r, _) = Metric::ValidationRmsMm.of(&e);
        assert!((r - 7.5f64.sqrt()).abs() < 1e-12);
        assert_eq!(Metric::ValidationRmsMm.of(&[2.0]), (2.0, None));
    }
}
