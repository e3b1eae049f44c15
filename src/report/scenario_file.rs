//! `scenario.toml` of a run or merge folder (docs/formats.md § 7.1), of every study kind: the scenario as the run
//! ran it — the file's table with `trials`, `seed` and every override applied, as TOML — under
//! one comment line giving the SHA-256 of that text, so that `calbench record` stores what
//! ran and refuses a scenario file that differs, and an edited copy is told by its hash.

use std::path::Path;

use crate::analysis::regression::Side;
use crate::calibrate::task::sha256::sha256_hex;
use crate::error::{Error, Result};
use crate::study::scenario::{effect, Scenario};

/// The file's name.
pub const NAME: &str = "scenario.toml";

/// The start of the first line, before the hash.
const HEAD: &str =
    "# The scenario as run (trials, seed and overrides applied); SHA-256 of the text below: ";

/// The canonical text of a scenario as run: its table as TOML.
pub fn canonical(sc: &Scenario) -> Result<String> {
    toml::to_string(sc.table())
        .map_err(|e| Error::Compute(format!("cannot write the scenario as TOML: {e}")))
}

/// The file's text for the scenario `sc`: the hash line, then [`canonical`].
pub fn text(sc: &Scenario) -> Result<String> {
    Ok(with_hash(&canonical(sc)?))
}

/// The file's text for a scenario whose canonical text (its table as run, as TOML) is `body`:
/// the hash line, then `body`.
pub fn with_hash(body: &str) -> String {
    format!("{HEAD}{}\n{body}", sha256_hex(body.as_bytes()))
}

/// The canonical text and its hash from the file's `text` read at `path`; refuses, naming
/// the file, a text without the hash line or whose text does not have the hash it states
/// (an edited copy). Line ends turned into CRLF are read as the LF that was written.
pub fn read(text: &str, path: &Path) -> Result<(String, String)> {
    let (first, body) = text.split_once('\n').unwrap_or((text, ""));
    let Some(stated) = first.strip_prefix(HEAD) else {
        return Err(Error::file(
            path,
            "line 1",
            "is not the hash line calbench writes; this is not a run's scenario.toml",
        ));
    };
    let (mut body, mut hash) = (body.to_string(), sha256_hex(body.as_bytes()));
    // A checkout that turned its line ends into CRLF (git's `core.autocrlf` on Windows)
    // holds the text that ran.
    if stated.trim() != hash && body.contains("\r\n") {
        body = body.replace("\r\n", "\n");
        hash = sha256_hex(body.as_bytes());
    }
    if stated.trim() != hash {
        return Err(Error::file(
            path,
            "line 1",
            format!(
                "states SHA-256 {} but the text below it has {hash}: the file was edited after \
                 the run",
                stated.trim()
            ),
        ));
    }
    Ok((body, hash))
}

/// The canonical text of the `scenario.toml` beside the summary file `summary` (hash line
/// checked, [`read`]); `None` when there is none (a baseline file, a summary copied alone).
pub fn beside(summary: &Path) -> Result<Option<String>> {
    let file = summary.parent().unwrap_or(Path::new(".")).join(NAME);
    if file.is_dir() {
        let why = "is a folder, where a run's scenario.toml is the file of the scenario it ran";
        return Err(Error::io(&file, std::io::Error::other(why)));
    }
    if !file.is_file() {
        return Ok(None);
    }
    let text = crate::error::read_text(&file)?;
    read(&text, &file).map(|(body, _)| Some(body))
}

/// The scenario the run of `side` ran (canonical text): the one its baseline file records
/// ([`Side::scenario`]), else the `scenario.toml` beside its summary ([`beside`]); `None`
/// when neither says.
pub fn ran(side: &Side) -> Result<Option<String>> {
    if let Some(s) = &side.scenario {
        return Ok(Some(s.clone()));
    }
    let Some(text) = beside(&side.path)? else {
        return Ok(None);
    };
    // A summary of another run than the scenario.toml beside it: one of the two was edited.
    let own: toml::Table = crate::error::toml_keys(&side.path.with_file_name(NAME), &text)?;
    let s = &side.summary;
    same_run(&side.path, (&s.scenario, s.trials, s.seed), &own)?;
    Ok(Some(text))
}

