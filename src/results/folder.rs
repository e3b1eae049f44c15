//! What a recorded folder holds, read into a [`Record`]: a run or merge folder
//! (`summary.json`), an identify folder (`identified.json`) or a task folder (`task.json`,
//! docs/formats.md "The results database").

use std::path::Path;

use serde_json::Value;

use super::provenance::sha256_hex;
use crate::analysis::figures::{flatten, Figure, Reader};
use crate::analysis::regression::check_summary_for;
use crate::calibrate::record::IdentifiedRecord;
use crate::calibrate::task::record::TASK_FILE;
use crate::calibrate::task::{task_path, TaskRecord};
use crate::error::{read_text, shown, Error, Result};
use crate::numeric::Real;
use crate::report::scenario_file;
use crate::study::kind::AnyScenario;
use crate::study::scenario::Scenario;

/// What kind of output a record is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `calbench run`'s folder.
    Run,
    /// `calbench merge`'s folder.
    Merge,
    /// `calbench identify`'s folder.
    Identify,
    /// `calbench task`'s folder.
    Task,
}

impl Kind {
    /// The name in the database's `kind` column.
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::Run => "run",
            Kind::Merge => "merge",
            Kind::Identify => "identify",
            Kind::Task => "task",
        }
    }

    /// Whether `kind`, a name of the database's `kind` column, is that of a study's run
    /// (`run` or `merge`): the records whose metrics history compares across versions.
    pub fn is_study(kind: &str) -> bool {
        [Kind::Run, Kind::Merge].iter().any(|k| k.as_str() == kind)
    }
}

/// One entry of a record (`method / poses [/ sweep value]` of a run).
#[derive(Clone, Debug)]
pub struct Entry {
    /// The entry's name.
    pub name: String,
    /// Its method.
    pub method: String,
}

/// A task entry's result (the contract of `task.json`).
#[derive(Clone, Debug, PartialEq)]
pub struct TaskResult {
    /// The task's name.
    pub task: String,
    /// The ranking metric (lower is better).
    pub metric: String,
    /// The entry's value of it.
    pub value: Real,
    /// Its 95 % interval.
    pub ci: Option<[Real; 2]>,
    /// `closed` or `open`.
    pub division: String,
    /// The method.
    pub method: String,
    /// The models used, joined by `+`.
    pub models: String,
    /// `cv` or `given`.
    pub chosen_by: String,
    /// `calbench` or `python:<name>`.
    pub entrant: String,
    /// The authors' published figures.
    pub published: Vec<Published>,
}

/// A published figure as the database keeps it: label, value (mm), source, division.
pub type Published = (String, Real, String, String);

/// A scenario's (a task's, an identification's) name with its canonical text and the
/// text's hex SHA-256 (a task's `task_hash`). The text is the scenario as run (TOML,
/// overrides applied), an identification's settings (JSON), or a task's `task.json`.
#[derive(Clone, Debug)]
pub struct Canonical {
    /// The name.
    pub name: String,
    /// The hash.
    pub hash: String,
    /// The text.
    pub text: String,
}

/// Where a record comes from: the output document, its folder, and the seed and trials.
#[derive(Clone, Debug)]
pub struct Output {
    /// The master seed, where there is one.
    pub seed: Option<u64>,
    /// The trial indices run per sweep point, e.g. `0..8`.
    pub trials: Option<String>,
    /// The folder it was read from, and the document as written there (`summary.json`,
    /// `identified.json`, `task.json`): what the content hash covers, with the scenario's
    /// hash, label and machine.
    pub source_and_document: (String, String),
}

/// What a record holds: entries, figures, a task entry's result.
#[derive(Clone, Debug, Default)]
pub struct Results {
    /// The entries: a run's `method / poses [/ sweep value]`, an identification's method,
    /// a task's `entrant / method [/ models]`.
    pub entries: Vec<Entry>,
    /// Every figure of every entry.
    pub figures: Vec<Figure>,
    /// A task entry's result.
    pub task: Option<TaskResult>,
    /// The version and commit a task's `task.json` names (the calbench that ran it;
    /// `unknown` for one it does not name); none for the other kinds.
    pub ran_with: Option<(String, String)>,
}

