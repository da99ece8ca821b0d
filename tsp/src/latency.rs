//! Minimum-latency open paths (the travelling repairman problem): visit
//! every node from a fixed start so that the *sum of arrival costs* is
//! least, not the path's length.
//!
//! A search robot that may find its target behind any frontier wants each
//! frontier reached early, not the whole set covered cheaply: with the
//! target equally likely behind each of `n` frontiers, the expected cost
//! until the right one is reached is the path's latency divided by `n`.
//! The shortest path may leave a frontier two metres away for last because
//! it lies on the way back from a long corridor; the minimum-latency path
//! visits it first.
//!
//! On a path `π_0 = start, π_1, ..., π_{n-1}` the latency is
//! `Σ_k A(π_k)` with `A(π_k) = Σ_{j <= k} c(π_{j-1}, π_j)`, i.e. edge `j`
//! counts `n - j` times.

use crate::construct::nearest_neighbour;
use crate::error::TspError;
use crate::held_karp::backtrack;
use crate::matrix::CostMatrix;
use crate::solver::Method;

/// A minimum-latency open path.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LatencyPath {
    /// Every node exactly once, the start first.
    pub order: Vec<usize>,
    /// Sum of the arrival costs of every node but the start ([`latency`]).
    pub latency: f64,
    /// The path's length (sum of its arcs).
    pub cost: f64,
    /// How it was computed: [`Method::Exact`] (dynamic programming) or
    /// [`Method::Heuristic`] (nearest neighbour and local search).
    pub method: Method,
}

/// Latency of the open path `order` on `m`: the sum over its nodes after
/// the first of the cost of the path up to them.
///
/// # Errors
/// [`TspError::NodeOutOfRange`] for an index outside the matrix.
///
/// # Examples
/// ```
/// use sornav_tsp::{CostMatrix, latency};
/// let xs: [f64; 3] = [0.0, 1.0, 3.0];
/// let m = CostMatrix::from_fn(3, |i, j| (xs[i] - xs[j]).abs())?;
/// assert_eq!(latency(&m, &[0, 1, 2])?, 1.0 + 3.0);
/// assert_eq!(latency(&m, &[0, 2, 1])?, 3.0 + 5.0);
/// # Ok::<(), sornav_tsp::TspError>(())
/// ```
pub fn latency(m: &CostMatrix, order: &[usize]) -> Result<f64, TspError> {
    let n = m.len();
    if let Some(&v) = order.iter().find(|&&v| v >= n) {
        return Err(TspError::NodeOutOfRange { node: v, n });
    }
    Ok(latency_of(m.as_slice(), n, order, None))
}

/// [`weighted_latency`] on a row-major `n x n` slice (`weights` by node,
/// `None`: all 1), indices unchecked.
fn latency_of(c: &[f64], n: usize, order: &[usize], weights: Option<&[f64]>) -> f64 {
    let (mut arrival, mut sum) = (0.0, 0.0);
    for w in order.windows(2) {
        arrival += c[w[0] * n + w[1]];
        sum += weights.map_or(1.0, |ws| ws[w[1]]) * arrival;
    }
    sum
}

/// Weighted latency of the open path `order`: `Σ_k weights[π_k] A(π_k)`
/// over its nodes after the first, `A` the cost of the path up to them
/// (the start's weight is never read).
///
/// # Errors
/// [`TspError::NodeOutOfRange`] for an index outside the matrix,
/// [`TspError::InconsistentProblem`] for weights of the wrong length.
pub fn weighted_latency(m: &CostMatrix, order: &[usize], weights: &[f64]) -> Result<f64, TspError> {
    let n = m.len();
    if weights.len() != n {
        return Err(TspError::InconsistentProblem(format!(
            "{} weights for {n} nodes",
            weights.len()
        )));
    }
    if let Some(&v) = order.iter().find(|&&v| v >= n) {
        return Err(TspError::NodeOutOfRange { node: v, n });
    }
    Ok(latency_of(m.as_slice(), n, order, Some(weights)))
}

