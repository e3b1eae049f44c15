use super::*;
use crate::robot::builtin;

const HEAD: &str = "name = \"x\"\nconvention = \"dh\"\nangle_unit = \"deg\"\n";

/// A one-joint robot file in `length_unit` with `body` as the joint's keys.
fn one_joint(length_unit: &str, body: &str) -> String {
    format!("{HEAD}length_unit = \"{length_unit}\"\n[[joints]]\ntype = \"revolute\"\n{body}\n")
}

fn refused(text: &str, key: &str) -> String {
    let e = parse_robot_file(text, Path::new("dir/bad-robot.toml"))
        .expect_err(&format!("accepted:\n{text}"))
        .to_string();
    assert!(
        e.contains("dir/bad-robot.toml") && e.contains(key),
        "message `{e}` lacks the file or `{key}`"
    );
    e
}

const JOINT: &str = "alpha = 0.0\na = 0.0\nd = 0.0\ntheta = 0.0\nlimits = [-90.0, 90.0]";

#[test]
fn values_are_checked_after_unit_conversion() {
    // Finite in metres, infinite in mm.
    let e = refused(
        &one_joint("m", &JOINT.replace("\na = 0.0", "\na = 1e308")),
        "`a`",
    );
    assert!(e.contains("inf"), "{e}");
    refused(
        &one_joint("m", &JOINT.replace("d = 0.0", "d = -1e306")),
        "`d`",
    );
    let base = format!("{}[base]\nxyz = [0.0, 1e307, 0.0]\n", one_joint("m", JOINT));
    refused(&base, "base.xyz");
    // Distinct in degrees, equal (zero) in radians.
    let tiny = JOINT.replace("[-90.0, 90.0]", "[5e-324, 1e-323]");
    refused(&one_joint("mm", &tiny), "limits");
    let coupled = "name = \"c\"\nconvention = \"dh\"\nlength_unit = \"m\"\nangle_unit = \"deg\"\n\
        [coupling]\nkind = \"differential\"\nl1 = 1e308\n\
        [[joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 0.0\nd = 0.0\ntheta = 0.0\nlimits = [0.0, 0.4]\n\
        [[joints]]\ntype = \"prismatic\"\nalpha = 0.0\na = 0.0\nd = 0.0\ntheta = 0.0\nlimits = [0.0, 0.4]\n";
    refused(coupled, "coupling.l1");
    // A prismatic limit in metres that overflows.
    let pris = one_joint("m", JOINT)
        .replace("revolute", "prismatic")
        .replace("[-90.0, 90.0]", "[0.0, 1e306]");
    refused(&pris, "limits");
}

#[test]
fn refusals_name_the_line_of_the_key() {
    // Lines: 1-3 HEAD, 4 length_unit, 5 [[joints]], 6 type, 7 alpha, 8 a, 9 d, 10 theta,
    // 11 limits.
    let a = one_joint("m", &JOINT.replace("\na = 0.0", "\na = 1e308"));
    refused(&a, "bad-robot.toml: line 8, joint 1 (joints[0]), key `a`: ");
    let alpha = one_joint("mm", &JOINT.replace("alpha = 0.0", "alpha = 400"));
    refused(&alpha, "line 7, joint 1 (joints[0]), key `alpha`: ");
    let limits = one_joint("mm", &JOINT.replace("[-90.0, 90.0]", "[90.0, -90.0]"));
    refused(&limits, "line 11, joint 1 (joints[0]), key `limits`: ");
    // Lines 12 blank, 13 [[joints]], 14 type, 15 alpha, 16 a, 17 d.
    let two = format!(
        "{}\n[[joints]]\ntype = \"revolute\"\n{JOINT}\n",
        one_joint("mm", JOINT)
    );
    let i = two.rfind("d = 0.0").unwrap();
    let bad_second = format!("{}d = 2e6{}", &two[..i], &two[i + 7..]);
    refused(&bad_second, "line 17, joint 2 (joints[1]), key `d`: ");
    let base = format!("{}[base]\nxyz = [0.0, 1e307, 0.0]\n", one_joint("m", JOINT));
    refused(&base, "line 13, base.xyz: ");
    let kind = one_joint("mm", JOINT).replace("\"revolute\"", "\"hinge\"");
    refused(&kind, "line 6, joint 1 (joints[0]), key `type`: ");
    // A key the file does not write has no line; TOML errors name theirs, and the key.
    let e = refused(
        &format!("{HEAD}length_unit = \"mm\"\njoints = []\n"),
        "joints",
    );
    assert!(e.contains("line 5, joints: "), "{e}");
    let e = refused(
        &one_joint("mm", "alpha = 0.0\na = \"x\""),
        "line 8, joints[0].a: ",
    );
    assert!(
        e.ends_with("invalid type: string \"x\", expected a number"),
        "{e}"
    );
    refused(
        &format!("{}d = 1.0\n", one_joint("mm", JOINT)),
        ": duplicate key `d`",
    );
    assert_eq!(
        key_of_place("joint 12 (joints[11]), key `beta`"),
        "joints[11].beta"
    );
    assert_eq!(key_of_place("coupling.l1"), "coupling.l1");
}

