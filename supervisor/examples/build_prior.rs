//! Regenerates the embedded commonsense prior from the HM3D-Semantics
//! statistics (train scenes only):
//!
//! ```text
//! cargo run -p sornav-supervisor --example build_prior -- ../shared/data/hm3d-sem-stats [OUT.json]
//! ```
//!
//! Without `OUT.json` it overwrites the crate's
//! `data/hm3d_cooccurrence_prior.json`. The output is deterministic.

use std::path::PathBuf;
use std::process::ExitCode;

use sornav_supervisor::{CooccurrencePrior, Hm3dStats, PriorBuildConfig, Split};

fn main() -> ExitCode {
    let mut args = std::env::args_os().skip(1);
    let Some(dir) = args.next().map(PathBuf::from) else {
        eprintln!("usage: build_prior <hm3d-sem-stats folder> [out.json]");
        return ExitCode::from(2);
    };
    let out = args.next().map(PathBuf::from).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("data")
            .join("hm3d_cooccurrence_prior.json")
    });
    let stats = match Hm3dStats::read_dir(&dir) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let prior = match CooccurrencePrior::build(&stats.regions, PriorBuildConfig::default()) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Err(e) = std::fs::write(&out, prior.to_json()) {
        eprintln!("error: writing {}: {e}", out.display());
        return ExitCode::FAILURE;
    }
    eprintln!(
        "wrote {}: {} train scenes, {} train regions ({} val regions ignored, {} rows without a split), {} labels, {} targets",
        out.display(),
        prior.train_scenes,
        prior.train_regions,
        stats.split(Split::Val).count(),
        stats.skipped_rows,
        prior.labels.len(),
        prior.targets.len()
    );
    ExitCode::SUCCESS
}
