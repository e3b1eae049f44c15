//! Real tracker data in, compensated robot out: `import` of a raw Leica export (the first
//! rows of the IPA UR10 data set, shipped in examples/ipa-ur10/), URDF robots against their
//! DH twins, `identify` writing robot.urdf, and `compensate`.

use std::path::Path;

use calbench::numeric::Real;
use calbench::robot::builtin;
use calbench::robot::urdf::UrdfRobot;
use calbench::robot::Param;

use crate::common::{
    calbench, calbench_ok, import_ur10_sample, path_arg, positions_only, read, tmp_dir,
    ur10_example as ex,
};

/// Pose difference (mm, rad) of two robots' FK at internal joint values.
fn fk_gap(a: &calbench::robot::Robot, b: &calbench::robot::Robot, q: &[Real]) -> (Real, Real) {
    let (fa, fb) = (a.fk(q), b.fk(q));
    let r = calbench::numeric::rotation_vector(&(fa.rot.transpose() * fb.rot)).norm();
    ((fa.pos - fb.pos).norm(), r)
}

#[test]
fn import_reads_the_leica_export_and_refuses_bad_cells_by_line_and_column() {
    let d = tmp_dir("realdata-import");
    let out = d.join("m.csv");
    import_ur10_sample(&ex("mapping.toml"), &out);
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "q1,q2,q3,q4,q5,q6,x,y,z,qw,qx,qy,qz,sigma_mm"
    );
    // Raw row 1: joints -3,14159;-1,5708;0;-1,5708;0;0 rad, point 383,97123;-3240,7562;201,72621,
    // angles -90,179563;-20,112975;-90,157388 deg (intrinsic X-Y-Z), σ 0,041565;0,022023;0,0055848.
    let row: Vec<f64> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|c| c.parse().unwrap())
        .collect();
    // The file's own rounded values, not π and π/2.
    let (q1, q2): (f64, f64) = ("-3.14159".parse().unwrap(), "-1.5708".parse().unwrap());
    assert!((row[0] - q1.to_degrees()).abs() < 1e-8);
    assert!((row[1] - q2.to_degrees()).abs() < 1e-8);
    assert!((row[6] - 383.97123).abs() < 1e-9 && (row[7] + 3240.7562).abs() < 1e-9);
    let r = calbench::measurement::import::euler_matrix(
        [0, 1, 2],
        [
            (-90.179563f64).to_radians(),
            (-20.112975f64).to_radians(),
            (-90.157388f64).to_radians(),
        ],
        true,
    );
    let q = calbench::numeric::quaternion(&r);
    for k in 0..4 {
        assert!((row[9 + k] - q[k]).abs() < 1e-11, "quaternion {k}");
    }
    let sigma = ((0.041565f64.powi(2) + 0.022023f64.powi(2) + 0.0055848f64.powi(2)) / 3.0).sqrt();
    assert!((row[13] - sigma).abs() < 1e-9);
    assert_eq!(text.lines().count(), 200);

    // A bad cell: refused naming the line and the column, nothing written.
    let raw = std::fs::read_to_string(ex("sample-200.csv")).unwrap();
    let mut ls: Vec<String> = raw.lines().map(String::from).collect();
    let mut cells: Vec<String> = ls[5].split(';').map(String::from).collect();
    cells[16] = "1,2x".into(); // measurement_y
    ls[5] = cells.join(";");
    let bad = d.join("bad.csv");
    std::fs::write(&bad, ls.join("\n")).unwrap();
    let badout = d.join("bad-out.csv");
    let o = calbench(&[
        "import",
        path_arg(&bad),
        "--mapping",
        &ex("mapping.toml"),
        "--out",
        path_arg(&badout),
    ]);
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        msg.contains("line 6") && msg.contains("measurement_y"),
        "{msg}"
    );
    assert!(!badout.exists());
}

