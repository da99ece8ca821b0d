//! The SOR-Nav [`Agent`] on platform-sim's ObjectNav protocol.
//!
//! [`SornavPolicy`] implements platform-sim's [`Policy`]: every step it turns
//! the rendered depth + semantic frame into an [`Observation`] for the agent,
//! asks the agent for a command and turns the command into one of Habitat's
//! discrete actions.
//!
//! * **Start**: `scan_turns` (12) TURN_LEFT actions, observing after each,
//!   so the agent has seen all around before its first decision.
//! * **Missions** become actions with platform-sim's
//!   [`WaypointFollower`]: pure pursuit along the mission's executable path
//!   on the agent's own traversability map (the forward move must stay on
//!   the agent's traversable cells), collision memory, re-planning on the
//!   agent's map every `replan_every` actions and after every collision (the
//!   map changes as the robot sees more); after `max_collisions` collisions
//!   without progress the mission is reported stuck (the agent then
//!   excludes its frontier or rejects its candidate).
//! * **Verification**: on [`AgentCommand::Verify`] the camera is turned
//!   toward the candidate (one action even when already facing it, so that
//!   the next frame is fresh), the frame is observed and the agent stepped
//!   again: STOP only when the target gate confirms.
//! * **STOP** when the agent confirms the target, or when its search is
//!   exhausted (nothing left to explore, no candidate) and one more full
//!   turn in place has not revealed anything new.
//!
//! The agent's maps are built only from these frames: the semantic channel
//! is the simulator's instance image mapped to category labels (the
//! semantic sensor Habitat also provides); nothing else of the scene is
//! read. Coordinates are the world's with `z` measured from the start
//! floor, so the agent's 2-D grid sits on the floor it starts on.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use nalgebra::Point3;
use serde::{Deserialize, Serialize};
use sornav::executor::{FailureReason, MissionId, MissionKind, MissionStatus, RobotPose};
use sornav::semantic_map::{LabelId, PinholeCamera, optical_pose};
use sornav::{
    Agent, AgentCommand, AgentConfig, AgentError, BoxedPolicy, DecisionAction, DepthObservation,
    LabelEntry, Observation, Sensor,
};
use sornav_platform_sim::follow::{FollowerConfig, MoveOutcome, WaypointFollower};
use sornav_platform_sim::render::NO_INSTANCE;
use sornav_platform_sim::{Action, Episode, InstanceKind, Policy, Scene, Simulator};

use crate::decision_log::DecisionLog;
use crate::histogram::Histogram;

/// How agent commands become discrete actions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AdapterConfig {
    /// TURN_LEFT actions at the start of an episode (12 x 30 deg = one
    /// full turn).
    pub scan_turns: usize,
    /// Simulated seconds per action, the agent's clock (0.5 s: a 0.25 m
    /// step at 0.5 m/s). The supervisor's rate limit, mission timeouts and
    /// stuck detection run on this clock.
    pub seconds_per_action: f64,
    /// Heading error (degrees) below which the agent moves forward instead
    /// of turning (15: half of the simulator's 30-degree turn).
    pub heading_tolerance_deg: f64,
    /// A path point counts as passed within this distance (m).
    pub path_point_radius_m: f64,
    /// Pure-pursuit look-ahead along the path (m).
    pub lookahead_m: f64,
    /// Re-plan the active mission's path on the agent's map every this
    /// many actions.
    pub replan_every: usize,
    /// Collisions without progress before the mission is reported blocked.
    pub max_collisions: usize,
}

impl AdapterConfig {
    /// The follower settings of this configuration (traversability
    /// samples at half the agent map's `resolution`).
    pub fn follower(&self, resolution: f64) -> FollowerConfig {
        FollowerConfig {
            heading_tolerance_deg: self.heading_tolerance_deg,
            path_point_radius_m: self.path_point_radius_m,
            lookahead_m: self.lookahead_m,
            replan_every: self.replan_every,
            max_collisions: self.max_collisions,
            sample_spacing_m: resolution / 2.0,
            ..FollowerConfig::default()
        }
    }
}

impl Default for AdapterConfig {
    fn default() -> Self {
        Self {
            scan_turns: 12,
            seconds_per_action: 0.5,
            heading_tolerance_deg: 15.0,
            path_point_radius_m: 0.2,
            lookahead_m: 0.5,
            replan_every: 8,
            max_collisions: 4,
        }
    }
}

