//! Bad input gives typed errors (never a panic, never partial
//! integration); a depth/semantic frame with pinhole intrinsics works like
//! a labelled cloud.

mod common;

use std::time::Duration;

use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion};
use proptest::prelude::*;
use sornav::executor::{MissionId, MissionStatus, RobotPose};
use sornav::semantic_map::{LabelId, LabeledPoint, PinholeCamera, optical_pose};
use sornav::{
    Agent, AgentCommand, AgentConfig, AgentError, CloudObservation, DepthObservation, Observation,
    ObservationError, OccupancyObservation, Sensor,
};

fn pose() -> RobotPose {
    RobotPose::new(Point3::new(0.0, 0.0, 0.0), 0.0)
}

/// A 160 x 120 frame facing a wall 3 m ahead (+x) with a TV-labelled
/// patch in its middle.
fn depth_frame() -> DepthObservation {
    let camera = PinholeCamera::from_hfov(160, 120, 79f64.to_radians());
    let camera_pose = optical_pose(&Point3::new(0.0, 0.0, 0.88), 0.0, 0.0);
    let n = 160 * 120;
    let depth = vec![3.0f32; n];
    let labels = (0..n)
        .map(|i| {
            let (u, v) = (i % 160, i / 160);
            if (70..90).contains(&u) && (40..60).contains(&v) {
                LabelId(15)
            } else {
                LabelId(1)
            }
        })
        .collect();
    DepthObservation {
        camera,
        camera_pose,
        depth,
        labels,
    }
}

fn agent() -> Agent {
    let mut agent = Agent::new(AgentConfig::default()).unwrap();
    agent.set_target("tv_monitor").unwrap();
    agent
}

#[test]
fn depth_frames_build_both_maps_and_feed_the_gate() {
    let mut agent = agent();
    let observation = Observation {
        pose: pose(),
        sensor: Sensor::Depth(depth_frame()),
    };
    let mut last = None;
    for t in 0..3 {
        let report = agent.observe(&observation).unwrap();
        assert_eq!(report.points, 160 * 120);
        assert_eq!(report.semantic_rejected, 0);
        assert_eq!(report.target_detections, 1);
        last = Some(agent.step(Duration::from_secs(t)).unwrap());
    }
    let tv = agent
        .snapshot()
        .objects
        .into_iter()
        .find(|o| o.label.as_deref() == Some("tv_monitor"))
        .expect("TV cluster");
    assert!(
        (tv.centre.x - 3.0).abs() < 0.1 && tv.centre.y.abs() < 0.3,
        "{}",
        tv.centre
    );
    // Rows 40..60 lie above the optical centre: back-projection at 3 m.
    let camera = depth_frame().camera;
    let expected_z = 0.88 + 3.0 * (camera.cy - 49.5) / camera.fy;
    assert!(
        (tv.centre.z - expected_z).abs() < 0.05,
        "{} vs {expected_z}",
        tv.centre.z
    );
    match last {
        Some(AgentCommand::Dispatch { mission, .. }) => {
            assert_eq!(mission.kind.name(), "nav_to_object");
            let to_tv = (mission.waypoint.xy() - tv.centre.xy()).norm();
            assert!(to_tv < 1.0, "approach waypoint {} m from the TV", to_tv);
        }
        other => panic!("expected NAV_TO_OBJECT, got {other:?}"),
    }
}

