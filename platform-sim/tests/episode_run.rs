//! Generated episodes satisfy their constraints; the oracle scores SR = 1 and
//! SPL >= 0.95, stopping at once scores SR = 0 (validates the metric chain).

use nalgebra::Point3;
use sornav_platform_sim::episodes::generator::body_distance;
use sornav_platform_sim::episodes::{GeneratorConfig, HabitatDataset, generate_episodes};
use sornav_platform_sim::metrics::{Outcome, Summary};
use sornav_platform_sim::{
    CameraConfig, Episode, Oracle, Policy, RandomWalk, RunConfig, Scene, SimConfig, Simulator,
    StopAtOnce, run_episode,
};

mod common;

/// The simulator of these tests: a 160 x 120 camera.
fn simulator(scene: Scene) -> Simulator {
    common::simulator(scene, 160, 120)
}

/// Every episode satisfies the generator's own constraints, checked with
/// independent tools (parry's ray cast for visibility, a fresh geodesic field).
fn check_constraints(sim: &Simulator, episodes: &[Episode], config: &GeneratorConfig) {
    let nav = sim.nav();
    let scene = sim.scene();
    let parry = common::ParryMesh::new(scene);
    let cam_h = sim.camera().config().mount_height;
    for e in episodes {
        assert!(
            nav.is_navigable(&e.start_position),
            "episode {}: start not navigable",
            e.episode_id
        );
        let field = nav.geodesic_field(&e.view_point_positions()).unwrap();
        let d = field.distance(nav, &e.start_position).unwrap();
        assert!(
            (config.min_geodesic..=config.max_geodesic).contains(&d),
            "episode {}: geodesic {d}",
            e.episode_id
        );
        assert!((d - e.geodesic_distance.unwrap()).abs() < 1e-6);
        // The closest goal's centre is at most the view point reach plus half
        // the object's diagonal away from its nearest view point.
        let closest = scene
            .instance(e.closest_goal_object_id.unwrap() as u32)
            .unwrap();
        let reach = config.view_point_radius + cam_h + closest.bounds.extents().norm() / 2.0;
        assert!(
            d + reach >= e.euclidean_distance.unwrap(),
            "episode {}: geodesic {d} vs euclidean {:?}",
            e.episode_id,
            e.euclidean_distance
        );
        let goals_of_category = scene.objects_of(&e.object_category).count();
        assert!(!e.goals.is_empty() && e.goals.len() <= goals_of_category);
        for g in &e.goals {
            let obj = scene.instance(g.object_id as u32).unwrap();
            assert_eq!(obj.category, e.object_category);
            for v in &g.view_points {
                assert!(nav.is_navigable(&v.position));
                assert!(body_distance(obj, &v.position, cam_h) <= config.view_point_radius + 1e-9);
                // Some ray from the eye to the object's box first hits the object.
                let eye = v.position + nalgebra::Vector3::new(0.0, 0.0, cam_h);
                assert!(
                    common::sees(&parry, &eye, obj),
                    "view point {:?} does not see object {}",
                    v.position,
                    obj.id
                );
            }
        }
        // The recorded closest goal is the one with the shortest geodesic
        // distance, and the cross-floor flag compares the navmesh levels of
        // the start and of the nearest view point.
        let per_goal: Vec<(u64, f64)> = e
            .goals
            .iter()
            .map(|g| {
                let vps: Vec<Point3<f64>> = g.view_points.iter().map(|v| v.position).collect();
                let f = nav.geodesic_field(&vps).unwrap();
                (g.object_id, f.distance(nav, &e.start_position).unwrap())
            })
            .collect();
        let best = per_goal.iter().map(|g| g.1).fold(f64::INFINITY, f64::min);
        let recorded = per_goal
            .iter()
            .find(|g| Some(g.0) == e.closest_goal_object_id)
            .unwrap();
        assert!((recorded.1 - best).abs() < 1e-9, "episode {}", e.episode_id);
        assert!((best - d).abs() < 1e-9);
        // cross-floor: the nearest view point lies on another navmesh level
        let floors = sornav_platform_sim::floor_relation(
            sim.nav(),
            &e.start_position,
            &e.view_point_positions(),
        )
        .unwrap();
        assert_eq!(
            e.cross_floor,
            Some(floors.cross_floor()),
            "episode {}",
            e.episode_id
        );
        // No episode starts at a view point.
        assert!(
            e.view_point_positions()
                .iter()
                .all(|v| (v - e.start_position).norm() > 0.1)
        );
    }
}

