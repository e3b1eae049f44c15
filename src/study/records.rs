//! The record format of `records.txt`, in a shard folder and in a checkpoint
//! (docs/formats.md § 7.3): one line per trial with every number the aggregation reads,
//! floats in shortest round-trip form, ending in a checksum of the line.
//!
//! A line is `block trial n truth… crb… outcomes #SUM`, where `SUM` is 16 hexadecimal digits
//! of the FNV-1a 64-bit hash of the run's seed (8 bytes, little-endian) and the text before
//! ` #`. Each step of FNV-1a is a bijection of the hash, so any change of one byte of the line
//! changes the sum; the seed makes a record of another run fail it too. A reader
//! (`Verifier`) checks every line's sum and that the lines hold the run's trials in order,
//! each once: a changed, missing, duplicated or reordered record is refused, naming the file,
//! the line and the trial.

use std::path::{Path, PathBuf};

use crate::calibrate::ErrorStats;
use crate::error::{Error, Result};
use crate::identify::Termination;
use crate::numeric::Real;
use crate::study::outcome::{OptionalStats, Outcome};
use crate::study::stats::ecdf::{self, SearchRun};
use crate::study::TrialResult;

/// FNV-1a, 64 bits: the hash of `seed` (little-endian) then `body`.
fn checksum(seed: u64, body: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in seed.to_le_bytes().iter().chain(body.as_bytes()) {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// A word of a record as a message quotes it: at most 24 characters, escaped, so that a
/// damaged file never makes a long or multi-line message.
fn shown(w: &str) -> String {
    let mut s: String = w
        .chars()
        .take(24)
        .collect::<String>()
        .escape_debug()
        .to_string();
    if w.chars().count() > 24 {
        s.push('…');
    }
    s
}

fn push_stats(s: &mut String, e: &ErrorStats) {
    for v in [e.mean, e.rms, e.max, e.std] {
        s.push(' ');
        s.push_str(&format!("{v:e}"));
    }
}

/// A search's numbers ([`SearchRun`]): `+ budget`, the evaluations of each target (`-`: not
/// reached), the best fitness at each budget. Written only for the searches, so the records
/// of the other methods are those of before.
fn push_search(s: &mut String, r: &SearchRun) {
    s.push_str(&format!(" + {}", r.budget));
    for h in r.hits {
        match h {
            Some(e) => s.push_str(&format!(" {e}")),
            None => s.push_str(" -"),
        }
    }
    for v in r.at_budget {
        s.push_str(&format!(" {v:e}"));
    }
}

/// One trial of the run with `seed` as a line of `records.txt`: `block trial n truth… crb…
/// outcomes #SUM`, each outcome `strategy method termination rank-deficient-expected
/// iterations evaluations seconds`, four statistics of four numbers (validation and
/// calibration, before and after), the optional statistics (`-`, or `+` and four numbers)
/// and the n identified values, then for a search `+` and its [`SearchRun`]; `SUM` is the line's [`checksum`].
pub(crate) fn encode(seed: u64, block: usize, t: &TrialResult) -> String {
    let mut s = format!("{block} {} {}", t.index, t.truth.len());
    for v in &t.truth {
        s.push_str(&format!(" {v:e}"));
    }
    s.push_str(&format!(" {}", t.crb_trace.len()));
    for c in &t.crb_trace {
        match c {
            Some(v) => s.push_str(&format!(" {v:e}")),
            None => s.push_str(" -"),
        }
    }
    s.push_str(&format!(" {}", t.outcomes.len()));
    for o in &t.outcomes {
        s.push_str(&format!(
            " {} {} {} {} {} {} {:e}",
            o.strategy,
            o.method,
            o.termination.as_str(),
            u8::from(o.rank_deficient_expected),
            o.iterations,
            o.evaluations,
            o.seconds
        ));
        push_stats(&mut s, &o.before_mm);
        push_stats(&mut s, &o.after_mm);
        push_stats(&mut s, &o.calibration_before_mm);
        push_stats(&mut s, &o.calibration_after_mm);
        for d in o.optional.values() {
            match d {
                Some(d) => {
                    s.push_str(" +");
                    push_stats(&mut s, &d);
                }
                None => s.push_str(" -"),
            }
        }
        for v in &o.identified {
            s.push_str(&format!(" {v:e}"));
        }
        if let Some(r) = &o.search {
            push_search(&mut s, r);
        }
    }
    let sum = checksum(seed, &s);
    s.push_str(&format!(" #{sum:016x}\n"));
    s
}

/// Reads the tokens of one record line.
struct Tokens<'a> {
    it: std::iter::Peekable<std::str::SplitAsciiWhitespace<'a>>,
    path: &'a Path,
    line: usize,
}

impl<'a> Tokens<'a> {
    fn err(&self, what: &str) -> Error {
        Error::file(
            self.path,
            format!("line {}", self.line),
            format!("{what} (the file is not a calbench record, or is cut short)"),
        )
    }
    fn word(&mut self) -> Result<&'a str> {
        self.it.next().ok_or_else(|| self.err("missing field"))
    }
    fn usize(&mut self) -> Result<usize> {
        let w = self.word()?;
        w.parse()
            .map_err(|_| self.err(&format!("\"{}\" is not a count", shown(w))))
    }
    fn real(&mut self) -> Result<Real> {
        let w = self.word()?;
        w.parse()
            .map_err(|_| self.err(&format!("\"{}\" is not a number", shown(w))))
    }
    fn reals(&mut self, n: usize) -> Result<Vec<Real>> {
        (0..n).map(|_| self.real()).collect()
    }
    fn stats(&mut self) -> Result<ErrorStats> {
        Ok(ErrorStats {
            mean: self.real()?,
            rms: self.real()?,
            max: self.real()?,
            std: self.real()?,
        })
    }
    /// A search's numbers, if the next word is `+` (see [`push_search`]).
    fn search(&mut self) -> Result<Option<SearchRun>> {
        if self.it.peek() != Some(&"+") {
            return Ok(None);
        }
        self.word()?;
        let budget = self.usize()?;
        let mut hits = [None; ecdf::DELTAS.len()];
        for h in &mut hits {
            *h = match self.word()? {
                "-" => None,
                w => Some(
                    w.parse()
                        .map_err(|_| self.err(&format!("\"{}\" is not a count", shown(w))))?,
                ),
            };
        }
        let mut at_budget = [0.0; ecdf::BUDGET_FRACTIONS.len()];
        for v in &mut at_budget {
            *v = self.real()?;
        }
        Ok(Some(SearchRun {
            budget,
            hits,
            at_budget,
        }))
    }
    fn optional_stats(&mut self) -> Result<Option<ErrorStats>> {
        match self.word()? {
            "-" => Ok(None),
            "+" => self.stats().map(Some),
            w => Err(self.err(&format!("\"{}\" is neither - nor +", shown(w)))),
        }
    }
}

