//! Every writer of calbench's output files (docs/formats.md), each file an [`Output`]
//! ([`output`]: the trait, its common writers, and the writing of a folder): [`run`] makes a
//! run's `summary.json`, `trials.csv`, `timing.json`, `report.md` and figures
//! ([`run_outputs`] adds `report.html`); [`identified`] the files of `calbench identify`;
//! [`html`] the self-contained pages `report.html` and `compare.html`; [`poses`],
//! [`simulated`] and [`program`] the files of `calbench poses`, `simulate` and `compensate`.
//!
//! The report only reads results that are already computed: it runs no study (running,
//! resuming, sharding and merging a study are [`crate::runner::run`] and
//! [`crate::runner::shard`], which call these writers). [`plots`] draws the
//! figures of the source papers — η per parameter per method (Guo 2024, fig. 8), validation
//! error per point before and after calibration (Li 2018, fig. 3; Ban, fig. 7), validation
//! RMS over trials per method, objective or fitness per iteration (Qiao 2021; Guo 2024,
//! DETMAX-IDE) and a metric against a swept setting — each to `<stem>.png` and `<stem>.svg`.
//! [`markdown`] formats tables and numbers for `report.md`.
//!
//! Text is drawn with the bundled DejaVu Sans (`assets/DejaVuSans.ttf`, registered once as
//! family `sans-serif`), so plots render the same on every machine without system font
//! libraries, and the same data gives the same bytes.

pub mod exports;
pub mod guard;
pub mod html;
pub mod identified;
pub mod instruments;
pub mod markdown;
pub mod output;
pub mod plots;
pub mod poses;
pub mod practice;
pub mod program;
pub mod registration_study;
pub mod run;
pub mod scenario_file;
pub mod simulated;

pub use markdown::{fmt_num, table};
pub use output::Output;
pub use plots::{
    before_after, box_plot, box_stats, grouped_bars, heatmap, sweep, traces, BoxStats, SweepSeries,
    PLOT_SIZE,
};
pub use run::{columns, entry_table, Column, TrialsCsv};

use crate::analysis::summary::Summary;

/// The files of a complete run but `trials.csv` (streamed as the trials finish,
/// [`TrialsCsv`]), in the order they are written: those of [`run::outputs`] with the run's
/// figures ([`run::figures`]), then `report.html` ([`html::run`]), which inlines them.
pub fn run_outputs<'a>(
    r: &'a crate::study::RunResult,
    summary: &'a Summary,
) -> crate::Result<output::Outputs<'a>> {
    let figures = run::figures(r, summary);
    let listed: Vec<(String, String)> = figures.iter().map(output::Figure::listed).collect();
    let mut outputs = run::outputs(r, summary, figures)?;
    outputs.push(Box::new(output::FromFolder {
        name: "report.html",
        make: Box::new(move |dir| Ok(html::run::page(r, summary, &listed, dir)?.finish())),
    }));
    Ok(outputs)
}

/// Writes every file of a complete run into the folder `dir`: its finished `trials.csv`,
/// then those of [`run_outputs`] rendering its `summary`.
pub fn write_run(
    r: &crate::study::RunResult,
    summary: &Summary,
    trials_csv: Box<dyn Output>,
    dir: &std::path::Path,
) -> crate::Result<()> {
    let mut outputs = vec![trials_csv];
    outputs.extend(run_outputs(r, summary)?);
    output::write_all(dir, &outputs)
}

/// Writes the output folder of `calbench identify` as a whole ([`atomically`]): the files of
/// [`identified::outputs`], then `report.html` ([`html::identify`]); with `more` keys added
/// to `identified.json` and a section to `report.md` (cross-validation, priors, diagnostics: [`practice`]), and the `files`
/// (name, text) written beside them (the controller exports, [`exports`]).
pub fn write_identified_with(
    out: &std::path::Path,
    r: &identified::IdentifyRecord,
    more: &identified::Additions,
    files: &[(&str, String)],
) -> crate::Result<()> {
    let mut outputs = output::texts(files);
    outputs.extend(identified::outputs(r, more)?);
    outputs.push(Box::new(output::FromFolder {
        name: "report.html",
        make: Box::new(|dir| Ok(html::identify::page(dir, r, more)?.finish())),
    }));
    output::folder_of(out, &outputs)
}

/// Writes the output folder of an identification on a kind file as a whole ([`atomically`]):
/// `identified.json` of `record`, `robot.toml` of the compensated `robot`, and the `files`
/// (name, text) beside them (a socket task's `task.json` and `task.toml`).
pub fn write_kind(
    out: &std::path::Path,
    record: &crate::calibrate::record::IdentifiedRecord,
    robot: &crate::robot::Robot,
    files: &[(&str, String)],
) -> crate::Result<()> {
    let mut outputs: output::Outputs<'_> = vec![
        Box::new(identified::identified_json(record)),
        Box::new(output::RobotToml {
            name: "robot.toml",
            robot,
        }),
    ];
    outputs.extend(output::texts(files));
    output::folder_of(out, &outputs)
}

