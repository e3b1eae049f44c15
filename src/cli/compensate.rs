//! `calbench compensate --robot NOMINAL --identified IDENTIFIED (--joints PROGRAM |
//! --targets TARGETS) [--payload-kg W] --out CSV` (Li 2018 §3): per program row, the joints
//! (in the nominal robot's units, the controller's) at which the identified robot reaches the
//! nominal pose (or the Cartesian target), with the residual and a flag.

use std::path::{Path, PathBuf};

use anyhow::Result;

use calbench::calibrate::compensate::{compensate_row, compensate_targets, not_a_calibration_of};
use calbench::calibrate::kernel::KERNEL_FILE;
use calbench::error::Error;
use calbench::measurement::csv::read_targets;
use calbench::numeric::Real;
use calbench::numeric::{quaternion_matrix, Frame, Mat3};
use calbench::report::program::{cell, CorrectedProgram};
use calbench::report::Output as _;
use calbench::robot::builtin;

use super::guard_out_file;

/// Arguments of `calbench compensate`.
#[derive(clap::Args)]
pub struct CompensateArgs {
    /// The nominal robot (the controller's model).
    #[arg(long)]
    pub robot: String,
    /// The chain of a URDF tree.
    #[command(flatten)]
    pub chain: super::ChainArgs,
    /// The identified (compensated) robot, e.g. identify's robot.toml.
    #[arg(long)]
    pub identified: String,
    /// The program: a CSV with columns q1..qn (nominal joint commands).
    #[arg(long, required_unless_present = "targets", conflicts_with = "targets")]
    pub joints: Option<PathBuf>,
    /// Cartesian tool targets for the nominal robot: a CSV with columns x,y,z (mm, base
    /// frame) and optionally qw,qx,qy,qz (full poses); the output has columns q1..qn.
    #[arg(long)]
    pub targets: Option<PathBuf>,
    /// Payload at the tool (kg) while the program runs: a compensated robot with joint
    /// compliances corrects the commands for its gravity sag under this load.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = super::number)]
    pub payload_kg: Real,
    /// The corrected program to write (an existing file is replaced).
    #[arg(long)]
    pub out: PathBuf,
    /// Correct the program with an identified robot that cannot be a calibration of the
    /// nominal one (its parameters moved beyond the bounds of a calibration), with a warning.
    #[arg(long)]
    pub allow_implausible: bool,
}

/// Corrects every row of the program and writes the corrected program.
pub fn run(args: &CompensateArgs) -> Result<()> {
    let payload_kg = args.payload_kg;
    if let Some(msg) = calbench::robot::compliance::not_a_mass(payload_kg) {
        return Err(Error::setting("--payload-kg", msg).into());
    }
    let robots = [Path::new(&args.robot), Path::new(&args.identified)];
    let programs = [args.joints.as_deref(), args.targets.as_deref()];
    guard_out_file(
        &args.out,
        robots.into_iter().chain(programs.into_iter().flatten()),
    )?;
    let nominal = args.chain.load(&args.robot)?;
    let ident = if calbench::robot::urdf::is_urdf(&args.identified) {
        args.chain.load(&args.identified)
    } else {
        builtin::load(&args.identified)
    }
    // A robot that is not there is refused as the option that named it.
    .map_err(|e| match e {
        Error::Setting { key, msg } if key == "robot" => Error::Setting {
            key: "--identified".into(),
            msg,
        },
        e => e,
    })?;
    let kernel = Path::new(&args.identified).with_file_name(KERNEL_FILE);
    if kernel.is_file() {
        eprintln!(
            "warning: {} holds a kernel residual (model term `gp`) that compensate cannot \
             carry: the program is corrected with {}'s parametric model alone, without the \
             residual's correction",
            kernel.display(),
            args.identified
        );
    }
    let (n, m) = (ident.dof(), nominal.dof());
    if n != m {
        let msg = format!("{} has {n} joints, the nominal robot {m}", args.identified);
        return Err(Error::setting("--identified", msg).into());
    }
    let program = match &args.joints {
        Some(path) => {
            let qs = calbench::sim::poses::read_pose_list(path, &nominal)?;
            calbench::calibrate::verdict::radians_refused(path, &nominal, &qs)?;
            qs
        }
        None => Vec::new(),
    };
    let found = not_a_calibration_of(&nominal, &ident, &program);
    if !found.is_empty() {
        let what = format!(
            "{} cannot be a calibration of the nominal robot: {}; a calibration moves a robot \
             by millimetres and fractions of a degree",
            args.identified,
            found.join("; ")
        );
        if !args.allow_implausible {
            let msg = format!(
                "{what}. Check that it is what `calbench identify` wrote for --robot, or pass \
                 --allow-implausible to correct the program with it"
            );
            return Err(Error::setting("--identified", msg).into());
        }
        eprintln!("warning: {what}; the program is corrected with it (--allow-implausible)");
    }
    // What is written: the program's decimals in the nominal robot's units.
    let round = |q: &[Real]| -> Vec<Real> {
        let user: Vec<Real> = nominal
            .q_to_user(q)
            .iter()
            .enumerate()
            .map(|(j, &v)| cell(&nominal, j, v).parse().unwrap_or(v))
            .collect();
        nominal.q_from_user(&user)
    };
    let mut flagged = 0;
    let mut worst: (Real, Real) = (0.0, 0.0);
    let rows = if let Some(path) = &args.targets {
        let t = read_targets(path)?;
        let frames: Vec<Frame> = t
            .points
            .iter()
            .enumerate()
            .map(|(i, p)| Frame {
                rot: t
                    .quats
                    .as_ref()
                    .map_or(Mat3::identity(), |q| quaternion_matrix(&q[i])),
                pos: *p,
            })
            .collect();
        compensate_targets(&ident, &frames, t.quats.is_none(), payload_kg, round)?
    } else {
        program
            .iter()
            .map(|q| compensate_row(&nominal, &ident, q, payload_kg, round))
            .collect::<calbench::Result<Vec<_>>>()?
    };
    for c in &rows {
        flagged += usize::from(c.flag != "ok");
        worst = (worst.0.max(c.residual_mm), worst.1.max(c.residual_deg));
    }
    let program = CorrectedProgram {
        name: "program.csv",
        robot: &nominal,
        rows: &rows,
    };
    program.write(&args.out)?;
    out!(
        "{} rows corrected ({flagged} flagged), worst residual {:.1e} mm / {:.1e} deg; written to {}",
        rows.len(),
        worst.0,
        worst.1,
        args.out.display()
    );
    Ok(())
}
