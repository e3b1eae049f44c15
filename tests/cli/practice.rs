//! Real-data practice end to end: cross-validation and model choice with a held-out split,
//! fixed parameters and priors, the diagnostics in identified.json, the controller exports,
//! `compensate --targets`, a URDF tree with `--tip`, and a 7-axis arm through `fk`,
//! `identifiability`, `identify` and `compensate`.

use std::path::Path;

use calbench::numeric::rng::stream;
use calbench::numeric::Real;
use calbench::robot::{builtin, Param};

use crate::common::{
    calbench, calbench_ok, load_json, path_arg, read, refused, root, tmp_dir, ur10_example as ex,
    ur10_positions,
};

/// The arguments of `calbench identify --robot ROBOT --data DATA --method lm EXTRA… --out OUT`.
fn lm_args<'a>(robot: &'a str, data: &'a str, extra: &[&'a str], out: &'a Path) -> Vec<&'a str> {
    let mut a = vec![
        "identify", "--robot", robot, "--data", data, "--method", "lm",
    ];
    a.extend_from_slice(extra);
    a.extend_from_slice(&["--out", path_arg(out)]);
    a
}

#[test]
fn cv_models_holdout_diagnostics_and_exports_on_the_ur10_rows() {
    let d = tmp_dir("practice-cv");
    let data = ur10_positions(&d).display().to_string();
    let out = d.join("cv");
    let o = calbench_ok(&lm_args(
        &ex("ur10.toml"),
        &data,
        &[
            "--holdout",
            "3/10",
            "--cv",
            "4",
            "--models",
            "kinematic,beta",
            "--export",
            "ur-yaml,dh-csv",
        ],
        &out,
    ));
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(text.contains("(best)"), "{text}");
    let j = load_json(&out.join("identified.json"));
    assert_eq!(j["holdout"], "3/10");
    let cv = &j["cv"];
    assert_eq!(cv["k"], 4);
    assert_eq!(cv["fold_rms"].as_array().unwrap().len(), 4);
    let rms = cv["rms"].as_f64().unwrap();
    let val = j["validation_after_mm"]["rms"].as_f64().unwrap();
    assert!(rms > 0.1 && rms < 3.0 * val, "CV {rms} vs validation {val}");
    assert_eq!(j["cv_models"].as_array().unwrap().len(), 2);
    assert_eq!(j["cv_best"], cv["model"]);
    // 199 rows: 140 for calibration, 59 held out.
    let diag = &j["diagnostics"];
    assert_eq!(diag["leverage"].as_array().unwrap().len(), 140);
    assert_eq!(diag["cook_distance"].as_array().unwrap().len(), 140);
    assert_eq!(diag["top_points"].as_array().unwrap().len(), 10);
    let t = j["parameters"].as_array().unwrap().len();
    assert_eq!(diag["correlation"].as_array().unwrap().len(), t);
    assert_eq!(diag["predicted"]["at"], "validation");
    assert!(diag["predicted"]["rms_mm"].as_f64().unwrap() > 0.0);
    let trace: Vec<f64> = j["convergence_trace"]["trace"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(
        trace.len() > 2 && trace[0] > 10.0 * trace[trace.len() - 1],
        "{trace:?}"
    );
    assert!((trace[trace.len() - 1] - j["rms_residual_mm"].as_f64().unwrap()).abs() < 1e-3);
    let yaml = read(&out.join("ur-kinematics.yaml"));
    for seg in [
        "kinematics:",
        "shoulder:",
        "upper_arm:",
        "forearm:",
        "wrist_1:",
        "wrist_2:",
        "wrist_3:",
    ] {
        assert!(yaml.contains(seg), "{seg}");
    }
    let dh = read(&out.join("dh-table.csv"));
    assert!(dh.starts_with("joint,parameter,unit,nominal,identified,delta,sigma\n"));
    let report = read(&out.join("report.md"));
    assert!(report.contains("## Model choice") && report.contains("## Diagnostics"));
    // report.html shows the same section, its tables from the same rows.
    let page = read(&out.join("report.html"));
    let section = &page[page
        .find("Cross-validation, priors and diagnostics</h2>")
        .expect("report.html has the practice section")..];
    for h in ["Cross-validation", "Model choice", "Diagnostics"] {
        assert!(section.contains(&format!("<h3>{h}</h3>")), "{h} missing");
    }
    assert!(
        section.contains("aria-label=\"Diagnostics\"") && section.contains("Cook&apos;s distance")
    );
    // A bad split rule and a --holdout with --validate are refused.
    let bad = calbench(&lm_args(
        &ex("ur10.toml"),
        &data,
        &["--holdout", "10/10"],
        &d.join("x"),
    ));
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("LAST/EVERY"));
    // `identify` of `data` with `extra` refused with exit status 1 and nothing written: its
    // stderr.
    let refusal = |data: &str, extra: &[&str]| {
        let bad = calbench(&lm_args(&ex("ur10.toml"), data, extra, &d.join("x")));
        let msg = String::from_utf8_lossy(&bad.stderr).to_string();
        assert_eq!(bad.status.code(), Some(1), "{msg}");
        assert!(!d.join("x").exists());
        msg
    };
    // A rule that holds out no row of the data (a block longer than the file) is refused
    // naming the option, not as data without points.
    let msg = refusal(&data, &["--holdout", "1/1000"]);
    assert!(
        msg.contains("setting `--holdout`: `1/1000` holds out no row"),
        "{msg}"
    );
    // A rule that holds out fewer than 3 distinct poses is refused as a validation file of
    // them is; one row held out had been scored alone.
    let msg = refusal(&data, &["--holdout", "1/100"]);
    assert!(
        msg.contains("setting `--holdout`: `1/100` holds out 1 of the data's 199 rows")
            && msg.contains("of fewer than 3 distinct poses"),
        "{msg}"
    );
    // So is one that leaves fewer than 3 distinct poses to calibrate, naming the option: the
    // data file had been blamed ("registration needs at least 3 points").
    let msg = refusal(&data, &["--holdout", "198/199"]);
    assert!(
        msg.contains("setting `--holdout`: `198/199` leaves 1 of the data's 199 rows")
            && msg.contains("of fewer than 3 distinct poses: a calibration, as a data file"),
        "{msg}"
    );
    // A seed of folds without folds would change nothing, and is refused.
    let msg = refusal(&data, &["--cv-seed", "3"]);
    assert!(
        msg.contains("setting `--cv-seed`: seeds the folds of --cv or --models"),
        "{msg}"
    );
    // A model listed twice, under one name or two, would be cross-validated twice.
    for (twice, name) in [
        ("kinematic,kinematic", "kinematic"),
        ("beta+gravity,kinematic,gravity+beta", "beta+gravity"),
    ] {
        let msg = refusal(&data, &["--models", twice]);
        let says = format!("setting `--models`: `{name}` is listed twice");
        assert!(msg.contains(&says), "{msg}");
    }
    // Validation rows that repeat calibration rows are refused, named by their file and
    // rows: the data given as their own validation (said to be the data's own file), and a
    // file holding its rows twice held out from.
    let msg = refusal(&data, &["--validate", &data]);
    let own = format!("setting `--validate`: {data} is the data's own file: 199 validation row(s)");
    assert!(
        msg.contains(&own) && msg.contains("calibration row 0 = validation row 0, "),
        "{msg}"
    );
    // So are the same rows with their orientation columns (the file they were cut from), and
    // every tenth row with x nudged by 0.00001 mm: copies, not second readings.
    let all = d.join("all.csv");
    let msg = refusal(&data, &["--validate", path_arg(&all)]);
    let named = format!(
        "setting `--validate`: {}: 199 validation row(s) repeat",
        all.display()
    );
    assert!(msg.contains(&named), "{msg}");
    let text = read(Path::new(&data));
    let x = text
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == "x");
    let nudged: Vec<String> = text
        .lines()
        .enumerate()
        .filter(|(i, _)| i % 10 == 0)
        .map(|(i, line)| {
            let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
            if i > 0 {
                let x = x.expect("a column x");
                cells[x] = (cells[x].parse::<f64>().unwrap() + 1e-5).to_string();
            }
            cells.join(",")
        })
        .collect();
    let nudged_file = d.join("nudged.csv");
    std::fs::write(&nudged_file, nudged.join("\n") + "\n").unwrap();
    let msg = refusal(&data, &["--validate", path_arg(&nudged_file)]);
    assert!(
        msg.contains(&format!(
            "setting `--validate`: {}: 19 validation row(s) repeat a calibration row",
            nudged_file.display()
        )) && msg.contains("calibration row 9 = validation row 0, "),
        "{msg}"
    );
    let twice = d.join("twice.csv");
    let rows = text.split_once('\n').unwrap().1;
    std::fs::write(&twice, format!("{text}{rows}")).unwrap();
    // A file that holds its rows twice is refused as such, held out from or not: each copy
    // would count its reading twice and halve the variance the fit states.
    for extra in [&["--holdout", "3/10"][..], &[]] {
        let msg = refusal(path_arg(&twice), extra);
        let says = format!(
            "{}: data: 199 row(s) repeat an earlier row (the same joint values and measured \
             point; 0-based rows): row 0 = row 199, row 1 = row 200, ",
            twice.display()
        );
        assert!(
            msg.contains(&says) && msg.contains(", and 194 more;"),
            "{msg}"
        );
    }
    // One row copied once, nudged by 0.00001 mm, is a copy too.
    let lines: Vec<&str> = text.lines().collect();
    let mut cells: Vec<String> = lines[5].split(',').map(str::to_string).collect();
    let x = x.expect("a column x");
    cells[x] = (cells[x].parse::<f64>().unwrap() + 1e-5).to_string();
    let once = d.join("once.csv");
    std::fs::write(&once, format!("{text}{}\n", cells.join(","))).unwrap();
    let msg = refusal(path_arg(&once), &[]);
    assert!(msg.contains(": data: 1 row(s) repeat an earlier row (the same joint values and measured point; 0-based rows): row 4 = row 199; a copy counts"), "{msg}");
    // Folds whose rows cannot determine the model are refused, not scored: 14 rows in two
    // folds train on 7 points, 21 readings for the 23 parameters.
    let few = d.join("few.csv");
    let head: Vec<&str> = text.lines().take(15).collect();
    std::fs::write(&few, head.join("\n") + "\n").unwrap();
    let msg = refusal(path_arg(&few), &["--cv", "2"]);
    assert!(
        msg.contains("setting `--cv`: fold 1 of 2: the model `kinematic` identified on")
            && msg.contains("(21 readings for 23 parameters)"),
        "{msg}"
    );
    // ur-yaml of a robot that is not UR-like (an mdh robot) is refused before its data are
    // read: on these 5 rows, outside its limits, it had been the rows that were refused, and
    // on rows it takes it was refused only after the identification.
    let five = d.join("five.csv");
    std::fs::write(&five, head[..6].join("\n") + "\n").unwrap();
    let bad = calbench(&lm_args(
        "irb2600-mdh",
        path_arg(&five),
        &["--export", "ur-yaml"],
        &d.join("y"),
    ));
    let err = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(bad.status.code(), Some(1), "{err}");
    assert!(err.contains("ur-yaml needs a UR-like robot"), "{err}");
    assert!(!d.join("y").exists());
    // Nor of a URDF robot, read into DH frames that are not UR's: from the UR10's URDF the
    // file described another arm (joint 1 turned by 180°, d6 in the tool), 176 mm apart.
    let urdf = ex("ur10.urdf");
    let o = calbench(&lm_args(
        &urdf,
        &data,
        &["--export", "ur-yaml"],
        &d.join("urdf-yaml"),
    ));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("a URDF's joints are read into DH frames of calbench's choosing, not UR's"),
        "{err}"
    );
    assert!(!d.join("urdf-yaml").exists());
}

