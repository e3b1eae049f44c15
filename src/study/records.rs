//! The record format of `records.txt`, in a shard folder and in a checkpoint
//! (docs/formats.md § 7.3): one line per trial, the serde form of what the trial gave
//! (`Record`: its sweep point, its index and its result), then ` #` and a checksum.
//!
//! The serde form is RON (the `ron` crate): it writes every float in its shortest round-trip
//! form, `NaN` and `inf` included, so a record reads back bit for bit (JSON has no NaN, and a
//! search's fitness before its first iteration is one).
//!
//! The checksum binds the record to its run: 32 hexadecimal digits, the first 16 bytes of the
//! SHA-256 (the `sha2` crate) of the run's identity — the SHA-256 of its scenario as run (the
//! settings' TOML text that `shard.json` and `checkpoint.json` hold, then the SHA-256 of each
//! file it reads, [`super::inputs`]) and its seed — then the
//! record's sweep point and trial, then the text before ` #`. A changed byte, a record of
//! another run (another scenario's content, another seed, or the same name and seed with other
//! settings) and a record moved to another sweep point or trial each fail it. A reader
//! (`Verifier`) checks every line's sum and that the lines hold the run's trials in order,
//! each once: a changed, foreign, missing, duplicated or reordered record is refused, naming the
//! file, the line and the trial. The same checksum, at a trial index no trial has, binds what
//! a shard's `shard.json` says of each sweep point (`RunId::block_checksum`).

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::error::{Error, Result};
use crate::study::inputs::Input;

/// One line of `records.txt` before its checksum: trial `trial` of sweep point `point` (0
/// without a sweep) and what it gave.
#[derive(Serialize, Deserialize)]
struct Record<T> {
    point: usize,
    trial: usize,
    result: T,
}

/// What a record's checksum binds of its run: its scenario as run and its seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct RunId {
    scenario: [u8; 32],
    seed: u64,
}

impl RunId {
    /// The run of the scenario whose settings as run are the TOML text `settings`, reading
    /// the files `inputs` (their hashes bound after the text; none: the text's hash alone),
    /// with `seed`.
    pub(crate) fn new(settings: &str, inputs: &[Input], seed: u64) -> RunId {
        let mut h = Sha256::new();
        h.update(settings.as_bytes());
        for i in inputs {
            h.update(i.sha256.as_bytes());
        }
        RunId {
            scenario: h.finalize().into(),
            seed,
        }
    }

    /// The checksum of `body`, what a shard's `shard.json` says of sweep point `point`
    /// (docs/formats.md § 7.3 `blocks`): a record's checksum with the trial index `u64::MAX`,
    /// which no trial has.
    pub(crate) fn block_checksum(&self, point: usize, body: &str) -> String {
        self.sum(point as u64, u64::MAX, body)
    }

    /// The checksum of the record text `body` of trial `trial` of sweep point `point`.
    fn checksum(&self, point: usize, trial: usize, body: &str) -> String {
        self.sum(point as u64, trial as u64, body)
    }

    fn sum(&self, point: u64, trial: u64, body: &str) -> String {
        let mut h = Sha256::new();
        h.update(self.scenario);
        h.update(self.seed.to_le_bytes());
        h.update(point.to_le_bytes());
        h.update(trial.to_le_bytes());
        h.update(body.as_bytes());
        h.finalize()[..16]
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect()
    }
}

/// Trial `trial` of sweep point `point` of the run `id`, which gave `result`, as a line of
/// `records.txt` ending in its checksum and a line end.
pub(crate) fn encode<T: Serialize>(
    id: &RunId,
    point: usize,
    trial: usize,
    result: &T,
) -> Result<String> {
    let record = Record {
        point,
        trial,
        result,
    };
    let body = ron::to_string(&record)
        .map_err(|e| Error::Compute(format!("cannot write a trial's record: {e}")))?;
    let sum = id.checksum(point, trial, &body);
    Ok(format!("{body} #{sum}\n"))
}