fn run_all(
    sim: &Simulator,
    episodes: &[Episode],
    policy: &mut dyn Policy,
    config: &RunConfig,
) -> Summary {
    let results: Vec<_> = episodes
        .iter()
        .map(|e| run_episode(sim, e, policy, config).unwrap())
        .collect();
    for r in &results {
        assert!((0.0..=1.0).contains(&r.spl) && (0.0..=1.0).contains(&r.soft_spl));
        assert!(r.actions <= config.max_actions);
        if r.spl == 1.0 {
            assert!(r.success && r.path_length_m <= r.start_geodesic_m + 1e-9);
        }
    }
    Summary::of(&results)
}

fn oracle_and_stop(sim: &Simulator, episodes: &[Episode]) {
    let config = RunConfig::default();
    let oracle = run_all(sim, episodes, &mut Oracle::new(), &config);
    assert_eq!(oracle.success_rate, 1.0, "oracle: {oracle:?}");
    // Habitat success (0.1 m of a view point) does not imply 1 m of the
    // object: the oracle stops on entering the view point band, up to 0.1 m
    // outside its 1 m edge.
    assert!(oracle.success_rate_1m > 0.0);
    assert!(oracle.spl >= 0.95, "oracle SPL {}", oracle.spl);
    let cross = episodes
        .iter()
        .filter(|e| e.cross_floor == Some(true))
        .count();
    eprintln!(
        "{}: {} episodes ({cross} cross-floor), oracle SR {} SPL {:.4} SR@1m {:.2} actions {:.1}",
        sim.scene().name(),
        episodes.len(),
        oracle.success_rate,
        oracle.spl,
        oracle.success_rate_1m,
        oracle.mean_actions
    );
    let stop = run_all(sim, episodes, &mut StopAtOnce, &config);
    assert_eq!(stop.success_rate, 0.0);
    assert_eq!(stop.mean_actions, 1.0);
    assert_eq!(stop.spl, 0.0);
}

#[test]
fn procedural_houses_oracle_and_stop() {
    let config = GeneratorConfig {
        episodes_per_category: 2,
        seed: 3,
        ..GeneratorConfig::default()
    };
    let mut total = 0;
    for (seed, floors) in [(1u64, 1u32), (2, 2)] {
        let sim = simulator(common::house(seed, floors));
        let episodes = generate_episodes(&sim, &config).unwrap();
        assert!(
            episodes.len() >= 4,
            "house {seed}: only {} episodes",
            episodes.len()
        );
        // Deterministic per seed.
        assert_eq!(episodes, generate_episodes(&sim, &config).unwrap());
        check_constraints(&sim, &episodes, &config);
        oracle_and_stop(&sim, &episodes);
        // Episodes survive Habitat's file format.
        let back = HabitatDataset::from_episodes(&episodes, &[])
            .to_episodes()
            .unwrap();
        assert_eq!(back.len(), episodes.len());
        total += episodes.len();
    }
    assert!(total >= 10);
}

#[test]
fn shared_homes_oracle() {
    let Some(dir) = sornav_test_support::shared_data("sh3d-homes") else {
        return;
    };
    let config = GeneratorConfig {
        episodes_per_category: 2,
        seed: 5,
        ..GeneratorConfig::default()
    };
    for home in ["Studio", "4BedroomHouse", "2BedroomHouseWithBasement"] {
        let scene = Scene::from_home_xml(
            &dir.join("homes").join(format!("{home}.xml")),
            &dir.join("models"),
        )
        .unwrap();
        let sim = simulator(scene);
        let episodes = generate_episodes(&sim, &config).unwrap();
        assert!(!episodes.is_empty(), "{home}: no episodes");
        check_constraints(&sim, &episodes, &config);
        oracle_and_stop(&sim, &episodes);
    }
}