#[test]
fn fix_holds_and_a_prior_pulls_towards_nominal() {
    let d = tmp_dir("practice-prior");
    let data = ur10_positions(&d).display().to_string();
    let robot = ex("ur10.toml");
    let run = |extra: &[&str], name: &str| {
        let out = d.join(name);
        calbench_ok(&lm_args(&robot, &data, extra, &out));
        load_json(&out.join("identified.json"))
    };
    let free = run(&[], "free");
    let a2 = free["errors"]["a2"].as_f64().unwrap();
    assert!(a2.abs() > 0.05, "a2 moves freely ({a2} mm)");
    let fixed = run(&["--fix", "a2,theta3"], "fix");
    assert!(fixed["errors"].get("a2").is_none() && fixed["errors"].get("theta3").is_none());
    assert_eq!(fixed["fixed"], serde_json::json!(["a2", "theta3"]));
    let prior = run(&["--prior", "a2=0.001"], "prior");
    let p = prior["errors"]["a2"].as_f64().unwrap();
    assert!(p.abs() < 0.1 * a2.abs(), "{a2} -> {p}");
    let moved = &prior["priors"][0];
    assert_eq!(moved["parameter"], "a2");
    assert!((moved["without_prior"].as_f64().unwrap() - a2).abs() < 1e-9);
    // The same prior from a file; a loose prior hardly moves the estimate.
    let f = d.join("priors.toml");
    std::fs::write(&f, "a2 = 1000.0\n").unwrap();
    let loose = run(&["--prior", path_arg(&f)], "loose");
    assert!((loose["errors"]["a2"].as_f64().unwrap() - a2).abs() < 1e-3 * a2.abs());
    // A prior on a fixed parameter, and a bad σ, are refused.
    let bad = calbench(&lm_args(
        &ex("ur10.toml"),
        &data,
        &["--fix", "a2", "--prior", "a2=0.1"],
        &d.join("bad"),
    ));
    let said = String::from_utf8_lossy(&bad.stderr);
    assert!(
        said.contains("setting `--prior`: `a2` is not among the identified parameters"),
        "{said}"
    );
    let bad = calbench(&lm_args(
        &ex("ur10.toml"),
        &data,
        &["--prior", "a2=-1"],
        &d.join("bad2"),
    ));
    assert!(!bad.status.success());
    // A parameter given two priors (on the command line, or there and in a file) is refused:
    // neither σ would be the one the estimate used.
    std::fs::write(d.join("a2.toml"), "a2 = 0.5\n").unwrap();
    for twice in [
        ["--prior", "a2=0.1", "--prior", "a2=0.2"],
        ["--prior", path_arg(&d.join("a2.toml")), "--prior", "a2=0.2"],
    ] {
        let o = calbench(&lm_args(&robot, &data, &twice, &d.join("twice")));
        let said = String::from_utf8_lossy(&o.stderr);
        assert!(
            said.contains("setting `--prior`: `a2` is given twice"),
            "{said}"
        );
        assert!(!d.join("twice").exists());
    }
    // A σ whose precision 1/σ² overflows is refused at its key, in a file as inline; so is
    // a parameter the robot lacks, in a file (it had been refused as `--prior`'s alone).
    std::fs::write(d.join("tiny.toml"), "a2 = 1e-300\n").unwrap();
    std::fs::write(d.join("nine.toml"), "a2 = 0.5\ntheta9 = 1.0\n").unwrap();
    for (arg, says) in [
        (
            path_arg(&d.join("tiny.toml")),
            "tiny.toml: line 1, key `a2`: σ = 1e-300 is too small",
        ),
        (
            path_arg(&d.join("nine.toml")),
            "nine.toml: line 2, key `theta9`: `theta9` is not a parameter of robot",
        ),
        (
            "a2=1e-300",
            "σ = 1e-300 is too small: its precision 1/σ² overflows",
        ),
    ] {
        let o = calbench(&lm_args(&robot, &data, &["--prior", arg], &d.join("tiny")));
        let said = String::from_utf8_lossy(&o.stderr);
        assert!(said.contains(says), "{said}");
    }
    // The smallest σ whose precision is finite still identifies, the parameter held nominal.
    let held = run(&["--prior", "a2=1e-150"], "held");
    assert!(
        held["errors"]["a2"].as_f64().unwrap().abs() < 1e-9,
        "{held}"
    );
    // A prior file's refusals name the file, the line and the key, as a run's error (exit 1),
    // not as a malformed command line.
    for (i, (text, says)) in [
        (
            "a2 = 0.1\nzz9 = 0.1\n",
            "line 2, key `zz9`: `zz9` is not a parameter name",
        ),
        ("a2 = 0.1\n\na3 = \"x\"\n", "line 3, key `a3`"),
        ("a2 = \n", "line 1: string values must be quoted"),
        ("# nothing\n", "priors: holds no `NAME = σ` line"),
        (
            "a2 = 0.1\nbase.x = 1.0\n",
            "line 2, key `base`: `base.x` is read by TOML as the key `x` of a table `base`: \
             quote a parameter name that holds a dot, \"base.x\" = σ",
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let f = d.join(format!("bad-priors-{i}.toml"));
        std::fs::write(&f, text).unwrap();
        let o = calbench(&lm_args(
            &robot,
            &data,
            &["--prior", path_arg(&f)],
            &d.join("bad3"),
        ));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains(&format!("bad-priors-{i}.toml: {says}")),
            "{err}"
        );
        assert!(!d.join("bad3").exists());
    }
}

