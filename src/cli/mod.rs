//! The commands of the `calbench` binary, one function each: they call the library, print
//! to stdout and write files through [`calbench::report`]; `main.rs` parses arguments and
//! reports errors.

use std::io::Write as _;
use std::path::{Path, PathBuf};

/// `println!` that ignores a closed stdout (`calbench … | head`): results are on disk before
/// anything is printed, and a reader that stops early is not an error.
macro_rules! out {
    ($($arg:tt)*) => {{
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// `print!` likewise.
macro_rules! out_raw {
    ($($arg:tt)*) => {{
        let _ = write!(std::io::stdout(), $($arg)*);
    }};
}

use serde_json::json;

use calbench::calibrate::{calibrate, Registration, RoundsEnd};
use calbench::error::{Error, Result};
use calbench::identify::{method_by_name, Termination};
use calbench::measurement::csv::{read_measurements, write_measurements, write_pose_list};
use calbench::measurement::Measure;
use calbench::numeric::{Frame, Real};
use calbench::poses::{RobotPoseModel, SelectOptions, Strategy as Optimiser};
use calbench::report::check::{compare, read_json, Regression};
use calbench::report::identified::{validate_file, write_identified, IdentifyRecord};
use calbench::report::markdown::table as markdown_table;
use calbench::report::{entry_table, run_study};
use calbench::robot::builtin::{self, BUILTINS};
use calbench::robot::compliance::CompliancePick;
use calbench::robot::identifiability::analyse;
use calbench::robot::param_sets;
use calbench::robot::robot_to_toml;
use calbench::sim::measure_poses;
use calbench::sim::poses::sample_region;
use calbench::study::registration_study::RegistrationScenario;
use calbench::study::scenario::Scenario;
use calbench::study::{self, plan, trial, RunOptions, RunResult, Study};

/// `calbench robots [NAME]`.
pub fn robots(name: Option<&str>) -> Result<()> {
    match name {
        None => {
            for b in BUILTINS {
                out!("{:<12} {}", b.name, b.summary);
            }
            Ok(())
        }
        Some(n) => {
            let b = builtin::builtin(n).ok_or_else(|| {
                let names: Vec<&str> = BUILTINS.iter().map(|b| b.name).collect();
                Error::setting(
                    "NAME",
                    format!("no built-in robot \"{n}\"; built-ins: {}", names.join(", ")),
                )
            })?;
            out_raw!("# {}\n{}", b.summary, robot_to_toml(&(b.build)()));
            Ok(())
        }
    }
}

/// The comma-separated values of option `key`'s `text`, each trimmed and parsed as `T`; a
/// value that does not parse or that `valid` refuses is an error with the message `not(value)`
/// (the value as written).
fn parse_list<T: std::str::FromStr>(
    text: &str,
    key: &str,
    valid: impl Fn(&T) -> bool,
    not: impl Fn(&str) -> String,
) -> Result<Vec<T>> {
    text.split(',')
        .map(|s| {
            s.trim()
                .parse::<T>()
                .ok()
                .filter(|v| valid(v))
                .ok_or_else(|| Error::setting(key, not(s)))
        })
        .collect()
}

/// Parses a comma-separated list of numbers (joint values) for a robot with `dof` joints.
pub fn parse_q(text: &str, dof: usize) -> Result<Vec<Real>> {
    let q = parse_list(
        text,
        "--q",
        |v: &Real| v.is_finite(),
        |s| format!("\"{}\" is not a finite number", s.trim()),
    )?;
    if q.len() != dof {
        return Err(Error::joint_count("--q", "the values given", q.len(), dof));
    }
    Ok(q)
}

/// Parses `position` / `pose`.
pub fn parse_measure(text: &str) -> Result<Measure> {
    match text {
        "position" => Ok(Measure::Position),
        "pose" => Ok(Measure::Pose),
        other => Err(Error::setting(
            "--measure",
            format!("\"{other}\"; allowed: position, pose"),
        )),
    }
}

/// `calbench fk --robot R --q … [--json]`.
pub fn fk(robot: &str, q: &str, json: bool) -> Result<()> {
    let robot = builtin::load(robot)?;
    let q = robot.q_from_user_checked(&parse_q(q, robot.dof())?, "--q")?;
    let f = robot.fk(&q);
    let rot: Vec<[Real; 3]> = (0..3)
        .map(|i| [f.rot[(i, 0)], f.rot[(i, 1)], f.rot[(i, 2)]])
        .collect();
    if json {
        out!(
            "{}",
            json!({"position_mm": [f.pos.x, f.pos.y, f.pos.z], "rotation": rot})
        );
    } else {
        out!(
            "position (mm): {:.6} {:.6} {:.6}",
            f.pos.x,
            f.pos.y,
            f.pos.z
        );
        out!("rotation:");
        for r in rot {
            out!("  {:>10.6} {:>10.6} {:>10.6}", r[0], r[1], r[2]);
        }
    }
    if !robot.within_limits(&q) {
        eprintln!("warning: the joint values lie outside the robot's joint limits");
    }
    Ok(())
}

/// `calbench identifiability --robot R --measure M --poses N --seed S [--json]`.
pub fn identifiability(
    robot: &str,
    measure: &str,
    poses: usize,
    seed: u64,
    poses_file: Option<&Path>,
    gcn_blocks: Option<Real>,
    json: bool,
) -> Result<()> {
    let robot = builtin::load(robot)?;
    if let Some(t) = gcn_blocks {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::setting(
                "--gcn-threshold",
                format!("must be a finite number > 0, got {t}"),
            ));
        }
    }
    let measure = parse_measure(measure)?;
    if poses == 0 {
        return Err(Error::setting("--poses", "must be at least 1"));
    }
    let qs = match poses_file {
        Some(p) => calbench::sim::poses::read_pose_list(p, &robot)?,
        None => {
            let mut rng = calbench::numeric::rng::stream(seed, "identifiability");
            calbench::robot::sampling::uniform_joint_poses(&robot, poses, &mut rng)
        }
    };
    let poses = qs.len();
    let a = analyse(&robot, &robot.params(), &qs, measure);
    let names = |v: &[calbench::robot::Param]| v.iter().map(|p| p.to_string()).collect::<Vec<_>>();
    // Guo 2024 §3.1: the separation of the joint parameters (θ, α, a, d, β blocks).
    let sep = gcn_blocks
        .map(|t| calbench::poses::separate(&robot, &robot.joint_params(), &qs, measure, t));
    if json {
        let groups: Vec<Vec<String>> = a.groups.iter().map(|g| names(g)).collect();
        let mut v = json!({
            "rank": a.rank,
            "identifiable": names(&a.identifiable),
            "unidentifiable": names(&a.unidentifiable),
            "groups": groups,
            "condition_number": a.condition_number,
        });
        if let (Some(sep), Some(obj)) = (&sep, v.as_object_mut()) {
            if let Some(extra) = sep.to_json().as_object() {
                obj.extend(extra.clone());
            }
        }
        out!("{v}");
    } else {
        out!("robot {} ({} poses, {:?})", robot.name, poses, measure);
        out!("rank {} of {} parameters", a.rank, robot.params().len());
        out!("identifiable:   {}", names(&a.identifiable).join(" "));
        out!("unidentifiable: {}", names(&a.unidentifiable).join(" "));
        for g in &a.groups {
            out!("dependent group: {}", names(g).join(" "));
        }
        out!(
            "condition number (column-scaled): {:.4e}",
            a.condition_number
        );
        if let Some(sep) = &sep {
            out!("GCN per block (Guo 2024 eq. 14), before and after the separation:");
            for b in &sep.blocks {
                out!(
                    "  {:<6} {:>12.4e} {:>12.4e}",
                    b.name,
                    b.gcn_before,
                    b.gcn_after
                );
            }
            out!("removed: {}", names(&sep.removed).join(" "));
            out!(
                "GCN full model {:.4e}, separated {:.4e}",
                sep.gcn_full(),
                sep.gcn_separated()
            );
        }
    }
    Ok(())
}

fn write_file(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}

fn to_json_text(v: &serde_json::Value) -> Result<String> {
    serde_json::to_string_pretty(v)
        .map(|s| s + "\n")
        .map_err(|e| Error::Compute(e.to_string()))
}

/// `calbench simulate SCENARIO [--trial I] --out DIR`: the measurement of one trial, as a
/// tracker would deliver it (docs/formats.md), with the truth beside it.
pub fn simulate(scenario: &Path, trial: usize, out: &Path) -> Result<()> {
    let sc = Scenario::load(scenario)?;
    if trial >= sc.trials {
        return Err(Error::setting(
            "--trial",
            format!(
                "trial {trial} does not exist: the scenario has {} trials (0-based)",
                sc.trials
            ),
        ));
    }
    let study = Study::new(sc)?;
    let sc = &study.scenario;
    let (errors, truth) = trial::true_robot(&study, trial);
    let seed = calbench::numeric::rng::trial_seed(sc.seed, trial as u64);
    let qs = trial::calibration_poses(&study, 0, trial)?;
    let vqs = trial::validation_poses(&study, trial)?;
    let sag = trial::sag_fn(&study);
    let sag_ref = sag.as_deref();
    let m = trial::measure_calibration(
        &study,
        &truth,
        &qs,
        sag_ref,
        &mut calbench::numeric::rng::stream(seed, "measure"),
    )?;
    // The validation file records its payload when the scenario measures under loads.
    let loaded = sc.calibration.payloads_kg.is_some() || sc.validation.payload_kg.is_some();
    let vloads = loaded.then(|| vec![study.validation_payload(); vqs.len()]);
    let v = measure_poses(
        &truth,
        &vqs,
        &study.tracker,
        None,
        sag_ref,
        vloads.as_deref(),
        &mut calbench::numeric::rng::stream(seed, "measure/validation"),
    )?;
    let errs: serde_json::Map<String, serde_json::Value> = errors
        .iter()
        .map(|(p, e)| (p.to_string(), json!(e)))
        .collect();
    let mut truth_json = json!({
        "scenario": sc.name,
        "trial": trial,
        "seed": seed,
        "robot": study.nominal.name,
        "calibration_poses": sc.calibration.strategies[0].name(),
        "errors": errs,
        "tracker_pose": sc.tracker.pose,
        "outliers": m.truth.outliers,
        "sag_mm": m.truth.sag_mm,
        "validation_sag_mm": v.truth.sag_mm,
    });
    if let Some(c) = study.true_compliance_json() {
        truth_json["true_compliance"] = c;
    }
    calbench::report::atomically(out, |dir| {
        write_measurements(&dir.join("measurements.csv"), &study.nominal, &m.data)?;
        write_measurements(&dir.join("validation.csv"), &study.nominal, &v.data)?;
        write_file(&dir.join("truth.json"), &to_json_text(&truth_json)?)
    })?;
    out!(
        "{} calibration and {} validation poses of trial {trial} written to {}",
        m.data.len(),
        v.data.len(),
        out.display()
    );
    Ok(())
}

/// `calbench identify --robot R --data CSV --method M [--registration …] [--validate CSV] [--k K]
/// [--seed S] --out DIR`: identification on a measurement file, real or simulated; `seed`
/// seeds the random searches.
#[allow(clippy::too_many_arguments)]
pub fn identify_file(
    robot: &str,
    data: &Path,
    method: &str,
    options: &[String],
    registration: &str,
    validate: Option<&Path>,
    k: Option<Real>,
    allow_rank_deficient: bool,
    export: Option<&str>,
    compliance: Option<&str>,
    seed: u64,
    out: &Path,
) -> Result<()> {
    let nominal = builtin::load(robot)?;
    if let Some(e) = export {
        if !matches!(e, "urdf" | "toml") {
            return Err(Error::setting(
                "--export",
                format!("\"{e}\"; allowed: urdf, toml"),
            ));
        }
    }
    let mut spec = method_with_options(method, options)?;
    let registration: Registration = calbench::robot::names::parse("--registration", registration)?;
    let d = read_measurements(data, &nominal)?;
    let measure = d.measure();
    if let Some(k) = k {
        if measure == Measure::Position {
            return Err(Error::setting(
                "--k",
                "weighs orientation against position errors; the data hold positions only",
            ));
        }
        calbench::error::finite_positive("--k", k)?;
        spec.k = k;
    }
    let val = validate
        .map(|p| read_measurements(p, &nominal))
        .transpose()?;
    let with_base = registration == Registration::Identify;
    let kinematic = param_sets::identified_params_tool_first(&nominal, measure, with_base);
    let mut params = kinematic.clone();
    if let Some(c) = compliance {
        params.extend(CompliancePick::from_arg(c).params(&nominal, "--compliance")?);
    }
    // For real data "known" means the points are already in the base frame.
    let c = calibrate(
        &nominal,
        &params,
        &d,
        registration,
        &Frame::identity(),
        &spec,
        &mut calbench::numeric::rng::stream(seed, "identify"),
    )?;
    let undetermined = matches!(
        c.identified.termination,
        Termination::RankDeficient | Termination::Singular
    );
    if undetermined && !allow_rank_deficient {
        // The analysis of the kinematic model (a compliance column's scale is per pose).
        let a = analyse(&nominal, &kinematic, &d.qs, measure);
        let names = |v: &[calbench::robot::Param]| {
            v.iter()
                .map(|p| p.to_string())
                .collect::<Vec<_>>()
                .join(" ")
        };
        let groups: Vec<String> = a.groups.iter().map(|g| format!("[{}]", names(g))).collect();
        return Err(Error::file(
            data,
            "data",
            format!(
                "the poses determine only {} of the {} parameters (rank {}; undetermined: {}; \
                 dependent groups: {}); {} ended {}, so nothing was written. Measure poses \
                 that move every joint, or pass --allow-rank-deficient",
                a.rank,
                params.len(),
                c.identified.rank.unwrap_or(a.rank),
                names(&a.unidentifiable),
                groups.join(" "),
                spec.name(),
                c.identified.termination.as_str(),
            ),
        ));
    }
    if matches!(
        c.rounds.termination,
        RoundsEnd::MaxRounds | RoundsEnd::Stalled
    ) {
        eprintln!(
            "warning: {} registration and identification did not settle within {} mm in {} \
             rounds ({}; the smallest frame step was {:.3e} mm, and that round is the result)",
            registration.as_str(),
            calbench::calibrate::ROUND_TOLERANCE_MM,
            c.rounds.rounds,
            c.rounds.termination.as_str(),
            c.rounds.last_step_mm
        );
    }
    let validation = val
        .as_ref()
        .map(|v| validate_file(&nominal, &c, v))
        .transpose()?;
    let record = IdentifyRecord {
        nominal: &nominal,
        data_path: data,
        data: &d,
        method: spec.name(),
        registration,
        params: &params,
        calibrated: &c,
        validation: validation.as_ref(),
        urdf: compensated_urdf(robot, export, &c.robot)?,
    };
    write_identified(out, &record)?;
    if let Some(v) = &validation {
        out!("validation error (mm)   mean      rms       max       std");
        for (label, s) in [("before", v.before_mm), ("after", v.after_mm)] {
            out!(
                "  {label:<8} {:>10.4} {:>9.4} {:>9.4} {:>9.4}",
                s.mean,
                s.rms,
                s.max,
                s.std
            );
        }
    }
    let r = &c.identified;
    let rounds = match c.rounds.termination {
        RoundsEnd::Single => String::new(),
        end => format!(
            " ({} rounds of {} registration and identification, {})",
            c.rounds.rounds,
            registration.as_str(),
            end.as_str()
        ),
    };
    out!(
        "{} on {} points: {} after {} iterations{rounds}; written to {}",
        spec.name(),
        d.len(),
        r.termination.as_str(),
        r.iterations,
        out.display()
    );
    Ok(())
}

/// `calbench poses SCENARIO --strategy S [--count M] [--curve A,B,…] --out DIR`: choose a
/// calibration pose set on the scenario's nominal robot (Guo 2024 §3).
pub fn poses(
    scenario: &Path,
    strategy: &str,
    count: Option<usize>,
    curve: Option<&str>,
    out: &Path,
) -> Result<()> {
    let sc = Scenario::load(scenario)?;
    let strategy: Optimiser = calbench::robot::names::parse("--strategy", strategy)?;
    let nominal = sc.robot()?;
    let measure = sc.tracker.measure.measure();
    let c = &sc.calibration;
    let count = count.unwrap_or(c.count);
    if count == 0 || count > c.candidates {
        return Err(Error::setting(
            "--count",
            format!(
                "must be between 1 and calibration.candidates ({})",
                c.candidates
            ),
        ));
    }
    // Every argument is checked before any work: the pool is `candidates` poses.
    let counts = curve
        .map(|list| {
            parse_list(
                list,
                "--curve",
                |&n: &usize| n >= 1 && n <= c.candidates,
                |s| format!("\"{s}\" is not a pose count in 1..={}", c.candidates),
            )
        })
        .transpose()?;
    let with_base = sc.registration == Registration::Identify;
    let mut params = param_sets::identified_params(&nominal, measure, with_base);
    let mut g = calbench::numeric::rng::stream(sc.seed, "poses-command");
    let pool = sample_region(&nominal, &c.region, c.candidates, &mut g)?;
    let mut separation = None;
    if c.separate {
        let (kept, s) =
            plan::separated_params(&nominal, measure, with_base, &pool, c.separate_threshold);
        params = kept;
        separation = Some(s);
    }
    let model = RobotPoseModel::new(&nominal, &params, measure);
    let mut opts = SelectOptions::new(count);
    opts.objective = c.objective;
    let sel = calbench::poses::select(&model, &pool, strategy, &opts, &mut g)?;
    // Everything is computed before anything is written, and written as a whole.
    let curve = counts
        .map(|counts| calbench::poses::objective_curve(&model, &pool, &counts, &opts, &mut g))
        .transpose()?;
    let mut scores = serde_json::to_value(sel.scores).map_err(|e| Error::Compute(e.to_string()))?;
    scores["strategy"] = json!(strategy.as_str());
    scores["count"] = json!(sel.poses.len());
    scores["parameters"] = json!(params.iter().map(|p| p.to_string()).collect::<Vec<_>>());
    scores["termination"] = json!(sel.termination);
    if let Some(s) = &separation {
        let mut j = s.to_json();
        // The earlier form of the table, kept for scripts that read it.
        j["gcn"] = json!(s
            .table
            .iter()
            .map(|(k, v)| json!({"block": k, "gcn": v}))
            .collect::<Vec<_>>());
        scores["separation"] = j;
    }
    let mut trace = String::from("iteration,objective\n");
    for (i, f) in sel.trace.iter().enumerate() {
        trace += &format!("{i},{f}\n");
    }
    let curve_csv = curve.as_ref().map(|pts| {
        let mut text = String::from("count,objective\n");
        for (n, f) in pts {
            text += &format!("{n},{f}\n");
        }
        text
    });
    calbench::report::atomically(out, |dir| {
        write_pose_list(&dir.join("poses.csv"), &nominal, &sel.poses)?;
        write_file(&dir.join("scores.json"), &to_json_text(&scores)?)?;
        write_file(&dir.join("trace.csv"), &trace)?;
        if let (Some(text), Some(pts)) = (&curve_csv, &curve) {
            write_file(&dir.join("curve.csv"), text)?;
            let pts: Vec<(Real, Real, Real)> =
                pts.iter().map(|&(n, f)| (n as Real, f, 0.0)).collect();
            calbench::report::plots::sweep(
                &dir.join("curve"),
                "Objective against pose count (Guo 2024 fig. 7)",
                "pose count",
                "objective",
                &[(format!("{} objective", c.objective.as_str()), pts)],
            )?;
        }
        Ok(())
    })?;
    out!(
        "{} of {} candidates by {}: composite {:.4}, O1 {:.4e}, GCN {:.4e}, condition number {:.4e}",
        sel.poses.len(),
        pool.len(),
        strategy.as_str(),
        sel.scores.composite,
        sel.scores.o1,
        sel.scores.gcn,
        sel.scores.condition_number
    );
    if let Some(pts) = &curve {
        out!("objective against pose count (Guo 2024 fig. 7):");
        for (n, f) in pts {
            out!("  {n:>5} {f:.6}");
        }
    }
    Ok(())
}

/// Prints the main table of a run.
fn print_table(r: &RunResult) {
    use calbench::report::columns::*;
    let columns = [
        ETA_MEAN,
        BEFORE_MEAN,
        AFTER_MEAN,
        AFTER_RMS,
        AFTER_MAX,
        FAILURES,
    ];
    let (headers, rows) = entry_table(r, &columns);
    let headers: Vec<&str> = headers.iter().map(String::as_str).collect();
    out_raw!("{}", markdown_table(&headers, &rows));
}

/// The method `name` with the `--set KEY=VALUE` options (values in TOML), read like a
/// scenario's `[[methods]]` entry.
fn method_with_options(name: &str, options: &[String]) -> Result<calbench::identify::MethodSpec> {
    if options.is_empty() {
        return method_by_name(name);
    }
    let mut t = toml::Table::new();
    t.insert("name".into(), toml::Value::String(name.into()));
    for o in options {
        let (key, value) = o
            .split_once('=')
            .ok_or_else(|| Error::setting("--set", format!("\"{o}\" is not KEY=VALUE")))?;
        let v: toml::Table = toml::from_str(&format!("v = {value}")).map_err(|_| {
            Error::setting("--set", format!("{key}: \"{value}\" is not a TOML value"))
        })?;
        t.insert(key.trim().to_string(), v["v"].clone());
    }
    calbench::identify::MethodSpec::from_table(&t)
        .map_err(|(k, msg)| Error::setting(format!("--set {k}"), msg))
}

/// Checks, before any work, that `dir` is (or can be made) a folder calbench can write in.
fn writable_folder(dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::setting(
            "--out",
            format!("{} exists and is not a folder", dir.display()),
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let probe = dir.join(".calbench-write-test");
    std::fs::write(&probe, b"").map_err(|e| Error::io(&probe, e))?;
    std::fs::remove_file(&probe).map_err(|e| Error::io(&probe, e))
}

/// `calbench run SCENARIO [--trials N] [--seed S] [--threads T] [--out DIR]`, and the default
/// study when `scenario` is `None`.
pub fn run(
    scenario: Option<&Path>,
    trials: Option<usize>,
    seed: Option<u64>,
    threads: Option<usize>,
    out: Option<PathBuf>,
    shard: Option<&str>,
) -> Result<()> {
    if let Some(p) = scenario {
        let text = std::fs::read_to_string(p).map_err(|e| Error::io(p, e))?;
        let table: toml::Table =
            toml::from_str(&text).map_err(|e| Error::file(p, "TOML", e.to_string().trim_end()))?;
        if RegistrationScenario::is_one(&table) {
            if shard.is_some() {
                return Err(Error::setting(
                    "--shard",
                    "a registration study (`[registration_study]`) runs whole, not in shards",
                ));
            }
            return registration_study(
                RegistrationScenario::from_table(table, p)?,
                trials,
                seed,
                threads,
                out,
            );
        }
    }
    let shard = shard.map(study::Shard::parse).transpose()?;
    let mut sc = match scenario {
        Some(p) => Scenario::load(p)?,
        None => Scenario::default_study()?,
    };
    if let Some(n) = trials {
        sc = sc.with_override("trials", toml::Value::Integer(n as i64))?;
    }
    if let Some(s) = seed {
        let s = i64::try_from(s).map_err(|_| Error::setting("--seed", "must be below 2^63"))?;
        sc = sc.with_override("seed", toml::Value::Integer(s))?;
    }
    if threads == Some(0) {
        return Err(Error::setting("--threads", "must be at least 1"));
    }
    eprintln!(
        "running {}: {} trials{}{}",
        sc.name,
        sc.trials,
        sc.sweep.as_ref().map_or(String::new(), |s| format!(
            " × {} sweep points of {}",
            s.points().len(),
            s.keys().join(", ")
        )),
        shard.map_or(String::new(), |s| format!(
            ", shard {}/{}",
            s.index, s.count
        ))
    );
    let out = out.unwrap_or_else(|| Path::new("results").join(&sc.name));
    writable_folder(&out)?;
    let opts = RunOptions {
        threads,
        out: Some(out),
        progress: true,
        shard,
    };
    let r = run_study(sc, &opts)?;
    if let Some(s) = shard {
        out!(
            "shard {}/{} of {} in {:.1} s: {}; combine all {} shards with `calbench merge`",
            s.index,
            s.count,
            r.scenario.name,
            r.seconds,
            r.out.display(),
            s.count
        );
        return Ok(());
    }
    print_table(&r);
    out!(
        "\n{} trials in {:.1} s; report: {}",
        r.scenario.trials * r.blocks.len(),
        r.seconds,
        r.out.join("report.md").display()
    );
    Ok(())
}

/// `calbench merge DIR… --out DIR`.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<()> {
    writable_folder(out)?;
    let r = calbench::report::shard::merge(dirs, out)?;
    print_table(&r);
    out!(
        "\nmerged {} shards; report: {}",
        dirs.len(),
        out.join("report.md").display()
    );
    Ok(())
}

/// `calbench run` of a scenario with a `[registration_study]` table (Ban fig. 3): the grid
/// of SVD against weighted-SVD registration errors, its report and heat map.
fn registration_study(
    mut sc: RegistrationScenario,
    trials: Option<usize>,
    seed: Option<u64>,
    threads: Option<usize>,
    out: Option<PathBuf>,
) -> Result<()> {
    if let Some(n) = trials {
        if n == 0 || n > calbench::study::scenario::MAX_TRIALS {
            return Err(Error::setting(
                "--trials",
                format!(
                    "must be between 1 and {}",
                    calbench::study::scenario::MAX_TRIALS
                ),
            ));
        }
        sc.trials = n;
    }
    if let Some(s) = seed {
        sc.seed = s;
    }
    if threads == Some(0) {
        return Err(Error::setting("--threads", "must be at least 1"));
    }
    let st = &sc.registration_study;
    eprintln!(
        "running {}: registration study, {} × {} cells × {} draws",
        sc.name,
        st.outlier_counts.len(),
        st.magnitude_mm.len(),
        sc.trials
    );
    let out = out.unwrap_or_else(|| Path::new("results").join(&sc.name));
    writable_folder(&out)?;
    let t0 = std::time::Instant::now();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| Error::Compute(e.to_string()))?;
    let cells = pool.install(|| st.run(sc.seed, sc.trials))?;
    calbench::report::registration_study::write_all(&sc, &cells, &out)?;
    out!(
        "{}\n{} draws per cell in {:.1} s; report: {}",
        calbench::report::registration_study::report_md(&sc, &cells, "heatmap_difference.png")
            .lines()
            .skip_while(|l| !l.starts_with("## "))
            .take_while(|l| !l.starts_with("!["))
            .collect::<Vec<_>>()
            .join("\n"),
        sc.trials,
        t0.elapsed().as_secs_f64(),
        out.join("report.md").display()
    );
    Ok(())
}

