//! The curved staircase of a real Sweet Home 3D basement
//! (`2BedroomHouseWithBasement` of `../shared/data/sh3d-homes`): from the
//! basement floor beside its foot, the agent maps the stair up.
//!
//! The flight turns in a stairwell walled on the basement's side; its
//! bottom sub-step (0.11 m, re-stepped on import) is narrower than a
//! 0.1 m surface column, so the first column of the flight is two
//! sub-steps (0.22 m) above the floor beside it, more than a step, and
//! from the floor beside the foot the camera sees the flight's first
//! treads at a grazing angle, the columns between unobserved. Before the
//! flight was attached across unobserved columns at its foot and by the
//! robot's own walked steps, the agent mapped no stair from these starts
//! and declared the basement exhausted (5 of the 11 exhausted false stops
//! of the shared homes at 160 x 120).
//!
//! The target is a category no pixel carries, so the agent explores until
//! the budget; the criterion is the map: a stair from the start floor
//! (level 0) that reaches at least [`MIN_RISE_M`] above it (complete or
//! partly seen). Skipped with a message when the shared data is missing,
//! a failure when `CI=true`.

mod absent_target;
#[allow(dead_code)] // this binary uses only the simulator helper
mod common;

use absent_target::{AbsentTargetFactory, absent_target_episode};
use common::simulator_160x120;
use nalgebra::Point3;
use sornav::frontier_graph::LevelId;
use sornav_examples::adapter::{AdapterConfig, ConfigFactory, SornavPolicy, sim_agent_config};
use sornav_platform_sim::{RunConfig, Scene, run_episode};

/// Actions per start.
const BUDGET: usize = 250;
/// Height (m) above the start floor a mapped stair must reach.
const MIN_RISE_M: f64 = 1.0;

#[test]
fn the_curved_stair_is_mapped_from_the_basement_beside_its_foot() {
    let Some(dir) = sornav_test_support::shared_data("sh3d-homes") else {
        return;
    };
    let home = dir.join("homes").join("2BedroomHouseWithBasement.xml");
    let sim = simulator_160x120(
        Scene::from_home_xml(&home, &dir.join("models"))
            .unwrap_or_else(|e| panic!("{}: {e}", home.display())),
    );
    // Basement floor positions 0.6-0.9 m from the foot of the flight (at
    // about (5.35, -0.25)), facing away from it, along and towards it:
    // the starts and headings of two `sornav-sim` episodes (seed 1, 20
    // per category) that ended in an exhausted false stop, and four more
    // headings.
    //
    // Not asserted (a known failure): (5.891, -0.693) heading -0.567 with
    // this test's absent target. The flight's first walkable tread is
    // never mapped from there: the treads next to the foot border the
    // stairwell's wall and fail the footprint test, the columns behind
    // them stay unobserved, and the chain from the foot finds no walkable
    // neighbour. (The `sornav-sim` episode from this start succeeds: its
    // route walks onto the first tread.)
    let starts = [
        (5.941, -0.593, 1.786),
        (5.941, -0.993, 1.200),
        (5.94, -0.59, std::f64::consts::FRAC_PI_2),
        (5.94, -0.99, 0.0),
        (5.89, -0.69, std::f64::consts::PI),
        (5.94, -0.99, -std::f64::consts::FRAC_PI_2),
    ];
    let mut failures = Vec::new();
    for &(x, y, yaw) in &starts {
        let z = sim
            .nav()
            .height_at(x, y, -1.5)
            .unwrap_or_else(|| panic!("no basement floor at ({x}, {y})"));
        let p = Point3::new(x, y, z);
        let episode = absent_target_episode(
            format!("({x}, {y}) yaw {yaw:.2}"),
            "2BedroomHouseWithBasement",
            p,
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
        let reach = map
            .stairs()
            .iter()
            .filter(|s| s.lower.level == Some(LevelId(0)))
            .map(|s| s.upper.position.z - s.lower.position.z)
            .fold(0.0, f64::max);
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
            "{}: {} actions, end {:?}, stair from the start floor rising {reach:.2} m; stairs {stairs:?}",
            episode.episode_id,
            trace.trajectory.len(),
            trace.agent_end
        );
        if reach < MIN_RISE_M {
            failures.push(episode.episode_id);
        }
    }
    assert!(
        failures.is_empty(),
        "no stair up mapped from {failures:?} within {BUDGET} actions"
    );
}
