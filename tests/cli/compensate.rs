//! `calbench compensate` on robots its other tests do not use, run as a user runs it
//! (docs/formats.md § 2.8): an arm of five joints reaches each row's position, checked by
//! `calbench fk` of both robots; another robot given as the identified one is refused.

use std::path::Path;

use crate::common::{
    calbench, calbench_ok, import_ur10_sample, path_arg, read, refused, root, tmp_dir, ur10_example,
};

/// A five-joint arm (DH, mm, deg), `a2` of its second joint and θ of its third as given.
pub(crate) fn arm5(a2: f64, theta3: f64) -> String {
    let joint = |alpha: f64, a: f64, d: f64, theta: f64, limit: f64| {
        format!(
            "[[joints]]\ntype = \"revolute\"\nalpha = {alpha:?}\na = {a:?}\nd = {d:?}\n\
             theta = {theta:?}\nlimits = [{:?}, {limit:?}]\n\n",
            -limit
        )
    };
    format!(
        "name = \"arm5\"\nconvention = \"dh\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n\n\
         {}{}{}{}{}[tool]\nxyz = [0.0, 0.0, 80.0]\nrpy = [0.0, 0.0, 0.0]\n",
        joint(-90.0, 50.0, 300.0, 0.0, 170.0),
        joint(0.0, a2, 0.0, -90.0, 100.0),
        joint(0.0, 350.0, 0.0, theta3, 120.0),
        joint(-90.0, 0.0, 0.0, 90.0, 120.0),
        joint(0.0, 0.0, 120.0, 0.0, 180.0),
    )
}

/// A `[[joints]]` entry of a robot file (mm, deg).
fn joint(kind: &str, alpha: f64, a: f64, d: f64, theta: f64, (lo, hi): (f64, f64)) -> String {
    format!(
        "[[joints]]\ntype = \"{kind}\"\nalpha = {alpha:?}\na = {a:?}\nd = {d:?}\n\
         theta = {theta:?}\nlimits = [{lo:?}, {hi:?}]\n\n"
    )
}

/// The tool position `calbench fk` prints for `robot` at the joints `q` (a CSV row).
fn position(robot: &Path, q: &str) -> Vec<f64> {
    let o = calbench_ok(&["fk", "--robot", path_arg(robot), "--q", q]);
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix("position (mm): "))
        .unwrap_or_else(|| panic!("{text}"));
    line.split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect()
}

/// How far (mm) the tool point of `identified` at the joints `q` is from that of `nominal`
/// at `row` (CSV rows), by `calbench fk` of each.
fn miss_mm((nominal, row): (&Path, &str), (identified, q): (&Path, &str)) -> f64 {
    let (want, got) = (position(nominal, row), position(identified, q));
    (want.iter().zip(&got))
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// `calbench compensate` of the program `rows` (joint values, the nominal robot's units) for
/// the robots `nominal` and `identified`, in `dir`: the corrected program's text.
pub(crate) fn compensate_rows(
    dir: &Path,
    nominal: &Path,
    identified: &Path,
    rows: &[&str],
) -> String {
    let n = rows[0].split(',').count();
    let header: Vec<String> = (1..=n).map(|j| format!("q{j}")).collect();
    let program = dir.join("program.csv");
    std::fs::write(
        &program,
        format!("{}\n{}\n", header.join(","), rows.join("\n")),
    )
    .unwrap();
    let out = dir.join("corrected.csv");
    calbench_ok(&[
        "compensate",
        "--robot",
        path_arg(nominal),
        "--identified",
        path_arg(identified),
        "--joints",
        path_arg(&program),
        "--out",
        path_arg(&out),
    ]);
    read(&out)
}

/// Five joints cannot take the whole pose a changed model asks for: the corrected commands
/// put the identified arm's tool point where the nominal arm's was (every row `ok`), where
/// solving for the whole pose had left each row `failed`, millimetres off.
#[test]
fn an_arm_of_five_joints_reaches_each_row_s_position() {
    let d = tmp_dir("cli-compensate-arm5");
    let (nominal, identified) = (d.join("arm5.toml"), d.join("arm5-id.toml"));
    std::fs::write(&nominal, arm5(400.0, 0.0)).unwrap();
    std::fs::write(&identified, arm5(400.8, 0.3)).unwrap();
    let rows = [
        "10.0,20.0,-30.0,40.0,50.0",
        "-60.0,-45.0,15.0,-80.0,120.0",
        "120.0,70.0,-100.0,20.0,-170.0",
    ];
    let text = compensate_rows(&d, &nominal, &identified, &rows);
    let written: Vec<&str> = text.lines().skip(1).collect();
    assert_eq!(written.len(), rows.len(), "{text}");
    for (row, line) in rows.iter().zip(written) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[7], "ok", "{line}");
        let q = cells[..5].join(",");
        let miss = miss_mm((&nominal, row), (&identified, &q));
        // fk prints its positions to 1e-4 mm; the arm moved by about 0.8 mm.
        assert!(miss < 2e-4, "{row} -> {q}: {miss} mm");
        assert!(
            position(&nominal, &q) != position(&nominal, row),
            "{row}: the command did not change"
        );
    }
}