/// The agent configuration of simulator runs: the paper's defaults, with
/// * `NAV_TO_OBJECT` waypoints 0.4-0.7 m from the object with a line of
///   sight to it, reached within 0.3 m: Habitat's success needs the agent
///   within 0.1 m of a view point, a pose within 1 m of the object from
///   which the object is visible in the camera's vertical field of view;
///   roomy waypoints (see `approach.clearance_margin_m`) up to 0.85 m
///   from the object before snug ones within 0.7 m (a plant on a round
///   table ringed by chairs: its near waypoints lie in gaps between the
///   chairs that the inflated map admits and the simulator's cylinder
///   does not pass; on 4BedroomHouse's plant episodes SR 15 -> 45 %);
/// * frontier viewpoints reached within 0.5 m (the camera does not see the
///   floor within 1.5 m of the robot);
/// * missing depth where the floor would be in range is no floor: the
///   simulated camera returns every surface within its range, so a floor
///   edge over nothing (a terrace, a mezzanine) is an edge.
pub fn sim_agent_config() -> AgentConfig {
    let mut c = AgentConfig::default();
    c.approach.min_standoff_m = 0.4;
    c.approach.standoff_m = 0.7;
    c.approach.roomy_standoff_m = 0.85;
    c.executor.nav_to_object.arrival.radius_m = 0.3;
    c.executor.explore.arrival.radius_m = 0.5;
    c.voids_from_missing_depth = true;
    c
}

/// The semantic sensor's vocabulary for one scene: every category of the
/// scene becomes a label; building structure is ignored for objects.
///
/// Label 0 is `unknown` (pixels without an instance), ids from 1 follow the
/// sorted category names, so the table depends only on the scene's set of
/// categories.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneLabels {
    entries: Vec<LabelEntry>,
    /// Label of each instance id (index = instance id).
    by_instance: Vec<LabelId>,
}

impl SceneLabels {
    /// The table of `scene`.
    pub fn of(scene: &Scene) -> Self {
        let mut categories: BTreeMap<&str, bool> = BTreeMap::new();
        for inst in scene.instances() {
            let ignored = inst.kind != InstanceKind::Object;
            let e = categories.entry(inst.category.as_str()).or_insert(ignored);
            // A category used by objects and structure alike stays an object.
            *e &= ignored;
        }
        let mut entries = vec![LabelEntry {
            id: 0,
            name: "unknown".to_owned(),
            ignored: true,
        }];
        let mut ids: BTreeMap<&str, LabelId> = BTreeMap::new();
        for (k, (name, ignored)) in categories.iter().enumerate() {
            let Ok(id) = u16::try_from(k + 1) else { break };
            if name.is_empty() || *name == "unknown" {
                continue;
            }
            ids.insert(name, LabelId(id));
            entries.push(LabelEntry {
                id,
                name: (*name).to_owned(),
                ignored: *ignored,
            });
        }
        let by_instance = scene
            .instances()
            .iter()
            .map(|i| ids.get(i.category.as_str()).copied().unwrap_or_default())
            .collect();
        Self {
            entries,
            by_instance,
        }
    }

    /// The label entries for [`AgentConfig::labels`].
    pub fn entries(&self) -> &[LabelEntry] {
        &self.entries
    }

    /// The label of a pixel's instance id (`unknown` for none).
    pub fn label(&self, instance: u32) -> LabelId {
        if instance == NO_INSTANCE {
            return LabelId(0);
        }
        self.by_instance
            .get(instance as usize)
            .copied()
            .unwrap_or_default()
    }

    /// The labels of an instance image, into `out` (replacing its
    /// contents, keeping its allocation).
    pub fn labels_into(&self, instances: &[u32], out: &mut Vec<LabelId>) {
        out.clear();
        out.extend(instances.iter().map(|&i| self.label(i)));
    }
}

/// Builds the agent for one episode (the maps start empty every episode,
/// as in Habitat).
pub trait AgentFactory: Send + Sync {
    /// A fresh agent whose label vocabulary is `labels`.
    ///
    /// # Errors
    /// The agent's construction errors.
    fn build(&self, labels: &[LabelEntry]) -> Result<Agent, AgentError>;
}

impl<T: AgentFactory + ?Sized> AgentFactory for &T {
    fn build(&self, labels: &[LabelEntry]) -> Result<Agent, AgentError> {
        (**self).build(labels)
    }
}

/// An [`AgentFactory`] from a configuration, with an optional policy
/// constructor (for example an LLM policy over a record/replay transport).
pub struct ConfigFactory {
    /// The configuration (its `labels` are replaced by the scene's).
    pub config: AgentConfig,
    /// Builds the context policy; `None` uses `config.policy`.
    #[allow(clippy::type_complexity)]
    pub policy: Option<Box<dyn Fn() -> Result<BoxedPolicy, AgentError> + Send + Sync>>,
}

