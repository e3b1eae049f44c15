//! Files that come from other programs and go to them: `import` reads a raw export as the
//! measurement files are read (a UTF-8 byte-order mark, CRLF line ends, quoted fields) and
//! refuses an ambiguous header or mapping; the exports escape what they write, so a robot
//! with any name goes out and comes back the same; refusals and the compare page show names
//! and numbers as they are.

use std::path::Path;

use crate::common::{calbench, calbench_ok, fk_point, path_arg, read, tmp_dir, ur10_example};

/// The shipped UR10 export as a comma-separated file with a `.` decimal mark and a text column
/// `note` (holding `note`), and the example mapping rewritten for it.
fn comma_export(dir: &Path) -> (String, String) {
    let raw = read(Path::new(&ur10_example("sample-200.csv")));
    let text: String = raw
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let cells: Vec<String> = l.split(';').map(|c| c.replace(',', ".")).collect();
            let note = if i == 0 { "note" } else { "plain" };
            format!("{},{note}\n", cells.join(","))
        })
        .collect();
    let mapping = read(Path::new(&ur10_example("mapping.toml")))
        .replace("separator = \";\"", "separator = \",\"")
        .replace("decimal = \",\"", "decimal = \".\"");
    let m = dir.join("mapping-comma.toml");
    std::fs::write(&m, mapping).unwrap();
    (text, path_arg(&m).to_string())
}

/// `calbench import RAW --mapping MAPPING --out OUT` run as a user does.
fn import(raw: &Path, mapping: &str, out: &Path) -> std::process::Output {
    calbench(&[
        "import",
        path_arg(raw),
        "--mapping",
        mapping,
        "--out",
        path_arg(out),
    ])
}

#[test]
fn import_reads_a_byte_order_mark_crlf_and_quoted_fields_as_the_plain_file() {
    let d = tmp_dir("interchange-dialect");
    let (plain, mapping) = comma_export(&d);
    let plain_raw = d.join("plain.csv");
    std::fs::write(&plain_raw, &plain).unwrap();
    // The same export as a spreadsheet writes it: a byte-order mark before the first header
    // name (a mapped joint column), CRLF line ends, a text cell holding commas and a quote,
    // and a mapped number quoted.
    let mut fancy = vec![0xEF, 0xBB, 0xBF];
    let rows: Vec<String> = plain
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                return l.to_string();
            }
            let mut cells: Vec<String> = l.split(',').map(String::from).collect();
            let last = cells.len() - 1;
            cells[last] = format!("\"pose {i}, left arm, \"\"slow\"\"\"");
            cells[14] = format!("\"{}\"", cells[14]); // measurement_x
            cells.join(",")
        })
        .collect();
    fancy.extend(rows.join("\r\n").into_bytes());
    fancy.extend(b"\r\n");
    let fancy_raw = d.join("fancy.csv");
    std::fs::write(&fancy_raw, &fancy).unwrap();
    // The first header name a joint the mapping names: a kept mark would miss it.
    let fancy = String::from_utf8(fancy).unwrap();
    let mut header = plain.lines().next().unwrap().split(',');
    let joint = header.position(|c| c == "shoulder_pan_joint").unwrap();
    // The joint's column moved first, cells and all, behind the mark.
    let swapped: Vec<String> = fancy
        .trim_start_matches('\u{feff}')
        .split("\r\n")
        .map(|l| {
            let mut cells: Vec<&str> = l.split(',').collect();
            if cells.len() > joint {
                cells.swap(0, joint);
            }
            cells.join(",")
        })
        .collect();
    let fancy_first = d.join("fancy-first.csv");
    std::fs::write(&fancy_first, format!("\u{feff}{}", swapped.join("\r\n"))).unwrap();

    // And as an old Mac program saves it, every line ended by a lone CR.
    let mac_raw = d.join("mac.csv");
    std::fs::write(&mac_raw, plain.replace('\n', "\r")).unwrap();

    let (a, b, c, m) = (
        d.join("a.csv"),
        d.join("b.csv"),
        d.join("c.csv"),
        d.join("m.csv"),
    );
    for (raw, out) in [
        (&plain_raw, &a),
        (&fancy_raw, &b),
        (&fancy_first, &c),
        (&mac_raw, &m),
    ] {
        let o = import(raw, &mapping, out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(
            String::from_utf8_lossy(&o.stdout).starts_with("199 rows of "),
            "{}",
            String::from_utf8_lossy(&o.stdout)
        );
    }
    let a = std::fs::read(&a).unwrap();
    assert_eq!(
        a,
        std::fs::read(&b).unwrap(),
        "the same rows, byte for byte"
    );
    assert_eq!(a, std::fs::read(&m).unwrap(), "CR line ends: the same rows");
    // The export with the joint's column first, its name behind the mark, gives the same rows.
    assert_eq!(
        a,
        std::fs::read(&c).unwrap(),
        "a mapped first column: the same rows"
    );
    // And the shipped semicolon export gives the same rows as its comma form.
    let semicolon = d.join("semicolon.csv");
    calbench_ok(&[
        "import",
        &ur10_example("sample-200.csv"),
        "--mapping",
        &ur10_example("mapping.toml"),
        "--out",
        path_arg(&semicolon),
    ]);
    assert_eq!(a, std::fs::read(&semicolon).unwrap());
}

