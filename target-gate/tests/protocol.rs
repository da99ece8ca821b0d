//! The verification protocol.

use nalgebra::Point3;
use proptest::prelude::*;
use sornav_target_gate::{
    AbandonReason, CandidateReport, GateCommand, GateConfig, GateError, GateEvent, ObjectId, Phase,
    RejectReason, TargetGate,
};

fn report(id: u64, detected: bool) -> CandidateReport<u8> {
    CandidateReport {
        object: ObjectId(id),
        category: 1,
        voxels: 25,
        centre: Point3::new(id as f64, 0.0, 0.0),
        detected,
    }
}

fn robot() -> Point3<f64> {
    Point3::origin()
}

fn gate() -> TargetGate<u8> {
    TargetGate::new(1, GateConfig::default()).unwrap()
}

fn qualify(gate: &mut TargetGate<u8>, id: u64) -> Vec<GateEvent> {
    let mut events = Vec::new();
    for _ in 0..3 {
        events.extend(gate.update(&[report(id, true)], &robot()).unwrap());
    }
    events
}

#[test]
fn full_confirmation() {
    let mut g = gate();
    let events = qualify(&mut g, 4);
    assert_eq!(
        events,
        vec![
            GateEvent::Tracked(ObjectId(4)),
            GateEvent::Selected(ObjectId(4))
        ]
    );
    assert_eq!(
        g.command(),
        GateCommand::NavToObject {
            object: ObjectId(4),
            centre: Point3::new(4.0, 0.0, 0.0)
        }
    );
    // Detections during the approach do not confirm: b_nav = 0.
    g.update(&[report(4, true)], &robot()).unwrap();
    assert!(!g.is_confirmed());
    assert_eq!(
        g.on_arrived(ObjectId(4)).unwrap(),
        vec![GateEvent::Arrived(ObjectId(4))]
    );
    assert!(matches!(
        g.command(),
        GateCommand::Verify {
            object: ObjectId(4),
            ..
        }
    ));
    // Frames without a detection inside the window are tolerated.
    g.update(&[report(4, false)], &robot()).unwrap();
    let events = g.update(&[report(4, true)], &robot()).unwrap();
    assert_eq!(events, vec![GateEvent::Confirmed(ObjectId(4))]);
    assert!(matches!(
        g.command(),
        GateCommand::Stop {
            object: ObjectId(4),
            ..
        }
    ));
    // Confirmed is terminal.
    for _ in 0..20 {
        g.update(&[], &robot()).unwrap();
    }
    assert!(g.is_confirmed());
    g.reset();
    assert_eq!(g.phase(), Phase::Search);
    assert!(g.tracker().tracks().next().is_none());
}

#[test]
fn no_fresh_detection_rejects_and_blocks_reselection() {
    let mut g = gate();
    qualify(&mut g, 4);
    g.on_arrived(ObjectId(4)).unwrap();
    let window = g.tracker().config().verify_window;
    let mut events = Vec::new();
    for _ in 0..window {
        events = g.update(&[report(4, false)], &robot()).unwrap();
    }
    assert_eq!(
        events,
        vec![GateEvent::Rejected {
            object: ObjectId(4),
            reason: RejectReason::NotSeenOnVerification
        }]
    );
    assert_eq!(g.command(), GateCommand::Search);
    // Even with new detections it is not chosen again immediately.
    for _ in 0..5 {
        g.update(&[report(4, true)], &robot()).unwrap();
        assert_eq!(g.phase(), Phase::Search);
    }
    // Another candidate can be chosen meanwhile.
    qualify(&mut g, 9);
    assert_eq!(
        g.phase(),
        Phase::Approach {
            object: ObjectId(9)
        }
    );
}

