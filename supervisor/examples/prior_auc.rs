//! Held-out evaluation of the embedded prior: ROC AUC of `P(target | other
//! objects in the region)` for target presence in the HM3D **val** regions.
//!
//! ```text
//! cargo run -p sornav-supervisor --example prior_auc -- ../shared/data/hm3d-sem-stats
//! ```
//!
//! Prints a Markdown table to stderr and one JSON line to stdout.

use std::path::PathBuf;
use std::process::ExitCode;

use sornav_supervisor::{
    CooccurrencePrior, Hm3dStats, OBJECTNAV_CATEGORIES, Split, evaluate_prior,
};

fn main() -> ExitCode {
    let Some(dir) = std::env::args_os().nth(1).map(PathBuf::from) else {
        eprintln!("usage: prior_auc <hm3d-sem-stats folder>");
        return ExitCode::from(2);
    };
    let stats = match Hm3dStats::read_dir(&dir) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let prior = CooccurrencePrior::embedded();
    let table = evaluate_prior(prior, &stats.regions, Split::Val, &OBJECTNAV_CATEGORIES);
    eprintln!("| target | val regions with target | without | ROC AUC |");
    eprintln!("|---|---|---|---|");
    let mut sum = 0.0;
    for (g, row) in &table {
        let auc = row.auc.unwrap_or(f64::NAN);
        sum += auc;
        eprintln!("| {g} | {} | {} | {auc:.3} |", row.positives, row.negatives);
    }
    let mean = sum / table.len() as f64;
    eprintln!("| mean | | | {mean:.3} |");
    let json = serde_json::json!({
        "split": "val",
        "val_regions": stats.split(Split::Val).count(),
        "auc": table.iter().map(|(g, r)| (g.clone(), serde_json::json!(r.auc))).collect::<serde_json::Map<_, _>>(),
        "mean_auc": mean,
    });
    println!("{json}");
    ExitCode::SUCCESS
}
