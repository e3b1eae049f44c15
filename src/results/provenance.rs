//! Where and with what a result was recorded: calbench's version and git commit, a hash of
//! `Cargo.lock`, the machine (host name, CPU model, cores, operating system) and the date.
//!
//! The commit is fixed when calbench is built (`build.rs`: `CALBENCH_GIT_COMMIT` from the
//! build's environment, else `git rev-parse HEAD` of the source tree, else `unknown` for a
//! tarball without `.git`); `Cargo.lock` is compiled in, so neither needs the source tree
//! when recording.

/// calbench's version (`Cargo.toml`).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The git commit calbench was built from, or `unknown`.
pub const GIT_COMMIT: &str = env!("CALBENCH_GIT_COMMIT");

/// The time of that commit, seconds since 1970 UTC, or empty when unknown.
pub const GIT_COMMIT_TIME: &str = env!("CALBENCH_GIT_COMMIT_TIME");

/// `Cargo.lock` as built.
const CARGO_LOCK: &[u8] = include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.lock"));

pub use crate::calibrate::task::sha256::sha256_hex;

/// A machine: what a result was computed or recorded on (also each shard's `machine` in
/// `shard.json`, docs/formats.md § 7.3).
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Machine {
    /// The host name.
    pub host: String,
    /// The CPU model (`/proc/cpuinfo`'s `model name`, else the architecture).
    pub cpu: String,
    /// The logical cores.
    pub cores: u32,
    /// The operating system, its kernel release and architecture.
    pub os: String,
}

impl Machine {
    /// This machine.
    pub fn here() -> Machine {
        Machine {
            host: host_name(),
            cpu: cpu_model(),
            cores: std::thread::available_parallelism().map_or(1, |n| n.get() as u32),
            os: os(),
        }
    }
}

/// The record's provenance.
#[derive(Clone, Debug)]
pub struct Provenance {
    /// The version label history orders and groups by: `--label`, or `VERSION+COMMIT12`.
    pub label: String,
    /// calbench's version.
    pub version: String,
    /// calbench's git commit.
    pub git_commit: String,
    /// SHA-256 of `Cargo.lock`.
    pub cargo_lock_hash: String,
    /// The machine's name: `--machine`, else the host name.
    pub machine: String,
    /// The CPU model (`/proc/cpuinfo`'s `model name`, else the architecture).
    pub cpu: String,
    /// The logical cores.
    pub cores: u32,
    /// The operating system, its kernel release and architecture.
    pub os: String,
    /// When it was recorded, UTC, `YYYY-MM-DDTHH:MM:SSZ`.
    pub recorded_at: String,
    /// The time of calbench's git commit, seconds since 1970 UTC, when known.
    pub commit_time: Option<i64>,
}

impl Provenance {
    /// This calbench on this machine now; `label` and `machine` override the defaults.
    pub fn here(label: Option<&str>, machine: Option<&str>) -> Provenance {
        let short: String = GIT_COMMIT.chars().take(12).collect();
        let here = Machine::here();
        Provenance {
            label: label.map_or_else(|| format!("{VERSION}+{short}"), str::to_string),
            version: VERSION.to_string(),
            git_commit: GIT_COMMIT.to_string(),
            cargo_lock_hash: sha256_hex(CARGO_LOCK),
            machine: machine.map_or(here.host, str::to_string),
            cpu: here.cpu,
            cores: here.cores,
            os: here.os,
            recorded_at: utc_now(),
            commit_time: GIT_COMMIT_TIME.parse().ok(),
        }
    }
}

fn read_trimmed(path: &str) -> Option<String> {
    let s = std::fs::read_to_string(path).ok()?;
    let s = s.trim();
    (!s.is_empty()).then(|| s.to_string())
}

fn host_name() -> String {
    read_trimmed("/proc/sys/kernel/hostname")
        .or_else(|| read_trimmed("/etc/hostname"))
        .or_else(|| std::env::var("COMPUTERNAME").ok())
        .unwrap_or_else(|| "unknown".to_string())
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

fn os() -> String {
    let name = std::fs::read_to_string("/etc/os-release")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("PRETTY_NAME="))
                .map(|v| v.trim_matches('"').to_string())
        })
        .unwrap_or_else(|| std::env::consts::OS.to_string());
    match read_trimmed("/proc/sys/kernel/osrelease") {
        Some(k) => format!("{name}, kernel {k}, {}", std::env::consts::ARCH),
        None => format!("{name}, {}", std::env::consts::ARCH),
    }
}

/// Now, UTC, as `YYYY-MM-DDTHH:MM:SSZ` ([`utc_text`]).
fn utc_now() -> String {
    utc_text(time::OffsetDateTime::now_utc())
}

/// `t` (UTC) as `YYYY-MM-DDTHH:MM:SSZ`.
fn utc_text(t: time::OffsetDateTime) -> String {
    let (date, clock) = (t.date(), t.time());
    format!(
        "{:04}-{:02}-{:02}T{:02}:{:02}:{:02}Z",
        date.year(),
        u8::from(date.month()),
        date.day(),
        clock.hour(),
        clock.minute(),
        clock.second()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_dates() {
        let at = |secs| utc_text(time::OffsetDateTime::from_unix_timestamp(secs).unwrap());
        assert_eq!(at(0), "1970-01-01T00:00:00Z");
        assert_eq!(at(19_782 * 86_400 + 3_723), "2024-02-29T01:02:03Z");
        assert_eq!(at(20_784 * 86_400 + 86_399), "2026-11-27T23:59:59Z");
    }
}