/// A folder's results, ready to be stored.
#[derive(Clone, Debug)]
pub struct Record {
    /// The kind of output.
    pub kind: Kind,
    /// What was run.
    pub scenario: Canonical,
    /// The output it was read from.
    pub output: Output,
    /// Its results.
    pub results: Results,
}

/// A run or merge folder's `summary.json` as read (`document`) and checked for recording:
/// its summary and its figures, unedited ([`check_summary_for`] for [`Reader::Record`]).
pub(super) struct RanSummary {
    /// The file.
    pub path: std::path::PathBuf,
    /// Its text.
    pub document: String,
    /// The summary.
    pub summary: crate::analysis::summary::Summary,
    /// Its figures.
    pub figures: Vec<Figure>,
}

impl RanSummary {
    /// The summary `v` of the file `path`, whose text is `document`, checked for recording.
    pub(super) fn check(path: &Path, document: String, v: Value) -> Result<RanSummary> {
        let (summary, figures) = check_summary_for(v, path, Reader::Record)?;
        Ok(RanSummary {
            path: path.to_path_buf(),
            document,
            summary,
            figures,
        })
    }
}

pub(super) fn read(path: &Path) -> Result<(String, Value)> {
    let text = read_text(path)?;
    let v = crate::error::json_value(path, &text)?;
    Ok((text, v))
}

impl Record {
    /// A record of `kind` read from `dir` with its `document`, of the scenario `name` whose
    /// canonical text is `text`; no seed, trials, entries, figures or task yet.
    pub(super) fn new(
        kind: Kind,
        dir: &Path,
        document: String,
        name: String,
        text: String,
    ) -> Record {
        Record {
            kind,
            scenario: Canonical {
                name,
                hash: sha256_hex(text.as_bytes()),
                text,
            },
            output: Output {
                seed: None,
                trials: None,
                source_and_document: (dir.display().to_string(), document),
            },
            results: Results::default(),
        }
    }

    /// The run or merge folder `dir` of the scenario `sc` (as run: overrides applied).
    pub fn of_run(dir: &Path, sc: &Scenario, kind: Kind) -> Result<Record> {
        let text = scenario_file::canonical(sc)?;
        let trials = Some(sc.trials);
        let path = dir.join("summary.json");
        let (document, v) = read(&path)?;
        let ran = RanSummary::check(&path, document, v)?;
        Record::of_run_text(dir, (&sc.name, Some(sc.seed), trials), text, kind, ran)
    }

    /// The run or merge folder `dir` of the scenario named `name` with its seed and trials,
    /// whose canonical text as run is `text`, from its `summary.json` as read and checked
    /// (`ran`), which must name that scenario and seed.
    pub(super) fn of_run_text(
        dir: &Path,
        (name, seed, trials): (&str, Option<u64>, Option<usize>),
        text: String,
        kind: Kind,
        ran: RanSummary,
    ) -> Result<Record> {
        let RanSummary {
            path,
            document,
            summary: s,
            figures,
        } = ran;
        let ran_seed = s.seed;
        check_ran(
            &path,
            (&s.scenario, ran_seed),
            &(name.to_string(), seed, trials),
        )?;
        let entries = s
            .results
            .iter()
            .map(|e| Entry {
                name: e.key(),
                method: e.method.clone(),
            })
            .collect();
        let mut r = Record::new(kind, dir, document, name.to_string(), text);
        r.output.seed = seed.or(ran_seed);
        r.output.trials = trials.map(|n| format!("0..{n}"));
        (r.results.entries, r.results.figures) = (entries, figures);
        Ok(r)
    }

