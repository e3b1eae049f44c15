//! Ill-conditioned parameter separation (Guo 2024 §3.1, tables 1–3, eqs. 14 and 27–28).
//!
//! The Jacobian J over the poses is split by parameter type into sub-blocks (θ, α, a, d, β,
//! and base and tool when present, [`Param::block`]) and the GCN = cond(J_block)/m (eq. 14) of
//! each is computed (table 1). Blocks at or under the threshold are pruned. In a block over
//! it, the branch step removes each parameter in turn and computes the GCN of what is left
//! (tables 2–3); backward elimination then removes the parameter whose removal leaves the
//! smallest GCN (ties to the later parameter), and repeats on the reduced block until it is
//! under the threshold. The kept parameters of all blocks form Guo's model J_p° (eq. 28,
//! `separated` in the table); without the partners too, Guo's J_p (eq. 27, `reduced`, the
//! table's last row).
//!
//! Differences from the paper, on purpose: the paper averages each GCN over pose counts
//! 1..100 of one random set (§4.1); here the decisions use the GCN of all the poses passed in,
//! and Guo's average ([`gcn_mean`]) is reported beside it (`gcn_mean_*`). The average is
//! dominated by its first counts, at which a block can be singular for want of rows alone: on
//! the IRB2600, a1, a2 and a3 act along x1, x2 and x3, all normal to the parallel axes z2 and
//! z3, so one pose never sees them independently and the averaged GCN of the `a` block is
//! infinite, although 30 poses identify all three (the test
//! `a_well_conditioned_block_is_pruned`). The paper finally
//! removes every parameter whose single removal brings its block under the threshold (both
//! a4 and a5, both d2 and d3); here one parameter at a time is removed until the block is
//! under the threshold, which keeps an identifiable partner of a dependent pair.
//!
//! The GCN compares columns of one block, which share a unit (except base and tool, which
//! mix mm and rad); no column scaling is applied.

use nalgebra::DMatrix;

use super::indices::{gcn, gcn_mean};
use crate::measurement::Measure;
use crate::numeric::Real;
use crate::robot::jacobian::{jacobian, Columns};
use crate::robot::{Param, Robot};

/// The outcome of [`separate`].
#[derive(Clone, Debug, PartialEq)]
pub struct Separation {
    /// Parameters kept by the one-at-a-time elimination (Guo's J_p°, eq. 28), in the input
    /// order.
    pub kept: Vec<Param>,
    /// Parameters separated as ill-conditioned, in the order removed.
    pub removed: Vec<Param>,
    /// Guo's reading of eq. 27, in the input order: every parameter whose single removal
    /// brings its block to or under the threshold (both members of a dependent pair: Guo's
    /// a4, a5, d2 and d3), with those [`Separation::removed`] holds. The model without them is
    /// Guo's J_p ([`Separation::reduced`]); `kept` is Guo's J_p° (eq. 28).
    pub ill_conditioned: Vec<Param>,
    /// The GCN table: `full` (all parameters), each block (`theta`, `d`, …, tables 1), each
    /// branch `d-d2` (block `d` without `d2`, tables 2–3), each reduced block `d[-d3]` (after
    /// the removals so far), and `separated` (the kept parameters).
    pub table: Vec<GcnRow>,
    /// Per block, in order of first appearance: its GCN before and after the separation
    /// (Guo 2024 table 1 and the reduced blocks of tables 2–3).
    pub blocks: Vec<BlockGcn>,
}

/// One entry of [`Separation::table`]: a set of columns and its two GCNs.
#[derive(Clone, Debug, PartialEq)]
pub struct GcnRow {
    /// What the columns are: `full`, a block, a branch `d-d2`, a reduced block `d[-d3]` or
    /// `separated`.
    pub label: String,
    /// Eq. 14 over all the poses (the separation's decisions).
    pub gcn: Real,
    /// Guo's GCN, eq. 14 averaged over pose counts ([`gcn_mean`]).
    pub gcn_mean: Real,
}

/// One block's GCN (eq. 14) before and after the separation.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockGcn {
    /// The block: `theta`, `d`, `a`, `alpha`, `beta`, `base` or `tool` ([`Param::block`]).
    pub name: &'static str,
    /// GCN of the whole block.
    pub gcn_before: Real,
    /// GCN of the block's kept parameters (0 when none is kept).
    pub gcn_after: Real,
    /// Guo's GCN of the whole block: eq. 14 averaged over pose counts ([`gcn_mean`]).
    pub gcn_mean_before: Real,
    /// … of the block's kept parameters.
    pub gcn_mean_after: Real,
}