impl std::fmt::Debug for ConfigFactory {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ConfigFactory")
            .field("config", &self.config)
            .field("policy", &self.policy.is_some())
            .finish()
    }
}

impl AgentFactory for ConfigFactory {
    fn build(&self, labels: &[LabelEntry]) -> Result<Agent, AgentError> {
        let mut config = self.config.clone();
        config.labels = labels.to_vec();
        match &self.policy {
            Some(make) => Agent::with_policy(config, make()?),
            None => Agent::new(config),
        }
    }
}

/// What the adapter measured and logged during one episode.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct EpisodeTrace {
    /// Decision latency (observe + step) of every action, ms, less the
    /// time spent waiting for LLM answers due in simulated time.
    pub decision_ms: Histogram,
    /// Time between consecutive decisions spent outside the agent (render
    /// + simulator bookkeeping), ms.
    pub frame_ms: Histogram,
    /// Feet positions at every observation (world, z up), starting with
    /// the spawn pose.
    pub trajectory: Vec<[f32; 3]>,
    /// Where relocations were dispatched: (action index, robot position,
    /// relocation waypoint).
    pub relocations: Vec<(usize, [f32; 2], [f32; 2])>,
    /// Where the agent verified a candidate: (action index, candidate
    /// centre).
    pub verifications: Vec<(usize, [f32; 3])>,
    /// The decision log, with runs of identical decisions merged.
    pub decisions: DecisionLog,
    /// Agent errors (observation refused, step failed), counted.
    pub errors: Vec<String>,
    /// How the agent ended the episode: `stop` (target confirmed),
    /// `exhausted`, or empty while running / for budget ends.
    pub agent_end: String,
    /// Collisions reported by the motion layer.
    pub collisions: usize,
    /// Missions reported blocked or without a path by the motion layer.
    pub blocked_missions: usize,
    /// Missions dispatched.
    pub missions: usize,
    /// The LLM policy's counters, when the agent asks a model.
    pub llm: Option<sornav::supervisor::LlmStats>,
    /// Frontiers the agent excluded after its exploration missions had
    /// reached their place three times (bounded re-dispatches).
    #[serde(default)]
    pub revisit_exclusions: usize,
}

/// SOR-Nav on platform-sim: a [`Policy`] around the [`Agent`].
pub struct SornavPolicy<F> {
    factory: F,
    config: AdapterConfig,
    agent: Option<Agent>,
    labels: Option<SceneLabels>,
    camera: Option<(PinholeCamera, f64)>,
    target: String,
    floor_z: f64,
    /// The mission being followed (the follower has its goal).
    mission: Option<MissionId>,
    follower: WaypointFollower,
    last_act_end: Option<Instant>,
    exhausted_turns: usize,
    turns: i32,
    /// Camera pitch of the current frame (rad, positive up), the tilt
    /// of one LOOK_UP / LOOK_DOWN and the platform's largest tilt (rad).
    pitch: f64,
    tilt: f64,
    max_tilt: f64,
    /// The followed mission's look-at point.
    look_at: Option<Point3<f64>>,
    /// Camera mount height (m) and half the vertical field of view (rad).
    mount: f64,
    half_vfov: f64,
    trace: EpisodeTrace,
    /// The depth and label buffers of the last observation, refilled by
    /// the next one (a frame's buffers are not allocated again).
    spare: Option<DepthObservation>,
    /// `SORNAV_DEBUG` is set: log every dispatch to stderr.
    debug: bool,
    /// `SORNAV_DEBUG_ACTIONS` is set: log every action to stderr.
    debug_actions: bool,
    /// `SORNAV_DEBUG_FRAMES` names a directory: every frame is written
    /// there as two PNGs (labels in false colours, depth in grey).
    debug_frames: Option<std::path::PathBuf>,
}

impl<F> std::fmt::Debug for SornavPolicy<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SornavPolicy")
            .field("config", &self.config)
            .field("target", &self.target)
            .finish_non_exhaustive()
    }
}

/// To [-pi, pi), 0 if non-finite (not `wrap_angle`: (-pi, pi], keeps NaN).
fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let r = (a + std::f64::consts::PI).rem_euclid(t) - std::f64::consts::PI;
    if r.is_finite() { r } else { 0.0 }
}

fn f32x3(p: &Point3<f64>) -> [f32; 3] {
    [p.x as f32, p.y as f32, p.z as f32]
}

