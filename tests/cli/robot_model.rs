//! A robot file's whole model where a command computes with it (docs/formats.md § 3.1): `fk`
//! turns a joint by its joint-angle harmonics as `compensate` does, and a study, whose
//! simulation has no harmonics, gravity basis or compliances of a robot file, refuses such a
//! file when the scenario is read instead of identifying a model its truth lacks; `simulate`
//! refuses a robot whose tool points lie beyond the range a measurement file is read in (a
//! robot in m written as if in mm) rather than write a file `identify` refuses.

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};

use crate::common::{
    calbench, calbench_ok, fk_point, path_arg, refused, root, tmp_dir, write_scenario,
};

/// The IRB2600 as a robot file in `dir/NAME.toml`, with `extra` (TOML keys) added to joint 2.
fn irb2600_with(dir: &Path, name: &str, extra: &str) -> PathBuf {
    let text = String::from_utf8(calbench_ok(&["robots", "irb2600"]).stdout).unwrap();
    let joint2 = "theta = -90.0\n";
    assert!(text.contains(joint2), "{text}");
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(
        &path,
        text.replacen(joint2, &format!("{joint2}{extra}\n"), 1),
    )
    .unwrap();
    path
}

/// `fk` of a robot whose joint 2 carries harmonics is the rigid robot's at joint 2 turned by
/// `Σ a_n sin nq + b_n cos nq` (docs/formats.md "Joint-angle harmonics"), computed here apart
/// from calbench's code, where it was the rigid robot's, up to 4 mm away.
#[test]
fn fk_turns_a_joint_by_its_harmonics() {
    let dir = tmp_dir("robot-model-fk");
    let h: [f64; 4] = [0.001, -0.002, 0.0005, 0.0003];
    let harmonic = irb2600_with(&dir, "harmonic", &format!("harmonics = {h:?}"));
    let rigid = irb2600_with(&dir, "rigid", "");
    for q in [
        [0.0f64, 0.0, 0.0, 0.0, 0.0, 0.0],
        [10.0, 20.0, 30.0, 40.0, 50.0, 60.0],
        [-120.0, -60.0, 45.0, 100.0, -30.0, 170.0],
    ] {
        let q2 = q[1].to_radians();
        let turn =
            h[0] * q2.sin() + h[1] * q2.cos() + h[2] * (2.0 * q2).sin() + h[3] * (2.0 * q2).cos();
        let mut turned = q;
        turned[1] = (q2 + turn).to_degrees();
        let (got, want) = (fk_point(&harmonic, &q), fk_point(&rigid, &turned));
        for i in 0..3 {
            assert!(
                (got[i] - want[i]).abs() < 1e-6,
                "q {q:?}: {got:?} against {want:?}"
            );
        }
        assert!(
            (got[2] - fk_point(&rigid, &q)[2]).abs() > 0.1,
            "q {q:?}: no harmonic offset"
        );
    }
}