/// Minimum-latency open path from `start` through every node of `m`.
///
/// Instances of at most `exact_max_nodes` nodes (and never more than
/// [`LATENCY_EXACT_MAX_NODES`]) are solved exactly by dynamic programming
/// over subsets: the arc into `j` after visiting the set `S` (start
/// included) counts `n - |S|` times, once for `j` and for every node after
/// it, so `D[S + j][j] = min_i D[S][i] + (n - |S|) c(i, j)`. Larger ones
/// start from the better of nearest neighbour and
/// `initial` (a permutation starting at `start`, e.g. the previous plan)
/// and descend with first-improvement moves until none improves by more
/// than a relative `1e-12`: moving a stretch of one to three nodes
/// elsewhere (Or-opt) and reversing a stretch (2-opt). Deterministic.
///
/// # Errors
/// [`TspError::NodeOutOfRange`] for a bad `start`;
/// [`TspError::InvalidInitialOrder`] when `initial` is not a permutation
/// starting at `start`.
///
/// # Complexity
/// Exact: `O(2^n n^2)`. Heuristic: each descent pass tries `O(n^2)` moves
/// priced in `O(n)` each, so `O(n^3)` per pass; passes are at most
/// [`LATENCY_MAX_PASSES`].
///
/// # Examples
/// ```
/// use sornav_tsp::{CostMatrix, Solver, SolverConfig, min_latency_path};
/// // Robot at x = 0, one frontier at -1, four frontiers at 1.5 .. 3.
/// let xs: [f64; 6] = [0.0, -1.0, 1.5, 2.0, 2.5, 3.0];
/// let m = CostMatrix::from_fn(6, |i, j| (xs[i] - xs[j]).abs())?;
/// // The shortest path takes the single frontier first (1 + 4 = 5 m) ...
/// let shortest = Solver::new(SolverConfig::default())?.open_path(&m, 0, None)?;
/// assert_eq!(shortest.order, vec![0, 1, 2, 3, 4, 5]);
/// // ... the least latency serves the four first (arrivals 1.5 .. 3, then 7).
/// let path = min_latency_path(&m, 0, None, 13)?;
/// assert_eq!(path.order, vec![0, 2, 3, 4, 5, 1]);
/// assert_eq!((path.cost, path.latency), (7.0, 1.5 + 2.0 + 2.5 + 3.0 + 7.0));
/// # Ok::<(), sornav_tsp::TspError>(())
/// ```
pub fn min_latency_path(
    m: &CostMatrix,
    start: usize,
    initial: Option<&[usize]>,
    exact_max_nodes: usize,
) -> Result<LatencyPath, TspError> {
    solve(m, start, None, initial, exact_max_nodes)
}

/// As [`min_latency_path`], each node's arrival cost counted `weights[v]`
/// times ([`weighted_latency`]): with `weights` the probabilities that the
/// target lies behind each node, the objective is the expected cost of
/// reaching it. The start's weight is not read.
///
/// # Errors
/// As [`min_latency_path`], and [`TspError::InconsistentProblem`] when
/// `weights` does not hold one finite, non-negative value per node.
///
/// # Examples
/// ```
/// use sornav_tsp::{CostMatrix, min_weighted_latency_path};
/// // The cluster of four small frontiers (weight 1 each) at 1.5 .. 3 m
/// // waits when the single frontier at -1 m opens far more (weight 10).
/// let xs: [f64; 6] = [0.0, -1.0, 1.5, 2.0, 2.5, 3.0];
/// let m = CostMatrix::from_fn(6, |i, j| (xs[i] - xs[j]).abs())?;
/// let w = [0.0, 10.0, 1.0, 1.0, 1.0, 1.0];
/// let path = min_weighted_latency_path(&m, 0, &w, None, 13)?;
/// assert_eq!(path.order, vec![0, 1, 2, 3, 4, 5]);
/// # Ok::<(), sornav_tsp::TspError>(())
/// ```
pub fn min_weighted_latency_path(
    m: &CostMatrix,
    start: usize,
    weights: &[f64],
    initial: Option<&[usize]>,
    exact_max_nodes: usize,
) -> Result<LatencyPath, TspError> {
    solve(m, start, Some(weights), initial, exact_max_nodes)
}