impl<F: AgentFactory> SornavPolicy<F> {
    /// A policy that builds its agent with `factory` at every episode start.
    pub fn new(factory: F, config: AdapterConfig) -> Self {
        let follower = WaypointFollower::new(
            config.follower(0.05),
            &sornav_platform_sim::AgentConfig::default(),
        );
        Self {
            factory,
            config,
            agent: None,
            labels: None,
            camera: None,
            target: String::new(),
            floor_z: 0.0,
            mission: None,
            follower,
            last_act_end: None,
            exhausted_turns: 0,
            turns: 12,
            pitch: 0.0,
            tilt: 30f64.to_radians(),
            max_tilt: 60f64.to_radians(),
            look_at: None,
            mount: 0.88,
            half_vfov: 0.55,
            trace: EpisodeTrace::default(),
            spare: None,
            debug: std::env::var_os("SORNAV_DEBUG").is_some(),
            debug_actions: std::env::var_os("SORNAV_DEBUG_ACTIONS").is_some(),
            debug_frames: std::env::var_os("SORNAV_DEBUG_FRAMES").map(std::path::PathBuf::from),
        }
    }

    /// The agent of the current episode.
    pub fn agent(&self) -> Option<&Agent> {
        self.agent.as_ref()
    }

    /// Takes the trace of the last episode (with the LLM policy's
    /// counters, when it asks a model).
    pub fn take_trace(&mut self) -> EpisodeTrace {
        let mut trace = std::mem::take(&mut self.trace);
        trace.llm = self.agent.as_ref().and_then(Agent::llm_stats);
        trace.revisit_exclusions = self
            .agent
            .as_ref()
            .map_or(0, |a| a.stats().revisit_exclusions as usize);
        trace
    }

    fn error(&mut self, context: &str, e: &AgentError) {
        // Keep the log bounded: the first few messages, then only a count.
        if self.trace.errors.len() < 20 {
            self.trace.errors.push(format!("{context}: {e}"));
        }
    }

    fn to_local(&self, p: &Point3<f64>) -> Point3<f64> {
        Point3::new(p.x, p.y, p.z - self.floor_z)
    }

    /// The agent's observation of a simulator frame (in the buffers of the
    /// last one, see [`recycle`](Self::recycle)).
    fn observation(&mut self, obs: &sornav_platform_sim::Observation<'_>) -> Option<Observation> {
        let frame = obs.frame?;
        let (camera, mount) = self.camera.as_ref()?;
        let labels = self.labels.as_ref()?;
        let feet = self.to_local(&obs.position);
        let eye = Point3::new(feet.x, feet.y, feet.z + mount);
        let (mut depth, mut label_image) = self
            .spare
            .take()
            .map_or_else(Default::default, |d| (d.depth, d.labels));
        depth.clear();
        depth.extend_from_slice(&frame.depth);
        labels.labels_into(&frame.instance, &mut label_image);
        Some(Observation {
            pose: RobotPose::new(feet, obs.yaw),
            sensor: Sensor::Depth(DepthObservation {
                camera: *camera,
                // The simulator's pitch is positive up; the optical pose
                // takes a downward tilt.
                camera_pose: optical_pose(&eye, obs.yaw, -obs.pitch),
                depth,
                labels: label_image,
            }),
        })
    }

    /// Keeps an observed frame's buffers for the next observation.
    fn recycle(&mut self, observation: Observation) {
        if let Sensor::Depth(d) = observation.sensor {
            self.spare = Some(d);
        }
    }

    fn now(&self, step: usize) -> Duration {
        Duration::from_secs_f64(step as f64 * self.config.seconds_per_action.max(0.0))
    }

    /// Turn (the shorter way) toward a heading error; `None` when within
    /// the tolerance.
    fn turn_toward(&self, error: f64) -> Option<Action> {
        self.follower.turn_toward(error)
    }

    fn report(&mut self, id: MissionId, reason: FailureReason) {
        self.trace.blocked_missions += 1;
        if let Some(agent) = self.agent.as_mut() {
            // The agent may have moved on already (unknown mission): fine.
            let _ = agent.on_mission_outcome(id, MissionStatus::Failed(reason));
        }
        self.drop_mission();
    }

    fn drop_mission(&mut self) {
        self.mission = None;
        self.look_at = None;
        self.follower.clear_goal();
    }

    fn replan(&mut self, from: &Point3<f64>, step: usize) {
        let Some(id) = self.mission else {
            return;
        };
        let Some(agent) = self.agent.as_mut() else {
            return;
        };
        let Some(waypoint) = self.follower.waypoint() else {
            return;
        };
        match agent.plan_path(from, &waypoint) {
            Ok(Some(path)) => self.follower.replanned(step, Some(path)),
            Ok(None) => {
                // Not connected on the agent's map (any more).
                self.follower.replanned(step, None);
                self.report(id, FailureReason::PathInvalidated);
            }
            Err(e) => {
                self.follower.replanned(step, None);
                self.error("plan_path", &e);
            }
        }
    }

