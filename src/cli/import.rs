//! `calbench import RAW --mapping MAPPING --out CSV`: a tracker's raw export turned into a
//! measurement CSV, as a mapping file says.

use std::path::PathBuf;

use anyhow::Result;

use super::guard_out_file;

/// Arguments of `calbench import`.
#[derive(clap::Args)]
pub struct ImportArgs {
    /// The raw export.
    pub raw: PathBuf,
    /// The mapping file (separator, decimal mark, columns, units, conventions).
    #[arg(long)]
    pub mapping: PathBuf,
    /// The measurement CSV to write (an existing file is replaced).
    #[arg(long)]
    pub out: PathBuf,
}

/// Imports the export and prints `N rows of RAW written to CSV`.
pub fn run(args: &ImportArgs) -> Result<()> {
    guard_out_file(&args.out, [&args.raw, &args.mapping])?;
    let n = calbench::measurement::import::import(&args.raw, &args.mapping, &args.out)?;
    out!(
        "{n} rows of {} written to {}",
        args.raw.display(),
        args.out.display()
    );
    Ok(())
}
