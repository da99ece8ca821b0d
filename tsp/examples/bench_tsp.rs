//! Benchmark: solve TSPLIB-format instances and print one JSON line each.
//!
//! ```text
//! cargo run --release -p sornav-tsp --example bench_tsp -- FILE...
//! ```
//!
//! Output per instance: `{"instance","n","open","cost","ms"}` where `ms` is
//! the median wall time of 5 solves (parsing excluded). An instance whose
//! column of node 1 is all zero is the open-tour form FUEL hands to LKH
//! (node 1 = robot, free return): it is solved as an open path from node 1
//! and `n` counts the frontiers (`DIMENSION - 1`). Anything else is solved
//! as a closed tour and `n` is `DIMENSION`.
use std::time::Instant;

use sornav_tsp::{CostMatrix, Solver, SolverConfig, tsplib};

const REPS: usize = 5;

fn is_open_form(m: &CostMatrix) -> bool {
    (1..m.len()).all(|i| m.cost(i, 0) == 0.0)
}

fn main() {
    let files: Vec<String> = std::env::args().skip(1).collect();
    if files.is_empty() {
        eprintln!("usage: bench_tsp FILE...");
        std::process::exit(2);
    }
    let solver = match Solver::new(SolverConfig::default()) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("bad configuration: {e}");
            std::process::exit(2);
        }
    };
    let mut failed = false;
    for file in &files {
        let inst = match tsplib::read(file) {
            Ok(i) => i,
            Err(e) => {
                eprintln!("{file}: {e}");
                failed = true;
                continue;
            }
        };
        let m = &inst.matrix;
        let open = is_open_form(m);
        let mut times = Vec::with_capacity(REPS);
        let mut cost = f64::NAN;
        for _ in 0..REPS {
            let t0 = Instant::now();
            let tour = if open {
                solver.open_path(m, 0, None)
            } else {
                solver.closed_tour(m, 0)
            };
            times.push(t0.elapsed().as_secs_f64() * 1e3);
            match tour {
                Ok(t) => cost = t.cost,
                Err(e) => {
                    eprintln!("{file}: {e}");
                    failed = true;
                    break;
                }
            }
        }
        if times.len() < REPS {
            continue;
        }
        times.sort_by(f64::total_cmp);
        let stem = std::path::Path::new(file)
            .file_stem()
            .map_or_else(|| file.clone(), |s| s.to_string_lossy().into_owned());
        let line = serde_json::json!({
            "instance": stem,
            "n": if open { m.len() - 1 } else { m.len() },
            "open": open,
            "cost": cost,
            "ms": times[REPS / 2],
        });
        println!("{line}");
    }
    if failed {
        std::process::exit(1);
    }
}
