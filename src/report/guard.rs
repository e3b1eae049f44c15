//! The output-folder guard of every writer (docs/formats.md § 1, "Output folders"): an
//! output path where the outputs would destroy something is refused before any work — the
//! root folder, the home folder (`$HOME`), an input of the command (a file or folder it
//! reads), a folder holding an input under the name of one of the files written there, or a
//! folder holding another command's results ([`SIGNATURES`]).
//! The command line, Python's `run`, `study.write` and `task` and every folder written whole
//! ([`super::atomically`]) go through [`guard_out`]; the caller names its option (`key`).

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Refuses, before any work, an output path `out` (the caller's option `key`) where the
/// outputs would destroy something: the root folder, the home folder (`$HOME`), one of
/// `inputs` (a file or folder the command reads), or a folder holding one of them under the
/// name of one of `outputs`, the files written there (empty for the commands that write the
/// one file `out`), or a folder holding another command's results ([`SIGNATURES`] that
/// `outputs` lacks; not checked when `outputs` is empty). Paths are compared as the file
/// system resolves them (`.`, `..` and symbolic links); and a folder a live run writes into
/// ([`live_writer`]). An output folder (`outputs` not empty) is also refused for what its
/// writing ([`super::atomically`]) would refuse after the work: `out` a file, or one of
/// `outputs` a folder in it ([`blocked_folder`]).
pub fn guard_out<P: AsRef<Path>>(
    out: &Path,
    key: &str,
    outputs: &[&str],
    inputs: impl IntoIterator<Item = P>,
) -> Result<()> {
    guard(out, key, outputs, inputs, None)?;
    if outputs.is_empty() {
        return Ok(());
    }
    blocked_folder(out, key, outputs)
}

/// Refuses, naming the path in the way, an output folder `out` (the caller's option `key`)
/// that cannot hold the files `outputs`: `out` is not a folder, or one of `outputs` is a
/// folder in it. Nothing is created.
pub fn blocked_folder(out: &Path, key: &str, outputs: &[&str]) -> Result<()> {
    match super::blocked_output(out, outputs) {
        None => Ok(()),
        Some(p) if p == out => Err(Error::setting(
            key,
            format!("{} exists and is not a folder", out.display()),
        )),
        Some(p) => Err(Error::setting(
            key,
            format!(
                "{} is a folder, where the command writes a file of that name; nothing was \
                 written",
                p.display()
            ),
        )),
    }
}

/// The files that mark a folder as the results of one command, each with what wrote it: a
/// command that does not write the file refuses to write into such a folder, which would
/// otherwise hold two results mixed (a run's `summary.json` beside an identification's
/// `report.md`).
pub const SIGNATURES: [(&str, &str); 5] = [
    ("trials.csv", "a study's run"),
    ("summary.json", "a study's run"),
    ("shard.json", "a shard of a run"),
    ("identified.json", "an identification"),
    ("task.json", "a task's entry"),
];

/// [`guard_out`] without the live run's check.
fn paths<P: AsRef<Path>>(
    out: &Path,
    key: &str,
    outputs: &[&str],
    inputs: impl IntoIterator<Item = P>,
) -> Result<()> {
    let refuse = |why: String| Err(Error::setting(key, why));
    if out.as_os_str().is_empty() {
        return refuse(
            "is empty; give the outputs a folder or file name (nothing was written)".into(),
        );
    }
    // A path from Python may hold a NUL byte, which no file name can: refused as the key's,
    // where the system's refusal named the temporary folder of the outputs.
    if out.as_os_str().as_encoded_bytes().contains(&0) {
        return refuse(format!(
            "{out:?} holds a NUL byte, which no file or folder name can (nothing was written)"
        ));
    }
    let at = resolved(out);
    if at.parent().is_none() {
        return refuse(format!(
            "{} is the root folder; give the outputs a folder of their own (nothing was \
             written)",
            out.display()
        ));
    }
    if let Some(home) = std::env::var_os("HOME").filter(|h| !h.is_empty()) {
        if resolved(Path::new(&home)) == at {
            return refuse(format!(
                "{} is the home folder; give the outputs a folder of their own (nothing was \
                 written)",
                out.display()
            ));
        }
    }
    for input in inputs {
        let input = input.as_ref();
        if !input.exists() {
            continue;
        }
        let it = resolved(input);
        if it == at {
            return refuse(format!(
                "{} is an input of this command; writing the outputs there would destroy it \
                 (nothing was written)",
                out.display()
            ));
        }
        if let Some(name) = outputs.iter().find(|n| at.join(n) == it) {
            return refuse(format!(
                "{} is an input of this command, and the command writes its {name} there; \
                 give another output folder (nothing was written)",
                input.display()
            ));
        }
    }
    // An input is named first: the more precise refusal.
    let foreign = SIGNATURES.iter().find(|(file, _)| {
        !outputs.is_empty() && !outputs.contains(file) && at.join(file).is_file()
    });
    if let Some((file, what)) = foreign {
        return refuse(format!(
            "{} holds the results of {what} ({file}), which this command does not write; its \
             files there would mix two results (nothing was written): give another folder",
            out.display()
        ));
    }
    Ok(())
}

/// [`guard_out`], where `force` lets a folder a live run writes into pass (`run --force`).
pub fn guard_out_with<P: AsRef<Path>>(
    out: &Path,
    key: &str,
    outputs: &[&str],
    inputs: impl IntoIterator<Item = P>,
    force: bool,
) -> Result<()> {
    guard(out, key, outputs, inputs, Some(force))
}

/// [`guard_out_with`] for a command that has `--force` (`Some`, whether it was given) or not.
fn guard<P: AsRef<Path>>(
    out: &Path,
    key: &str,
    outputs: &[&str],
    inputs: impl IntoIterator<Item = P>,
    force: Option<bool>,
) -> Result<()> {
    paths(out, key, outputs, inputs)?;
    let checkpoint = super::checkpoint_folder(out);
    match live_writer(out) {
        // Forcing passes a number another program took, never the run that is writing.
        Some(pid) if force == Some(true) && writing(pid, &checkpoint) => Err(Error::setting(
            key,
            format!(
                "{} is the output folder of a run still in progress: process {pid} holds its \
                 checkpoint's records.txt open ({}), so it is that run, not another program \
                 that took its number, and forcing does not pass it (nothing was written). \
                 Wait for it or stop it",
                out.display(),
                checkpoint.display(),
            ),
        )),
        Some(pid) if force != Some(true) => Err(Error::setting(
            key,
            format!(
                "{} is the output folder of a run still in progress (process {pid} on this \
                 host, its checkpoint {}); writing there would destroy it (nothing was \
                 written). Wait for it or stop it{}",
                out.display(),
                checkpoint.display(),
                match force {
                    Some(_) => " (forcing passes when that process is not calbench)",
                    None => "",
                }
            ),
        )),
        _ => Ok(()),
    }
}

/// The process of another run writing into `out` that is alive on this host: the `pid` and
/// `host` of the `checkpoint.json` beside `out` ([`super::checkpoint_folder`]), when that process runs.
pub fn live_writer(out: &Path) -> Option<u32> {
    let (pid, on_this_host) = writer(out)?;
    (on_this_host && alive(pid)).then_some(pid)
}

/// Whether process `pid` holds the file `records.txt` of the checkpoint folder `checkpoint`
/// open (its `/proc/PID/fd` links, where they can be read): the run that writes it, as every
/// run keeps its records open while it runs. `false` where it cannot be told.
pub fn writing(pid: u32, checkpoint: &Path) -> bool {
    let Ok(records) = checkpoint.join("records.txt").canonicalize() else {
        return false;
    };
    let Ok(fds) = std::fs::read_dir(format!("/proc/{pid}/fd")) else {
        return false;
    };
    fds.flatten()
        .any(|fd| std::fs::read_link(fd.path()).is_ok_and(|l| l == records))
}

/// The process that the checkpoint beside `out` names, and whether it ran on this host.
pub(crate) fn writer(out: &Path) -> Option<(u32, bool)> {
    let text =
        crate::error::read_bounded_text(&super::checkpoint_folder(out).join("checkpoint.json"))
            .ok()?;
    let meta: serde_json::Value = serde_json::from_str(&text).ok()?;
    let pid = u32::try_from(meta.get("pid")?.as_u64()?).ok()?;
    Some((pid, meta.get("host")?.as_str()? == host()))
}

/// The name of this host (empty where it cannot be read).
pub fn host() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .or_else(|_| std::fs::read_to_string("/etc/hostname"))
        .or_else(|_| std::env::var("HOSTNAME"))
        .map(|h| h.trim().to_string())
        .unwrap_or_default()
}

