//! Candidate tracking against a direct model of the equations, selection
//! against brute force, and remaps against a reference.

use std::collections::BTreeMap;

use nalgebra::Point3;
use proptest::prelude::*;
use sornav_target_gate::{
    CandidateReport, CandidateTracker, Evidence, GateConfig, GateEvent, NeverVisible, ObjectId,
    Phase, StraightLine, TargetGate,
};

const TARGET: &str = "toilet";

/// What happens to one object at one update.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Obs {
    Detected,
    Undetected,
    WrongCategory,
    TooSmall,
    Absent,
    Malformed,
    /// Detected, followed by a conflicting duplicate report.
    DetectedThenDuplicate,
}

fn obs() -> impl Strategy<Value = Obs> {
    prop_oneof![
        4 => Just(Obs::Detected),
        3 => Just(Obs::Undetected),
        1 => Just(Obs::WrongCategory),
        1 => Just(Obs::TooSmall),
        3 => Just(Obs::Absent),
        1 => Just(Obs::Malformed),
        1 => Just(Obs::DetectedThenDuplicate),
    ]
}

/// A path-cost answer: unreachable, malformed (NaN, negative, infinite),
/// or a cost (with repeats, so that ties on cost occur).
fn cost() -> impl Strategy<Value = Option<f64>> {
    prop_oneof![
        2 => Just(None),
        1 => Just(Some(f64::NAN)),
        1 => Just(Some(-1.0)),
        1 => Just(Some(f64::INFINITY)),
        1 => Just(Some(f64::NEG_INFINITY)),
        1 => Just(Some(0.0)),
        2 => Just(Some(5.0)),
        4 => (0.0f64..20.0).prop_map(Some),
    ]
}

fn centre(id: u64) -> Point3<f64> {
    Point3::new(id as f64, 2.0, 0.5)
}

fn reports(step: &[(Obs, bool)], n_min: u32) -> Vec<CandidateReport<&'static str>> {
    let mut out = Vec::new();
    for (i, &(o, _)) in step.iter().enumerate() {
        let object = ObjectId(i as u64);
        let base = CandidateReport {
            object,
            category: TARGET,
            voxels: n_min + 5,
            centre: centre(i as u64),
            detected: true,
        };
        match o {
            Obs::Detected => out.push(base),
            Obs::Undetected => out.push(CandidateReport {
                detected: false,
                ..base
            }),
            Obs::WrongCategory => out.push(CandidateReport {
                category: "sink",
                ..base
            }),
            Obs::TooSmall => out.push(CandidateReport {
                voxels: n_min.saturating_sub(1),
                ..base
            }),
            Obs::Absent => {}
            Obs::Malformed => out.push(CandidateReport {
                centre: Point3::new(f64::NAN, 0.0, 0.0),
                ..base
            }),
            Obs::DetectedThenDuplicate => {
                out.push(base.clone());
                out.push(CandidateReport {
                    category: "sink",
                    detected: false,
                    ..base
                });
            }
        }
    }
    out
}