#[test]
fn compensate_targets_reaches_cartesian_targets_on_the_identified_robot() {
    let d = tmp_dir("practice-targets");
    let data = ur10_positions(&d).display().to_string();
    let out = d.join("id");
    calbench_ok(&lm_args(&ex("ur10.toml"), &data, &[], &out));
    let nominal = builtin::load(ex("ur10.toml")).unwrap();
    let ident = builtin::load(out.join("robot.toml").to_str().unwrap()).unwrap();
    let mut g = stream(4, "targets");
    let qs = calbench::robot::sampling::uniform_joint_poses(&nominal, 8, &mut g);
    let mut pos = String::from("x,y,z\n");
    let mut full = String::from("x,y,z,qw,qx,qy,qz\n");
    for q in &qs {
        let f = nominal.fk(q);
        let q4 = calbench::numeric::quaternion(&f.rot);
        pos += &format!("{},{},{}\n", f.pos.x, f.pos.y, f.pos.z);
        full += &format!(
            "{},{},{},{},{},{},{}\n",
            f.pos.x, f.pos.y, f.pos.z, q4[0], q4[1], q4[2], q4[3]
        );
    }
    let identified = out.join("robot.toml");
    let compensate = |targets: &Path, corrected: &Path| {
        calbench(&[
            "compensate",
            "--robot",
            &ex("ur10.toml"),
            "--identified",
            path_arg(&identified),
            "--targets",
            path_arg(targets),
            "--out",
            path_arg(corrected),
        ])
    };
    for (name, text, pose) in [("pos", pos, false), ("full", full, true)] {
        let t = d.join(format!("{name}.csv"));
        std::fs::write(&t, text).unwrap();
        let c = d.join(format!("{name}-out.csv"));
        let o = compensate(&t, &c);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let written = read(&c);
        let mut lines = written.lines();
        assert_eq!(
            lines.next().unwrap(),
            "q1,q2,q3,q4,q5,q6,residual_mm,residual_deg,flag"
        );
        for (line, q) in lines.zip(&qs) {
            let cells: Vec<&str> = line.split(',').collect();
            assert_eq!(cells[8], "ok", "{line}");
            let user: Vec<Real> = cells[..6].iter().map(|c| c.parse().unwrap()).collect();
            let f = ident.fk(&ident.q_from_user(&user));
            let t = nominal.fk(q);
            assert!((f.pos - t.pos).norm() < 1e-6);
            if pose {
                let r = calbench::numeric::rotation_vector(&(f.rot.transpose() * t.rot)).norm();
                assert!(r < 1e-8);
            }
        }
    }
    // A targets file without z, or with a column of its own, is refused by line and column;
    // the columns expected are the Cartesian ones.
    for (text, says) in [
        ("x,y\n1,2\n", "\"z\""),
        (
            "x,y,z,w\n1,2,3,4\n",
            "line 1, column 4: unknown column \"w\" (expected x, y, z and optionally qw",
        ),
    ] {
        let t = d.join("bad.csv");
        std::fs::write(&t, text).unwrap();
        let bad = compensate(&t, &d.join("o.csv"));
        let err = String::from_utf8_lossy(&bad.stderr);
        assert!(err.contains(says), "{err}");
    }
}

