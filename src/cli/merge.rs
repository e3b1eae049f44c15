//! `calbench merge DIR… --out DIR`: the partial results of `run --shard I/N` combined into
//! the output of the whole run.

use std::path::PathBuf;

use anyhow::Result;
use calbench::study::reporter::Terminal;

use super::{print_table, writable_folder};

/// Arguments of `calbench merge`.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// The shard folders.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub record: super::record::RecordFlags,
}

/// Checks that the folders are the N shards of one run, writes the whole run's files and
/// prints its table.
pub fn run(args: &MergeArgs) -> Result<()> {
    let out = &args.out;
    // The guard of `run` and `run --resume`: the shards are not overwritten, then the folder
    // is checked and probed once (`writable_folder`).
    calbench::report::guard::guard_out(out, "--out", &super::run::OUTPUTS, &args.dirs)?;
    writable_folder(out, &super::run::OUTPUTS)?;
    let db = args.record.open()?;
    let r = match calbench::runner::shard::merge(&args.dirs, out, &Terminal)? {
        calbench::runner::shard::Merged::Run(r) => *r,
        calbench::runner::shard::Merged::Cells(table) => {
            out!(
                "{table}\nmerged {} shards; report: {}",
                args.dirs.len(),
                out.join("report.md").display()
            );
            let record = || super::record::of_study(out, calbench::results::Kind::Merge);
            return args.record.finish(db, record);
        }
    };
    print_table(&r);
    out!(
        "\nmerged {} shards; report: {}",
        args.dirs.len(),
        out.join("report.md").display()
    );
    let record = || super::record::of_run(out, &r.scenario, calbench::results::Kind::Merge);
    args.record.finish(db, record)
}
