//! The simulator and the ObjectNav episode loop.
//!
//! [`Simulator`] bundles a [`Scene`], its walkable height field and a camera;
//! [`run_episode`] plays one [`Episode`] with a [`Policy`] under Habitat's
//! protocol and scores it ([`EpisodeResult`]).
//!
//! # Example
//! ```
//! use sornav_platform_sim::episodes::{GeneratorConfig, generate_episodes};
//! use sornav_platform_sim::procedural::ProceduralConfig;
//! use sornav_platform_sim::{
//!     CameraConfig, Oracle, RunConfig, Scene, SimConfig, Simulator, Summary, run_episode,
//! };
//!
//! let house = ProceduralConfig { floors: Some(1), ..ProceduralConfig::default() };
//! let scene = Scene::procedural(7, &house).unwrap();
//! let camera = CameraConfig { width: 160, height: 120, ..CameraConfig::default() };
//! let sim = Simulator::new(scene, SimConfig { camera, ..SimConfig::default() }).unwrap();
//! let generator = GeneratorConfig { episodes_per_category: 1, ..GeneratorConfig::default() };
//! let episodes = generate_episodes(&sim, &generator).unwrap();
//! let results: Vec<_> = episodes
//!     .iter()
//!     .map(|e| run_episode(&sim, e, &mut Oracle::new(), &RunConfig::default()).unwrap())
//!     .collect();
//! let summary = Summary::of(&results);
//! assert!(summary.episodes > 0);
//! assert_eq!(summary.success_rate, 1.0); // the ground-truth oracle always succeeds
//! assert!(summary.spl > 0.9);
//! ```

use std::time::Instant;

use nalgebra::{Point3, Vector2};
use serde::{Deserialize, Serialize};

use crate::agent::{Action, Agent, AgentConfig, AgentError};
use crate::episodes::Episode;
use crate::geodesic::GeodesicField;
use crate::metrics::{self, EpisodeResult, Termination};

/// How [`run_episode`]'s loop ended (before the end pose is scored).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LoopEnd {
    Stopped,
    StepLimit,
    Timeout,
}
use crate::policy::Policy;
use crate::render::{Camera, CameraConfig, Frame, RenderError};
use crate::{Aabb, NavError, NavMesh, NavMeshConfig, Scene, SceneError};

/// Configuration of a [`Simulator`].
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SimConfig {
    /// Camera (Habitat defaults).
    pub camera: CameraConfig,
    /// Walkable height field (Habitat's navmesh defaults).
    pub nav: NavMeshConfig,
    /// Motion (Habitat ObjectNav defaults).
    pub agent: AgentConfig,
}

/// Rules of an episode (Habitat ObjectNav defaults).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RunConfig {
    /// Action budget (500).
    pub max_actions: usize,
    /// Wall-clock budget in seconds (120, as in the paper), from the first
    /// observation to the last action, setup excluded (see [`run_episode`]);
    /// running out ends the episode as a timeout.
    pub wall_clock_s: f64,
    /// Success radius around goal view points, geodesic metres (0.1).
    pub success_distance: f64,
    /// The paper's object boundary for `success_1m` (1.0 m).
    pub object_distance: f64,
    /// Seed of the camera noise stream (combined with the step index).
    pub noise_seed: u64,
}

impl Default for RunConfig {
    fn default() -> Self {
        RunConfig {
            max_actions: 500,
            wall_clock_s: 120.0,
            success_distance: 0.1,
            object_distance: 1.0,
            noise_seed: 0,
        }
    }
}

impl RunConfig {
    /// Checks that an episode can run under these rules.
    ///
    /// # Errors
    /// [`SimError::Config`] naming the field: `max_actions` must be at least
    /// 1, `wall_clock_s` positive (not NaN; infinite means no limit),
    /// `success_distance` at least 0.
    pub fn validate(&self) -> Result<(), SimError> {
        if self.max_actions == 0 {
            return Err(SimError::Config("max_actions must be at least 1"));
        }
        if self.wall_clock_s.is_nan() || self.wall_clock_s <= 0.0 {
            return Err(SimError::Config("wall_clock_s must be positive (not NaN)"));
        }
        if !(0.0..).contains(&self.success_distance) {
            return Err(SimError::Config("success_distance must be at least 0"));
        }
        Ok(())
    }
}

