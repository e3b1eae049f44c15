//! The commands of the `calbench` binary, one module each: its arguments (a `clap::Args`
//! struct whose doc comments are the `--help` text) and its `run`, which calls the library,
//! prints to stdout and writes files through [`calbench::report`]. `main.rs` parses the
//! command line, dispatches and reports errors. This module holds what several commands share.

use std::path::{Path, PathBuf};

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};

use calbench::error::{Error, Result};
use calbench::numeric::Real;
use calbench::report::markdown::table as markdown_table;
use calbench::report::output::{folder, Bytes};
use calbench::report::{entry_table, MadeFolders};
use calbench::study::RunResult;

/// `println!` that ignores a closed stdout (`calbench … | head`): results are on disk before
/// anything is printed, and a reader that stops early is not an error. Control characters are
/// escaped ([`escaped`]): a robot's or a parameter's name read from a file may hold any.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), "{}", $crate::cli::escaped(&format!($($arg)*)));
    }};
}

/// `eprintln!` likewise: a line of results on stderr (`check`'s regressions).
macro_rules! err {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), "{}", $crate::cli::escaped(&format!($($arg)*)));
    }};
}

/// `print!` likewise.
macro_rules! out_raw {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stdout(), "{}", $crate::cli::escaped(&format!($($arg)*)));
    }};
}

pub mod check;
pub mod compare;
pub mod compensate;
pub mod fk;
pub mod history;
pub mod identifiability;
pub mod identify;
pub mod identify_kind;
pub mod import;
pub mod leaderboard;
pub mod merge;
pub mod poses;
pub mod record;
pub mod robots;
pub mod run;
pub mod simulate;
pub mod task;

/// How the command line spells an option the library names ([`calbench::error::Opt`]):
/// `--allow-worse`, named and turned on alike.
pub fn spell(opt: calbench::error::Opt, _on: bool) -> String {
    format!("--{}", opt.name().replace('_', "-"))
}

/// An error as the command line shows it: its causes joined as `{:#}` joins them, the
/// library's errors with their options spelled by `spell` ([`spell`], or that of a command
/// that takes only some of them, [`task::spell`]).
pub fn message(e: &anyhow::Error, spell: calbench::error::Spell) -> String {
    let parts: Vec<String> = e
        .chain()
        .map(|c| match c.downcast_ref::<Error>() {
            Some(e) => e.spelled(spell),
            None => c.to_string(),
        })
        .collect();
    for_terminal(&parts.join(": "))
}

/// The longest line of an error the terminal is shown, in characters.
const MAX_LINE: usize = 2000;

/// `text` as a terminal may show it: control characters other than line breaks and tabs
/// escaped (`\u{1b}`), as a name read from a file may hold any, and a line longer than
/// [`MAX_LINE`] characters (a header of megabytes, a file of NUL bytes read as one name) cut,
/// saying by how much.
pub fn for_terminal(text: &str) -> String {
    text.split('\n')
        .map(|line| {
            let mut chars = line.chars();
            let mut out = escaped(&chars.by_ref().take(MAX_LINE).collect::<String>());
            let more = chars.count();
            if more > 0 {
                out.push_str(&format!("… ({more} characters more)"));
            }
            out
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// `text` with its control characters other than line breaks and tabs, and its bidirectional
/// formatting characters, escaped (`\u{1b}`, `\u{202e}`; [`calbench::error::is_hidden`]):
/// what every line of results on stdout or stderr is given (results are not cut, unlike an
/// error's lines in [`for_terminal`]).
pub fn escaped(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\t' | '\n' => out.push(c),
            c if calbench::error::is_hidden(c) => out.extend(c.escape_unicode()),
            c => out.push(c),
        }
    }
    out
}

/// A value parser for a library enum named by its `strum` derive: it accepts exactly the
/// names of `T`'s variants (the names of files and reports), which `--help` lists and the
/// refusal of any other value repeats.
pub fn named<T>() -> impl TypedValueParser<Value = T>
where
    T: strum::VariantNames + std::str::FromStr + Clone + Send + Sync + 'static,
{
    PossibleValuesParser::new(T::VARIANTS.iter().copied()).map(|name| {
        name.parse::<T>()
            .unwrap_or_else(|_| unreachable!("\"{name}\" is one of the enum's own names"))
    })
}

/// A value parser accepting the `names` of `entries` (each with its help line), giving the
/// entry named: for the library's registries (identification methods, built-in robots).
pub fn entry_of<T: Sync + 'static>(
    entries: &'static [T],
    name: fn(&T) -> &'static str,
    help: fn(&T) -> &'static str,
) -> impl TypedValueParser<Value = &'static T> {
    PossibleValuesParser::new(
        entries
            .iter()
            .map(|e| PossibleValue::new(name(e)).help(help(e))),
    )
    .map(move |s| {
        entries
            .iter()
            .find(|e| name(e) == s)
            .unwrap_or_else(|| unreachable!("\"{s}\" is one of the registry's names"))
    })
}