/// A five-joint MD-H arm with a sliding fourth joint (mm, limits [0, 300]): each row is
/// corrected near its commands, within the limits. Solved for the position from the joints
/// closest to the whole pose alone, 14 of these 20 rows had been sent to another branch
/// (the slide to 1401 mm, joints moved by up to 1740 deg or mm) and flagged `limits`, where a
/// position solve from the row's commands moves no joint by more than about 2 (deg or mm).
#[test]
fn a_five_joint_arm_with_a_slide_is_corrected_near_each_row() {
    let d = tmp_dir("cli-compensate-slide");
    // The nominal arm, and a calibration of it: every length and angle moved a little.
    let arm = |e: f64| {
        format!(
            "name = \"slide5\"\nconvention = \"mdh\"\nlength_unit = \"mm\"\n\
             angle_unit = \"deg\"\n\n{}{}{}{}{}[base]\nxyz = [100.0, -50.0, 20.0]\n\
             rpy = [0.0, 0.0, 30.0]\n[tool]\nxyz = [{:?}, {:?}, {:?}]\nrpy = [20.0, 0.0, 90.0]\n",
            joint("revolute", 0.0, 0.0, 400.0 + 0.3 * e, 0.0, (-170.0, 170.0)),
            joint(
                "revolute",
                -90.0,
                150.0 - 0.2 * e,
                0.0,
                -90.0 + 0.15 * e,
                (-90.0, 150.0)
            ),
            joint(
                "revolute",
                0.12 * e,
                600.0 + 0.4 * e,
                0.0,
                0.0,
                (-170.0, 80.0)
            ),
            joint("prismatic", -90.0, 120.0 + 0.25 * e, 0.0, 0.0, (0.0, 300.0)),
            joint("revolute", 90.0 - 0.1 * e, 0.0, 0.0, 0.0, (-120.0, 120.0)),
            0.2 * e,
            -0.1 * e,
            150.0 + 0.3 * e,
        )
    };
    let (nominal, identified) = (d.join("slide5.toml"), d.join("slide5-id.toml"));
    std::fs::write(&nominal, arm(0.0)).unwrap();
    std::fs::write(&identified, arm(1.0)).unwrap();
    // Rows drawn once within the limits, on which the branch jumps were found.
    let rows = [
        "138.708431905,-1.722512593,26.075373719,220.666483659,-21.735545866",
        "-150.708201987,62.719599720,-11.747164649,86.430755152,-82.910263082",
        "-87.999387227,6.593734695,-83.091046044,257.353172822,60.609573166",
        "114.704113602,-83.507012110,-16.055534093,258.638637158,76.511117673",
        "-111.911247815,61.694007808,-47.326384008,263.151929040,-38.090459403",
        "-102.299852454,-39.043759023,-93.827618519,166.924359855,-64.057943773",
        "-69.825735153,-77.891627328,-85.894913322,192.925510009,-38.466534921",
        "124.086548960,-29.788902638,-96.885845622,277.609512140,23.702492375",
        "80.541698072,-55.190724325,-69.724377485,194.553682987,60.682858395",
        "147.661245080,103.339466826,19.951119030,152.633430967,13.312941332",
        "53.302544081,-61.333291408,-71.381240100,189.295144630,51.598512967",
        "-10.991874804,-53.285560419,-156.827807772,56.470310160,-29.790402268",
        "-104.930845240,-49.351639923,47.302265858,54.605230018,-76.398062337",
        "-61.818757751,-25.944696777,-45.291776469,292.928676056,53.784712023",
        "150.611615574,93.348613762,-159.521131153,31.034219982,-46.107686985",
        "-67.949646329,43.838574110,72.892942505,53.306770256,48.945488600",
        "-84.412970257,-46.877295218,40.906385813,188.889393363,37.727666087",
        "142.564581323,21.853806775,-126.568870506,98.267701547,71.690772840",
        "-101.951360175,-47.991260708,-143.568832302,198.696381953,26.850878660",
        "-69.228630314,-45.929335996,37.246332866,121.705322507,61.087357526",
    ];
    let text = compensate_rows(&d, &nominal, &identified, &rows);
    let written: Vec<&str> = text.lines().skip(1).collect();
    assert_eq!(written.len(), rows.len(), "{text}");
    let values =
        |l: &str| -> Vec<f64> { l.split(',').take(5).map(|v| v.parse().unwrap()).collect() };
    for (i, (row, line)) in rows.iter().zip(written).enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[7], "ok", "{row} -> {line}");
        let moved = (values(row).iter().zip(values(line)))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(moved < 3.0, "{row} -> {line}: a joint moved by {moved}");
        // The tool point, by `calbench fk` of both robots (every fifth row: a process each).
        if i % 5 == 0 {
            let q = cells[..5].join(",");
            let miss = miss_mm((&nominal, row), (&identified, &q));
            assert!(miss < 2e-4, "{row} -> {q}: {miss} mm");
        }
    }
}

