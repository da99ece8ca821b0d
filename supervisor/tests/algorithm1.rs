//! Algorithm 1's ordering on random event sequences, checked against a
//! direct transcription of the paper's listing.

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use nalgebra::Point3;
use proptest::prelude::*;
use sornav_supervisor::{
    ActiveMissionKind, Candidate, ClusterCandidate, ContextObject, ContextPolicy, MissionState,
    PolicyDecision, RegionContext, RegionSnapshot, Situation, StepInput, Supervisor,
    SupervisorCommand, SupervisorConfig, SupervisorError,
};

#[derive(Clone, Copy, Debug)]
enum Choice {
    Explore,
    Index(usize),
    Bogus,
}

/// A policy whose answer is scripted per call; it records what it was shown.
struct Scripted {
    next: Rc<Cell<Choice>>,
    seen: Rc<std::cell::RefCell<Vec<Vec<u64>>>>,
}

impl ContextPolicy for Scripted {
    fn name(&self) -> &str {
        "scripted"
    }
    fn decide(&mut self, s: &RegionSnapshot, _: &Situation) -> PolicyDecision {
        self.seen
            .borrow_mut()
            .push(s.candidates.iter().map(|c| c.cluster_id).collect());
        match self.next.get() {
            Choice::Explore => PolicyDecision::explore("scripted explore"),
            Choice::Index(i) if !s.candidates.is_empty() => PolicyDecision::relocate(
                s.candidates[i % s.candidates.len()].cluster_id,
                "scripted",
            ),
            Choice::Index(_) => PolicyDecision::explore("no candidates"),
            Choice::Bogus => PolicyDecision::relocate(10_000, "scripted bogus"),
        }
    }
}

#[derive(Clone, Debug)]
struct Event {
    dt: f64,
    accepted: Option<u64>,
    kind: ActiveMissionKind,
    mission_id: u64,
    u_geo: Vec<f64>,
    choice: Choice,
}

fn arb_event() -> impl Strategy<Value = Event> {
    (
        prop_oneof![Just(0.0), 0.0..0.6f64, 0.5..3.0f64],
        prop::option::weighted(0.15, 0u64..50),
        prop_oneof![
            Just(ActiveMissionKind::Idle),
            Just(ActiveMissionKind::Explore),
            Just(ActiveMissionKind::Relocate),
            Just(ActiveMissionKind::NavToObject)
        ],
        0u64..4,
        prop::collection::vec(0.0..10.0f64, 0..7),
        prop_oneof![
            Just(Choice::Explore),
            (0usize..6).prop_map(Choice::Index),
            Just(Choice::Bogus)
        ],
    )
        .prop_map(|(dt, accepted, kind, mission_id, u_geo, choice)| Event {
            dt,
            accepted,
            kind,
            mission_id,
            u_geo,
            choice,
        })
}

fn clusters(u_geo: &[f64]) -> Vec<ClusterCandidate> {
    u_geo
        .iter()
        .enumerate()
        .map(|(i, &u)| ClusterCandidate {
            candidate: Candidate {
                floor: 0,
                cluster_id: i as u64 * 3 + 1,
                distance_m: 2.0 + i as f64,
                context: vec![],
            },
            u_geo: u,
            waypoint: Point3::new(i as f64, 1.0, 0.0),
        })
        .collect()
}