/// A scenario whose robot file gives harmonics, a gravity basis or compliances, or names a
/// URDF, is refused naming the file, the line and `robot.file`; a linear sag without stiffness
/// for a robot file names the `[compliance]` line and the key; an instruments study on such a
/// robot names `robot`. Nothing runs.
#[test]
fn a_study_refuses_a_robot_model_it_does_not_simulate() {
    let dir = tmp_dir("robot-model-study");
    let ci_guard = std::fs::read_to_string(root().join("scenarios/ci-guard.toml")).unwrap();
    let on =
        |robot: &str| ci_guard.replace("builtin = \"irb2600\"", &format!("file = \"{robot}\""));
    let cases = [
        ("harmonics = [0.001, 0.0]", "`harmonics` on joint 2"),
        ("gravity = [0.0, 0.001, 0.0]", "`gravity` on joint 2"),
        ("compliance = 3e-7", "`compliance` on joint 2"),
    ];
    for (i, (extra, named)) in cases.into_iter().enumerate() {
        irb2600_with(&dir, &format!("r{i}"), extra);
        let sc = write_scenario(&dir, &format!("s{i}"), &on(&format!("r{i}.toml")));
        let out = dir.join(format!("out{i}"));
        let o = calbench(&["run", path_arg(&sc), "--out", path_arg(&out)]);
        refused(
            &o,
            &[path_arg(&sc), "line 10, robot.file", named, "[unmodelled]"],
        );
        assert!(!out.exists(), "{} written", out.display());
    }
    std::fs::write(dir.join("arm.urdf"), "<robot name=\"a\"/>").unwrap();
    let sc = write_scenario(&dir, "urdf", &on("arm.urdf"));
    let o = calbench(&["run", path_arg(&sc), "--out", path_arg(&dir.join("o"))]);
    refused(&o, &["line 10, robot.file", "is a URDF", "in TOML"]);

    irb2600_with(&dir, "bare", "");
    let sc = write_scenario(&dir, "stiff", &on("bare.toml"));
    let o = calbench(&["run", path_arg(&sc), "--out", path_arg(&dir.join("o"))]);
    refused(
        &o,
        &[
            "line 22, compliance.stiffness_nm_per_rad",
            "one value per joint (6)",
        ],
    );

    let robot = irb2600_with(&dir, "harmonic", "harmonics = [0.001, 0.0]");
    let text = format!(
        "name = \"i\"\nseed = 1\ntrials = 2\nrobot = \"{}\"\n\n[instruments_study]\nposes = [20]\n\
         strategies = [\"random\"]\ncandidates = 40\nvalidation = 5\n\n[errors]\nkind = \"paper\"\n\n\
         [[measurement]]\nkind = \"distance\"\n",
        robot.display()
    );
    let sc = write_scenario(&dir, "instruments", &text);
    let o = calbench(&["run", path_arg(&sc), "--out", path_arg(&dir.join("o"))]);
    refused(
        &o,
        &[path_arg(&sc), "robot: robot", "`harmonics` on joint 2"],
    );
}

/// An IRB2600-like arm in metres and radians (joints: α, a, d, θ; limits ±π).
const ARM_M_RAD: &str =
    "name = \"arm\"\nconvention = \"dh\"\nlength_unit = \"m\"\nangle_unit = \"rad\"\n";
const ARM_JOINTS: [[f64; 4]; 6] = [
    [-FRAC_PI_2, 0.15, 0.445, 0.0],
    [0.0, 0.9, 0.0, -FRAC_PI_2],
    [-FRAC_PI_2, 0.15, 0.0, 0.0],
    [FRAC_PI_2, 0.0, 0.938, 0.0],
    [-FRAC_PI_2, 0.0, 0.0, 0.0],
    [0.0, 0.0, 0.2, PI],
];

/// [`ARM_M_RAD`] with joint 2's `a` made `a2`, and a tool, in `dir/NAME.toml`.
fn arm_m_rad(dir: &Path, name: &str, a2: f64) -> PathBuf {
    let mut text = ARM_M_RAD.to_string();
    for (j, [alpha, a, d, theta]) in ARM_JOINTS.into_iter().enumerate() {
        let a = if j == 1 { a2 } else { a };
        text += &format!(
            "\n[[joints]]\ntype = \"revolute\"\nalpha = {alpha:?}\na = {a:?}\nd = {d:?}\n\
             theta = {theta:?}\nlimits = [-3.14159, 3.14159]\n"
        );
    }
    text += "\n[tool]\nxyz = [0.01, 0.005, 0.12]\nrpy = [0.26, -0.35, 0.79]\n";
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// `compensate` of a robot in metres and radians writes each command finely enough to reach
/// its pose within the program's 1e-6 mm (docs/formats.md § 7.8: 11 decimals in radians),
/// where 9 decimals of a radian (1e-6 mm at a metre's reach) flagged reachable rows `failed`.
#[test]
fn compensate_writes_radians_finely_enough_to_reach_the_pose() {
    let dir = tmp_dir("robot-model-radians");
    let nominal = arm_m_rad(&dir, "nominal", 0.9);
    let identified = arm_m_rad(&dir, "identified", 0.9005);
    let rows = [
        "-1.123659223,2.670038818,-0.860808331,-0.647600210,-0.116880514,-1.012686749",
        "1.681464214,0.766469109,-0.316981096,1.111998572,1.648769217,2.234910654",
        "0.3,-0.4,0.5,1.2,-0.8,2.5",
        "-2.5,1.1,-2.0,-1.5,1.9,-0.7",
        "2.9,-1.2,0.9,2.8,-2.6,0.1",
    ];
    let text = crate::compensate::compensate_rows(&dir, &nominal, &identified, &rows);
    for line in text.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[8], "ok", "{line}");
        assert!(
            cells[..6]
                .iter()
                .all(|c| c.split_once('.').unwrap().1.len() == 11),
            "{line}"
        );
        assert!(cells[6].parse::<f64>().unwrap() < 1e-7, "{line}");
    }
}