#[test]
fn malformed_frames_are_typed_errors_and_change_nothing() {
    let mut agent = agent();
    let good = depth_frame();
    let cases: Vec<(Observation, ObservationError)> = vec![
        (
            Observation {
                pose: RobotPose::new(Point3::new(f64::NAN, 0.0, 0.0), 0.0),
                sensor: Sensor::Depth(good.clone()),
            },
            ObservationError::NonFinitePose,
        ),
        (
            Observation {
                pose: RobotPose::new(Point3::origin(), f64::INFINITY),
                sensor: Sensor::Depth(good.clone()),
            },
            ObservationError::NonFinitePose,
        ),
        (
            Observation {
                pose: pose(),
                sensor: Sensor::Depth(DepthObservation {
                    depth: vec![1.0; 10],
                    ..good.clone()
                }),
            },
            ObservationError::FrameSize {
                width: 160,
                height: 120,
                depth: 10,
                labels: 160 * 120,
            },
        ),
        (
            Observation {
                pose: pose(),
                sensor: Sensor::Depth(DepthObservation {
                    camera_pose: Isometry3::from_parts(
                        Translation3::new(f64::NAN, 0.0, 0.0),
                        UnitQuaternion::identity(),
                    ),
                    ..good.clone()
                }),
            },
            ObservationError::NonFiniteSensorPose,
        ),
        (
            Observation {
                pose: pose(),
                sensor: Sensor::Cloud(CloudObservation {
                    origin: Point3::new(0.0, f64::NEG_INFINITY, 0.0),
                    points: vec![LabeledPoint::new(1.0, 0.0, 0.5, LabelId(1))],
                }),
            },
            ObservationError::NonFiniteSensorPose,
        ),
        (
            Observation {
                pose: pose(),
                sensor: Sensor::Cloud(CloudObservation {
                    origin: Point3::origin(),
                    points: vec![],
                }),
            },
            ObservationError::Empty,
        ),
    ];
    for (observation, expected) in cases {
        match agent.observe(&observation) {
            Err(AgentError::Observation(e)) => assert_eq!(e, expected),
            other => panic!("expected {expected:?}, got {other:?}"),
        }
    }
    let mut bad_intrinsics = good.clone();
    bad_intrinsics.camera.fx = 0.0;
    let result = agent.observe(&Observation {
        pose: pose(),
        sensor: Sensor::Depth(bad_intrinsics),
    });
    assert!(matches!(
        result,
        Err(AgentError::Observation(
            ObservationError::InvalidIntrinsics(_)
        ))
    ));
    // Coordinates beyond the grid's numeric range: the frontier map's
    // typed error, and the semantic map is untouched.
    let far = Observation {
        pose: pose(),
        sensor: Sensor::Cloud(CloudObservation {
            origin: Point3::origin(),
            points: vec![LabeledPoint::new(1.0e9, 0.0, 0.5, LabelId(1))],
        }),
    };
    assert!(matches!(agent.observe(&far), Err(AgentError::Frontier(_))));
    assert_eq!(agent.semantic_map().integrations(), 0);
    assert_eq!(agent.stats().refused_observations, 8);
    assert_eq!(agent.stats().observations, 0);
    // Nothing was observed: the pose is still unknown.
    assert!(matches!(
        agent.step(Duration::ZERO),
        Err(AgentError::NoObservation)
    ));
}

#[test]
fn invalid_points_inside_a_valid_frame_are_counted() {
    let mut agent = agent();
    let mut points: Vec<LabeledPoint> = (0..50)
        .map(|i| LabeledPoint::new(2.0, -1.25 + 0.05 * i as f32, 0.5, LabelId(1)))
        .collect();
    points.push(LabeledPoint::new(f32::NAN, 0.0, 0.5, LabelId(1)));
    points.push(LabeledPoint::new(1.0, f32::INFINITY, 0.5, LabelId(15)));
    let report = agent
        .observe(&Observation {
            pose: pose(),
            sensor: Sensor::Cloud(CloudObservation {
                origin: Point3::new(0.0, 0.0, 0.88),
                points,
            }),
        })
        .unwrap();
    assert_eq!(report.points, 52);
    assert_eq!(report.semantic_rejected, 2);
    assert_eq!(report.occupancy_rejected, 2);
    assert_eq!(report.occupancy_points, 50);
    // The free footprint: the 0.05 m lattice points of the 0.18 m disk.
    let lattice = (-3i32..=3)
        .flat_map(|i| (-3i32..=3).map(move |j| (i, j)))
        .filter(|(i, j)| (0.05 * f64::from(*i)).hypot(0.05 * f64::from(*j)) <= 0.18)
        .count() as u64;
    assert_eq!(report.footprint_points, lattice);
    assert_eq!(agent.stats().rejected_points, 4);
}

