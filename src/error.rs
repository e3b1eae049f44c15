//! The library's error type.

use std::path::PathBuf;

mod hidden;
mod json;
mod lines;
mod serde_words;
mod text;
mod toml_read;
mod underflow;
pub use hidden::{is_hidden, quoted};
pub use json::{json_refusal, json_typed, json_value, unique_keys};
pub use lines::{json_key_line, line_of, toml_key_line};
use serde_words::plain_types;
pub use serde_words::{scenario_value_error, toml_value_error, unknown_field};
pub use text::{read_bounded, read_bounded_text, read_text, read_text_whole, TEXT_CAP_MIB};
pub use toml_read::{toml_error_line, toml_keys};
pub use underflow::{refuse_toml_underflow, toml_underflow, underflow};

/// Everything that can go wrong in the library. Non-convergence of an identification is not an
/// error: it is reported as a termination reason.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An input file (robot, scenario, measurement, pose list) is malformed or holds a value
    /// out of range. `place` names the key, joint or line.
    #[error("{}: {place}: {msg}", file.display())]
    File {
        /// The offending file.
        file: PathBuf,
        /// Where in the file: a key path such as `joints[2].limits` or `line 14`.
        place: String,
        /// What is wrong and what is allowed (it may name a front end's options).
        msg: Said,
    },
    /// A setting (from a scenario, the command line or an API call) is out of range.
    #[error("setting `{key}`: {msg}")]
    Setting {
        /// The setting's key, e.g. `tracker.mpe_a_um`.
        key: String,
        /// What is wrong and what is allowed (it may name a front end's options).
        msg: Said,
    },
    /// A front end's option is out of range: a setting whose key each front end spells.
    #[error("setting `{}`: {msg}", option.name())]
    Option {
        /// The option.
        option: Opt,
        /// What is wrong and what is allowed (it may name other options).
        msg: Said,
    },
    /// The points of a registration do not determine the frame (fewer than 3, collinear,
    /// all weights zero), or a solve is singular: the data, not the code, are the cause.
    #[error("{0}")]
    Singular(String),
    /// An iteration did not converge to a usable result (the alternation of registration
    /// and identification diverged).
    #[error("{0}")]
    Diverged(String),
    /// A computation could not be carried out (e.g. too few reachable poses in a box).
    #[error("{0}")]
    Compute(String),
    /// Reading or writing a file failed. The message carries the operating system's; it
    /// is not also given as a `source`, so that a report of the error chain (`{:#}`) says it
    /// once.
    #[error("{}: {cause}", shown_path(path))]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        cause: std::io::Error,
    },
}

/// The library's result type.
pub type Result<T> = std::result::Result<T, Error>;

/// An option of a front end (the `calbench` command line, the Python module) that a message
/// names. The library names it by this type only and names no flag; each front end spells
/// it its own way ([`Spell`]: the command line `--allow-worse`, Python `allow_worse=True`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, strum::IntoStaticStr, strum::EnumIter)]
#[strum(serialize_all = "snake_case")]
#[non_exhaustive]
pub enum Opt {
    /// Keep a result whose data do not determine every parameter.
    AllowRankDeficient,
    /// Keep a result that makes the robot worse than the nominal one.
    AllowWorse,
    /// Keep a result that cannot be physically right.
    AllowImplausible,
    /// The joint compliances identified with the kinematic errors.
    Compliance,
    /// K-fold cross-validation.
    Cv,
    /// The seed of the cross-validation's folds.
    CvSeed,
    /// The compensated robot's formats.
    Export,
    /// Parameters held at their nominal values.
    Fix,
    /// Rows held out for validation.
    Holdout,
    /// The orientation weight of full-pose data.
    K,
    /// The identification method.
    Method,
    /// Candidate models compared by cross-validation.
    Models,
    /// The identified parameters.
    Params,
    /// The precision a run stops at.
    Precision,
    /// Priors on parameters' errors.
    Prior,
    /// The registration.
    Registration,
    /// The run's seed.
    Seed,
    /// A shard of a run.
    Shard,
    /// The trial of a study.
    Trial,
    /// The number of trials of a run.
    Trials,
    /// A validation measurement.
    Validate,
    /// The base link of a URDF chain.
    Base,
    /// The tip link of a URDF chain.
    Tip,
    /// Joint values given to a command.
    Q,
    /// The output folder.
    Out,
    /// The instrument of an instruments study whose readings a simulation writes.
    Measure,
    /// The task file a task folder's entry ran.
    Task,
    /// The planes of a plane instrument.
    Planes,
    /// The spheres of a sphere instrument.
    Spheres,
}