/// A SCARA (R R P R, all axes vertical) whose calibration tilts its axes a little cannot
/// take every yaw exactly: each row's position is reached, and its yaw as nearly as the
/// joints allow. The rows' residuals had been up to 1.6° where 0.33° was reachable: the
/// solution nearer the yaw was dropped for sliding joint 3 a micrometre further.
#[test]
fn a_scara_keeps_the_yaw_nearer_for_a_micrometre_of_slide() {
    let d = tmp_dir("cli-compensate-scara");
    // The nominal arm (`e` = 0) and a calibration of it (`e` = 1).
    let arm = |e: f64| {
        format!(
            "name = \"scara\"\nconvention = \"dh\"\nlength_unit = \"mm\"\n\
             angle_unit = \"deg\"\n\n{}{}{}{}[base]\nxyz = [{:?}, {:?}, {:?}]\n\
             rpy = [{:?}, {:?}, {:?}]\n[tool]\nxyz = [{:?}, 0.0, 40.0]\nrpy = [0.0, 0.0, 0.0]\n",
            joint(
                "revolute",
                0.176 * e,
                300.0 - 0.04 * e,
                400.0,
                0.0,
                (-150.0, 150.0)
            ),
            joint(
                "revolute",
                180.0 - 0.054 * e,
                250.0 - 0.23 * e,
                0.0,
                -0.123 * e,
                (-145.0, 145.0)
            ),
            joint("prismatic", -0.071 * e, 0.0, 50.0, 0.0, (0.0, 180.0)),
            joint("revolute", 0.0, 0.0, 20.0, 0.055 * e, (-360.0, 360.0)),
            -0.26 * e,
            -0.39 * e,
            -0.035 * e,
            -0.035 * e,
            0.022 * e,
            0.028 * e,
            30.0 - 1.08 * e,
        )
    };
    let (nominal, identified) = (d.join("scara.toml"), d.join("scara-id.toml"));
    std::fs::write(&nominal, arm(0.0)).unwrap();
    std::fs::write(&identified, arm(1.0)).unwrap();
    let rows = [
        "-73.370,11.942,69.193,62.352",
        "35.202,-117.307,12.107,202.481",
        "-67.381,-71.731,169.303,-17.842",
        "94.209,-6.385,112.251,-209.630",
        "37.761,99.372,93.709,144.751",
        "47.995,-117.712,131.317,54.660",
        "-55.645,-126.627,148.484,-16.351",
        "61.271,102.279,124.261,252.659",
        "-29.410,81.245,81.139,261.352",
        "106.083,-108.687,31.755,-169.808",
        "130.334,-17.236,110.264,-119.384",
        "2.028,-30.816,66.146,51.044",
    ];
    let text = compensate_rows(&d, &nominal, &identified, &rows);
    let written: Vec<&str> = text.lines().skip(1).collect();
    assert_eq!(written.len(), rows.len(), "{text}");
    for (row, line) in rows.iter().zip(&written) {
        let cells: Vec<&str> = line.split(',').collect();
        let (mm, deg): (f64, f64) = (cells[4].parse().unwrap(), cells[5].parse().unwrap());
        assert!(cells[6] == "ok" && mm < 1e-6, "{row} -> {line}");
        assert!(deg < 0.5, "{row} -> {line}: the yaw is {deg}° off");
    }
    // The first row's position, by `calbench fk` of both robots.
    let q = written[0].split(',').take(4).collect::<Vec<_>>().join(",");
    let miss = miss_mm((&nominal, rows[0]), (&identified, &q));
    assert!(miss < 2e-4, "{q}: {miss} mm");
}

