//! Property and differential tests of the solvers.
mod common;

use approx::assert_relative_eq;
use common::{Shape, brute_force, build, is_permutation, matrix};
use proptest::prelude::*;
use sornav_tsp::{
    CostMatrix, HELD_KARP_MAX_NODES, MAX_ABS_COST, Method, Solver, SolverConfig, TspError,
    held_karp, nearest_neighbour_route,
};

/// A solver that never uses the exact DP (beyond 3 nodes).
fn heuristic_only(seed: u64) -> Solver {
    Solver::new(SolverConfig {
        exact_max_nodes: 0,
        kicks_per_node: 20,
        seed,
        ..SolverConfig::default()
    })
    .unwrap()
}

fn pick_end(n: usize, start: usize, e: usize, fixed: bool) -> Option<usize> {
    let e = e % n;
    (fixed && e != start).then_some(e)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn held_karp_equals_brute_force(m in matrix(1, 8), s in 0usize..8, e in 0usize..8, fixed: bool, closed: bool) {
        let n = m.len();
        let start = s % n;
        let end = if closed { None } else { pick_end(n, start, e, fixed) };
        let t = held_karp(&m, start, end, closed).unwrap();
        prop_assert!(is_permutation(&t.order, n));
        prop_assert_eq!(t.order[0], start);
        if let Some(e) = end { prop_assert_eq!(*t.order.last().unwrap(), e); }
        prop_assert_eq!(t.method, Method::Exact);
        prop_assert_eq!(t.closed, closed);
        let reference = brute_force(&m, start, end, closed);
        prop_assert!((t.cost - reference).abs() <= 1e-9 * reference.abs().max(1.0),
            "DP {} vs brute force {}", t.cost, reference);
        let priced = if closed { m.tour_cost(&t.order) } else { m.path_cost(&t.order) }.unwrap();
        prop_assert_eq!(priced, t.cost);
    }

    #[test]
    fn heuristic_is_valid_bounded_by_optimum_and_nearest_neighbour(
        m in matrix(4, 10), s in 0usize..10, e in 0usize..10, fixed: bool, closed: bool, seed: u64,
    ) {
        let n = m.len();
        let start = s % n;
        let end = if closed { None } else { pick_end(n, start, e, fixed) };
        let solver = heuristic_only(seed);
        let t = if closed { solver.closed_tour(&m, start) } else { solver.open_path(&m, start, end) }.unwrap();
        prop_assert!(is_permutation(&t.order, n));
        prop_assert_eq!(t.order[0], start);
        if let Some(e) = end { prop_assert_eq!(*t.order.last().unwrap(), e); }
        let exact = held_karp(&m, start, end, closed).unwrap().cost;
        let nn = nearest_neighbour_route(&m, start, end, closed).unwrap();
        prop_assert!(is_permutation(&nn.order, n));
        let tol = 1e-9 * exact.abs().max(1.0);
        prop_assert!(t.cost >= exact - tol, "heuristic {} below optimum {}", t.cost, exact);
        prop_assert!(t.cost <= nn.cost + tol, "heuristic {} worse than nearest neighbour {}", t.cost, nn.cost);
    }

    #[test]
    fn large_instances_stay_valid_and_beat_nearest_neighbour(m in matrix(14, 60), s in 0usize..60, seed: u64) {
        let n = m.len();
        let start = s % n;
        let solver = heuristic_only(seed);
        for end in [None, Some((start + 1) % n)] {
            let t = solver.open_path(&m, start, end).unwrap();
            prop_assert!(is_permutation(&t.order, n));
            prop_assert_eq!(t.order[0], start);
            let nn = nearest_neighbour_route(&m, start, end, false).unwrap();
            prop_assert!(t.cost <= nn.cost + 1e-6);
            prop_assert_eq!(t.cost, m.path_cost(&t.order).unwrap());
        }
        let t = solver.closed_tour(&m, start).unwrap();
        prop_assert!(is_permutation(&t.order, n));
        prop_assert!(t.cost <= nearest_neighbour_route(&m, start, None, true).unwrap().cost + 1e-6);
    }

    #[test]
    fn warm_start_is_never_worse_than_the_hint(m in matrix(5, 30), seed: u64) {
        let n = m.len();
        let hint: Vec<usize> = (0..n).collect();
        let t = heuristic_only(seed).open_path_from(&m, 0, None, &hint).unwrap();
        prop_assert!(is_permutation(&t.order, n));
        prop_assert!(t.cost <= m.path_cost(&hint).unwrap() + 1e-6);
    }
}