#[test]
fn import_refuses_a_bad_cell_in_a_quoted_crlf_file_naming_line_and_column() {
    let d = tmp_dir("interchange-dialect-bad");
    let (plain, mapping) = comma_export(&d);
    let text: Vec<String> = plain
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let mut cells: Vec<String> = l.split(',').map(String::from).collect();
            if i == 4 {
                cells[16] = "\"1,5\"".into(); // measurement_y, quoted with a comma
            }
            cells.join(",")
        })
        .collect();
    let raw = d.join("bad.csv");
    std::fs::write(&raw, format!("\u{feff}{}\r\n", text.join("\r\n"))).unwrap();
    let out = d.join("out.csv");
    let o = import(&raw, &mapping, &out);
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        msg.contains(
            "bad.csv: line 5, column measurement_y: \"1,5\" is not a finite number with the \
             mapping's decimal = \".\" (this export writes \",\"?)"
        ),
        "{msg}"
    );
    assert!(!out.exists());
}

/// A cell below the smallest 64-bit number is refused, as a measurement file refuses it; it
/// had been written as 0.
#[test]
fn import_refuses_a_number_that_would_read_as_zero() {
    let d = tmp_dir("interchange-underflow");
    // Line 2's measurement_x (column 15).
    let raw = read(Path::new(&ur10_example("sample-200.csv")));
    let path = d.join("tiny.csv");
    std::fs::write(&path, raw.replacen(";383,97123;", ";1E-400;", 1)).unwrap();
    let out = d.join("out.csv");
    let o = import(&path, &ur10_example("mapping.toml"), &out);
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        msg.contains(
            "tiny.csv: line 2, column measurement_x: \"1E-400\" is below the smallest 64-bit \
             number (about 4.9e-324) and would read as 0"
        ),
        "{msg}"
    );
    assert!(!out.exists());
}