/// The reference: the two equations applied per the documented mapping from
/// reports to `z_t`.
fn model_step(
    model: &mut BTreeMap<u64, Evidence>,
    step: &[(Obs, bool)],
    cfg: &GateConfig,
) -> Vec<u64> {
    for (i, &(o, visible)) in step.iter().enumerate() {
        let id = i as u64;
        let z = match (o, model.contains_key(&id)) {
            (Obs::Detected | Obs::DetectedThenDuplicate, _) => Some(true),
            (Obs::Undetected, true) if cfg.negative_evidence && visible => Some(false),
            (Obs::WrongCategory | Obs::TooSmall | Obs::Absent, true) => Some(false),
            _ => None,
        };
        match (z, model.get_mut(&id)) {
            (Some(z), Some(e)) => {
                e.support += u32::from(z);
                e.misses = if z { 0 } else { e.misses + 1 };
            }
            (Some(true), None) => {
                model.insert(
                    id,
                    Evidence {
                        support: 1,
                        misses: 0,
                    },
                );
            }
            _ => {}
        }
    }
    let expired: Vec<u64> = model
        .iter()
        .filter(|(_, e)| e.misses > cfg.n_miss)
        .map(|(&id, _)| id)
        .collect();
    for id in &expired {
        model.remove(id);
    }
    expired
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    #[test]
    fn tracker_follows_the_equations(
        steps in proptest::collection::vec(proptest::collection::vec((obs(), any::<bool>()), 4), 1..60),
        negative_evidence in any::<bool>(),
        n_miss in 0u32..6,
    ) {
        let cfg = GateConfig { negative_evidence, n_miss, ..GateConfig::default() };
        let mut tracker = CandidateTracker::new(TARGET, cfg).unwrap();
        let mut model = BTreeMap::new();
        for step in &steps {
            let visible: Vec<bool> = step.iter().map(|&(_, v)| v).collect();
            let vis = move |o: ObjectId, _: &Point3<f64>| visible[o.0 as usize];
            let summary = tracker.update(&reports(step, cfg.n_min), &vis);
            let expired = model_step(&mut model, step, &cfg);
            prop_assert_eq!(summary.expired, expired.into_iter().map(ObjectId).collect::<Vec<_>>());
            let got: BTreeMap<u64, Evidence> = tracker.tracks().map(|t| (t.object.0, t.evidence)).collect();
            prop_assert_eq!(&got, &model);
            let expected_rejected = step
                .iter()
                .filter(|(o, _)| matches!(o, Obs::Malformed | Obs::DetectedThenDuplicate))
                .count() as u32;
            prop_assert_eq!(summary.rejected_reports, expected_rejected);
            for t in tracker.tracks() {
                prop_assert!(t.evidence.misses <= cfg.n_miss);
                prop_assert!(t.centre.x.is_finite());
            }
        }
    }

    #[test]
    fn best_matches_brute_force(
        tracks in proptest::collection::vec((0u32..6, 0u32..4, -5.0f64..5.0, -5.0f64..5.0), 0..8),
        robot in (-5.0f64..5.0, -5.0f64..5.0),
    ) {
        // Build each candidate's evidence through the tracker itself: `s`
        // detections, then `m` absences (other candidates reported as
        // undetected, so they hold).
        let cfg = GateConfig::default();
        let mut tracker = CandidateTracker::new(TARGET, cfg).unwrap();
        let report = |i: usize, detected: bool| CandidateReport {
            object: ObjectId(i as u64),
            category: TARGET,
            voxels: 50,
            centre: Point3::new(tracks[i].2, tracks[i].3, 0.0),
            detected,
        };
        for (i, &(s, m, _, _)) in tracks.iter().enumerate() {
            let others: Vec<_> = (0..tracks.len()).filter(|&j| j != i).map(|j| report(j, false)).collect();
            for _ in 0..s {
                let mut r = others.clone();
                r.push(report(i, true));
                tracker.update(&r, &NeverVisible);
            }
            for _ in 0..m {
                tracker.update(&others, &NeverVisible);
            }
        }
        let robot = Point3::new(robot.0, robot.1, 0.0);
        // Brute force: all qualifying candidates sorted by (-s, distance, id).
        let mut qualifying: Vec<_> = tracker
            .tracks()
            .filter(|t| t.evidence.support >= cfg.n_obs && t.evidence.misses <= cfg.n_miss)
            .map(|t| (t.evidence.support, nalgebra::distance(&t.centre, &robot), t.object))
            .collect();
        qualifying.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
        prop_assert_eq!(tracker.best(&robot).unwrap(), qualifying.first().map(|q| q.2));
    }

    /// Selection by path cost equals a brute-force argmin over the
    /// qualifying candidates under the ranking (most support, reachable
    /// first, lower cost, smaller id), with random costs including
    /// unreachable, NaN, negative and infinite answers; the cost is asked
    /// only about candidates tied on the largest support, once each.
    #[test]
    fn best_by_matches_brute_force_argmin(
        tracks in proptest::collection::vec((0u32..6, 0u32..4, any::<bool>(), cost()), 0..8),
    ) {
        let cfg = GateConfig::default();
        let mut tracker = CandidateTracker::new(TARGET, cfg).unwrap();
        // Unique centres: the cost callback finds its candidate by centre.
        let centre = |i: usize| Point3::new(i as f64 * 3.0 - 7.0, (i % 3) as f64, 0.5 + i as f64);
        let report = |i: usize, detected: bool| CandidateReport {
            object: ObjectId(i as u64),
            category: TARGET,
            voxels: 50,
            centre: centre(i),
            detected,
        };
        for (i, &(s, m, _, _)) in tracks.iter().enumerate() {
            let others: Vec<_> = (0..tracks.len()).filter(|&j| j != i).map(|j| report(j, false)).collect();
            for _ in 0..s {
                let mut r = others.clone();
                r.push(report(i, true));
                tracker.update(&r, &NeverVisible);
            }
            for _ in 0..m {
                tracker.update(&others, &NeverVisible);
            }
        }
        for (i, &(_, _, rejected, _)) in tracks.iter().enumerate() {
            if rejected {
                tracker.reject(ObjectId(i as u64));
            }
        }
        let asked = std::cell::RefCell::new(Vec::new());
        let cost_of = |c: &Point3<f64>| {
            let i = (0..tracks.len()).find(|&i| centre(i) == *c).expect("a tracked centre");
            asked.borrow_mut().push(i as u64);
            tracks[i].3
        };
        let selection = tracker.best_by(&cost_of);

        // Brute force: rank every qualifying candidate by the full key.
        let qualifying: Vec<_> = tracker
            .tracks()
            .filter(|t| t.evidence.support >= cfg.n_obs && t.evidence.misses <= cfg.n_miss)
            .filter(|t| tracker.rejected_until(t.object).is_none())
            .collect();
        let valid = |c: Option<f64>| c.filter(|c| c.is_finite() && *c >= 0.0);
        let key = |t: &sornav_target_gate::Track| {
            let c = valid(tracks[t.object.0 as usize].3);
            (std::cmp::Reverse(t.evidence.support), c.is_none(), c.unwrap_or(0.0), t.object)
        };
        let expected = qualifying
            .iter()
            .min_by(|a, b| {
                let (ka, kb) = (key(a), key(b));
                ka.0.cmp(&kb.0)
                    .then(ka.1.cmp(&kb.1))
                    .then(ka.2.total_cmp(&kb.2))
                    .then(ka.3.cmp(&kb.3))
            })
            .map(|t| t.object);
        prop_assert_eq!(selection.object, expected);

        // Laziness: asked exactly about the tied candidates (when tied).
        let top = qualifying.iter().map(|t| t.evidence.support).max();
        let mut tied: Vec<u64> = qualifying
            .iter()
            .filter(|t| Some(t.evidence.support) == top)
            .map(|t| t.object.0)
            .collect();
        tied.sort_unstable();
        prop_assert_eq!(selection.tied as usize, tied.len());
        let mut asked = asked.into_inner();
        asked.sort_unstable();
        if tied.len() > 1 {
            prop_assert_eq!(&asked, &tied);
        } else {
            prop_assert!(asked.is_empty());
        }
        prop_assert_eq!(selection.queries as usize, asked.len());
        let answers: Vec<Option<f64>> = asked.iter().map(|&i| tracks[i as usize].3).collect();
        prop_assert_eq!(selection.unreachable as usize, answers.iter().filter(|c| c.is_none()).count());
        prop_assert_eq!(
            selection.invalid_costs as usize,
            answers.iter().filter(|c| c.is_some() && valid(**c).is_none()).count()
        );
        // The straight-line selection is best_by with StraightLine.
        let robot = Point3::new(0.3, -0.2, 0.0);
        prop_assert_eq!(
            tracker.best(&robot).unwrap(),
            tracker.best_by(&StraightLine::new(robot)).object
        );
    }

    #[test]
    fn remap_matches_reference(
        initial in proptest::collection::btree_map(0u64..8, (1u32..9, 0u32..5, 1u32..100, any::<bool>()), 0..8),
        pairs in proptest::collection::vec((0u64..8, 0u64..10), 0..8),
    ) {
        let cfg = GateConfig { n_miss: 10, reject_cooldown: 100, ..GateConfig::default() };
        let mut tracker = CandidateTracker::new(TARGET, cfg).unwrap();
        // Drive the tracker to the initial evidence: `s` detections of every
        // candidate with the given sizes, then per-candidate misses.
        let max_s = initial.values().map(|v| v.0).max().unwrap_or(0);
        for round in 0..max_s {
            let r: Vec<_> = initial
                .iter()
                .map(|(&id, &(s, _, voxels, _))| CandidateReport {
                    object: ObjectId(id),
                    category: TARGET,
                    voxels: cfg.n_min + voxels,
                    centre: Point3::new(id as f64, 0.0, 0.0),
                    detected: round >= max_s - s,
                })
                .collect();
            tracker.update(&r, &NeverVisible);
        }
        let max_m = initial.values().map(|v| v.1).max().unwrap_or(0);
        for round in 0..max_m {
            let r: Vec<_> = initial
                .iter()
                .filter(|(_, v)| round < max_m - v.1 )
                .map(|(&id, &(_, _, voxels, _))| CandidateReport {
                    object: ObjectId(id),
                    category: TARGET,
                    voxels: cfg.n_min + voxels,
                    centre: Point3::new(id as f64, 0.0, 0.0),
                    detected: false,
                })
                .collect();
            tracker.update(&r, &NeverVisible);
        }
        for (&id, &(.., rejected)) in &initial {
            if rejected {
                tracker.reject(ObjectId(id));
            }
        }
        let before: BTreeMap<ObjectId, _> = tracker.tracks().map(|t| (t.object, t.clone())).collect();
        let marked: std::collections::BTreeSet<ObjectId> = before
            .keys()
            .copied()
            .filter(|&id| tracker.rejected_until(id).is_some())
            .collect();
        for (&id, &(s, m, _, rejected)) in &initial {
            let t = &before[&ObjectId(id)];
            prop_assert_eq!(t.evidence, Evidence { support: if rejected { 0 } else { s }, misses: m });
        }

        let pairs: Vec<(ObjectId, ObjectId)> = pairs.iter().map(|&(a, b)| (ObjectId(a), ObjectId(b))).collect();
        tracker.apply_remap(&pairs);

        // Reference: for each resulting id, its sources by definition.
        let olds: std::collections::BTreeSet<ObjectId> = pairs.iter().map(|p| p.0).collect();
        let mut expected: BTreeMap<ObjectId, Vec<ObjectId>> = BTreeMap::new();
        for &id in before.keys() {
            if !olds.contains(&id) {
                expected.entry(id).or_default().push(id);
            }
        }
        for &(old, new) in &pairs {
            if before.contains_key(&old) {
                let e = expected.entry(new).or_default();
                if !e.contains(&old) {
                    e.push(old);
                }
            }
        }
        let got: BTreeMap<ObjectId, _> = tracker.tracks().map(|t| (t.object, t.clone())).collect();
        prop_assert_eq!(got.keys().collect::<Vec<_>>(), expected.keys().collect::<Vec<_>>());
        for (id, srcs) in &expected {
            let t = &got[id];
            let src: Vec<_> = srcs.iter().map(|s| &before[s]).collect();
            prop_assert_eq!(t.evidence.support, src.iter().map(|s| s.evidence.support).max().unwrap());
            prop_assert_eq!(t.evidence.misses, src.iter().map(|s| s.evidence.misses).min().unwrap());
            let max_voxels = src.iter().map(|s| s.voxels).max().unwrap();
            prop_assert_eq!(t.voxels, max_voxels);
            prop_assert_eq!(tracker.rejected_until(*id).is_some(), srcs.iter().all(|s| marked.contains(s)));
        }
    }
}

