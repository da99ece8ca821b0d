//! Shared helpers: brute-force reference and random instances.
#![allow(dead_code)]

use std::collections::HashMap;
use std::path::Path;

use proptest::prelude::*;
use sornav_tsp::CostMatrix;

/// Optimal cost by enumerating every order of the free nodes.
///
/// Open path from `start` (to `end` if given), or closed tour when `closed`.
pub fn brute_force(m: &CostMatrix, start: usize, end: Option<usize>, closed: bool) -> f64 {
    let n = m.len();
    let mut free: Vec<usize> = (0..n).filter(|&v| v != start && Some(v) != end).collect();
    let mut best = f64::INFINITY;
    permute(&mut free, 0, &mut |perm| {
        let mut order = vec![start];
        order.extend_from_slice(perm);
        if let Some(e) = end {
            order.push(e);
        }
        let c = if closed {
            m.tour_cost(&order)
        } else {
            m.path_cost(&order)
        }
        .unwrap();
        if c < best {
            best = c;
        }
    });
    best
}

fn permute(v: &mut Vec<usize>, k: usize, f: &mut impl FnMut(&[usize])) {
    if k == v.len() {
        f(v);
        return;
    }
    for i in k..v.len() {
        v.swap(k, i);
        permute(v, k + 1, f);
        v.swap(k, i);
    }
}

/// Whether `order` is a permutation of `0..n`.
pub fn is_permutation(order: &[usize], n: usize) -> bool {
    let mut seen = vec![false; n];
    order.len() == n
        && order
            .iter()
            .all(|&v| v < n && !std::mem::replace(&mut seen[v], true))
}

/// Shape of random instances.
#[derive(Debug, Clone, Copy)]
pub enum Shape {
    /// Independent integer costs (asymmetric).
    Asymmetric,
    /// Euclidean distances of random points (symmetric).
    Euclidean,
    /// Euclidean plus a random per-arc asymmetric term.
    Skewed,
}

/// Random square matrices of `lo..=hi` nodes.
pub fn matrix(lo: usize, hi: usize) -> impl Strategy<Value = CostMatrix> {
    let shape = prop_oneof![
        Just(Shape::Asymmetric),
        Just(Shape::Euclidean),
        Just(Shape::Skewed)
    ];
    (lo..=hi, shape, any::<u64>()).prop_map(|(n, shape, seed)| build(n, shape, seed))
}

/// Deterministic instance from a seed (small LCG, no extra dependency).
pub fn build(n: usize, shape: Shape, seed: u64) -> CostMatrix {
    let mut s = seed | 1;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 33) as f64 / (1u64 << 31) as f64
    };
    let pts: Vec<(f64, f64)> = (0..n).map(|_| (next() * 100.0, next() * 100.0)).collect();
    let noise: Vec<f64> = (0..n * n).map(|_| next()).collect();
    CostMatrix::from_fn(n, |i, j| {
        let d = ((pts[i].0 - pts[j].0).powi(2) + (pts[i].1 - pts[j].1).powi(2))
            .sqrt()
            .round();
        match shape {
            Shape::Asymmetric => (noise[i * n + j] * 100.0).round(),
            Shape::Euclidean => d,
            Shape::Skewed => d + (noise[i * n + j] * 20.0).round(),
        }
    })
    .unwrap()
}

/// `name : value` lines of a TSPLIB `bestSolutions.txt`.
pub fn read_best(path: &Path) -> HashMap<String, f64> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter_map(|l| l.split_once(':'))
        .map(|(k, v)| (k.trim().to_string(), v.trim().parse().unwrap()))
        .collect()
}
