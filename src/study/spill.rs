//! Per-trial numbers kept in a scratch file instead of memory, so that a study's memory does
//! not grow with its trials: the parameter errors and η values from which [`super::stats`]
//! takes exact medians and two-pass standard deviations.
//!
//! A [`Spill`] holds numbered streams of values. Each stream keeps its last [`SPILL_CHUNK`]
//! values in memory and writes every full chunk to one shared scratch file (created on the
//! first full chunk, so a study of a few hundred trials never touches the disk; removed
//! from the file system as soon as it is open, so nothing is left behind even by SIGKILL).
//! Reading a stream back goes through its chunks in push order, so every sum over it runs in
//! the order of an in-memory vector and gives the same bits; the median is the exact order
//! statistic, found by [`Spill::select`] in a few passes with bounded memory.
//!
//! A finished study keeps each trial's numbers as [`Spilled`] handles on the same file, read
//! back only by the analysis that pairs them ([`crate::analysis`]), one pair at a time.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::sync::{Arc, Mutex, PoisonError};

use crate::error::{Error, Result};
use crate::numeric::Real;

/// Values per chunk of a stream (4 kB).
pub const SPILL_CHUNK: usize = 512;

/// Values [`Spill::select`] sorts in memory: above it, it first narrows the candidates by
/// [`SELECT_BITS`] bits of their order key per pass over the stream.
const SELECT_IN_MEMORY: usize = 4096;

/// Bits of the order key [`Spill::select`] resolves per pass.
const SELECT_BITS: u32 = 8;

/// Numbered streams of values, spilled to a scratch file a chunk at a time.
#[derive(Debug, Default)]
pub struct Spill {
    file: Option<Arc<Mutex<File>>>,
    end: u64,
    streams: Vec<Stream>,
}

/// One stream: its full chunks' offsets in the file and its last, partial chunk.
#[derive(Clone, Debug, Default)]
struct Stream {
    chunks: Vec<u64>,
    tail: Vec<Real>,
}

impl Stream {
    fn len(&self) -> usize {
        self.chunks.len() * SPILL_CHUNK + self.tail.len()
    }

    /// Calls `f` on every value, in push order, reading the full chunks from `file`.
    fn for_each(&self, file: Option<&Mutex<File>>, mut f: impl FnMut(Real)) -> Result<()> {
        if !self.chunks.is_empty() {
            let file = file.expect("chunks are in the file");
            let mut file = file.lock().unwrap_or_else(PoisonError::into_inner);
            let mut bytes = vec![0u8; SPILL_CHUNK * 8];
            for &at in &self.chunks {
                file.seek(SeekFrom::Start(at))
                    .and_then(|_| file.read_exact(&mut bytes))
                    .map_err(scratch_error)?;
                for b in bytes.chunks_exact(8) {
                    f(Real::from_le_bytes(b.try_into().expect("8 bytes")));
                }
            }
        }
        self.tail.iter().for_each(|&x| f(x));
        Ok(())
    }
}

/// One stream of a [`Spill`] as it stood when taken ([`Spill::stream`]): its values stay in
/// the scratch file (kept open while a handle lives) and are read back on demand.
#[derive(Clone, Debug, Default)]
pub struct Spilled {
    file: Option<Arc<Mutex<File>>>,
    stream: Stream,
}

impl Spilled {
    /// The values, in push order.
    pub fn values(&self) -> Result<Vec<Real>> {
        let mut v = Vec::with_capacity(self.stream.len());
        self.stream.for_each(self.file.as_deref(), |x| v.push(x))?;
        Ok(v)
    }
}

/// The order key of `x` under [`Real::total_cmp`]: unsigned comparison of keys is that order.
fn key(x: Real) -> u64 {
    let b = x.to_bits();
    if b >> 63 == 1 {
        !b
    } else {
        b | (1 << 63)
    }
}

fn unkey(k: u64) -> Real {
    Real::from_bits(if k >> 63 == 1 { k & !(1 << 63) } else { !k })
}

fn scratch_error(e: std::io::Error) -> Error {
    Error::Compute(format!(
        "cannot use the scratch file of the per-trial statistics in {}: {e}",
        std::env::temp_dir().display()
    ))
}