/// Refuses, naming the key of the `summary` file and its line, a summary whose
/// scenario name, trials or seed (`run`; a missing one is not compared) are not those of the
/// scenario the `scenario.toml` beside it says was run (`own`, its table as run: `name`,
/// `trials` and `seed` at its top, the last two absent only from a Monte-Carlo study that
/// ran with their defaults): the summary of another run.
pub fn same_run(
    summary_file: &Path,
    (name, trials, seed): (&str, Option<usize>, Option<u64>),
    own: &toml::Table,
) -> Result<()> {
    use crate::study::scenario::{DEFAULT_SEED, DEFAULT_TRIALS};
    let shown = |key: &str, default: String| match own.get(key) {
        Some(toml::Value::String(s)) => s.clone(),
        Some(v) => v.to_string(),
        None => default,
    };
    let said = [
        ("scenario", Some(name.to_string()), shown("name", "".into())),
        (
            "trials",
            trials.map(|t| t.to_string()),
            shown("trials", DEFAULT_TRIALS.to_string()),
        ),
        (
            "seed",
            seed.map(|s| s.to_string()),
            shown("seed", DEFAULT_SEED.to_string()),
        ),
    ];
    for (key, summary, ran) in said {
        if let Some(summary) = summary.filter(|s| *s != ran) {
            let msg = format!(
                "is {summary}, but {} (the scenario as run) has {key} {ran}: the summary is \
                 not of the run beside it",
                summary_file.with_file_name(NAME).display()
            );
            return Err(Error::file(summary_file, key, msg).at_json_key_line());
        }
    }
    Ok(())
}

/// What the runs of `a` and `b` ran differently ([`differences`] of [`ran`]); empty when
/// they ran one scenario or either does not say what it ran.
pub fn settings_apart(a: &Side, b: &Side) -> Result<Vec<String>> {
    Ok(match (ran(a)?, ran(b)?) {
        (Some(a), Some(b)) => differences(&a, &b),
        _ => Vec::new(),
    })
}

/// The keys of a scenario that change no trial: `seed` and `trials` only choose the draws, and
/// `description`, `[[claims]]` and `[report]` say how the results are read (docs/formats.md
/// § 4.16, § 4.17). Two runs apart only in them ran one study.
const NOT_THE_STUDY: [&str; 5] = ["seed", "trials", "description", "claims", "report"];

/// What two scenarios as run (canonical texts) set differently, other than the keys that
/// change no trial (`NOT_THE_STUDY`): each setting as `key: A → B` by its dotted key
/// (`calibration.count: 40 → 25`, `methods[1].name: "igg3" → "ridge"`, `(none)` where one
/// lacks it), in the tables' order; empty for one study. One study is one effect
/// ([`effect`]): settings written another way (`2500` for `2500.0`, a default written out)
/// are not differences, and a setting that differs only so is left out of a list of those
/// that matter. A text that is not TOML differs from every other as a whole.
pub fn differences(a: &str, b: &str) -> Vec<String> {
    let table = |t: &str| -> Option<toml::Table> {
        let mut t: toml::Table = toml::from_str(t).ok()?;
        for key in NOT_THE_STUDY {
            t.remove(key);
        }
        Some(t)
    };
    let (Some(a), Some(b)) = (table(a), table(b)) else {
        return vec!["the scenario's text: it is not TOML".into()];
    };
    let mut all = Vec::new();
    apart(
        &mut Vec::new(),
        &a.clone().into(),
        &b.clone().into(),
        &mut all,
    );
    let shown = |apart: &[Apart]| apart.iter().map(Apart::to_string).collect();
    let Some(of_b) = effect(&b).filter(|_| !all.is_empty()) else {
        return shown(&all);
    };
    if effect(&a).as_ref() == Some(&of_b) {
        return Vec::new();
    }
    // Each setting as `a` writes it in `b`: those that leave `b`'s effect as it is.
    let matters = |d: &&Apart| {
        let mut with_a = toml::Value::Table(b.clone());
        d.put_in(&mut with_a);
        with_a.as_table().and_then(effect).as_ref() != Some(&of_b)
    };
    let kept: Vec<&Apart> = all.iter().filter(matters).collect();
    match kept.is_empty() {
        true => shown(&all),
        false => kept.iter().map(|d| d.to_string()).collect(),
    }
}

