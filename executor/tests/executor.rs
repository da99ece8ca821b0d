//! Executor lifecycle, pre-emption rules and failure detection.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

use nalgebra::Point3;
use proptest::prelude::*;
use sornav_executor::*;

/// A motion stack that records what it is told; can be told to refuse.
#[derive(Debug, Default)]
struct Recorder {
    current: Option<Mission>,
    dispatches: usize,
    cancels: usize,
    refuse: bool,
}

impl MotionStack for Recorder {
    fn dispatch(&mut self, mission: &Mission) -> Result<(), MotionError> {
        self.dispatches += 1;
        if self.refuse {
            return Err(MotionError("no route".into()));
        }
        self.current = Some(mission.clone());
        Ok(())
    }
    fn cancel(&mut self) {
        self.cancels += 1;
        self.current = None;
    }
}

type Exec = Executor<Recorder, SimClock>;

fn exec(config: ExecutorConfig) -> Exec {
    Executor::new(
        config,
        Recorder::default(),
        SimClock::new(Duration::from_secs(1)),
    )
    .unwrap()
}

fn explore(f: u64) -> MissionKind {
    MissionKind::Explore {
        frontier: FrontierId(f),
    }
}
fn relocate(c: u64) -> MissionKind {
    MissionKind::Relocate {
        cluster: ClusterId(c),
    }
}
fn nav(o: u64) -> MissionKind {
    MissionKind::NavToObject {
        object: ObjectId(o),
    }
}

fn far(kind: MissionKind) -> Mission {
    Mission::new(kind, Point3::new(20.0, 0.0, 0.0))
}

fn pose(x: f64, y: f64) -> RobotPose {
    RobotPose::new(Point3::new(x, y, 0.0), 0.0)
}

fn finished(events: &[ExecutorEvent]) -> Vec<(MissionId, MissionStatus)> {
    events
        .iter()
        .filter_map(|e| match e {
            ExecutorEvent::Finished(o) => Some((o.id, o.status.clone())),
            _ => None,
        })
        .collect()
}

#[test]
fn preemption_truth_table() {
    use Admission::*;
    use RefusalReason::*;
    let kinds = [explore(1), relocate(1), nav(1)];
    let other = [explore(2), relocate(2), nav(2)];
    // Rows: active (None, Explore, Relocate, NavToObject); columns: new kind.
    // Each cell: (same target, different target).
    let table: [[(Admission, Admission); 3]; 3] = [
        [(Update, Preempt), (Preempt, Preempt), (Preempt, Preempt)],
        [
            (Refuse(RelocationActive), Refuse(RelocationActive)),
            (Update, Preempt),
            (Preempt, Preempt),
        ],
        [
            (Refuse(TargetPursuitActive), Refuse(TargetPursuitActive)),
            (Refuse(TargetPursuitActive), Refuse(TargetPursuitActive)),
            (Update, Preempt),
        ],
    ];
    for new in kinds.iter().chain(&other) {
        assert_eq!(admit(None, new), Start);
    }
    for (a, row) in table.iter().enumerate() {
        for (n, &(same, different)) in row.iter().enumerate() {
            assert_eq!(admit(Some(&kinds[a]), &kinds[n]), same, "{a} {n} same");
            assert_eq!(
                admit(Some(&kinds[a]), &other[n]),
                different,
                "{a} {n} other"
            );
        }
    }

    // The executor applies the table.
    let mut e = exec(ExecutorConfig::default());
    let r = e.submit(far(relocate(1))).unwrap();
    assert_eq!(r, Submission::Started(MissionId(0)));
    assert_eq!(
        e.submit(far(explore(3))).unwrap(),
        Submission::Refused {
            active: MissionId(0),
            reason: RelocationActive
        }
    );
    assert_eq!(
        e.submit(far(relocate(1))).unwrap(),
        Submission::Updated(MissionId(0))
    );
    assert_eq!(
        e.submit(far(nav(5))).unwrap(),
        Submission::Started(MissionId(1))
    );
    assert_eq!(
        finished(&e.drain_events()),
        vec![(
            MissionId(0),
            MissionStatus::Preempted {
                by: Some(MissionId(1))
            }
        )]
    );
    assert!(matches!(
        e.submit(far(relocate(2))).unwrap(),
        Submission::Refused { .. }
    ));
    assert_eq!(e.cancel(), Some(MissionId(1)));
    assert_eq!(e.cancel(), None);
    assert_eq!(
        finished(&e.drain_events()),
        vec![(MissionId(1), MissionStatus::Preempted { by: None })]
    );
    assert_eq!(
        e.submit(far(explore(3))).unwrap(),
        Submission::Started(MissionId(2))
    );
    assert_eq!(e.motion().dispatches, 3); // the identical re-submission is not re-dispatched
    assert_eq!(e.motion().cancels, 1);
}

