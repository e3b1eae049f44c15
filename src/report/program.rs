//! The corrected program of `calbench compensate` (docs/formats.md): per row, the joints in
//! the nominal robot's units (as fine as 9 decimals of a degree or a millimetre, [`cell`]), the
//! residual of the identified robot there (mm, deg, three significant digits) and the flag.

use std::path::Path;

use super::output::{text, Output};
use crate::calibrate::compensate::Corrected;
use crate::error::Result;
use crate::measurement::csv::fixed;
use crate::measurement::JointSpace;
use crate::numeric::Real;

/// Joint `j`'s value `v` (user units) of `robot` as the corrected program writes it: with
/// [`JointSpace::decimals`], 9 in degrees and millimetres, more in radians and metres, so the
/// written command reaches its pose within the program's 1e-6 mm in every unit.
pub fn cell<R: JointSpace + ?Sized>(robot: &R, j: usize, v: Real) -> String {
    fixed(v, robot.decimals(j))
}

/// The corrected program: columns q1..qn, `residual_mm`, `residual_deg`, `flag`.
pub struct CorrectedProgram<'a, R: JointSpace + ?Sized> {
    /// The file's name in a folder (`compensate` writes it at `--out`).
    pub name: &'a str,
    /// The nominal robot, whose units the joints are written in.
    pub robot: &'a R,
    /// The corrected rows, in program order.
    pub rows: &'a [Corrected],
}

impl<R: JointSpace + ?Sized> Output for CorrectedProgram<'_, R> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        use std::fmt::Write as _;
        let mut s: String = (1..=self.robot.dof()).map(|j| format!("q{j},")).collect();
        s.push_str("residual_mm,residual_deg,flag\n");
        for c in self.rows {
            for (j, v) in self.robot.q_to_user(&c.q).into_iter().enumerate() {
                s.push_str(&cell(self.robot, j, v));
                s.push(',');
            }
            let _ = writeln!(s, "{:.3e},{:.3e},{}", c.residual_mm, c.residual_deg, c.flag);
        }
        text(path, &s)
    }
}