impl Opt {
    /// The option's name in words of the library (`allow_worse`): how [`Said`]'s own
    /// `Display` writes it, and the stem each front end spells.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

/// How a front end writes an option: `on` false names it (`--fix`, `fix`), true says how it
/// is turned on (`--allow-worse`, `allow_worse=True`).
pub type Spell = fn(opt: Opt, on: bool) -> String;

/// A message that may name front ends' options: text, and options typed ([`Opt`]), which
/// each front end spells ([`Said::spell`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Said(Vec<Piece>);

/// A piece of a [`Said`]: text, or an option named (`false`) or turned on (`true`).
#[derive(Clone, Debug, PartialEq)]
enum Piece {
    Text(String),
    Opt(Opt, bool),
}

impl Said {
    /// The message with `t` added.
    pub fn text(mut self, t: impl Into<String>) -> Self {
        self.0.push(Piece::Text(plain_types(t.into())));
        self
    }

    /// The message naming the option `o`.
    pub fn name(mut self, o: Opt) -> Self {
        self.0.push(Piece::Opt(o, false));
        self
    }

    /// The message saying how the option `o` is turned on.
    pub fn on(mut self, o: Opt) -> Self {
        self.0.push(Piece::Opt(o, true));
        self
    }

    /// The message followed by `more`.
    pub fn then(mut self, more: Said) -> Self {
        self.0.extend(more.0);
        self
    }

    /// The message with its options as `spell` writes them.
    pub fn spell(&self, spell: Spell) -> String {
        self.0
            .iter()
            .map(|p| match p {
                Piece::Text(t) => t.clone(),
                Piece::Opt(o, on) => spell(*o, *on),
            })
            .collect()
    }
}

impl std::fmt::Display for Said {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // The library's own spelling: the name in backquotes.
        f.write_str(&self.spell(|o, _| format!("`{}`", o.name())))
    }
}

impl From<String> for Said {
    fn from(t: String) -> Self {
        Said::default().text(t)
    }
}

impl From<&str> for Said {
    fn from(t: &str) -> Self {
        Said::default().text(t)
    }
}

impl Error {
    /// The key of a [`Error::Setting`] (`None` for other errors): for callers that report
    /// or test which setting was refused.
    pub fn key(&self) -> Option<&str> {
        match self {
            Error::Setting { key, .. } => Some(key),
            Error::Option { option, .. } => Some(option.name()),
            _ => None,
        }
    }

    /// The message as the front end that spells options with `spell` shows it (the
    /// `Display` of the error, with its options so spelled).
    pub fn spelled(&self, spell: Spell) -> String {
        match self {
            Error::File { file, place, msg } => {
                format!("{}: {place}: {}", file.display(), msg.spell(spell))
            }
            Error::Setting { key, msg } => format!("setting `{key}`: {}", msg.spell(spell)),
            Error::Option { option, msg } => {
                format!("setting `{}`: {}", spell(*option, false), msg.spell(spell))
            }
            e => e.to_string(),
        }
    }

    /// A refusal of a key of the TOML file whose text is `text`, with the line where the key
    /// is written (`line 12, claims[0].relation`) when its place names a key that `text`
    /// writes and no line yet; any other error as it is.
    pub fn at_key_line(self, text: &str) -> Self {
        self.at_line_of(|key| toml_key_line(text, key))
    }

    /// [`Error::at_key_line`] of a JSON file (`line 4, results`, `line 12, per_trial.format`:
    /// [`json_key_line`]), the file it names read again for the message; an error of a file
    /// that cannot be read as it is.
    pub fn at_json_key_line(self) -> Self {
        let text = match &self {
            Error::File { file, .. } => std::fs::read_to_string(file).ok(),
            _ => None,
        };
        match text {
            Some(text) => self.at_line_of(|key| json_key_line(&text, key)),
            None => self,
        }
    }

    /// A refusal of a file whose place names a key and no line yet, with the line `line`
    /// gives that key; any other error as it is.
    fn at_line_of(self, line: impl Fn(&str) -> Option<usize>) -> Self {
        match self {
            Error::File { file, place, msg } if !place.starts_with("line ") => Error::File {
                file,
                place: at_line(line(&place), place),
                msg,
            },
            e => e,
        }
    }