#[test]
fn the_ur10_urdf_has_the_fk_of_the_dh_file() {
    let dh = builtin::load(ex("ur10.toml")).unwrap();
    let urdf = builtin::load(ex("ur10.urdf")).unwrap();
    let mut g = calbench::numeric::rng::stream(3, "urdf-test");
    for q in calbench::robot::sampling::uniform_joint_poses(&dh, 50, &mut g) {
        let (mm, rad) = fk_gap(&dh, &urdf, &q);
        assert!(mm < 1e-9 && rad < 1e-12, "{mm} mm, {rad} rad at {q:?}");
    }
}

/// Writing back: a URDF whose joint origins carry a robot's identified errors has that
/// robot's FK, at every joint vector (the constant offsets stay right as the joints move).
#[test]
fn a_written_urdf_has_the_fk_of_the_robot_it_was_written_from() {
    let u = UrdfRobot::load(Path::new(&ex("ur10.urdf"))).unwrap();
    let n = u.robot.dof();
    let errors: Vec<(Param, Real)> = u
        .robot
        .params()
        .into_iter()
        .enumerate()
        .map(|(i, p)| {
            (
                p,
                if p.is_length() { 0.7 } else { 2e-3 } * if i % 3 == 0 { -1.0 } else { 1.0 },
            )
        })
        .collect();
    let changed = u.robot.with_errors(&errors);
    let d = tmp_dir("realdata-urdf-write");
    let path = d.join("changed.urdf");
    std::fs::write(&path, u.write(&changed).unwrap()).unwrap();
    let back = builtin::load(path_arg(&path)).unwrap();
    assert_eq!(back.dof(), n);
    let mut g = calbench::numeric::rng::stream(4, "urdf-test");
    let mut moved: Real = 0.0;
    for q in calbench::robot::sampling::uniform_joint_poses(&changed, 50, &mut g) {
        let (mm, rad) = fk_gap(&changed, &back, &q);
        assert!(mm < 1e-8 && rad < 1e-11, "{mm} mm, {rad} rad");
        moved = moved.max(fk_gap(&changed, &u.robot, &q).0);
    }
    assert!(moved > 1.0, "the errors move the tip ({moved} mm)");
}

/// `calbench identify --robot URDF` on the shipped rows (imported in rad, position only) into
/// `DIR/id`, whose robot.urdf is checked to have the FK of its robot.toml; returns `DIR/id`.
fn identify_urdf_on_the_shipped_rows(urdf: &str, d: &Path) -> std::path::PathBuf {
    let m = d.join("m.csv");
    let mapping = d.join("mapping-rad.toml");
    let text = std::fs::read_to_string(ex("mapping.toml"))
        .unwrap()
        .replace("write_unit = \"deg\"", "write_unit = \"rad\"");
    std::fs::write(&mapping, text).unwrap();
    import_ur10_sample(path_arg(&mapping), &m);
    // Position only: the q and xyz columns.
    let p = d.join("pos.csv");
    positions_only(&m, &p);
    let out = d.join("id");
    calbench_ok(&[
        "identify",
        "--robot",
        urdf,
        "--data",
        path_arg(&p),
        "--method",
        "lm",
        "--out",
        path_arg(&out),
    ]);
    let toml = builtin::load(path_arg(&out.join("robot.toml"))).unwrap();
    let urdf = builtin::load(path_arg(&out.join("robot.urdf"))).unwrap();
    let mut g = calbench::numeric::rng::stream(5, "urdf-test");
    for q in calbench::robot::sampling::uniform_joint_poses(&toml, 20, &mut g) {
        let (mm, rad) = fk_gap(&toml, &urdf, &q);
        assert!(mm < 1e-8 && rad < 1e-11, "{mm} mm, {rad} rad");
    }
    out
}