const INTERVAL: f64 = 1.0;
const K: usize = 3;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn ordering_matches_the_listing(events in prop::collection::vec(arb_event(), 1..40), dwell in prop::sample::select(vec![0.0, 0.7, 3.0])) {
        let next = Rc::new(Cell::new(Choice::Explore));
        let seen = Rc::new(std::cell::RefCell::new(Vec::new()));
        let policy = Scripted { next: Rc::clone(&next), seen: Rc::clone(&seen) };
        let mut sup: Supervisor<_, f64> =
            Supervisor::new(policy, SupervisorConfig { interval_s: INTERVAL, top_k: K, region_dwell_s: dwell }).unwrap();
        let frontier = Some(Point3::new(9.0, 9.0, 0.0));
        let mut t = 0.0;
        let mut last_eval: Option<f64> = None;
        let mut calls = 0;
        let mut previous: Option<ActiveMissionKind> = None;
        let mut dwell_until: Option<f64> = None;
        for e in &events {
            t += e.dt;
            if previous == Some(ActiveMissionKind::Relocate) && e.kind != ActiveMissionKind::Relocate {
                dwell_until = Some(t + dwell);
            }
            previous = Some(e.kind);
            next.set(e.choice);
            let built = Cell::new(false);
            let input = StepInput {
                target: "bed",
                target_accepted: e.accepted,
                mission: MissionState { id: e.mission_id, kind: e.kind },
                first_frontier: frontier,
            };
            let got = sup
                .step(t, &input, || {
                    built.set(true);
                    RegionContext { local_context: vec![ContextObject::new("sink", 20.0)], clusters: clusters(&e.u_geo) }
                })
                .unwrap();
            // The reference: Algorithm 1 line by line.
            let expected_kind;
            if let Some(id) = e.accepted {
                prop_assert_eq!(&got, &SupervisorCommand::NavToObject { target_id: id });
                expected_kind = "nav";
            } else if e.kind == ActiveMissionKind::Relocate {
                prop_assert_eq!(&got, &SupervisorCommand::KeepRelocation);
                expected_kind = "keep";
            } else if e.kind != ActiveMissionKind::Idle && last_eval.is_some_and(|l| t - l < INTERVAL) {
                prop_assert_eq!(&got, &SupervisorCommand::ContinueMission);
                expected_kind = "continue";
            } else if dwell_until.is_some_and(|u| t < u) {
                last_eval = Some(t);
                let is_expected = matches!(&got, SupervisorCommand::ExploreNewRegion { frontier: f, remaining_s }
                    if *f == frontier && *remaining_s > 0.0 && *remaining_s <= dwell + 1e-9);
                prop_assert!(is_expected, "{:?}", got);
                expected_kind = "dwell";
            } else {
                last_eval = Some(t);
                calls += 1;
                let mut ranked = clusters(&e.u_geo);
                ranked.sort_by(|a, b| b.u_geo.partial_cmp(&a.u_geo).unwrap().then(a.candidate.cluster_id.cmp(&b.candidate.cluster_id)));
                ranked.truncate(K);
                let ids: Vec<u64> = ranked.iter().map(|c| c.candidate.cluster_id).collect();
                let shown = seen.borrow().last().cloned();
                prop_assert_eq!(shown, Some(ids));
                match (e.choice, ranked.is_empty()) {
                    (Choice::Index(i), false) => {
                        let c = &ranked[i % ranked.len()];
                        let is_expected = matches!(&got, SupervisorCommand::Relocate { cluster_id, waypoint, .. }
                            if *cluster_id == c.candidate.cluster_id && *waypoint == c.waypoint);
                        prop_assert!(is_expected, "{:?}", got);
                        // A commanded relocation counts as under way.
                        previous = Some(ActiveMissionKind::Relocate);
                    }
                    _ => {
                        let is_expected = matches!(&got, SupervisorCommand::Explore { frontier: f, .. } if *f == frontier);
                        prop_assert!(is_expected, "{:?}", got);
                    }
                }
                expected_kind = "policy";
            }
            // The region context is built only when the policy runs.
            prop_assert_eq!(built.get(), expected_kind == "policy");
        }
        prop_assert_eq!(seen.borrow().len(), calls);
        prop_assert_eq!(sup.stats().policy_calls, calls as u64);
        prop_assert_eq!(sup.stats().steps, events.len() as u64);
    }
}

#[test]
fn works_on_duration_and_instant_clocks_and_rejects_nan_time() {
    let policy = sornav_supervisor::NeverRelocate;
    let mut sup: Supervisor<_, Duration> =
        Supervisor::new(policy, SupervisorConfig::default()).unwrap();
    let input = StepInput {
        target: "bed",
        target_accepted: None,
        mission: MissionState {
            id: 1,
            kind: ActiveMissionKind::Explore,
        },
        first_frontier: None,
    };
    let c = sup
        .step(Duration::from_millis(0), &input, RegionContext::default)
        .unwrap();
    assert!(matches!(
        c,
        SupervisorCommand::Explore { frontier: None, .. }
    ));
    let c = sup
        .step(Duration::from_millis(500), &input, RegionContext::default)
        .unwrap();
    assert_eq!(c, SupervisorCommand::ContinueMission);
    let c = sup
        .step(Duration::from_millis(1000), &input, RegionContext::default)
        .unwrap();
    assert!(matches!(c, SupervisorCommand::Explore { .. }));

    let mut sup: Supervisor<_, std::time::Instant> = Supervisor::new(
        sornav_supervisor::NeverRelocate,
        SupervisorConfig::default(),
    )
    .unwrap();
    assert!(
        sup.step(std::time::Instant::now(), &input, RegionContext::default)
            .is_ok()
    );

    let mut sup: Supervisor<_, f64> = Supervisor::new(
        sornav_supervisor::NeverRelocate,
        SupervisorConfig::default(),
    )
    .unwrap();
    sup.step(0.0, &input, RegionContext::default).unwrap();
    assert!(matches!(
        sup.step(f64::NAN, &input, RegionContext::default),
        Err(SupervisorError::InvalidNumber { .. })
    ));
    assert!(
        Supervisor::<_, f64>::new(
            sornav_supervisor::NeverRelocate,
            SupervisorConfig {
                interval_s: f64::NAN,
                ..SupervisorConfig::default()
            }
        )
        .is_err()
    );
    for dwell in [-1.0, f64::NAN, f64::INFINITY] {
        let config = SupervisorConfig {
            region_dwell_s: dwell,
            ..SupervisorConfig::default()
        };
        assert!(Supervisor::<_, f64>::new(sornav_supervisor::NeverRelocate, config).is_err());
    }
}