#[test]
fn heuristic_finds_the_optimum_of_moderate_instances() {
    // Differential check against Held-Karp just above its default range.
    let solver = heuristic_only(7);
    for (k, shape) in [Shape::Euclidean, Shape::Skewed, Shape::Asymmetric]
        .into_iter()
        .enumerate()
    {
        for seed in 0..4 {
            let m = build(15, shape, 1000 * k as u64 + seed);
            let exact = held_karp(&m, 0, None, false).unwrap().cost;
            let t = solver.open_path(&m, 0, None).unwrap();
            assert_relative_eq!(t.cost, exact, max_relative = 1e-9);
        }
    }
}

#[test]
fn same_seed_same_tour() {
    let m = build(80, Shape::Skewed, 3);
    let a = heuristic_only(11).open_path(&m, 0, None).unwrap();
    let b = heuristic_only(11).open_path(&m, 0, None).unwrap();
    assert_eq!(a, b);
}

#[test]
fn time_budget_stops_the_search() {
    let m = build(150, Shape::Euclidean, 5);
    let solver = Solver::new(SolverConfig {
        kicks_per_node: 1_000_000,
        time_budget: Some(std::time::Duration::from_millis(30)),
        ..SolverConfig::default()
    })
    .unwrap();
    let t = solver.closed_tour(&m, 3).unwrap();
    assert!(is_permutation(&t.order, 150));
    assert_eq!(t.order[0], 3);
}

#[test]
fn tiny_and_degenerate_inputs() {
    let solver = Solver::new(SolverConfig::default()).unwrap();
    let one = CostMatrix::new(1, vec![0.0]).unwrap();
    let t = solver.open_path(&one, 0, None).unwrap();
    assert_eq!((t.order.clone(), t.cost), (vec![0], 0.0));
    assert_eq!(solver.closed_tour(&one, 0).unwrap().cost, 0.0);
    let two = CostMatrix::from_rows(&[vec![0.0, 3.0], vec![5.0, 0.0]]).unwrap();
    assert_eq!(solver.open_path(&two, 1, Some(0)).unwrap().cost, 5.0);
    assert_eq!(solver.closed_tour(&two, 0).unwrap().cost, 8.0);
    // Equal costs everywhere: any permutation is optimal.
    let flat = CostMatrix::from_fn(40, |_, _| 1.0).unwrap();
    assert_eq!(solver.open_path(&flat, 5, None).unwrap().cost, 39.0);
}

#[test]
fn costs_up_to_the_bound_never_overflow() {
    // Beyond the bound: a typed error (sums of such entries overflow to
    // infinity, and the exact DP then lost its parent chain and returned a
    // non-permutation).
    assert!(matches!(
        CostMatrix::from_fn(3, |i, j| if i == j { 0.0 } else { f64::MAX / 5.0 }),
        Err(TspError::CostOutOfRange { row: 0, col: 1, .. })
    ));
    assert!(matches!(
        CostMatrix::new(2, vec![0.0, 1.0, -1.5 * MAX_ABS_COST, 0.0]),
        Err(TspError::CostOutOfRange { row: 1, col: 0, .. })
    ));
    // At the bound (exact multiples of a power of two, so that the debug
    // cost tracking of the local search sees no rounding): every solver
    // returns a permutation with a finite cost.
    let unit = 2f64.powi(994); // 1.7e299; 5 units < MAX_ABS_COST
    assert!(5.0 * unit <= MAX_ABS_COST);
    let solver = Solver::new(SolverConfig::default()).unwrap();
    for n in [2, 3, 5, 9, 13, 20, 40] {
        let m = CostMatrix::from_fn(n, |i, j| {
            if i == j {
                0.0
            } else {
                unit * ((i * 7 + j * 3) % 5 + 1) as f64
            }
        })
        .unwrap();
        let mut tours = vec![
            solver.open_path(&m, 0, None).unwrap(),
            solver.open_path(&m, 0, Some(n - 1)).unwrap(),
            solver.closed_tour(&m, n - 1).unwrap(),
            nearest_neighbour_route(&m, 0, None, false).unwrap(),
        ];
        if n <= HELD_KARP_MAX_NODES {
            tours.push(held_karp(&m, 1 % n, None, true).unwrap());
        }
        for t in tours {
            assert!(is_permutation(&t.order, n), "n = {n}: {:?}", t.order);
            assert!(t.cost.is_finite(), "n = {n}: {}", t.cost);
        }
    }
}

