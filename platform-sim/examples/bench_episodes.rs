//! Episode-loop throughput on a procedural house: ms per step (render +
//! policy + bookkeeping) at 160x120 and 640x480, and oracle episodes per
//! second (without frames, and rendering 640x480 frames every step).
//!
//! ```text
//! RAYON_NUM_THREADS=1 cargo run --release -p sornav-platform-sim --example bench_episodes [seed]
//! ```
//! Prints one JSON line of medians:
//! `{"scene","triangles","episodes","step_ms_160x120","step_ms_640x480","oracle_episodes_per_s","oracle_episodes_per_s_rendering"}`.

use std::time::Instant;

use sornav_platform_sim::episodes::{GeneratorConfig, generate_episodes};
use sornav_platform_sim::procedural::ProceduralConfig;
use sornav_platform_sim::{
    Action, CameraConfig, Episode, Observation, Oracle, Policy, RandomWalk, RunConfig, Scene,
    SimConfig, Simulator, run_episode,
};

/// Wraps a policy and makes the loop render a frame every step.
struct WithFrames<P: Policy>(P);

impl<P: Policy> Policy for WithFrames<P> {
    fn reset(&mut self, sim: &Simulator, episode: &Episode) {
        self.0.reset(sim, episode);
    }
    fn act(&mut self, obs: &Observation<'_>) -> Action {
        std::hint::black_box(obs.frame.map(|f| f.valid_depth_count()));
        self.0.act(obs)
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn simulator(scene: &Scene, width: u32, height: u32) -> Result<Simulator, String> {
    let config = SimConfig {
        camera: CameraConfig {
            width,
            height,
            ..CameraConfig::default()
        },
        ..SimConfig::default()
    };
    Simulator::new(scene.clone(), config).map_err(|e| e.to_string())
}

fn main() -> Result<(), String> {
    let seed: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let scene = Scene::procedural(seed, &ProceduralConfig::default()).map_err(|e| e.to_string())?;
    let sim_small = simulator(&scene, 160, 120)?;
    let sim_large = simulator(&scene, 640, 480)?;
    let episodes = generate_episodes(
        &sim_small,
        &GeneratorConfig {
            episodes_per_category: 3,
            ..GeneratorConfig::default()
        },
    )
    .map_err(|e| e.to_string())?;
    if episodes.is_empty() {
        return Err("no episodes".into());
    }
    // Step time: a random walk that reads every frame, 100 actions per episode.
    let walk_cfg = RunConfig {
        max_actions: 100,
        ..RunConfig::default()
    };
    let mut step_ms = Vec::new();
    for sim in [&sim_small, &sim_large] {
        let mut per_episode = Vec::new();
        for e in &episodes {
            let r = run_episode(sim, e, &mut WithFrames(RandomWalk::new(3)), &walk_cfg)
                .map_err(|e| e.to_string())?;
            per_episode.push(r.wall_s * 1e3 / r.actions as f64);
        }
        step_ms.push(median(per_episode));
    }
    // Oracle episodes per second, without and with frames.
    let cfg = RunConfig::default();
    let mut eps = Vec::new();
    let mut successes = 0;
    for _ in 0..3 {
        let t = Instant::now();
        for e in &episodes {
            successes += usize::from(
                run_episode(&sim_small, e, &mut Oracle::new(), &cfg)
                    .map_err(|e| e.to_string())?
                    .success,
            );
        }
        eps.push(episodes.len() as f64 / t.elapsed().as_secs_f64());
    }
    let t = Instant::now();
    for e in &episodes {
        run_episode(&sim_large, e, &mut WithFrames(Oracle::new()), &cfg)
            .map_err(|e| e.to_string())?;
    }
    let eps_render = episodes.len() as f64 / t.elapsed().as_secs_f64();
    eprintln!("oracle successes {successes} / {}", 3 * episodes.len());
    println!(
        "{{\"scene\":\"{}\",\"triangles\":{},\"episodes\":{},\"step_ms_160x120\":{:.3},\"step_ms_640x480\":{:.3},\"oracle_episodes_per_s\":{:.1},\"oracle_episodes_per_s_rendering\":{:.2}}}",
        scene.name(),
        scene.triangles().len(),
        episodes.len(),
        step_ms[0],
        step_ms[1],
        median(eps),
        eps_render
    );
    Ok(())
}