#[test]
fn relocation_completion_requests_global_exploration() {
    let mut e = exec(ExecutorConfig::default());
    e.submit(far(relocate(7))).unwrap();
    let outcome = e.tick(&pose(19.0, 0.5), &AlwaysValid).unwrap().unwrap();
    assert_eq!(outcome.status, MissionStatus::Reached);
    assert!(!outcome.is_target_arrival());
    let events = e.drain_events();
    assert_eq!(events.len(), 2);
    assert_eq!(events[0], ExecutorEvent::Finished(outcome));
    assert_eq!(
        events[1],
        ExecutorEvent::ExploreFromRegion {
            after: MissionId(0),
            cluster: ClusterId(7),
            position: Point3::new(19.0, 0.5, 0.0)
        }
    );
    assert!(e.active().is_none());
    // Nothing more is emitted for it.
    assert_eq!(e.tick(&pose(19.0, 0.5), &AlwaysValid).unwrap(), None);
    assert!(e.drain_events().is_empty());
}

#[test]
fn nav_to_object_needs_heading() {
    let mut e = exec(ExecutorConfig::default());
    let m = far(nav(3)).with_look_at(Point3::new(21.0, 0.0, 0.5));
    e.submit(m).unwrap();
    // In the radius but facing away.
    let away = RobotPose::new(Point3::new(19.8, 0.0, 0.0), std::f64::consts::PI);
    assert_eq!(e.tick(&away, &AlwaysValid).unwrap(), None);
    let facing = RobotPose::new(Point3::new(19.8, 0.0, 0.0), 0.2);
    let outcome = e.tick(&facing, &AlwaysValid).unwrap().unwrap();
    assert!(outcome.is_target_arrival());
}

#[test]
fn a_mission_can_ask_for_a_tighter_arrival() {
    let mut e = exec(ExecutorConfig::default());
    let m = far(nav(3))
        .with_look_at(Point3::new(21.0, 0.0, 0.5))
        .with_arrival_radius(0.1);
    e.submit(m).unwrap();
    // Within the kind's 0.5 m but not the mission's 0.1 m.
    let near = RobotPose::new(Point3::new(19.8, 0.0, 0.0), 0.0);
    assert_eq!(e.tick(&near, &AlwaysValid).unwrap(), None);
    let at = RobotPose::new(Point3::new(19.95, 0.0, 0.0), 0.0);
    assert!(
        e.tick(&at, &AlwaysValid)
            .unwrap()
            .unwrap()
            .is_target_arrival()
    );
    // A looser one than the kind's does not loosen the kind's rule.
    let mut e = exec(ExecutorConfig::default());
    e.submit(far(nav(3)).with_arrival_radius(5.0)).unwrap();
    let off = RobotPose::new(Point3::new(18.0, 0.0, 0.0), 0.0);
    assert_eq!(e.tick(&off, &AlwaysValid).unwrap(), None);
}