#[test]
fn import_refuses_a_mapped_column_named_twice_in_the_header() {
    let d = tmp_dir("interchange-repeated-header");
    let raw = read(Path::new(&ur10_example("sample-200.csv")));
    // `Goal x` (column 2) renamed `measurement_x`: the header has it twice.
    let twice = raw.replacen("Goal x;", "measurement_x;", 1);
    let path = d.join("twice.csv");
    std::fs::write(&path, twice).unwrap();
    let out = d.join("out.csv");
    let o = import(&path, &ur10_example("mapping.toml"), &out);
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        msg.contains("twice.csv: line 1, column measurement_x: column \"measurement_x\" appears twice in the header (columns 2 and 15)")
            && msg.contains("`position.columns`"),
        "{msg}"
    );
    assert!(!out.exists());
    // A repeated name the mapping does not use is no ambiguity: the two timestamps.
    let unused = raw.replacen("Goal x;", "Timestamp;", 1);
    std::fs::write(&path, unused).unwrap();
    let o = import(&path, &ur10_example("mapping.toml"), &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn import_refuses_a_mapping_that_maps_a_column_twice_or_writes_another_kind_of_unit() {
    let d = tmp_dir("interchange-mapping-twice");
    let mapping = read(Path::new(&ur10_example("mapping.toml")));
    let cases = [
        (
            "columns = [\"measurement_x\", \"measurement_y\", \"measurement_z\"]",
            "columns = [\"measurement_x\", \"measurement_x\", \"measurement_z\"]",
            "line 13, position.columns[1]: column \"measurement_x\" is mapped already by `position.columns[0]`",
        ),
        (
            "\"wrist_1_joint\", \"wrist_2_joint\"",
            "\"wrist_1_joint\", \"elbow_joint\"",
            "line 8, joints.columns[4]: column \"elbow_joint\" is mapped already by `joints.columns[2]`",
        ),
        (
            "position = [\"measurement_std_x\"",
            "position = [\"measurement_z\"",
            "line 24, sigma.position[0]: column \"measurement_z\" is mapped already by `position.columns[2]`",
        ),
        (
            "write_unit = \"deg\"",
            "write_unit = \"mm\"",
            "line 10, joints.write_unit: a length unit for joints read in an angle unit",
        ),
    ];
    for (i, (from, to, expected)) in cases.iter().enumerate() {
        let msg = refused_mapping(&d, &mapping, i, (from, to));
        assert!(msg.contains(&format!("m{i}.toml: {expected}")), "{msg}");
    }
}

/// `calbench import` of the UR10 sample through `map` with its first `from` replaced by
/// `to`, written as `m{i}.toml` in `d`: refused (exit status 1), nothing written; its stderr.
pub(crate) fn refused_mapping(d: &Path, map: &str, i: usize, (from, to): (&str, &str)) -> String {
    assert!(map.contains(from), "{from}");
    let m = d.join(format!("m{i}.toml"));
    std::fs::write(&m, map.replacen(from, to, 1)).unwrap();
    let out = d.join("out.csv");
    let o = import(
        Path::new(&ur10_example("sample-200.csv")),
        path_arg(&m),
        &out,
    );
    let msg = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{msg}");
    assert!(!out.exists(), "{msg}");
    msg
}

/// The refusal of `identify --robot ROBOT --data DATA --method lm --out OUT`: it fails, and
/// its stderr.
fn refused_lm(robot: &str, data: &Path, out: &Path) -> String {
    let o = calbench(&[
        "identify",
        "--robot",
        robot,
        "--data",
        path_arg(data),
        "--method",
        "lm",
        "--out",
        path_arg(out),
    ]);
    assert!(!o.status.success());
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_measurement_file_with_a_byte_order_mark_and_any_line_ends_names_the_right_line() {
    let d = tmp_dir("interchange-crlf-lines");
    let rows = [
        "# exported by the tracker",
        "q1,q2,q3,q4,q5,q6,x,y,z",
        "0,0,0,0,0,0,1,2,3",
        "\"1\",0,0,0,0,0,1,2,3",
        "2,0,0,0,0,0,1,2,3",
        "3,0,0,0,0,0,1,zz,3",
    ];
    // CRLF (Windows), a lone CR (old Mac programs), and the two mixed.
    let mixed = format!("{}\r{}\r\n", rows[..3].join("\r\n"), rows[3..].join("\n"));
    for (name, text) in [
        ("crlf", format!("{}\r\n", rows.join("\r\n"))),
        ("cr", format!("{}\r", rows.join("\r"))),
        ("mixed", mixed),
    ] {
        let path = d.join(format!("{name}.csv"));
        std::fs::write(&path, format!("\u{feff}{text}")).unwrap();
        let msg = refused_lm("irb2600", &path, &d.join("out"));
        assert!(
            msg.contains(&format!(
                "{name}.csv: line 6, column y: \"zz\" is not a finite number"
            )),
            "{msg}"
        );
    }
}

/// `calbench robots irb2600` under another name.
fn renamed_irb2600(dir: &Path, file: &str, name: &str) -> std::path::PathBuf {
    let o = calbench_ok(&["robots", "irb2600"]);
    let text = String::from_utf8(o.stdout).unwrap();
    let line = text.lines().find(|l| l.starts_with("name = ")).unwrap();
    let quoted = format!("{name:?}"); // a TOML basic string for these names
    let path = dir.join(file);
    std::fs::write(&path, text.replacen(line, &format!("name = {quoted}"), 1)).unwrap();
    path
}

/// `calbench simulate scenarios/ci-guard.toml` into `DIR/sim`, which it returns.
fn simulated_ci_guard(dir: &Path) -> std::path::PathBuf {
    let sim = dir.join("sim");
    calbench_ok(&[
        "simulate",
        path_arg(&crate::common::root().join("scenarios/ci-guard.toml")),
        "--out",
        path_arg(&sim),
    ]);
    sim
}

/// `calbench identify --robot ROBOT --data SIM/measurements.csv --method lm --export urdf
/// --out OUT`.
fn identify_to_urdf(robot: &Path, sim: &Path, out: &Path) {
    calbench_ok(&[
        "identify",
        "--robot",
        path_arg(robot),
        "--data",
        path_arg(&sim.join("measurements.csv")),
        "--method",
        "lm",
        "--export",
        "urdf",
        "--out",
        path_arg(out),
    ]);
}

#[test]
fn a_urdf_export_of_a_robot_with_markup_in_its_name_reads_back_as_the_same_robot() {
    let d = tmp_dir("interchange-urdf");
    let name = "R&D <arm> \"x\"";
    let robot = renamed_irb2600(&d, "rd.toml", name);
    let sim = simulated_ci_guard(&d);
    let first = d.join("first");
    identify_to_urdf(&robot, &sim, &first);
    let urdf = first.join("robot.urdf");
    let text = read(&urdf);
    assert!(
        text.contains("<robot name=\"R&amp;D &lt;arm&gt; &quot;x&quot;-calibrated\">"),
        "{text}"
    );
    // The URDF is the identified robot: the same tool point at any joint values (the URDF in
    // rad, the robot file in deg).
    for q in [
        [0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
        [-1.0, 0.5, -0.2, 2.0, -1.2, 3.0],
    ] {
        let deg: Vec<f64> = q.iter().map(|v: &f64| v.to_degrees()).collect();
        let (a, b) = (
            fk_point(&urdf, &q),
            fk_point(&first.join("robot.toml"), &deg),
        );
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-6, "{a:?} against {b:?}");
        }
    }
    // Identified again on the same data from the exported URDF: the robot read back is the
    // one identified (nothing left to correct), named as robot.toml names it.
    let measurements = read(&sim.join("measurements.csv"));
    let rad: String = measurements
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let cells: Vec<String> = l
                .split(',')
                .enumerate()
                .map(|(c, v)| match (i, c) {
                    (1.., 0..6) => format!("{:?}", v.parse::<f64>().unwrap().to_radians()),
                    _ => v.to_string(),
                })
                .collect();
            cells.join(",") + "\n"
        })
        .collect();
    std::fs::write(d.join("rad.csv"), rad).unwrap();
    let second = d.join("second");
    calbench_ok(&[
        "identify",
        "--robot",
        path_arg(&urdf),
        "--data",
        path_arg(&d.join("rad.csv")),
        "--method",
        "lm",
        "--out",
        path_arg(&second),
    ]);
    let (a, b) = (
        crate::common::load_json(&first.join("identified.json")),
        crate::common::load_json(&second.join("identified.json")),
    );
    assert_eq!(b["robot"], format!("{name}-calibrated"));
    let (ra, rb) = (
        a["rms_residual_mm"].as_f64().unwrap(),
        b["rms_residual_mm"].as_f64().unwrap(),
    );
    assert!((ra - rb).abs() < 1e-3 * ra, "{ra} then {rb}");
    // Written back from the URDF, the name is escaped again.
    let again = read(&second.join("robot.urdf"));
    assert!(
        again.contains("R&amp;D &lt;arm&gt; &quot;x&quot;"),
        "{again}"
    );
}