#[test]
fn approach_failure_rejects() {
    let mut g = gate();
    qualify(&mut g, 2);
    assert_eq!(
        g.on_arrived(ObjectId(3)),
        Err(GateError::NotActive(ObjectId(3)))
    );
    let events = g.on_approach_failed(ObjectId(2)).unwrap();
    assert_eq!(
        events,
        vec![GateEvent::Rejected {
            object: ObjectId(2),
            reason: RejectReason::ApproachFailed
        }]
    );
    assert_eq!(
        g.on_arrived(ObjectId(2)),
        Err(GateError::WrongPhase("search"))
    );
    assert_eq!(
        g.on_approach_failed(ObjectId(2)),
        Err(GateError::WrongPhase("search"))
    );
}

#[test]
fn expiry_during_approach_abandons() {
    let mut g = gate();
    qualify(&mut g, 2);
    let mut last = Vec::new();
    for _ in 0..=g.tracker().config().n_miss {
        last = g.update(&[], &robot()).unwrap();
    }
    assert_eq!(
        last,
        vec![
            GateEvent::Expired(ObjectId(2)),
            GateEvent::Abandoned {
                object: ObjectId(2),
                reason: AbandonReason::Expired
            }
        ]
    );
    assert_eq!(g.phase(), Phase::Search);
}

#[test]
fn remaps_are_followed() {
    let mut g = gate();
    qualify(&mut g, 2);
    let events = g.apply_remap(&[(ObjectId(2), ObjectId(20))]);
    assert_eq!(
        events,
        vec![GateEvent::Followed {
            from: ObjectId(2),
            to: ObjectId(20)
        }]
    );
    g.on_arrived(ObjectId(20)).unwrap();
    // Merge into another cluster during verification: still followed.
    g.update(&[report(20, false), report(30, true)], &robot())
        .unwrap();
    g.apply_remap(&[(ObjectId(20), ObjectId(30))]);
    assert!(matches!(
        g.phase(),
        Phase::Verify {
            object: ObjectId(30),
            ..
        }
    ));
    assert_eq!(
        g.update(&[report(30, true)], &robot()).unwrap(),
        vec![GateEvent::Confirmed(ObjectId(30))]
    );

    // A split abandons the candidate; a part is re-selected at the next update.
    let mut g = gate();
    qualify(&mut g, 2);
    let events = g.apply_remap(&[(ObjectId(2), ObjectId(5)), (ObjectId(2), ObjectId(6))]);
    assert_eq!(
        events,
        vec![GateEvent::Abandoned {
            object: ObjectId(2),
            reason: AbandonReason::Split
        }]
    );
    let events = g
        .update(&[report(5, true), report(6, false)], &robot())
        .unwrap();
    assert_eq!(events, vec![GateEvent::Selected(ObjectId(5))]);
}

#[test]
fn invalid_robot_position_changes_nothing() {
    let mut g = gate();
    assert_eq!(
        g.update(&[report(1, true)], &Point3::new(f64::NAN, 0.0, 0.0)),
        Err(GateError::NonFinite("robot position"))
    );
    assert_eq!(g.tracker().updates(), 0);
}

#[test]
fn serde_round_trip() {
    let mut g = gate();
    qualify(&mut g, 2);
    let json = serde_json::to_string(&g).unwrap();
    let back: TargetGate<u8> = serde_json::from_str(&json).unwrap();
    assert_eq!(back.phase(), g.phase());
    assert_eq!(back.command(), g.command());
}

/// One caller action in a random episode.
#[derive(Debug, Clone)]
enum Step {
    /// An update with, per object 0..3: detected / reported undetected / absent.
    Update([u8; 3]),
    Arrived,
    ApproachFailed,
}

