//! `calbench identifiability --robot R [--measure M] [--poses N] [--seed S] [--poses-file CSV]
//! [--gcn-blocks [--gcn-threshold T]] [--json]`: rank, identifiable parameters and dependent
//! groups, for the tracker (`position`, `pose`) or another instrument (`distance`, `plane`,
//! `sphere`, `multi-target`).

use std::path::PathBuf;

use anyhow::Result;
use serde_json::json;

use calbench::error::Error;
use calbench::identify::kind::KindAnalysis;
use calbench::measurement::kind::Kind;
use calbench::measurement::kind_csv::file_kind;
use calbench::numeric::Real;
use calbench::robot::identifiability::{analyse, Identifiability};
use calbench::robot::Param;
use calbench::sim::instrument::InstrumentSettings;
use calbench::sim::settings::MeasureSetting;

/// Arguments of `calbench identifiability`.
#[derive(clap::Args)]
pub struct IdentifiabilityArgs {
    /// Built-in robot name or robot file.
    #[arg(long)]
    pub robot: String,
    /// The chain of a URDF tree.
    #[command(flatten)]
    pub chain: super::ChainArgs,
    /// What is measured per pose: the point (3 rows), the full pose (6 rows), or another
    /// instrument's reading (docs/formats.md, "Measurement kinds").
    #[arg(long, default_value = "position", value_parser = super::named::<Kind>())]
    pub measure: Kind,
    /// `distance`: lengths between consecutive poses instead of from a pivot.
    #[arg(long)]
    pub between_poses: bool,
    /// `plane`: the number of planes (default 3).
    #[arg(long)]
    pub planes: Option<usize>,
    /// `sphere`: the number of spheres (default 1).
    #[arg(long)]
    pub spheres: Option<usize>,
    /// Number of random poses within the joint limits.
    #[arg(long, default_value_t = 100)]
    pub poses: usize,
    /// Seed of the random poses.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Analyse these poses instead (a pose list or measurement CSV, `q1..qn` columns).
    #[arg(long)]
    pub poses_file: Option<PathBuf>,
    /// Also report Guo 2024's ill-conditioned parameter separation of the joint
    /// parameters: each block's GCN before and after, and the removed parameters.
    #[arg(long)]
    pub gcn_blocks: bool,
    /// GCN threshold of the separation (Guo 2024 §3.1: 1e2).
    #[arg(long, requires = "gcn_blocks", allow_negative_numbers = true, value_parser = super::number)]
    pub gcn_threshold: Option<Real>,
    /// Print JSON to stdout.
    #[arg(long)]
    pub json: bool,
}