#[test]
fn a_hostile_robot_name_gives_no_markup_in_the_urdf() {
    let d = tmp_dir("interchange-urdf-hostile");
    let name = "x\"/><link name=\"evil\"/><joint name='j' type=\"fixed\"><!--";
    let robot = renamed_irb2600(&d, "evil.toml", name);
    let sim = simulated_ci_guard(&d);
    let out = d.join("out");
    identify_to_urdf(&robot, &sim, &out);
    let text = read(&out.join("robot.urdf"));
    assert!(
        !text.contains("evil\"/>") && !text.contains("<!--"),
        "{text}"
    );
    // world, base_link, link_1 … link_6, flange, tcp.
    assert_eq!(text.matches("<link ").count(), 10, "{text}");
    assert_eq!(text.matches("<robot ").count(), 1, "{text}");
    let back = calbench::robot::urdf::UrdfRobot::load(&out.join("robot.urdf")).unwrap();
    assert_eq!(back.robot.name, format!("{name}-calibrated"));
}

#[test]
fn the_compare_page_shows_a_scenario_name_as_it_is() {
    let d = tmp_dir("interchange-compare");
    let guard = read(&crate::common::root().join("scenarios/ci-guard.toml"));
    let run = |file: &str, name: &str| {
        let text = guard.replacen("name = \"ci-guard\"", &format!("name = {name:?}"), 1);
        let scenario = d.join(file);
        std::fs::write(&scenario, text).unwrap();
        let out = d.join(file.trim_end_matches(".toml"));
        calbench_ok(&[
            "run",
            path_arg(&scenario),
            "--trials",
            "1",
            "--out",
            path_arg(&out),
        ]);
        out
    };
    let a = run("a.toml", "R&D <b>\"quoted\"");
    let b = run("b.toml", "plain");
    let out = d.join("cmp");
    calbench_ok(&[
        "compare",
        path_arg(&a),
        path_arg(&b),
        "--out",
        path_arg(&out),
    ]);
    // Markdown shows the name as it is: its `<` and `>` escaped, so that `<b>` is no tag.
    let md = read(&out.join("compare.md"));
    assert!(
        md.contains("(scenario R&D \\<b\\>\"quoted\", 1 trials, seed 42)"),
        "{md}"
    );
    assert!(
        md.contains("A is a run of scenario \"R&D \\<b\\>\"quoted\"\" and B of scenario \"plain\""),
        "{md}"
    );
    let html = read(&out.join("compare.html"));
    assert!(
        html.contains("scenario R&amp;D &lt;b&gt;&quot;quoted&quot;, 1 trials"),
        "{html}"
    );
    assert!(!html.contains('\\') && !html.contains("<b>"), "{html}");
}