#[test]
fn bad_requests_are_typed_errors() {
    let m = build(6, Shape::Euclidean, 1);
    let solver = Solver::new(SolverConfig::default()).unwrap();
    assert_eq!(
        solver.open_path(&m, 6, None),
        Err(TspError::NodeOutOfRange { node: 6, n: 6 })
    );
    assert_eq!(
        solver.open_path(&m, 0, Some(9)),
        Err(TspError::NodeOutOfRange { node: 9, n: 6 })
    );
    assert_eq!(
        solver.open_path(&m, 2, Some(2)),
        Err(TspError::EndEqualsStart(2))
    );
    assert!(matches!(
        solver.open_path_from(&m, 0, None, &[0, 1, 2]),
        Err(TspError::InvalidInitialOrder(_))
    ));
    assert!(matches!(
        solver.open_path_from(&m, 0, None, &[1, 0, 2, 3, 4, 5]),
        Err(TspError::InvalidInitialOrder(_))
    ));
    assert!(matches!(
        solver.open_path_from(&m, 0, Some(5), &[0, 1, 2, 3, 5, 4]),
        Err(TspError::InvalidInitialOrder(_))
    ));
    assert!(matches!(
        solver.closed_tour_from(&m, 0, &[0, 1, 1, 3, 4, 5]),
        Err(TspError::InvalidInitialOrder(_))
    ));
    let big = build(HELD_KARP_MAX_NODES + 2, Shape::Euclidean, 1);
    assert!(matches!(
        held_karp(&big, 0, None, true),
        Err(TspError::TooLargeForExact { .. })
    ));
    assert!(matches!(
        held_karp(&m, 0, Some(1), true),
        Err(TspError::InvalidConfig(_))
    ));
    for bad in [
        SolverConfig {
            exact_max_nodes: HELD_KARP_MAX_NODES + 1,
            ..SolverConfig::default()
        },
        SolverConfig {
            candidates: 0,
            ..SolverConfig::default()
        },
    ] {
        assert!(matches!(Solver::new(bad), Err(TspError::InvalidConfig(_))));
    }
}

#[test]
fn matrices_reject_bad_values() {
    assert_eq!(CostMatrix::new(0, vec![]), Err(TspError::Empty));
    assert_eq!(
        CostMatrix::new(2, vec![0.0; 3]),
        Err(TspError::NotSquare { n: 2, len: 3 })
    );
    assert!(matches!(
        CostMatrix::new(2, vec![0.0, f64::NAN, 1.0, 0.0]),
        Err(TspError::NonFinite { row: 0, col: 1, .. })
    ));
    assert!(matches!(
        CostMatrix::from_rows(&[vec![0.0, 1.0], vec![0.0]]),
        Err(TspError::RaggedRow {
            row: 1,
            len: 1,
            n: 2
        })
    ));
    let json = r#"{"n":2,"data":[0.0,1.0,2.0]}"#;
    assert!(serde_json::from_str::<CostMatrix>(json).is_err());
    let m = build(5, Shape::Skewed, 2);
    let back: CostMatrix = serde_json::from_str(&serde_json::to_string(&m).unwrap()).unwrap();
    assert_eq!(back, m);
    assert_eq!(CostMatrix::from_dmatrix(&m.to_dmatrix()).unwrap(), m);
    assert!(matches!(
        m.path_cost(&[0, 7]),
        Err(TspError::NodeOutOfRange { node: 7, .. })
    ));
}

