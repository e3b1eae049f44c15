//! `calbench identifiability --robot R [--measure M] [--poses N] [--seed S] [--poses-file CSV]
//! [--gcn-blocks [--gcn-threshold T]] [--json]`: rank, identifiable parameters and dependent
//! groups.

use std::path::PathBuf;

use anyhow::Result;
use serde_json::json;

use calbench::error::Error;
use calbench::numeric::Real;
use calbench::robot::identifiability::analyse;
use calbench::robot::Param;
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
    /// What is measured per pose: the point (3 rows) or the full pose (6 rows).
    #[arg(long, default_value = "position", value_parser = super::named::<MeasureSetting>())]
    pub measure: MeasureSetting,
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
    #[arg(long, default_value_t = 1e2)]
    pub gcn_threshold: Real,
    /// Print JSON to stdout.
    #[arg(long)]
    pub json: bool,
}

/// Analyses every parameter of the robot's model over the poses and prints the result.
pub fn run(args: &IdentifiabilityArgs) -> Result<()> {
    let robot = args.chain.load(&args.robot)?;
    let gcn_blocks = args.gcn_blocks.then_some(args.gcn_threshold);
    if let Some(t) = gcn_blocks {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::setting(
                "--gcn-threshold",
                format!("must be a finite number > 0, got {t}"),
            )
            .into());
        }
    }
    let measure = args.measure.measure();
    if args.poses == 0 {
        return Err(Error::setting("--poses", "must be at least 1").into());
    }
    let qs = match &args.poses_file {
        Some(p) => calbench::sim::poses::read_pose_list(p, &robot)?,
        None => {
            let mut rng = calbench::numeric::rng::stream(args.seed, "identifiability");
            calbench::robot::sampling::uniform_joint_poses(&robot, args.poses, &mut rng)
        }
    };
    let poses = qs.len();
    let a = analyse(&robot, &robot.params(), &qs, measure);
    let names = |v: &[Param]| v.iter().map(|p| p.to_string()).collect::<Vec<_>>();
    // Guo 2024 §3.1: the separation of the joint parameters (θ, α, a, d, β blocks).
    let sep = gcn_blocks
        .map(|t| calbench::poses::separate(&robot, &robot.joint_params(), &qs, measure, t));
    if args.json {
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
        return Ok(());
    }
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
    Ok(())
}