#[test]
fn a_huge_number_in_a_refusal_is_written_in_exponent_form() {
    let d = tmp_dir("interchange-huge");
    let h = "q1,q2,q3,q4,q5,q6,x,y,z,sigma_mm\n";
    let ok = "0,0,0,0,0,0,1,2,3,0.01\n1,0,0,0,0,0,1,2,3,0.01\n";
    for (row, expected) in [
        (
            "1e300,0,0,0,0,0,1,2,3,0.01",
            "line 4, column q1: 1e300 is outside the joint limits [-180, 180]",
        ),
        (
            "2,0,0,0,0,0,1,2,3,-1e300",
            "line 4, column sigma_mm: -1e300 is not a positive standard deviation",
        ),
        (
            "2,0,0,0,0,0,1,2,3,-0.000000001",
            "line 4, column sigma_mm: -1e-9 is not a positive standard deviation",
        ),
        (
            "2,0,0,0,0,0,1,2,3,1e-12",
            "line 4, column sigma_mm: 1e-12 mm is out of range: a standard deviation must be \
             within [1e-9, 1000000] mm",
        ),
        (
            "-90.5,0,0,0,0,0,1,2,3,0.01",
            "line 4, column q1: -90.5 is outside the joint limits [-90, 90]",
        ),
    ] {
        let path = d.join("huge.csv");
        std::fs::write(&path, format!("{h}{ok}{row}\n")).unwrap();
        let robot = if row.starts_with("-90.5") {
            let text = String::from_utf8(calbench_ok(&["robots", "irb2600"]).stdout).unwrap();
            let narrow = d.join("narrow.toml");
            std::fs::write(
                &narrow,
                text.replacen("limits = [-180.0, 180.0]", "limits = [-90.0, 90.0]", 1),
            )
            .unwrap();
            path_arg(&narrow).to_string()
        } else {
            "irb2600".to_string()
        };
        let msg = refused_lm(&robot, &path, &d.join("out"));
        assert!(msg.contains(expected), "{msg}");
        assert!(msg.len() < 300, "{msg}");
    }
}

