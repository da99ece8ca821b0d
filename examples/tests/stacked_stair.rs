//! A steep straight flight under another flight, in a real Sweet Home 3D
//! home (`3BedroomHouseWithAttic` of `../shared/data/sh3d-homes`): the
//! staircase from the ground floor to the second floor rises 2.62 m over
//! 2.2 m (about 50 degrees), and the second floor's curved staircase to
//! the attic turns above it in the same stairwell.
//!
//! On such a flight the camera, tilted one step (30 degrees) down, sees
//! the treads only from about 0.7 m ahead of the feet: the treads just
//! below the robot stay unobserved from every pose on the flight, and
//! from its head and its foot (from below, treads are not seen at all),
//! so the map holds two pieces of the flight with an unobserved gap
//! between them that no path crosses. Before the platform tilted as far
//! down as it can on a stair going down, the robot turned and stepped
//! back and forth at the upper piece's open end until the step limit or
//! declared its floor exhausted; an episode starting on the flight never
//! moved. Tilting further fixed 6 of the home's 10 failures at 160 x 120
//! (2 other episodes fail since).
//!
//! From starts on the flight's upper half, the agent (a target category
//! no pixel carries, so it explores until the budget) must map the rest of
//! the flight down: its map gives a path from the start to the ground
//! floor at the flight's foot. (Mapping the flight up from such a start is
//! not asserted: from a tread, the treads above the camera are not seen,
//! and from a start at the flight's middle the agent declares the search
//! exhausted without the second floor, a known failure.) Skipped with a
//! message when the shared data is missing, a failure when `CI=true`.

mod absent_target;
#[allow(dead_code)] // this binary uses only the simulator helper
mod common;

use absent_target::{AbsentTargetFactory, absent_target_episode};
use common::simulator_160x120;
use nalgebra::Point3;
use sornav_examples::adapter::{AdapterConfig, ConfigFactory, SornavPolicy, sim_agent_config};
use sornav_platform_sim::{RunConfig, Scene, run_episode};

const BUDGET: usize = 150;
/// A ground-floor place beside the flight's foot (world coordinates,
/// feet).
const FOOT: [f64; 3] = [3.6, -3.7, 0.0];

#[test]
fn a_steep_flight_under_another_is_mapped_down_from_starts_on_it() {
    let Some(dir) = sornav_test_support::shared_data("sh3d-homes") else {
        return;
    };
    let home = dir.join("homes").join("3BedroomHouseWithAttic.xml");
    let sim = simulator_160x120(
        Scene::from_home_xml(&home, &dir.join("models"))
            .unwrap_or_else(|e| panic!("{}: {e}", home.display())),
    );
    // (x, y, height hint, yaw): on the flight's upper half facing down and
    // up, and a generated episode's start at its middle.
    let starts = [
        (3.62, -1.89, 1.85, -std::f64::consts::FRAC_PI_2),
        (3.70, -1.65, 2.1, std::f64::consts::FRAC_PI_2),
        (3.705, -2.24, 1.42, 1.328),
    ];
    let mut failures = Vec::new();
    for &(x, y, hint, yaw) in &starts {
        let z = sim
            .nav()
            .height_at(x, y, hint)
            .unwrap_or_else(|| panic!("no tread at ({x}, {y}) near {hint} m"));
        let episode = absent_target_episode(
            format!("({x}, {y}, {z:.2}) yaw {yaw:.2}"),
            "3BedroomHouseWithAttic",
            Point3::new(x, y, z),
            yaw,
        );
        let factory = AbsentTargetFactory(ConfigFactory {
            config: sim_agent_config(),
            policy: None,
        });
        let mut policy = SornavPolicy::new(factory, AdapterConfig::default());
        let run = RunConfig {
            max_actions: BUDGET,
            wall_clock_s: f64::INFINITY,
            ..RunConfig::default()
        };
        run_episode(&sim, &episode, &mut policy, &run).unwrap();
        let trace = policy.take_trace();
        assert!(trace.errors.is_empty(), "agent errors {:?}", trace.errors);
        let map = policy.agent().expect("the agent was built").frontier_map();
        // The agent's frame: world x, y; z from the start's feet.
        let local = |p: [f64; 3]| Point3::new(p[0], p[1], p[2] - z);
        let joined = map
            .clone()
            .path(&local([x, y, z]), &local(FOOT))
            .unwrap_or_else(|e| panic!("path query: {e}"))
            .is_some();
        let stairs: Vec<String> = map
            .stairs()
            .iter()
            .map(|s| {
                format!(
                    "{:?} ({:.2}) -> {:?} ({:.2})",
                    s.lower.level, s.lower.position.z, s.upper.level, s.upper.position.z
                )
            })
            .collect();
        eprintln!(
            "{}: {} actions, end {:?}, joined to the floor below: {joined}; stairs {stairs:?}",
            episode.episode_id,
            trace.trajectory.len(),
            trace.agent_end
        );
        if !joined {
            failures.push(episode.episode_id);
        }
    }
    assert!(
        failures.is_empty(),
        "the flight was not mapped down to the floor below from {failures:?} within {BUDGET} actions"
    );
}