fn toilet(id: u64, detected: bool) -> CandidateReport<&'static str> {
    CandidateReport {
        object: ObjectId(id),
        category: TARGET,
        voxels: 30,
        centre: centre(id),
        detected,
    }
}

#[test]
fn merge_split_and_rename() {
    let mut tracker = CandidateTracker::new(TARGET, GateConfig::default()).unwrap();
    // 1 seen three times, 2 seen once.
    tracker.update(&[toilet(1, true), toilet(2, true)], &NeverVisible);
    tracker.update(&[toilet(1, true), toilet(2, false)], &NeverVisible);
    tracker.update(&[toilet(1, true)], &NeverVisible); // 2 absent: a miss
    let ev = |t: &CandidateTracker<&str>, id| t.track(ObjectId(id)).map(|t| t.evidence);
    assert_eq!(
        ev(&tracker, 1),
        Some(Evidence {
            support: 3,
            misses: 0
        })
    );
    assert_eq!(
        ev(&tracker, 2),
        Some(Evidence {
            support: 1,
            misses: 1
        })
    );

    // Merge 2 into 1: 1 keeps its id, support = max, misses = min.
    let s = tracker.apply_remap(&[(ObjectId(2), ObjectId(1))]);
    assert_eq!(s.moved[&ObjectId(2)], vec![ObjectId(1)]);
    assert_eq!(
        ev(&tracker, 1),
        Some(Evidence {
            support: 3,
            misses: 0
        })
    );
    assert_eq!(ev(&tracker, 2), None);

    // Rename 1 -> 5.
    tracker.apply_remap(&[(ObjectId(1), ObjectId(5))]);
    assert_eq!(ev(&tracker, 1), None);
    assert_eq!(
        ev(&tracker, 5),
        Some(Evidence {
            support: 3,
            misses: 0
        })
    );

    // Split 5 -> 6 + 7: both inherit.
    let s = tracker.apply_remap(&[(ObjectId(5), ObjectId(6)), (ObjectId(5), ObjectId(7))]);
    assert_eq!(s.moved[&ObjectId(5)], vec![ObjectId(6), ObjectId(7)]);
    assert_eq!(ev(&tracker, 6), ev(&tracker, 7));
    assert_eq!(ev(&tracker, 5), None);

    // Swap 6 and 7 (both are old and new ids).
    tracker.update(&[toilet(6, true), toilet(7, false)], &NeverVisible);
    let (e6, e7) = (ev(&tracker, 6), ev(&tracker, 7));
    tracker.apply_remap(&[(ObjectId(6), ObjectId(7)), (ObjectId(7), ObjectId(6))]);
    assert_eq!((ev(&tracker, 6), ev(&tracker, 7)), (e7, e6));

    // Untracked ids are ignored.
    let s = tracker.apply_remap(&[(ObjectId(99), ObjectId(6))]);
    assert!(s.moved.is_empty());
    assert_eq!(ev(&tracker, 6), e7);
}