#[test]
fn import_reads_an_export_with_latin_1_bytes_in_an_unmapped_column() {
    let d = tmp_dir("interchange-latin1");
    let (plain, mapping) = comma_export(&d);
    let plain_raw = d.join("plain.csv");
    std::fs::write(&plain_raw, &plain).unwrap();
    // `note` renamed `t °C` in Latin-1 (0xB0), which is not UTF-8.
    let mut latin = plain.replacen(",note\n", ",t \u{1}C\n", 1).into_bytes();
    let at = latin.iter().position(|&b| b == 1).unwrap();
    latin[at] = 0xB0;
    let latin_raw = d.join("latin.csv");
    std::fs::write(&latin_raw, &latin).unwrap();
    let (a, b) = (d.join("a.csv"), d.join("b.csv"));
    for (raw, out) in [(&plain_raw, &a), (&latin_raw, &b)] {
        let o = import(raw, &mapping, out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

/// A cell that is a finite number in the export but not in the measurement CSV written from
/// it — a joint value that overflows on its conversion from rad to deg or that no robot's
/// joint reaches, an orientation angle beyond a turn, a point beyond 1 km, a
/// standard deviation below 1e-9 mm (written as 0) — is refused naming the export, the line
/// and the column, as the measurement CSV would be, and nothing is written (no `inf` cell).
#[test]
fn import_refuses_a_value_the_measurement_csv_would_refuse() {
    let d = tmp_dir("interchange-import-range");
    let (plain, mapping) = comma_export(&d);
    for (column, at, value, expected) in [
        (
            7,
            "shoulder_pan_joint",
            "1e308",
            "1e308 overflows: it is inf",
        ),
        // Finite, but beyond what any robot's joint takes; an orientation beyond a turn,
        // whose quaternion had been written from the sine of 1e300.
        (
            7,
            "shoulder_pan_joint",
            "1e306",
            "1e306 is beyond ±1000000, which no robot's joint reaches",
        ),
        (20, "measurement_rx", "1e300", "1e300 is beyond one turn"),
        (14, "measurement_x", "-2e6", "-2000000 mm is out of range"),
        (
            15,
            "measurement_std_x",
            "1e-300",
            "1e-300 mm is out of range",
        ),
    ] {
        let text: Vec<String> = plain
            .lines()
            .enumerate()
            .map(|(i, l)| {
                let mut cells: Vec<String> = l.split(',').map(String::from).collect();
                if i == 3 {
                    cells[column] = value.into();
                }
                cells.join(",")
            })
            .collect();
        let raw = d.join("range.csv");
        std::fs::write(&raw, text.join("\n")).unwrap();
        let out = d.join("out.csv");
        let o = import(&raw, &mapping, &out);
        let msg = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{msg}");
        assert!(
            msg.contains(&format!("range.csv: line 4, column {at}: {expected}")),
            "{msg}"
        );
        assert!(!out.exists());
    }
}

/// A mapping's separator or decimal mark that is a control character is shown escaped in its
/// refusal (`"\n"`), as a cell of a measurement file is; the line break went raw into the
/// message, splitting it over two lines.
#[test]
fn a_control_character_in_a_mapping_is_shown_escaped() {
    let dir = tmp_dir("cli-mapping-escaped");
    let mapping = read(Path::new(&ur10_example("mapping.toml")));
    let raw = ur10_example("sample-200.csv");
    for (given, to, said) in [
        (
            "separator = \";\"",
            "separator = \"\\n\"",
            "line 3, separator: \"\\n\": an ASCII character other than the quote, a line break",
        ),
        (
            "decimal = \",\"",
            "decimal = \"\\t\"",
            "line 4, decimal: \"\\t\": \".\" or \",\", and not the separator",
        ),
    ] {
        assert!(mapping.contains(given), "{given}");
        let m = dir.join("mapping.toml");
        std::fs::write(&m, mapping.replacen(given, to, 1)).unwrap();
        let out = dir.join("out.csv");
        let o = import(Path::new(&raw), path_arg(&m), &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(said), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(!out.exists());
    }
}