/// Parses the text before the checksum of line `line` of `path` (see [`encode`]): the block
/// index and the trial.
fn decode(text: &str, path: &Path, line: usize) -> Result<(usize, TrialResult)> {
    let mut t = Tokens {
        it: text.split_ascii_whitespace().peekable(),
        path,
        line,
    };
    let block = t.usize()?;
    let index = t.usize()?;
    let n = t.usize()?;
    let truth = t.reals(n)?;
    let ns = t.usize()?;
    let mut crb_trace = Vec::with_capacity(ns);
    for _ in 0..ns {
        crb_trace.push(match t.word()? {
            "-" => None,
            w => Some(
                w.parse()
                    .map_err(|_| t.err(&format!("\"{}\" is not a number", shown(w))))?,
            ),
        });
    }
    let no = t.usize()?;
    let mut outcomes = Vec::with_capacity(no);
    for _ in 0..no {
        let strategy = t.usize()?;
        let method = t.usize()?;
        let name = t.word()?.to_string();
        let termination: Termination = crate::robot::names::parse("termination", &name)
            .map_err(|_| t.err(&format!("unknown termination \"{}\"", shown(&name))))?;
        let rank_deficient_expected = match t.usize()? {
            0 => false,
            1 => true,
            v => return Err(t.err(&format!("{v} is not a flag (0 or 1)"))),
        };
        let iterations = t.usize()?;
        let evaluations = t.usize()?;
        let seconds = t.real()?;
        let before_mm = t.stats()?;
        let after_mm = t.stats()?;
        let calibration_before_mm = t.stats()?;
        let calibration_after_mm = t.stats()?;
        let mut optional = OptionalStats::default();
        for o in optional.values_mut() {
            *o = t.optional_stats()?;
        }
        let identified = t.reals(n)?;
        let search = t.search()?;
        outcomes.push(Outcome {
            method,
            strategy,
            identified,
            before_mm,
            after_mm,
            calibration_before_mm,
            calibration_after_mm,
            optional,
            per_point: None,
            per_point_attitude_deg: None,
            trace: None,
            search,
            iterations,
            evaluations,
            termination,
            rank_deficient_expected,
            seconds,
            // Shards run scenario files, whose methods are all registered ones.
            error: None,
        });
    }
    if t.it.next().is_some() {
        return Err(t.err("extra fields at the end of the line"));
    }
    Ok((
        block,
        TrialResult {
            index,
            truth,
            crb_trace,
            outcomes,
        },
    ))
}

/// The reader of one `records.txt` that holds the work units `[start, end)` of a run (unit
/// `u` is trial `u % trials` of block `u / trials`): every line must carry its checksum and
/// the next unit, so a changed, missing, duplicated or reordered record is refused, naming
/// the file, the line and the trial.
pub(crate) struct Verifier {
    path: PathBuf,
    seed: u64,
    trials: u64,
    sweep: bool,
    next: u64,
    end: u64,
    line: usize,
}

impl Verifier {
    /// The reader of `path`, records of the run with `seed` and `trials` trials per block
    /// (`sweep`: whether blocks are sweep points), holding the units `units`.
    pub(crate) fn new(
        path: &Path,
        seed: u64,
        trials: usize,
        sweep: bool,
        units: (u64, u64),
    ) -> Verifier {
        Verifier {
            path: path.to_path_buf(),
            seed,
            trials: trials.max(1) as u64,
            sweep,
            next: units.0,
            end: units.1,
            line: 0,
        }
    }