impl Separation {
    /// GCN of the full model (every parameter passed in).
    pub fn gcn_full(&self) -> Real {
        self.lookup("full", |r| r.gcn)
    }

    /// GCN of the kept parameters (Guo's J_p°, eq. 28).
    pub fn gcn_separated(&self) -> Real {
        self.lookup("separated", |r| r.gcn)
    }

    /// Guo's reconstructed model J_p (eq. 27): the input parameters without every
    /// [`Separation::ill_conditioned`] one, in the input order.
    pub fn reduced(&self, params: &[Param]) -> Vec<Param> {
        params
            .iter()
            .copied()
            .filter(|p| !self.ill_conditioned.contains(p))
            .collect()
    }

    /// Guo's GCN (averaged over pose counts) of the full model.
    pub fn gcn_mean_full(&self) -> Real {
        self.lookup("full", |r| r.gcn_mean)
    }

    /// Guo's GCN (averaged over pose counts) of the kept parameters (J_p°, eq. 28).
    pub fn gcn_mean_separated(&self) -> Real {
        self.lookup("separated", |r| r.gcn_mean)
    }

    fn lookup(&self, label: &str, value: impl Fn(&GcnRow) -> Real) -> Real {
        self.table
            .iter()
            .find(|r| r.label == label)
            .map_or(Real::NAN, value)
    }

    /// The report as JSON (docs/formats.md `identifiability --gcn-blocks`, `summary.json`
    /// `separation`): `blocks` (name → `gcn_before`, `gcn_after`), `removed` (names, in the
    /// order removed), `kept`, `gcn_full`, `gcn_separated` and `table` (every GCN computed, in
    /// order, as `{"label", "gcn"}`). Infinite GCNs are written as `null`.
    pub fn to_json(&self) -> serde_json::Value {
        use serde_json::json;
        let names = |v: &[Param]| v.iter().map(|p| p.to_string()).collect::<Vec<_>>();
        let blocks: serde_json::Map<String, serde_json::Value> = self
            .blocks
            .iter()
            .map(|b| {
                (
                    b.name.to_string(),
                    json!({
                        "gcn_before": b.gcn_before,
                        "gcn_after": b.gcn_after,
                        "gcn_mean_before": b.gcn_mean_before,
                        "gcn_mean_after": b.gcn_mean_after,
                    }),
                )
            })
            .collect();
        json!({
            "blocks": blocks,
            "removed": names(&self.removed),
            "kept": names(&self.kept),
            "ill_conditioned": names(&self.ill_conditioned),
            "gcn_full": self.gcn_full(),
            "gcn_separated": self.gcn_separated(),
            "gcn_mean_full": self.gcn_mean_full(),
            "gcn_mean_separated": self.gcn_mean_separated(),
            "table": self
                .table
                .iter()
                .map(|r| json!({"label": r.label, "gcn": r.gcn, "gcn_mean": r.gcn_mean}))
                .collect::<Vec<_>>(),
        })
    }
}