    /// A refusal of the setting `key` as one of the file `path`, placed at that key (whose
    /// line [`Error::at_key_line`] adds); any other error as it is.
    pub fn in_file(self, path: &std::path::Path) -> Self {
        match self {
            Error::Setting { key, msg } => Error::file(path, key, msg),
            e => e,
        }
    }

    /// A refusal of a place in `path`, a scenario that is no file (a Python dict, shown as
    /// `path`), as a refusal of the setting at that key, the line of the text it was written
    /// as dropped (`line 12, measurement[0].kind` is the setting `measurement[0].kind`): the
    /// inverse of [`Error::in_file`]. Any other error, one of another file included, as it is.
    pub fn as_setting(self, path: &std::path::Path) -> Self {
        match self {
            Error::File { file, place, msg } if file == path => Error::Setting {
                key: without_line(&place).to_string(),
                msg,
            },
            e => e,
        }
    }

    /// An error about the front end's option `option`.
    pub fn option(option: Opt, msg: impl Into<Said>) -> Self {
        Error::Option {
            option,
            msg: msg.into(),
        }
    }

    /// A refused setting as the refusal of the front end's option `option` that gave it;
    /// any other error as it is.
    pub fn of_option(self, option: Opt) -> Self {
        match self {
            Error::Setting { msg, .. } => Error::option(option, msg),
            e => e,
        }
    }

    /// The refused setting `key` as the refusal of the front end's option `option` that gave
    /// it ([`Error::of_option`] for that key alone); any other error as it is.
    pub fn setting_as(self, key: &str, option: Opt) -> Self {
        match &self {
            Error::Setting { key: k, .. } if k == key => self.of_option(option),
            _ => self,
        }
    }

    /// An error about a setting.
    pub fn setting(key: impl Into<String>, msg: impl Into<Said>) -> Self {
        Error::Setting {
            key: key.into(),
            msg: msg.into(),
        }
    }

    /// An error about a place in an input file.
    pub fn file(file: impl Into<PathBuf>, place: impl Into<String>, msg: impl Into<Said>) -> Self {
        Error::File {
            file: file.into(),
            place: place.into(),
            msg: msg.into(),
        }
    }

    /// `got` joint values where the robot has `dof` joints: the setting `key` refused, with
    /// `what` naming the offending values (`pose 3`, `--q`).
    pub fn joint_count(key: &str, what: impl std::fmt::Display, got: usize, dof: usize) -> Self {
        Error::setting(
            key,
            format!("{what}: {got} joint values for a {dof}-joint robot"),
        )
    }

    /// An error about the value of the dotted `key` (`calibration.region`, `joints[1].a`) in
    /// the TOML file `file` whose text is `text`: the place is `line N, PLACE` where the key
    /// is written in the text ([`toml_key_line`]), else `place` alone.
    pub fn toml_file(
        file: impl Into<PathBuf>,
        text: &str,
        key: &str,
        place: impl Into<String>,
        msg: impl Into<Said>,
    ) -> Self {
        Error::file(file, at_line(toml_key_line(text, key), place), msg)
    }

    /// An I/O error on a path.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            cause: source,
        }
    }
}

/// Whether `path` exists: `false` where nothing is there (or a file stands where a folder of
/// it would), and refused with the system's words where it cannot be told (a link that loops,
/// a folder not searchable), which [`std::path::Path::exists`] would call missing.
pub fn exists(path: &std::path::Path) -> Result<bool> {
    match path.try_exists() {
        Err(e) if e.kind() == std::io::ErrorKind::NotADirectory => Ok(false),
        r => r.map_err(|e| Error::io(path, e)),
    }
}

/// Reads calbench's file `what` (`summary.json`, `task.json`) from `de`, `path` naming it: a
/// missing or unknown key, or one of the wrong type, is refused naming the file and the key
/// path (`not a calbench WHAT: …`); a missing key's path is its own (`chosen_by`,
/// `published[0].label`), not that of the table it is missing from.
pub fn read_typed<'de, T, D>(de: D, path: &std::path::Path, what: &str) -> Result<T>
where
    T: serde::Deserialize<'de>,
    D: serde::Deserializer<'de>,
{
    serde_path_to_error::deserialize(de).map_err(|e| {
        // serde reads a struct from a list too, field by field in order: a list where a
        // table of keys stands (every calbench JSON file is one) is said so, not as a field
        // of the wrong type or a count of elements.
        let top_list = matches!(
            e.path().iter().next(),
            Some(serde_path_to_error::Segment::Seq { .. })
        );
        let mut key = e.path().to_string();
        let mut msg = e.into_inner().to_string();
        if top_list || (msg.starts_with("invalid length ") && msg.contains(", expected struct ")) {
            if top_list {
                key = ".".into();
            }
            msg = "is a list, where a table of keys (a JSON object) stands".into();
        }
        // Named by its own key, so that the refusal stands at that key's line.
        let key = toml_read::own_key(key, &msg);
        Error::file(path, key, format!("not a calbench {what}: {msg}"))
    })
}