/// Analyses every parameter of the robot's model over the poses and prints the result.
pub fn run(args: &IdentifiabilityArgs) -> Result<()> {
    // An instrument's option with a kind that does not read it is refused, not ignored.
    for (given, option, kind) in [
        (args.between_poses, "--between-poses", Kind::Distance),
        (args.planes.is_some(), "--planes", Kind::Plane),
        (args.spheres.is_some(), "--spheres", Kind::Sphere),
    ] {
        if given && args.measure != kind {
            let why = format!("is read only with --measure {}", kind.as_str());
            return Err(Error::setting(option, why).into());
        }
    }
    if args.gcn_blocks && !matches!(args.measure, Kind::Position | Kind::Pose) {
        return Err(Error::setting(
            "--gcn-blocks",
            "Guo 2024's separation is for the tracker's `position` and `pose` only",
        )
        .into());
    }
    let robot = args.chain.load(&args.robot)?;
    let gcn_blocks = args.gcn_blocks.then(|| args.gcn_threshold.unwrap_or(1e2));
    if let Some(t) = gcn_blocks {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::setting(
                "--gcn-threshold",
                format!("must be a finite number > 0, got {t}"),
            )
            .into());
        }
    }
    if args.poses == 0 {
        return Err(Error::setting("--poses", "must be at least 1").into());
    }
    calbench::study::scenario::check_pose_count("--poses", args.poses)?;
    // A measurement-kind file's readings are analysed as `identify` analyses them.
    let kind_file = args
        .poses_file
        .as_deref()
        .and_then(|p| file_kind(p).map(|k| (p, k)));
    if let Some((path, kind)) = kind_file {
        return of_kind_file(args, &robot, path, kind);
    }
    let qs = match &args.poses_file {
        Some(p) => {
            let qs = calbench::sim::poses::read_pose_list(p, &robot)?;
            calbench::calibrate::verdict::radians_refused(p, &robot, &qs)?;
            qs
        }
        None => {
            let mut rng = calbench::numeric::rng::stream(args.seed, "identifiability");
            calbench::robot::sampling::uniform_joint_poses(&robot, args.poses, &mut rng)
        }
    };
    let poses = qs.len();
    let measure = match args.measure {
        Kind::Position => MeasureSetting::Position.measure(),
        Kind::Pose => MeasureSetting::Pose.measure(),
        kind => return instrument(args, &robot, &qs, kind),
    };
    let a = analyse(&robot, &robot.params(), &qs, measure);
    // Guo 2024 §3.1: the separation of the joint parameters (θ, α, a, d, β blocks).
    let sep = gcn_blocks
        .map(|t| calbench::poses::separate(&robot, &robot.joint_params(), &qs, measure, t));
    if args.json {
        let mut v = analysis_json(&a);
        if let (Some(sep), Some(obj)) = (&sep, v.as_object_mut()) {
            if let Some(extra) = sep.to_json().as_object() {
                obj.extend(extra.clone());
            }
        }
        out!("{v}");
        return Ok(());
    }
    out!("robot {} ({} poses, {:?})", robot.name, poses, measure);
    print_analysis(&robot, &a);
    if let Some(sep) = &sep {
        out!(
            "GCN per block (Guo 2024 eq. 14) before and after the separation, all poses and \
             averaged over pose counts (Guo §4.1):"
        );
        for b in &sep.blocks {
            out!(
                "  {:<6} {:>12.4e} {:>12.4e}   {:>12.4e} {:>12.4e}",
                b.name,
                b.gcn_before,
                b.gcn_after,
                b.gcn_mean_before,
                b.gcn_mean_after
            );
        }
        out!("removed: {}", names(&sep.removed).join(" "));
        out!(
            "GCN full model {:.4e}, separated {:.4e}; averaged {:.4e}, {:.4e}",
            sep.gcn_full(),
            sep.gcn_separated(),
            sep.gcn_mean_full(),
            sep.gcn_mean_separated()
        );
    }
    Ok(())
}

/// `--poses-file` of a measurement-kind file (docs/formats.md § 5.3) of `kind`: its readings
/// on the file's own instrument (its planes, spheres, sockets or targets), judged as
/// `identify` judges them. `--measure` must name that kind; the instrument's options come
/// from the file and are refused.
fn of_kind_file(
    args: &IdentifiabilityArgs,
    robot: &calbench::robot::Robot,
    path: &std::path::Path,
    kind: Kind,
) -> Result<()> {
    if args.measure != kind {
        let why = format!(
            "{} is a {} file (docs/formats.md § 5.3): give --measure {}, which analyses its \
             readings as identify does",
            path.display(),
            kind.as_str(),
            kind.as_str()
        );
        return Err(Error::setting("--measure", why).into());
    }
    for (given, option) in [
        (args.between_poses, "--between-poses"),
        (args.planes.is_some(), "--planes"),
        (args.spheres.is_some(), "--spheres"),
    ] {
        if given {
            let why = format!(
                "is not read with a {} file: its instrument is the file's",
                kind.as_str()
            );
            return Err(Error::setting(option, why).into());
        }
    }
    let file = calbench::measurement::kind_csv::read_kind_file(path, robot)?;
    let a = calbench::calibrate::on_kind::file_identifiability(robot, &file)?;
    let poses = format!("{} poses of {}", file.qs.len(), path.display());
    print_instrument(args, robot, kind, &a, &poses);
    Ok(())
}