/// Issue 21: valid matrices mixing costs above ~1e16 with small ones made
/// the local search's tracked-cost check (debug builds) fire, since the
/// rounding of one move's delta exceeds a tolerance relative to a small tour
/// cost. Every solver must return a permutation priced like the matrix.
#[test]
fn huge_and_small_costs_mixed_stay_consistent() {
    for (big, seed) in [(1e17, 0u64), (3.3e16, 1), (1e20, 2), (7e250, 3)] {
        let n = 24;
        let m = CostMatrix::from_fn(n, |i, j| {
            if i == j {
                0.0
            } else if (i * 5 + j * 3 + seed as usize).is_multiple_of(4) {
                big * (1.0 + ((i + 2 * j) % 7) as f64 / 10.0)
            } else {
                1.0 + ((i * 13 + j * 7) % 17) as f64 * 0.37
            }
        })
        .unwrap();
        let solver = heuristic_only(seed);
        for closed in [false, true] {
            let t = if closed {
                solver.closed_tour(&m, 0)
            } else {
                solver.open_path(&m, 0, None)
            }
            .unwrap();
            assert!(is_permutation(&t.order, n));
            let priced = if closed {
                m.tour_cost(&t.order)
            } else {
                m.path_cost(&t.order)
            }
            .unwrap();
            assert_eq!(priced, t.cost, "big {big} closed {closed}");
            let nn = nearest_neighbour_route(&m, 0, None, closed).unwrap();
            assert!(t.cost <= nn.cost, "big {big}: {} > {}", t.cost, nn.cost);
        }
    }
}

/// Issue 21: a time budget of `i64::MAX` seconds validated and then
/// panicked ("overflow when adding duration to instant"); a kick budget of
/// `kicks_per_pair = 1e300` validated and never returned. Both are now
/// rejected when the configuration is built, naming the field and the limit.
#[test]
fn unbounded_budgets_are_rejected_with_their_limit() {
    use sornav_tsp::{MAX_KICKS_PER_NODE, MAX_KICKS_PER_PAIR, MAX_TIME_BUDGET};
    use std::time::Duration;
    let reject = |config: SolverConfig, field: &str| match Solver::new(config) {
        Err(TspError::InvalidConfig(msg)) => {
            assert!(msg.contains(field) && msg.contains("limit"), "{msg}");
        }
        other => panic!("{field}: expected InvalidConfig, got {other:?}"),
    };
    reject(
        SolverConfig {
            time_budget: Some(Duration::from_secs(i64::MAX as u64)),
            ..SolverConfig::default()
        },
        "time_budget",
    );
    reject(
        SolverConfig {
            kicks_per_pair: 1e300,
            ..SolverConfig::default()
        },
        "kicks_per_pair",
    );
    reject(
        SolverConfig {
            kicks_per_node: MAX_KICKS_PER_NODE + 1,
            ..SolverConfig::default()
        },
        "kicks_per_node",
    );
    // At the limits the solver is built and finishes.
    let at_limits = Solver::new(SolverConfig {
        kicks_per_node: MAX_KICKS_PER_NODE,
        kicks_per_pair: MAX_KICKS_PER_PAIR,
        ..SolverConfig::default()
    })
    .unwrap();
    let m = build(30, Shape::Euclidean, 2);
    assert!(is_permutation(
        &at_limits.open_path(&m, 0, None).unwrap().order,
        30
    ));
    // With a time budget (up to its limit) the kick count is free: the
    // budget ends the search.
    let budgeted = Solver::new(SolverConfig {
        kicks_per_pair: 1e300,
        time_budget: Some(Duration::from_millis(20)),
        ..SolverConfig::default()
    })
    .unwrap();
    let began = std::time::Instant::now();
    assert!(is_permutation(
        &budgeted.closed_tour(&m, 0).unwrap().order,
        30
    ));
    assert!(began.elapsed() < Duration::from_secs(5));
    assert!(
        Solver::new(SolverConfig {
            time_budget: Some(MAX_TIME_BUDGET),
            ..SolverConfig::default()
        })
        .is_ok()
    );
}