fn solve(
    m: &CostMatrix,
    start: usize,
    weights: Option<&[f64]>,
    initial: Option<&[usize]>,
    exact_max_nodes: usize,
) -> Result<LatencyPath, TspError> {
    let n = m.len();
    if start >= n {
        return Err(TspError::NodeOutOfRange { node: start, n });
    }
    if let Some(w) = weights
        && (w.len() != n || !w.iter().all(|v| v.is_finite() && *v >= 0.0))
    {
        return Err(TspError::InconsistentProblem(format!(
            "latency weights: {} given for {n} nodes, each must be finite and >= 0",
            w.len()
        )));
    }
    if let Some(init) = initial {
        check_initial(n, start, init)?;
    }
    // Relabel so that the start is node 0.
    let nodes: Vec<usize> = std::iter::once(start)
        .chain((0..n).filter(|&v| v != start))
        .collect();
    let mut c = Vec::with_capacity(n * n);
    for &i in &nodes {
        c.extend(nodes.iter().map(|&j| m.cost(i, j)));
    }
    let relabelled: Option<Vec<f64>> = weights.map(|w| nodes.iter().map(|&v| w[v]).collect());
    let w = relabelled.as_deref();
    let (order, method) = if n <= exact_max_nodes.clamp(2, LATENCY_EXACT_MAX_NODES) {
        (exact(&c, n, w), Method::Exact)
    } else {
        let mut relabel = vec![0; n];
        for (r, &v) in nodes.iter().enumerate() {
            relabel[v] = r;
        }
        let nn = nearest_neighbour(&c, n);
        let mut best = nn;
        if let Some(init) = initial {
            let hint: Vec<usize> = init.iter().map(|&v| relabel[v]).collect();
            if latency_of(&c, n, &hint, w) < latency_of(&c, n, &best, w) {
                best = hint;
            }
        }
        descend(&c, n, w, &mut best);
        (best, Method::Heuristic)
    };
    let order: Vec<usize> = order.into_iter().map(|r| nodes[r]).collect();
    let lat = latency_of(m.as_slice(), n, &order, weights);
    let cost = m.path_cost(&order).unwrap_or(f64::NAN);
    Ok(LatencyPath {
        order,
        latency: lat,
        cost,
        method,
    })
}

/// Largest instance solved by the exact dynamic programme (its table has
/// `2^(n-1) (n-1)` entries: 49,152 at 13 nodes, 9.4 M at 20).
pub const LATENCY_EXACT_MAX_NODES: usize = 20;

/// Cap on the heuristic's descent passes (each pass either improves the
/// latency or ends the search; the cap bounds pathological cases).
pub const LATENCY_MAX_PASSES: usize = 200;

fn check_initial(n: usize, start: usize, initial: &[usize]) -> Result<(), TspError> {
    let bad = |msg: String| Err(TspError::InvalidInitialOrder(msg));
    if initial.len() != n {
        return bad(format!("{} nodes given, the matrix has {n}", initial.len()));
    }
    if initial[0] != start {
        return bad(format!("the path must start at node {start}"));
    }
    let mut seen = vec![false; n];
    for &v in initial {
        if v >= n || std::mem::replace(&mut seen[v], true) {
            return bad(format!("node {v} is out of range or repeated"));
        }
    }
    Ok(())
}

