//! Which study a scenario file runs, read by serde from its sections (docs/formats.md § 4): a
//! `[registration_study]` table is Ban fig. 3's registration study, an `[instruments_study]`
//! table (with its `[[measurement]]` tables) an instruments study, and a file with neither is
//! a Monte-Carlo study. Every kind runs
//! through [`crate::runner`], and what its checkpoint and shards keep of it is its
//! [`AnyScenario::settings`].

use std::path::Path;

use serde::Deserialize;

use crate::error::{read_text, Error, Result};
use crate::study::instruments::InstrumentsScenario;
use crate::study::instruments_table::{INSTRUMENTS_KEYS, INSTRUMENTS_STUDY, MIGRATE};
use crate::study::registration_study::RegistrationScenario;
use crate::study::registration_study::REGISTRATION_STUDY;
use crate::study::scenario::Scenario;
use crate::study::whole::{self, Head};

/// The sections that tell a study's kind (every other key is read by the kind's own parser).
#[derive(Deserialize)]
struct Sections {
    registration_study: Option<toml::Value>,
    instruments_study: Option<toml::Value>,
    measurement: Option<toml::Value>,
}

/// A checked scenario of any kind.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
pub enum AnyScenario {
    /// A Monte-Carlo study of calibration methods.
    MonteCarlo(Scenario),
    /// Ban fig. 3's registration study.
    Registration(RegistrationScenario),
    /// An instruments study.
    Instruments(InstrumentsScenario),
}

impl AnyScenario {
    /// Reads and checks a scenario file of any kind.
    pub fn load(path: &Path) -> Result<AnyScenario> {
        let text = read_text(path)?;
        AnyScenario::parse(&text, Some(path))
    }

    /// Parses and checks a scenario's text of any kind; `path` is the file it came from.
    pub fn parse(text: &str, path: Option<&Path>) -> Result<AnyScenario> {
        let shown = path.unwrap_or(Path::new("<built-in default scenario>"));
        let table: toml::Table = crate::error::toml_keys(shown, text)?;
        let kind: Sections =
            toml::Value::Table(table.clone())
                .try_into()
                .map_err(|e: toml::de::Error| {
                    let (msg, key) = crate::error::toml_value_error(&e);
                    Error::file(shown, key.unwrap_or_else(|| "scenario".into()), msg)
                        .at_key_line(text)
                })?;
        let instruments = kind.instruments_study.is_some();
        match (kind.registration_study, instruments, kind.measurement) {
            (Some(_), true, _) => Err(Error::file(
                shown,
                INSTRUMENTS_STUDY,
                "a scenario is one study: [registration_study] or [instruments_study], not both",
            )),
            (Some(_), false, Some(_)) => Err(Error::file(
                shown,
                "measurement",
                "a registration study takes no [[measurement]] tables",
            )),
            (Some(_), false, None) => RegistrationScenario::from_table(table, shown)
                .map(AnyScenario::Registration)
                .map_err(|e| whole::at_key_line(e, text)),
            (None, true, _) => InstrumentsScenario::from_table(table, shown)
                .map(AnyScenario::Instruments)
                .map_err(|e| whole::at_key_line(e, text)),
            // [[measurement]] tables without the study's table: a file of the layout before,
            // refused naming the first of the study's keys it has at the top level.
            (None, false, Some(_)) => {
                let key = INSTRUMENTS_KEYS.iter().find(|k| table.contains_key(**k));
                Err(Error::file(shown, *key.unwrap_or(&"measurement"), MIGRATE))
            }
            (None, false, None) => Scenario::parse(text, path)
                .map(AnyScenario::MonteCarlo)
                .map_err(other_kinds),
        }
    }

