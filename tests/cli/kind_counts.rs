//! Kind files whose readings cannot fix what a fit needs, as a user meets them: too few
//! readings for the robot's parameters and the instrument's own unknowns, a plane touched at
//! one point, a sphere's radius in another unit (docs/formats.md § 8.5).

use std::path::Path;

use crate::common::{calbench, calbench_ok, path_arg, read, tmp_dir};
use crate::kinds::{identify_args, simulate};

/// Readings too few for what their instrument determines are refused before any solve,
/// saying how many poses would do: the robot parameters `identifiability` finds on poses
/// spread over the workspace and the instrument's unknowns, plus one. A plane touched at one
/// point leaves its tilt free: `identify` refuses it and `identifiability` lists the plane's
/// free unknowns.
#[test]
fn too_few_readings_and_a_free_plane_are_refused() {
    let dir = tmp_dir("cli-kinds-few");
    let sim = simulate(&dir, "s", "[[measurement]]\nkind = \"sphere\"", &[]);
    let csv = read(&sim.join("measurements.csv"));
    let lines: Vec<&str> = csv.lines().collect();
    let a = calbench_ok(&[
        "identifiability",
        "--robot",
        "irb2600",
        "--measure",
        "sphere",
        "--poses",
        "200",
        "--json",
    ]);
    let a: serde_json::Value = serde_json::from_slice(&a.stdout).unwrap();
    let unknowns =
        a["rank"].as_u64().unwrap() as usize + a["instrument_unknowns"].as_array().unwrap().len();
    let refusal = |n: usize, extra: &[&str]| {
        let data = dir.join(format!("s{n}.csv"));
        std::fs::write(&data, lines[..=n].join("\n") + "\n").unwrap();
        let out = dir.join(format!("o{n}"));
        let o = calbench(&identify_args(
            &data,
            &out,
            &[&["--method", "ls"], extra].concat(),
        ));
        (String::from_utf8_lossy(&o.stderr).into_owned(), out)
    };
    for n in [5, unknowns] {
        let (err, out) = refusal(n, &[]);
        let said = format!("{n} poses give {n} sphere readings for {unknowns} unknowns");
        let least = format!("Measure at least {} poses", unknowns + 1);
        assert!(err.contains(&said) && err.contains(&least), "{err}");
        assert!(
            err.contains("--allow-rank-deficient") && !out.exists(),
            "{err}"
        );
    }
    assert!(!refusal(unknowns + 1, &[]).0.contains("readings for"));
    assert!(!refusal(5, &["--allow-rank-deficient"])
        .0
        .contains("readings for"));

    // Every row of plane 1 at the pose of its first row.
    let sim = simulate(&dir, "p", "[[measurement]]\nkind = \"plane\"", &[]);
    let csv = read(&sim.join("measurements.csv"));
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    let first = rows.iter().position(|r| r[6] == "1").unwrap();
    let one: Vec<String> = rows
        .iter()
        .map(|r| match r[6] == "1" {
            true => [&rows[first][..6], &r[6..]].concat().join(","),
            false => r.join(","),
        })
        .collect();
    let data = dir.join("one-point.csv");
    std::fs::write(&data, one.join("\n") + "\n").unwrap();
    let out = dir.join("plane-out");
    let o = calbench(&identify_args(&data, &out, &["--method", "ls"]));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && !out.exists(), "{err}");
    assert!(
        err.contains("one-point.csv: data: the plane readings do not determine the instrument's own unknowns plane1_c")
            && err.contains("touch each plane at points spread over it"),
        "{err}"
    );
    let free = |poses: &Path| {
        let a = calbench_ok(&[
            "identifiability",
            "--robot",
            "irb2600",
            "--measure",
            "plane",
            "--poses-file",
            path_arg(poses),
            "--json",
        ]);
        let a: serde_json::Value = serde_json::from_slice(&a.stdout).unwrap();
        a["undetermined_instrument_unknowns"].clone()
    };
    let a = free(&data);
    let free_ones = a.as_array().unwrap();
    assert_eq!(free_ones.len(), 2, "{a}");
    assert!(free_ones
        .iter()
        .all(|n| n.as_str().unwrap().starts_with("plane1_")));
    let args = identify_args(&data, &out, &["--method", "ls", "--allow-rank-deficient"]);
    calbench_ok(&args);
    let all = free(&sim.join("measurements.csv"));
    assert_eq!(all, serde_json::json!([]));
}

