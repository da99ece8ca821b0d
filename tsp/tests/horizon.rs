//! Receding-horizon planner and replacement rule.
use nalgebra::Point3;
use proptest::prelude::*;
use sornav_tsp::{
    CostMatrix, HorizonFrontier, HorizonProblem, RecedingHorizon, ReplacementRule, SolverConfig,
    TspError,
};

#[test]
fn replacement_rule_truth_table() {
    let rule = ReplacementRule::default();
    // (first leg, distance of nearby frontier, its leg) -> replaces?
    let table = [
        ((12.0, 4.0, 5.0), true),   // within 5 m, 12 > 2 x 5
        ((12.0, 5.0, 5.0), true),   // exactly 5 m counts as within
        ((12.0, 5.01, 5.0), false), // too far
        ((10.0, 4.0, 5.0), false),  // exactly twice: not more than twice
        ((10.01, 4.0, 5.0), true),
        ((3.0, 1.0, 2.0), false), // first leg short
        ((30.0, 9.0, 2.0), false),
        ((0.0, 0.0, 0.0), false),
    ];
    for ((first, dist, near), expected) in table {
        assert_eq!(
            rule.replaces(first, dist, near),
            expected,
            "{first} {dist} {near}"
        );
    }
    let custom = ReplacementRule {
        radius: 2.0,
        leg_ratio: 3.0,
    };
    assert!(custom.replaces(10.0, 2.0, 3.0));
    assert!(!custom.replaces(9.0, 2.0, 3.0));
    assert!(!custom.replaces(10.0, 2.5, 3.0));
    assert!(
        ReplacementRule {
            radius: f64::NAN,
            leg_ratio: 2.0
        }
        .validate()
        .is_err()
    );
    assert!(
        ReplacementRule {
            radius: 5.0,
            leg_ratio: -1.0
        }
        .validate()
        .is_err()
    );
}

/// Robot at the origin, frontiers on the x axis; costs = |dx| scaled by
/// `detour[i]` for legs from the robot (walls make some legs long).
fn line_problem(xs: &[f64], robot_detour: &[f64], home: bool) -> HorizonProblem<u32> {
    let mut pts = vec![0.0];
    pts.extend_from_slice(xs);
    if home {
        pts.push(0.0);
    }
    let n = pts.len();
    HorizonProblem {
        robot: Point3::origin(),
        frontiers: xs
            .iter()
            .enumerate()
            .map(|(i, &x)| HorizonFrontier {
                id: 100 + i as u32,
                position: Point3::new(x, 0.0, 0.0),
                weight: 1.0,
            })
            .collect(),
        costs: CostMatrix::from_fn(n, |i, j| {
            let d = (pts[i] - pts[j]).abs();
            if i == 0 && (1..=xs.len()).contains(&j) {
                d * robot_detour[j - 1]
            } else {
                d
            }
        })
        .unwrap(),
        home,
    }
}