/// Exact minimum-(weighted-)latency path from node 0 on the row-major
/// `n x n` `c` (`2 <= n <= LATENCY_EXACT_MAX_NODES`); ties keep the lowest
/// index. With `S` the nodes visited before an arc (the start aside), the
/// arc counts `W - W(S)` times, `W` the total weight: a function of `S`.
fn exact(c: &[f64], n: usize, weights: Option<&[f64]>) -> Vec<usize> {
    if n <= 2 {
        return (0..n).collect();
    }
    let k = n - 1; // nodes 1..n are bits 0..k
    let full = (1usize << k) - 1;
    let mut dp = vec![f64::INFINITY; (full + 1) * k];
    let mut parent = vec![u8::MAX; (full + 1) * k];
    let wt = |j: usize| weights.map_or(1.0, |w| w[j + 1]);
    let total: f64 = (0..k).map(wt).sum();
    // Weight of each subset of 1..n, built from the subset without its
    // lowest bit.
    let mut subset_weight = vec![0.0; full + 1];
    for mask in 1..=full {
        let low = mask.trailing_zeros() as usize;
        subset_weight[mask] = subset_weight[mask & (mask - 1)] + wt(low);
    }
    // The first arc counts for every node after the start.
    for j in 0..k {
        dp[(1 << j) * k + j] = total * c[j + 1];
    }
    for mask in 1..=full {
        // Visited before the arc into j: the start and mask \ {j}, so the
        // arc counts for the nodes not yet visited, j included.
        for j in 0..k {
            if mask & (1 << j) == 0 {
                continue;
            }
            let prev = mask & !(1 << j);
            if prev == 0 {
                continue;
            }
            let weight = total - subset_weight[prev];
            let (mut best, mut arg) = (f64::INFINITY, u8::MAX);
            let mut rest = prev;
            while rest != 0 {
                let i = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                let v = dp[prev * k + i] + weight * c[(i + 1) * n + j + 1];
                if v < best {
                    best = v;
                    arg = i as u8;
                }
            }
            dp[mask * k + j] = best;
            parent[mask * k + j] = arg;
        }
    }
    let last = (0..k)
        .min_by(|&a, &b| {
            dp[full * k + a]
                .total_cmp(&dp[full * k + b])
                .then(a.cmp(&b))
        })
        .unwrap_or(0);
    backtrack(&parent, k, last)
}