/// The reader of one `records.txt` that holds the work units `[start, end)` of a run (unit
/// `u` is trial `u % trials` of sweep point `u / trials`): every line must carry its checksum
/// and the next unit, so a changed, foreign, missing, duplicated or reordered record is
/// refused, naming the file, the line and the trial.
pub(crate) struct Verifier {
    path: PathBuf,
    id: RunId,
    trials: u64,
    block: Option<&'static str>,
    next: u64,
    end: u64,
    line: usize,
}

impl Verifier {
    /// The reader of `path`, records of the run `id` with `trials` trials per block (`block`:
    /// what the messages call one, `None` for a run of one block), holding the units `units`.
    pub(crate) fn new(
        path: &Path,
        id: RunId,
        trials: usize,
        block: Option<&'static str>,
        units: (u64, u64),
    ) -> Verifier {
        Verifier {
            path: path.to_path_buf(),
            id,
            trials: trials.max(1) as u64,
            block,
            next: units.0,
            end: units.1,
            line: 0,
        }
    }

    /// Unit `u` as the messages name it: `trial I`, and its block (`of sweep point P`).
    fn trial(&self, u: u64) -> String {
        let (b, i) = (u / self.trials, u % self.trials);
        match self.block {
            Some(what) => format!("trial {i} of {what} {b}"),
            None => format!("trial {i}"),
        }
    }

    /// Where the line being read stands: `where trial I was expected`, or after the last
    /// record these records hold (a line appended).
    pub(crate) fn expected(&self) -> String {
        match self.next < self.end {
            true => format!("where {} was expected", self.trial(self.next)),
            false => {
                let last = self.trial(self.end.saturating_sub(1));
                format!("after the last one these records hold ({last})")
            }
        }
    }

    fn err(&self, msg: String) -> Error {
        Error::file(&self.path, format!("line {}", self.line), msg)
    }

    /// The file these records are read from.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// Records read so far.
    pub(crate) fn lines(&self) -> usize {
        self.line
    }

    /// Reads the next line, `text` (without its line end): checks its checksum and that it
    /// holds the next unit; returns its sweep point, its trial and what the trial gave.
    pub(crate) fn record<T: DeserializeOwned>(&mut self, text: &str) -> Result<(usize, usize, T)> {
        self.line += 1;
        if text.ends_with('\r') {
            return Err(self.err(format!(
                "the record {} ends in CR LF, where calbench writes LF: the file was \
                 converted (by an editor or a checkout), and a checkpoint is continued by its \
                 byte count",
                self.expected()
            )));
        }
        let Some((body, sum)) = text.rsplit_once(" #") else {
            return Err(self.err(format!(
                "the record {} has no checksum at its end: it was cut short or altered",
                self.expected()
            )));
        };
        let r: Record<T> = ron::from_str(body).map_err(|e| {
            self.err(format!(
                "the record {} cannot be read ({e}): it was altered, or the file is not a \
                 calbench record",
                self.expected()
            ))
        })?;
        if r.trial as u64 >= self.trials {
            return Err(self.err(format!(
                "trial {} is beyond the run's {} trials",
                r.trial, self.trials
            )));
        }
        // A point so large that its units overflow is past any run's last unit.
        let Some(u) = (r.point as u64)
            .checked_mul(self.trials)
            .and_then(|u| u.checked_add(r.trial as u64))
        else {
            return Err(self.err(format!(
                "sweep point {} is beyond the run's sweep points: the record was altered",
                r.point
            )));
        };
        if sum != self.id.checksum(r.point, r.trial, body) {
            return Err(self.err(format!(
                "the record of {} does not match its checksum: it was altered, or belongs to \
                 another run (another scenario, seed, sweep point or trial)",
                self.trial(u)
            )));
        }
        if self.next >= self.end {
            return Err(self.err(format!(
                "{} is past the last trial these records hold ({}): an extra record",
                self.trial(u),
                self.trial(self.end.saturating_sub(1))
            )));
        }
        if u < self.next {
            return Err(self.err(format!(
                "{} again, where {} was expected: a duplicated or reordered record",
                self.trial(u),
                self.trial(self.next)
            )));
        }
        if u > self.next {
            return Err(self.err(format!(
                "{} where {} was expected: the records from {} are missing, or out of \
                 order (a run writes them in order)",
                self.trial(u),
                self.trial(self.next),
                self.trial(self.next)
            )));
        }
        self.next += 1;
        Ok((r.point, r.trial, r.result))
    }

