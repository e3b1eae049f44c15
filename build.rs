//! Build-time provenance for the results database (docs/formats.md, "The results
//! database"): the git commit the binary is built from, as `CALBENCH_GIT_COMMIT`.
//!
//! Taken, in order, from the environment variable `CALBENCH_GIT_COMMIT` at build time (a
//! packager building from a tarball sets it), from `git rev-parse HEAD` in the source tree,
//! or else `unknown` (a tarball without `.git` and without the variable). The build is rerun
//! when the checked-out commit changes.

use std::path::{Path, PathBuf};
use std::process::Command;

fn git(dir: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .args(args)
        .current_dir(dir)
        .output()
        .ok()?;
    let text = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (out.status.success() && !text.is_empty()).then_some(text)
}

fn main() {
    println!("cargo:rerun-if-env-changed=CALBENCH_GIT_COMMIT");
    let dir = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let commit = match std::env::var("CALBENCH_GIT_COMMIT") {
        Ok(c) if !c.trim().is_empty() => c.trim().to_string(),
        _ => match git(&dir, &["rev-parse", "HEAD"]) {
            Some(c) => {
                // Rebuild when HEAD moves: HEAD itself and the branch it points at.
                for file in [
                    git(&dir, &["rev-parse", "--git-path", "HEAD"]),
                    git(&dir, &["symbolic-ref", "-q", "HEAD"])
                        .and_then(|r| git(&dir, &["rev-parse", "--git-path", &r])),
                    git(&dir, &["rev-parse", "--git-path", "packed-refs"]),
                ]
                .into_iter()
                .flatten()
                {
                    let p = dir.join(file);
                    if p.exists() {
                        println!("cargo:rerun-if-changed={}", p.display());
                    }
                }
                c
            }
            None => "unknown".to_string(),
        },
    };
    println!("cargo:rustc-env=CALBENCH_GIT_COMMIT={commit}");
    println!("cargo:rerun-if-env-changed=CALBENCH_GIT_COMMIT_TIME");
    let time = match std::env::var("CALBENCH_GIT_COMMIT_TIME") {
        Ok(t) if !t.trim().is_empty() => t.trim().to_string(),
        _ if commit == "unknown" => String::new(),
        _ => git(&dir, &["show", "-s", "--format=%ct", &commit]).unwrap_or_default(),
    };
    println!("cargo:rustc-env=CALBENCH_GIT_COMMIT_TIME={time}");
}