    pub(super) fn of_identify(dir: &Path) -> Result<Record> {
        let path = dir.join("identified.json");
        let document = read_text(&path)?;
        let (id, figures) = identified(&document, &path)?;
        let scenario_text =
            serde_json::to_string(&id.settings()).map_err(|e| Error::Compute(e.to_string()))?;
        let data = Path::new(&id.data)
            .file_name()
            .map_or(String::new(), |f| f.to_string_lossy().into_owned());
        let name = format!("identify {} {data}", id.robot);
        let mut r = Record::new(Kind::Identify, dir, document, name, scenario_text);
        r.results.entries = vec![Entry {
            name: id.method.clone(),
            method: id.method,
        }];
        r.results.figures = figures;
        Ok(r)
    }

    /// The task folder `dir`, whose task file (`task`, else `tasks/<task>.toml` under the
    /// current folder) has the files its `task.toml` names beside it; a folder without
    /// `task.toml` (written before entries carried it) is checked against `task` when given,
    /// and recorded as it is without.
    pub(super) fn of_task(dir: &Path, task: Option<&Path>) -> Result<Record> {
        let path = dir.join("task.json");
        let (document, v) = read(&path)?;
        let t = TaskRecord::from_value(v.clone(), &path)?;
        // The task file the entry ran, as its folder carries it: the published figures must
        // be its own, and with the files it fixes as they are now it must have the hash the
        // entry states. A folder written before it carried one is checked against the task
        // file given (`--task`), which it then must have run, and recorded as it is without.
        let carried = dir.join(TASK_FILE);
        let file = task.map_or_else(|| task_path(&t.task), Path::to_path_buf);
        if carried.is_file() || task.is_some() {
            let ran = match carried.is_file() {
                true => carried,
                false => file.clone(),
            };
            let text = read_text(&ran)?;
            t.check_published((&document, &path), (&text, &ran))?;
            if !file.is_file() {
                let why = format!(
                    "cannot be checked: the files {} names lie beside the task file it was \
                     copied from, and {} is not a file; give the task file the entry ran with ",
                    ran.display(),
                    file.display()
                );
                let why = crate::error::Said::from(why).name(crate::error::Opt::Task);
                return Err(Error::file(&path, "task_hash", why));
            }
            t.check_ran(&path, (&text, &ran), &file)?;
            check_rows(&t, &path, (&text, &ran), &file)?;
        }
        t.check_figure(&path)?;
        let identified = dir.join("identified.json");
        let beside = match identified.is_file() {
            true => Some(read(&identified)?),
            false => None,
        };
        t.check_choice(
            &path,
            beside.as_ref().map(|(_, v)| (identified.as_path(), v)),
        )?;
        if let Some((text, _)) = &beside {
            let (id, _) = self::identified(text, &identified)?;
            t.check_identified_figure(&path, &identified, id.validation_after_mm)?;
        }
        t.check_written(&path, &v)?;
        check_ran_with(&t, &path)?;
        let bad = |key: &str, what: &str| Error::file(&path, key, what.to_string());
        let value = t.value;
        if !value.is_finite() {
            return Err(bad("value", "missing or not a finite number"));
        }
        let ci = t.ci95;
        // The metric is an error (mm): never negative, and inside its own interval.
        if value < 0.0 {
            return Err(bad(
                "value",
                "is negative: the task's metric is an error (mm), ≥ 0",
            ));
        }
        if let Some([lo, hi]) = ci {
            if lo > hi || value < lo || value > hi {
                return Err(bad(
                    "ci95",
                    &format!(
                        "[{}, {}] does not hold the value {}: edited figures",
                        shown(lo),
                        shown(hi),
                        shown(value)
                    ),
                ));
            }
        }
        if let Some(i) = t.published.iter().position(|p| p.value < 0.0) {
            return Err(bad(
                &format!("published[{i}].value"),
                "is negative: an error (mm) is ≥ 0",
            ));
        }
        let result = TaskResult::of(&t);
        let (method, models) = (&result.method, &result.models);
        let entry = if models.is_empty() {
            format!("{} / {method}", result.entrant)
        } else {
            format!("{} / {method} / {models}", result.entrant)
        };
        // The calbench that ran the entry, never the one recording it: `unknown` where the
        // entry names none (a task file outside a git repository has no commit).
        let unknown = || "unknown".to_string();
        let ran_with = (
            t.calbench_version.unwrap_or_else(unknown),
            t.git_commit.unwrap_or_else(unknown),
        );
        let task = result.task.clone();
        let mut r = Record::new(Kind::Task, dir, document.clone(), task, document);
        r.scenario.hash = t.task_hash;
        r.results.entries = vec![Entry {
            name: entry.clone(),
            method: method.clone(),
        }];
        r.results.figures = vec![Figure {
            entry,
            metric: result.metric.clone(),
            value,
            ci,
        }];
        r.results.ran_with = Some(ran_with);
        r.results.task = Some(result);
        Ok(r)
    }
}

