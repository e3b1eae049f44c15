//! Strict inputs on the command line: robot files checked after unit conversion (`fk`), and
//! `check` refusing files that are not comparable summaries, each naming the file.

use std::path::Path;
use std::process::Output;

use crate::common::{calbench, load_json, refused, root, tmp_dir};

#[test]
fn fk_refuses_a_length_that_overflows_in_mm() {
    let d = tmp_dir("strict-fk");
    let text = String::from_utf8(calbench(&["robots", "irb2600"]).stdout).unwrap();
    // The IRB2600 in metres, with a2 = 1e308 m: finite in the file, infinite in mm.
    let mut joint = 0;
    let metres: String = text
        .lines()
        .map(|l| {
            if l.starts_with("[[joints]]") {
                joint += 1;
            }
            if l == "length_unit = \"mm\"" {
                "length_unit = \"m\"".to_string()
            } else if joint == 2 && l.starts_with("a = ") {
                "a = 1e308".to_string()
            } else if let Some(v) = l.strip_prefix("d = ") {
                format!("d = {}", v.parse::<f64>().unwrap() / 1000.0)
            } else if let Some(v) = l.strip_prefix("a = ") {
                format!("a = {}", v.parse::<f64>().unwrap() / 1000.0)
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let huge = d.join("huge.toml");
    std::fs::write(&huge, metres.replace("a = 1e308", "a = 1.2")).unwrap();
    let h = huge.to_str().unwrap();
    let ok = calbench(&["fk", "--robot", h, "--q", "0,0,0,0,0,0", "--json"]);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    std::fs::write(&huge, &metres).unwrap();
    let o = calbench(&["fk", "--robot", h, "--q", "0,0,0,0,0,0", "--json"]);
    refused(&o, &["huge.toml", "joints[1]", "`a`"]);
    assert!(
        o.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
}

/// A URDF's numbers are checked as a robot file's: a NaN or 1e308 m origin, an infinite
/// angle, an axis of infinite length or a limit beyond ten turns is refused naming the URDF,
/// the joint and the element, where `fk` printed `NaN` and `identify` failed in the
/// registration without naming the file. So is a chain whose origins add up beyond 1 km, and
/// a file that is not well-formed XML (naming the line).
/// `calbench fk --robot DIR/NAME.urdf --q 0,0,0,0,0,0` on the URDF `text`, which prints
/// nothing to stdout.
fn fk_on_urdf(d: &Path, name: &str, text: &str) -> Output {
    let p = d.join(format!("{name}.urdf"));
    std::fs::write(&p, text).unwrap();
    let o = calbench(&["fk", "--robot", p.to_str().unwrap(), "--q", "0,0,0,0,0,0"]);
    assert!(
        o.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    o
}

/// Each refusal names the line of the element (it named `URDF` and no line).
#[test]
fn a_urdf_with_a_number_out_of_range_is_refused_naming_the_joint() {
    let d = tmp_dir("strict-urdf");
    let src = std::fs::read_to_string(root().join("examples/ipa-ur10/ur10.urdf")).unwrap();
    let fk = |name: &str, from: &str, to: &str| {
        assert!(src.contains(from), "{from}");
        fk_on_urdf(&d, name, &src.replacen(from, to, 1))
    };
    let tool = "<origin xyz=\"0.0 0.0 0.109\"";
    let o = fk("nan", tool, "<origin xyz=\"0.0 0.0 nan\"");
    refused(
        &o,
        &[
            "nan.urdf: line 72: joint \"tool_fixed\", <origin xyz>: must be a finite length",
            "got NaN m",
        ],
    );
    let o = fk("huge", tool, "<origin xyz=\"0.0 0.0 1e308\"");
    refused(
        &o,
        &[
            "huge.urdf: line 72: joint \"tool_fixed\", <origin xyz>:",
            "got 1e308 m, which is inf mm",
        ],
    );
    let o = fk(
        "rpy",
        "rpy=\"1.5707963267948966 0.0 0.0\"",
        "rpy=\"inf 0.0 0.0\"",
    );
    refused(
        &o,
        &[
            "rpy.urdf: line 26: joint \"shoulder_lift_joint\", <origin rpy>:",
            "got inf rad",
        ],
    );
    let o = fk("axis", "<axis xyz=\"0 0 1\"/>", "<axis xyz=\"0 0 1e308\"/>");
    refused(
        &o,
        &[
            "axis.urdf: line 19: joint \"shoulder_pan_joint\", <axis xyz>:",
            "finite length",
        ],
    );
    let o = fk("limit", "upper=\"6.283185307179586\"", "upper=\"1e9\"");
    refused(
        &o,
        &[
            "limit.urdf: line 20: joint \"shoulder_pan_joint\", <limit>:",
            "got 1000000000.0 rad",
        ],
    );
    // Not well-formed XML: the line, where the refusal had none ("Elements not properly
    // nested").
    let o = fk("nested", "</joint>", "</joint_>");
    refused(
        &o,
        &["nested.urdf: line 13: ill-formed document: expected `</joint>`, but `</joint_>`"],
    );
    // Two fixed origins of 600 m each put the first joint 1.2 km from the root.
    let zero = "<origin xyz=\"0.0 0.0 0.0\"";
    let far = src.replacen(zero, "<origin xyz=\"0.0 0.0 600.0\"", 2);
    let p = d.join("far.urdf");
    std::fs::write(&p, far).unwrap();
    let o = calbench(&["fk", "--robot", p.to_str().unwrap(), "--q", "0,0,0,0,0,0"]);
    refused(
        &o,
        &[
            "far.urdf: URDF: the robot the chain makes: base.xyz:",
            "within ±1000000 mm, got 1200000.0 mm",
        ],
    );
}

#[test]
fn check_refuses_files_that_are_not_comparable_summaries() {
    let d = tmp_dir("strict-check");
    let summary = root().join("results/baselines/ci-guard.json");
    let s = summary.to_str().unwrap();
    let real = load_json(&summary);
    let mut other = real.clone();
    other["scenario"] = serde_json::json!("another-study");
    let mut unrelated = real.clone();
    // Methods the real summary has none of, one name an entry (a summary has one entry per
    // method and poses); a summary alone, as per-trial values of entries it has no result of
    // are refused.
    unrelated.as_object_mut().unwrap().remove("per_trial");
    for (i, e) in unrelated["results"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .enumerate()
    {
        e["method"] = serde_json::json!(format!("pso{i}"));
    }
    // An unknown key inside an entry's block had been passed over, where one in the entry
    // is refused.
    let mut nested = real.clone();
    nested["results"][0]["validation_after_mm"]["bogus"] = 1.into();
    let mut eta = real.clone();
    let first = eta["results"][0]["eta"].as_object_mut().unwrap();
    first.values_mut().next().unwrap()["bogus"] = 1.into();
    // serde reads a struct from a list too: a list is said so, not by its length or its
    // second element's type.
    let list = "is a list, where a table of keys (a JSON object) stands";
    let cases = [
        ("empty.json", "{}".to_string(), "results"),
        ("notlist.json", r#"{"results": 3}"#.to_string(), "results"),
        ("array.json", "[1, 2]".to_string(), list),
        ("empty-array.json", "[]".to_string(), list),
        ("nested.json", nested.to_string(), "unknown field `bogus`"),
        ("eta.json", eta.to_string(), "unknown field `bogus`"),
        ("other.json", other.to_string(), "scenario"),
        ("unrelated.json", unrelated.to_string(), "shares no metric"),
    ];
    for (name, body, key) in cases {
        let p = d.join(name);
        std::fs::write(&p, body).unwrap();
        let p = p.to_str().unwrap();
        refused(&calbench(&["check", s, "--baseline", p]), &[name, key]);
        refused(&calbench(&["check", p, "--baseline", s]), &[name, key]);
    }
    let same = calbench(&["check", s, "--baseline", s]);
    assert!(same.status.success());
}

/// Found by fuzzing: a URDF whose links and joints do not make a tree was read as some tree,
/// where urdfdom refuses it. `examples/ipa-ur10/ur10.urdf` with the line `<link name="world"/>`
/// swapped with the start tag of the joint `wrist_3_joint` (which then holds every link and
/// joint after it, set aside unread) was read as a one-joint robot, and so was ROS-Industrial's
/// KUKA KR 10 R1420 URDF with its first `</joint>` moved to the end; with a joint or
/// a link written twice, or a second joint to the same child, one of the two was read and
/// `identify` wrote the other back unchanged; two joints' child links exchanged (a loop off
/// the chain) gave a one-joint robot too, and so did a `</robot>` after the first joint (the
/// elements after it read as roots of their own). Each is refused naming the file and the line.
#[test]
fn a_urdf_that_is_not_a_tree_is_refused_naming_the_line() {
    let d = tmp_dir("strict-urdf-tree");
    let src = std::fs::read_to_string(root().join("examples/ipa-ur10/ur10.urdf")).unwrap();
    let world = "  <link name=\"world\"/>";
    let wrist = "  <joint name=\"wrist_3_joint\" type=\"revolute\">";
    let swapped = src
        .replace(world, "@")
        .replace(wrist, world)
        .replace('@', wrist);
    let elbow = src.find("  <joint name=\"elbow_joint\"").unwrap();
    let elbow = &src[elbow..elbow + src[elbow..].find("</joint>").unwrap() + 8];
    let link_3 = "<link name=\"link_3\"/>";
    let cases = [
        (
            "nested",
            swapped,
            "nested.urdf: line 8: <link> inside the <joint> of line 7: links and joints are \
             children of <robot>",
        ),
        (
            "moved",
            src.replacen("  </joint>\n", "", 1)
                .replace("</robot>", "  </joint>\n</robot>"),
            "moved.urdf: line 13: <link> inside the <joint> of line 9",
        ),
        (
            "twice",
            src.replace(elbow, &format!("{elbow}\n{elbow}")),
            "twice.urdf: line 38: joint \"elbow_joint\": already declared on line 31",
        ),
        (
            "link",
            src.replace(link_3, &format!("{link_3}{link_3}")),
            "link.urdf: line 30: link \"link_3\": already declared on line 30",
        ),
        (
            "parents",
            src.replace(
                elbow,
                &format!("{elbow}\n{}", elbow.replace("\"elbow_joint\"", "\"e2\"")),
            ),
            "parents.urdf: line 38: joint \"e2\", <child link>: link \"link_3\" is already the \
             child of joint \"elbow_joint\" (line 31)",
        ),
        (
            "loop",
            src.replacen("<child link=\"link_1\"/>", "<child link=\"@\"/>", 1)
                .replacen("<child link=\"tcp\"/>", "<child link=\"link_1\"/>", 1)
                .replacen("<child link=\"@\"/>", "<child link=\"tcp\"/>", 1),
            "loop.urdf: line 47: joint \"wrist_2_joint\": the joints form a loop at link \"link_5\"",
        ),
        (
            "roots",
            src.replace(
                "<link name=\"tcp\"/>",
                "<link name=\"tcp\"/><link name=\"lone\"/>",
            ),
            "roots.urdf: line 68: link \"lone\": a second root link (no joint has it as its \
             child) besides \"world\"",
        ),
        (
            "after",
            src.replace("</robot>", "")
                .replacen("  </joint>\n", "  </joint>\n</robot>\n", 1),
            "after.urdf: line 15: <link> after the end of the root element on line 14",
        ),
        (
            "undeclared",
            src.replace(link_3, ""),
            "undeclared.urdf: line 31: joint \"elbow_joint\", <child link>: no link \"link_3\"",
        ),
    ];
    for (name, text, want) in cases {
        refused(&fk_on_urdf(&d, name, &text), &[want]);
    }
}

/// A value urdf-rs refuses inside an element calbench reads was refused naming no line
/// (`ur10.urdf: URDF: custom: Wrong vector element count, expected 3 found 2 for [0.0 0.1273]`),
/// and an `xyz` with a word among four numbers (`"0 zero 1 2"`) was read as the three numbers.
/// Each is refused naming the file, the line, the joint and the element.
#[test]
fn a_urdf_value_that_cannot_be_read_is_refused_naming_the_line() {
    let d = tmp_dir("strict-urdf-values");
    let src = std::fs::read_to_string(root().join("examples/ipa-ur10/ur10.urdf")).unwrap();
    let limit = "<limit lower=\"-6.283185307179586\"";
    let cases = [
        (
            "short",
            src.replace("xyz=\"0.0 0.0 0.1273\"", "xyz=\"0.0 0.1273\""),
            "short.urdf: line 26: joint \"shoulder_lift_joint\", <origin xyz>: \"0.0 0.1273\" \
             is not three numbers",
        ),
        (
            "word",
            src.replacen("<axis xyz=\"0 0 1\"/>", "<axis xyz=\"0 zero 1 2\"/>", 1),
            "word.urdf: line 19: joint \"shoulder_pan_joint\", <axis xyz>: \"0 zero 1 2\" is not \
             three numbers",
        ),
        (
            "limit",
            src.replacen(limit, "<limit lower=\"minus\"", 1),
            "limit.urdf: line 20: joint \"shoulder_pan_joint\", <limit lower>: \"minus\" is not \
             a number",
        ),
        (
            "entity",
            src.replacen(limit, "<limit lower=\"&foo;\"", 1),
            "entity.urdf: line 20: <limit lower>:",
        ),
        (
            "twice",
            src.replacen(limit, &format!("{limit} lower=\"0\""), 1),
            "twice.urdf: line 20: <limit>:",
        ),
        (
            "type",
            src.replacen("type=\"revolute\"", "type=\"revolve\"", 1),
            "type.urdf: line 15: joint \"shoulder_pan_joint\": type revolve is not a one-axis \
             joint (revolute, continuous, prismatic, fixed)",
        ),
        // A URDF type calbench does not read, refused at its line like an unknown one (which
        // urdf-rs had answered offering `floating`, `planar` and `spherical`).
        (
            "planar",
            src.replacen("type=\"revolute\"", "type=\"planar\"", 1),
            "planar.urdf: line 15: joint \"shoulder_pan_joint\": type planar is not a one-axis \
             joint (revolute, continuous, prismatic, fixed)",
        ),
        (
            "parent",
            src.replacen("<parent link=", "<parent name=", 1),
            "parent.urdf: line 10: joint \"base_placement\", <parent>: missing field `link`",
        ),
        (
            "origins",
            src.replacen("</joint>", "<origin xyz=\"0 0 0\"/></joint>", 1),
            "origins.urdf: line 9: joint \"base_placement\": duplicate field `origin`",
        ),
        (
            "nameless",
            src.replacen("<link name=\"link_2\"/>", "<link/>", 1),
            "nameless.urdf: line 22: <link>: missing field `name`",
        ),
        // A file of no element named urdf-rs's "No elements found"; a root that is not
        // <robot> and a <robot/> were read as robots of no link ("0 leaf links ()").
        (
            "empty",
            "<?xml version=\"1.0\"?>\n<!-- nothing -->\n".to_string(),
            "empty.urdf: URDF: no <robot> element",
        ),
        (
            "root",
            src.replace("<robot name=", "<robt name=")
                .replace("</robot>", "</robt>"),
            "root.urdf: line 6: the root element is <robt>: a URDF is one <robot> element",
        ),
        (
            "bare",
            "<robot name=\"bare\"/>\n".to_string(),
            "bare.urdf: URDF: the robot has no <link>",
        ),
        // A file cut short at a tag's end was "no <robot> element", naming no line.
        (
            "unclosed",
            src.replace("</robot>", ""),
            "the file ends inside <robot>: the <robot> of line 6 is not closed",
        ),
        (
            "cut",
            src[..src.find("<origin").unwrap()].to_string(),
            "cut.urdf: line 12: the file ends inside <joint>: the <robot> of line 6 is not closed",
        ),
        // Cut after a line's newline: its last line is the one the newline ends (it had
        // been refused at the line after the file's last).
        (
            "cut_line",
            src[..src.find("<origin").unwrap()]
                .trim_end_matches(' ')
                .to_string(),
            "cut_line.urdf: line 11: the file ends inside <joint>",
        ),
        // A robot without a name had been read as "" (`identify` wrote `-calibrated`), and a
        // name holding a character XML does not take was refused at a position in a piece
        // of the file ("Syntax: 1:16").
        (
            "robotless",
            src.replacen("<robot name=\"ur10\">", "<robot>", 1),
            "robotless.urdf: line 6: <robot>: its `name` is missing or empty",
        ),
        (
            "bell",
            src.replacen("<robot name=\"ur10\">", "<robot name=\"ur&#7;10\">", 1),
            "bell.urdf: line 6: <robot name>: \"ur\\u{7}10\" holds a control character",
        ),
    ];
    for (name, text, want) in cases {
        refused(&fk_on_urdf(&d, name, &text), &[want]);
    }
}

/// A text file that is not UTF-8 (a Latin-1 `°` in a comment, as a Windows editor saves it)
/// was refused as "stream did not contain valid UTF-8", naming no line. Scenario, robot and
/// mapping files (every text file calbench reads whole) name the line and the byte.
#[test]
fn a_file_that_is_not_utf8_is_refused_naming_the_line() {
    let d = tmp_dir("strict-utf8");
    let latin1 = |name: &str, from: &Path| {
        let text = std::fs::read(from).unwrap();
        let line = text.iter().position(|&b| b == b'\n').unwrap() + 1;
        let mut bytes = text[..line].to_vec();
        bytes.extend_from_slice(b"# 20 \xb0C\n");
        bytes.extend_from_slice(&text[line..]);
        let p = d.join(name);
        std::fs::write(&p, bytes).unwrap();
        p.to_str().unwrap().to_string()
    };
    let want = "line 2: not UTF-8 text: byte 6 of the line is 0xB0; save the file as UTF-8";
    let sc = latin1("s.toml", &root().join("scenarios/ci-guard.toml"));
    let out = d.join("out");
    let out = out.to_str().unwrap();
    refused(
        &calbench(&["run", &sc, "--out", out]),
        &[&format!("s.toml: {want}")],
    );
    let robot = latin1("r.toml", &root().join("examples/ipa-ur10/ur10.toml"));
    let q = ["--q", "0,0,0,0,0,0"];
    refused(
        &calbench(&[&["fk", "--robot", &robot], &q[..]].concat()),
        &[&format!("r.toml: {want}")],
    );
    let urdf = latin1("r.urdf", &root().join("examples/ipa-ur10/ur10.urdf"));
    refused(
        &calbench(&[&["fk", "--robot", &urdf], &q[..]].concat()),
        &[&format!("r.urdf: {want}")],
    );
    let mapping = latin1("m.toml", &root().join("examples/ipa-ur10/mapping.toml"));
    let raw = root().join("examples/ipa-ur10/sample-200.csv");
    let args = [
        "import",
        raw.to_str().unwrap(),
        "--mapping",
        &mapping,
        "--out",
        out,
    ];
    refused(&calbench(&args), &[&format!("m.toml: {want}")]);
    assert!(!Path::new(out).exists());
}

/// `calbench identify --robot irb2600 --data DATA --method lm --out OUT`.
fn identify_lm(data: &Path, out: &Path) -> Output {
    let (data, out) = (data.to_str().unwrap(), out.to_str().unwrap());
    let args = [
        "--robot", "irb2600", "--data", data, "--method", "lm", "--out", out,
    ];
    calbench(&[&["identify"][..], &args].concat())
}

#[test]
fn a_folder_given_as_a_measurement_file_is_an_io_error_of_its_path() {
    let d = tmp_dir("strict-folder-data");
    let out = d.join("out");
    let o = identify_lm(&d, &out);
    // It had been refused as a fault of its text: `line 1: cannot read the header`.
    let err = refused(&o, &[&format!("error: {}: ", d.display())]);
    assert!(
        !err.contains("line 1") && !err.contains("header") && !out.exists(),
        "{err}"
    );
}

/// A quote that opens a field and is not closed takes the separators and lines after it into
/// that field. The row had been refused by its field count alone; the refusal now names the
/// field, in a measurement file and in an export `import` reads.
#[test]
fn an_unclosed_quote_is_named_by_its_field() {
    let d = tmp_dir("strict-unclosed-quote");
    let out = d.join("out");
    let data = d.join("m.csv");
    std::fs::write(
        &data,
        "q1,q2,q3,q4,q5,q6,x,y,z\n1,2,3,4,5,6,\"7,8,9\n1,2,3,4,5,6,7,8,9\n",
    )
    .unwrap();
    refused(
        &identify_lm(&data, &out),
        &["m.csv: line 2: 7 fields, expected 9 as in the header: field 7 (column \"x\") is quoted"],
    );
    let raw = std::fs::read_to_string(root().join("examples/ipa-ur10/sample-200.csv")).unwrap();
    let mut lines: Vec<&str> = raw.lines().take(4).collect();
    let open = lines[2].replacen(";21,", ";\"21,", 1);
    assert_ne!(open, lines[2]);
    lines[2] = &open;
    let export = d.join("export.csv");
    std::fs::write(&export, lines.join("\n") + "\n").unwrap();
    let mapping = root().join("examples/ipa-ur10/mapping.toml");
    let args = [
        "import",
        export.to_str().unwrap(),
        "--mapping",
        mapping.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    refused(
        &calbench(&args),
        &["export.csv: line 3: 14 fields, expected 26 as in the header: field 14 (column \"measurement_temperature\") is quoted and runs on"],
    );
    assert!(!out.exists());
}

/// A URDF whose base hangs from its world by a `floating` joint (a mobile manipulator's): the
/// chain below `--base` is read as the same file with that joint fixed, where the whole file
/// had been refused for a joint the chain does not hold; the chain through it is still
/// refused, at that joint's line.
#[test]
fn a_floating_joint_off_the_chain_is_not_read() {
    let d = tmp_dir("strict-floating");
    let ur10 = root().join("examples/ipa-ur10/ur10.urdf");
    let src = std::fs::read_to_string(&ur10).unwrap();
    let floating = src.replacen(
        "<joint name=\"base_placement\" type=\"fixed\">",
        "<joint name=\"base_placement\" type=\"floating\">",
        1,
    );
    assert_ne!(floating, src);
    let file = d.join("floating.urdf");
    std::fs::write(&file, floating).unwrap();
    let q = "0.1,-0.5,0.7,-1.2,0.4,2.0";
    let fk = |robot: &Path| {
        let robot = robot.to_str().unwrap();
        calbench(&["fk", "--robot", robot, "--base", "base_link", "--q", q])
    };
    let (o, want) = (fk(&file), fk(&ur10));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.stdout, want.stdout);
    let whole = calbench(&["fk", "--robot", file.to_str().unwrap(), "--q", q]);
    refused(
        &whole,
        &["floating.urdf: line 9: joint \"base_placement\": type floating is not a one-axis joint"],
    );
}

/// A URDF joint with a `<mimic>` moves with another joint: on the chain it is refused at its
/// `<mimic>`'s line, where it had been read as a joint of its own (a seventh variable the data
/// do not give); off the chain (a gripper's second finger) it is not read.
#[test]
fn a_mimic_joint_is_refused_on_the_chain_only() {
    let d = tmp_dir("strict-mimic");
    let ur10 = root().join("examples/ipa-ur10/ur10.urdf");
    let src = std::fs::read_to_string(&ur10).unwrap();
    let mimic = "<mimic joint=\"wrist_2_joint\" multiplier=\"1\" offset=\"0\"/>";
    let child = "<child link=\"link_6\"/>";
    let on_chain = src.replacen(child, &format!("{child}\n    {mimic}"), 1);
    assert_ne!(on_chain, src);
    let fingers = "  <link name=\"finger_1\"/>\n  <link name=\"finger_2\"/>\n  \
        <joint name=\"finger_1_joint\" type=\"prismatic\">\n    <parent link=\"flange\"/>\n    \
        <child link=\"finger_1\"/>\n    <axis xyz=\"1 0 0\"/>\n    \
        <limit lower=\"0\" upper=\"0.04\" effort=\"1\" velocity=\"1\"/>\n  </joint>\n  \
        <joint name=\"finger_2_joint\" type=\"prismatic\">\n    <parent link=\"flange\"/>\n    \
        <child link=\"finger_2\"/>\n    <axis xyz=\"-1 0 0\"/>\n    \
        <limit lower=\"0\" upper=\"0.04\" effort=\"1\" velocity=\"1\"/>\n    \
        <mimic joint=\"finger_1_joint\"/>\n  </joint>\n</robot>";
    let gripper = src.replacen("</robot>", fingers, 1);
    let (on_chain_file, gripper_file) = (d.join("mimic.urdf"), d.join("gripper.urdf"));
    std::fs::write(&on_chain_file, on_chain).unwrap();
    std::fs::write(&gripper_file, gripper).unwrap();
    let q = "0.1,-0.5,0.7,-1.2,0.4,2.0";
    let fk = |robot: &Path, tip: &[&str]| {
        let mut args = vec!["fk", "--robot", robot.to_str().unwrap(), "--q", q];
        args.extend(tip);
        calbench(&args)
    };
    refused(
        &fk(&on_chain_file, &[]),
        &[
            "mimic.urdf: line 58: joint \"wrist_3_joint\" on the chain to \"tcp\" mimics joint \
             \"wrist_2_joint\"",
            "--tip",
        ],
    );
    let (o, want) = (fk(&gripper_file, &["--tip", "tcp"]), fk(&ur10, &[]));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.stdout, want.stdout);
    refused(
        &fk(&gripper_file, &["--tip", "finger_2"]),
        &["gripper.urdf: line 87: joint \"finger_2_joint\" on the chain to \"finger_2\" mimics joint \"finger_1_joint\""],
    );
}