#[test]
fn single_frame_false_positive_never_qualifies() {
    let mut tracker = CandidateTracker::new(TARGET, GateConfig::default()).unwrap();
    tracker.update(&[toilet(3, true)], &NeverVisible);
    // The cluster persists in the map but is never detected again.
    for _ in 0..100 {
        tracker.update(&[toilet(3, false)], &NeverVisible);
        assert!(!tracker.qualifies(ObjectId(3)));
    }
    assert_eq!(
        tracker.track(ObjectId(3)).unwrap().evidence,
        Evidence {
            support: 1,
            misses: 0
        }
    );
}

#[test]
fn negative_evidence_expires_a_candidate_in_view() {
    let cfg = GateConfig {
        negative_evidence: true,
        ..GateConfig::default()
    };
    let mut tracker = CandidateTracker::new(TARGET, cfg).unwrap();
    tracker.update(&[toilet(3, true)], &NeverVisible);
    let in_view = |_: ObjectId, _: &Point3<f64>| true;
    for i in 1..=cfg.n_miss {
        let s = tracker.update(&[toilet(3, false)], &in_view);
        assert_eq!(s.missed, vec![ObjectId(3)]);
        assert_eq!(tracker.track(ObjectId(3)).unwrap().evidence.misses, i);
    }
    let s = tracker.update(&[toilet(3, false)], &in_view);
    assert_eq!(s.expired, vec![ObjectId(3)]);
    assert!(tracker.track(ObjectId(3)).is_none());
}