fn step() -> impl Strategy<Value = Step> {
    prop_oneof![
        6 => proptest::array::uniform3(0u8..3).prop_map(Step::Update),
        1 => Just(Step::Arrived),
        1 => Just(Step::ApproachFailed),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    /// Whatever the caller does, confirmation only happens with `N_obs`
    /// detections of the object and a detection strictly after arrival,
    /// and a rejected candidate is not re-selected during its cool-down.
    #[test]
    fn confirmation_requires_evidence_and_navigation(steps in proptest::collection::vec(step(), 1..80)) {
        let cfg = GateConfig { reject_cooldown: 6, ..GateConfig::default() };
        let mut g = TargetGate::new(1u8, cfg).unwrap();
        let mut detections = [0u32; 3];
        let mut arrived_at: Option<(ObjectId, usize)> = None;
        let mut detected_after_arrival = false;
        let mut rejected_at: Vec<(ObjectId, u64)> = Vec::new();
        for (i, s) in steps.iter().enumerate() {
            let events = match s {
                Step::Update(kinds) => {
                    let reports: Vec<_> = kinds
                        .iter()
                        .enumerate()
                        .filter(|&(_, &k)| k < 2)
                        .map(|(id, &k)| report(id as u64, k == 0))
                        .collect();
                    for (id, &k) in kinds.iter().enumerate() {
                        if k == 0 {
                            detections[id] += 1;
                            if arrived_at.is_some_and(|(o, _)| o.0 == id as u64) {
                                detected_after_arrival = true;
                            }
                        }
                    }
                    g.update(&reports, &robot()).unwrap()
                }
                Step::Arrived => match g.phase() {
                    Phase::Approach { object } => {
                        arrived_at = Some((object, i));
                        detected_after_arrival = false;
                        g.on_arrived(object).unwrap()
                    }
                    _ => {
                        prop_assert!(g.on_arrived(ObjectId(0)).is_err());
                        vec![]
                    }
                },
                Step::ApproachFailed => match g.phase() {
                    Phase::Approach { object } => g.on_approach_failed(object).unwrap(),
                    _ => vec![],
                },
            };
            let now = g.tracker().updates();
            for e in &events {
                match *e {
                    GateEvent::Confirmed(o) => {
                        prop_assert!(detections[o.0 as usize] >= cfg.n_obs);
                        prop_assert_eq!(arrived_at.map(|a| a.0), Some(o));
                        prop_assert!(detected_after_arrival);
                    }
                    GateEvent::Rejected { object, .. } => rejected_at.push((object, now)),
                    GateEvent::Selected(o) => {
                        for &(r, at) in &rejected_at {
                            prop_assert!(r != o || now >= at + u64::from(cfg.reject_cooldown));
                        }
                        prop_assert!(g.tracker().track(o).unwrap().evidence.support >= cfg.n_obs);
                    }
                    _ => {}
                }
            }
            if let Some(o) = g.phase().object() {
                // The protocol's candidate always exists in the tracker.
                prop_assert!(g.tracker().track(o).is_some() || g.is_confirmed());
            }
        }
    }
}

/// `GateConfig::first_sight` (the `no-target-gate` ablation): one detection
/// selects the candidate, misses during the approach never drop it, and
/// arrival confirms it without a fresh detection.
#[test]
fn first_sight_confirms_on_the_first_detection() {
    let mut g = TargetGate::new(1, GateConfig::default().first_sight()).unwrap();
    let events = g.update(&[report(4, true)], &robot()).unwrap();
    assert_eq!(
        events,
        vec![
            GateEvent::Tracked(ObjectId(4)),
            GateEvent::Selected(ObjectId(4))
        ]
    );
    for _ in 0..100 {
        g.update(&[report(4, false)], &robot()).unwrap();
    }
    assert!(matches!(
        g.command(),
        GateCommand::NavToObject {
            object: ObjectId(4),
            ..
        }
    ));
    assert_eq!(
        g.on_arrived(ObjectId(4)).unwrap(),
        vec![
            GateEvent::Arrived(ObjectId(4)),
            GateEvent::Confirmed(ObjectId(4))
        ]
    );
    assert!(g.is_confirmed());
    assert_eq!(
        g.command(),
        GateCommand::Stop {
            object: ObjectId(4),
            centre: Point3::new(4.0, 0.0, 0.0)
        }
    );
    // The paper's gate needs N_obs = 3 detections for the same candidate.
    let mut paper = gate();
    paper.update(&[report(4, true)], &robot()).unwrap();
    assert_eq!(paper.command(), GateCommand::Search);
}