#[test]
fn each_failure_has_its_reason() {
    let cfg = ExecutorConfig {
        stuck_window_s: 5.0,
        stuck_progress_m: 0.5,
        ..ExecutorConfig::default()
    };
    // Stuck: the robot does not move.
    let mut e = exec(cfg);
    e.submit(far(explore(1))).unwrap();
    let mut out = None;
    for _ in 0..10 {
        out = e.tick(&pose(0.0, 0.0), &AlwaysValid).unwrap();
        if out.is_some() {
            break;
        }
        e.clock_mut().advance(1);
    }
    let out = out.unwrap();
    assert!(matches!(
        out.status,
        MissionStatus::Failed(FailureReason::Stuck { .. })
    ));
    assert_eq!(out.at, Duration::from_secs(5));

    // Timeout: the robot keeps progressing but too slowly for the timeout.
    let cfg = ExecutorConfig {
        explore: KindConfig {
            timeout_s: Some(8.0),
            ..cfg.explore
        },
        ..cfg
    };
    let mut e = exec(cfg);
    e.submit(far(explore(1))).unwrap();
    let mut out = None;
    for s in 0..20 {
        out = e.tick(&pose(s as f64, 0.0), &AlwaysValid).unwrap();
        if out.is_some() {
            break;
        }
        e.clock_mut().advance(1);
    }
    assert_eq!(
        out.unwrap().status,
        MissionStatus::Failed(FailureReason::Timeout {
            elapsed: Duration::from_secs(8)
        })
    );

    // Path invalidated by the map.
    let mut e = exec(cfg);
    e.submit(far(explore(1)).with_path(vec![Point3::origin(), Point3::new(20.0, 0.0, 0.0)]))
        .unwrap();
    let blocked = |_: &Mission| false;
    assert_eq!(e.tick(&pose(1.0, 0.0), &AlwaysValid).unwrap(), None);
    let out = e.tick(&pose(1.0, 0.0), &blocked).unwrap().unwrap();
    assert_eq!(
        out.status,
        MissionStatus::Failed(FailureReason::PathInvalidated)
    );
    assert!(e.motion().current.is_none());

    // Dispatch refused by the motion stack.
    let mut e = exec(cfg);
    e.motion_mut().refuse = true;
    let id = e.submit(far(explore(1))).unwrap().id().unwrap();
    assert!(e.active().is_none());
    assert_eq!(
        finished(&e.drain_events()),
        vec![(
            id,
            MissionStatus::Failed(FailureReason::DispatchFailed("no route".into()))
        )]
    );
}

#[test]
fn updates_keep_the_timeout_and_only_changes_restart_the_stuck_window() {
    let cfg = ExecutorConfig {
        stuck_window_s: 5.0,
        ..ExecutorConfig::default()
    };
    // Identical re-submissions every step do not hide a stuck robot.
    let mut e = exec(cfg);
    let id = e.submit(far(explore(1))).unwrap().id().unwrap();
    let mut out = None;
    for _ in 0..10 {
        assert_eq!(e.submit(far(explore(1))).unwrap(), Submission::Updated(id));
        out = e.tick(&pose(0.0, 0.0), &AlwaysValid).unwrap();
        if out.is_some() {
            break;
        }
        e.clock_mut().advance(1);
    }
    assert!(matches!(
        out.unwrap().status,
        MissionStatus::Failed(FailureReason::Stuck { .. })
    ));
    assert_eq!(e.motion().dispatches, 1);

    // A changed waypoint is re-dispatched and restarts the stuck window, but
    // the timeout still counts from the start.
    let cfg = ExecutorConfig {
        explore: KindConfig {
            timeout_s: Some(7.0),
            ..cfg.explore
        },
        ..cfg
    };
    let mut e = exec(cfg);
    let id = e.submit(far(explore(1))).unwrap().id().unwrap();
    let mut out = None;
    for s in 0..10 {
        let moved = Mission::new(explore(1), Point3::new(20.0, s as f64, 0.0));
        assert_eq!(e.submit(moved).unwrap(), Submission::Updated(id));
        out = e.tick(&pose(0.0, 0.0), &AlwaysValid).unwrap();
        if out.is_some() {
            break;
        }
        e.clock_mut().advance(1);
    }
    assert_eq!(
        out.unwrap().status,
        MissionStatus::Failed(FailureReason::Timeout {
            elapsed: Duration::from_secs(7)
        })
    );
    assert_eq!(e.motion().dispatches, 8);
}