/// The folder holding `out` (`.` for a bare name) and `out`'s last part (`out` when it has
/// none): where the temporary and checkpoint folders of an output folder go.
pub fn parent_and_name(out: &std::path::Path) -> (std::path::PathBuf, String) {
    let name = out
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    let parent = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(std::path::Path::new("."));
    (parent.to_path_buf(), name)
}

/// The temporary folder or file `.NAME.partial-PID` beside the output `out` that process `pid`
/// writes before it becomes `out` ([`atomically`], [`output::json_file`]), and that a killed
/// run's checkpoint names.
pub fn partial_path(out: &std::path::Path, pid: u32) -> std::path::PathBuf {
    let (parent, name) = parent_and_name(out);
    parent.join(partial_name(&name, pid))
}

/// Removes the temporary folders `.NAME.partial-PID` beside the output folder `out` whose
/// process no longer runs on this host (a `merge` or an `identify` killed before it moved its
/// files into `out`), unless a run's checkpoint beside `out` keeps one for its resume
/// (`run --resume` and a new run into `out` remove that one). Best effort: a temporary
/// folder that cannot be removed stays.
fn remove_dead_partials(out: &std::path::Path) {
    if checkpoint_folder(out).exists() {
        return;
    }
    let (parent, name) = parent_and_name(out);
    let prefix = format!(".{name}.partial-");
    let Ok(entries) = std::fs::read_dir(&parent) else {
        return;
    };
    for entry in entries.flatten() {
        let file = entry.file_name();
        let pid = file.to_str().and_then(|f| f.strip_prefix(&prefix));
        let pid = pid.and_then(|p| p.parse::<u32>().ok());
        let folder = entry.file_type().is_ok_and(|t| t.is_dir());
        if pid.is_some_and(|p| folder && p != std::process::id() && !guard::alive(p)) {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

/// The name of the temporary folder `.NAME.partial-PID` ([`partial_path`]).
fn partial_name(name: &str, pid: u32) -> String {
    format!(".{name}.partial-{pid}")
}

/// The checkpoint folder of the output folder `out`: `.NAME.checkpoint` beside it, where a
/// run keeps what it has done until it ends.
pub fn checkpoint_folder(out: &std::path::Path) -> std::path::PathBuf {
    let (parent, name) = parent_and_name(out);
    parent.join(format!(".{name}.checkpoint"))
}

/// The first path that keeps `out` from being written as a folder holding the files `names`:
/// `out` itself when it exists and is not a folder, or `out/NAME` when that is a folder
/// (which no file can replace). `None` when nothing is in the way.
pub fn blocked_output<S: AsRef<std::ffi::OsStr>>(
    out: &std::path::Path,
    names: impl IntoIterator<Item = S>,
) -> Option<std::path::PathBuf> {
    if out.exists() && !out.is_dir() {
        return Some(out.to_path_buf());
    }
    names
        .into_iter()
        .map(|n| out.join(n.as_ref()))
        .find(|p| std::fs::symlink_metadata(p).is_ok_and(|m| m.is_dir()))
}

/// `summary.json` of a study that runs whole (a registration or an instruments study):
/// `scenario`, `description`, `kind`, `trials` and `seed`, then `more`'s keys.
pub(crate) fn whole_summary(
    (scenario, description, kind): (&str, &str, &str),
    (trials, seed): (usize, u64),
    more: serde_json::Value,
) -> crate::Result<output::Text<'static>> {
    let mut summary = serde_json::json!({
        "scenario": scenario, "description": description, "kind": kind,
        "trials": trials, "seed": seed,
    });
    if let (Some(head), serde_json::Value::Object(more)) = (summary.as_object_mut(), more) {
        head.extend(more);
    }
    Ok(output::Text {
        name: "summary.json",
        text: run::json_text(&summary)?,
    })
}

/// The folders an output path needed and a command created for it (the output folder or the
/// folders that hold it, missing ancestors included): when the value is dropped, those still
/// empty are removed again, the deepest first, so that a command refused after it made its
/// output folder leaves no folder it created; folders that existed before are never touched,
/// and a folder that received the outputs is not empty and stays. [`atomically`], the command
/// line's probe of an output folder and a run's checkpoint make their folders through it.
#[must_use = "the folders are removed again, when still empty, as soon as this is dropped"]
pub struct MadeFolders(Vec<std::path::PathBuf>);

impl MadeFolders {
    /// Creates the folder `dir` and its missing ancestors, and remembers those it created.
    ///
    /// Another process may remove an empty folder it made between the look for the missing
    /// folders and the creation of one inside it (the shards of one run started at once into
    /// one new folder, each probing its own `--out`): the creation then starts again from the
    /// folder that vanished.
    pub fn create(dir: &std::path::Path) -> crate::Result<MadeFolders> {
        const ATTEMPTS: usize = 1000;
        let mut made = MadeFolders(Vec::new());
        let mut attempt = 0;
        'again: loop {
            let missing: Vec<std::path::PathBuf> = dir
                .ancestors()
                .filter(|p| !p.as_os_str().is_empty())
                .take_while(|p| std::fs::symlink_metadata(p).is_err())
                .map(std::path::Path::to_path_buf)
                .collect();
            for p in missing.into_iter().rev() {
                match std::fs::create_dir(&p) {
                    Ok(()) => made.0.push(p),
                    Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && p.is_dir() => {}
                    // NotFound: a folder above vanished; AlreadyExists with nothing there: `p`
                    // itself was made and removed again between the creation and the look.
                    Err(e)
                        if attempt < ATTEMPTS
                            && (e.kind() == std::io::ErrorKind::NotFound
                                || (e.kind() == std::io::ErrorKind::AlreadyExists
                                    && std::fs::symlink_metadata(&p).is_err())) =>
                    {
                        attempt += 1;
                        continue 'again;
                    }
                    Err(e) => return Err(crate::Error::io(&p, e)),
                }
            }
            return Ok(made);
        }
    }
}

impl Drop for MadeFolders {
    fn drop(&mut self) {
        for p in self.0.iter().rev() {
            match std::fs::remove_dir(p) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => break,
                _ => {}
            }
        }
    }
}