#[test]
fn rejection_blocks_reselection_for_the_cooldown() {
    let cfg = GateConfig {
        reject_cooldown: 4,
        ..GateConfig::default()
    };
    let mut tracker = CandidateTracker::new(TARGET, cfg).unwrap();
    let robot = Point3::origin();
    for _ in 0..3 {
        tracker.update(&[toilet(1, true)], &NeverVisible);
    }
    assert_eq!(tracker.best(&robot).unwrap(), Some(ObjectId(1)));
    assert!(tracker.reject(ObjectId(1)));
    assert!(!tracker.reject(ObjectId(42)));
    // Support is reset and the cooldown runs: even with fresh detections it
    // stays unselectable for 4 updates.
    for _ in 0..3 {
        tracker.update(&[toilet(1, true)], &NeverVisible);
        assert_eq!(tracker.best(&robot).unwrap(), None);
    }
    tracker.update(&[toilet(1, true)], &NeverVisible);
    assert_eq!(tracker.best(&robot).unwrap(), Some(ObjectId(1)));
}

#[test]
fn rejection_mark_survives_expiry_and_follows_remaps() {
    let cfg = GateConfig {
        reject_cooldown: 20,
        ..GateConfig::default()
    };
    let mut tracker = CandidateTracker::new(TARGET, cfg).unwrap();
    let robot = Point3::origin();
    for _ in 0..3 {
        tracker.update(&[toilet(1, true), toilet(2, true)], &NeverVisible);
    }
    tracker.reject(ObjectId(1));
    // 1 expires, then is detected anew: still not selectable.
    for _ in 0..=cfg.n_miss {
        tracker.update(&[toilet(2, false)], &NeverVisible);
    }
    assert!(tracker.track(ObjectId(1)).is_none());
    for _ in 0..3 {
        tracker.update(&[toilet(1, true), toilet(2, false)], &NeverVisible);
    }
    assert!(!tracker.qualifies(ObjectId(1)));
    assert_eq!(tracker.best(&robot).unwrap(), Some(ObjectId(2)));
    // A rename carries the mark; a merge with a non-rejected cluster drops it.
    tracker.apply_remap(&[(ObjectId(1), ObjectId(3))]);
    assert!(tracker.rejected_until(ObjectId(3)).is_some());
    assert!(tracker.rejected_until(ObjectId(1)).is_none());
    tracker.apply_remap(&[(ObjectId(3), ObjectId(2))]);
    assert!(tracker.rejected_until(ObjectId(2)).is_none());
    assert!(tracker.qualifies(ObjectId(2)));
}

