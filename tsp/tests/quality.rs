//! Quality targets on the shared instances (quality only, never time):
//! * tsp-fuel (open paths as FUEL hands them to LKH): every cost <= 1.01 x
//!   LKH with FUEL's settings, total (mean) cost <= LKH's, exact optimum on
//!   every n = 10 instance;
//! * TSPLIB (symmetric and asymmetric) up to 150 cities: mean gap to the
//!   proven optimum <= 1 %, max <= 2 %.
mod common;

use std::collections::HashMap;

use common::read_best;
use sornav_tsp::{Solver, SolverConfig, tsplib};

#[test]
fn tsp_fuel_matches_lkh_with_fuel_settings() {
    let Some(dir) = sornav_test_support::shared_data("tsp-fuel") else {
        return;
    };
    let solver = Solver::new(SolverConfig::default()).unwrap();
    let table = std::fs::read_to_string(dir.join("reference.tsv")).unwrap();
    let header: Vec<&str> = table.lines().next().unwrap().split('\t').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (c_inst, c_lkh, c_exact) = (col("instance"), col("lkh_fuel_cost"), col("exact_cost"));
    let (mut ours_total, mut lkh_total, mut count) = (0.0, 0.0, 0);
    let mut per_size: HashMap<usize, (f64, f64)> = HashMap::new();
    for line in table.lines().skip(1).filter(|l| !l.is_empty()) {
        let f: Vec<&str> = line.split('\t').collect();
        let inst = tsplib::read(dir.join(format!("{}.atsp", f[c_inst]))).unwrap();
        let m = &inst.matrix;
        // Node 1 = robot; the return column is zero, so the open path from
        // the robot is what LKH's tour prices.
        assert!((1..m.len()).all(|i| m.cost(i, 0) == 0.0));
        let path = solver.open_path(m, 0, None).unwrap();
        let lkh: f64 = f[c_lkh].parse().unwrap();
        assert!(
            path.cost <= 1.01 * lkh,
            "{}: {} > 1.01 x LKH {}",
            f[c_inst],
            path.cost,
            lkh
        );
        if let Some(exact) = f.get(c_exact).and_then(|v| v.parse::<f64>().ok()) {
            assert_eq!(path.cost, exact, "{}: not the optimum", f[c_inst]);
        }
        let e = per_size.entry(m.len() - 1).or_default();
        e.0 += path.cost;
        e.1 += lkh;
        ours_total += path.cost;
        lkh_total += lkh;
        count += 1;
    }
    let mut sizes: Vec<_> = per_size.into_iter().collect();
    sizes.sort_by_key(|s| s.0);
    for (n, (ours, lkh)) in &sizes {
        eprintln!("n = {n}: ours / LKH = {:.5}", ours / lkh);
    }
    assert!(count >= 60, "only {count} instances");
    assert!(
        ours_total <= lkh_total,
        "mean cost {} > LKH's {}",
        ours_total / 60.0,
        lkh_total / 60.0
    );
}

#[test]
fn tsplib_up_to_150_cities_within_one_percent_on_average() {
    let Some(dir) = sornav_test_support::shared_data("tsplib") else {
        return;
    };
    let solver = Solver::new(SolverConfig::default()).unwrap();
    let mut gaps = Vec::new();
    for sub in ["tsp", "atsp"] {
        let best = read_best(&dir.join(sub).join("bestSolutions.txt"));
        let mut files: Vec<_> = std::fs::read_dir(dir.join(sub))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("tsp" | "atsp")))
            .collect();
        files.sort();
        for path in files {
            let inst = tsplib::read(&path).unwrap();
            if inst.matrix.len() > 150 {
                continue;
            }
            // bestSolutions.txt names kro124p "kro124".
            let opt = best
                .get(&inst.name)
                .or_else(|| best.get(inst.name.trim_end_matches('p')))
                .copied()
                .unwrap_or_else(|| panic!("no optimum for {}", inst.name));
            let tour = solver.closed_tour(&inst.matrix, 0).unwrap();
            let gap = tour.cost / opt - 1.0;
            eprintln!(
                "{}: n = {} gap = {:.3} %",
                inst.name,
                inst.matrix.len(),
                100.0 * gap
            );
            assert!(gap >= -1e-12, "{} below the proven optimum", inst.name);
            assert!(gap <= 0.02, "{}: gap {:.3} % > 2 %", inst.name, 100.0 * gap);
            gaps.push(gap);
        }
    }
    assert!(gaps.len() >= 20, "only {} instances", gaps.len());
    let mean = gaps.iter().sum::<f64>() / gaps.len() as f64;
    assert!(mean <= 0.01, "mean gap {:.3} % > 1 %", 100.0 * mean);
}