#[test]
fn bad_inputs_are_errors() {
    let mut e = exec(ExecutorConfig::default());
    let nan = Point3::new(f64::NAN, 0.0, 0.0);
    assert!(e.submit(Mission::new(explore(1), nan)).is_err());
    assert!(e.submit(far(explore(1)).with_path(vec![])).is_err());
    assert!(e.submit(far(explore(1)).with_path(vec![nan])).is_err());
    assert!(e.submit(far(nav(1)).with_look_at(nan)).is_err());
    for r in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(e.submit(far(nav(1)).with_arrival_radius(r)).is_err(), "{r}");
    }
    assert!(e.active().is_none());
    e.submit(far(explore(1))).unwrap();
    assert_eq!(
        e.tick(
            &RobotPose::new(Point3::origin(), f64::INFINITY),
            &AlwaysValid
        ),
        Err(ExecError::InvalidPose)
    );
    let bad = ExecutorConfig {
        stuck_window_s: 0.0,
        ..ExecutorConfig::default()
    };
    assert!(
        Executor::new(
            bad,
            Recorder::default(),
            SimClock::new(Duration::from_secs(1))
        )
        .is_err()
    );
    let mut bad = ExecutorConfig::default();
    bad.nav_to_object.arrival.heading_tolerance_rad = Some(4.0);
    assert!(bad.validate().is_err());
    bad = ExecutorConfig::default();
    bad.relocate.arrival.radius_m = f64::NAN;
    assert!(bad.validate().is_err());
    // Finite but beyond what a `Duration` can hold: an error, not a panic
    // in `Executor::new` or `tick`.
    bad = ExecutorConfig::default();
    bad.explore.timeout_s = Some(1e30);
    assert!(bad.validate().is_err());
    bad = ExecutorConfig {
        stuck_window_s: 1e30,
        ..ExecutorConfig::default()
    };
    assert!(
        Executor::new(
            bad,
            Recorder::default(),
            SimClock::new(Duration::from_secs(1))
        )
        .is_err()
    );
}

#[test]
fn clocks() {
    let mut c = SimClock::new(Duration::from_millis(250));
    c.advance(4);
    assert_eq!((c.steps(), c.now()), (4, Duration::from_secs(1)));
    let w = WallClock::new();
    assert!(w.now() <= w.now());
    let fixed = || Duration::from_secs(3);
    assert_eq!(Clock::now(&fixed), Duration::from_secs(3));
    // The same executor type runs on wall time.
    let mut e = Executor::new(
        ExecutorConfig::default(),
        Recorder::default(),
        WallClock::new(),
    )
    .unwrap();
    e.submit(far(explore(1))).unwrap();
    assert_eq!(e.tick(&pose(0.0, 0.0), &AlwaysValid).unwrap(), None);
}