/// A sphere file whose radius is in µm puts the first guess's sphere out of the arm's reach;
/// one in tenths of a mm leaves the solve singular where the first guess determined every
/// unknown. Each is refused naming what to check, not as poses that fail to move the joints.
#[test]
fn a_radius_in_another_unit_is_refused_as_such() {
    let dir = tmp_dir("cli-kinds-radius");
    let sim = simulate(&dir, "s", "[[measurement]]\nkind = \"sphere\"", &[]);
    let csv = read(&sim.join("measurements.csv"));
    for (factor, said) in [
        (
            1000.0,
            "the points lie far from one sphere of the file's radius 25400 mm",
        ),
        (
            100.0,
            "unknowns at the instrument's first guess (the robot's 18 parameters and the \
             instrument's 3), yet the solve's rank fell to 20; ls ended singular, so nothing \
             was written. Check the readings (a radius, length or offset in another unit, a \
             plane or sphere column that mixes surfaces, a step file's rows out of their \
             measured order, a gross reading)",
        ),
    ] {
        let mut lines = csv.lines();
        let header = lines.next().unwrap();
        let radius = header.split(',').position(|c| c == "radius_mm").unwrap();
        let mut text = format!("{header}\n");
        for l in lines {
            let mut cells: Vec<String> = l.split(',').map(String::from).collect();
            let r: f64 = cells[radius].parse().unwrap();
            cells[radius] = format!("{:.9}", r * factor);
            text += &(cells.join(",") + "\n");
        }
        let data = dir.join(format!("r{factor}.csv"));
        std::fs::write(&data, text).unwrap();
        let out = dir.join(format!("o{factor}"));
        let o = calbench(&identify_args(&data, &out, &["--method", "ls"]));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && !out.exists(), "{err}");
        assert!(
            err.contains(said) && !err.contains("move every joint"),
            "{factor}: {err}"
        );
    }
}

/// A kind file whose rows are all there twice is refused, as a tracker's is: the fit would
/// state standard errors √2 too small. A second reading of a pose, a micrometre apart, is
/// taken.
#[test]
fn repeated_kind_rows_are_refused() {
    let dir = tmp_dir("cli-kinds-twice");
    let sim = simulate(&dir, "p", "[[measurement]]\nkind = \"plane\"", &[]);
    let csv = read(&sim.join("measurements.csv"));
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.collect();
    let n = rows.len();
    let twice = dir.join("twice.csv");
    let text = format!("{header}\n{}\n{}\n", rows.join("\n"), rows.join("\n"));
    std::fs::write(&twice, text).unwrap();
    let out = dir.join("o-twice");
    let o = calbench(&identify_args(&twice, &out, &["--method", "ls"]));
    let err = String::from_utf8_lossy(&o.stderr);
    let said = format!(
        "twice.csv: data: {n} row(s) repeat an earlier row (the same joint values, plane and \
         offset; 0-based rows): row 0 = row {n}, row 1 = row {}",
        n + 1
    );
    assert!(!o.status.success() && err.contains(&said), "{err}");
    assert!(!out.exists());
    // The first row read again, its offset 1 µm on.
    let offset = header.split(',').position(|c| c == "offset_mm").unwrap();
    let mut again: Vec<String> = rows[0].split(',').map(String::from).collect();
    let v: f64 = again[offset].parse().unwrap();
    again[offset] = format!("{:.9}", v + 0.001);
    let second = dir.join("second.csv");
    let text = format!("{header}\n{}\n{}\n", rows.join("\n"), again.join(","));
    std::fs::write(&second, text).unwrap();
    let out = dir.join("o-second");
    calbench_ok(&identify_args(&second, &out, &["--method", "ls"]));
    assert!(out.join("identified.json").exists());
}

/// A socket file whose socket 2 is given 10 times its distance (500 mm for 50) is refused at
/// the line of socket 2's first row and its column, as a socket task's `sockets.distances_mm`
/// is: the rows that could not reach socket 2 there had been dropped, and the file refused as
/// "socket 2 has no pose" although it has.
#[test]
fn a_socket_distance_in_another_unit_is_refused_at_its_column() {
    let dir = tmp_dir("cli-kinds-socket-unit");
    let entry = "[[measurement]]\nkind = \"socket\"\nsockets = 2\nsocket_distance_mm = 50.0";
    let sim = simulate(&dir, "s", entry, &["--measure", "socket"]);
    let csv = read(&sim.join("measurements.csv"));
    let mut lines: Vec<String> = csv.lines().map(str::to_string).collect();
    let header: Vec<String> = lines[0].split(',').map(str::to_string).collect();
    let (s, k) = (
        header.iter().position(|c| c == "socket").unwrap(),
        header
            .iter()
            .position(|c| c == "socket_distance_mm")
            .unwrap(),
    );
    let mut first = None;
    for (i, line) in lines.iter_mut().enumerate().skip(1) {
        let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
        if cells[s] == "2" {
            first.get_or_insert(i + 1);
            cells[k] = format!("{}", cells[k].parse::<f64>().unwrap() * 10.0);
        }
        *line = cells.join(",");
    }
    let data = dir.join("tenfold.csv");
    std::fs::write(&data, lines.join("\n") + "\n").unwrap();
    let out = dir.join("out");
    let o = calbench(&identify_args(&data, &out, &["--method", "lm"]));
    let err = String::from_utf8_lossy(&o.stderr);
    let want = format!(
        "tenfold.csv: line {}, column socket_distance_mm: socket 2 is 500 mm from socket 1, \
         where the nominal robot puts the tool points of its rows ",
        first.unwrap()
    );
    assert!(
        !o.status.success() && err.contains(&want) && !out.exists(),
        "{err}"
    );
    assert!(
        err.contains("10 times nearer): are the file's distances"),
        "{err}"
    );
}
