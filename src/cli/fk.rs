//! `calbench fk --robot R --q Q1,…,QN [--json]`: forward kinematics of the tool point, of the
//! robot's whole model with no payload (docs/formats.md § 2.11).

use anyhow::Result;
use serde_json::json;

use calbench::error::Error;
use calbench::numeric::Real;

/// Arguments of `calbench fk`.
#[derive(clap::Args)]
pub struct FkArgs {
    /// Built-in robot name or robot file.
    #[arg(long)]
    pub robot: String,
    /// The chain of a URDF tree.
    #[command(flatten)]
    pub chain: super::ChainArgs,
    /// Joint values in the robot's units, comma-separated (`--q -10,20,30,0,45,0`).
    #[arg(
        long,
        required = true,
        allow_hyphen_values = true,
        value_delimiter = ',',
        value_parser = super::finite_number,
        action = clap::ArgAction::Set
    )]
    pub q: Vec<Real>,
    /// Print JSON to stdout.
    #[arg(long)]
    pub json: bool,
}

/// Prints the tool point and the rotation of the tool frame; warns on stderr when the joint
/// values lie outside the joint limits, naming the first joint outside.
pub fn run(args: &FkArgs) -> Result<()> {
    let robot = args.chain.load(&args.robot)?;
    if args.q.len() != robot.dof() {
        let e = Error::joint_count("--q", "the values given", args.q.len(), robot.dof());
        return Err(e.into());
    }
    let q = robot
        .q_from_user_checked(&args.q, "q")
        .map_err(|e| e.of_option(calbench::error::Opt::Q))?;
    let f = calbench::robot::loaded::LoadedFk::new(&robot).at(&q, 0.0)?;
    let rot: Vec<[Real; 3]> = (0..3)
        .map(|i| [f.rot[(i, 0)], f.rot[(i, 1)], f.rot[(i, 2)]])
        .collect();
    if args.json {
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
    if let Some(joint) = robot.outside_limits(&q) {
        eprintln!("warning: {}: {joint}", calbench::robot::OUTSIDE_LIMITS);
    }
    Ok(())
}