/// After a relocation ends, the policy is not asked for `region_dwell_s`:
/// the new region is explored first; then the policy runs again.
#[test]
fn the_region_reached_by_a_relocation_is_explored_first() {
    let next = Rc::new(Cell::new(Choice::Index(0)));
    let seen = Rc::new(std::cell::RefCell::new(Vec::new()));
    let policy = Scripted {
        next: Rc::clone(&next),
        seen: Rc::clone(&seen),
    };
    let config = SupervisorConfig {
        region_dwell_s: 5.0,
        ..SupervisorConfig::default()
    };
    let mut sup: Supervisor<_, f64> = Supervisor::new(policy, config).unwrap();
    let frontier = Some(Point3::new(1.0, 2.0, 0.0));
    let step = |sup: &mut Supervisor<_, f64>, t: f64, kind: ActiveMissionKind| {
        let input = StepInput {
            target: "toilet",
            target_accepted: None,
            mission: MissionState { id: 1, kind },
            first_frontier: frontier,
        };
        sup.step(t, &input, || RegionContext {
            local_context: vec![],
            clusters: clusters(&[1.0, 2.0]),
        })
        .unwrap()
    };
    assert!(matches!(
        step(&mut sup, 0.0, ActiveMissionKind::Idle),
        SupervisorCommand::Relocate { .. }
    ));
    assert_eq!(
        step(&mut sup, 3.0, ActiveMissionKind::Relocate),
        SupervisorCommand::KeepRelocation
    );
    // The relocation ended at t = 10: explore the new region until t = 15.
    for t in [10.0, 12.0, 14.9] {
        assert_eq!(
            step(&mut sup, t, ActiveMissionKind::Idle),
            SupervisorCommand::ExploreNewRegion {
                frontier,
                remaining_s: 15.0 - t
            }
        );
    }
    let calls = seen.borrow().len();
    assert!(matches!(
        step(&mut sup, 15.0, ActiveMissionKind::Idle),
        SupervisorCommand::Relocate { .. }
    ));
    assert_eq!(
        seen.borrow().len(),
        calls + 1,
        "the policy runs again after the dwell"
    );
    // That relocation starts and ends between two steps (its waypoint is
    // within the arrival radius): its end still starts the dwell.
    assert!(matches!(
        step(&mut sup, 16.0, ActiveMissionKind::Idle),
        SupervisorCommand::ExploreNewRegion { .. }
    ));
    assert!(matches!(
        step(&mut sup, 21.0, ActiveMissionKind::Idle),
        SupervisorCommand::Relocate { .. }
    ));
    // Target evidence still pre-empts the dwell.
    step(&mut sup, 22.0, ActiveMissionKind::Relocate);
    let input = StepInput {
        target: "toilet",
        target_accepted: Some(7),
        mission: MissionState {
            id: 2,
            kind: ActiveMissionKind::Explore,
        },
        first_frontier: frontier,
    };
    assert_eq!(
        sup.step(23.0, &input, RegionContext::default).unwrap(),
        SupervisorCommand::NavToObject { target_id: 7 }
    );
}

#[test]
fn invalid_snapshot_and_unknown_cluster_fall_back_to_exploring() {
    let next = Rc::new(Cell::new(Choice::Bogus));
    let seen = Rc::new(std::cell::RefCell::new(Vec::new()));
    let mut sup: Supervisor<_, f64> = Supervisor::new(
        Scripted {
            next: Rc::clone(&next),
            seen,
        },
        SupervisorConfig::default(),
    )
    .unwrap();
    let input = StepInput {
        target: "bed",
        target_accepted: None,
        mission: MissionState {
            id: 1,
            kind: ActiveMissionKind::Idle,
        },
        first_frontier: None,
    };
    let c = sup
        .step(0.0, &input, || RegionContext {
            local_context: vec![],
            clusters: clusters(&[1.0, 2.0]),
        })
        .unwrap();
    assert!(
        matches!(&c, SupervisorCommand::Explore { reason, .. } if reason.contains("unknown cluster"))
    );
    assert_eq!(sup.stats().rejected_relocations, 1);
    // NaN support in the local context: the policy is not trusted with it.
    next.set(Choice::Index(0));
    let c = sup
        .step(5.0, &input, || RegionContext {
            local_context: vec![ContextObject::new("bed", f64::NAN)],
            clusters: clusters(&[1.0]),
        })
        .unwrap();
    assert!(
        matches!(&c, SupervisorCommand::Explore { reason, .. } if reason.contains("invalid snapshot"))
    );
}