/// `v` as pretty-printed JSON with a final newline: the text of calbench's JSON files.
pub fn json_text<T: serde::Serialize + ?Sized>(v: &T) -> Result<String> {
    let s = serde_json::to_string_pretty(v).map_err(|e| Error::Compute(e.to_string()))?;
    Ok(s + "\n")
}

/// Refuses the file `path` of calbench's format `found` of `what` (`summary`,
/// `identification record`) when it is later than `reads`, the one this calbench reads.
pub fn newer_format(path: &std::path::Path, what: &str, found: u32, reads: u32) -> Result<()> {
    if found > reads {
        let why = format!("{what} format {found} is newer than this calbench reads ({reads})");
        return Err(Error::file(path, "format", why));
    }
    Ok(())
}

/// A path as an I/O error names it: an empty one (an empty argument) said so, where it showed
/// as nothing before the colon.
fn shown_path(path: &std::path::Path) -> String {
    match path.as_os_str().is_empty() {
        true => "an empty path".into(),
        false => path.display().to_string(),
    }
}

/// `place` prefixed with its 1-based line where there is one: `line 14, joints[1].a`.
pub fn at_line(line: Option<usize>, place: impl Into<String>) -> String {
    let place = place.into();
    match line {
        Some(n) => format!("line {n}, {place}"),
        None => place,
    }
}

/// The key of a place [`at_line`] wrote (`line 12, measurement[0].kind` →
/// `measurement[0].kind`); a place without a line as it is.
pub fn without_line(place: &str) -> &str {
    match place.split_once(", ") {
        Some((line, key)) if line.starts_with("line ") => key,
        _ => place,
    }
}