/// Whether process `pid` (not this one) is running on this host: its `/proc` entry, not a
/// zombie, where there is a `/proc`; otherwise `kill -0`.
pub fn alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return false;
    }
    if Path::new("/proc/self").exists() {
        return std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|s| {
            let state = s.rsplit_once(')').map(|(_, rest)| rest.trim_start());
            !matches!(state.and_then(|r| r.chars().next()), Some('Z' | 'X') | None)
        });
    }
    std::process::Command::new("kill")
        .args(["-0", &pid.to_string()])
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// The output folders (resolved) this process writes, each with the thread that writes it
/// ([`Writing`]).
static WRITING: std::sync::Mutex<Vec<(PathBuf, std::thread::ThreadId)>> =
    std::sync::Mutex::new(Vec::new());

/// A thread's hold on an output folder while it writes it: a run from its checkpoint to its
/// last file, a folder written as a whole ([`super::atomically`]). Another thread of this
/// process is refused the folder until the hold is dropped, as another process is refused a
/// folder whose checkpoint names it ([`live_writer`]): both would write one temporary folder
/// and one checkpoint (named by the process), and the second would remove the first's as a
/// killed run's. The thread that holds a folder may hold it again (a run's checkpoint, then
/// its output).
#[must_use = "the folder is released as soon as this is dropped"]
pub struct Writing(Option<PathBuf>);

