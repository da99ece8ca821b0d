//! Decision latency of the agent on a scripted four-room house: every
//! action is one labelled 720-ray scan (`observe`) and one decision
//! (`step`). Prints one JSON line with the medians (and p99) over all
//! actions of all episodes.
//!
//! `cargo run --release -p sornav --example bench_agent`

#[path = "../tests/common/mod.rs"]
mod common;

use std::time::{Duration, Instant};

use common::{Robot, World, object, wall};
use sornav::{Agent, AgentCommand, AgentConfig, Variant};

/// Four 6 m x 5 m rooms in a row, 1 m doors, furniture, a TV in the last.
fn house() -> World {
    let mut blocks = vec![
        wall(-0.1, -0.1, 24.1, 0.1),
        wall(-0.1, 4.9, 24.1, 5.1),
        wall(-0.1, -0.1, 0.1, 5.1),
        wall(23.9, -0.1, 24.1, 5.1),
    ];
    for k in 1..4 {
        let x = 6.0 * f64::from(k);
        let door = if k % 2 == 0 { 0.8 } else { 3.2 };
        blocks.push(wall(x - 0.1, -0.1, x + 0.1, door));
        blocks.push(wall(x - 0.1, door + 1.0, x + 0.1, 5.1));
    }
    blocks.push(object(12, 0.5, 3.5, 2.5, 4.8, 0.0, 0.6)); // bed
    blocks.push(object(10, 8.0, 1.0, 8.5, 1.5, 0.0, 0.9)); // chair
    blocks.push(object(11, 9.0, 1.0, 10.5, 2.0, 0.0, 0.75)); // table
    blocks.push(object(13, 13.0, 4.0, 15.0, 4.8, 0.0, 0.8)); // sofa
    blocks.push(object(17, 19.0, 0.2, 20.5, 0.6, 0.0, 1.8)); // cabinet
    blocks.push(object(15, 22.0, 4.7, 22.8, 4.89, 0.5, 1.1)); // tv
    World { blocks }
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn main() {
    let world = house();
    let starts = [(1.5, 1.5), (3.0, 2.5), (4.5, 1.0), (1.0, 2.0), (3.5, 4.0)];
    let mut observe_ms = Vec::new();
    let mut step_ms = Vec::new();
    let mut successes = 0;
    let mut actions = 0;
    let wall_start = Instant::now();
    for &(x, y) in &starts {
        let mut agent = Agent::new(AgentConfig::for_variant(Variant::Sornav).unwrap()).unwrap();
        agent.set_target("television").unwrap();
        let mut robot = Robot::new(x, y);
        for action in 0..500u64 {
            let observation = world.observation(robot.pose);
            let t0 = Instant::now();
            agent.observe(&observation).unwrap();
            let t1 = Instant::now();
            let command = agent.step(Duration::from_millis(500 * action)).unwrap();
            let t2 = Instant::now();
            observe_ms.push((t1 - t0).as_secs_f64() * 1e3);
            step_ms.push((t2 - t1).as_secs_f64() * 1e3);
            actions += 1;
            if !robot.obey(&command) {
                successes += u32::from(matches!(command, AgentCommand::Stop { .. }));
                break;
            }
            robot.act();
        }
    }
    let wall_s = wall_start.elapsed().as_secs_f64();
    let mut decision: Vec<f64> = observe_ms
        .iter()
        .zip(&step_ms)
        .map(|(a, b)| a + b)
        .collect();
    println!(
        "{{\"bench\":\"agent_four_rooms\",\"episodes\":{},\"successes\":{},\"actions\":{},\"observe_ms_p50\":{:.3},\"step_ms_p50\":{:.3},\"decision_ms_p50\":{:.3},\"decision_ms_p99\":{:.3},\"wall_s\":{:.3}}}",
        starts.len(),
        successes,
        actions,
        percentile(&mut observe_ms, 0.5),
        percentile(&mut step_ms, 0.5),
        percentile(&mut decision, 0.5),
        percentile(&mut decision, 0.99),
        wall_s
    );
}
