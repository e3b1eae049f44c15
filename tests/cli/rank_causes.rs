//! A solve whose rank falls short although the poses determine every parameter names what in
//! the readings likely did it (docs/formats.md § 8.5), not weights or parameters the
//! identification does not have.

use crate::common::{calbench, calbench_ok, path_arg, read, root, tmp_dir};

/// The simulated file of `scenarios/ci-guard.toml` with its x and y columns swapped: `ls`
/// ends singular and is refused naming the mirror image, where it had blamed "the rows'
/// weights (the orientation weight k, the points' σ) or the parameters beside the kinematic
/// ones", which this file and identification do not have.
#[test]
fn a_rank_that_falls_short_names_the_readings_cause() {
    let d = tmp_dir("cli-rank-causes");
    let sim = d.join("sim");
    let sc = root().join("scenarios/ci-guard.toml");
    calbench_ok(&["simulate", path_arg(&sc), "--out", path_arg(&sim)]);
    let text = read(&sim.join("measurements.csv"));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let (x, y) = (
        header.iter().position(|c| *c == "x").unwrap(),
        header.iter().position(|c| *c == "y").unwrap(),
    );
    let mut swapped = header.join(",") + "\n";
    for line in lines {
        let mut cells: Vec<&str> = line.split(',').collect();
        cells.swap(x, y);
        swapped += &(cells.join(",") + "\n");
    }
    let file = d.join("xy.csv");
    std::fs::write(&file, swapped).unwrap();
    let out = d.join("out");
    let args = ["identify", "--robot", "irb2600", "--data", path_arg(&file)];
    let o = calbench(&[&args[..], &["--method", "ls", "--out", path_arg(&out)]].concat());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && !out.exists(), "{err}");
    let want = "yet the solve's rank is 23 of the 24 identified: the points are a mirror image \
                of the robot's: two columns look swapped";
    assert!(err.contains(want), "{err}");
    assert!(!err.contains("weight") && !err.contains("σ"), "{err}");
}