    /// Adopts a dispatched or continued mission.
    fn adopt(&mut self, id: MissionId, step: usize) {
        if self.mission == Some(id) {
            return;
        }
        let Some((active, mission)) = self.agent.as_ref().and_then(|a| a.active_mission()) else {
            self.drop_mission();
            return;
        };
        if active != id {
            self.drop_mission();
            return;
        }
        self.trace.missions += 1;
        let (waypoint, look_at) = (mission.waypoint, mission.look_at);
        let path = mission.path.clone().unwrap_or_default();
        self.mission = Some(id);
        // An explored frontier or a drop edge is looked down at; a
        // candidate is verified with a level camera.
        self.look_at = look_at.filter(|_| !matches!(mission.kind, MissionKind::NavToObject { .. }));
        self.follower.set_goal(waypoint, look_at, path, step);
    }

    /// One action toward the active mission's waypoint.
    fn follow(&mut self, feet: &Point3<f64>, yaw: f64, step: usize) -> Action {
        if self.follower.needs_replan(step) {
            self.replan(feet, step);
        }
        if !self.follower.has_goal() {
            // No mission: look around (observing) until the agent decides.
            return Action::TurnLeft;
        }
        let Some(agent) = self.agent.as_ref() else {
            return Action::Stop;
        };
        if let Some(tilt) = self.stair_tilt(agent, feet) {
            return tilt;
        }
        // Standing at an open stair end: turn around (the agent excludes
        // the end after a full turn that showed nothing).
        if agent.at_open_stair_end() {
            return Action::TurnLeft;
        }
        let resolution = agent.config().frontier.grid.resolution;
        let cell = |x: f64, y: f64| ((x / resolution).floor(), (y / resolution).floor());
        // The forward segment must stay on the agent's traversable map: its
        // level's grid, the approach to a stair or a stair's surface (the
        // start cell may be inside the inflation margin).
        let start_cell = cell(feet.x, feet.y);
        let traversable = |q: &Point3<f64>| cell(q.x, q.y) == start_cell || agent.is_traversable(q);
        self.follower.config_mut().sample_spacing_m = resolution / 2.0;
        self.follower.next_action(feet, yaw, &traversable)
    }

    /// LOOK_DOWN before going down a stair, LOOK_UP once off it: a stair
    /// descends more steeply (about 34 degrees) than half the camera's
    /// vertical field of view (31 degrees at 640x480, HFOV 79), so with a
    /// level camera the treads below are never seen and the stair's open
    /// end cannot advance.
    ///
    /// * One tilt step down when the goal is more than 0.3 m below the
    ///   feet and the robot is on a level within 2 m of a stair's upper
    ///   end (the flight ahead comes into view).
    /// * As far down as the platform tilts (60 degrees here) on a stair
    ///   with the goal below, and within 1 m of a stair's open lower end
    ///   with the goal at the feet' height (arrived there): one step down
    ///   shows the treads only from about 0.7 m ahead, so the treads just
    ///   below the feet stay unseen and a flight seen from both of its
    ///   ends keeps an unobserved gap the robot cannot cross.
    /// * At an arrived goal whose look-at point lies below the camera's
    ///   view: the fewest steps down that bring it into view.
    ///
    /// Level otherwise. `None`: the camera is where it should be.
    fn stair_tilt(&self, agent: &Agent, feet: &Point3<f64>) -> Option<Action> {
        let map = agent.frontier_map();
        let below = self.follower.waypoint().is_some_and(|w| w.z < feet.z - 0.3);
        let on_stair = map.level_at(feet.z).is_none();
        let near_top = map.stairs().iter().any(|s| {
            (s.upper.position.z - feet.z).abs() < 0.3
                && (s.upper.position.xy() - feet.xy()).norm() < 2.0
        });
        // At the open lower end of a stair going down (the robot arrived
        // at it): the steps further down are only seen looking down.
        let at_open_bottom = self
            .follower
            .waypoint()
            .is_some_and(|w| (w.z - feet.z).abs() <= 0.3)
            && map.stairs().iter().any(|s| {
                s.lower.level.is_none()
                    && s.upper.position.z > s.lower.position.z
                    && (s.lower.position - feet).norm() < 1.0
            });
        // Arrived at a goal whose look-at point (an explored frontier's
        // floor) lies below the camera's field of view: look down at it
        // (a stairwell's treads are only seen so).
        let look_down = self.look_at.and_then(|look| {
            let arrived = self.follower.waypoint().is_some_and(|w| {
                (w.xy() - feet.xy()).norm() < self.follower.config().path_point_radius_m
                    && (w.z - feet.z).abs() <= 0.3
            });
            let eye_above = feet.z + self.mount - look.z;
            let d = (look.xy() - feet.xy()).norm();
            (arrived && eye_above > 0.0)
                .then(|| tilt_to_see(eye_above.atan2(d), self.half_vfov, self.tilt, self.max_tilt))
                .filter(|&t| t > 0.0)
        });
        let down = if (below && on_stair) || at_open_bottom {
            self.max_tilt
        } else if below && near_top {
            self.tilt
        } else {
            0.0
        };
        self.tilt_toward(-down.max(look_down.unwrap_or(0.0)))
    }