/// First-improvement descent on `order` (node 0 first and fixed): Or-opt
/// moves of stretches of 1-3 nodes, then 2-opt reversals, repeated while a
/// pass improves (at most [`LATENCY_MAX_PASSES`] passes).
fn descend(c: &[f64], n: usize, w: Option<&[f64]>, order: &mut Vec<usize>) {
    let mut best = latency_of(c, n, order, w);
    let mut trial = Vec::with_capacity(n);
    for _ in 0..LATENCY_MAX_PASSES {
        let before = best;
        // Or-opt: stretch [i, i + len) moved to before position `at` of
        // the remaining path.
        let mut rest = Vec::with_capacity(n);
        for len in 1..=3usize {
            let mut i = 1;
            while i + len <= n {
                rest.clear();
                rest.extend_from_slice(&order[..i]);
                rest.extend_from_slice(&order[i + len..]);
                let mut moved = false;
                for at in (1..=rest.len()).filter(|&at| at != i) {
                    trial.clear();
                    trial.extend_from_slice(&rest[..at]);
                    trial.extend_from_slice(&order[i..i + len]);
                    trial.extend_from_slice(&rest[at..]);
                    let l = latency_of(c, n, &trial, w);
                    if l < best - 1e-12 * best.abs() {
                        best = l;
                        std::mem::swap(order, &mut trial);
                        moved = true;
                        break;
                    }
                }
                if !moved {
                    i += 1;
                }
            }
        }
        // 2-opt: reverse order[i..=j].
        for i in 1..n {
            for j in i + 1..n {
                trial.clear();
                trial.extend_from_slice(order);
                trial[i..=j].reverse();
                let l = latency_of(c, n, &trial, w);
                if l < best - 1e-12 * best.abs() {
                    best = l;
                    std::mem::swap(order, &mut trial);
                }
            }
        }
        if best >= before {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::lcg;
    use proptest::prelude::*;

    fn permutations(items: &[usize]) -> Vec<Vec<usize>> {
        if items.len() <= 1 {
            return vec![items.to_vec()];
        }
        let mut out = Vec::new();
        for i in 0..items.len() {
            let mut rest = items.to_vec();
            let head = rest.remove(i);
            for mut tail in permutations(&rest) {
                tail.insert(0, head);
                out.push(tail);
            }
        }
        out
    }

    /// Brute force over every order of the nodes other than `start`.
    fn brute(m: &CostMatrix, start: usize, weights: &[f64]) -> f64 {
        let rest: Vec<usize> = (0..m.len()).filter(|&v| v != start).collect();
        permutations(&rest)
            .into_iter()
            .map(|mut p| {
                p.insert(0, start);
                weighted_latency(m, &p, weights).unwrap()
            })
            .fold(f64::INFINITY, f64::min)
    }

    fn random_matrix(n: usize, seed: u64, symmetric: bool) -> CostMatrix {
        let mut r = lcg(seed);
        let pts: Vec<(f64, f64)> = (0..n).map(|_| (10.0 * r(), 10.0 * r())).collect();
        let extra: Vec<f64> = (0..n * n)
            .map(|_| if symmetric { 0.0 } else { 3.0 * r() })
            .collect();
        CostMatrix::from_fn(n, |i, j| {
            if i == j {
                0.0
            } else {
                let (a, b) = (pts[i], pts[j]);
                (a.0 - b.0).hypot(a.1 - b.1) + extra[i * n + j]
            }
        })
        .unwrap()
    }

    fn is_permutation_from(order: &[usize], n: usize, start: usize) -> bool {
        let mut s = order.to_vec();
        s.sort_unstable();
        order.first() == Some(&start) && s == (0..n).collect::<Vec<_>>()
    }

    #[test]
    fn trivial_sizes() {
        let one = CostMatrix::from_fn(1, |_, _| 0.0).unwrap();
        let p = min_latency_path(&one, 0, None, 13).unwrap();
        assert_eq!((p.order, p.latency, p.cost), (vec![0], 0.0, 0.0));
        let two = CostMatrix::from_fn(2, |i, j| if i == j { 0.0 } else { 4.0 }).unwrap();
        let p = min_latency_path(&two, 1, None, 13).unwrap();
        assert_eq!((p.order, p.latency), (vec![1, 0], 4.0));
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let m = random_matrix(5, 1, true);
        assert!(matches!(
            min_latency_path(&m, 5, None, 13),
            Err(TspError::NodeOutOfRange { node: 5, n: 5 })
        ));
        for bad in [
            &[0, 1, 2, 3][..],
            &[1, 0, 2, 3, 4],
            &[0, 1, 1, 3, 4],
            &[0, 1, 2, 3, 9],
        ] {
            assert!(matches!(
                min_latency_path(&m, 0, Some(bad), 13),
                Err(TspError::InvalidInitialOrder(_))
            ));
        }
        assert!(matches!(
            latency(&m, &[0, 7]),
            Err(TspError::NodeOutOfRange { node: 7, n: 5 })
        ));
        for w in [
            vec![1.0; 4],
            vec![1.0, 1.0, f64::NAN, 1.0, 1.0],
            vec![1.0, -1.0, 1.0, 1.0, 1.0],
        ] {
            assert!(matches!(
                min_weighted_latency_path(&m, 0, &w, None, 13),
                Err(TspError::InconsistentProblem(_))
            ));
        }
        assert!(matches!(
            weighted_latency(&m, &[0, 1], &[1.0; 3]),
            Err(TspError::InconsistentProblem(_))
        ));
    }

    #[test]
    fn many_frontiers_come_before_one_nearer_and_both_methods_agree() {
        // Latency serves the cluster first where the shortest path does not.
        let xs: [f64; 8] = [0.0, -1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0];
        let m = CostMatrix::from_fn(8, |i, j| (xs[i] - xs[j]).abs()).unwrap();
        let shortest = crate::Solver::new(crate::SolverConfig::default())
            .unwrap()
            .open_path(&m, 0, None)
            .unwrap();
        assert_eq!(shortest.order[1], 1);
        for exact_max in [0, 13] {
            let p = min_latency_path(&m, 0, None, exact_max).unwrap();
            assert_eq!(
                p.order,
                vec![0, 2, 3, 4, 5, 6, 7, 1],
                "exact_max {exact_max}"
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Exact = brute force on small random (a)symmetric instances, from
        /// any start; the heuristic (exact disabled) is a valid path no
        /// better than the optimum and no worse than nearest neighbour.
        #[test]
        fn exact_matches_brute_force_and_heuristic_is_bounded(
            n in 2usize..8,
            seed in any::<u64>(),
            symmetric in any::<bool>(),
            start_pick in any::<usize>(),
        ) {
            let m = random_matrix(n, seed, symmetric);
            let start = start_pick % n;
            let opt = brute(&m, start, &vec![1.0; n]);
            let exact = min_latency_path(&m, start, None, 13).unwrap();
            prop_assert!(is_permutation_from(&exact.order, n, start));
            prop_assert_eq!(exact.method, Method::Exact);
            prop_assert!((exact.latency - opt).abs() <= 1e-9 * opt.max(1.0), "{} vs {}", exact.latency, opt);
            prop_assert!((latency(&m, &exact.order).unwrap() - exact.latency).abs() < 1e-9);
            prop_assert!((m.path_cost(&exact.order).unwrap() - exact.cost).abs() < 1e-9);

            let heur = min_latency_path(&m, start, None, 0).unwrap();
            prop_assert!(is_permutation_from(&heur.order, n, start));
            prop_assert!(heur.latency >= opt - 1e-9 * opt.max(1.0));
            let nn = crate::nearest_neighbour_route(&m, start, None, false).unwrap();
            prop_assert!(heur.latency <= latency(&m, &nn.order).unwrap() + 1e-9);
        }

        /// Weighted: exact = brute force (zero weights included), the
        /// heuristic bounded by the optimum; unit weights give the
        /// unweighted optimum.
        #[test]
        fn weighted_exact_matches_brute_force(
            n in 2usize..8,
            seed in any::<u64>(),
            raw in proptest::collection::vec(0.0f64..5.0, 8),
            zero in any::<usize>(),
        ) {
            let m = random_matrix(n, seed, false);
            let mut w: Vec<f64> = raw[..n].to_vec();
            w[zero % n] = 0.0;
            let opt = brute(&m, 0, &w);
            let exact = min_weighted_latency_path(&m, 0, &w, None, 13).unwrap();
            prop_assert!(is_permutation_from(&exact.order, n, 0));
            prop_assert!((exact.latency - opt).abs() <= 1e-9 * opt.max(1.0), "{} vs {}", exact.latency, opt);
            prop_assert!((weighted_latency(&m, &exact.order, &w).unwrap() - exact.latency).abs() < 1e-9);
            let heur = min_weighted_latency_path(&m, 0, &w, None, 0).unwrap();
            prop_assert!(is_permutation_from(&heur.order, n, 0));
            prop_assert!(heur.latency >= opt - 1e-9 * opt.max(1.0));
            let unit = min_weighted_latency_path(&m, 0, &vec![1.0; n], None, 13).unwrap();
            let plain = min_latency_path(&m, 0, None, 13).unwrap();
            prop_assert!((unit.latency - plain.latency).abs() <= 1e-9 * plain.latency.max(1.0));
        }

        /// On larger instances the heuristic is a local optimum of its own
        /// moves (no single relocation or reversal improves it), never
        /// worse than nearest neighbour or the warm start, and the warm
        /// start is honoured as a candidate.
        #[test]
        fn heuristic_is_a_local_optimum(
            n in 14usize..40,
            seed in any::<u64>(),
            symmetric in any::<bool>(),
        ) {
            let m = random_matrix(n, seed, symmetric);
            let mut r = lcg(seed ^ 0x9e37);
            let mut warm: Vec<usize> = (1..n).collect();
            for i in (1..warm.len()).rev() {
                let j = (r() * (i + 1) as f64) as usize;
                warm.swap(i, j.min(i));
            }
            warm.insert(0, 0);
            let p = min_latency_path(&m, 0, Some(&warm), 13).unwrap();
            prop_assert_eq!(p.method, Method::Heuristic);
            prop_assert!(is_permutation_from(&p.order, n, 0));
            prop_assert!(p.latency <= latency(&m, &warm).unwrap() + 1e-9);
            let nn = crate::nearest_neighbour_route(&m, 0, None, false).unwrap();
            prop_assert!(p.latency <= latency(&m, &nn.order).unwrap() + 1e-9);
            let tol = 1e-9 * p.latency.max(1.0);
            for i in 1..n {
                for at in 1..n {
                    let mut t = p.order.clone();
                    let v = t.remove(i);
                    t.insert(at, v);
                    prop_assert!(latency(&m, &t).unwrap() >= p.latency - tol);
                }
                for j in i + 1..n {
                    let mut t = p.order.clone();
                    t[i..=j].reverse();
                    prop_assert!(latency(&m, &t).unwrap() >= p.latency - tol);
                }
            }
        }
    }
}
