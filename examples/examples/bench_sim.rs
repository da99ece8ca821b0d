//! Speed of the simulator pipeline on one core: the full SOR-Nav agent
//! (commonsense gate, TSP) on procedural-house episodes, at 160x120 and at
//! Habitat's 640x480. Prints one JSON line per resolution:
//! `{"width","height","episodes","actions_mean","episode_s_p50",
//! "s_per_500_actions","decision_ms_p50","decision_ms_p99","frame_ms_p50",
//! "timeouts","phases_s_per_500_actions"}`.
//!
//! `phases_s_per_500_actions` splits `s_per_500_actions` by phase:
//! `render` (the camera: every observed pose is rendered again after the
//! episode and timed alone, so the episode itself is not slowed), `policy`
//! (`Policy::act` of the SOR-Nav adapter: the frame's conversion to an
//! observation, the agent's `observe` (depth to points, occupancy and
//! semantic integration, frontiers) and `step` (decision), waypoint
//! following) and `other` (the rest: the simulator's motion and
//! bookkeeping).
//!
//! `cargo run --release -p sornav-examples --example bench_sim [-- EPISODES [WxH]]`
//! (`WxH`: one resolution only, say `640x480`, for profiling one of them).
//!
//! `BENCH_SIM_WALL_CLOCK_S=SECONDS` replaces the 120 s wall-clock budget
//! of an episode (say `1e9` under valgrind, where the budget would cut
//! episodes short and before/after runs would not cover the same
//! actions).

use std::time::Instant;

use nalgebra::Point3;

use sornav_examples::adapter::{AdapterConfig, ConfigFactory, SornavPolicy};
use sornav_examples::histogram::Histogram;
use sornav_platform_sim::episodes::{GeneratorConfig, generate_episodes};
use sornav_platform_sim::procedural::ProceduralConfig;
use sornav_platform_sim::{
    Action, CameraConfig, Episode, Observation, Outcome, Policy, RunConfig, Scene, SimConfig,
    Simulator, run_episode,
};

/// Delegates to a policy and records the camera pose of every observation,
/// so the frames can be rendered again and timed alone.
struct Recording<'a, P> {
    inner: &'a mut P,
    poses: Vec<(Point3<f64>, f64, f64)>,
    /// Time spent in the inner policy's `act`, s.
    act_s: f64,
}

impl<P: Policy> Policy for Recording<'_, P> {
    fn reset(&mut self, sim: &Simulator, episode: &Episode) {
        self.inner.reset(sim, episode);
    }
    fn needs_frames(&self) -> bool {
        self.inner.needs_frames()
    }
    fn act(&mut self, obs: &Observation<'_>) -> Action {
        self.poses.push((obs.position, obs.yaw, obs.pitch));
        let t = Instant::now();
        let action = self.inner.act(obs);
        self.act_s += t.elapsed().as_secs_f64();
        action
    }
}

fn main() {
    let episodes: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(12);
    // One core: a single-thread pool for rendering and everything else.
    let resolutions: Vec<(u32, u32)> = match std::env::args().nth(2) {
        Some(r) => {
            let (w, h) = r.split_once('x').expect("resolution WxH");
            vec![(
                w.parse().expect("width in WxH"),
                h.parse().expect("height in WxH"),
            )]
        }
        None => vec![(160, 120), (640, 480)],
    };
    let run_config = RunConfig {
        wall_clock_s: std::env::var("BENCH_SIM_WALL_CLOCK_S")
            .ok()
            .map(|s| s.parse().expect("BENCH_SIM_WALL_CLOCK_S: seconds"))
            .unwrap_or(RunConfig::default().wall_clock_s),
        ..RunConfig::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    let agent = sornav_examples::adapter::sim_agent_config();
    let factory = ConfigFactory {
        config: agent,
        policy: None,
    };
    for (width, height) in resolutions {
        let camera = CameraConfig {
            width,
            height,
            ..CameraConfig::default()
        };
        let (mut walls, mut actions, mut timeouts) = (Vec::new(), 0usize, 0usize);
        let (mut decision, mut frame) = (Histogram::new(), Histogram::new());
        let (mut render_s, mut policy_s) = (0.0f64, 0.0f64);
        let mut seed = 100;
        while walls.len() < episodes {
            seed += 1;
            let house = ProceduralConfig {
                floors: Some(1),
                ..ProceduralConfig::default()
            };
            let scene = Scene::procedural(seed, &house).expect("procedural house");
            let sim = Simulator::new(
                scene,
                SimConfig {
                    camera: camera.clone(),
                    ..SimConfig::default()
                },
            )
            .expect("simulator");
            let generator = GeneratorConfig {
                episodes_per_category: 1,
                seed,
                ..GeneratorConfig::default()
            };
            let eps = generate_episodes(&sim, &generator).expect("episodes");
            for e in eps.iter().take(2) {
                if walls.len() >= episodes {
                    break;
                }
                let mut policy = SornavPolicy::new(&factory, AdapterConfig::default());
                let mut recording = Recording {
                    inner: &mut policy,
                    poses: Vec::new(),
                    act_s: 0.0,
                };
                let t0 = Instant::now();
                let r = pool
                    .install(|| run_episode(&sim, e, &mut recording, &run_config))
                    .expect("episode");
                walls.push(t0.elapsed().as_secs_f64());
                let camera = sim.camera();
                let t1 = Instant::now();
                pool.install(|| {
                    for (p, yaw, pitch) in &recording.poses {
                        std::hint::black_box(camera.render(&camera.pose_at(p, *yaw, *pitch), 0));
                    }
                });
                render_s += t1.elapsed().as_secs_f64();
                policy_s += recording.act_s;
                actions += r.actions;
                timeouts += usize::from(r.outcome == Outcome::Timeout);
                let trace = policy.take_trace();
                decision.merge(&trace.decision_ms);
                frame.merge(&trace.frame_ms);
            }
        }
        let total: f64 = walls.iter().sum();
        walls.sort_by(f64::total_cmp);
        let line = serde_json::json!({
            "width": width,
            "height": height,
            "episodes": walls.len(),
            "actions_mean": actions as f64 / walls.len() as f64,
            "episode_s_p50": walls[walls.len() / 2],
            "s_per_500_actions": total / actions as f64 * 500.0,
            "decision_ms_p50": decision.quantile(0.5),
            "decision_ms_p99": decision.quantile(0.99),
            "frame_ms_p50": frame.quantile(0.5),
            "timeouts": timeouts,
            "phases_s_per_500_actions": {
                "render": render_s / actions as f64 * 500.0,
                "policy": policy_s / actions as f64 * 500.0,
                "other": (total - render_s - policy_s) / actions as f64 * 500.0,
            },
        });
        println!("{line}");
    }
}