/// Tracker points in an unknown frame do not fix where the robot stands (docs/formats.md
/// § 4.8): with the default `identify` registration, the program `compensate` corrects with the
/// identified robot reaches the nominal points on the true robot up to one rigid motion, which
/// the SVD of the nominal model onto the points leaves in `[base]`; with the points given in
/// the base frame (`known`) it reaches them. The truth differs from the nominal robot by a2
/// alone (+0.5 mm), and the data are noise-free.
#[test]
fn a_program_compensated_after_a_registration_is_right_up_to_a_rigid_motion() {
    let dir = tmp_dir("robot-model-gauge");
    let nominal = arm_m_rad(&dir, "nominal", 0.9);
    let truth = arm_m_rad(&dir, "truth", 0.9005);
    // Joint values spread over the limits (a fixed sequence, no generator).
    let q = |i: usize, j: usize| (((i * 7 + j * 13) % 29) as f64 / 14.0 - 1.0) * 2.8;
    let rows = |n: usize, from: usize| -> Vec<Vec<f64>> {
        (from..from + n)
            .map(|i| (0..6).map(|j| q(i, j)).collect())
            .collect()
    };
    let fmt = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:?}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let mut data = String::from("q1,q2,q3,q4,q5,q6,x,y,z\n");
    for qs in rows(29, 0) {
        data += &format!("{},{}\n", fmt(&qs), fmt(&fk_point(&truth, &qs)));
    }
    let data_file = dir.join("points.csv");
    std::fs::write(&data_file, data).unwrap();
    let program: Vec<Vec<f64>> = rows(5, 3);
    let program_file = dir.join("program.csv");
    let lines: Vec<String> = program.iter().map(|q| fmt(q)).collect();
    std::fs::write(
        &program_file,
        format!("q1,q2,q3,q4,q5,q6\n{}\n", lines.join("\n")),
    )
    .unwrap();
    // The true robot's points at the corrected commands, after `identify --registration REG`.
    let reached = |registration: &str| -> Vec<Vec<f64>> {
        let out = dir.join(registration);
        calbench_ok(&[
            "identify",
            "--robot",
            path_arg(&nominal),
            "--data",
            path_arg(&data_file),
            "--method",
            "ls",
            "--registration",
            registration,
            "--out",
            path_arg(&out),
        ]);
        let corrected = dir.join(format!("{registration}.csv"));
        calbench_ok(&[
            "compensate",
            "--robot",
            path_arg(&nominal),
            "--identified",
            path_arg(&out.join("robot.toml")),
            "--joints",
            path_arg(&program_file),
            "--out",
            path_arg(&corrected),
        ]);
        let text = std::fs::read_to_string(&corrected).unwrap();
        text.lines()
            .skip(1)
            .map(|l| {
                let q: Vec<f64> = l.split(',').take(6).map(|c| c.parse().unwrap()).collect();
                fk_point(&truth, &q)
            })
            .collect()
    };
    let wanted: Vec<Vec<f64>> = program.iter().map(|q| fk_point(&nominal, q)).collect();
    let dist = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let worst = |got: &[Vec<f64>]| {
        got.iter()
            .zip(&wanted)
            .map(|(g, w)| dist(g, w))
            .fold(0.0, f64::max)
    };
    let known = reached("known");
    assert!(worst(&known) < 1e-5, "{known:?}");
    // `svd` alternates registration and identification until the frame moves no point by
    // more than 1e-4 mm: its robot has the truth's shape to about that.
    for (registration, shape) in [("identify", 1e-5), ("svd", 1e-3)] {
        let registered = reached(registration);
        let off = worst(&registered);
        assert!(off > 1e-3, "{registration}: {off}");
        // The same shape: every distance between two reached points is the nominal one.
        for i in 0..wanted.len() {
            for j in 0..i {
                let (g, w) = (
                    dist(&registered[i], &registered[j]),
                    dist(&wanted[i], &wanted[j]),
                );
                assert!(
                    (g - w).abs() < shape,
                    "{registration} {i} {j}: {g} against {w}"
                );
            }
        }
    }
}