/// A URDF whose `<visual>` holds two `<material>` elements, as ROS-Industrial's IRB 4600 URDFs
/// write them, with a transmission and a comment: calbench reads none of them, so `fk` gives
/// the FK of the URDF without them, and `identify`'s robot.urdf is the source text with only
/// the joints' `<origin>` lines changed (where urdf-rs refused the robot, "duplicate field
/// `material`", and robot.urdf was written from what urdf-rs had parsed).
#[test]
fn a_urdf_with_two_materials_in_a_visual_is_read_and_written_back_whole() {
    let d = tmp_dir("realdata-urdf-visuals");
    let visual = "<link name=\"link_3\">
    <visual name=\"visual\">
      <geometry>
        <mesh filename=\"package://arm/meshes/link_3.dae\"/>
      </geometry>
      <material name=\"\">
        <color rgba=\"0.9254902 0.9254902 0.9058824 1\"/>
      </material>
      <material name=\"yellow\"/>
    </visual>
  </link>";
    let tail = "  <!-- not read by calbench -->
  <transmission name=\"t1\"><type>transmission_interface/SimpleTransmission</type></transmission>
</robot>";
    let src = read(Path::new(&ex("ur10.urdf")))
        .replace("<link name=\"link_3\"/>", visual)
        .replace("</robot>", tail);
    assert!(src.contains(visual) && src.contains(tail));
    let urdf = d.join("arm.urdf");
    std::fs::write(&urdf, &src).unwrap();
    let fk = |robot: &str| {
        let q = "0.1,-1.2,1.3,-1.6,1.2,0.3";
        calbench_ok(&["fk", "--robot", robot, "--q", q, "--json"]).stdout
    };
    assert_eq!(fk(path_arg(&urdf)), fk(&ex("ur10.urdf")));
    written_back_whole(&urdf, &src, &d);
}

/// `identify` on the URDF `urdf` of text `src` (into `DIR/id`): robot.urdf is `src` with only
/// the joints' `<origin>` elements changed.
fn written_back_whole(urdf: &Path, src: &str, d: &Path) {
    let out = identify_urdf_on_the_shipped_rows(path_arg(urdf), d);
    let written = read(&out.join("robot.urdf"));
    // Each line with its `<origin …/>` left out, what stands before and after it kept.
    let kept = |t: &str| -> Vec<String> {
        let line = |l: &str| match l.split_once("<origin ") {
            Some((before, rest)) => format!("{before}<origin{}", rest.split_once("/>").unwrap().1),
            None => l.to_string(),
        };
        t.lines().map(line).collect()
    };
    assert_eq!(kept(&written), kept(src), "{written}");
    assert_ne!(written, src, "the origins move");
}

/// Found by fuzzing: `examples/ipa-ur10/ur10.urdf` saved with a byte order mark (as Windows
/// editors save it) gave a robot.urdf with every `<origin>` written three bytes early
/// (`<origin …/>"/>`, `type="fixe<origin …/>d"`), which no reader takes: the offsets
/// quick-xml gives do not count the mark (two marks, as an editor that adds one to a file
/// that has one writes them, left the second uncounted).
#[test]
fn a_urdf_with_a_byte_order_mark_is_written_back_whole() {
    for marks in 1..=2 {
        let d = tmp_dir(&format!("realdata-urdf-bom-{marks}"));
        let src = "\u{feff}".repeat(marks) + &read(Path::new(&ex("ur10.urdf")));
        let urdf = d.join("bom.urdf");
        std::fs::write(&urdf, &src).unwrap();
        written_back_whole(&urdf, &src, &d);
    }
}

/// Found by fuzzing: a comment holding `--` (`<!-- see -- the DH table -->`), which
/// quick-xml and urdfdom read, was refused by the URDF parser naming a line of the text it was
/// given, not of the file. Comments are set aside unread, and written back.
#[test]
fn a_urdf_with_a_double_hyphen_in_a_comment_is_read_and_written_back_whole() {
    let d = tmp_dir("realdata-urdf-comment");
    let src = read(Path::new(&ex("ur10.urdf"))).replacen(
        "  <link name=\"link_2\"/>",
        "  <!-- see -- the DH table -->\n  <link name=\"link_2\"/>",
        1,
    );
    let urdf = d.join("comment.urdf");
    std::fs::write(&urdf, &src).unwrap();
    written_back_whole(&urdf, &src, &d);
}

