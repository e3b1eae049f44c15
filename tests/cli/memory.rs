//! `calbench identify --method ls` on 2 000 000 rows peaks at most at 450 MB
//! (docs/performance.md, "Streaming identification"): the readings move into the pipeline
//! instead of being copied, and the per-point residuals are not held while the diagnostics
//! run. Measured as a user would, by GNU time's peak resident set size of the command. Minutes
//! in the test profile: run with `cargo test --test cli -- --ignored identify_peak`
//! (`scripts/test.sh` does with `CI=true`, where .ci/run installs GNU time).

use crate::common::{bin, calbench_ok, tmp_dir};

/// The bound of docs/performance.md, MB (10⁶ bytes).
const PEAK_MB: f64 = 450.0;

#[test]
#[ignore]
fn identify_peak_memory_on_two_million_rows() {
    let time = std::path::Path::new("/usr/bin/time");
    assert!(
        time.exists(),
        "GNU time (/usr/bin/time) is needed to read the peak memory: apt-get install time"
    );
    let d = tmp_dir("memory");
    let scenario = d.join("rows.toml");
    let text = "name = \"rows\"\nseed = 11\ntrials = 1\n[robot]\nbuiltin = \"irb2600\"\n\
                [errors]\nkind = \"paper\"\n[tracker]\npose = [2500.0, 300.0, 400.0, 0.0, 0.0, 170.0]\n\
                [calibration]\ncount = 2000000\nstrategies = [\"random\"]\n[validation]\ncount = 10\n\
                [[methods]]\nname = \"ls\"\n";
    std::fs::write(&scenario, text).unwrap();
    let s = scenario.to_str().unwrap();
    let rows = d.join("rows");
    calbench_ok(&[
        "simulate",
        s,
        "--trial",
        "0",
        "--out",
        rows.to_str().unwrap(),
    ]);
    let data = rows.join("measurements.csv");
    let out = d.join("id");
    let o = std::process::Command::new(time)
        .arg("-v")
        .arg(bin().get_program())
        .args(["identify", "--robot", "irb2600", "--method", "ls", "--data"])
        .arg(&data)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "identify: {err}");
    let kb: f64 = err
        .lines()
        .find_map(|l| {
            l.trim()
                .strip_prefix("Maximum resident set size (kbytes): ")
        })
        .unwrap_or_else(|| panic!("no peak in GNU time's report: {err}"))
        .parse()
        .unwrap();
    let mb = kb * 1024.0 / 1e6;
    assert!(
        mb <= PEAK_MB,
        "identify on 2 000 000 rows peaked at {mb:.0} MB, over {PEAK_MB} MB"
    );
}