/// A robot file in m whose lengths are written in mm (`a = 400.0` under `length_unit = "m"`):
/// its scenario is refused when read, at `robot.file`, naming the reach and the range of a
/// measured coordinate, by `simulate` (which wrote a `validation.csv` that `identify` then
/// refused), `run` (which had run it, "before 144613 mm") and `poses`; nothing is written.
#[test]
fn a_study_refuses_a_robot_reaching_beyond_the_measurement_range() {
    let dir = tmp_dir("cli-simulate-range");
    let robot = dir.join("big.toml");
    // A five-joint arm whose lengths (mm) are declared in m.
    let metres = crate::compensate::arm5(400.0, 0.0).replace("\"mm\"", "\"m\"");
    std::fs::write(&robot, metres).unwrap();
    let sc = write_scenario(
        &dir,
        "sc-big",
        "name = \"sc-big\"\nseed = 3\ntrials = 3\n[robot]\nfile = \"big.toml\"\n\
         [errors]\nkind = \"normal\"\nlength_mm = 0.3\nangle_rad = 0.003\n\
         params = \"identifiable\"\n[tracker]\nmpe_a_um = 0.0\nmpe_b_um_per_m = 0.0\n\
         [outliers]\ncount = 0\n[calibration]\ncount = 40\nstrategies = [\"random\"]\n\
         [validation]\ncount = 20\n[[methods]]\nname = \"lm\"\n",
    );
    let out = dir.join("s3");
    let at = format!(
        "{}: line 5, robot.file: robot \"arm5\" may reach ",
        sc.display()
    );
    let commands: [&[&str]; 3] = [&["simulate"], &["run"], &["poses", "--strategy", "random"]];
    for command in commands {
        let o = calbench(&[command, &[path_arg(&sc), "--out", path_arg(&out)]].concat());
        let err = refused(
            &o,
            &[&at, "mm (1 km) a measurement is read in", "length_unit"],
        );
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.trim_end().lines().count() == 1, "{err}");
        assert!(!out.exists(), "{err}");
    }
}

/// A robot in metres and radians: `simulate` writes its joint values with 11 decimals (as
/// finely as 9 decimals of a degree), so that `identify --method ls` recovers noise-free
/// errors to a residual below 1e-8 mm, where 9 decimals of a radian left 2.8e-7 mm.
#[test]
fn a_simulated_file_in_radians_holds_its_joints_finely_enough_to_recover_the_errors() {
    let dir = tmp_dir("cli-simulate-radians");
    let robot = arm_m_rad(&dir, "arm", 0.9);
    let sc = write_scenario(
        &dir,
        "s",
        &format!(
            "name = \"rad\"\nseed = 3\ntrials = 1\n[robot]\nfile = \"{}\"\n[errors]\n\
             kind = \"normal\"\nlength_mm = 0.3\nangle_rad = 0.003\nparams = \"identifiable\"\n\
             [tracker]\nmpe_a_um = 0.0\nmpe_b_um_per_m = 0.0\n[outliers]\ncount = 0\n\
             [calibration]\ncount = 40\nstrategies = [\"random\"]\n[validation]\ncount = 20\n\
             [[methods]]\nname = \"ls\"\n",
            robot.display()
        ),
    );
    let sim = dir.join("sim");
    calbench_ok(&["simulate", path_arg(&sc), "--out", path_arg(&sim)]);
    let text = std::fs::read_to_string(sim.join("measurements.csv")).unwrap();
    let row: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    for cell in &row[..6] {
        assert_eq!(cell.split_once('.').unwrap().1.len(), 11, "{cell}");
    }
    let out = dir.join("id");
    calbench_ok(&[
        "identify",
        "--robot",
        path_arg(&robot),
        "--data",
        path_arg(&sim.join("measurements.csv")),
        "--method",
        "ls",
        "--out",
        path_arg(&out),
    ]);
    let id: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("identified.json")).unwrap())
            .unwrap();
    let rms = id["rms_residual_mm"].as_f64().unwrap();
    assert!(rms < 1e-8, "{rms}");
}