impl Writing {
    /// Holds `out` for this thread, or refuses it when another thread of this process holds
    /// it.
    pub fn hold(out: &Path) -> Result<Writing> {
        let path = resolved(out);
        let me = std::thread::current().id();
        let mut held = WRITING
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        match held.iter().find(|(p, _)| *p == path) {
            Some((_, t)) if *t == me => Ok(Writing(None)),
            Some(_) => Err(Error::option(
                crate::error::Opt::Out,
                format!(
                    "{} is the output folder of a run still in progress in this process (another \
                     thread writes it); writing there would destroy it (nothing was written). \
                     Wait for it",
                    out.display()
                ),
            )),
            None => {
                held.push((path.clone(), me));
                Ok(Writing(Some(path)))
            }
        }
    }
}

impl Drop for Writing {
    fn drop(&mut self) {
        if let Some(path) = self.0.take() {
            let mut held = WRITING
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            held.retain(|(p, _)| *p != path);
        }
    }
}

/// [`guard_out`] of a folder written with no input named: the root and the home folder.
pub fn guard_folder(out: &Path, key: &str) -> Result<()> {
    paths(out, key, &[], None::<&Path>)
}

/// `p` as an absolute path with `.` and `..` folded and the longest part that exists
/// resolved by the file system (symbolic links followed).
fn resolved(p: &Path) -> PathBuf {
    use std::path::Component;
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut folded = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                folded.pop();
            }
            c => folded.push(c),
        }
    }
    let mut rest = Vec::new();
    let mut head = folded.as_path();
    loop {
        if let Ok(mut real) = head.canonicalize() {
            real.extend(rest.iter().rev());
            return real;
        }
        match (head.parent(), head.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                head = parent;
            }
            _ => return folded,
        }
    }
}

/// Refuses, before any work, an output folder `out` (the caller's option `key`) that holds one
/// of `data`, the measurement files a command reads: a task's outputs written into its data
/// folder would lie beside the data as if they were part of it.
pub fn guard_data_folder<P: AsRef<Path>>(
    out: &Path,
    key: &str,
    data: impl IntoIterator<Item = P>,
) -> Result<()> {
    let at = resolved(out);
    for file in data {
        let file = file.as_ref();
        if file.is_file() && resolved(file).parent() == Some(&at) {
            return Err(Error::setting(
                key,
                format!(
                    "{} holds {}, an input of this command (its data); give the outputs a \
                     folder of their own (nothing was written)",
                    out.display(),
                    file.display()
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::Writing;

    /// A folder held by one thread is refused to another until the hold is dropped; the
    /// thread that holds it may hold it again (a run's checkpoint, then its output), and that
    /// second hold does not release it.
    #[test]
    fn a_folder_one_thread_writes_is_refused_to_another_until_released() {
        let out = std::env::temp_dir().join(format!("calbench-hold-{}", std::process::id()));
        let other = |out: std::path::PathBuf| {
            std::thread::spawn(move || Writing::hold(&out).map(drop).map_err(|e| e.to_string()))
                .join()
                .unwrap()
        };
        let first = Writing::hold(&out).unwrap();
        let again = Writing::hold(&out.join(".")).unwrap();
        drop(again);
        let refused = other(out.clone()).unwrap_err();
        assert!(refused.contains("another thread writes it"), "{refused}");
        drop(first);
        other(out).unwrap();
    }
}