/// Surface returns of a straight stair along +x (treads of `tread` m,
/// risers of `rise` m, 1 m wide, from x = 1.5) and the floor before it,
/// on a 5 cm lattice, as seen from above.
fn stair_points(rise: f64, tread: f64, steps: usize) -> Vec<Point3<f64>> {
    let mut points = Vec::new();
    let lattice = |a: f64, b: f64| {
        (0..)
            .map(move |k| a + 0.05 * f64::from(k))
            .take_while(move |v| *v < b)
    };
    for x in lattice(-1.0, 1.5) {
        for y in lattice(-1.0, 1.0) {
            points.push(Point3::new(x, y, 0.0));
        }
    }
    for k in 0..steps {
        let x0 = 1.5 + tread * k as f64;
        let z = rise * (k + 1) as f64;
        for x in lattice(x0, x0 + tread) {
            for y in lattice(-0.5, 0.5) {
                points.push(Point3::new(x, y, z));
            }
        }
    }
    points
}

#[test]
fn only_the_feet_on_a_stair() {
    // Standing on a stair's first tread (0.17 m up: still on level 0 for
    // the robot's tolerance) the footprint would lay a flat floor at
    // 0.17 m over the treads around it and the floor beside them; there
    // only the point under the feet is floor, and the disk is kept on the
    // floor.
    let (rise, tread) = (0.17, 0.28);
    let frame = |feet: Point3<f64>| Observation {
        pose: RobotPose::new(feet, 0.0),
        sensor: Sensor::Occupancy(OccupancyObservation {
            origin: feet + nalgebra::Vector3::new(0.0, 0.0, 0.88),
            points: stair_points(rise, tread, 8),
        }),
    };
    let mut agent = agent();
    let floor = Point3::new(0.5, 0.0, 0.0);
    let mut t = 0.0;
    for _ in 0..3 {
        assert!(agent.observe(&frame(floor)).unwrap().footprint_points > 0);
        agent.step(Duration::from_secs_f64(t)).unwrap();
        t += 0.5;
    }
    assert_eq!(
        agent.frontier_map().stairs().len(),
        1,
        "the stair is mapped"
    );
    let first_tread = Point3::new(1.5 + tread / 2.0, 0.0, rise);
    assert_eq!(
        agent.current_level(),
        Some(sornav::frontier_graph::LevelId(0))
    );
    for _ in 0..3 {
        let report = agent.observe(&frame(first_tread)).unwrap();
        // Only the point under the robot's feet.
        assert_eq!(report.footprint_points, 1);
        agent.step(Duration::from_secs_f64(t)).unwrap();
        t += 0.5;
    }
    assert_eq!(
        agent.frontier_map().stairs().len(),
        1,
        "still mapped from its first tread"
    );
    assert!(agent.observe(&frame(floor)).unwrap().footprint_points > 0);
}

#[test]
fn protocol_errors_are_typed() {
    let mut agent = Agent::new(AgentConfig::default()).unwrap();
    assert!(matches!(
        agent.step(Duration::ZERO),
        Err(AgentError::NoTarget)
    ));
    assert!(matches!(
        agent.set_target("find the spaceship"),
        Err(AgentError::UnknownTarget { .. })
    ));
    agent.set_target("couch").unwrap();
    assert!(matches!(
        agent.set_target("flux capacitor"),
        Err(AgentError::UnknownTarget { .. })
    ));
    assert_eq!(agent.target().unwrap().category, "sofa");
    assert!(matches!(
        agent.step(Duration::ZERO),
        Err(AgentError::NoObservation)
    ));
    let world = common::World {
        blocks: vec![common::wall(3.0, -2.0, 3.2, 2.0)],
    };
    agent.observe(&world.observation(pose())).unwrap();
    let command = agent.step(Duration::from_secs(10)).unwrap();
    assert!(matches!(
        agent.step(Duration::from_secs(9)),
        Err(AgentError::ClockBackwards { .. })
    ));
    assert!(matches!(
        agent.on_mission_outcome(MissionId(999), MissionStatus::Reached),
        Err(AgentError::UnknownMission(MissionId(999)))
    ));
    // The platform's failure of an exploration mission excludes its
    // frontier from later routes.
    let AgentCommand::Dispatch { id, mission } = command else {
        panic!("expected exploration, got {command:?}");
    };
    assert_eq!(mission.kind.name(), "explore");
    agent
        .on_mission_outcome(
            id,
            MissionStatus::Failed(sornav::executor::FailureReason::PathInvalidated),
        )
        .unwrap();
    assert!(agent.active_mission().is_none());
    assert_eq!(agent.snapshot().excluded_frontiers.len(), 1);
    let next = agent.step(Duration::from_secs(11)).unwrap();
    if let AgentCommand::Dispatch { mission: m2, .. } = next {
        assert_ne!(m2.kind, mission.kind, "the failed frontier is not retried");
    }
}

