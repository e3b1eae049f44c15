//! The worker threads of a study (docs/formats.md `run`, `--threads`): the count asked for
//! (or the one a Slurm task was given, `SLURM_CPUS_PER_TASK`), refused when it is 0, and
//! capped at the work (a thread per trial or unit at most) and at [`CORE_MULTIPLE`] times the
//! machine's cores, with a note when it is capped. Every front end (`calbench run`, Python's
//! `run` and `run_shard`) takes its count from here.

use crate::error::{check_count, Error, Result};
use crate::study::reporter::Reporter;

/// A study runs on at most this many threads per core of the machine.
pub const CORE_MULTIPLE: usize = 4;

/// The variable Slurm sets to the CPUs it gave a task.
pub const SLURM_CPUS: &str = "SLURM_CPUS_PER_TASK";

/// The thread count of a study: `given` (the option `key`; 0 refused), else the positive
/// whole number in [`SLURM_CPUS`] when it is set (`var` reads a variable; anything else is
/// refused naming it), else `None` (one per core).
pub fn requested(
    key: &str,
    given: Option<usize>,
    var: &dyn Fn(&str) -> Option<String>,
) -> Result<Option<usize>> {
    if let Some(t) = given {
        check_count(key, t)?;
        return Ok(given);
    }
    match var(SLURM_CPUS) {
        None => Ok(None),
        Some(v) => match v.trim().parse::<usize>() {
            Ok(n) if n >= 1 => Ok(Some(n)),
            _ => Err(Error::setting(
                SLURM_CPUS,
                format!("is \"{v}\", not a whole number ≥ 1 (the CPUs Slurm gave the task)"),
            )),
        },
    }
}

/// The threads a study of `work` trials or units runs on when `requested` are asked for
/// (`None`: one per core), given the machine's `cores`: at most `work` and at most
/// [`CORE_MULTIPLE`] × `cores`, at least 1; with a note when the count asked for was capped.
pub fn capped(requested: Option<usize>, work: u64, cores: usize) -> (usize, Option<String>) {
    let cores = cores.max(1);
    let ceiling = (CORE_MULTIPLE * cores).min(usize::try_from(work).unwrap_or(usize::MAX));
    let asked = requested.unwrap_or(cores);
    let n = asked.min(ceiling).max(1);
    let note = (requested.is_some() && n < asked).then(|| {
        format!(
            "{asked} threads asked for; running on {n}: a study uses at most one thread per \
             trial ({work} to run) and {CORE_MULTIPLE} per core ({cores} cores)"
        )
    });
    (n, note)
}

/// The machine's cores as the standard library counts them (1 when it cannot tell).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The worker threads of a study of `work` trials or units: `threads` of them (`None`: one
/// per core), [`capped`] with the note to `reporter`.
pub fn pool(
    threads: Option<usize>,
    work: u64,
    reporter: &dyn Reporter,
) -> Result<rayon::ThreadPool> {
    let (threads, note) = capped(threads, work, cores());
    if let Some(note) = note {
        reporter.warning(&note);
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Compute(format!("cannot start the worker threads: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_count_is_capped_at_the_work_and_the_cores_with_a_note() {
        assert_eq!(
            capped(Some(99_999), 4, 2),
            (4, capped(Some(99_999), 4, 2).1)
        );
        assert!(capped(Some(99_999), 4, 2)
            .1
            .unwrap()
            .contains("99999 threads"));
        assert_eq!(capped(Some(99_999), 1000, 2).0, 8);
        assert_eq!(capped(Some(2), 1000, 2), (2, None));
        assert_eq!(
            capped(None, 3, 16),
            (3, None),
            "the default is capped without a note"
        );
        assert_eq!(capped(None, 0, 16).0, 1);
    }

    #[test]
    fn zero_and_a_bad_slurm_count_are_refused_naming_them() {
        let none = |_: &str| None;
        let e = requested("threads", Some(0), &none)
            .unwrap_err()
            .to_string();
        assert!(e.contains("threads") && e.contains("at least 1"), "{e}");
        assert_eq!(requested("threads", None, &none).unwrap(), None);
        let slurm = |v: &'static str| move |k: &str| (k == SLURM_CPUS).then(|| v.to_string());
        assert_eq!(requested("t", None, &slurm("6")).unwrap(), Some(6));
        assert_eq!(requested("t", Some(2), &slurm("x")).unwrap(), Some(2));
        for bad in ["0", "-3", "x", ""] {
            let e = requested("t", None, &slurm(bad)).unwrap_err().to_string();
            assert!(e.contains(SLURM_CPUS), "{e}");
        }
    }
}