    /// LOOK_DOWN / LOOK_UP toward camera pitch `want` (radians, positive
    /// up); `None` within half a tilt step of it.
    fn tilt_toward(&self, want: f64) -> Option<Action> {
        let half = self.tilt / 2.0;
        if self.pitch > want + half {
            Some(Action::LookDown)
        } else if self.pitch < want - half {
            Some(Action::LookUp)
        } else {
            None
        }
    }

    /// Bookkeeping of the previous action's effect (collisions).
    fn after_last_action(&mut self, feet: &Point3<f64>, step: usize) {
        match self.follower.after_action(feet) {
            MoveOutcome::NotForward | MoveOutcome::Advanced => {}
            MoveOutcome::Blocked { stuck } => {
                self.trace.collisions += 1;
                if stuck {
                    if let Some(id) = self.mission {
                        self.report(id, FailureReason::Stuck { progress_m: 0.0 });
                    }
                } else {
                    // Re-plan on the updated map.
                    self.replan(feet, step);
                }
            }
        }
    }
}

/// The smallest downward camera tilt (rad), in whole steps of `step` and
/// at most `max`, that brings a point `below` radians under the horizon
/// into a vertical field of view of half-angle `half_vfov` (less a
/// 0.05 rad margin); `max` when no such tilt reaches it, 0 when the level
/// camera sees it.
///
/// # Complexity
/// `O(1)`.
fn tilt_to_see(below: f64, half_vfov: f64, step: f64, max: f64) -> f64 {
    let needed = below - (half_vfov - 0.05);
    if !(needed > 0.0 && step > 0.0) {
        return 0.0;
    }
    ((needed / step).ceil() * step).min(max.max(0.0))
}

impl<F: AgentFactory> Policy for SornavPolicy<F> {
    fn reset(&mut self, sim: &Simulator, episode: &Episode) {
        let labels = SceneLabels::of(sim.scene());
        let camera = sim.camera().config();
        self.camera = Some((
            PinholeCamera::from_hfov(camera.width, camera.height, camera.hfov_deg.to_radians()),
            camera.mount_height,
        ));
        self.mount = camera.mount_height;
        self.half_vfov = ((camera.hfov_deg.to_radians() / 2.0).tan() * f64::from(camera.height)
            / f64::from(camera.width))
        .atan();
        self.look_at = None;
        self.trace = EpisodeTrace::default();
        self.floor_z = episode.start_position.z;
        self.mission = None;
        self.follower.reset();
        self.last_act_end = None;
        self.exhausted_turns = 0;
        let motion = &sim.config().agent;
        self.follower.set_motion(motion);
        self.turns = (360.0 / motion.turn_deg).round().max(2.0) as i32;
        self.tilt = motion.tilt_deg.to_radians();
        self.max_tilt = motion.max_tilt_deg.to_radians();
        self.pitch = 0.0;
        self.target = episode.object_category.clone();
        self.agent = match self.factory.build(labels.entries()) {
            Ok(mut agent) => match agent.set_target(&episode.object_category) {
                Ok(_) => Some(agent),
                Err(e) => {
                    self.error("set_target", &e);
                    None
                }
            },
            Err(e) => {
                self.error("build", &e);
                None
            }
        };
        self.labels = Some(labels);
    }

    fn act(&mut self, obs: &sornav_platform_sim::Observation<'_>) -> Action {
        let step = obs.step;
        if let Some(t) = self.last_act_end.take() {
            self.trace.frame_ms.add(t.elapsed().as_secs_f64() * 1e3);
        }
        self.trace.trajectory.push(f32x3(&obs.position));
        if let (Some(dir), Some(frame)) = (self.debug_frames.as_ref(), obs.frame) {
            // Debugging aid: the frames the agent saw, as images.
            for r in [
                frame.save_png(&dir.join(format!("s{step:04}-labels.png"))),
                frame.save_depth_png(&dir.join(format!("s{step:04}-depth.png")), 6.0),
            ] {
                if let Err(e) = r {
                    eprintln!("SORNAV_DEBUG_FRAMES: {e}");
                }
            }
        }
        let feet = self.to_local(&obs.position);
        self.pitch = obs.pitch;
        self.after_last_action(&feet, step);
        let action = self.decide(obs, &feet, step);
        if self.debug_actions {
            eprintln!(
                "act {step} at ({:.2},{:.2},{:.2}) yaw {:.0} pitch {:.0}: {action:?}",
                feet.x,
                feet.y,
                feet.z,
                obs.yaw.to_degrees(),
                obs.pitch.to_degrees()
            );
        }
        self.follower.record(&feet, obs.yaw, action);
        self.last_act_end = Some(Instant::now());
        action
    }