/// One step of a setting's place: a table's key or an array's index.
#[derive(Clone)]
enum Step {
    Key(String),
    Index(usize),
}

/// A setting the two tables write differently: its place, and its value in each (`None`
/// where one lacks it).
struct Apart {
    at: Vec<Step>,
    a: Option<toml::Value>,
    b: Option<toml::Value>,
}

impl std::fmt::Display for Apart {
    /// `key: A → B`, the key dotted (`methods[1].name`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, step) in self.at.iter().enumerate() {
            match step {
                Step::Key(k) if i == 0 => write!(f, "{k}")?,
                Step::Key(k) => write!(f, ".{k}")?,
                Step::Index(n) => write!(f, "[{n}]")?,
            }
        }
        let show = |v: &Option<toml::Value>| v.as_ref().map_or("(none)".into(), |v| v.to_string());
        write!(f, ": {} → {}", show(&self.a), show(&self.b))
    }
}

impl Apart {
    /// Writes the setting into `value` as the first table has it (removed where it lacks it).
    fn put_in(&self, value: &mut toml::Value) {
        let Some((last, path)) = self.at.split_last() else {
            return;
        };
        let mut here = value;
        for step in path {
            let next = match step {
                Step::Key(k) => here.get_mut(k.as_str()),
                Step::Index(n) => here.get_mut(*n),
            };
            let Some(next) = next else { return };
            here = next;
        }
        match (last, &self.a, here) {
            (Step::Key(k), Some(v), toml::Value::Table(t)) => {
                t.insert(k.clone(), v.clone());
            }
            (Step::Key(k), None, toml::Value::Table(t)) => {
                t.remove(k);
            }
            (Step::Index(n), Some(v), toml::Value::Array(a)) if *n < a.len() => {
                a[*n] = v.clone();
            }
            _ => {}
        }
    }
}

/// Adds to `out` each setting under the place `at` where `a` and `b` differ other than in
/// how they write a number ([`same`]).
fn apart(at: &mut Vec<Step>, a: &toml::Value, b: &toml::Value, out: &mut Vec<Apart>) {
    use toml::Value::{Array, Table};
    match (a, b) {
        (Table(a), Table(b)) => {
            let keys = a.keys().chain(b.keys().filter(|k| !a.contains_key(*k)));
            for k in keys {
                at.push(Step::Key(k.clone()));
                match (a.get(k), b.get(k)) {
                    (Some(x), Some(y)) => apart(at, x, y, out),
                    (x, y) => out.push(Apart {
                        at: at.clone(),
                        a: x.cloned(),
                        b: y.cloned(),
                    }),
                }
                at.pop();
            }
        }
        (Array(a), Array(b)) if a.len() == b.len() && a.iter().any(toml::Value::is_table) => {
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                at.push(Step::Index(i));
                apart(at, x, y, out);
                at.pop();
            }
        }
        (a, b) if !same(a, b) => out.push(Apart {
            at: at.clone(),
            a: Some(a.clone()),
            b: Some(b.clone()),
        }),
        _ => {}
    }
}