#[test]
fn nearby_frontier_replaces_a_long_first_leg() {
    // Frontier 100 at x = 2 (2 m away), frontier 101 at x = -20.
    // Reaching 100 from the robot costs 24 (a wall forces a detour):
    // route 101 then 100 (20 + 22 = 42 < 24 + 22); first leg 20 is not more
    // than twice 24, so no replacement.
    let p = line_problem(&[2.0, -20.0], &[12.0, 1.0], false);
    let planner = RecedingHorizon::default();
    let plan = planner.plan(&p, None).unwrap().unwrap();
    assert_eq!(plan.order, vec![101, 100]);
    assert_eq!(plan.route_cost, 42.0);
    assert!(!plan.replaced);
    assert_eq!(plan.first, 101);

    // Now 100 is cheap to reach (3) but a dead end (everything from it costs
    // 1000): the route still visits it last, yet 20 > 2 x 3 and it is 2 m
    // away, so it replaces the first choice.
    let mut q = line_problem(&[2.0, -20.0], &[1.5, 1.0], false);
    let n = q.costs.len();
    q.costs = CostMatrix::from_fn(n, |i, j| {
        if i == 1 && j != 1 {
            1000.0
        } else {
            q.costs.cost(i, j)
        }
    })
    .unwrap();
    let plan = planner.plan(&q, None).unwrap().unwrap();
    assert_eq!(plan.order, vec![101, 100]);
    assert!(plan.replaced);
    assert_eq!(plan.first, 100);

    // A stricter ratio keeps the solver's choice...
    let strict = RecedingHorizon {
        rule: ReplacementRule {
            radius: 5.0,
            leg_ratio: 10.0,
        },
        ..RecedingHorizon::default()
    };
    let plan = strict.plan(&q, None).unwrap().unwrap();
    assert!(!plan.replaced);
    assert_eq!(plan.first, 101);

    // ...and so does a smaller radius.
    let near = RecedingHorizon {
        rule: ReplacementRule {
            radius: 1.5,
            leg_ratio: 2.0,
        },
        ..RecedingHorizon::default()
    };
    assert!(!near.plan(&q, None).unwrap().unwrap().replaced);
}

#[test]
fn home_is_the_fixed_end_and_empty_problems_have_no_plan() {
    let p = line_problem(&[5.0, -5.0, 10.0], &[1.0, 1.0, 1.0], true);
    let plan = RecedingHorizon::default().plan(&p, None).unwrap().unwrap();
    assert_eq!(plan.route_cost, 30.0); // out to 10 and back through -5
    assert_eq!(plan.order.len(), 3);
    let empty = line_problem(&[], &[], false);
    assert_eq!(RecedingHorizon::default().plan(&empty, None).unwrap(), None);
}