/// The worked example's pipeline on the shipped rows: import, identify on the URDF (robot.urdf
/// written, and equal to robot.toml), compensate.
#[test]
fn import_identify_compensate_on_the_shipped_rows() {
    let d = tmp_dir("realdata-pipeline");
    let out = identify_urdf_on_the_shipped_rows(&ex("ur10.urdf"), &d);
    let toml = builtin::load(path_arg(&out.join("robot.toml"))).unwrap();
    let prog = d.join("prog.csv");
    std::fs::write(
        &prog,
        "q1,q2,q3,q4,q5,q6\n0.1,-1.2,1.3,-1.6,1.2,0.3\n-2.0,-2.1,1.8,-2.2,0.9,0.1\n",
    )
    .unwrap();
    let corr = d.join("corr.csv");
    calbench_ok(&[
        "compensate",
        "--robot",
        &ex("ur10.urdf"),
        "--identified",
        path_arg(&out.join("robot.toml")),
        "--joints",
        path_arg(&prog),
        "--out",
        path_arg(&corr),
    ]);
    let c = std::fs::read_to_string(&corr).unwrap();
    let mut rows = c.lines();
    assert_eq!(
        rows.next().unwrap(),
        "q1,q2,q3,q4,q5,q6,residual_mm,residual_deg,flag"
    );
    let nominal = builtin::load(ex("ur10.urdf")).unwrap();
    for (row, qin) in rows.zip([
        [0.1, -1.2, 1.3, -1.6, 1.2, 0.3],
        [-2.0, -2.1, 1.8, -2.2, 0.9, 0.1],
    ]) {
        let f: Vec<&str> = row.split(',').collect();
        assert_eq!(f[8], "ok", "{row}");
        let qout: Vec<Real> = f[..6].iter().map(|v| v.parse().unwrap()).collect();
        let (a, b) = (toml.fk(&qout), nominal.fk(&qin));
        assert!((a.pos - b.pos).norm() < 1e-6);
        assert!(
            qout.iter().zip(&qin).any(|(x, y)| (x - y).abs() > 1e-5),
            "joints corrected"
        );
    }
}

/// `identify --export urdf` on a robot file: the URDF of a robot of each convention has its FK.
#[test]
fn robot_files_of_every_convention_export_to_a_urdf_with_their_fk() {
    let d = tmp_dir("realdata-export");
    for (i, r) in [builtin::irb2600(), builtin::irb2600_mdh(), builtin::tx60()]
        .into_iter()
        .enumerate()
    {
        // Nonzero β and base/tool frames, so every part of the link transforms is exercised.
        let errors: Vec<(Param, Real)> = r
            .params()
            .into_iter()
            .map(|p| (p, if p.is_length() { 3.0 } else { 0.02 }))
            .collect();
        let r = r.with_errors(&errors);
        let path = d.join(format!("r{i}.urdf"));
        std::fs::write(&path, calbench::robot::urdf::robot_to_urdf(&r).unwrap()).unwrap();
        let back = builtin::load(path_arg(&path)).unwrap();
        let mut g = calbench::numeric::rng::stream(6, "urdf-test");
        for q in calbench::robot::sampling::uniform_joint_poses(&r, 30, &mut g) {
            let (mm, rad) = fk_gap(&r, &back, &q);
            assert!(mm < 1e-8 && rad < 1e-11, "{}: {mm} mm, {rad} rad", r.name);
        }
    }
}