impl TaskResult {
    /// What the database keeps of the task entry `t` (its `tasks` and `published` rows):
    /// what `record` stores and `leaderboard --verify` finds again.
    pub fn of(t: &TaskRecord) -> TaskResult {
        TaskResult {
            task: t.task.clone(),
            metric: t.metric.as_str().to_string(),
            value: t.value,
            ci: t.ci95,
            division: t.division.as_str().to_string(),
            method: t.method.clone(),
            models: t.models.join("+"),
            chosen_by: t.chosen_by.clone(),
            entrant: t.entrant.clone(),
            published: t
                .published
                .iter()
                .map(|p| {
                    let division = p.division.as_str().to_string();
                    (p.label.clone(), p.value, p.source.clone(), division)
                })
                .collect(),
        }
    }
}

/// The identification record `text` of the file `path` (an identify folder's
/// `identified.json`, or a task folder's beside its `task.json`), with the figures it holds
/// (its numbers and validation errors), refused where no identification writes it
/// ([`super::identified::check_identified`]).
fn identified(text: &str, path: &Path) -> Result<(IdentifiedRecord, Vec<Figure>)> {
    let id = IdentifiedRecord::from_json(text, path)?;
    if id.method.is_empty() {
        return Err(Error::file(
            path,
            "method",
            "missing: not an identify output",
        ));
    }
    let written = serde_json::to_value(&id).map_err(|e| Error::Compute(e.to_string()))?;
    let kept: serde_json::Map<String, Value> = written
        .as_object()
        .into_iter()
        .flatten()
        .filter(|(k, v)| v.is_number() || k.starts_with("validation_"))
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    let mut figures = Vec::new();
    flatten(&id.method, "", &kept, None, &mut figures);
    super::identified::check_identified(&id, path, &figures)?;
    Ok((id, figures))
}

/// Refuses, naming the `task.json` file `path` and `validation_errors_mm`, per-row errors
/// that are not one for each validation row of the task file the entry ran (`text`, read
/// from `ran`, its files beside the task file `file` it was copied from): rows dropped,
/// whose figure [`TaskRecord::check_figure`] recomputes as stated. An entry without them
/// (written before calbench recorded them) passes.
fn check_rows(t: &TaskRecord, path: &Path, (text, ran): (&str, &Path), file: &Path) -> Result<()> {
    let dir = file.parent().unwrap_or(Path::new("."));
    let n = t.validation_errors_mm.len();
    let rows = crate::calibrate::task::validation_rows(text, ran, dir)?;
    if n == 0 || n == rows {
        return Ok(());
    }
    let msg = format!(
        "holds {n} errors, but the task validates on {rows} rows, one error each: rows were \
         dropped or added, and the figure is not the task's"
    );
    Err(Error::file(path, "validation_errors_mm", msg).at_json_key_line())
}