#[test]
fn bad_robot_position_is_an_error() {
    let tracker = CandidateTracker::new(TARGET, GateConfig::default()).unwrap();
    assert!(tracker.best(&Point3::new(f64::INFINITY, 0.0, 0.0)).is_err());
}

/// Two qualifying candidates with equal support: the one nearest in a
/// straight line is upstairs (far by path) or unreachable, so the other one
/// is approached; `update` (straight line) keeps today's choice.
#[test]
fn path_cost_overrides_straight_line_distance() {
    let robot = Point3::new(0.0, 0.0, 0.0);
    // 1: right above the robot, one floor up; 2: 5 m away on its floor.
    let upstairs = Point3::new(0.5, 0.0, 3.2);
    let same_floor = Point3::new(5.0, 0.0, 0.4);
    let reports = |detected| {
        vec![
            CandidateReport {
                object: ObjectId(1),
                category: TARGET,
                voxels: 50,
                centre: upstairs,
                detected,
            },
            CandidateReport {
                object: ObjectId(2),
                category: TARGET,
                voxels: 50,
                centre: same_floor,
                detected,
            },
        ]
    };
    assert!(nalgebra::distance(&robot, &upstairs) < nalgebra::distance(&robot, &same_floor));
    // Path cost: over the stairs (14 m) for the upper floor.
    let by_path = |c: &Point3<f64>| Some(if c.z > 2.0 { 14.0 } else { 5.2 });
    // Unreachable: the upper floor is not mapped yet.
    let no_stairs = |c: &Point3<f64>| (c.z < 2.0).then_some(5.2);
    // Malformed answers for the upper floor count as unreachable.
    let nan = |c: &Point3<f64>| Some(if c.z > 2.0 { f64::NAN } else { 5.2 });
    for cost in [
        &by_path as &dyn sornav_target_gate::PathCost,
        &no_stairs,
        &nan,
    ] {
        let mut gate = TargetGate::new(TARGET, GateConfig::default()).unwrap();
        let mut events = Vec::new();
        for _ in 0..3 {
            events = gate.update_with(&reports(true), &NeverVisible, cost);
        }
        assert!(
            events.contains(&GateEvent::Selected(ObjectId(2))),
            "{events:?}"
        );
        assert_eq!(
            gate.phase(),
            Phase::Approach {
                object: ObjectId(2)
            }
        );
        let selection = gate.last_selection().unwrap();
        assert_eq!((selection.tied, selection.queries), (2, 2));
        assert_eq!(selection.object, Some(ObjectId(2)));
    }
    let nan_selection = {
        let mut gate = TargetGate::new(TARGET, GateConfig::default()).unwrap();
        for _ in 0..3 {
            gate.update_with(&reports(true), &NeverVisible, &nan);
        }
        *gate.last_selection().unwrap()
    };
    assert_eq!(
        (nan_selection.invalid_costs, nan_selection.unreachable),
        (1, 0)
    );
    // The straight-line entry points keep choosing the nearer-looking one.
    let mut gate = TargetGate::new(TARGET, GateConfig::default()).unwrap();
    for _ in 0..3 {
        gate.update(&reports(true), &robot).unwrap();
    }
    assert_eq!(
        gate.phase(),
        Phase::Approach {
            object: ObjectId(1)
        }
    );
    // More support still beats reachability: with 2 seen once more, 1 is
    // never asked about.
    let mut gate = TargetGate::new(TARGET, GateConfig::default()).unwrap();
    let asked = std::cell::Cell::new(0);
    let counting = |c: &Point3<f64>| {
        asked.set(asked.get() + 1);
        no_stairs(c)
    };
    gate.update_with(&reports(true)[1..], &NeverVisible, &counting);
    for _ in 0..2 {
        gate.update_with(&reports(true), &NeverVisible, &counting);
    }
    assert_eq!(
        gate.phase(),
        Phase::Approach {
            object: ObjectId(2)
        }
    );
    assert_eq!(asked.get(), 0);
}