    /// The refusal of the record last read, which does not fit its run for the reason `why`
    /// (its block lists other methods or parameters, a study has other cells): naming the
    /// file and the line.
    pub(crate) fn unfit(&self, why: &str) -> Error {
        self.err(format!(
            "the record does not fit its run: {why} (the file was altered)"
        ))
    }

    /// Checks, once every line is read, that no unit is missing at the end.
    pub(crate) fn finish(&self) -> Result<()> {
        if self.next < self.end {
            return Err(Error::file(
                &self.path,
                format!("line {}", self.line + 1),
                format!(
                    "the records end before {}: {} of the {} trials they should hold are missing",
                    self.trial(self.next),
                    self.end - self.next,
                    self.end - self.next + self.line as u64
                ),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::ErrorStats;
    use crate::identify::Termination;
    use crate::numeric::Real;
    use crate::study::outcome::{Outcome, SearchRun};
    use crate::study::TrialResult;

    const SETTINGS: &str = "name = \"r\"\nseed = 5\n";

    #[test]
    fn a_record_reads_back_bit_for_bit() {
        let stats = |x: Real| ErrorStats {
            mean: x,
            rms: x * 1.1,
            max: 1e-300,
            std: Real::NAN,
        };
        let t = TrialResult {
            index: 17,
            truth: vec![0.1, -0.0, 1.0 / 3.0],
            crb_trace: vec![Some(2.5e-7), None],
            not_determinable: vec![vec![1], vec![]],
            outcomes: vec![Outcome {
                method: 1,
                strategy: 0,
                identified: vec![Real::INFINITY, Real::NAN, -1e300],
                before_mm: stats(0.7),
                after_mm: stats(0.1),
                calibration_before_mm: stats(0.6),
                calibration_after_mm: stats(0.05),
                optional: crate::study::trial::OptionalStats {
                    validation_after_deg: Some(stats(0.3)),
                    validation_before_axis_mm: Some(stats(-0.2)),
                    validation_after_axis_abs_mm: Some(stats(0.01)),
                    calibration_after_attitude_deg: Some(stats(0.02)),
                    ..Default::default()
                },
                per_point: None,
                per_point_attitude_deg: None,
                trace: None,
                search: Some(SearchRun {
                    budget: 40,
                    hits: [Some(10), None, Some(30), None],
                    at_budget: [Real::NAN, 1.5, 1.0 / 3.0, 0.25],
                    final_fitness: 0.25,
                }),
                iterations: 12,
                evaluations: 40,
                termination: Termination::MaxIterations,
                rank_deficient_expected: true,
                seconds: 0.00123,
                error: Some("a \"quoted\"\nmessage #1".into()),
            }],
        };
        let id = RunId::new(SETTINGS, &[], 5);
        let line = encode(&id, 3, 17, &t).unwrap();
        assert_eq!(line.lines().count(), 1, "{line}");
        let mut v = Verifier::new(Path::new("r.txt"), id, 20, Some("sweep point"), (77, 78));
        let (b, i, u): (usize, usize, TrialResult) = v.record(line.trim_end()).unwrap();
        v.finish().unwrap();
        assert_eq!((b, i), (3, 17));
        assert_eq!(encode(&id, 3, 17, &u).unwrap(), line);
        let bits = |v: &[Real]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&u.truth), bits(&t.truth));
        assert_eq!(u.not_determinable, t.not_determinable);
        assert_eq!(
            bits(&u.outcomes[0].identified),
            bits(&t.outcomes[0].identified)
        );
        let (a, o) = (&u.outcomes[0], &t.outcomes[0]);
        assert_eq!(format!("{:?}", a.optional), format!("{:?}", o.optional));
        assert_eq!(a.error, o.error);
        assert_eq!(a.termination, o.termination);
        assert_eq!(
            a.search.as_ref().unwrap().hits,
            o.search.as_ref().unwrap().hits
        );
        let mut v = Verifier::new(Path::new("r.txt"), id, 20, Some("sweep point"), (77, 78));
        let e = v
            .record::<TrialResult>("(point:3,trial:17) #00")
            .unwrap_err();
        assert!(e.to_string().contains("line 1") && e.to_string().contains("cannot be read"));
    }

    /// A changed digit, a record missing, twice or out of place, a record of another seed or
    /// of another scenario with the same name and seed, and a record moved to another trial or
    /// sweep point, are each refused naming the line and the trial; untouched records read back.
    #[test]
    fn damaged_and_foreign_records_are_refused_naming_the_line_and_the_trial() {
        let t = |index| TrialResult {
            index,
            truth: vec![0.25, -1.5],
            crb_trace: vec![None],
            not_determinable: vec![vec![]],
            outcomes: Vec::new(),
        };
        let id = RunId::new(SETTINGS, &[], 9);
        let lines: Vec<String> = (0..4).map(|i| encode(&id, 0, i, &t(i)).unwrap()).collect();
        let read = |id: RunId, lines: &[String]| -> Result<usize> {
            let mut v = Verifier::new(Path::new("r.txt"), id, 4, None, (0, 4));
            for l in lines {
                v.record::<TrialResult>(l.trim_end())?;
            }
            v.finish()?;
            Ok(v.lines())
        };
        assert_eq!(read(id, &lines).unwrap(), 4);
        let refused = |id: RunId, lines: &[String], want: &[&str]| {
            let e = read(id, lines).unwrap_err().to_string();
            for w in want {
                assert!(e.contains(w), "{e}: no {w}");
            }
        };
        let mut changed = lines.clone();
        changed[2] = changed[2].replace("0.25", "0.35");
        refused(id, &changed, &["line 3", "trial 2", "checksum"]);
        refused(
            RunId::new(SETTINGS, &[], 8),
            &lines,
            &["line 1", "trial 0", "another run"],
        );
        let other = RunId::new(&format!("{SETTINGS}trials = 9\n"), &[], 9);
        refused(other, &lines, &["line 1", "trial 0", "another run"]);
        // The same settings reading a robot file of other bytes: another run.
        let robot = crate::study::inputs::Input {
            path: "robots/arm.toml".into(),
            sha256: "0".repeat(64),
        };
        let other = RunId::new(SETTINGS, &[robot], 9);
        refused(other, &lines, &["line 1", "trial 0", "another run"]);
        let mut moved = lines.clone();
        moved[1] = moved[1].replacen("trial:1", "trial:2", 1);
        refused(id, &moved, &["line 2", "trial 2", "checksum"]);
        let mut point = lines.clone();
        point[1] = point[1].replacen("point:0", "point:1", 1);
        refused(id, &point, &["line 2", "checksum"]);
        let mut gone = lines.clone();
        gone.remove(1);
        refused(id, &gone, &["line 2", "trial 2", "trial 1 was expected"]);
        gone = lines[..3].to_vec();
        refused(id, &gone, &["line 4", "before trial 3", "1 of the 4"]);
        let mut twice = lines.clone();
        twice.insert(2, lines[1].clone());
        refused(id, &twice, &["line 3", "trial 1 again", "duplicated"]);
        let mut swapped = lines.clone();
        swapped.swap(1, 2);
        refused(
            id,
            &swapped,
            &["line 2", "trial 2 where trial 1", "out of order"],
        );
        let mut cut = lines.clone();
        cut[3] = cut[3][..cut[3].len() - 8].to_string();
        refused(id, &cut, &["line 4", "trial 3"]);
        // A line appended after the last record is placed after it, not at a trial 0.
        let mut garbage = lines.clone();
        garbage.push("garbage".into());
        let after = "after the last one these records hold (trial 3) has no checksum";
        refused(id, &garbage, &["line 5", after]);
    }
}