/// `a` and `b` are one value, an integer and a float of the same number counting as one.
fn same(a: &toml::Value, b: &toml::Value) -> bool {
    use toml::Value::{Array, Float, Integer, Table};
    match (a, b) {
        (Integer(i), Float(f)) | (Float(f), Integer(i)) => *i as f64 == *f,
        (Array(a), Array(b)) => a.len() == b.len() && a.iter().zip(b).all(|(x, y)| same(x, y)),
        (Table(a), Table(b)) => {
            a.len() == b.len() && a.iter().all(|(k, x)| b.get(k).is_some_and(|y| same(x, y)))
        }
        _ => a == b,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differences_name_each_setting_but_the_draws() {
        let a = "name = \"g\"\nseed = 1\ntrials = 3\n[calibration]\ncount = 40\n\
                 [[methods]]\nname = \"ls\"\n[[methods]]\nname = \"igg3\"\n";
        let b = a
            .replace("seed = 1", "seed = 2")
            .replace("trials = 3", "trials = 9");
        assert!(
            differences(a, &b).is_empty(),
            "seed and trials only choose the draws"
        );
        let read = format!(
            "description = \"other words\"\n{a}[report]\nbaseline = \"igg3\"\n\
             [[claims]]\nid = \"c\"\n"
        );
        assert!(
            differences(a, &read).is_empty(),
            "the description, the claims and the report change no trial"
        );
        let c = a
            .replace("count = 40", "count = 25")
            .replace("\"igg3\"", "\"ridge\"");
        assert_eq!(
            differences(a, &c),
            [
                "calibration.count: 40 → 25",
                "methods[1].name: \"igg3\" → \"ridge\""
            ]
        );
        let d = format!("{a}[outliers]\ncount = 2\n");
        assert_eq!(differences(a, &d), ["outliers: (none) → { count = 2 }"]);
        let e = a.replace("[[methods]]\nname = \"igg3\"\n", "");
        assert_eq!(
            differences(a, &e),
            ["methods: [{ name = \"ls\" }, { name = \"igg3\" }] → [{ name = \"ls\" }]"]
        );
        assert_eq!(
            differences(a, "not = toml = ["),
            ["the scenario's text: it is not TOML"]
        );
    }

    #[test]
    fn settings_written_another_way_are_not_differences() {
        let a = "name = \"g\"\nseed = 1\n[robot]\nbuiltin = \"irb2600\"\n\
                 [tracker]\npose = [2500.0, 0.0, 500.0, 0.0, 0.0, 180.0]\n\
                 [[methods]]\nname = \"lm\"\n";
        let ints = a.replace(
            "2500.0, 0.0, 500.0, 0.0, 0.0, 180.0",
            "2500, 0, 500, 0, 0, 180",
        );
        let defaults = a
            .replace("[tracker]\n", "[tracker]\nmpe_a_um = 15.0\ncoverage = 2\n")
            .replace(
                "name = \"lm\"\n",
                "name = \"lm\"\nlabel = \"lm\"\nmu = 1.0\n",
            );
        assert!(differences(a, &ints).is_empty());
        assert!(differences(a, &defaults).is_empty());
        assert!(differences(&ints, &defaults).is_empty());
        // Beside a setting that matters, the defaults written out are left out of the list;
        // an absent key is shown as `(none)`.
        let noisier = defaults.replace("mpe_a_um = 15.0", "mpe_a_um = 150.0");
        assert_eq!(
            differences(a, &noisier),
            ["tracker.mpe_a_um: (none) → 150.0"]
        );
        assert_eq!(
            differences(&noisier, &ints),
            ["tracker.mpe_a_um: 150.0 → (none)"]
        );
        let damped = ints.replace("name = \"lm\"\n", "name = \"lm\"\nmu = 2\n");
        assert_eq!(differences(&defaults, &damped), ["methods[0].mu: 1.0 → 2"]);
        // Another study kind's table is compared as written.
        let r = "name = \"r\"\n[registration_study]\nnoise = 1.0\n";
        assert_eq!(
            differences(r, &r.replace("1.0", "1")),
            Vec::<String>::new(),
            "numbers are compared by value"
        );
        assert_eq!(
            differences(r, &format!("{r}points = 10\n")),
            ["registration_study.points: (none) → 10"]
        );
    }

    #[test]
    fn line_ends_turned_into_crlf_read_as_written_and_an_edit_is_still_refused() {
        let body = "name = \"g\"\nseed = 1\n[calibration]\ncount = 40\n";
        let text = with_hash(body);
        let path = std::path::Path::new("scenario.toml");
        let crlf = text.replace('\n', "\r\n");
        assert_eq!(read(&crlf, path).unwrap(), read(&text, path).unwrap());
        assert_eq!(read(&text, path).unwrap().0, body);
        let edited = crlf.replace("count = 40", "count = 41");
        let e = read(&edited, path).unwrap_err().to_string();
        assert!(e.contains("the file was edited after the run"), "{e}");
    }
}