#[test]
fn a_urdf_tree_with_tip_gives_the_single_chain() {
    let d = tmp_dir("practice-tree");
    let src = read(std::path::Path::new(&ex("ur10.urdf")));
    let extra = "<link name=\"sensor\"/><joint name=\"sensor_joint\" type=\"fixed\">\
        <parent link=\"base_link\"/><child link=\"sensor\"/><origin xyz=\"0.1 0 0\" rpy=\"0 0 0\"/></joint>";
    let tree = d.join("tree.urdf");
    std::fs::write(&tree, src.replace("</robot>", &format!("{extra}</robot>"))).unwrap();
    let one = builtin::load(ex("ur10.urdf")).unwrap();
    let tip =
        calbench::robot::urdf::UrdfRobot::load(std::path::Path::new(&ex("ur10.urdf"))).unwrap();
    let leaf = {
        let s = read(std::path::Path::new(&ex("ur10.urdf")));
        let links: Vec<String> = s
            .split("<link name=\"")
            .skip(1)
            .map(|t| t[..t.find('"').unwrap()].to_string())
            .collect();
        links
            .into_iter()
            .find(|l| !s.contains(&format!("<parent link=\"{l}\"")))
            .unwrap()
    };
    let q = "0.1,-1.2,1.0,-0.5,1.4,0.3";
    let a = calbench_ok(&["fk", "--robot", &ex("ur10.urdf"), "--q", q, "--json"]);
    let b = calbench_ok(&[
        "fk",
        "--robot",
        path_arg(&tree),
        "--tip",
        &leaf,
        "--q",
        q,
        "--json",
    ]);
    assert_eq!(a.stdout, b.stdout);
    // A leaf that hangs from the root through fixed joints alone (the `base` frame of
    // ROS-Industrial's URDFs) cannot end the chain: the tree needs no --tip.
    let c = calbench_ok(&["fk", "--robot", path_arg(&tree), "--q", q, "--json"]);
    assert_eq!(a.stdout, c.stdout);
    // A second leaf behind a moving joint (a sensor on a pan axis) does.
    let pan = "<link name=\"pan\"/><joint name=\"pan_joint\" type=\"revolute\">\
        <parent link=\"base_link\"/><child link=\"pan\"/><axis xyz=\"0 0 1\"/>\
        <limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>";
    let two = d.join("two.urdf");
    std::fs::write(
        &two,
        src.replace("</robot>", &format!("{extra}{pan}</robot>")),
    )
    .unwrap();
    let refused = calbench(&["fk", "--robot", path_arg(&two), "--q", q]);
    assert_eq!(refused.status.code(), Some(1));
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        err.contains(&format!("2 leaf links ({leaf}, pan)")) && err.contains("--tip LINK"),
        "{err}"
    );
    let b2 = calbench_ok(&[
        "fk",
        "--robot",
        path_arg(&two),
        "--tip",
        &leaf,
        "--q",
        q,
        "--json",
    ]);
    assert_eq!(a.stdout, b2.stdout);
    let refused = calbench(&["fk", "--robot", path_arg(&tree), "--tip", "nope", "--q", q]);
    assert!(String::from_utf8_lossy(&refused.stderr).contains("no link \"nope\""));
    // A chain of a robot that is no URDF, named by the option given (`--base` alone had
    // been refused as `--tip`).
    for option in ["--tip", "--base"] {
        let refused = calbench(&[
            "fk",
            "--robot",
            "irb2600",
            option,
            "x",
            "--q",
            "0,0,0,0,0,0",
        ]);
        let e = String::from_utf8_lossy(&refused.stderr);
        assert!(
            e.contains(&format!("setting `{option}`: ")) && e.contains("\"irb2600\" is not one"),
            "{e}"
        );
    }
    // The sensor chain from the root: a fixed chain has no joints.
    assert_eq!(tip.robot.dof(), one.dof());
}