/// Makes the temporary folder `.NAME.partial-PID` beside `out` ([`partial_path`]) with the
/// folders above it ([`MadeFolders`]), so that none of them is ever an empty folder another
/// process may remove before this one is made in it. A folder that cannot be made is refused
/// naming `out`, the folder asked for, rather than the temporary one.
fn make_partial(out: &std::path::Path) -> crate::Result<(std::path::PathBuf, MadeFolders)> {
    let tmp = partial_path(out, std::process::id());
    let made = MadeFolders::create(&tmp).map_err(|e| match e {
        crate::Error::Io { path, cause } if path == tmp => {
            let why = format!(
                "{cause}: the folder is written as a whole, through a temporary folder beside \
                 it ({})",
                tmp.file_name().unwrap_or_default().to_string_lossy()
            );
            crate::Error::io(out, std::io::Error::new(cause.kind(), why))
        }
        e => e,
    })?;
    Ok((tmp, made))
}

/// Checks, before any work, that [`atomically`] can write `out`: its temporary folder is made
/// beside `out` and removed again, with any folder made to hold it.
pub fn probe_partial(out: &std::path::Path) -> crate::Result<()> {
    make_partial(out).map(drop)
}

/// Writes a folder of outputs as a whole: `write` fills a fresh temporary folder beside `out`
/// (`.<name>.partial-<pid>`). When it succeeds, the folder becomes `out` (one rename when
/// `out` is absent or empty; otherwise each new file replaces its namesake in `out`, other
/// files there are kept). On failure the temporary folder is removed and `out` is left as it
/// was, so a failed run leaves nothing half-written; that includes an `out` that is a file,
/// or that holds a folder named like one of the new files ([`blocked_output`]), which is
/// refused, naming it, before any file is moved; so is the root or the home folder
/// ([`guard::guard_folder`]). The folders made to hold `out` are removed again on failure
/// ([`MadeFolders`]).
pub fn atomically(
    out: &std::path::Path,
    write: impl FnOnce(&std::path::Path) -> crate::Result<()>,
) -> crate::Result<()> {
    use crate::Error;
    // A refusal of the output folder asked for, which each front end names its own way.
    let in_the_way = |p: std::path::PathBuf| {
        let why = if p == out {
            "exists and is not a folder; nothing was written"
        } else {
            "is a folder where an output file of that name is to be written; nothing was written"
        };
        Error::option(crate::error::Opt::Out, format!("{} {why}", p.display()))
    };
    guard::guard_folder(out, "out")?;
    let _writing = guard::Writing::hold(out)?;
    if let Some(p) = blocked_output(out, None::<&str>) {
        return Err(in_the_way(p));
    }
    let _ = std::fs::remove_dir_all(partial_path(out, std::process::id()));
    remove_dead_partials(out);
    let (tmp, _made) = make_partial(out)?;
    let done = write(&tmp).and_then(|()| {
        let written = std::fs::read_dir(&tmp)
            .map_err(|e| Error::io(&tmp, e))?
            .map(|e| e.map(|e| e.file_name()).map_err(|e| Error::io(&tmp, e)))
            .collect::<crate::Result<Vec<_>>>()?;
        if let Some(p) = blocked_output(out, &written) {
            return Err(in_the_way(p));
        }
        let empty = out.read_dir().map_or(true, |mut d| d.next().is_none());
        if out.is_dir() && empty {
            std::fs::remove_dir(out).map_err(|e| Error::io(out, e))?;
        }
        if !out.exists() {
            return std::fs::rename(&tmp, out).map_err(|e| Error::io(out, e));
        }
        for entry in std::fs::read_dir(&tmp).map_err(|e| Error::io(&tmp, e))? {
            let entry = entry.map_err(|e| Error::io(&tmp, e))?;
            let target = out.join(entry.file_name());
            std::fs::rename(entry.path(), &target).map_err(|e| Error::io(&target, e))?;
        }
        std::fs::remove_dir(&tmp).map_err(|e| Error::io(&tmp, e))
    });
    if done.is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    done
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_nothing_and_a_good_one_keeps_other_files() {
        let root = std::env::temp_dir().join(format!("calbench-atomic-{}", std::process::id()));
        let out = root.join("results");
        let _ = std::fs::remove_dir_all(&root);
        // Failure half-way: neither the folder, nor a temporary one, nor the folder made to
        // hold them is left.
        let r = atomically(&out, |d| {
            std::fs::write(d.join("summary.json"), "{}").unwrap();
            Err(crate::Error::Compute("disk full".into()))
        });
        assert!(r.is_err());
        assert!(!root.exists());
        // Success into an absent folder, then into a folder holding a user's file.
        let write = |d: &std::path::Path| {
            std::fs::write(d.join("summary.json"), "{\"n\": 1}").map_err(|e| crate::Error::io(d, e))
        };
        atomically(&out, write).unwrap();
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        atomically(&out, write).unwrap();
        assert!(out.join("notes.txt").exists() && out.join("summary.json").exists());
        assert_eq!(std::fs::read_dir(&root).unwrap().count(), 1);
        // A folder where a new file goes: refused, naming it, before any file is moved.
        std::fs::create_dir(out.join("trials.csv")).unwrap();
        let e = atomically(&out, |d| {
            std::fs::write(d.join("summary.json"), "{\"n\": 2}").unwrap();
            std::fs::write(d.join("trials.csv"), "n\n2\n").map_err(|e| crate::Error::io(d, e))
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("trials.csv") && e.contains("is a folder"), "{e}");
        let kept = std::fs::read_to_string(out.join("summary.json")).unwrap();
        assert_eq!(kept, "{\"n\": 1}");
        assert_eq!(std::fs::read_dir(&root).unwrap().count(), 1);
        // A file where the folder goes: refused, naming it, before `write` runs.
        let file = out.join("notes.txt");
        let e = atomically(&file, |_| unreachable!())
            .unwrap_err()
            .to_string();
        assert!(e.contains("notes.txt") && e.contains("not a folder"), "{e}");
        std::fs::remove_dir_all(&root).unwrap();
    }

    /// Processes (here threads) that make folders in one new folder at once, each removing
    /// again what it made once it is empty, as shards started together do: none fails for a
    /// folder another removed under it. (Which of them made a shared folder is a race, so an
    /// empty shared folder may stay: only its maker removes it.)
    #[test]
    fn folders_made_at_once_in_one_new_folder_do_not_fail_each_other() {
        let root = std::env::temp_dir().join(format!("calbench-made-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let (threads, rounds) = (8, 300);
        let start = std::sync::Barrier::new(threads);
        let failed = std::sync::Mutex::new(Vec::new());
        std::thread::scope(|s| {
            for t in 0..threads {
                let (root, start, failed) = (&root, &start, &failed);
                s.spawn(move || {
                    for r in 0..rounds {
                        let leaf = root.join(format!("{r}/shards/run/{t}"));
                        start.wait();
                        match MadeFolders::create(&leaf) {
                            Ok(made) => drop(made),
                            Err(e) => failed.lock().unwrap().push(e.to_string()),
                        }
                        if leaf.exists() {
                            failed
                                .lock()
                                .unwrap()
                                .push(format!("{} stays", leaf.display()));
                        }
                    }
                });
            }
        });
        std::fs::remove_dir_all(&root).unwrap();
        let failed = failed.into_inner().unwrap();
        assert!(failed.is_empty(), "{} failures: {failed:?}", failed.len());
    }
}