/// Another robot given as the identified one (a built-in robot's name for the result) is
/// refused naming `--identified` and the moves, and nothing is written; under
/// `--allow-implausible` the program is corrected with a warning.
#[test]
fn another_robot_is_no_calibration_of_the_nominal_one() {
    let d = tmp_dir("cli-compensate-other");
    let nominal = d.join("arm5.toml");
    std::fs::write(&nominal, arm5(400.0, 0.0)).unwrap();
    let other = d.join("other.toml");
    std::fs::write(&other, arm5(700.0, 0.0)).unwrap();
    std::fs::write(d.join("program.csv"), "q1,q2,q3,q4,q5\n10,20,-30,40,50\n").unwrap();
    let (program, out) = (d.join("program.csv"), d.join("corrected.csv"));
    let args = [
        "compensate",
        "--robot",
        path_arg(&nominal),
        "--identified",
        path_arg(&other),
        "--joints",
        path_arg(&program),
        "--out",
        path_arg(&out),
    ];
    let msg = refused(
        &calbench(&args),
        &[
            "--identified",
            "cannot be a calibration of the nominal robot",
        ],
    );
    assert!(msg.contains("a2 moved by 300.000 mm"), "{msg}");
    assert!(!out.exists());
    let o = calbench_ok(&[&args[..], &["--allow-implausible"]].concat());
    assert!(String::from_utf8_lossy(&o.stderr).contains("warning: "));
    assert!(out.exists());
}

/// A URDF whose parallel axes 2 and 3 a calibration tilted by a hair is read with the common
/// normal of that link along z₁ × z₂, which turns over with the tilt's sign: the same robot
/// read as θ2 and θ3 moved by π and a2 by twice its length. Either sign is a calibration of
/// the nominal URDF, and the program is corrected (every row `ok`); an 11° tilt is not one.
#[test]
fn a_urdf_whose_parallel_axes_a_calibration_tilted_either_way_is_a_calibration() {
    let d = tmp_dir("cli-compensate-tilted-urdf");
    let nominal = root().join("examples/ipa-ur10/ur10.urdf");
    let text = read(&nominal);
    let elbow = "<origin xyz=\"-0.612 0.0 0.0\" rpy=\"0.0 0.0 0.0\"/>";
    assert_eq!(text.matches(elbow).count(), 1);
    let rows = ["-0.9,-0.05,-1.9,-1.2,-2.1,0.0", "0.4,-1.2,1.1,-0.7,1.3,0.5"];
    // The nominal URDF with the elbow's frame turned by `tilt` rad about x.
    let tilted = |tilt: &str| {
        let path = d.join(format!("tilted{tilt}.urdf"));
        let origin = format!("<origin xyz=\"-0.612 0.0 0.0\" rpy=\"{tilt} 0.0 0.0\"/>");
        std::fs::write(&path, text.replace(elbow, &origin)).unwrap();
        path
    };
    for tilt in ["0.0003", "-0.0003"] {
        let corrected = compensate_rows(&d, &nominal, &tilted(tilt), &rows);
        let flags: Vec<&str> = corrected
            .lines()
            .skip(1)
            .map(|l| l.rsplit(',').next().unwrap())
            .collect();
        assert_eq!(flags, ["ok", "ok"], "{tilt}: {corrected}");
    }
    let program = d.join("program.csv");
    std::fs::write(&program, format!("q1,q2,q3,q4,q5,q6\n{}\n", rows[0])).unwrap();
    let o = calbench(&[
        "compensate",
        "--robot",
        path_arg(&nominal),
        "--identified",
        path_arg(&tilted("0.2")),
        "--joints",
        path_arg(&program),
        "--out",
        path_arg(&d.join("o.csv")),
    ]);
    let msg = refused(&o, &["cannot be a calibration of the nominal robot"]);
    assert!(msg.contains("alpha2 moved by"), "{msg}");
    assert!(!msg.contains("theta2 moved"), "{msg}");
}