/// The analysis `a` of an instrument of `kind`, over `poses` (how many and whence), as JSON
/// with `--json` or as text.
fn print_instrument(
    args: &IdentifiabilityArgs,
    robot: &calbench::robot::Robot,
    kind: Kind,
    a: &KindAnalysis,
    poses: &str,
) {
    if args.json {
        let mut v = analysis_json(&a.robot);
        v["measure"] = json!(kind.as_str());
        v["instrument_unknowns"] = json!(a.unknowns);
        v["undetermined_instrument_unknowns"] = json!(a.undetermined);
        out!("{v}");
        return;
    }
    out!("robot {} ({poses}, {})", robot.name, kind.as_str());
    out!("instrument unknowns: {}", a.unknowns.join(" "));
    if !a.undetermined.is_empty() {
        out!(
            "undetermined instrument unknowns: {} (the poses leave them free)",
            a.undetermined.join(" ")
        );
    }
    print_analysis(robot, &a.robot);
}

/// `--measure distance|plane|sphere|multi-target`: the kind's Jacobian at the nominal robot
/// over the poses, the instrument's own unknowns (pivot, planes, spheres) projected out.
fn instrument(
    args: &IdentifiabilityArgs,
    robot: &calbench::robot::Robot,
    qs: &[Vec<Real>],
    kind: Kind,
) -> Result<()> {
    let default = InstrumentSettings::default();
    let s = InstrumentSettings {
        kind,
        pivot: !args.between_poses,
        planes: args.planes.unwrap_or(default.planes),
        spheres: args.spheres.unwrap_or(default.spheres),
        ..default
    };
    // The library names the poses `q`: here they are the file's, or the random count's.
    let of_poses = |e: Error| match e {
        Error::Option {
            option: calbench::error::Opt::Q,
            msg,
        } => match args.poses_file {
            Some(_) => Error::setting("--poses-file", msg.to_string()),
            None => Error::setting("--poses", msg.to_string()),
        },
        e => e,
    };
    // Random poses move onto their planes or spheres; a pose file's poses are taken as
    // they are (they touch, or the fitted surfaces are the instrument's).
    let moved;
    let (a, qs) = if args.poses_file.is_some() {
        (
            calbench::identify::kind::identifiability_at(robot, qs, &s).map_err(of_poses)?,
            qs,
        )
    } else {
        let mut rng = calbench::numeric::rng::stream(args.seed, "identifiability");
        let (lay, q, g) =
            calbench::sim::instrument::instrument_poses(&s, robot, args.poses, &mut rng)
                .map_err(calbench::sim::instrument::counts_as_options)?;
        moved = q;
        let a = calbench::identify::kind::identifiability_of(robot, &moved, lay.instrument, g)
            .map_err(of_poses)?;
        (a, &moved[..])
    };
    let poses = format!("{} poses", qs.len());
    print_instrument(args, robot, kind, &a, &poses);
    Ok(())
}

/// The rank, the identifiable and unidentifiable parameters, the dependent groups and the
/// condition number of `a`, as text.
fn print_analysis(robot: &calbench::robot::Robot, a: &Identifiability) {
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
}

/// The parameters' names.
fn names(v: &[Param]) -> Vec<String> {
    v.iter().map(|p| p.to_string()).collect()
}

/// `--json`'s keys of an analysis: rank, identifiable, unidentifiable, groups and condition
/// number.
fn analysis_json(a: &Identifiability) -> serde_json::Value {
    let groups: Vec<Vec<String>> = a.groups.iter().map(|g| names(g)).collect();
    json!({
        "rank": a.rank,
        "identifiable": names(&a.identifiable),
        "unidentifiable": names(&a.unidentifiable),
        "groups": groups,
        "condition_number": a.condition_number,
    })
}