/// An orientation weight so small that the solve loses the rank the orientation gave (two of
/// UR10's 28 full-pose parameters) is refused saying so, not as "the poses determine only 28
/// of the 28 parameters" with empty lists of undetermined parameters and groups.
#[test]
fn a_rank_lost_in_the_solve_is_not_reported_as_undetermined_poses() {
    let d = tmp_dir("realdata-rank-lost");
    let data = d.join("m.csv");
    import_ur10_sample(&ex("mapping.toml"), &data);
    let out = d.join("out");
    let o = calbench(&[
        "identify",
        "--robot",
        &ex("ur10.toml"),
        "--data",
        path_arg(&data),
        "--method",
        "ls",
        "--k",
        "1e-6",
        "--out",
        path_arg(&out),
    ]);
    let msg = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{msg}");
    assert!(
        msg.contains(
            "data: the poses determine all 28 kinematic parameters, yet the solve's rank is 26 \
             of the 28 identified"
        ) && !msg.contains("undetermined: ;"),
        "{msg}"
    );
    assert!(!out.exists());
}

/// A program row at a singular pose (UR's home pose, elbow and wrist straight) that the
/// identified robot cannot reach: `compensate` flags it `failed` and writes the commands that
/// came closest, no farther than the program's own, where the Gauss–Newton steps ran off to a
/// command 733 mm off and ten turns outside the joint limits.
#[test]
fn a_failed_row_keeps_the_commands_that_came_closest() {
    let d = tmp_dir("realdata-compensate-singular");
    let identified = crate::common::root().join("tests/data/ur10-series-b-identified.toml");
    let home = [-179.999847961, -90.000210459, 0.0, -90.000210459, 0.0, 0.0];
    let prog = d.join("prog.csv");
    let row: Vec<String> = home.iter().map(|v| v.to_string()).collect();
    std::fs::write(&prog, format!("q1,q2,q3,q4,q5,q6\n{}\n", row.join(","))).unwrap();
    let corr = d.join("corr.csv");
    calbench_ok(&[
        "compensate",
        "--robot",
        &ex("ur10.toml"),
        "--identified",
        path_arg(&identified),
        "--joints",
        path_arg(&prog),
        "--out",
        path_arg(&corr),
    ]);
    let c = std::fs::read_to_string(&corr).unwrap();
    let f: Vec<&str> = c.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(f[8], "failed", "{c}");
    let qout: Vec<Real> = f[..6].iter().map(|v| v.parse().unwrap()).collect();
    assert!(qout.iter().all(|q| q.abs() <= 360.0), "{c}");
    // The identified robot at the program's own commands, against the nominal pose.
    let (nominal, id) = (
        builtin::load(ex("ur10.toml")).unwrap(),
        builtin::load(path_arg(&identified)).unwrap(),
    );
    let own = fk_gap(&nominal, &id, &nominal.q_from_user(&home)).0;
    let written: Real = f[6].parse().unwrap();
    assert!(
        own > 0.5 && written <= own * 1.01,
        "{written} mm against {own} mm"
    );
}

/// A URDF under another name (`ur10.xml`, as ROS tools write one) is read as a URDF by its
/// text (docs/formats.md § 1.4): `fk` gives the `.urdf` file's pose, where the file had been
/// read as TOML and refused at line 1 ("key with no value"), and `identify` writes its
/// `robot.urdf` with the FK of its `robot.toml`. A TOML robot file keeps its reading under any
/// name.
#[test]
fn a_urdf_named_xml_is_read_as_a_urdf() {
    let d = tmp_dir("realdata-urdf-xml");
    let xml = d.join("ur10.xml");
    std::fs::copy(ex("ur10.urdf"), &xml).unwrap();
    let fk = |robot: &str, q: &str| calbench_ok(&["fk", "--robot", robot, "--q", q]).stdout;
    let q = "0.1,-1.2,1.3,0.4,-0.5,0.6";
    assert_eq!(fk(path_arg(&xml), q), fk(&ex("ur10.urdf"), q));
    let toml = d.join("dh.xml");
    std::fs::copy(ex("ur10.toml"), &toml).unwrap();
    let q = "10,-70,80,20,-30,40";
    assert_eq!(fk(path_arg(&toml), q), fk(&ex("ur10.toml"), q));
    identify_urdf_on_the_shipped_rows(path_arg(&xml), &d);
}