#[test]
fn serde_round_trip() {
    let cfg = ExecutorConfig::default();
    let back: ExecutorConfig = serde_json::from_str(&serde_json::to_string(&cfg).unwrap()).unwrap();
    assert_eq!(back, cfg);
    let partial: ExecutorConfig = serde_json::from_str(r#"{"stuck_window_s": 3.0}"#).unwrap();
    assert_eq!(partial.stuck_window_s, 3.0);
    let m = far(nav(2)).with_look_at(Point3::new(1.0, 2.0, 3.0));
    let back: Mission = serde_json::from_str(&serde_json::to_string(&m).unwrap()).unwrap();
    assert_eq!(back, m);
}

/// One caller action in a random run.
#[derive(Debug, Clone)]
enum Op {
    Submit(u8, u64, (f64, f64), bool),
    Tick((f64, f64), f64, bool),
    Advance(u64),
    Cancel,
    /// Make the motion stack refuse (or accept) dispatches from now on.
    Refuse(bool),
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        2 => (0u8..3, 0u64..3, (-6.0f64..6.0, -6.0f64..6.0), any::<bool>())
            .prop_map(|(k, t, w, p)| Op::Submit(k, t, w, p)),
        6 => ((-6.0f64..6.0, -6.0f64..6.0), -4.0f64..4.0, proptest::bool::weighted(0.05))
            .prop_map(|(p, yaw, invalid)| Op::Tick(p, yaw, invalid)),
        3 => (0u64..4).prop_map(Op::Advance),
        1 => Just(Op::Cancel),
        1 => proptest::bool::weighted(0.3).prop_map(Op::Refuse),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    /// Random missions and pose traces: every admitted mission ends at most
    /// once, outcomes are consistent with the arrival rule and the
    /// pre-emption table, and the motion stack mirrors the active mission.
    #[test]
    fn lifecycle_invariants(ops in proptest::collection::vec(op(), 1..120)) {
        let cfg = ExecutorConfig { stuck_window_s: 4.0, ..ExecutorConfig::default() };
        let mut e = exec(cfg);
        let mut admitted: BTreeSet<MissionId> = BTreeSet::new();
        let mut ended: BTreeMap<MissionId, MissionStatus> = BTreeMap::new();
        let mut kinds: BTreeMap<MissionId, MissionKind> = BTreeMap::new();
        for op in &ops {
            let before = e.active().map(|(id, m)| (id, m.clone()));
            let mut tick_pose = None;
            match *op {
                Op::Submit(k, t, w, with_path) => {
                    let kind = [explore(t), relocate(t), nav(t)][k as usize];
                    let waypoint = Point3::new(w.0, w.1, 0.0);
                    let mut m = Mission::new(kind, waypoint).with_look_at(Point3::new(w.0 + 1.0, w.1, 0.5));
                    if with_path {
                        m = m.with_path(vec![Point3::origin(), Point3::new(w.0, 0.0, 0.0), waypoint]);
                    }
                    let expected = admit(before.as_ref().map(|(_, m)| &m.kind), &kind);
                    let s = e.submit(m).unwrap();
                    match (expected, s) {
                        (Admission::Start | Admission::Preempt, Submission::Started(id)) => {
                            prop_assert!(admitted.insert(id), "ids are fresh");
                            kinds.insert(id, kind);
                        }
                        (Admission::Update, Submission::Updated(id)) => {
                            prop_assert_eq!(Some(id), before.as_ref().map(|b| b.0));
                        }
                        (Admission::Refuse(r), Submission::Refused { active, reason }) => {
                            prop_assert_eq!(r, reason);
                            prop_assert_eq!(Some(active), before.as_ref().map(|b| b.0));
                        }
                        (a, s) => prop_assert!(false, "admission {:?} but submission {:?}", a, s),
                    }
                    if e.motion().refuse && s.id().is_some() {
                        // A refused dispatch ends the mission at once.
                        prop_assert!(e.active().is_none());
                    }
                }
                Op::Tick(p, yaw, invalid) => {
                    let pose = RobotPose::new(Point3::new(p.0, p.1, 0.0), yaw);
                    tick_pose = Some(pose);
                    let validity = move |_: &Mission| !invalid;
                    let out = e.tick(&pose, &validity).unwrap();
                    if let (Some(out), Some((id, m))) = (&out, &before) {
                        prop_assert_eq!(out.id, *id);
                        let rule = cfg.for_kind(&m.kind).arrival;
                        let reached = arrived(&pose, m, &rule);
                        prop_assert_eq!(out.status == MissionStatus::Reached, reached);
                        if invalid && !reached {
                            prop_assert_eq!(&out.status, &MissionStatus::Failed(FailureReason::PathInvalidated));
                        }
                    }
                    if before.is_none() {
                        prop_assert!(out.is_none());
                    }
                }
                Op::Advance(n) => e.clock_mut().advance(n),
                Op::Refuse(r) => e.motion_mut().refuse = r,
                Op::Cancel => {
                    let id = e.cancel();
                    prop_assert_eq!(id, before.as_ref().map(|b| b.0));
                }
            }
            let events = e.drain_events();
            for (i, ev) in events.iter().enumerate() {
                match ev {
                    ExecutorEvent::Finished(o) => {
                        prop_assert!(admitted.contains(&o.id));
                        prop_assert!(ended.insert(o.id, o.status.clone()).is_none(), "outcome emitted twice for {:?}", o.id);
                        prop_assert_eq!(o.kind, kinds[&o.id]);
                        let nav_kind = matches!(o.kind, MissionKind::NavToObject { .. });
                        prop_assert!(!o.is_target_arrival() || nav_kind);
                        let follows = matches!(events.get(i + 1), Some(ExecutorEvent::ExploreFromRegion { after, .. }) if *after == o.id);
                        let relocated = matches!(o.kind, MissionKind::Relocate { .. }) && o.status == MissionStatus::Reached;
                        prop_assert_eq!(follows, relocated);
                    }
                    ExecutorEvent::ExploreFromRegion { after, position, .. } => {
                        let reached = matches!(ended.get(after), Some(MissionStatus::Reached));
                        prop_assert!(reached);
                        prop_assert_eq!(Some(*position), tick_pose.map(|p| p.position));
                    }
                }
            }
            // The active mission is admitted and not ended; the motion stack
            // holds exactly it.
            match e.active() {
                Some((id, m)) => {
                    prop_assert!(admitted.contains(&id) && !ended.contains_key(&id));
                    prop_assert_eq!(e.motion().current.as_ref(), Some(m));
                }
                None => prop_assert!(e.motion().current.is_none()),
            }
            // Every admitted mission is either active or ended.
            for id in &admitted {
                prop_assert!(ended.contains_key(id) || e.active().map(|a| a.0) == Some(*id));
            }
        }
    }
}