/// Refuses, naming the `task.json` file `path` and the key, a calbench that ran the entry `t`
/// no `calbench task` writes: a `calbench_version` that is not a version as calbench writes
/// its own ([`VersionKey::is_release`]), a `git_commit` that is not a commit's 40 hexadecimal digits
/// (`git rev-parse HEAD`).
fn check_ran_with(t: &TaskRecord, path: &Path) -> Result<()> {
    let bad = |key: &str, msg: String| Err(Error::file(path, key, msg).at_json_key_line());
    if let Some(v) = t.calbench_version.as_deref() {
        if !super::history::VersionKey::is_release(v) {
            let msg = format!("is {v:?}, which is no version (MAJOR.MINOR.PATCH[-PRE])");
            return bad("calbench_version", msg);
        }
    }
    if let Some(c) = t.git_commit.as_deref() {
        if c.len() != 40 || !c.bytes().all(|b| b.is_ascii_hexdigit()) {
            let msg = format!("is {c:?}, which is no commit (its 40 hexadecimal digits)");
            return bad("git_commit", msg);
        }
    }
    Ok(())
}

/// The name, seed and trials of the scenario a run ran.
pub(super) type Named = (String, Option<u64>, Option<usize>);

/// The scenario a run or merge folder `dir` ran, as its canonical text, with the name, seed
/// and trials it names: the text of the folder's `scenario.toml` (its hash line checked; a
/// scenario file given, with the run's trials and seed applied, must have the same hash,
/// else it is refused naming both) with the run's own name, seed and trials (`run`, from its
/// `summary.json`); for a folder without one, the file given, else `scenarios/<name>.toml`
/// under the current folder, with the run's trials and seed applied.
pub(super) fn scenario_as_run(
    dir: &Path,
    (name, trials, seed): (&str, Option<usize>, Option<u64>),
    scenario: Option<&Path>,
) -> Result<(String, Named)> {
    let given = |file: &Path| -> Result<AnyScenario> {
        AnyScenario::load(file)?.with_run_overrides(trials, seed)
    };
    let ran = dir.join(scenario_file::NAME);
    if ran.is_file() {
        let file_text = read_text(&ran)?;
        let (text, hash) = scenario_file::read(&file_text, &ran)?;
        // Its name, trials and seed, read from its text alone: its other settings may name
        // files by paths relative to the scenario's own folder, which the run folder is not.
        let own: toml::Table = crate::error::toml_keys(&ran, &text)?;
        scenario_file::same_run(&dir.join("summary.json"), (name, trials, seed), &own)?;
        if let Some(file) = scenario {
            let other = sha256_hex(given(file)?.settings()?.as_bytes());
            if other != hash {
                return Err(Error::file(
                    file,
                    "scenario",
                    format!(
                        "is not the scenario the run ran: with the run's trials and seed it \
                         has SHA-256 {other}, but {} (the scenario as run) has {hash}; record \
                         the folder without a scenario file, or with the one it ran",
                        ran.display()
                    ),
                ));
            }
        }
        return Ok((text, (name.to_string(), seed, trials)));
    }
    let fallback = Path::new("scenarios").join(format!("{name}.toml"));
    let file = match scenario {
        Some(p) => p.to_path_buf(),
        None if !name.is_empty() && fallback.is_file() => fallback,
        None => {
            return Err(Error::file(
                dir,
                "summary.json",
                format!(
                    "the folder holds no scenario.toml and the scenario `{name}` of this run \
                     is not at {}; give its file with --scenario FILE",
                    fallback.display()
                ),
            ))
        }
    };
    let sc = given(&file)?;
    let named = (sc.name().to_string(), Some(sc.seed()), Some(sc.trials()));
    Ok((sc.settings()?, named))
}

/// Refuses, naming the summary `path`, a run of the scenario `ran` with the seed `ran_seed`
/// recorded as the scenario `named` (name, seed, trials) of another name or seed.
pub(super) fn check_ran(
    path: &Path,
    (ran, ran_seed): (&str, Option<u64>),
    (name, seed, _): &Named,
) -> Result<()> {
    if ran == name && (ran_seed.is_none() || seed.is_none() || ran_seed == *seed) {
        return Ok(());
    }
    let show = |s: Option<u64>| s.map_or("?".into(), |s| s.to_string());
    Err(Error::file(
        path,
        "scenario",
        format!(
            "the run is of `{ran}` with seed {}, the scenario given is `{name}` with seed {}",
            show(ran_seed),
            show(*seed)
        ),
    ))
}