/// A 7-axis arm (an iiwa-like DH table) with injected errors through every command.
#[test]
fn a_seven_axis_arm_end_to_end() {
    let d = tmp_dir("practice-seven");
    let dh = [
        (340.0, -90.0),
        (0.0, 90.0),
        (400.0, 90.0),
        (0.0, -90.0),
        (400.0, -90.0),
        (0.0, 90.0),
        (126.0, 0.0),
    ];
    let mut text = String::from(
        "name = \"seven\"\nconvention = \"dh\"\nlength_unit = \"mm\"\nangle_unit = \"deg\"\n",
    );
    for (dd, al) in dh {
        text += &format!("\n[[joints]]\ntype = \"revolute\"\nalpha = {al}\na = 0.0\nd = {dd}\ntheta = 0.0\nlimits = [-170.0, 170.0]\n");
    }
    let r7 = d.join("r7.toml");
    std::fs::write(&r7, text).unwrap();
    let nominal = builtin::load(path_arg(&r7)).unwrap();
    assert_eq!(nominal.dof(), 7);
    let errors: Vec<(Param, Real)> = (0..7)
        .flat_map(|j| {
            [
                (Param::D(j), 0.3 - 0.1 * j as Real),
                (Param::Theta(j), 1e-3 * (j as Real - 3.0)),
            ]
        })
        .collect();
    let truth = nominal.with_errors(&errors);
    let mut g = stream(7, "seven");
    let qs = calbench::robot::sampling::uniform_joint_poses(&nominal, 80, &mut g);
    let mut m = (1..=7).map(|j| format!("q{j},")).collect::<String>() + "x,y,z\n";
    for q in &qs {
        let p = truth.fk(q).pos;
        for v in nominal.q_to_user(q) {
            m += &format!("{v:.12},");
        }
        m += &format!("{:.9},{:.9},{:.9}\n", p.x, p.y, p.z);
    }
    let data = d.join("m7.csv");
    std::fs::write(&data, m).unwrap();
    calbench_ok(&[
        "fk",
        "--robot",
        path_arg(&r7),
        "--q",
        "10,20,30,40,50,60,70",
    ]);
    calbench_ok(&[
        "identifiability",
        "--robot",
        path_arg(&r7),
        "--poses-file",
        path_arg(&data),
    ]);
    let out = d.join("id");
    calbench_ok(&lm_args(
        path_arg(&r7),
        path_arg(&data),
        &["--cv", "3", "--export", "dh-csv"],
        &out,
    ));
    let j = load_json(&out.join("identified.json"));
    assert!(
        j["rms_residual_mm"].as_f64().unwrap() < 1e-4,
        "{}",
        j["rms_residual_mm"]
    );
    assert!(j["cv"]["rms"].as_f64().unwrap() < 1e-3);
    let program = d.join("program.csv");
    let rows: String = (1..=7)
        .map(|j| format!("q{j}"))
        .collect::<Vec<_>>()
        .join(",")
        + "\n10,20,30,40,50,60,70\n-10,25,-30,45,20,-60,5\n";
    std::fs::write(&program, rows).unwrap();
    let c = d.join("c.csv");
    calbench_ok(&[
        "compensate",
        "--robot",
        path_arg(&r7),
        "--identified",
        path_arg(&out.join("robot.toml")),
        "--joints",
        path_arg(&program),
        "--out",
        path_arg(&c),
    ]);
    assert!(
        read(&c).lines().skip(1).all(|l| l.ends_with(",ok")),
        "{}",
        read(&c)
    );
}

