//! The full agent across floors: in two-floor procedural houses it finds
//! targets on the other floor (up and down the stairs), from its own
//! rendered frames only.

#[allow(dead_code)] // this binary uses only the simulator helper
mod common;

use common::simulator_160x120;
use sornav_examples::adapter::{AdapterConfig, ConfigFactory, SornavPolicy, sim_agent_config};
use sornav_platform_sim::episodes::{GeneratorConfig, generate_episodes};
use sornav_platform_sim::procedural::ProceduralConfig;
use sornav_platform_sim::{RunConfig, Scene, Simulator, run_episode};

fn house(seed: u64, floors: u32) -> Simulator {
    let scene = Scene::procedural(
        seed,
        &ProceduralConfig {
            // SORNAV_MF_ANY_FLOORS: the generator's own floor count (the
            // houses of `sornav-sim --scenes procedural:N`).
            floors: (std::env::var_os("SORNAV_MF_ANY_FLOORS").is_none()).then_some(floors),
            ..ProceduralConfig::default()
        },
    )
    .unwrap();
    simulator_160x120(scene)
}

/// Runs the cross-floor episodes of `houses`; returns (successes, runs)
/// and prints what the agent knew at the end of each failure.
fn cross_floor(houses: &[u64], floors: u32, per_category: usize) -> (usize, usize) {
    let factory = ConfigFactory {
        config: sim_agent_config(),
        policy: None,
    };
    let mut policy = SornavPolicy::new(&factory, AdapterConfig::default());
    let (mut ok, mut runs) = (0, 0);
    for &seed in houses {
        let sim = house(seed, floors);
        let episodes = generate_episodes(
            &sim,
            &GeneratorConfig {
                episodes_per_category: per_category,
                seed,
                ..GeneratorConfig::default()
            },
        )
        .unwrap();
        for e in &episodes {
            let r = run_episode(&sim, e, &mut policy, &RunConfig::default()).unwrap();
            if !r.cross_floor {
                continue;
            }
            runs += 1;
            let trace = policy.take_trace();
            if r.success {
                ok += 1;
                continue;
            }
            let agent = policy.agent().expect("agent");
            let map = agent.frontier_map();
            eprintln!(
                "house {seed} episode {} ({} from level {} to {}): {:?} after {} actions, end {}",
                e.episode_id,
                e.object_category,
                r.start_level,
                r.goal_level,
                r.outcome,
                r.actions,
                trace.agent_end
            );
            eprintln!("  levels {:?}", map.levels().collect::<Vec<_>>());
            let zs: Vec<f32> = trace.trajectory.iter().map(|p| p[2]).collect();
            eprintln!(
                "  trajectory z {:?}..{:?}",
                zs.iter().copied().fold(f32::INFINITY, f32::min),
                zs.iter().copied().fold(f32::NEG_INFINITY, f32::max)
            );
            let samples: Vec<String> = trace
                .trajectory
                .iter()
                .step_by(25)
                .map(|p| format!("({:.1},{:.1},{:.2})", p[0], p[1], p[2]))
                .collect();
            eprintln!("  every 25 actions: {}", samples.join(" "));
            if std::env::var_os("SORNAV_MF_DUMP").is_some()
                && let Some(last) = trace.trajectory.last()
            {
                // The surface nearest the robot's final height per column
                // (decimetres relative to the start floor), 5 m around it.
                let floor0 = trace.trajectory[0][2];
                let (cx, cy, cz) = match map.stairs().iter().find_map(|s| s.open_end()) {
                    Some(e) => (e.position.x, e.position.y, e.position.z),
                    None => (
                        f64::from(last[0]),
                        f64::from(last[1]),
                        f64::from(last[2] - floor0),
                    ),
                };
                eprintln!(
                    "  surfaces around the open stair end or the end ({cx:.1},{cy:.1},{cz:.2}), y down the page:"
                );
                for dy in (-25..=25).rev() {
                    let row: String = (-25..=25)
                        .map(|dx| {
                            let v =
                                map.surfaces_at(cx + 0.1 * f64::from(dx), cy + 0.1 * f64::from(dy));
                            match v
                                .iter()
                                .min_by(|a, b| (*a - cz).abs().total_cmp(&(*b - cz).abs()))
                            {
                                None => "   .".to_string(),
                                Some(z) if dx == 0 && dy == 0 => {
                                    format!("{:>4}", format!("*{}", (z * 10.0).round() as i32))
                                }
                                Some(z) => format!("{:4}", (z * 10.0).round() as i32),
                            }
                        })
                        .collect();
                    eprintln!("  {row}");
                }
            }
            if let Ok(at) = std::env::var("SORNAV_MF_AT") {
                // Level 0's grid ('.' free, '#' occupied, ' ' unknown, 'T'
                // traversable) and the surface nearest the floor (dm) per
                // 0.1 m column, 3 m around x,y.
                let v: Vec<f64> = at.split(',').filter_map(|t| t.parse().ok()).collect();
                let (cx, cy) = (v[0], v[1]);
                let grid = map
                    .level_map(sornav::frontier_graph::LevelId(0))
                    .unwrap()
                    .grid();
                for dy in (-30..=30).rev() {
                    let mut row = String::new();
                    for dx in -30..=30 {
                        let q = nalgebra::Point2::new(
                            cx + 0.1 * f64::from(dx),
                            cy + 0.1 * f64::from(dy),
                        );
                        let c = grid.cell_of(&q).unwrap();
                        let ch = if grid.is_traversable(c) {
                            'T'
                        } else {
                            match grid.state(c) {
                                sornav::frontier_graph::CellState::Free => '.',
                                sornav::frontier_graph::CellState::Occupied => '#',
                                _ => ' ',
                            }
                        };
                        let sz = map.surfaces_at(q.x, q.y);
                        let z = sz
                            .iter()
                            .copied()
                            .min_by(|a, b| a.abs().total_cmp(&b.abs()));
                        row.push(ch);
                        row.push_str(&match z {
                            None => "  ".to_string(),
                            Some(z) => format!("{:>2}", ((-z * 10.0).round() as i32).clamp(-9, 99)),
                        });
                    }
                    eprintln!("  {row}");
                }
            }
            for s in map.stairs() {
                eprintln!("  stair {:?} -> {:?} ({:.1} m)", s.lower, s.upper, s.length);
            }
            for l in map.levels() {
                let lg = map.level_map(l.id).unwrap().graph();
                for id in lg.node_ids() {
                    if let sornav::frontier_graph::NodeId::Portal(_) = id {
                        eprintln!(
                            "  level {:?} portal {:?} at {:?}: robot edge {:?}, traversable cells nearby {}",
                            l.id,
                            id,
                            lg.position(id),
                            lg.cost(sornav::frontier_graph::NodeId::Robot, id),
                            {
                                let p = lg.position(id).unwrap();
                                let grid = map.level_map(l.id).unwrap().grid();
                                let mut n = 0;
                                for dx in -16..=16 {
                                    for dy in -16..=16 {
                                        let q = nalgebra::Point2::new(
                                            p.x + 0.05 * f64::from(dx),
                                            p.y + 0.05 * f64::from(dy),
                                        );
                                        if grid.cell_of(&q).is_ok_and(|c| grid.is_traversable(c)) {
                                            n += 1;
                                        }
                                    }
                                }
                                n
                            }
                        );
                    }
                }
            }
            let g = map.graph();
            eprintln!(
                "  frontiers {} (reachable {}), robot {:?}",
                g.len(),
                g.nodes()
                    .filter(|n| g
                        .cost(
                            sornav::frontier_graph::NodeId::Robot,
                            sornav::frontier_graph::NodeId::Frontier(n.id)
                        )
                        .is_some())
                    .count(),
                g.robot()
            );
            let runs = trace.decisions.runs();
            for d in &runs[runs.len().saturating_sub(6)..] {
                eprintln!("  {d:?}");
            }
        }
    }
    (ok, runs)
}