/// Standard and modified DH name other quantities alike (`a1`, `alpha1`), so robots of the
/// two conventions are compared by their tool points: the built-in IRB 2600 in modified DH is
/// a calibration of the one in standard DH (every row `ok`), and the standard table relabelled
/// `mdh`, a robot whose tool is metres away, is refused naming that. Compared by name, the
/// first had been refused (`alpha4 moved by 3.1416 rad`) and the second accepted.
#[test]
fn robots_of_standard_and_modified_dh_are_compared_by_their_tool_points() {
    let d = tmp_dir("cli-compensate-conventions");
    let rows = ["10,-20,30,-40,50,-60", "-5,15,-25,35,-45,55"];
    let corrected = compensate_rows(&d, Path::new("irb2600"), Path::new("irb2600-mdh"), &rows);
    let flags: Vec<&str> = corrected
        .lines()
        .skip(1)
        .map(|l| l.rsplit(',').next().unwrap())
        .collect();
    assert_eq!(flags, ["ok", "ok"], "{corrected}");
    let dh = String::from_utf8(calbench_ok(&["robots", "irb2600"]).stdout).unwrap();
    assert_eq!(dh.matches("convention = \"dh\"").count(), 1);
    let relabelled = d.join("relabelled.toml");
    std::fs::write(
        &relabelled,
        dh.replace("convention = \"dh\"", "convention = \"mdh\""),
    )
    .unwrap();
    let out = d.join("o.csv");
    let o = calbench(&[
        "compensate",
        "--robot",
        "irb2600",
        "--identified",
        path_arg(&relabelled),
        "--joints",
        path_arg(&d.join("program.csv")),
        "--out",
        path_arg(&out),
    ]);
    refused(
        &o,
        &[
            "--identified",
            "cannot be a calibration of the nominal robot: its tool point is",
            "the robots' conventions, mdh and dh",
        ],
    );
    assert!(!out.exists());
}