    /// Unit `u` as the messages name it: `trial I`, and its sweep point in a sweep.
    fn trial(&self, u: u64) -> String {
        let (b, i) = (u / self.trials, u % self.trials);
        if self.sweep {
            format!("trial {i} of sweep point {b}")
        } else {
            format!("trial {i}")
        }
    }

    fn err(&self, msg: String) -> Error {
        Error::file(&self.path, format!("line {}", self.line), msg)
    }

    /// Records read so far.
    pub(crate) fn lines(&self) -> usize {
        self.line
    }

    /// Reads the next line, `text` (without its line end): checks its checksum and that it
    /// holds the next unit; returns its block and trial.
    pub(crate) fn record(&mut self, text: &str) -> Result<(usize, TrialResult)> {
        self.line += 1;
        let claim = {
            let mut w = text.split_ascii_whitespace();
            match (
                w.next().and_then(|b| b.parse::<u64>().ok()),
                w.next().and_then(|i| i.parse::<u64>().ok()),
            ) {
                (Some(b), Some(i)) if i < self.trials => {
                    format!("the record of {}", self.trial(b * self.trials + i))
                }
                _ => "the record".to_string(),
            }
        };
        let Some((body, sum)) = text.rsplit_once(" #") else {
            return Err(self.err(format!(
                "{claim} has no checksum at its end: it was cut short or altered"
            )));
        };
        let sum = u64::from_str_radix(sum, 16)
            .ok()
            .filter(|_| sum.len() == 16);
        if sum != Some(checksum(self.seed, body)) {
            return Err(self.err(format!(
                "{claim} does not match its checksum: it was altered, or belongs to another run"
            )));
        }
        let (b, t) = decode(body, &self.path, self.line)?;
        if t.index as u64 >= self.trials {
            return Err(self.err(format!(
                "trial {} is beyond the run's {} trials",
                t.index, self.trials
            )));
        }
        let u = b as u64 * self.trials + t.index as u64;
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
                "{} where {} was expected: the records from {} are missing",
                self.trial(u),
                self.trial(self.next),
                self.trial(self.next)
            )));
        }
        self.next += 1;
        Ok((b, t))
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
                }),
                iterations: 12,
                evaluations: 40,
                termination: Termination::MaxIterations,
                rank_deficient_expected: true,
                seconds: 0.00123,
                error: None,
            }],
        };
        let line = encode(5, 3, &t);
        let mut v = Verifier::new(Path::new("r.txt"), 5, 20, true, (77, 78));
        let (b, u) = v.record(line.trim_end()).unwrap();
        v.finish().unwrap();
        assert_eq!(b, 3);
        assert_eq!(encode(5, 3, &u), line);
        assert_eq!(u.truth[2].to_bits(), t.truth[2].to_bits());
        assert_eq!(u.truth[1].to_bits(), (-0.0f64).to_bits());
        assert!(u.outcomes[0].identified[1].is_nan());
        assert!(decode("3 17 2 0.1", Path::new("r.txt"), 4)
            .unwrap_err()
            .to_string()
            .contains("line 4"));
    }

    /// A changed digit, a record missing, twice or out of place, and a record of another
    /// seed are each refused naming the line and the trial; untouched records read back.
    #[test]
    fn damaged_records_are_refused_naming_the_line_and_the_trial() {
        let t = |index| TrialResult {
            index,
            truth: vec![0.25, -1.5],
            crb_trace: vec![None],
            outcomes: Vec::new(),
        };
        let lines: Vec<String> = (0..4).map(|i| encode(9, 0, &t(i))).collect();
        let read = |seed: u64, lines: &[String]| -> Result<usize> {
            let mut v = Verifier::new(Path::new("r.txt"), seed, 4, false, (0, 4));
            for l in lines {
                v.record(l.trim_end())?;
            }
            v.finish()?;
            Ok(v.lines())
        };
        assert_eq!(read(9, &lines).unwrap(), 4);
        let refused = |seed: u64, lines: &[String], want: &[&str]| {
            let e = read(seed, lines).unwrap_err().to_string();
            for w in want {
                assert!(e.contains(w), "{e}: no {w}");
            }
        };
        let mut changed = lines.clone();
        changed[2] = changed[2].replace("2.5e-1", "3.5e-1");
        refused(9, &changed, &["line 3", "trial 2", "checksum"]);
        refused(8, &lines, &["line 1", "trial 0", "another run"]);
        let mut gone = lines.clone();
        gone.remove(1);
        refused(9, &gone, &["line 2", "trial 2", "trial 1 was expected"]);
        gone = lines[..3].to_vec();
        refused(9, &gone, &["line 4", "before trial 3", "1 of the 4"]);
        let mut twice = lines.clone();
        twice.insert(2, lines[1].clone());
        refused(9, &twice, &["line 3", "trial 1 again", "duplicated"]);
        let mut cut = lines.clone();
        cut[3] = cut[3][..cut[3].len() - 8].to_string();
        refused(9, &cut, &["line 4", "trial 3"]);
    }
}