/// A robot file named with a control character is refused at `name`, as a study's name and
/// a method's label are: `identify --export urdf` had written it into a URDF no reader takes
/// (XML 1.0 holds no ESC), and into the reports raw.
#[test]
fn a_robot_named_with_a_control_character_is_refused_at_its_name() {
    let dir = tmp_dir("cli-robot-name");
    for (stem, name) in [("esc", "arm \\u001b[1m"), ("rlo", "arm \\u202e")] {
        let text = String::from_utf8(calbench_ok(&["robots", "irb2600"]).stdout).unwrap();
        let first = text.lines().find(|l| l.starts_with("name = ")).unwrap();
        let line = text.lines().position(|l| l == first).unwrap() + 1;
        let path = dir.join(format!("{stem}.toml"));
        std::fs::write(
            &path,
            text.replacen(first, &format!("name = \"{name}\""), 1),
        )
        .unwrap();
        let o = calbench(&["fk", "--robot", path_arg(&path), "--q", "0,0,0,0,0,0"]);
        let want = format!(
            "{}: line {line}, name: must be a name without control characters",
            path.display()
        );
        refused(&o, &[&want]);
    }
}

/// A URDF chain of more moving joints than a robot holds (16, as a robot file's
/// `[[joints]]`) is refused at the first joint too many, by its line, as a robot file of 17
/// joints is: `fk`, `identifiability` and `identify` had panicked on one of 17. Sixteen are
/// read.
#[test]
fn a_urdf_chain_of_seventeen_moving_joints_is_refused_at_the_seventeenth() {
    let dir = tmp_dir("cli-urdf-17");
    let chain = |n: usize| {
        let mut xml = String::from("<robot name=\"long\">\n<link name=\"l0\"/>\n");
        for i in 1..=n {
            xml += &format!(
                "<link name=\"l{i}\"/>\n<joint name=\"j{i}\" type=\"revolute\">\n\
                 <parent link=\"l{}\"/><child link=\"l{i}\"/>\n\
                 <origin xyz=\"0.1 0 0.05\" rpy=\"0.3 0.2 0\"/><axis xyz=\"0 0 1\"/>\n\
                 <limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/>\n</joint>\n",
                i - 1
            );
        }
        let path = dir.join(format!("chain{n}.urdf"));
        std::fs::write(&path, xml + "</robot>\n").unwrap();
        path
    };
    let q = |n: usize| vec!["0.1"; n].join(",");
    let sixteen = chain(16);
    calbench_ok(&["fk", "--robot", path_arg(&sixteen), "--q", &q(16)]);
    let long = chain(17);
    // j17's start tag: 2 lines of the robot and its first link, 6 per joint before it.
    let want = format!(
        "{}: line {}: joint \"j17\" is moving joint 17 of the chain to \"l17\": at most \
         16 moving joints are supported",
        long.display(),
        3 + 6 * 16 + 1
    );
    let commands: [&[&str]; 2] = [
        &["fk", "--robot", path_arg(&long), "--q", &q(17)],
        &[
            "identifiability",
            "--robot",
            path_arg(&long),
            "--poses",
            "5",
        ],
    ];
    for args in commands {
        refused(&calbench(args), &[&want]);
    }
}