/// The two-storey homes at the agent's 0.2 m step (their staircases are
/// re-stepped on import, see `scene_sh3d::multi_level_homes_connect_floors`):
/// episodes cross floors, and the oracle climbs the staircases (straight and
/// curved) by moving forward.
#[test]
fn shared_homes_across_floors_oracle() {
    let Some(dir) = sornav_test_support::shared_data("sh3d-homes") else {
        return;
    };
    let config = GeneratorConfig {
        episodes_per_category: 3,
        seed: 11,
        ..GeneratorConfig::default()
    };
    let mut cross = 0;
    for home in ["2BedroomHouseWithBasement", "3BedroomHouseWithAttic"] {
        let scene = Scene::from_home_xml(
            &dir.join("homes").join(format!("{home}.xml")),
            &dir.join("models"),
        )
        .unwrap();
        let sim = Simulator::new(
            scene,
            SimConfig {
                camera: CameraConfig {
                    width: 160,
                    height: 120,
                    ..CameraConfig::default()
                },
                ..SimConfig::default()
            },
        )
        .unwrap();
        let episodes = generate_episodes(&sim, &config).unwrap();
        check_constraints(&sim, &episodes, &config);
        // Episodes whose start and closest goal are a storey (2.62 m) apart.
        cross += episodes
            .iter()
            .filter(|e| {
                let goal = e
                    .goals
                    .iter()
                    .find(|g| Some(g.object_id) == e.closest_goal_object_id)
                    .unwrap();
                e.cross_floor == Some(true)
                    && goal
                        .view_points
                        .iter()
                        .all(|v| (v.position.z - e.start_position.z).abs() > 2.0)
            })
            .count();
        oracle_and_stop(&sim, &episodes);
    }
    assert!(cross >= 3, "only {cross} episodes across storeys");
}

#[test]
fn random_walk_hits_the_step_limit_and_taxonomy_holds() {
    let sim = simulator(common::house(4, 1));
    let episodes = common::one_episode_per_category(&sim);
    let config = RunConfig {
        max_actions: 60,
        ..RunConfig::default()
    };
    let mut walk = RandomWalk::new(9);
    for e in &episodes {
        let r = run_episode(&sim, e, &mut walk, &config).unwrap();
        assert_eq!(r.actions, 60);
        assert!(!r.success && r.spl == 0.0);
        // the cause is recorded whatever the floors
        assert_eq!(r.outcome, Outcome::StepLimit);
        assert_eq!(r.cross_floor, r.floors_between > 0);
        assert_eq!(r.floors_between, r.start_level.abs_diff(r.goal_level));
        assert!(r.path_length_m <= 0.25 * 60.0 + 1e-9);
    }
    // A zero wall-clock budget is rejected; a tiny one times out.
    assert!(
        run_episode(
            &sim,
            &episodes[0],
            &mut walk,
            &RunConfig {
                wall_clock_s: 0.0,
                ..RunConfig::default()
            }
        )
        .is_err()
    );
    let r = run_episode(
        &sim,
        &episodes[0],
        &mut RenderingWalk(RandomWalk::new(1)),
        &RunConfig {
            wall_clock_s: 1e-9,
            ..RunConfig::default()
        },
    )
    .unwrap();
    // the first action came after the budget ran out: discarded (see
    // `run_episode`'s wall-clock rules)
    assert_eq!(r.actions, 0);
    assert_eq!(r.outcome, Outcome::Timeout);
}

/// A random walk that sleeps in every `act` and reports the sleep as
/// accounted in simulated time (an LLM answer the policy waited for).
struct WaitingWalk {
    walk: RandomWalk,
    sleep: std::time::Duration,
    waited_s: f64,
    reported: bool,
}