#[test]
fn inconsistent_problems_are_rejected() {
    let mut p = line_problem(&[1.0, 2.0], &[1.0, 1.0], false);
    p.home = true;
    assert!(matches!(
        RecedingHorizon::default().plan(&p, None),
        Err(TspError::InconsistentProblem(_))
    ));
    let mut p = line_problem(&[1.0, 2.0], &[1.0, 1.0], false);
    p.frontiers[1].id = p.frontiers[0].id;
    assert!(matches!(
        RecedingHorizon::default().plan(&p, None),
        Err(TspError::InconsistentProblem(_))
    ));
    let mut p = line_problem(&[1.0, 2.0], &[1.0, 1.0], false);
    p.frontiers[0].position.x = f64::INFINITY;
    assert!(matches!(
        RecedingHorizon::default().plan(&p, None),
        Err(TspError::InconsistentProblem(_))
    ));
    let p = line_problem(&[1.0, 2.0], &[1.0, 1.0], false);
    let bad = RecedingHorizon {
        solver: SolverConfig {
            candidates: 0,
            ..SolverConfig::default()
        },
        ..RecedingHorizon::default()
    };
    assert!(matches!(
        bad.plan(&p, None),
        Err(TspError::InvalidConfig(_))
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Re-planning after frontiers vanish and appear keeps plans valid and the
    /// decision consistent with the rule, warm start or not.
    #[test]
    fn replanning_is_consistent(
        xs in prop::collection::vec(-30.0f64..30.0, 1..40),
        keep in prop::collection::vec(any::<bool>(), 40),
        extra in prop::collection::vec(-30.0f64..30.0, 0..5),
        home: bool,
    ) {
        let detour: Vec<f64> = xs.iter().enumerate().map(|(i, _)| 1.0 + (i % 3) as f64).collect();
        let p = line_problem(&xs, &detour, home);
        let planner = RecedingHorizon::default();
        let first = planner.plan(&p, None).unwrap().unwrap();
        prop_assert_eq!(first.order.len(), xs.len());
        // Next step: some frontiers gone, new ones appended (fresh ids).
        let mut xs2: Vec<f64> = xs.iter().zip(&keep).filter(|(_, k)| **k).map(|(x, _)| *x).collect();
        xs2.extend_from_slice(&extra);
        prop_assume!(!xs2.is_empty());
        let detour2: Vec<f64> = (0..xs2.len()).map(|i| 1.0 + (i % 3) as f64).collect();
        let p2 = line_problem(&xs2, &detour2, home);
        let warm = planner.plan(&p2, Some(&first)).unwrap().unwrap();
        let cold = planner.plan(&p2, None).unwrap().unwrap();
        for plan in [&warm, &cold] {
            let mut ids = plan.order.clone();
            ids.sort_unstable();
            let expected: Vec<u32> = (0..xs2.len() as u32).map(|i| 100 + i).collect();
            prop_assert_eq!(ids, expected);
            // The decision follows the rule applied to the planned first frontier.
            let planned = plan.order[0];
            let leg = |id: u32| p2.costs.cost(0, (id - 99) as usize);
            if plan.replaced {
                let f = &p2.frontiers[(plan.first - 100) as usize];
                prop_assert!(f.position.coords.norm() <= 5.0);
                prop_assert!(leg(planned) > 2.0 * leg(plan.first));
            } else {
                prop_assert_eq!(plan.first, planned);
            }
        }
    }
}

/// Two floors: the robot on floor 0 at the origin, floor 1 at 3 m, a stair
/// whose foot is at `stair` on floor 0 and whose top is right above it,
/// `stair_len` long. Path cost between two feet positions `(x, y, floor)`:
/// horizontal distance on one floor, via the stair otherwise.
fn two_floor_cost(a: (f64, f64, u8), b: (f64, f64, u8), stair: (f64, f64), stair_len: f64) -> f64 {
    let h = |p: (f64, f64), q: (f64, f64)| (p.0 - q.0).hypot(p.1 - q.1);
    if a.2 == b.2 {
        h((a.0, a.1), (b.0, b.1))
    } else {
        h((a.0, a.1), stair) + stair_len + h(stair, (b.0, b.1))
    }
}

/// A problem whose positions are the true 3-D frontier positions (floor 1
/// at z = 3 m) and whose costs are two-floor path costs.
fn two_floor_problem(
    frontiers: &[(f64, f64, u8)],
    stair: (f64, f64),
    stair_len: f64,
) -> HorizonProblem<u32> {
    let mut nodes = vec![(0.0, 0.0, 0u8)];
    nodes.extend_from_slice(frontiers);
    HorizonProblem {
        robot: Point3::origin(),
        frontiers: frontiers
            .iter()
            .enumerate()
            .map(|(i, &(x, y, floor))| HorizonFrontier {
                id: 100 + i as u32,
                position: Point3::new(x, y, 3.0 * f64::from(floor)),
                weight: 1.0,
            })
            .collect(),
        costs: CostMatrix::from_fn(nodes.len(), |i, j| {
            two_floor_cost(nodes[i], nodes[j], stair, stair_len)
        })
        .unwrap(),
        home: false,
    }
}

/// A frontier right above the robot, one floor up (3 m in a straight
/// line, 12 m over the stair), is not nearby: it does not replace a 30 m
/// first leg, which a straight-line rule would do (3 m <= 5 m and
/// 30 > 2 x 12). The same frontier reached with a 3 m
/// path does, and so does one reported 100 m away in a straight line but
/// 3 m away by path: the rule reads path costs, not positions.
#[test]
fn nearby_means_near_by_path_cost_not_straight_line() {
    // 100: upstairs, directly above the robot; 101: 30 m away on floor 0.
    // The stair's foot is 4.5 m from the robot, its top right above it.
    let p = two_floor_problem(&[(0.0, 0.0, 1), (-30.0, 0.0, 0)], (4.5, 0.0), 3.0);
    let robot_to = |v: usize| p.costs.cost(0, v);
    assert_eq!(robot_to(1), 12.0); // 4.5 + 3 + 4.5
    assert_eq!((p.frontiers[0].position - p.robot).norm(), 3.0);
    let planner = RecedingHorizon::default();
    let plan = planner.plan(&p, None).unwrap().unwrap();
    // Visiting 100 first (12 + 42) beats 30 + 42: no replacement involved.
    assert_eq!(plan.order, vec![100, 101]);
    assert!(!plan.replaced);

    // Make 100 a dead end (the route visits it last), so the planned first
    // is 101 with a 30 m leg.
    let dead_end = |mut p: HorizonProblem<u32>, leg: f64| {
        let n = p.costs.len();
        p.costs = CostMatrix::from_fn(n, |i, j| match (i, j) {
            (0, 1) | (1, 0) => leg,
            (1, _) if j != 1 => 1000.0,
            _ => p.costs.cost(i, j),
        })
        .unwrap();
        p
    };
    let far = dead_end(p.clone(), 12.0);
    let plan = planner.plan(&far, None).unwrap().unwrap();
    assert_eq!(plan.order, vec![101, 100]);
    assert_eq!(far.costs.cost(0, 2), 30.0);
    // 3 m away in a straight line, 12 m by path: not nearby.
    let rule = ReplacementRule::default();
    assert!(rule.replaces(30.0, 3.0, 12.0)); // what a straight line would give
    assert!(!rule.replaces(30.0, 12.0, 12.0)); // what the path cost gives
    assert!(!plan.replaced);
    assert_eq!(plan.first, 101);

    // Same positions, but a 3 m path: nearby, and 30 > 2 x 3 replaces.
    let near = dead_end(p.clone(), 3.0);
    let plan = planner.plan(&near, None).unwrap().unwrap();
    assert_eq!(plan.order, vec![101, 100]);
    assert!(plan.replaced);
    assert_eq!(plan.first, 100);

    // Reported 100 m away in a straight line, 3 m by path: still nearby.
    let mut moved = near.clone();
    moved.frontiers[0].position = Point3::new(100.0, 0.0, 0.0);
    let plan = planner.plan(&moved, None).unwrap().unwrap();
    assert!(plan.replaced);
    assert_eq!(plan.first, 100);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// On random two-floor layouts (costs = path costs over one stair,
    /// positions = true 3-D positions): the plan's decision equals the
    /// rule applied to path costs (the nearby candidate is the cheapest leg
    /// within the radius), a frontier right above the robot on the other
    /// floor is never a replacement unless its path is short, and the plan
    /// does not change when every position is moved (here: all stacked
    /// right above the robot), so straight-line distances play no part.
    #[test]
    fn replacement_follows_path_costs_on_two_floors(
        frontiers in prop::collection::vec((-12.0f64..12.0, -12.0f64..12.0, 0u8..2), 1..9),
        stair in (3.0f64..10.0, -6.0f64..6.0),
        stair_len in 2.0f64..6.0,
        above in any::<bool>(),
        radius in 2.0f64..8.0,
    ) {
        let mut frontiers = frontiers;
        if above {
            // One frontier exactly above the robot, one floor up.
            frontiers[0] = (0.0, 0.0, 1);
        }
        let p = two_floor_problem(&frontiers, stair, stair_len);
        let planner = RecedingHorizon {
            rule: ReplacementRule { radius, leg_ratio: 2.0 },
            ..RecedingHorizon::default()
        };
        let plan = planner.plan(&p, None).unwrap().unwrap();
        let k = frontiers.len();
        let leg = |v: usize| p.costs.cost(0, v);
        // Reference: nearby by path cost only.
        let nearby = (1..=k)
            .filter(|&v| leg(v) <= radius)
            .min_by(|&a, &b| leg(a).total_cmp(&leg(b)).then(a.cmp(&b)));
        let planned = (plan.order[0] - 100) as usize + 1;
        let expected = match nearby {
            Some(v) if v != planned && leg(planned) > 2.0 * leg(v) => (v, true),
            _ => (planned, false),
        };
        prop_assert_eq!((plan.first, plan.replaced), (100 + expected.0 as u32 - 1, expected.1));
        if plan.replaced {
            prop_assert!(leg((plan.first - 100) as usize + 1) <= radius);
        }
        if above && plan.replaced && plan.first == 100 {
            // Only when the stair makes the path short enough.
            prop_assert!(2.0 * stair.0.hypot(stair.1) + stair_len <= radius);
        }
        // Positions are informational: stacking them all above the robot
        // changes nothing.
        let mut stacked = p.clone();
        for (i, f) in stacked.frontiers.iter_mut().enumerate() {
            f.position = Point3::new(0.0, 0.0, 3.0 + i as f64 * 1e-3);
        }
        prop_assert_eq!(planner.plan(&stacked, None).unwrap().unwrap(), plan);
    }
}

/// The latency objective: the plan's order is the minimum weighted
/// latency path of the same matrix and weights, it needs a free end, and
/// a bad weight is a typed error.
#[test]
fn latency_objective_plans_the_weighted_latency_path() {
    use sornav_tsp::{RouteObjective, min_weighted_latency_path};
    // Robot at 0, one frontier at -1 (heavy), a cluster at 1.5 .. 3.
    let xs = [0.0, -1.0, 1.5, 2.0, 2.5, 3.0];
    let make = |heavy: f64| HorizonProblem {
        robot: Point3::origin(),
        frontiers: (1..xs.len())
            .map(|i| HorizonFrontier {
                id: i as u32,
                position: Point3::new(xs[i], 0.0, 0.0),
                weight: if i == 1 { heavy } else { 1.0 },
            })
            .collect(),
        costs: CostMatrix::from_fn(xs.len(), |i, j| (xs[i] - xs[j]).abs()).unwrap(),
        home: false,
    };
    let horizon = RecedingHorizon {
        objective: RouteObjective::Latency,
        ..RecedingHorizon::default()
    };
    for (heavy, first) in [(1.0, 2), (10.0, 1)] {
        let problem = make(heavy);
        let plan = horizon.plan(&problem, None).unwrap().unwrap();
        let weights: Vec<f64> = std::iter::once(0.0)
            .chain(problem.frontiers.iter().map(|f| f.weight))
            .collect();
        let path = min_weighted_latency_path(&problem.costs, 0, &weights, None, 13).unwrap();
        let ids: Vec<u32> = path.order[1..].iter().map(|&v| v as u32).collect();
        assert_eq!(plan.order, ids);
        assert_eq!(plan.first, first, "heavy weight {heavy}");
        assert!((plan.route_cost - path.cost).abs() < 1e-12);
        // Warm-started from its own plan, the answer is the same.
        let again = horizon.plan(&problem, Some(&plan)).unwrap().unwrap();
        assert_eq!(again.order, plan.order);
    }
    // The path-length objective ignores the weights.
    let shortest = RecedingHorizon::default()
        .plan(&make(10.0), None)
        .unwrap()
        .unwrap();
    assert_eq!(
        shortest,
        RecedingHorizon::default()
            .plan(&make(1.0), None)
            .unwrap()
            .unwrap()
    );
    let mut bad = make(1.0);
    bad.frontiers[2].weight = f64::NAN;
    assert!(matches!(
        horizon.plan(&bad, None),
        Err(TspError::InconsistentProblem(_))
    ));
    let mut home = make(1.0);
    home.home = true;
    home.costs = CostMatrix::from_fn(xs.len() + 1, |i, j| {
        let x = |k: usize| if k == xs.len() { 0.0 } else { xs[k] };
        (x(i) - x(j)).abs()
    })
    .unwrap();
    assert!(matches!(
        horizon.plan(&home, None),
        Err(TspError::InvalidConfig(_))
    ));
}