/// One element of a comma-separated list of numbers (`--q`), blanks around it ignored.
pub fn finite_number(text: &str) -> std::result::Result<Real, String> {
    let t = text.trim();
    match t.parse::<Real>() {
        Ok(v) if v.is_finite() => as_written(t, v),
        _ => Err("not a finite number".into()),
    }
}

/// A number option as Rust reads a 64-bit number (`nan` and `inf` left to the option's own
/// check), refused when written below the smallest one ([`as_written`]).
pub fn number(text: &str) -> std::result::Result<Real, String> {
    let t = text.trim();
    let v: Real = t
        .parse()
        .map_err(|e: std::num::ParseFloatError| e.to_string())?;
    as_written(t, v)
}

/// `v`, read from `t`, unless `t` is below the smallest 64-bit number (`1e-400`) and so reads
/// as 0 ([`calbench::error::underflow`]).
fn as_written(t: &str, v: Real) -> std::result::Result<Real, String> {
    calbench::error::underflow(t, v).map_or(Ok(v), Err)
}

/// Checks, before any work, that `out` can become an output folder holding the files
/// `outputs` (the fixed names a command writes) ([`calbench::report::guard::blocked_folder`]).
/// Nothing is created; the output is then written as a whole by
/// [`calbench::report::atomically`], which checks every file it writes the same way before
/// anything lands in `out`.
pub fn check_out_folder(out: &Path, outputs: &[&str]) -> Result<()> {
    calbench::report::guard::blocked_folder(out, "--out", outputs)
}

/// Refuses, before any work, an output folder where the outputs would destroy something
/// ([`calbench::report::guard::guard_out`], the option named `--out`) or could not be
/// written ([`check_out_folder`]; a folder where the temporary folder beside it cannot be
/// made, [`calbench::report::probe_partial`]). Every command that writes a folder calls it.
pub fn guard_out<P: AsRef<Path>>(
    out: &Path,
    outputs: &[&str],
    inputs: impl IntoIterator<Item = P>,
) -> Result<()> {
    calbench::report::guard::guard_out(out, "--out", outputs, inputs)?;
    calbench::report::probe_partial(out)
}

/// Writes the page and its table, `outputs` (`NAME.html`, `NAME.csv`), into `out` as a whole;
/// returns the page's path.
pub fn write_page(out: &Path, outputs: &[&str; 2], html: &str, csv: &str) -> Result<PathBuf> {
    let [page, table] = *outputs;
    let files = [(page, html), (table, csv)].map(|(name, text)| Bytes {
        name,
        bytes: text.as_bytes(),
    });
    folder(out, &[&files[0], &files[1]])?;
    Ok(out.join(page))
}

/// The files `identify` reads: the data, the validation file and a robot file.
pub fn identify_inputs(args: &identify::IdentifyArgs) -> Vec<&Path> {
    [
        Some(args.data.as_path()),
        args.validate.as_deref(),
        Some(Path::new(&args.robot)),
    ]
    .into_iter()
    .flatten()
    .chain(args.prior.iter().filter_map(|p| match p {
        identify::PriorArg::File(f) => Some(f.as_path()),
        identify::PriorArg::One(..) => None,
    }))
    .collect()
}

