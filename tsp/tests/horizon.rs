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