impl Policy for WaitingWalk {
    fn needs_frames(&self) -> bool {
        false
    }
    fn act(&mut self, obs: &sornav_platform_sim::Observation<'_>) -> sornav_platform_sim::Action {
        std::thread::sleep(self.sleep);
        self.waited_s += self.sleep.as_secs_f64();
        self.walk.act(obs)
    }
    fn simulated_wait_s(&self) -> f64 {
        if self.reported { self.waited_s } else { 0.0 }
    }
}

/// Issue 22: wall time a policy accounts in simulated time does not count
/// toward the wall-clock budget; the same waits unreported time out.
#[test]
fn simulated_waits_are_left_out_of_the_wall_clock_budget() {
    let sim = simulator(common::house(4, 1));
    let episodes = common::one_episode_per_category(&sim);
    let config = RunConfig {
        max_actions: 8,
        wall_clock_s: 0.2,
        ..RunConfig::default()
    };
    let walk = |reported| WaitingWalk {
        walk: RandomWalk::new(3),
        sleep: std::time::Duration::from_millis(50),
        waited_s: 0.0,
        reported,
    };
    let r = run_episode(&sim, &episodes[0], &mut walk(true), &config).unwrap();
    assert_eq!(r.outcome, Outcome::StepLimit, "{r:?}");
    assert_eq!(r.actions, 8);
    assert!(
        r.timed_s < 0.2 && r.wall_s >= 0.4,
        "{} {}",
        r.timed_s,
        r.wall_s
    );
    let r = run_episode(&sim, &episodes[0], &mut walk(false), &config).unwrap();
    assert_eq!(r.outcome, Outcome::Timeout, "{r:?}");
}

/// A random walk that asks for frames (exercises the render path of the loop).
struct RenderingWalk(RandomWalk);

impl Policy for RenderingWalk {
    fn act(&mut self, obs: &sornav_platform_sim::Observation<'_>) -> sornav_platform_sim::Action {
        let f = obs.frame.expect("frames requested");
        assert_eq!(f.depth.len(), 160 * 120);
        self.0.act(obs)
    }
}

/// habitat-lab's filter against trivial episodes: below a geodesic/euclidean
/// ratio of 1.1 an episode is kept with probability 20 (r - 0.98)^2. As in
/// habitat-lab, the Euclidean distance goes to the closest goal's centre and
/// the geodesic one to its nearest view point, so most ratios are below 1 and
/// the filter mostly removes ratios near 1 (0.9-1.05 keep at most 13 %).
#[test]
fn ratio_filter_thins_near_straight_line_episodes() {
    let mut near_one = [0usize; 2];
    let mut total = [0usize; 2];
    for seed in [1u64, 2] {
        let sim = simulator(common::house(seed, 1));
        for (k, ratio) in [0.0, 1.1].into_iter().enumerate() {
            let config = GeneratorConfig {
                episodes_per_category: 20,
                geodesic_to_euclid_ratio: ratio,
                seed: 7,
                ..GeneratorConfig::default()
            };
            let episodes = generate_episodes(&sim, &config).unwrap();
            total[k] += episodes.len();
            near_one[k] += episodes
                .iter()
                .filter(|e| {
                    let r = e.geodesic_distance.unwrap() / e.euclidean_distance.unwrap();
                    (0.9..1.05).contains(&r)
                })
                .count();
        }
    }
    assert!(total[1] >= 150 && total[0] >= 150, "{total:?}");
    assert!(near_one[0] >= 20, "unfiltered: {near_one:?}");
    assert!(near_one[1] * 3 < near_one[0], "filtered: {near_one:?}");
}

/// Habitat's protocol defaults, and the 500-action limit of a policy that
/// never stops.
#[test]
fn default_rules_are_habitats() {
    let c = RunConfig::default();
    assert_eq!(c.max_actions, 500);
    assert_eq!(c.wall_clock_s, 120.0);
    assert_eq!(c.success_distance, 0.1);
    assert_eq!(c.object_distance, 1.0);
    let sim = simulator(common::house(4, 1));
    let episodes = common::one_episode_per_category(&sim);
    let r = run_episode(&sim, &episodes[0], &mut RandomWalk::new(3), &c).unwrap();
    assert_eq!(r.actions, 500);
    assert_eq!(r.outcome, Outcome::StepLimit);
    assert!(!r.success && !r.success_1m);
}