/// A KUKA KR 16 (standard DH, a textbook table) whose program is corrected with the built-in
/// IRB 2600 in modified DH: another arm of much the same size, its tool point 872 mm from the
/// KR 16's at a pose. Within half the reach (the bound of a base's move, 1217 mm) it had been
/// taken for a calibration and every row rewritten, joints by up to 345°; a tool point is now
/// compared against a link's length bound (49 mm), and it is refused. The same arm written
/// otherwise, examples/ipa-ur10's ur10.toml and ur10.urdf (θ1 and θ6 by 180° and d6 apart,
/// their tool points together to 1e-12 mm), had been refused by those parameters; every row of
/// a program is `ok`, its commands unchanged.
#[test]
fn another_arm_is_refused_and_the_same_arm_written_otherwise_is_not() {
    let d = tmp_dir("cli-compensate-other-arm");
    let joint = |alpha: f64, a: f64, dd: f64, theta: f64, lim: f64| {
        format!(
            "[[joints]]\ntype = \"revolute\"\nalpha = {alpha:?}\na = {a:?}\nd = {dd:?}\n\
             theta = {theta:?}\nlimits = [{:?}, {lim:?}]\n\n",
            -lim
        )
    };
    let kr16 = format!(
        "name = \"kr16\"\nconvention = \"dh\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n\n\
         {}{}{}{}{}{}",
        joint(-90.0, 260.0, 675.0, 0.0, 185.0),
        joint(0.0, 680.0, 0.0, -90.0, 155.0),
        joint(90.0, -35.0, 0.0, 0.0, 130.0),
        joint(-90.0, 0.0, -670.0, 0.0, 350.0),
        joint(90.0, 0.0, 0.0, 0.0, 130.0),
        joint(180.0, 0.0, -115.0, 0.0, 350.0),
    );
    std::fs::write(d.join("kr16.toml"), kr16).unwrap();
    let program = d.join("program.csv");
    std::fs::write(
        &program,
        "q1,q2,q3,q4,q5,q6\n-61.3,11.3,57.3,-168.5,-45.8,-40.9\n15.7,-48.4,54.1,120.6,-7.9,1.9\n",
    )
    .unwrap();
    let out = d.join("o.csv");
    let o = calbench(&[
        "compensate",
        "--robot",
        path_arg(&d.join("kr16.toml")),
        "--identified",
        "irb2600-mdh",
        "--joints",
        path_arg(&program),
        "--out",
        path_arg(&out),
    ]);
    let msg = refused(
        &o,
        &[
            "--identified",
            "cannot be a calibration of the nominal robot: its tool point is",
            "(bound 49 mm: the larger of 2 % of the robot's reach",
            "the robots' conventions, mdh and dh",
        ],
    );
    assert!(!out.exists(), "{msg}");
    let ur10 = root().join("examples/ipa-ur10");
    let rows = ["10,-80,60,-20,45,30", "-30,-100,90,10,-60,120"];
    let corrected = compensate_rows(&d, &ur10.join("ur10.toml"), &ur10.join("ur10.urdf"), &rows);
    for (line, row) in corrected.lines().skip(1).zip(rows) {
        assert!(line.ends_with(",ok"), "{corrected}");
        let q: Vec<f64> = line
            .split(',')
            .take(6)
            .map(|v| v.parse().unwrap())
            .collect();
        let given: Vec<f64> = row.split(',').map(|v| v.parse().unwrap()).collect();
        for (a, b) in q.iter().zip(&given) {
            assert!((a - b).abs() < 1e-9, "{corrected}");
        }
    }
}

/// A UR10 identified from the shipped rows as docs/formats.md § 2.8 does, and a program
/// whose rows stand a degree inside the ±360° limits of joints 1 and 6, where the
/// corrections (+1.04° on joint 1, −0.99° on joint 6) take them past the limits: each row's
/// solution nearest its command is written and flagged `limits`. They had been turned by a
/// whole turn into the limits (q1 −359.96, q6 −0.94) and flagged `ok`, a move of 719° and
/// 359° on the arm. A row well inside the limits is corrected by about a degree and `ok`.
#[test]
fn a_correction_past_a_limit_is_flagged_not_turned_into_the_limits() {
    let d = tmp_dir("cli-compensate-past-limit");
    let data = d.join("ur10.csv");
    import_ur10_sample(&ur10_example("mapping.toml"), &data);
    let (robot, out) = (ur10_example("ur10.toml"), d.join("ur10-id"));
    calbench_ok(&[
        "identify",
        "--robot",
        &robot,
        "--data",
        path_arg(&data),
        "--method",
        "lm",
        "--out",
        path_arg(&out),
    ]);
    let rows = [
        "359,-80,80,-90,90,0",
        "0,-80,80,-90,90,-359.95",
        "10,-80,80,-90,90,30",
    ];
    let text = compensate_rows(&d, Path::new(&robot), &out.join("robot.toml"), &rows);
    let written: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(written.len(), rows.len(), "{text}");
    let flags: Vec<&str> = written.iter().map(|c| c[8]).collect();
    assert_eq!(flags, ["limits", "limits", "ok"], "{text}");
    for (row, cells) in rows.iter().zip(&written) {
        let given: Vec<f64> = row.split(',').map(|v| v.parse().unwrap()).collect();
        let q: Vec<f64> = cells[..6].iter().map(|v| v.parse().unwrap()).collect();
        // Every joint within a few degrees of the row's: no whole turn.
        for (a, b) in q.iter().zip(&given) {
            assert!((a - b).abs() < 3.0, "{row}: {text}");
        }
        // Reached: the flag judges the limits, not the residuals.
        let residual: f64 = cells[6].parse().unwrap();
        assert!(residual < 1e-6, "{row}: {text}");
    }
    assert!(written[0][0].parse::<f64>().unwrap() > 360.0, "{text}");
    assert!(written[1][5].parse::<f64>().unwrap() < -360.0, "{text}");
}