/// [`check_out_folder`] and [`calbench::report::probe_partial`], then creates `out` and checks
/// that calbench can write in it: for the
/// commands that run long (`run`, `merge`), so that a folder they cannot write in is refused
/// before the work rather than after it. The folders made for the probe are removed again
/// ([`MadeFolders`]): the outputs are written as a whole once the work is done, so a command
/// refused or killed after the probe leaves no empty folder behind.
pub fn writable_folder(out: &Path, outputs: &[&str]) -> Result<()> {
    check_out_folder(out, outputs)?;
    calbench::report::probe_partial(out)?;
    let _made = MadeFolders::create(out)?;
    let probe = out.join(".calbench-write-test");
    std::fs::write(&probe, b"").map_err(|e| Error::io(&probe, e))?;
    std::fs::remove_file(&probe).map_err(|e| Error::io(&probe, e))
}

/// Checks, before any work, that `out` can be the one file a command writes (`import`,
/// `compensate`, `baseline`) from `inputs`: not an input, the root or the home folder
/// ([`calbench::report::guard::guard_out`]), not an existing folder, which is refused
/// naming it, and not a symbolic link the file system cannot follow (a loop), refused with
/// the OS error; an existing file is replaced.
pub fn guard_out_file<P: AsRef<Path>>(
    out: &Path,
    inputs: impl IntoIterator<Item = P>,
) -> Result<()> {
    calbench::report::guard::guard_out(out, "--out", &[], inputs)?;
    if out.is_symlink() {
        match out.metadata() {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(Error::io(out, e));
            }
            _ => {}
        }
    }
    if out.is_dir() {
        return Err(Error::setting(
            "--out",
            format!(
                "{} is a folder; give the path of the file to write",
                out.display()
            ),
        ));
    }
    Ok(())
}

/// Prints the main table of a run.
pub fn print_table(r: &RunResult) {
    use calbench::report::columns::*;
    let columns = [
        ETA_MEAN,
        BEFORE_MEAN,
        AFTER_MEAN,
        AFTER_RMS,
        AFTER_MAX,
        FAILURES,
    ];
    let (headers, rows) = entry_table(r, &columns);
    let headers: Vec<&str> = headers.iter().map(String::as_str).collect();
    out_raw!("{}", markdown_table(&headers, &rows));
    // Why entries failed, which the table's count does not say.
    for e in r.blocks.iter().flat_map(|b| &b.entries) {
        if e.failures > 0 {
            let ended: Vec<String> = e
                .terminations
                .iter()
                .map(|(k, n)| format!("{k} {n}"))
                .collect();
            out!(
                "{} / {}: {} of {} identifications failed (ended: {}); their trials are left \
                 out of the entry's figures, and trials.csv gives each trial's termination",
                e.method,
                e.poses,
                e.failures,
                e.terminations.values().sum::<usize>(),
                ended.join(", ")
            );
        }
    }
}

/// `--base LINK` / `--tip LINK`: the chain of a URDF tree that is the robot.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct ChainArgs {
    /// URDF robots: the link the chain starts at (default: the root link).
    #[arg(long, value_name = "LINK")]
    pub base: Option<String>,
    /// URDF robots: the link the chain ends at, for a tree with several leaves (a gripper's
    /// fingers, a sensor link).
    #[arg(long, value_name = "LINK")]
    pub tip: Option<String>,
}

impl ChainArgs {
    /// The chain chosen.
    pub fn chain(&self) -> calbench::robot::urdf::UrdfChain {
        calbench::robot::urdf::UrdfChain {
            base: self.base.clone(),
            tip: self.tip.clone(),
        }
    }

    /// The robot `name_or_path`, a URDF's chain chosen by these options.
    pub fn load(&self, name_or_path: &str) -> Result<calbench::robot::Robot> {
        calbench::robot::builtin::load_chain(name_or_path, &self.chain())
    }
}