/// `calbench check SUMMARY --baseline BASELINE [--tolerance X]`: returns the regressions.
pub fn check(summary: &Path, baseline: &Path, tolerance: Real) -> Result<Vec<Regression>> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(Error::setting("--tolerance", "must be a number ≥ 0"));
    }
    let s = read_json(summary)?;
    let b = read_json(baseline)?;
    calbench::report::check::comparable(&s, summary, &b, baseline)?;
    Ok(compare(&s, &b, tolerance))
}

/// `calbench import RAW --mapping MAPPING --out CSV`.
pub fn import(raw: &Path, mapping: &Path, out: &Path) -> Result<()> {
    let n = calbench::measurement::import::import(raw, mapping, out)?;
    out!("{n} rows of {} written to {}", raw.display(), out.display());
    Ok(())
}

/// `calbench compensate --robot NOMINAL --identified IDENTIFIED --joints PROGRAM --out CSV`
/// (Li 2018 §3): per program row, the joints (in the nominal robot's units, the controller's)
/// at which the identified robot reaches the nominal pose, with the residual and a flag.
pub fn compensate(
    robot: &str,
    identified: &str,
    joints: &Path,
    payload_kg: Real,
    out: &Path,
) -> Result<()> {
    if !(payload_kg.is_finite() && payload_kg >= 0.0) {
        return Err(Error::setting(
            "--payload-kg",
            format!("must be a finite payload ≥ 0 kg, got {payload_kg}"),
        ));
    }
    let nominal = builtin::load(robot)?;
    let ident = builtin::load(identified)?;
    let (n, m) = (ident.dof(), nominal.dof());
    if n != m {
        let msg = format!("{identified} has {n} joints, the nominal robot {m}");
        return Err(Error::setting("--identified", msg));
    }
    let program = calbench::sim::poses::read_pose_list(joints, &nominal)?;
    let cell = |v: Real| calbench::measurement::csv::fixed(v, 9);
    // What is written: 9 decimals in the nominal robot's units.
    let round = |q: &[Real]| -> Vec<Real> {
        let user: Vec<Real> = nominal
            .q_to_user(q)
            .iter()
            .map(|&v| cell(v).parse().unwrap_or(v))
            .collect();
        nominal.q_from_user(&user)
    };
    let n = nominal.dof();
    let mut s: String = (1..=n).map(|j| format!("q{j},")).collect();
    s.push_str("residual_mm,residual_deg,flag\n");
    let mut flagged = 0;
    let mut worst: (Real, Real) = (0.0, 0.0);
    for q in &program {
        let c = calbench::calibrate::compensate::compensate_row(
            &nominal, &ident, q, payload_kg, round,
        )?;
        for v in nominal.q_to_user(&c.q) {
            s.push_str(&cell(v));
            s.push(',');
        }
        s.push_str(&format!(
            "{:.3e},{:.3e},{}\n",
            c.residual_mm, c.residual_deg, c.flag
        ));
        flagged += usize::from(c.flag != "ok");
        worst = (worst.0.max(c.residual_mm), worst.1.max(c.residual_deg));
    }
    write_file(out, &s)?;
    out!(
        "{} rows corrected ({flagged} flagged), worst residual {:.1e} mm / {:.1e} deg; written to {}",
        program.len(),
        worst.0,
        worst.1,
        out.display()
    );
    Ok(())
}

/// The compensated robot as a URDF: for a URDF robot (its source with the joint origins
/// moved) unless `--export toml`, for a robot file with `--export urdf`.
fn compensated_urdf(
    robot: &str,
    export: Option<&str>,
    compensated: &calbench::robot::Robot,
) -> Result<Option<String>> {
    if export == Some("toml") {
        return Ok(None);
    }
    if !calbench::robot::urdf::is_urdf(robot) {
        return match export {
            Some("urdf") => calbench::robot::urdf::robot_to_urdf(compensated).map(Some),
            _ => Ok(None),
        };
    }
    let source = calbench::robot::urdf::UrdfRobot::load(Path::new(robot))?;
    source.write(compensated).map(Some)
}