/// The oracle across floors: the cross-floor episodes of twelve houses with
/// 2 to 4 floors (houses where it once failed: turning back and forth
/// between two headings whose forward probes disagreed in the last bits,
/// or stopping in front of a passage one or two cells wide that the
/// discrete moves cannot follow). SR >= 0.95 is required; failures are printed.
#[test]
fn procedural_cross_floor_oracle_many_houses() {
    let config = GeneratorConfig {
        episodes_per_category: 4,
        seed: 3,
        ..GeneratorConfig::default()
    };
    let houses = [
        (2u32, 9u64),
        (2, 11),
        (2, 14),
        (2, 16),
        (3, 9),
        (3, 12),
        (3, 16),
        (3, 18),
        (4, 5),
        (4, 7),
        (4, 8),
        (4, 12),
    ];
    let (mut episodes_run, mut successes) = (0usize, 0usize);
    let mut failures = Vec::new();
    for (floors, seed) in houses {
        let sim = simulator(common::house(seed, floors));
        let episodes = generate_episodes(&sim, &config).unwrap();
        for e in episodes.iter().filter(|e| e.cross_floor == Some(true)) {
            let r = run_episode(&sim, e, &mut Oracle::new(), &RunConfig::default()).unwrap();
            assert!(
                r.cross_floor,
                "episode {}: flag and metric differ",
                e.episode_id
            );
            episodes_run += 1;
            if r.success {
                successes += 1;
            } else {
                failures.push(format!(
                    "{floors} floors seed {seed} episode {} ({}): start {:?}, geodesic {:.1} m, \
                     walked {:.1} m in {} actions, {:?}, {:.2} m left",
                    e.episode_id,
                    e.object_category,
                    e.start_position,
                    r.start_geodesic_m,
                    r.path_length_m,
                    r.actions,
                    r.outcome,
                    r.dtg_m.unwrap_or(f64::INFINITY)
                ));
            }
        }
    }
    let sr = successes as f64 / episodes_run.max(1) as f64;
    eprintln!(
        "cross-floor oracle: {successes}/{episodes_run} (SR {sr:.3}) over {} houses",
        houses.len()
    );
    for f in &failures {
        eprintln!("  failed: {f}");
    }
    assert!(
        episodes_run >= 100,
        "only {episodes_run} cross-floor episodes"
    );
    assert!(sr >= 0.95, "cross-floor oracle SR {sr:.3}: {failures:#?}");
}

/// Issue 21: rules under which no episode can run are refused up front by
/// `RunConfig::validate` (the harness checks them before any episode),
/// naming the field.
#[test]
fn run_rules_that_cannot_run_are_refused() {
    assert!(RunConfig::default().validate().is_ok());
    let infinite = RunConfig {
        wall_clock_s: f64::INFINITY,
        ..RunConfig::default()
    };
    assert!(infinite.validate().is_ok(), "infinite means no limit");
    for (config, field) in [
        (
            RunConfig {
                max_actions: 0,
                ..RunConfig::default()
            },
            "max_actions",
        ),
        (
            RunConfig {
                wall_clock_s: 0.0,
                ..RunConfig::default()
            },
            "wall_clock_s",
        ),
        (
            RunConfig {
                wall_clock_s: f64::NAN,
                ..RunConfig::default()
            },
            "wall_clock_s",
        ),
        (
            RunConfig {
                success_distance: -1.0,
                ..RunConfig::default()
            },
            "success_distance",
        ),
    ] {
        match config.validate() {
            Err(e @ sornav_platform_sim::SimError::Config(_)) => {
                assert!(e.to_string().contains(field), "{e}");
            }
            other => panic!("{field}: expected a configuration error, got {other:?}"),
        }
    }
}
