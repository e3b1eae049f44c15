//! A solve whose rank falls short although the poses determine every parameter names what in
//! the readings likely did it (docs/formats.md § 8.5), not weights or parameters the
//! identification does not have.

use crate::common::{calbench, calbench_ok, path_arg, read, root, tmp_dir};

/// The measurements of `scenarios/ci-guard.toml`, simulated into `dir/sim`.
fn simulated(dir: &std::path::Path) -> std::path::PathBuf {
    let sim = dir.join("sim");
    let sc = root().join("scenarios/ci-guard.toml");
    calbench_ok(&["simulate", path_arg(&sc), "--out", path_arg(&sim)]);
    sim.join("measurements.csv")
}

/// The simulated file of `scenarios/ci-guard.toml` with its x and y columns swapped: `ls`
/// ends singular and is refused naming the mirror image, where it had blamed "the rows'
/// weights (the orientation weight k, the points' σ) or the parameters beside the kinematic
/// ones", which this file and identification do not have.
#[test]
fn a_rank_that_falls_short_names_the_readings_cause() {
    let d = tmp_dir("cli-rank-causes");
    let text = read(&simulated(&d));
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

/// A robot file of no length (every `a`, `d` and the tool's offset 0) puts the model's point
/// of every pose at one place. The refusal had called the measured points collinear, which
/// they are not; it now names the model's points.
#[test]
fn a_robot_of_no_length_is_named_not_the_data() {
    let d = tmp_dir("cli-rank-no-length");
    let data = simulated(&d);
    let text = read(&root().join("robots/ban-irb2600.toml"));
    let zero: String = (text.lines())
        .map(|l| match l.split_once(" = ") {
            Some(("a" | "d", _)) => format!("{} = 0.0\n", &l[..1]),
            Some(("xyz", _)) => "xyz = [0.0, 0.0, 0.0]\n".into(),
            _ => format!("{l}\n"),
        })
        .collect();
    assert!(!zero.contains("445") && zero.contains("d = 0.0"), "{zero}");
    let robot = d.join("zero.toml");
    std::fs::write(&robot, zero).unwrap();
    let out = d.join("out");
    let o = calbench(&[
        "identify",
        "--robot",
        path_arg(&robot),
        "--data",
        path_arg(&data),
        "--method",
        "ls",
        "--out",
        path_arg(&out),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && !out.exists(), "{err}");
    assert!(
        err.contains(
            "the model's points (the robot's at these joint values) are (nearly) collinear"
        ),
        "{err}"
    );
    assert!(!err.contains("measured points are"), "{err}");
}