/// Separates ill-conditioned parameters of `params` over the poses `qs` (internal units):
/// see the module docs (Guo 2024 §3.1). `threshold` is the GCN limit (the paper's 1e2).
pub fn separate(
    robot: &Robot,
    params: &[Param],
    qs: &[Vec<Real>],
    measure: Measure,
    threshold: Real,
) -> Separation {
    let cols = Columns::new(params, robot.dof());
    let j = jacobian(robot, &cols, qs, measure);
    let m = qs.len();
    // Eq. 14 on the poses passed in (the decisions) and Guo's average over pose counts.
    let sub_gcn = |idx: &[usize]| -> (Real, Real) {
        if idx.is_empty() {
            return (0.0, 0.0);
        }
        let s: DMatrix<Real> = j.select_columns(idx);
        (gcn(&s, m), gcn_mean(&s, measure.rows()))
    };
    let mut table = Vec::new();
    let mut record = |label: String, (gcn, gcn_mean): (Real, Real)| {
        table.push(GcnRow {
            label,
            gcn,
            gcn_mean,
        });
        gcn
    };
    let all: Vec<usize> = (0..params.len()).collect();
    record("full".to_string(), sub_gcn(&all));
    // Blocks in order of first appearance.
    let mut blocks: Vec<(&'static str, Vec<usize>)> = Vec::new();
    for (c, p) in params.iter().enumerate() {
        match blocks.iter_mut().find(|(b, _)| *b == p.block()) {
            Some((_, v)) => v.push(c),
            None => blocks.push((p.block(), vec![c])),
        }
    }
    let mut removed_cols: Vec<usize> = Vec::new();
    // Guo's eq. 27: the parameters whose single removal brings their block under.
    let mut single: Vec<usize> = Vec::new();
    let mut offending = Vec::new();
    let mut before = Vec::with_capacity(blocks.len());
    for (name, idx) in &blocks {
        let g = sub_gcn(idx);
        record(name.to_string(), g);
        before.push(g);
        if g.0.is_nan() || g.0 > threshold {
            offending.push((*name, idx.clone()));
        }
    }
    for (name, mut idx) in offending {
        let mut tag = String::new();
        loop {
            // A block of one parameter is over the threshold only when its column is zero
            // (the parameter moves no point): it is removed, leaving an empty block.
            if idx.is_empty() {
                break;
            }
            let mut best: Option<((Real, Real), usize)> = None;
            for pos in 0..idx.len() {
                let rest: Vec<usize> = idx
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != pos)
                    .map(|(_, &c)| c)
                    .collect();
                let g = sub_gcn(&rest);
                record(format!("{name}{tag}-{}", params[idx[pos]]), g);
                if tag.is_empty() && g.0 <= threshold {
                    single.push(idx[pos]);
                }
                // Smallest GCN, ties (and NaN-free infinities) to the later parameter.
                if best.is_none_or(|(bg, _)| g.0 <= bg.0) {
                    best = Some((g, pos));
                }
            }
            let Some((g, pos)) = best else { break };
            let c = idx.remove(pos);
            removed_cols.push(c);
            tag.push_str(&format!("-{}", params[c]));
            if record(format!("{name}[{tag}]"), g) <= threshold {
                break;
            }
        }
    }
    let kept_idx: Vec<usize> = all
        .iter()
        .copied()
        .filter(|c| !removed_cols.contains(c))
        .collect();
    record("separated".to_string(), sub_gcn(&kept_idx));
    let ill: Vec<usize> = all
        .iter()
        .copied()
        .filter(|c| removed_cols.contains(c) || single.contains(c))
        .collect();
    let reduced_idx: Vec<usize> = all.iter().copied().filter(|c| !ill.contains(c)).collect();
    record("reduced".to_string(), sub_gcn(&reduced_idx));
    let blocks = blocks
        .iter()
        .zip(before)
        .map(|((name, idx), (gcn_before, gcn_mean_before))| {
            let kept: Vec<usize> = idx
                .iter()
                .copied()
                .filter(|c| !removed_cols.contains(c))
                .collect();
            let (gcn_after, gcn_mean_after) = sub_gcn(&kept);
            BlockGcn {
                name,
                gcn_before,
                gcn_after,
                gcn_mean_before,
                gcn_mean_after,
            }
        })
        .collect();
    Separation {
        kept: kept_idx.iter().map(|&c| params[c]).collect(),
        removed: removed_cols.iter().map(|&c| params[c]).collect(),
        ill_conditioned: ill.iter().map(|&c| params[c]).collect(),
        table,
        blocks,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::rng::from_seed;
    use crate::robot::identifiability::analyse;
    use crate::robot::sampling::uniform_joint_poses;

    #[test]
    fn separates_d2_d3_on_irb2600_like_identifiability() {
        let robot = crate::robot::builtin::irb2600();
        let params: Vec<Param> = robot
            .params()
            .into_iter()
            .filter(|p| p.joint().is_some())
            .collect();
        let qs = uniform_joint_poses(&robot, 50, &mut from_seed(5));
        let sep = separate(&robot, &params, &qs, Measure::Position, 1e2);
        let ident = analyse(&robot, &params, &qs, Measure::Position);
        // The d block is ill-conditioned: d2 and d3 act along parallel axes.
        let d_gcn = sep.table.iter().find(|r| r.label == "d").map(|r| r.gcn);
        assert!(d_gcn.is_some_and(|g| g > 1e6), "{:?}", sep.table);
        let removed_d: Vec<Param> = sep
            .removed
            .iter()
            .copied()
            .filter(|p| matches!(p, Param::D(_)))
            .collect();
        assert_eq!(removed_d.len(), 1, "{:?}", sep.removed);
        assert!(matches!(removed_d[0], Param::D(1) | Param::D(2)));
        // identifiability names the same dependent pair.
        assert!(ident
            .groups
            .iter()
            .any(|g| g.contains(&Param::D(1)) && g.contains(&Param::D(2))));
        // Every block of the reconstructed model is under the threshold: the reduced d block
        // entry is.
        let reduced = sep
            .table
            .iter()
            .find(|r| r.label.starts_with("d[") && !r.label.contains("]-"))
            .map(|r| r.gcn);
        assert!(reduced.is_some_and(|g| g <= 1e2), "{:?}", sep.table);
        assert!(sep.kept.len() + sep.removed.len() == params.len());
        let sep_gcn = sep.gcn_separated();
        // Guo's J_p removes both members of the pair.
        assert!(sep.ill_conditioned.contains(&Param::D(1)), "{:?}", sep);
        assert!(sep.ill_conditioned.contains(&Param::D(2)), "{:?}", sep);
        assert!(!sep.reduced(&params).contains(&Param::D(1)));
        assert_eq!(sep.table.last().map(|r| r.label.as_str()), Some("reduced"));
        let full_gcn = sep.table[0].gcn;
        assert!(sep_gcn <= full_gcn, "{sep_gcn} vs {full_gcn}");
    }

    #[test]
    fn a_well_conditioned_block_is_pruned() {
        let robot = crate::robot::builtin::irb2600();
        let params = vec![Param::A(0), Param::A(1), Param::A(2)];
        let qs = uniform_joint_poses(&robot, 30, &mut from_seed(6));
        let sep = separate(&robot, &params, &qs, Measure::Position, 1e2);
        assert!(sep.removed.is_empty());
        assert_eq!(sep.kept, params);
        // full, a, separated, reduced
        assert_eq!(sep.table.len(), 4);
        assert!(sep.ill_conditioned.is_empty());
        // Guo's average flags the block that one pose cannot see in full: the first count's
        // 3 × 3 block has rank 2 (x1, x2 and x3 are all normal to the parallel z2 and z3).
        assert!(sep.blocks[0].gcn_before < 1.0, "{:?}", sep.blocks);
        assert!(sep.blocks[0].gcn_mean_before > 1e2, "{:?}", sep.blocks);
        let one = jacobian(
            &robot,
            &Columns::new(&params, 6),
            &qs[..1],
            Measure::Position,
        );
        let sv = one.singular_values();
        assert!(sv.min() <= 1e-12 * sv.max(), "{sv}");
        assert_eq!(analyse(&robot, &params, &qs, Measure::Position).rank, 3);
    }

    /// A parameter that moves no point is separated even alone in its block: on a one-joint
    /// robot whose tool point lies on the frame's origin after the joint, α1 (a twist about
    /// that frame's x axis) moves nothing, and its block's GCN is infinite.
    #[test]
    fn a_parameter_alone_in_its_block_that_moves_nothing_is_removed() {
        let text = "name = \"one\"\nconvention = \"dh\"\nlength_unit = \"mm\"\n\
                    angle_unit = \"deg\"\n[[joints]]\ntype = \"revolute\"\nalpha = 0.0\n\
                    a = 300.0\nd = 200.0\ntheta = 0.0\nlimits = [-170.0, 170.0]\n";
        let robot = crate::robot::parse_robot_file(text, std::path::Path::new("one.toml")).unwrap();
        let params = robot.joint_params();
        let qs = uniform_joint_poses(&robot, 20, &mut from_seed(7));
        let sep = separate(&robot, &params, &qs, Measure::Position, 1e2);
        assert_eq!(sep.removed, vec![Param::Alpha(0)], "{:?}", sep.table);
        assert!(sep.ill_conditioned.contains(&Param::Alpha(0)));
        let alpha = sep.blocks.iter().find(|b| b.name == "alpha").unwrap();
        assert!(alpha.gcn_before.is_infinite() || alpha.gcn_before.is_nan());
        assert_eq!(alpha.gcn_after, 0.0);
        assert!(sep.gcn_separated() <= 1e2, "{:?}", sep.table);
        // The one-parameter blocks of the rest keep their parameter (GCN 1/m).
        assert_eq!(sep.kept, vec![Param::Theta(0), Param::D(0), Param::A(0)]);
    }
}
