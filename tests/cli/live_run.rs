//! No run destroys another (docs/formats.md § 1.7): a command writing into the folder of a
//! run whose process is alive on this host is refused, naming the process, and the live run
//! finishes with the bytes it writes alone.

use crate::common::{bin, calbench, calbench_ok, path_arg, read, root, tmp_dir};

#[test]
fn a_run_into_the_folder_of_a_live_run_is_refused_and_the_live_run_is_unharmed() {
    let d = tmp_dir("cli-live-run");
    let sc = root().join("scenarios/ci-guard.toml");
    let sc = path_arg(&sc);
    let (live, alone) = (d.join("live"), d.join("alone"));
    let meta = d.join(".live.checkpoint").join("checkpoint.json");
    let args = ["run", sc, "--trials", "2000", "--threads", "1", "--out"];
    let mut child = bin()
        .args(args)
        .arg(&live)
        .stderr(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while !meta.exists() {
        assert!(t0.elapsed().as_secs() < 120, "no checkpoint");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let pid = child.id().to_string();
    for second in [
        vec!["run", sc, "--trials", "2", "--out", path_arg(&live)],
        vec!["simulate", sc, "--out", path_arg(&live)],
        vec!["merge", path_arg(&d), "--out", path_arg(&live)],
    ] {
        let o = calbench(&second);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{second:?}: {err}");
        assert!(err.contains(&format!("process {pid}")), "{err}");
        assert!(err.contains("still in progress"), "{err}");
        // Forcing is offered only by a command that has `--force` (run), not by merge.
        let forcing = second[0] == "run";
        assert_eq!(err.contains("forcing passes"), forcing, "{second:?}: {err}");
    }
    // Forcing passes a number another program took, never the run itself, which holds its
    // records open: a forced run had removed its checkpoint and killed it ("No such file").
    let forced = [
        "run",
        sc,
        "--trials",
        "2",
        "--force",
        "--out",
        path_arg(&live),
    ];
    let resumed = ["run", "--resume", path_arg(&live), "--force"];
    for (second, says) in [
        (&forced[..], "forcing does not pass it"),
        (&resumed[..], "forcing does not pass it"),
    ] {
        let o = calbench(second);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{second:?}: {err}");
        assert!(
            err.contains(&format!("process {pid}")) && err.contains(says),
            "{err}"
        );
    }
    assert!(meta.exists(), "the live run's checkpoint is left");
    assert!(child.wait().unwrap().success(), "the live run finishes");
    calbench_ok(&[&args[..], &[path_arg(&alone)]].concat());
    for f in ["summary.json", "trials.csv"] {
        assert_eq!(read(&live.join(f)), read(&alone.join(f)), "{f}");
    }
    // Its writer gone, the folder takes a new run.
    calbench_ok(&["run", sc, "--trials", "2", "--out", path_arg(&live)]);
}