    /// The wall time the LLM policy spent waiting for answers due in
    /// simulated time.
    fn simulated_wait_s(&self) -> f64 {
        self.agent
            .as_ref()
            .and_then(Agent::llm_stats)
            .map_or(0.0, |s| s.waited_ms as f64 / 1e3)
    }
}

impl<F: AgentFactory> SornavPolicy<F> {
    fn decide(
        &mut self,
        obs: &sornav_platform_sim::Observation<'_>,
        feet: &Point3<f64>,
        step: usize,
    ) -> Action {
        if self.agent.is_none() {
            // The agent could not be built: nothing sensible to do.
            return Action::Stop;
        }
        let t0 = Instant::now();
        if let Some(o) = self.observation(obs) {
            if let Some(agent) = self.agent.as_mut()
                && let Err(e) = agent.observe(&o)
            {
                self.error("observe", &e);
            }
            self.recycle(o);
        }
        if step < self.config.scan_turns {
            self.trace.decision_ms.add(t0.elapsed().as_secs_f64() * 1e3);
            return Action::TurnLeft;
        }
        let now = self.now(step);
        let waited_before_s = self.simulated_wait_s();
        let command = self.agent.as_mut().map(|a| a.step(now));
        if let Some(agent) = self.agent.as_mut() {
            self.trace.decisions.extend(agent.take_decisions());
        }
        // Waiting for an LLM answer due in simulated time is not decision
        // time (it is accounted in simulated time).
        let waited_ms = (self.simulated_wait_s() - waited_before_s) * 1e3;
        self.trace
            .decision_ms
            .add((t0.elapsed().as_secs_f64() * 1e3 - waited_ms).max(0.0));
        let command = match command {
            Some(Ok(c)) => c,
            Some(Err(e)) => {
                self.error("step", &e);
                return Action::TurnLeft;
            }
            None => return Action::Stop,
        };
        let yaw = obs.yaw;
        match command {
            AgentCommand::Dispatch { id, mission } => {
                self.exhausted_turns = 0;
                // A relocation decided by the supervisor; retreats (walking
                // back, looking at an unreached frontier or down through a
                // drop edge) are relocate missions outside any cluster and
                // are not counted.
                let relocation = self
                    .agent
                    .as_ref()
                    .and_then(Agent::last_decision)
                    .is_some_and(|d| d.action == DecisionAction::Relocate);
                if matches!(mission.kind, MissionKind::Relocate { .. }) && relocation {
                    self.trace.relocations.push((
                        step,
                        [feet.x as f32, feet.y as f32],
                        [mission.waypoint.x as f32, mission.waypoint.y as f32],
                    ));
                }
                // A re-dispatch with a new waypoint replaces the old one.
                if self.debug {
                    let last = self.agent.as_ref().map(Agent::last_outcome);
                    // The stairs mapped so far: lower -> upper end height
                    // ("?" for a partly seen stair).
                    let stairs: Vec<String> = self.agent.as_ref().map_or(Vec::new(), |a| {
                        a.frontier_map()
                            .stairs()
                            .iter()
                            .map(|s| {
                                let open = if s.is_complete() { "" } else { "?" };
                                format!(
                                    "{:.2}->{:.2}{open}",
                                    s.lower.position.z, s.upper.position.z
                                )
                            })
                            .collect()
                    });
                    eprintln!(
                        "step {step} at ({:.2},{:.2},{:.2}) yaw {:.0} dispatch {id:?} {} wp ({:.2},{:.2},{:.2}) path {} stairs {stairs:?} last {:?}",
                        feet.x,
                        feet.y,
                        feet.z,
                        obs.yaw.to_degrees(),
                        mission.kind.name(),
                        mission.waypoint.x,
                        mission.waypoint.y,
                        mission.waypoint.z,
                        mission.path.as_ref().map_or(0, Vec::len),
                        last
                    );
                    if let Some(agent) = self.agent.as_ref() {
                        // The target category's objects and the gate's
                        // candidate tracks (support s_t / misses m_t).
                        let snapshot = agent.snapshot();
                        let category = snapshot.target.as_ref().map(|t| &t.category);
                        let objects: Vec<String> = snapshot
                            .objects
                            .iter()
                            .filter(|o| category.is_some() && o.label.as_ref() == category)
                            .map(|o| {
                                format!(
                                    "{} voxels {} obs {} at ({:.2},{:.2},{:.2})",
                                    o.id,
                                    o.support,
                                    o.observations,
                                    o.centre.x,
                                    o.centre.y,
                                    o.centre.z
                                )
                            })
                            .collect();
                        let tracks: Vec<String> = snapshot
                            .candidates
                            .iter()
                            .map(|t| {
                                format!(
                                    "{} s {} m {}",
                                    t.object.0, t.evidence.support, t.evidence.misses
                                )
                            })
                            .collect();
                        eprintln!("  targets {objects:?} tracks {tracks:?}");
                    }
                }
                self.drop_mission();
                self.adopt(id, step);
                self.follow(feet, yaw, step)
            }
            AgentCommand::Continue { mission: Some(id) } => {
                self.adopt(id, step);
                self.follow(feet, yaw, step)
            }
            AgentCommand::Continue { mission: None } => {
                self.drop_mission();
                // Looking around between floors (on a stair or a landing the
                // map does not place on a level): with the camera tilted
                // down, the next flight's treads come into view (a level
                // camera does not see a stair going down).
                let between = self
                    .agent
                    .as_ref()
                    .is_some_and(|a| a.current_level().is_none());
                let want = if between { -self.tilt } else { 0.0 };
                self.tilt_toward(want).unwrap_or(Action::TurnLeft)
            }
            AgentCommand::Verify { look_at, .. } => {
                self.drop_mission();
                self.trace.verifications.push((step, f32x3(&look_at)));
                // Face the candidate; when already facing it, turn toward
                // its side (it stays within half the 79-degree field of
                // view) so that the next frame is a fresh observation.
                let e = wrap((look_at.y - feet.y).atan2(look_at.x - feet.x) - yaw);
                self.turn_toward(e).unwrap_or(if e >= 0.0 {
                    Action::TurnLeft
                } else {
                    Action::TurnRight
                })
            }
            AgentCommand::Stop { .. } => {
                self.trace.agent_end = "stop".to_owned();
                Action::Stop
            }
            AgentCommand::Exhausted | AgentCommand::FloorExhausted { .. } => {
                // Look all around once more before giving up: the camera
                // may not have seen the floor next to the robot.
                if self.exhausted_turns < self.turns as usize {
                    self.exhausted_turns += 1;
                    Action::TurnLeft
                } else {
                    self.trace.agent_end = "exhausted".to_owned();
                    Action::Stop
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::tilt_to_see;
    use proptest::prelude::*;

    /// Reference: try 0, 1, 2, ... steps (clamped to `max`, as the
    /// simulator clamps the pitch) and return the first that shows the
    /// point, or the largest tilt.
    fn brute_force(below: f64, half_vfov: f64, step: f64, max: f64) -> f64 {
        let mut k = 0.0;
        loop {
            let t = (k * step).min(max.max(0.0));
            if below <= t + half_vfov - 0.05 || t >= max.max(0.0) {
                return t;
            }
            k += 1.0;
        }
    }

    #[test]
    fn treads_below_the_feet_need_the_largest_tilt() {
        let (half, step, max) = (0.55, 30f64.to_radians(), 60f64.to_radians());
        // A tread 0.3 m ahead and 0.3 m below the feet, camera at 0.88 m.
        let below = (0.88f64 + 0.3).atan2(0.3);
        assert!((tilt_to_see(below, half, step, max) - max).abs() < 1e-12);
        // The floor 2 m ahead: the level camera sees it.
        assert_eq!(tilt_to_see(0.88f64.atan2(2.0), half, step, max), 0.0);
        // The floor 1 m ahead: one step.
        assert!((tilt_to_see(0.88f64.atan2(1.0), half, step, max) - step).abs() < 1e-12);
    }

    proptest! {
        #[test]
        fn matches_the_step_by_step_search(
            below in -1.6f64..1.6,
            half in 0.1f64..1.2,
            step_deg in 5.0f64..45.0,
            max_deg in 0.0f64..90.0,
        ) {
            let (step, max) = (step_deg.to_radians(), max_deg.to_radians());
            let t = tilt_to_see(below, half, step, max);
            prop_assert!((0.0..=max + 1e-12).contains(&t));
            prop_assert!((t - brute_force(below, half, step, max)).abs() < 1e-9);
            // The tilt shows the point unless the platform cannot tilt that far.
            prop_assert!(below <= t + half - 0.05 + 1e-9 || (t - max).abs() < 1e-12);
        }
    }
}