/// A scenario's `priors` in `[[methods]]` run under the entry's label, and a bad σ is
/// refused naming `priors.NAME`.
#[test]
fn scenario_priors_run_and_bad_ones_are_named() {
    let d = tmp_dir("practice-scenario-priors");
    let base = read(&root().join("scenarios/ci-guard.toml"));
    let text = base.replace(
        "name = \"lm\"",
        "name = \"lm\"\n\n[[methods]]\nname = \"lm\"\nlabel = \"lm-prior\"\npriors = { a2 = 0.001 }",
    );
    let s = d.join("s.toml");
    // `calbench run` of the scenario with the entry's priors `priors`, into `d/OUT`.
    let run = |priors: &str, out: &str| {
        std::fs::write(&s, text.replace("a2 = 0.001", priors)).unwrap();
        calbench(&[
            "run",
            path_arg(&s),
            "--trials",
            "2",
            "--out",
            path_arg(&d.join(out)),
        ])
    };
    let o = run("a2 = 0.001", "out");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = load_json(&d.join("out").join("summary.json"));
    let text_summary = summary.to_string();
    assert!(text_summary.contains("lm-prior"));
    let bad = run("a2 = 0", "bad");
    assert!(String::from_utf8_lossy(&bad.stderr).contains("priors.a2"));
    // An unquoted dotted name is a table to TOML: refused saying to quote it.
    let bad = run("base.x = 0.5", "bad");
    refused(
        &bad,
        &[
            "priors.base: `base.x` is read by TOML as the key `x` of a table",
            "\"base.x\" = σ",
        ],
    );
    // Quoted, it is the base's x.
    let o = run("\"base.x\" = 0.5", "quoted");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