/// The positions of labelled points, labels dropped.
fn positions(points: &[LabeledPoint]) -> Vec<Point3<f64>> {
    points
        .iter()
        .map(|p| {
            Point3::new(
                f64::from(p.position.x),
                f64::from(p.position.y),
                f64::from(p.position.z),
            )
        })
        .collect()
}

/// The labelled scan of `world` at `xy` as unlabelled world points.
fn unlabelled(world: &common::World, xy: Point2<f64>) -> Vec<Point3<f64>> {
    positions(&world.scan(xy))
}

fn occupancy_observation(points: Vec<Point3<f64>>) -> Observation {
    Observation {
        pose: pose(),
        sensor: Sensor::Occupancy(OccupancyObservation {
            origin: Point3::new(0.0, 0.0, 0.88),
            points,
        }),
    }
}

#[test]
fn occupancy_frames_build_the_grid_but_never_touch_semantics_or_the_gate() {
    let world = common::World {
        blocks: vec![
            common::wall(3.0, -2.0, 3.2, 2.0),
            common::object(15, 2.5, -0.3, 2.9, 0.3, 0.4, 1.0),
        ],
    };
    let xy = Point2::new(0.0, 0.0);
    let mut agent = agent();
    let report = agent
        .observe(&occupancy_observation(unlabelled(&world, xy)))
        .unwrap();
    assert!(report.occupancy_points > 0);
    assert_eq!(report.points, report.occupancy_points);
    assert_eq!((report.semantic_accepted, report.semantic_rejected), (0, 0));
    assert_eq!((report.objects, report.target_detections), (0, 0));
    assert!(report.frontiers_added > 0);
    assert_eq!(agent.semantic_map().integrations(), 0);
    assert_eq!(agent.semantic_map().cluster_count(), 0);
    assert_eq!(agent.stats().occupancy_observations, 1);
    assert_eq!(agent.stats().observations, 1);
    // The pose is known now, so the agent can explore.
    assert!(matches!(
        agent.step(Duration::ZERO).unwrap(),
        AgentCommand::Dispatch { .. }
    ));

    // Two labelled frames see the TV: s = 2. Occupancy frames in between
    // add neither support nor misses (the gate's update counter stays).
    let labelled = world.observation(pose());
    for _ in 0..2 {
        agent.observe(&labelled).unwrap();
        let updates = agent.gate().unwrap().tracker().updates();
        for _ in 0..4 {
            agent
                .observe(&occupancy_observation(unlabelled(&world, xy)))
                .unwrap();
        }
        assert_eq!(agent.gate().unwrap().tracker().updates(), updates);
    }
    let track = agent
        .gate()
        .unwrap()
        .tracker()
        .tracks()
        .next()
        .unwrap()
        .clone();
    assert_eq!((track.evidence.support, track.evidence.misses), (2, 0));
    assert_eq!(agent.semantic_map().integrations(), 2);
    assert_eq!(agent.stats().occupancy_observations, 9);
}