    /// The scenario with `--trials` and `--seed` applied, checked again.
    pub fn with_run_overrides(self, trials: Option<usize>, seed: Option<u64>) -> Result<Self> {
        let mut head = match &self {
            AnyScenario::MonteCarlo(s) => {
                return Ok(AnyScenario::MonteCarlo(s.with_run_overrides(trials, seed)?))
            }
            AnyScenario::Registration(s) => s.head.clone(),
            AnyScenario::Instruments(s) => s.head.clone(),
        };
        head.set(trials.unwrap_or(head.trials), seed.unwrap_or(head.seed))?;
        // The settings' text is not the file's: a refusal names the option, not a line.
        AnyScenario::parse(&head.settings()?, self.path()).map_err(|e| {
            use crate::error::Opt;
            let e = crate::study::scenario::given(e, "trials", Opt::Trials);
            crate::study::scenario::given(e, "seed", Opt::Seed)
        })
    }

    /// The head of a study that runs whole (`None` for a Monte-Carlo study).
    fn head(&self) -> Option<&Head> {
        match self {
            AnyScenario::MonteCarlo(_) => None,
            AnyScenario::Registration(s) => Some(&s.head),
            AnyScenario::Instruments(s) => Some(&s.head),
        }
    }

    /// The file it came from.
    pub fn path(&self) -> Option<&Path> {
        match self {
            AnyScenario::MonteCarlo(s) => s.path.as_deref(),
            AnyScenario::Registration(s) => Some(&s.head.path),
            AnyScenario::Instruments(s) => Some(&s.head.path),
        }
    }

    /// Its name (the default output folder `results/<name>/`).
    pub fn name(&self) -> &str {
        match (self, self.head()) {
            (AnyScenario::MonteCarlo(s), _) => &s.name,
            (_, Some(h)) => &h.name,
            _ => "",
        }
    }

    /// The master seed.
    pub fn seed(&self) -> u64 {
        match (self, self.head()) {
            (AnyScenario::MonteCarlo(s), _) => s.seed,
            (_, Some(h)) => h.seed,
            _ => 0,
        }
    }

    /// Trials per block.
    pub fn trials(&self) -> usize {
        match (self, self.head()) {
            (AnyScenario::MonteCarlo(s), _) => s.trials,
            (_, Some(h)) => h.trials,
            _ => 0,
        }
    }

    /// The scenario as run (overrides applied), TOML text: what a checkpoint and a shard keep,
    /// and what the records' checksums bind ([`crate::study::records`]).
    pub fn settings(&self) -> Result<String> {
        match (self, self.head()) {
            (AnyScenario::MonteCarlo(s), _) => toml::to_string(s.table())
                .map_err(|e| Error::Compute(format!("cannot write the scenario: {e}"))),
            (_, Some(h)) => h.settings(),
            _ => Err(Error::Compute("a scenario without settings".into())),
        }
    }

    /// The blocks of the run (each runs the scenario's trials), and what a message calls one:
    /// sweep points, the cells of an instruments study, or the one block of the others.
    pub fn blocks(&self) -> (usize, Option<&'static str>) {
        match self {
            AnyScenario::MonteCarlo(s) => match &s.sweep {
                Some(sw) => (sw.points().len(), Some("sweep point")),
                None => (1, None),
            },
            AnyScenario::Registration(_) => (1, None),
            AnyScenario::Instruments(s) => (s.cells(), Some("cell")),
        }
    }

    /// The work units of the run: blocks × trials.
    pub fn units(&self) -> u64 {
        self.blocks().0 as u64 * self.trials() as u64
    }
}

/// A Monte-Carlo scenario's refusal of an unknown top-level key (its place the scenario
/// itself), naming beside the keys it lists the sections that make a study of another kind,
/// which [`AnyScenario::parse`] reads the kind from.
fn other_kinds(e: Error) -> Error {
    match e {
        Error::File { file, place, msg }
            if place.ends_with("scenario") && msg.to_string().contains("unknown field") =>
        {
            let msg = msg.text(format!(
                ", or `{REGISTRATION_STUDY}` or `{INSTRUMENTS_STUDY}`, the section of a study \
                 of another kind"
            ));
            Error::File { file, place, msg }
        }
        e => e,
    }
}