#[test]
fn values_out_of_range_are_refused() {
    for (unit, from, to, key) in [
        ("mm", "\na = 0.0", "\na = 2e6", "`a`"),
        ("m", "d = 0.0", "d = 1001.0", "`d`"),
        ("mm", "theta = 0.0", "theta = 400.0", "`theta`"),
        ("mm", "alpha = 0.0", "alpha = -1e300", "`alpha`"),
    ] {
        refused(&one_joint(unit, &JOINT.replace(from, to)), key);
    }
    let wide = JOINT.replace("[-90.0, 90.0]", "[-1e300, 1e300]");
    refused(&one_joint("mm", &wide), "limits");
    let tool = format!(
        "{}[tool]\nrpy = [0.0, 720.0, 0.0]\n",
        one_joint("mm", JOINT)
    );
    refused(&tool, "tool.rpy");
    // The bounds themselves are accepted, in either unit.
    let edge = JOINT
        .replace("theta = 0.0", "theta = -360.0")
        .replace("\na = 0.0", "\na = 1000.0")
        .replace("[-90.0, 90.0]", "[-3600.0, 3600.0]");
    parse_robot_file(&one_joint("m", &edge), Path::new("ok.toml")).unwrap();
    let rad = one_joint("mm", JOINT)
        .replace("\"deg\"", "\"rad\"")
        .replace("theta = 0.0", "theta = 6.283185307179586")
        .replace("[-90.0, 90.0]", "[-62.83185307179586, 62.83185307179586]");
    parse_robot_file(&rad, Path::new("ok.toml")).unwrap();
}

#[test]
fn builtins_pass_the_model_check() {
    for b in builtin::BUILTINS {
        assert_eq!((b.build)().check(), Ok(()), "{}", b.name);
    }
}

#[test]
fn model_check_names_the_key() {
    let mut r = builtin::irb2600();
    r.set(Param::A(1), Real::INFINITY);
    assert_eq!(r.check().unwrap_err().place, "joint 2 (joints[1]), key `a`");
    let mut r = builtin::irb2600();
    r.set(Param::Tool(4), Real::NAN);
    assert_eq!(r.check().unwrap_err().place, "tool.rpy");
    let mut r = builtin::irb2600();
    r.joints[3].limits = (1.0, 1.0);
    assert_eq!(
        r.check().unwrap_err().place,
        "joint 4 (joints[3]), key `limits`"
    );
    let mut r = builtin::irb2600();
    r.set(Param::Beta(2), 0.01);
    assert_eq!(
        r.check().unwrap_err().place,
        "joint 3 (joints[2]), key `beta`"
    );
}

#[test]
fn joint_values_are_checked_after_unit_conversion() {
    let text = one_joint("m", JOINT).replace("revolute", "prismatic")
        + "[[joints]]\ntype = \"revolute\"\n"
        + JOINT;
    let r = parse_robot_file(&text, Path::new("p.toml")).unwrap();
    let q = r.q_from_user_checked(&[0.5, 30.0], "q").unwrap();
    assert!((q[0] - 500.0).abs() < 1e-12 && (q[1] - 30.0_f64.to_radians()).abs() < 1e-12);
    for bad in [[1e306, 0.0], [0.0, 1e300], [Real::NAN, 0.0]] {
        let e = r.q_from_user_checked(&bad, "q").unwrap_err().to_string();
        assert!(e.contains("`q`") && e.contains("joint"), "{e}");
    }
    assert!(r.q_from_user_checked(&[0.0], "q").is_err());
}

#[test]
fn any_name_reads_back_and_control_characters_are_refused() {
    let mut r = builtin::tx60();
    for name in ["quote \" and \\ back", "ü ✓", "a # b = 'c'"] {
        r.name = name.into();
        let back = parse_robot_file(&robot_to_toml(&r), Path::new("n.toml")).unwrap();
        assert_eq!(back.name, name);
    }
    // Written escaped, read back, and refused: a terminal, a report and a URDF (XML 1.0)
    // would not show them as written.
    for name in [
        "two\nlines\ttab",
        "bell \u{7} del \u{7f}",
        "esc \u{1b}[1m",
        "rlo \u{202e}",
    ] {
        r.name = name.into();
        let e = parse_robot_file(&robot_to_toml(&r), Path::new("n.toml")).unwrap_err();
        assert!(
            e.to_string()
                .contains("line 1, name: must be a name without control characters"),
            "{e}"
        );
    }
    // An empty name had been taken (`identify` named the compensated robot `-calibrated`).
    for name in ["", "  "] {
        r.name = name.into();
        let e = parse_robot_file(&robot_to_toml(&r), Path::new("n.toml")).unwrap_err();
        assert!(e.to_string().contains("line 1, name: is empty"), "{e}");
    }
}