#[test]
fn occupancy_frames_are_validated() {
    let mut agent = agent();
    assert!(matches!(
        agent.observe(&occupancy_observation(Vec::new())),
        Err(AgentError::Observation(ObservationError::Empty))
    ));
    let mut bad_origin = occupancy_observation(vec![Point3::new(1.0, 0.0, 0.5)]);
    if let Sensor::Occupancy(o) = &mut bad_origin.sensor {
        o.origin.y = f64::NAN;
    }
    assert!(matches!(
        agent.observe(&bad_origin),
        Err(AgentError::Observation(
            ObservationError::NonFiniteSensorPose
        ))
    ));
    assert_eq!(agent.stats().refused_observations, 2);
    let report = agent
        .observe(&occupancy_observation(vec![
            Point3::new(2.0, 0.0, 0.5),
            Point3::new(f64::NAN, 0.0, 0.5),
            Point3::new(2.0, f64::NEG_INFINITY, 0.5),
        ]))
        .unwrap();
    assert_eq!((report.points, report.occupancy_points), (3, 1));
    assert_eq!(report.occupancy_rejected, 2);
    assert_eq!(agent.stats().rejected_points, 2);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Differential: an occupancy frame leaves exactly the occupancy grid
    /// and frontiers a labelled cloud of the same points leaves.
    #[test]
    fn occupancy_frames_equal_clouds_for_the_grid(
        raw in proptest::collection::vec((-6.0f64..6.0, -6.0f64..6.0, -0.2f64..2.2, 0u16..20), 1..300),
        origin in (-1.0f64..1.0, -1.0f64..1.0),
    ) {
        let origin = Point3::new(origin.0, origin.1, 0.88);
        let points: Vec<LabeledPoint> = raw
            .iter()
            .map(|&(x, y, z, l)| LabeledPoint::new(x as f32, y as f32, z as f32, LabelId(l)))
            .collect();
        let occupancy = Observation {
            pose: pose(),
            sensor: Sensor::Occupancy(OccupancyObservation {
                origin,
                points: positions(&points),
            }),
        };
        let cloud = Observation {
            pose: pose(),
            sensor: Sensor::Cloud(CloudObservation { origin, points }),
        };
        let (mut a, mut b) = (agent(), agent());
        let ra = a.observe(&cloud).unwrap();
        let rb = b.observe(&occupancy).unwrap();
        prop_assert_eq!(ra.occupancy_points, rb.occupancy_points);
        prop_assert_eq!(ra.footprint_points, rb.footprint_points);
        prop_assert_eq!((ra.frontiers_added, ra.frontiers_removed), (rb.frontiers_added, rb.frontiers_removed));
        let (sa, sb) = (a.snapshot(), b.snapshot());
        prop_assert_eq!(&sa.occupancy, &sb.occupancy);
        prop_assert_eq!(&sa.frontiers, &sb.frontiers);
        prop_assert_eq!(b.semantic_map().integrations(), 0);
        prop_assert!(sb.objects.is_empty());
    }
}

/// A contact (a forward move stopped by something the camera did not
/// show) puts an obstacle one cell beyond the robot's radius along its
/// heading, which the robot can no longer stand on and later frames do not
/// clear; a non-finite heading is a typed error and changes nothing.
#[test]
fn contacts_put_lasting_obstacles_on_the_map() {
    let mut agent = agent();
    let world = common::World {
        blocks: vec![common::wall(3.0, -2.0, 3.2, 2.0)],
    };
    agent.observe(&world.observation(pose())).unwrap();
    let ahead = Point3::new(0.5, 0.0, 0.0);
    assert!(agent.is_traversable(&ahead), "free before the contact");
    let feet = Point3::new(0.3, 0.0, 0.0);
    assert!(matches!(
        agent.on_contact(&feet, f64::NAN),
        Err(AgentError::Frontier(_))
    ));
    assert!(agent.is_traversable(&ahead), "an error changes nothing");
    assert!(agent.on_contact(&feet, 0.0).unwrap());
    for _ in 0..5 {
        agent.observe(&world.observation(pose())).unwrap();
    }
    assert!(
        !agent.is_traversable(&ahead),
        "the contact stays an obstacle"
    );
}