/// An empty program or target list says the header it lacks: a program's joints, a target
/// list's point (both had asked for `q1,…,qn,x,y,z`, columns neither needs).
#[test]
fn an_empty_program_or_target_list_names_the_header_it_needs() {
    let d = tmp_dir("cli-compensate-empty");
    let empty = d.join("empty.csv");
    std::fs::write(&empty, "").unwrap();
    for (flag, header) in [("--joints", "q1,…,qn"), ("--targets", "x,y,z")] {
        let o = calbench(&[
            "compensate",
            "--robot",
            "irb2600",
            "--identified",
            "irb2600",
            flag,
            path_arg(&empty),
            "--out",
            path_arg(&d.join("out.csv")),
        ]);
        let want = format!("empty.csv: line 1: empty file: expected a header row {header}");
        let err = refused(&o, &[&want]);
        assert!(!err.contains(&format!("{header},")), "{err}");
    }
}

/// A program in radians for the IRB2600, which takes degrees, is refused by `compensate` and
/// by `identifiability --poses-file`, naming the file: read as degrees it is poses a few
/// degrees from zero, which `compensate` had corrected onto other arm configurations (joint
/// moves of 170°, each flagged `ok`). The same program in degrees is taken, and so is a
/// program of the zero pose alone.
#[test]
fn a_program_in_radians_for_a_robot_in_degrees_is_refused_naming_the_file() {
    let d = tmp_dir("cli-compensate-radians");
    let degrees = [
        [10.0, 20.0, -30.0, 40.0, 50.0, -60.0],
        [-35.0, 5.0, 15.0, -80.0, 30.0, 90.0],
        [60.0, -25.0, 40.0, 10.0, -45.0, 120.0],
        [120.0, 35.0, -10.0, -150.0, 70.0, -20.0],
    ];
    let write = |name: &str, rows: Vec<Vec<f64>>| {
        let text: String = rows
            .iter()
            .map(|q| {
                q.iter()
                    .map(|v| format!("{v:.9}"))
                    .collect::<Vec<_>>()
                    .join(",")
                    + "\n"
            })
            .collect();
        let path = d.join(name);
        std::fs::write(&path, format!("q1,q2,q3,q4,q5,q6\n{text}")).unwrap();
        path
    };
    let deg = write("deg.csv", degrees.iter().map(|q| q.to_vec()).collect());
    let rad = write(
        "rad.csv",
        degrees
            .iter()
            .map(|q| q.iter().map(|v| v.to_radians()).collect())
            .collect(),
    );
    let zero = write("zero.csv", vec![vec![0.0; 6]]);
    let compensate = |program: &Path, out: &Path| {
        let args = [
            "compensate",
            "--robot",
            "irb2600",
            "--identified",
            "irb2600",
        ];
        let rest = ["--joints", path_arg(program), "--out", path_arg(out)];
        calbench(&[&args[..], &rest[..]].concat())
    };
    let out = d.join("corrected.csv");
    let o = compensate(&rad, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    let want = format!(
        "{}: joint values: every revolute joint value lies within",
        rad.display()
    );
    assert!(!o.status.success() && err.contains(&want), "{err}");
    assert!(err.contains("likely in radians") && !out.exists(), "{err}");
    let o = calbench(&[
        "identifiability",
        "--robot",
        "irb2600",
        "--poses-file",
        path_arg(&rad),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains(&want), "{err}");
    for program in [&deg, &zero] {
        let o = compensate(program, &out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
}