impl Spill {
    /// `streams` empty streams.
    pub fn new(streams: usize) -> Spill {
        Spill {
            file: None,
            end: 0,
            streams: (0..streams).map(|_| Stream::default()).collect(),
        }
    }

    /// Appends `x` to stream `s`.
    pub fn push(&mut self, s: usize, x: Real) -> Result<()> {
        let st = &mut self.streams[s];
        st.tail.push(x);
        if st.tail.len() < SPILL_CHUNK {
            return Ok(());
        }
        if self.file.is_none() {
            let file = scratch_file().map_err(scratch_error)?;
            self.file = Some(Arc::new(Mutex::new(file)));
        }
        let file = self.file.as_ref().expect("opened");
        let mut file = file.lock().unwrap_or_else(PoisonError::into_inner);
        let bytes: Vec<u8> = st.tail.iter().flat_map(|v| v.to_le_bytes()).collect();
        file.seek(SeekFrom::Start(self.end))
            .and_then(|_| file.write_all(&bytes))
            .map_err(scratch_error)?;
        st.chunks.push(self.end);
        self.end += bytes.len() as u64;
        st.tail.clear();
        Ok(())
    }

    /// Values in stream `s`.
    pub fn len(&self, s: usize) -> usize {
        self.streams[s].len()
    }

    /// Whether stream `s` is empty.
    pub fn is_empty(&self, s: usize) -> bool {
        self.len(s) == 0
    }

    /// Calls `f` on every value of stream `s`, in push order.
    pub fn for_each(&self, s: usize, f: impl FnMut(Real)) -> Result<()> {
        self.streams[s].for_each(self.file.as_deref(), f)
    }

    /// Stream `s` as it stands, to be read back after the spill is gone.
    pub fn stream(&self, s: usize) -> Spilled {
        Spilled {
            file: self.file.clone(),
            stream: self.streams[s].clone(),
        }
    }

    /// The mean of stream `s`, summed in order from −0 as `Iterator::sum` (NaN when empty).
    pub fn mean(&self, s: usize) -> Result<Real> {
        self.mean_of(s, |x| x)
    }

    /// The mean of `f(x)` over stream `s`, summed in order from −0 (NaN when empty).
    pub fn mean_of(&self, s: usize, f: impl Fn(Real) -> Real) -> Result<Real> {
        let n = self.len(s);
        if n == 0 {
            return Ok(Real::NAN);
        }
        let mut total = -0.0;
        self.for_each(s, |x| total += f(x))?;
        Ok(total / n as Real)
    }

    /// The standard deviation (divisor n) of stream `s` in two passes: the mean, then the
    /// mean square deviation from it, each summed in order (NaN when empty).
    pub fn std(&self, s: usize) -> Result<Real> {
        let m = self.mean(s)?;
        Ok(self.mean_of(s, |x| (x - m) * (x - m))?.sqrt())
    }

    /// The exact median of stream `s` (the mean of the two middle values of an even count;
    /// NaN when empty), as [`crate::numeric::median`] of the values in memory.
    pub fn median(&self, s: usize) -> Result<Real> {
        let n = self.len(s);
        if n == 0 {
            return Ok(Real::NAN);
        }
        if n % 2 == 1 {
            return self.select(s, n / 2);
        }
        Ok(0.5 * (self.select(s, n / 2 - 1)? + self.select(s, n / 2)?))
    }