/// Ignored: the issue-19 target (cross-floor SR >= 60 %) is not met yet
/// (see the README's multi-floor results and the closing note of issue
/// 19). Run it with `--ignored` to see each failure with the agent's
/// levels, stairs, portals, trajectory and last decisions
/// (`SORNAV_MF_HOUSES=1,5` picks houses, `SORNAV_MF_ANY_FLOORS=1` uses the
/// generator's floor count as `sornav-sim --scenes procedural:N` does,
/// `SORNAV_MF_DUMP=1` prints the surface map around an open stair end,
/// `SORNAV_MF_AT=x,y` level 0's grid and surfaces around a point;
/// `SORNAV_DEBUG=1` / `SORNAV_DEBUG_ACTIONS=1` log dispatches / actions).
#[test]
#[ignore = "cross-floor success target not met yet; a diagnostic run"]
fn finds_targets_on_the_other_floor() {
    // SORNAV_MF_HOUSES=1,5 runs only those houses (debugging).
    let houses: Vec<u64> = std::env::var("SORNAV_MF_HOUSES")
        .ok()
        .map(|v| v.split(',').filter_map(|s| s.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![1, 5, 7]);
    let (ok, runs) = cross_floor(&houses, 2, 1);
    eprintln!("cross-floor: {ok} / {runs}");
    assert!(runs >= 3, "the houses give cross-floor episodes");
    assert!(
        ok * 2 >= runs,
        "{ok} of {runs} cross-floor episodes succeeded"
    );
}

/// A start at the head of a switchback's descending flight (procedural
/// house 2014 of `sornav-sim --scenes procedural:N`, three floors as the
/// generator draws them; the robot stands on the middle floor at the top
/// of the flight down, a stair up beside it). A level camera never sees
/// the treads below the head (the flight descends about as steeply as the
/// lowest ray), rays over the stairwell used to map it as free floor, and
/// the agent declared its floor exhausted after the first look around, 26
/// actions in, with no stair down mapped. Now it looks down through the
/// floor's edge first (a drop edge within reach) and maps the flight down
/// within its first 60 actions. (Whether it then searches the floor below
/// or the one above first is the policy's choice, not asserted here.)
#[test]
fn a_start_at_the_head_of_a_stair_going_down_maps_the_flight() {
    let sim = simulator_160x120(Scene::procedural(2014, &ProceduralConfig::default()).unwrap());
    let episodes = generate_episodes(
        &sim,
        &GeneratorConfig {
            categories: vec!["plant".to_owned()],
            episodes_per_category: 1,
            seed: 7,
            ..GeneratorConfig::default()
        },
    )
    .unwrap();
    let mut episode = episodes.into_iter().next().expect("a plant episode");
    episode.start_position = nalgebra::Point3::new(1.42, 2.12, 2.15);
    episode.start_yaw = (-28.0f64).to_radians();
    sim.spawn(&episode).expect("the stair head is navigable");
    let factory = ConfigFactory {
        config: sim_agent_config(),
        policy: None,
    };
    let mut policy = SornavPolicy::new(&factory, AdapterConfig::default());
    let run = RunConfig {
        max_actions: 60,
        ..RunConfig::default()
    };
    let r = run_episode(&sim, &episode, &mut policy, &run).unwrap();
    let trace = policy.take_trace();
    let agent = policy.agent().expect("agent");
    // Heights are relative to the start floor.
    let down: Vec<_> = agent
        .frontier_map()
        .stairs()
        .iter()
        .filter(|s| s.lower.position.z < -0.5 && s.upper.position.z.abs() < 0.3)
        .collect();
    assert!(
        !down.is_empty(),
        "no stair down mapped after {} actions ({:?}, end: {}); stairs {:?}; last decisions {:?}",
        r.actions,
        r.outcome,
        trace.agent_end,
        agent
            .frontier_map()
            .stairs()
            .iter()
            .map(|s| (s.lower.position, s.upper.position))
            .collect::<Vec<_>>(),
        &trace.decisions.runs()[trace.decisions.runs().len().saturating_sub(4)..]
    );
    assert_ne!(trace.agent_end, "exhausted", "the floor is not exhausted");
}