#[test]
fn tiny_levers_and_ranges_read_back() {
    // Found by fuzzing: tidying wrote l1 = 1e-320 as 0.0, and a range of 1e-13 degrees
    // as [0.0, 0.0], files the parser refuses.
    let mut r = builtin::guo_3t2r();
    r.coupling = Some(Coupling::Differential { l1_mm: 1e-320 });
    r.joints[3].limits = (0.0, 1e-13_f64.to_radians());
    r.joints[4].limits = (1.0, 1.0 + 1e-14);
    assert_eq!(r.check(), Ok(()));
    let back = parse_robot_file(&robot_to_toml(&r), Path::new("t.toml")).unwrap();
    assert_eq!(back.coupling, r.coupling);
    assert!(back.joints[3].limits.1 > 0.0 && back.joints[4].limits.1 > 1.0);
    // Ordinary robots are still written tidied.
    assert!(robot_to_toml(&builtin::irb2600()).contains("alpha = -90.0\n"));
}

#[test]
fn a_written_robot_reads_back_value_for_value_in_every_unit() {
    // Tidying had rounded every number to 12 decimals: in radians −π/2 was written
    // -1.570796326795 (1.8e-13 rad off), in metres a length moved by up to 5e-10 mm.
    let mut r = builtin::irb2600();
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut draw = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as Real / (1u64 << 53) as Real - 0.5
    };
    let n = r.dof();
    for j in 0..n {
        for (p, scale) in [
            (Param::Alpha(j), 1e-3),
            (Param::A(j), 0.5),
            (Param::D(j), 0.5),
            (Param::Theta(j), 1e-3),
        ] {
            r.values[p.index(n)] += scale * draw();
        }
        r.values[Param::Compliance(j).index(n)] = 1e-7 * (1.0 + draw());
    }
    for (length, angle) in [
        (LengthUnit::Mm, AngleUnit::Deg),
        (LengthUnit::M, AngleUnit::Deg),
        (LengthUnit::Mm, AngleUnit::Rad),
        (LengthUnit::M, AngleUnit::Rad),
    ] {
        r.units = Units { length, angle };
        let text = robot_to_toml(&r);
        let back = parse_robot_file(&text, Path::new("r.toml")).unwrap();
        for (i, (got, want)) in back.values.iter().zip(&r.values).enumerate() {
            assert_eq!(
                got.to_bits(),
                want.to_bits(),
                "{length:?} {angle:?} value {i}"
            );
        }
        for (b, j) in back.joints.iter().zip(&r.joints) {
            assert_eq!(b.limits, j.limits, "{length:?} {angle:?}");
        }
    }
    let mut plain = builtin::irb2600();
    plain.units.angle = AngleUnit::Rad;
    let text = robot_to_toml(&plain);
    assert!(text.contains("alpha = -1.5707963267948966\n"), "{text}");
}

#[test]
fn a_rotation_key_on_a_prismatic_joint_is_refused_even_at_zero() {
    let pris = one_joint("mm", JOINT).replace("revolute", "prismatic");
    for (key, value) in [
        ("compliance", "0.0"),
        ("gravity", "[0.0, 0.0, 0.0]"),
        ("harmonics", "[0.0, 0.0]"),
    ] {
        let e = refused(&format!("{pris}{key} = {value}\n"), &format!("key `{key}`"));
        assert!(e.contains("joint 1 is prismatic"), "{e}");
        // The same key on a revolute joint is read.
        let revolute = one_joint("mm", JOINT) + &format!("{key} = {value}\n");
        let read = parse_robot_file(&revolute, Path::new("r.toml"));
        assert!(read.is_ok(), "{key}: {read:?}");
    }
}

#[test]
fn beta_joints_naming_a_joint_twice_says_so() {
    let two = one_joint("mm", JOINT).replace("\"dh\"", "\"dh_beta\"")
        + "[[joints]]\ntype = \"revolute\"\n"
        + JOINT;
    let e = refused(&format!("beta_joints = [2, 2]\n{two}"), "beta_joints");
    assert!(e.contains("lists joint 2 twice"), "{e}");
    let e = refused(&format!("beta_joints = [3]\n{two}"), "beta_joints");
    assert!(e.contains("from 1 to 2, got 3"), "{e}");
}