    /// The `k`-th smallest value of stream `s` (from 0, in [`Real::total_cmp`] order): the
    /// values whose order key starts with the bits chosen so far are counted by their next
    /// 8 bits, the bucket holding rank `k` is kept, and once few enough
    /// candidates remain they are sorted in memory. At most eight passes, usually two or
    /// three; memory independent of the stream's length (32 kB).
    pub fn select(&self, s: usize, k: usize) -> Result<Real> {
        let (mut prefix, mut bits, mut rank, mut candidates) = (0u64, 0u32, k, self.len(s));
        let matches =
            |x: Real, prefix: u64, bits: u32| bits == 0 || key(x) >> (64 - bits) == prefix;
        loop {
            if bits == 64 {
                return Ok(unkey(prefix));
            }
            if candidates <= SELECT_IN_MEMORY {
                let mut v = Vec::with_capacity(candidates);
                self.for_each(s, |x| {
                    if matches(x, prefix, bits) {
                        v.push(x);
                    }
                })?;
                v.sort_unstable_by(|a, b| a.total_cmp(b));
                return Ok(v[rank]);
            }
            let mut counts = [0usize; 1 << SELECT_BITS];
            self.for_each(s, |x| {
                if matches(x, prefix, bits) {
                    counts[((key(x) << bits) >> (64 - SELECT_BITS)) as usize] += 1;
                }
            })?;
            let mut bucket = 0;
            while rank >= counts[bucket] {
                rank -= counts[bucket];
                bucket += 1;
            }
            candidates = counts[bucket];
            prefix = (prefix << SELECT_BITS) | bucket as u64;
            bits += SELECT_BITS;
        }
    }
}

/// A new scratch file in the temporary folder, already unlinked where the system allows it.
fn scratch_file() -> std::io::Result<File> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir();
    loop {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let path = dir.join(format!("calbench-{}-{n}.spill", std::process::id()));
        match std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&path)
        {
            Ok(f) => {
                // Unix keeps an open, unlinked file until it is closed; elsewhere the file
                // stays until the next cleaning of the temporary folder.
                let _ = std::fs::remove_file(&path);
                return Ok(f);
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Means, deviations and medians of spilled streams (several streams interleaved, lengths
    /// around the chunk size and beyond the in-memory selection, ties, signs and zeros)
    /// against the same statistics of the values in memory, to the bit.
    #[test]
    fn spilled_statistics_are_those_of_the_values_in_memory() {
        let mut g = crate::numeric::rng::from_seed(4);
        let lengths = [
            0,
            1,
            2,
            SPILL_CHUNK - 1,
            SPILL_CHUNK,
            3 * SPILL_CHUNK + 7,
            70_001,
        ];
        let mut spill = Spill::new(lengths.len());
        let mut values: Vec<Vec<Real>> = vec![Vec::new(); lengths.len()];
        let longest = *lengths.iter().max().expect("lengths");
        for i in 0..longest {
            for (s, &n) in lengths.iter().enumerate() {
                if i < n {
                    let x = match i % 5 {
                        0 => 0.0,
                        1 => -0.0,
                        2 => 1.5,
                        _ => rand::Rng::random_range(&mut g, -100.0..100.0),
                    };
                    spill.push(s, x).expect("push");
                    values[s].push(x);
                }
            }
        }
        let mean = |v: &[Real]| v.iter().sum::<Real>() / v.len() as Real;
        for (s, v) in values.iter().enumerate() {
            assert_eq!(spill.len(s), v.len());
            let mut back = Vec::new();
            spill.for_each(s, |x| back.push(x)).expect("read");
            assert_eq!(
                back.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
            );
            if v.is_empty() {
                assert!(spill.median(s).expect("median").is_nan());
                continue;
            }
            let m = mean(v);
            assert_eq!(spill.mean(s).expect("mean").to_bits(), m.to_bits());
            let sd = (v.iter().map(|x| (x - m) * (x - m)).sum::<Real>() / v.len() as Real).sqrt();
            assert_eq!(spill.std(s).expect("std").to_bits(), sd.to_bits());
            let med = crate::numeric::median(&mut v.clone());
            assert_eq!(spill.median(s).expect("median").to_bits(), med.to_bits());
        }
        for x in [-3.5, -0.0, 0.0, 2.0, Real::INFINITY, Real::NEG_INFINITY] {
            assert_eq!(unkey(key(x)).to_bits(), x.to_bits());
        }
        // a stream taken out, then more pushed into the spill, then the spill dropped: the
        // handle reads the values as they stood when it was taken
        let taken: Vec<Spilled> = (0..lengths.len()).map(|s| spill.stream(s)).collect();
        for i in 0..2 * SPILL_CHUNK {
            spill.push(lengths.len() - 1, i as Real).expect("push");
        }
        drop(spill);
        for (t, v) in taken.iter().zip(&values) {
            let back = t.values().expect("read");
            assert_eq!(
                back.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
            );
        }
    }
}