/// A number as a refusal shows it: as `{}` writes it (`0.5`, `-180`), but in exponent form
/// (`1e300`, `-2.5e-9`) where that would be a long run of digits (magnitudes from 1e16 on, or
/// below 1e-5).
pub fn shown(v: f64) -> String {
    let a = v.abs();
    if a.is_finite() && a != 0.0 && !(1e-5..1e16).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// A value converted from the unit a file or a robot writes it in, as [`shown`] shows it to
/// 12 significant digits: the conversion's last bits are not the user's (`-3240.7562` m is
/// shown `-3240756.2` mm, not `-3240756.1999999997`).
pub fn shown_converted(v: f64) -> String {
    shown(format!("{v:.11e}").parse().unwrap_or(v))
}

/// `n` and its noun, singular for one (`counted(1, "trial", "trials")` is `1 trial`).
pub fn counted(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// Largest mass of a link or a payload, kg (100 t): far above any arm (the heaviest
/// industrial payloads are about 2.3 t); a larger one gives a sag that is not a sag.
pub const MAX_MASS_KG: f64 = 1e5;

/// Whether `kg` is a mass a robot, a scenario or a measured point may give: finite, ≥ 0 and
/// at most [`MAX_MASS_KG`].
pub fn is_mass(kg: f64) -> bool {
    (0.0..=MAX_MASS_KG).contains(&kg)
}

/// The refusal of `kg` where it is not a mass ([`is_mass`]); `None` where it is.
pub fn not_a_mass(kg: f64) -> Option<String> {
    let got = shown(kg);
    (!is_mass(kg)).then(|| format!("must be a mass from 0 to {MAX_MASS_KG} kg, got {got}"))
}

/// Refuses a setting `v` unless it is finite and positive (the error names `key`).
pub fn finite_positive(key: &str, v: f64) -> Result<()> {
    finite_where(key, v, v > 0.0, "positive")
}

/// Checks that setting `key` is finite and at least 0.
pub fn finite_non_negative(key: &str, v: f64) -> Result<()> {
    finite_where(key, v, v >= 0.0, "non-negative")
}

/// Refuses, as the setting `key`, the first of the lengths `v` (mm) that is not finite or
/// beyond ±`most` (a robot file's range of lengths).
pub fn lengths_within(key: &str, v: &[f64], most: f64) -> Result<()> {
    match v.iter().find(|v| !(v.is_finite() && v.abs() <= most)) {
        Some(v) => Err(Error::setting(
            key,
            format!(
                "must be finite and within ±{most} mm (a robot file's range), got {}",
                shown(*v)
            ),
        )),
        None => Ok(()),
    }
}

/// Refuses `v` unless it is finite and `holds`, saying it must be finite and `what`.
fn finite_where(key: &str, v: f64, holds: bool, what: &str) -> Result<()> {
    if v.is_finite() && holds {
        Ok(())
    } else {
        Err(Error::setting(
            key,
            format!("must be finite and {what}, got {}", shown(v)),
        ))
    }
}

/// Checks that the count `key` is at least 1.
pub fn check_count(key: &str, n: usize) -> Result<()> {
    if n == 0 {
        Err(Error::setting(key, "must be at least 1"))
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn numbers_are_shown_short() {
        use super::shown;
        assert_eq!(shown(1e300), "1e300");
        assert_eq!(shown(-1e300), "-1e300");
        assert_eq!(shown(1e16), "1e16");
        assert_eq!(shown(2.5e-9), "2.5e-9");
        for (v, s) in [
            (0.5, "0.5"),
            (-180.0, "-180"),
            (0.0, "0"),
            (123456.75, "123456.75"),
        ] {
            assert_eq!(shown(v), s);
        }
        assert_eq!(shown(f64::INFINITY), "inf");
        assert_eq!(shown(f64::NAN), "NaN");
        // A converted value loses the conversion's last bits, and shows no `.0`.
        assert_eq!(shown_converted(-3240.7562 * 1000.0), "-3240756.2");
        assert_eq!(-3240.7562 * 1000.0, -3240756.1999999997);
        assert_eq!(shown_converted(1e7), "10000000");
        assert_eq!(shown_converted(1e308), "1e308");
        assert_eq!(shown_converted(f64::INFINITY), "inf");
    }

    use super::*;

    const TEXT: &str = "name = \"x\"\n\n[calibration]\ncount = 5\nregion = { kind = \"box\" }\n\n\
        [[joints]]\na = 1.0\n\n[[joints]]\n# the second\na = 2.0\nlimits = [0.0, 1.0]\n\n\
        [[methods]]\nname = \"ls\"\n";

    #[test]
    fn a_place_of_a_scenario_that_is_no_file_is_a_setting() {
        let dict = std::path::Path::new("<scenario dict>");
        let e =
            Error::file(dict, "line 12, measurement[0].kind", "unknown variant").as_setting(dict);
        assert_eq!(
            e.to_string(),
            "setting `measurement[0].kind`: unknown variant"
        );
        let e = Error::file(dict, "trials", "expected usize").as_setting(dict);
        assert_eq!(e.key(), Some("trials"));
        let other = Error::file("robot.toml", "line 3, joints", "bad").as_setting(dict);
        assert_eq!(other.to_string(), "robot.toml: line 3, joints: bad");
    }

    #[test]
    fn key_lines_are_found() {
        assert_eq!(toml_key_line(TEXT, "name"), Some(1));
        assert_eq!(toml_key_line(TEXT, "calibration.region"), Some(5));
        assert_eq!(toml_key_line(TEXT, "calibration.region.kind"), Some(5));
        assert_eq!(toml_key_line(TEXT, "joints[0].a"), Some(8));
        assert_eq!(toml_key_line(TEXT, "joints[1].a"), Some(12));
        assert_eq!(toml_key_line(TEXT, "joints[1].limits"), Some(13));
        assert_eq!(toml_key_line(TEXT, "methods[0].name"), Some(16));
        for absent in [
            "calibration.strategies",
            "joints[2].a",
            "joints[1].d",
            "name.x",
            "methods[x]",
            "",
        ] {
            assert_eq!(toml_key_line(TEXT, absent), None, "{absent}");
        }
        assert_eq!(toml_key_line("a = [", "a"), None);
    }

    #[test]
    fn places_carry_their_line() {
        let e = Error::toml_file("r.toml", TEXT, "joints[1].a", "joint 2, key `a`", "bad");
        assert_eq!(e.to_string(), "r.toml: line 12, joint 2, key `a`: bad");
        let e = Error::toml_file("r.toml", TEXT, "joints[1].d", "joint 2, key `d`", "bad");
        assert_eq!(e.to_string(), "r.toml: joint 2, key `d`: bad");
    }
}