/// Errors of simulator construction and episode runs.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// Building the height field failed.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Building the camera failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The episode's start is not navigable.
    #[error(transparent)]
    Agent(#[from] AgentError),
    /// The episode's view points are all off the walkable surface.
    #[error("episode {episode_id}: {source}")]
    Goals {
        /// The episode.
        episode_id: String,
        /// Why.
        #[source]
        source: NavError,
    },
    /// The run configuration is invalid.
    #[error("invalid run configuration: {0}")]
    Config(&'static str),
}

/// A scene ready for episodes: mesh, walkable height field and camera.
#[derive(Debug, Clone)]
pub struct Simulator {
    scene: Scene,
    nav: std::sync::Arc<NavMesh>,
    camera: Camera,
    config: SimConfig,
}

impl Simulator {
    /// Builds the height field and the camera's BVH.
    ///
    /// # Errors
    /// [`SimError`] for invalid configurations.
    ///
    /// # Complexity
    /// Height field construction plus O(T log T) for the BVH.
    pub fn new(scene: Scene, config: SimConfig) -> Result<Simulator, SimError> {
        config.agent.validate()?;
        let nav = std::sync::Arc::new(NavMesh::build(&scene, &config.nav)?);
        let camera = Camera::for_scene(&scene, config.camera.clone())?;
        Ok(Simulator {
            scene,
            nav,
            camera,
            config,
        })
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// The walkable height field.
    pub fn nav(&self) -> &NavMesh {
        &self.nav
    }
    /// The walkable height field, shared (for policies that keep it).
    pub fn nav_shared(&self) -> std::sync::Arc<NavMesh> {
        std::sync::Arc::clone(&self.nav)
    }
    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }
    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// Places an agent at an episode's start.
    ///
    /// # Errors
    /// [`SimError::Agent`] when the start is not navigable.
    pub fn spawn(&self, episode: &Episode) -> Result<Agent, SimError> {
        Ok(Agent::spawn(
            &self.nav,
            &episode.start_position,
            episode.start_yaw,
            self.config.agent.clone(),
        )?)
    }

    /// Renders what the agent sees.
    pub fn observe_frame(&self, agent: &Agent, seed: u64) -> Frame {
        let pose = self
            .camera
            .pose_at(&agent.position(), agent.yaw(), agent.pitch());
        self.camera.render(&pose, seed)
    }

    /// [`Simulator::observe_frame`] into `frame`, reusing its buffers
    /// ([`Camera::render_into`]).
    pub fn observe_frame_into(&self, agent: &Agent, seed: u64, frame: &mut Frame) {
        let pose = self
            .camera
            .pose_at(&agent.position(), agent.yaw(), agent.pitch());
        self.camera.render_into(&pose, seed, frame);
    }

    /// Geodesic field to all view points of an episode.
    ///
    /// # Errors
    /// [`SimError::Goals`] when no view point lies on the walkable surface.
    ///
    /// # Complexity
    /// O(S log S) for S spans.
    pub fn goal_field(&self, episode: &Episode) -> Result<GeodesicField, SimError> {
        self.nav
            .geodesic_field(&episode.view_point_positions())
            .map_err(|source| SimError::Goals {
                episode_id: episode.episode_id.clone(),
                source,
            })
    }

    /// Distance from an agent standing at `feet` (body up to camera height) to
    /// the closest goal object of the episode: to the object's bounds when the
    /// goal's object id is an instance of this scene with that category, else
    /// to the goal's centre.
    pub fn distance_to_goal_objects(&self, episode: &Episode, feet: &Point3<f64>) -> f64 {
        let height = self.config.camera.mount_height;
        episode
            .goals
            .iter()
            .map(|g| {
                let bounds = u32::try_from(g.object_id)
                    .ok()
                    .and_then(|id| self.scene.instance(id))
                    .filter(|i| i.category == g.category)
                    .map(|i| i.bounds)
                    .unwrap_or(Aabb {
                        min: g.position,
                        max: g.position,
                    });
                bounds.body_distance(feet, height)
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// What a policy sees at each step: the camera frame, ground-truth pose
/// (Habitat's GPS + compass, and the world pose) and the target category.
#[derive(Debug, Clone, Copy)]
pub struct Observation<'a> {
    /// The rendered frame (`None` when the policy declared it needs none).
    pub frame: Option<&'a Frame>,
    /// Feet position (world, z up).
    pub position: Point3<f64>,
    /// Heading (radians, counter-clockwise from +x).
    pub yaw: f64,
    /// Camera tilt (radians, positive up).
    pub pitch: f64,
    /// GPS: position relative to the start in the start frame (x forward, y left).
    pub gps: Vector2<f64>,
    /// Compass: heading relative to the start heading.
    pub compass: f64,
    /// The target category.
    pub object_category: &'a str,
    /// Actions taken so far.
    pub step: usize,
    /// The agent (for its span and motion model).
    pub agent: &'a Agent,
    scene: &'a Scene,
}

impl Observation<'_> {
    /// Category of an instance id seen in the semantic channel (the
    /// semantic annotation that Habitat also provides).
    pub fn category_of(&self, instance: u32) -> Option<&str> {
        self.scene.instance(instance).map(|i| i.category.as_str())
    }
}

/// Plays one episode: spawn, then observe -> act until STOP, the action budget
/// or the wall-clock budget; then score.
///
/// # Wall-clock budget
/// [`RunConfig::wall_clock_s`] counts from the first observation (just
/// before the first frame is rendered) to the end of the last action:
/// rendering, the policy's [`Policy::act`] and the agent's motion. Setup is
/// not counted: spawning the agent, the goal's geodesic field and
/// [`Policy::reset`]. The budget is checked before every observation but the
/// first and right after every `act`; an action returned after the budget ran out is
/// discarded (neither executed nor counted, so a late STOP is no success)
/// and the episode ends as a timeout. A policy blocked inside `act` is not
/// interrupted: it times out when `act` returns. Time the policy reports as
/// accounted in simulated time ([`Policy::simulated_wait_s`]) is not
/// counted.
/// [`EpisodeResult::timed_s`] reports the counted time,
/// [`EpisodeResult::wall_s`] the whole call.
///
/// # Floors
/// [`EpisodeResult::start_level`], [`EpisodeResult::goal_level`],
/// [`EpisodeResult::floors_between`] and [`EpisodeResult::cross_floor`]
/// come from the height field's levels ([`crate::levels::floor_relation`]),
/// for generated and imported episodes alike.
///
/// # Errors
/// [`SimError`] when the start is not navigable, no view point lies on the
/// walkable surface or the run configuration is invalid.
///
/// # Complexity
/// O(A (W H log T + step)) for A actions with W x H frames, plus two geodesic
/// fields (goals, and start for the floor relation), O(S log S).
pub fn run_episode(
    sim: &Simulator,
    episode: &Episode,
    policy: &mut dyn Policy,
    config: &RunConfig,
) -> Result<EpisodeResult, SimError> {
    config.validate()?;
    let t0 = Instant::now();
    let mut agent = sim.spawn(episode)?;
    let field = sim.goal_field(episode)?;
    let nav = sim.nav();
    let start_d = field
        .distance(nav, &agent.position())
        .unwrap_or(f64::INFINITY);
    let shortest = episode
        .geodesic_distance
        .filter(|d| d.is_finite() && *d > 0.0)
        .unwrap_or(start_d);
    policy.reset(sim, episode);
    let needs_frames = policy.needs_frames();
    let (mut actions, mut collisions, mut path) = (0usize, 0usize, 0.0f64);
    let mut step_ms = Vec::new();
    let seed_base = config.noise_seed ^ hash_str(&episode.episode_id);
    // the budget counts from the first observation on (setup excluded)
    let clock = Instant::now();
    // One frame buffer for the whole episode, rendered into at every step.
    let mut frame = needs_frames.then(|| Frame {
        width: 0,
        height: 0,
        pose: sim
            .camera()
            .pose_at(&agent.position(), agent.yaw(), agent.pitch()),
        depth: Vec::new(),
        instance: Vec::new(),
        rgb: None,
    });
    let counted = |clock: &Instant, policy: &dyn Policy| {
        clock.elapsed().as_secs_f64() - policy.simulated_wait_s().max(0.0)
    };
    let spent = |clock: &Instant, policy: &dyn Policy| counted(clock, policy) > config.wall_clock_s;
    // How the loop ended: STOP, step limit or timeout.
    let loop_end = loop {
        // (before the first observation nothing has been counted yet)
        if actions > 0 && spent(&clock, policy) {
            break LoopEnd::Timeout;
        }
        let ts = Instant::now();
        if let Some(frame) = frame.as_mut() {
            sim.observe_frame_into(&agent, seed_base.wrapping_add(actions as u64), frame);
        }
        let obs = Observation {
            frame: frame.as_ref(),
            position: agent.position(),
            yaw: agent.yaw(),
            pitch: agent.pitch(),
            gps: agent.gps(),
            compass: agent.compass(),
            object_category: &episode.object_category,
            step: actions,
            agent: &agent,
            scene: sim.scene(),
        };
        let action = policy.act(&obs);
        if spent(&clock, policy) {
            // the action came after the budget ran out: discarded
            step_ms.push(ts.elapsed().as_secs_f64() * 1e3);
            break LoopEnd::Timeout;
        }
        actions += 1;
        let stopped = action == Action::Stop;
        if !stopped {
            let out = agent.step(nav, action);
            path += out.moved;
            collisions += usize::from(out.collided);
        }
        step_ms.push(ts.elapsed().as_secs_f64() * 1e3);
        if stopped {
            break LoopEnd::Stopped;
        }
        if actions >= config.max_actions {
            break LoopEnd::StepLimit;
        }
    };
    let stopped = loop_end == LoopEnd::Stopped;
    let timed_s = counted(&clock, policy);
    let end = agent.position();
    let dtg = field.distance(nav, &end).ok().filter(|d| d.is_finite());
    let success = stopped && dtg.is_some_and(|d| d <= config.success_distance);
    let near_object = sim.distance_to_goal_objects(episode, &end) <= config.object_distance;
    // Floors from the height field's levels (the same definition for
    // generated and imported episodes; `episode.cross_floor` is not read).
    let floors = crate::levels::floor_relation(
        nav,
        &episode.start_position,
        &episode.view_point_positions(),
    )
    .unwrap_or(crate::levels::FloorRelation {
        start_level: 0,
        goal_level: 0,
        floors_between: 0,
    });
    step_ms.sort_by(f64::total_cmp);
    Ok(EpisodeResult {
        episode_id: episode.episode_id.clone(),
        scene_id: episode.scene_id.clone(),
        object_category: episode.object_category.clone(),
        success,
        success_1m: stopped && near_object,
        spl: metrics::spl(success, shortest, path),
        soft_spl: metrics::soft_spl(dtg.unwrap_or(f64::INFINITY), start_d, shortest, path),
        start_geodesic_m: start_d,
        dtg_m: dtg,
        path_length_m: path,
        actions,
        collisions,
        start_level: floors.start_level,
        goal_level: floors.goal_level,
        floors_between: floors.floors_between,
        cross_floor: floors.cross_floor(),
        outcome: metrics::classify(match loop_end {
            LoopEnd::Stopped => Termination::Stopped {
                success,
                near_object,
            },
            LoopEnd::StepLimit => Termination::StepLimit,
            LoopEnd::Timeout => Termination::Timeout,
        }),
        wall_s: t0.elapsed().as_secs_f64(),
        timed_s,
        step_ms_p50: step_ms.get(step_ms.len() / 2).copied().unwrap_or(0.0),
    })
}

/// FNV-1a hash of a string (seeds per-episode noise).
fn hash_str(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}
