//! The SOR-Nav agent: one instance of each component and the decision loop.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};
use sornav_cluster_graph::{ClusterGraph, ObjectSummary};
use sornav_executor::{
    AlwaysValid, Clock, ClusterId as ExecClusterId, Executor, ExecutorEvent, FailureReason,
    FrontierId as ExecFrontierId, Mission, MissionId, MissionKind, MissionOutcome, MissionStatus,
    MotionError, MotionStack, ObjectId as ExecObjectId, RobotPose, Submission,
};
use sornav_frontier_graph::{FrontierGraph, FrontierId, LevelId, Location, MultiLevelMap, NodeId};
use sornav_semantic_map::{DepthFrame, LabelId, SemanticMap};
use sornav_supervisor::{
    ActiveMissionKind as SupKind, Candidate, CandidateObject, ClusterCandidate, CommonsensePolicy,
    ContextObject, ContextPolicy, MissionState, NeverRelocate, RegionContext, StepInput,
    Supervisor, SupervisorCommand, normalize_label,
};
use sornav_target_gate::{CandidateReport, GateCommand, NeverVisible, ObjectId, TargetGate};
use sornav_tsp::HorizonPlan;

use crate::approach::{ApproachTarget, ViewDemand, approach_waypoint};
use crate::back_off::BackOff;
use crate::commitment;
use crate::config::{AgentConfig, PolicyConfig};
use crate::drop_edges::{DROP_LOOK_RADIUS_M, DropEdges};
use crate::error::AgentError;
use crate::observation::{Observation, ObservationReport, Sensor};
use crate::ordering::{self, OrderingInput, Route};
use crate::path_cost::MapPathCost;
use crate::revisit::Visits;
use crate::snapshot::{
    AgentSnapshot, AgentStats, Decision, DecisionAction, DecisionStep, ObjectRecord,
    OccupancyRaster, RelocationRecord,
};
use crate::target::{Target, Vocabulary};
use crate::view::{FLOOR_TOLERANCE_M, ObjectView, Sight, Viewer};
use sornav_semantic_map::VoxelKey;

/// A context policy the agent can own.
pub type BoxedPolicy = Box<dyn ContextPolicy + Send>;

/// What the platform should do after [`Agent::step`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum AgentCommand {
    /// Start (or restart with a new waypoint / path) this mission; it
    /// replaces whatever the platform was doing.
    Dispatch {
        /// Mission id, for [`Agent::on_mission_outcome`].
        id: MissionId,
        /// The mission (kind, waypoint, executable path on the agent's map,
        /// look-at point for `NAV_TO_OBJECT`).
        mission: Mission,
    },
    /// Keep executing the active mission (`None`: hold position).
    Continue {
        /// The active mission.
        mission: Option<MissionId>,
    },
    /// Turn toward `look_at` and send a fresh observation: the robot is at
    /// a target candidate (the gate confirms or rejects it), or, while
    /// searching, a candidate seen fewer than `N_obs` times is within
    /// 4 m and out of the latest frame (a *second look*, at most six turns
    /// per candidate and support value; the active mission, if any, is
    /// continued afterwards).
    Verify {
        /// The candidate (semantic-map cluster id).
        object: ObjectId,
        /// Its centre.
        look_at: Point3<f64>,
    },
    /// The target is confirmed: STOP (end the episode / report success).
    Stop {
        /// The confirmed object.
        object: ObjectId,
        /// Its centre.
        centre: Point3<f64>,
    },
    /// No reachable frontier, no active mission and no accepted candidate
    /// at this step: the search is exhausted *for now*. Not terminal: later
    /// observations can open a frontier or bring a candidate to N_obs, and
    /// the next step then dispatches again (the simulator adapter turns in
    /// place for a full turn before giving up; the robot bridge holds and
    /// keeps stepping).
    Exhausted,
    /// Exhausted on this floor, and stairs seen from it lead to a floor
    /// the robot has not explored, but the robot does not climb
    /// (`frontier.levels.allow_stairs = false`): "not found on this floor;
    /// stairs at these points lead to an unexplored floor". Like
    /// [`Exhausted`](Self::Exhausted), per step, not terminal.
    FloorExhausted {
        /// Where each such stair starts on the robot's floor (its end on
        /// this floor), nearest first.
        stairs: Vec<Point3<f64>>,
    },
}

/// The executor's clock: the reading passed to [`Agent::step`].
#[derive(Debug, Clone, Copy, Default)]
struct StepClock(Duration);

impl Clock for StepClock {
    fn now(&self) -> Duration {
        self.0
    }
}

/// The executor's motion stack: missions leave the agent through
/// [`AgentCommand::Dispatch`], so dispatching only accepts them.
#[derive(Debug, Clone, Copy, Default)]
struct Outbox;

impl MotionStack for Outbox {
    fn dispatch(&mut self, _mission: &Mission) -> Result<(), MotionError> {
        Ok(())
    }
    fn cancel(&mut self) {}
}

/// What the stop-in-view check makes of a confirmed target.
enum StopView {
    /// Not at a view point: this command moves the robot to one.
    Move(AgentCommand),
    /// At a clear view point: stop.
    InView,
    /// At a view point that only glimpses the object, with no clear view
    /// point reachable or the moves used up: stop.
    Glimpse,
    /// The check is turned off: stop.
    Off,
    /// Stop anyway, for this reason.
    GaveUp(&'static str),
}

/// The current target and its gate.
#[derive(Debug)]
struct TargetState {
    target: Target,
    gate: TargetGate<String>,
    /// Second looks at unconfirmed candidates: per candidate, the support
    /// `s_t` at the last look and the looks spent at that support.
    looks: BTreeMap<u64, (u32, u32)>,
}

/// Horizontal distance (m) within which an unconfirmed candidate (seen,
/// but fewer than `N_obs` times) gets a second look: within the depth
/// range, where a detection can still add support.
const LOOK_RANGE_M: f64 = 4.0;

/// Vertical distance (m) from the robot's feet within which an unconfirmed
/// candidate gets a second look (on the robot's floor, not one above).
const LOOK_HEIGHT_M: f64 = 2.0;

/// Turns toward one unconfirmed candidate (at one support value) before
/// the agent gives up looking at it: half a turn, enough to face anything
/// around the robot.
const LOOK_BUDGET: u32 = 6;

/// Arrivals at the same open stair end before it is excluded like any
/// reached frontier.
const STAIR_END_ARRIVALS: u32 = 3;

/// Exploration missions toward one frontier that ended neither reached
/// nor failed (short of a stair end, or pre-empted for another goal) after
/// which the frontier is excluded: normally the map changes and the
/// frontier gets a new id (a stair grows, a frontier shrinks); one the
/// robot keeps stopping short of or switching away from is thrash.
const UNFINISHED_MISSIONS_LIMIT: u32 = 16;

/// A robot off a known floor with nothing reachable retreats to the last
/// pose with a reachable frontier when it is farther than this (m).
const RETREAT_MIN_M: f64 = 0.3;

/// Decisions spent looking around off a known floor with nothing reachable
/// (two full turns at 30 degrees) before the robot walks back along its
/// trail to the last floor it stood on.
const LOOK_AROUND_LIMIT: u32 = 24;

/// Walks back over a stair the robot crossed (see `Crossing`) per episode,
/// attempts that end short of the floor (a collision at the stair's head)
/// included: a pair of floors whose frontiers are each unreachable from
/// the other cannot make the robot shuttle for ever.
const CROSSING_BACK_LIMIT: u32 = 3;

/// Spacing (m) of the trail's points and their largest number.
const TRAIL_SPACING_M: f64 = 0.1;
const TRAIL_MAX: usize = 10_000;

/// How near (m, horizontally; vertically within a step) the robot must be
/// to a stair end to count as standing at it.
const STAIR_END_REACH: f64 = 0.4;

/// Arrivals of exploration missions at one place (within
/// [`REVISIT_RADIUS_M`]) after which the frontiers whose viewpoints lie
/// there are excluded. A frontier that standing at its viewpoint does not
/// observe away changes a little with every frame and comes back under a
/// new id, so the per-id arrival count never reaches its limit and the
/// robot is sent to the same spot again and again (a thrash); counting by
/// place bounds the re-dispatches of the same goal.
const REVISIT_LIMIT: u32 = 3;

/// Radius (m) of a place for [`REVISIT_LIMIT`], horizontally and
/// vertically: an arrival radius and the drift of a re-extracted
/// frontier's viewpoint.
const REVISIT_RADIUS_M: f64 = 0.4;

/// A move to look at something: the path to the place to look from, and
/// the point to look at (the viewpoint of an unreached frontier, the floor
/// at a drop edge).
struct LookMove {
    path: Vec<Point3<f64>>,
    at: Point3<f64>,
}

/// Most "look at an unreached frontier" moves per target before the floor
/// is declared exhausted (see `Agent::unreached_look`).
const UNREACHED_LOOK_LIMIT: u32 = 3;

/// A look again at an object of the target's category (see
/// `Agent::recheck_look`): the object, its centre (to face) and the path to
/// its view point.
struct Recheck {
    object: u64,
    centre: Point3<f64>,
    path: Vec<Point3<f64>>,
}

/// Most objects of the target's category looked at again per target
/// before the floor is declared exhausted (see `Agent::recheck_look`).
const RECHECK_LIMIT: usize = 3;

/// Radius (m) around an unreached frontier's viewpoint within which a
/// traversable place to look at it from is sought; a frontier within this
/// distance of one already looked at is not looked at again.
const UNREACHED_LOOK_RADIUS_M: f64 = 1.5;

/// Most looks down into drop edges per target before the floor is
/// declared exhausted (see `Agent::drop_look`).
const DROP_LOOK_LIMIT: u32 = 4;

/// Most looks down into deep drop edges near the robot per target while it
/// explores (see `Agent::drop_look`).
const NEAR_LOOK_LIMIT: u32 = 3;

/// A drop edge near the robot is looked into while exploring only when a
/// return this far (m) under the floor was seen through it: a stairwell
/// going down a storey, not ground outside a window or the floor beside a
/// step the robot stands on.
const DEEP_DROP_M: f64 = 1.0;

/// Longest time (s) the robot stands at a drop edge waiting for a view
/// down into it (turning to it and tilting its camera take a few steps).
const DROP_LOOK_TIME: Duration = Duration::from_secs(4);

/// A look down through a drop edge (see `Agent::drop_look`).
#[derive(Debug, Clone, Copy)]
struct DropLook {
    /// Where the floor ends before the drop edge: the point looked at.
    edge: Point3<f64>,
    /// Where the robot looks from.
    place: Point3<f64>,
    /// The mission taking the robot there (none before its dispatch).
    mission: Option<MissionId>,
    /// When the robot first stood at the place.
    since: Option<Duration>,
}

/// Unseen drop edges within this distance (m) of the robot are looked
/// into before it explores on: a stair going down from where the robot
/// stands (a start at a stair's head) is otherwise walked onto unmapped.
const DROP_NEAR_M: f64 = 2.0;

/// How far (m) back from where the floor ends before a drop edge, toward
/// where the sensor stood when it saw the edge, the robot stands to look
/// down through it.
const DROP_LOOK_STANDOFF_M: f64 = 0.4;

/// Arrival radius (m) of a look's retreat mission.
const DROP_LOOK_ARRIVAL_M: f64 = 0.3;

/// Arrival radius (m) of a back-off (see [`BackOff`]): near the end of the
/// way back, not anywhere within a relocation's radius of it.
const BACK_OFF_ARRIVAL_M: f64 = 0.2;

/// How far (m) under a drop edge the robot is told to look: deep enough
/// that a platform with a tiltable camera looks down at it.
const DROP_LOOK_BELOW_M: f64 = 1.5;

/// How long the robot stands at a reached frontier before it is excluded
/// (two control steps at 2 Hz: time to look at it).
const LOOK_TIME: Duration = Duration::from_secs(1);

/// How long the robot stands at an open stair end that shows nothing new
/// before it is excluded: a full turn of the simulator's platform (12
/// turns of 30 degrees at 2 Hz). The next flight of a switchback stair
/// starts behind or beside its landing, away from the way the robot came
/// up, so a platform turns around there.
const STAIR_LOOK_TIME: Duration = Duration::from_secs(6);

/// The SOR-Nav agent.
///
/// It owns the semantic map, the frontier map (occupancy, frontiers, G_F),
/// the cluster graph of the last step, the receding-horizon route, the
/// target gate, the supervisor and the executor, and runs the loop of
/// GUIDE.md section 2: [`observe`](Self::observe) every sensor frame,
/// [`step`](Self::step) at the control rate, and report what the platform
/// learns about missions with [`on_mission_outcome`](Self::on_mission_outcome)
/// (arrival is also detected from the pose).
///
/// Maps are built only from observations; targets can change without
/// resetting them ([`set_target`](Self::set_target)).
pub struct Agent {
    config: AgentConfig,
    vocabulary: Vocabulary,
    /// Normalised category of each label id (`None`: structure / unnamed).
    categories: BTreeMap<LabelId, Option<String>>,
    semantic: SemanticMap,
    frontiers: MultiLevelMap,
    supervisor: Supervisor<BoxedPolicy, Duration>,
    executor: Executor<Outbox, StepClock>,
    target: Option<TargetState>,
    pose: Option<RobotPose>,
    last_step: Option<Duration>,
    plan: Option<HorizonPlan<FrontierId>>,
    route: Option<Route>,
    clusters: Option<ClusterGraph<FrontierId>>,
    excluded: BTreeSet<FrontierId>,
    /// Arrivals at each frontier and the time of the first.
    arrivals: BTreeMap<FrontierId, (u32, Duration)>,
    /// Exploration missions that ended short of their frontier or
    /// pre-empted, by frontier (see [`UNFINISHED_MISSIONS_LIMIT`]).
    unfinished: BTreeMap<FrontierId, u32>,
    /// Places where exploration missions arrived (see [`REVISIT_LIMIT`]).
    visits: Visits,
    /// The last pose at which a frontier was reachable.
    last_placed: Option<Point3<f64>>,
    /// Recent positions and stuck places (see [`BackOff`]).
    back_off: BackOff,
    /// The excluded stair ends were retried once (see `retry_stairs`).
    stairs_retried: bool,
    /// The robot's positions since it last stood on a known floor (the
    /// first is on that floor), every `TRAIL_SPACING_M`: the way back
    /// from a stair or landing the map does not place.
    trail: Vec<Point3<f64>>,
    /// Consecutive decisions spent looking around off a known floor.
    looking_around: u32,
    /// Viewpoints of unreached frontiers the robot went to look at (see
    /// `unreached_look`).
    looked_at: Vec<Point3<f64>>,
    /// Attempts of the exhaustion check so far (see `unreached_look`).
    unreached_looks: u32,
    /// Objects of the target's category the exhaustion check went back to
    /// look at (see `recheck_look`), and whether any is left.
    rechecked: Vec<u64>,
    recheck_done: bool,
    /// Where the robot saw through its floor (see [`DropEdges`]).
    drop_edges: DropEdges,
    /// Looks down into drop edges before exhaustion so far (see
    /// `drop_look`).
    drop_looks: u32,
    /// Looks down into deep drop edges near the robot so far.
    near_looks: u32,
    /// The look down through a drop edge under way.
    drop_look: Option<DropLook>,
    /// The robot walked back along its trail since it last stood on a
    /// known floor (a second time it is exhausted instead).
    walked_back: bool,
    /// The floor the robot last stood on.
    last_level: Option<LevelId>,
    /// The last stair walked between two known floors.
    crossing: Option<Crossing>,
    /// Walks back over a crossing so far (see [`CROSSING_BACK_LIMIT`]).
    crossings_back: u32,
    relocation: Option<RelocationRecord>,
    /// How the sensor sees (from the last depth or cloud frame).
    viewer: Option<Viewer>,
    /// View-point approaches made for the confirmed target (stop in view).
    stop_moves: u32,
    last_outcome: Option<MissionOutcome>,
    decisions: Vec<Decision>,
    last_decision: Option<Decision>,
    stats: AgentStats,
}

impl std::fmt::Debug for Agent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Agent")
            .field("target", &self.target.as_ref().map(|t| &t.target))
            .field("pose", &self.pose)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

/// What the planning phase of [`Agent::step`] produced.
struct Planning {
    objects: Vec<ObjectSummary>,
    category: String,
    levels: BTreeMap<LevelId, f64>,
    clusters: ClusterGraph<FrontierId>,
    route: Option<Route>,
}

/// Where a relocation goes: the cluster's frontiers, the frontier whose
/// viewpoint is the waypoint, the waypoint and the robot's path to it.
type RelocationTarget = (Vec<FrontierId>, FrontierId, Point3<f64>, Vec<Point3<f64>>);

/// The supervisor's command with the missions it would start.
struct Decided {
    command: SupervisorCommand,
    explore: Option<Mission>,
    relocation: Option<RelocationTarget>,
}

fn build_policy(config: &PolicyConfig) -> Result<BoxedPolicy, AgentError> {
    Ok(match config {
        PolicyConfig::Commonsense(c) => Box::new(CommonsensePolicy::embedded(c.clone())?),
        PolicyConfig::NeverRelocate => Box::new(NeverRelocate),
        #[cfg(feature = "llm")]
        PolicyConfig::Llm(c) => Box::new(sornav_supervisor::LlmPolicy::http(c.clone())?),
        // Rejected by `AgentConfig::validate` in builds without `llm`.
        #[cfg(not(feature = "llm"))]
        PolicyConfig::Llm(_) => return Err(crate::config::llm_disabled().into()),
    })
}

fn supervisor_kind(kind: &MissionKind) -> SupKind {
    match kind {
        MissionKind::Explore { .. } => SupKind::Explore,
        MissionKind::Relocate { .. } => SupKind::Relocate,
        MissionKind::NavToObject { .. } => SupKind::NavToObject,
    }
}

/// G_F's executable 3-D path from the robot to frontier `id`, if any.
fn robot_path(graph: &FrontierGraph, id: FrontierId) -> Option<Vec<Point3<f64>>> {
    graph
        .edge(NodeId::Robot, NodeId::Frontier(id))
        .and_then(|e| e.path_from(NodeId::Robot))
        .filter(|p| !p.is_empty())
}

/// The explore mission toward frontier `id` with G_F's executable path
/// (over stairs when the frontier is on another level).
fn explore_mission(graph: &FrontierGraph, id: FrontierId) -> Option<Mission> {
    let node = graph.frontier(id)?;
    let mission = Mission::new(
        MissionKind::Explore {
            frontier: ExecFrontierId(id.0),
        },
        node.viewpoint3(),
    )
    // The frontier's floor: a platform that can tilt its camera looks at
    // it on arrival (the near floor and a stairwell's treads lie below a
    // level camera's view).
    .with_look_at(Point3::new(node.centroid.x, node.centroid.y, node.z));
    Some(match robot_path(graph, id) {
        Some(p) => mission.with_path(p),
        None => mission,
    })
}

/// A mission to `back` that is no relocation of Algorithm 1 (a retreat, a
/// look, a back-off): a relocation to no cluster.
/// A stair the robot walked from one known floor to another: the trail
/// from the floor it left to the first pose the new floor placed. The map
/// may never close such a stair (its top out of sight, a landing the
/// extraction does not attach), and then the floor left behind is
/// unreachable in G_F although the robot has just walked from it: the
/// crossing is the way back (see `Agent::cross_back`).
#[derive(Debug, Clone)]
struct Crossing {
    /// The floor the robot left.
    from: LevelId,
    /// The floor it reached.
    to: LevelId,
    /// Positions from `from` to `to`.
    path: Vec<Point3<f64>>,
}

fn retreat_mission(back: Point3<f64>) -> Mission {
    Mission::new(
        MissionKind::Relocate {
            cluster: ExecClusterId(u64::MAX),
        },
        back,
    )
}

/// Floor returns on a `resolution` lattice covering the disk of `radius`
/// around the robot: the floor the robot stands on is free (the occupancy
/// grid marks floor returns free and carves the rays to them).
fn footprint_points(pose: &RobotPose, radius: f64, resolution: f64, points: &mut Vec<Point3<f64>>) {
    if !(radius > 0.0 && resolution > 0.0) {
        return;
    }
    let n = (radius / resolution).floor() as i32;
    let p = pose.position;
    for i in -n..=n {
        for j in -n..=n {
            let (dx, dy) = (f64::from(i) * resolution, f64::from(j) * resolution);
            if dx.hypot(dy) <= radius {
                points.push(Point3::new(p.x + dx, p.y + dy, p.z));
            }
        }
    }
}

/// The floor of `level` relative to the robot's at height `z`: how many
/// known floors lie between them (+1: the next floor up).
fn relative_floor(levels: &BTreeMap<LevelId, f64>, level: LevelId, z: f64) -> i32 {
    let Some(&h) = levels.get(&level) else {
        return 0;
    };
    // Floors at or below a height (a robot half-way up a stair is on the
    // floor it left).
    let rank = |at: f64| {
        let n = levels.values().filter(|&&f| f <= at + 0.5).count();
        i32::try_from(n).unwrap_or(i32::MAX)
    };
    rank(h) - rank(z)
}

/// S_r and the top-K candidate clusters (Algorithm 1's inputs); each
/// candidate carries its floor relative to the robot's.
fn region_context(
    cg: &ClusterGraph<FrontierId>,
    graph: &FrontierGraph,
    objects: &[ObjectSummary],
    excluded: &BTreeSet<FrontierId>,
    floors: &dyn Fn(LevelId) -> i32,
    unexplored_floors: &[UnexploredFloor],
) -> RegionContext {
    let local_context = cg
        .robot_context(objects)
        .objects
        .into_iter()
        .map(|o| ContextObject::new(o.label, o.support as f64))
        .collect();
    let clusters = cg
        .top_k()
        .iter()
        .filter_map(|&k| {
            let cluster = cg.cluster(k)?;
            let reloc = cluster.relocation.as_ref()?;
            if excluded.contains(&reloc.waypoint) {
                return None;
            }
            let node = graph.frontier(reloc.waypoint)?;
            let context = cg.cluster_context(k, objects).ok()?;
            Some(ClusterCandidate {
                candidate: Candidate {
                    cluster_id: k.0 as u64,
                    distance_m: reloc.cost,
                    context: context
                        .objects
                        .into_iter()
                        .map(|o| CandidateObject::new(o.label, o.support as f64, o.distance))
                        .collect(),
                    floor: floors(node.level),
                },
                u_geo: cluster.utility,
                waypoint: node.viewpoint3(),
            })
        })
        .chain(
            unexplored_floors
                .iter()
                .enumerate()
                .map(|(i, f)| ClusterCandidate {
                    candidate: Candidate {
                        cluster_id: FLOOR_CANDIDATE_BASE + i as u64,
                        distance_m: f.cost,
                        context: Vec::new(),
                        floor: f.floor,
                    },
                    // Always among the top K: a floor is not ranked against
                    // regions by geometry.
                    u_geo: f64::MAX,
                    waypoint: f.waypoint,
                }),
        )
        .collect();
    RegionContext {
        local_context,
        clusters,
    }
}

/// Supervisor candidate ids at and above this are unexplored floors (the
/// index into the step's [`UnexploredFloor`] list), below it clusters.
const FLOOR_CANDIDATE_BASE: u64 = 1 << 40;

/// "An unexplored floor reached by these stairs": a reachable stair
/// frontier leading off the robot's floor.
#[derive(Debug, Clone, Copy)]
struct UnexploredFloor {
    frontier: FrontierId,
    /// +1 up, -1 down.
    floor: i32,
    cost: f64,
    waypoint: Point3<f64>,
}

/// The reachable, non-excluded stair frontiers of `graph` that leave the
/// robot's floor (at least half a storey's step away in height).
fn unexplored_floors(
    graph: &FrontierGraph,
    excluded: &BTreeSet<FrontierId>,
    is_stair: &dyn Fn(FrontierId) -> bool,
    robot_z: f64,
) -> Vec<UnexploredFloor> {
    graph
        .nodes()
        .filter(|n| is_stair(n.id) && !excluded.contains(&n.id))
        .filter_map(|n| {
            let dz = n.z - robot_z;
            if dz.abs() < 0.3 {
                return None;
            }
            let cost = graph.cost(NodeId::Robot, NodeId::Frontier(n.id))?;
            Some(UnexploredFloor {
                frontier: n.id,
                floor: if dz > 0.0 { 1 } else { -1 },
                cost,
                waypoint: n.viewpoint3(),
            })
        })
        .collect()
}

impl Agent {
    /// An agent with the policy named by `config.policy`.
    ///
    /// # Errors
    /// [`AgentError::Config`] for an invalid configuration, and the
    /// components' errors when constructing them.
    pub fn new(config: AgentConfig) -> Result<Self, AgentError> {
        let policy = build_policy(&config.policy)?;
        Self::with_policy(config, policy)
    }

    /// An agent with a caller-supplied context policy (for example an LLM
    /// policy over a record/replay transport); `config.policy` is then only
    /// recorded.
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn with_policy(config: AgentConfig, policy: BoxedPolicy) -> Result<Self, AgentError> {
        config.validate()?;
        let labels = config.label_set()?;
        let categories = labels
            .iter()
            .map(|(id, name)| {
                let category = (!labels.is_ignored(id))
                    .then(|| normalize_label(name))
                    .flatten();
                (id, category)
            })
            .collect();
        let vocabulary = Vocabulary::new(
            labels
                .iter()
                .filter(|(id, _)| !labels.is_ignored(*id))
                .map(|(_, name)| name),
        );
        let semantic = SemanticMap::new(config.semantic_map, labels)?;
        let frontiers = MultiLevelMap::new(config.frontier.clone())?;
        let supervisor = Supervisor::new(policy, config.supervisor.clone())?;
        let executor = Executor::new(config.executor, Outbox, StepClock::default())?;
        Ok(Self {
            config,
            vocabulary,
            categories,
            semantic,
            frontiers,
            supervisor,
            executor,
            target: None,
            pose: None,
            last_step: None,
            plan: None,
            route: None,
            clusters: None,
            excluded: BTreeSet::new(),
            arrivals: BTreeMap::new(),
            unfinished: BTreeMap::new(),
            visits: Visits::new(REVISIT_LIMIT, REVISIT_RADIUS_M),
            last_placed: None,
            back_off: BackOff::default(),
            stairs_retried: false,
            viewer: None,
            stop_moves: 0,
            trail: Vec::new(),
            looking_around: 0,
            looked_at: Vec::new(),
            unreached_looks: 0,
            rechecked: Vec::new(),
            recheck_done: false,
            drop_edges: DropEdges::default(),
            drop_looks: 0,
            near_looks: 0,
            drop_look: None,
            walked_back: false,
            last_level: None,
            crossing: None,
            crossings_back: 0,
            relocation: None,
            last_outcome: None,
            decisions: Vec::new(),
            last_decision: None,
            stats: AgentStats::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &AgentConfig {
        &self.config
    }

    /// The categories targets are resolved against.
    pub fn vocabulary(&self) -> &Vocabulary {
        &self.vocabulary
    }

    /// The semantic map.
    pub fn semantic_map(&self) -> &SemanticMap {
        &self.semantic
    }

    /// The frontier map (levels, stairs, and per level occupancy and
    /// frontiers; G_F across levels).
    pub fn frontier_map(&self) -> &MultiLevelMap {
        &self.frontiers
    }

    /// The level the robot stands on (`None` on a stair or before the
    /// first observation).
    pub fn current_level(&self) -> Option<LevelId> {
        self.pose
            .and_then(|p| self.frontiers.level_at(p.position.z))
    }

    /// Whether the robot can stand at `feet` on the agent's own map: a
    /// traversable cell of that level, the approach to a stair, or a
    /// stair's walkable surface (see
    /// [`MultiLevelMap::is_traversable`]).
    pub fn is_traversable(&self, feet: &Point3<f64>) -> bool {
        self.frontiers.is_traversable(feet)
    }

    /// The platform's word that a forward move from `feet` with heading
    /// `yaw` (radians, counter-clockwise from +x) was stopped without
    /// moving the robot, by something its sensor did not show (glass, an
    /// edge with nothing visible beyond it, a bumper hit). The map takes an
    /// obstacle one cell beyond the robot's radius along the heading, on
    /// the level the robot stands on, and keeps it whatever later scans
    /// show: paths are planned around it, and frontiers reached only
    /// through it become unreachable instead of being dispatched again and
    /// again. Returns whether it was recorded (not on a stair, where the
    /// treads are not in a level's grid).
    ///
    /// # Errors
    /// [`AgentError::Frontier`] for non-finite or out-of-range input.
    pub fn on_contact(&mut self, feet: &Point3<f64>, yaw: f64) -> Result<bool, AgentError> {
        let grid = &self.config.frontier.grid;
        let reach = grid.robot_radius + grid.resolution;
        let point = Point2::new(feet.x + reach * yaw.cos(), feet.y + reach * yaw.sin());
        Ok(self.frontiers.contact(feet, &point)?.is_some())
    }

    /// The current target.
    pub fn target(&self) -> Option<&Target> {
        self.target.as_ref().map(|t| &t.target)
    }

    /// The target gate of the current target.
    pub fn gate(&self) -> Option<&TargetGate<String>> {
        self.target.as_ref().map(|t| &t.gate)
    }

    /// The last robot pose.
    pub fn pose(&self) -> Option<RobotPose> {
        self.pose
    }

    /// The clock reading of the last [`step`](Self::step).
    pub fn last_step(&self) -> Option<Duration> {
        self.last_step
    }

    /// The active mission.
    pub fn active_mission(&self) -> Option<(MissionId, &Mission)> {
        self.executor.active()
    }

    /// Every decision so far, oldest first.
    pub fn decisions(&self) -> &[Decision] {
        &self.decisions
    }

    /// The latest decision (kept when the log is taken).
    pub fn last_decision(&self) -> Option<&Decision> {
        self.last_decision.as_ref()
    }

    /// The latest mission outcome.
    pub fn last_outcome(&self) -> Option<&MissionOutcome> {
        self.last_outcome.as_ref()
    }

    /// Takes the decision log (for streaming it to a file).
    pub fn take_decisions(&mut self) -> Vec<Decision> {
        std::mem::take(&mut self.decisions)
    }

    /// Counters.
    pub fn stats(&self) -> AgentStats {
        self.stats
    }

    /// The counters of the context policy when it asks a language model
    /// (calls, valid answers, fallbacks by cause, latencies, tokens); `None`
    /// for the other policies.
    pub fn llm_stats(&self) -> Option<sornav_supervisor::LlmStats> {
        self.supervisor.policy().llm_stats()
    }

    /// Sets the target from a category or a free-text request ("find the
    /// television"), see [`Vocabulary::resolve`]. The maps are kept (several
    /// targets in a row); the gate, the route and any active mission are
    /// reset.
    ///
    /// # Errors
    /// [`AgentError::UnknownTarget`]; the previous target is kept then.
    pub fn set_target(&mut self, request: &str) -> Result<&Target, AgentError> {
        let target = self.vocabulary.resolve(request)?;
        let gate = TargetGate::new(target.category.clone(), self.config.gate)?;
        self.executor.cancel();
        self.process_events();
        self.supervisor.reset();
        self.plan = None;
        self.route = None;
        self.relocation = None;
        self.stairs_retried = false;
        self.back_off.reset_target();
        self.rechecked.clear();
        self.recheck_done = false;
        self.stop_moves = 0;
        self.drop_looks = 0;
        self.near_looks = 0;
        self.drop_look = None;
        let state = self.target.insert(TargetState {
            target,
            gate,
            looks: BTreeMap::new(),
        });
        Ok(&state.target)
    }

    /// Integrates one observation into both maps and updates the target
    /// gate with the clusters this frame detected.
    ///
    /// A [`Sensor::Occupancy`] frame (unlabelled LiDAR returns, a terrain
    /// map) updates the occupancy grid and frontiers only: the semantic map
    /// and the target gate are left alone (it is neither a detection nor a
    /// miss of any candidate), and it does not count as a semantic frame.
    ///
    /// # Errors
    /// [`AgentError::Observation`] for a non-finite pose, bad intrinsics,
    /// mismatched buffers or an empty frame, and the maps' errors (for
    /// example coordinates outside the grid's range); nothing is integrated
    /// on error. Invalid points inside a valid frame are counted in the
    /// report, never fused.
    ///
    /// # Complexity
    /// That of the two map updates (linear in the points, plus the rays'
    /// lengths) plus `O(c)` for `c` object clusters.
    pub fn observe(&mut self, observation: &Observation) -> Result<ObservationReport, AgentError> {
        if let Err(e) = observation.validate() {
            self.stats.refused_observations += 1;
            return Err(e.into());
        }
        let origin = observation.origin();
        let (mut points, occupancy_rejected) =
            observation.occupancy_points(&self.config.depth, self.config.occupancy_max_columns);
        let sensor_points = points.len() as u64;
        // The footprint is a floor at the robot's height: on a stair's
        // tread (even within a robot's tolerance of a level) a disk would
        // lay one flat surface over several treads and the floor beside
        // them, and the stair would no longer be extracted; there only the
        // point under the robot's feet is floor.
        let on_stair = matches!(
            self.frontiers.locate(&observation.pose.position),
            Some(Location::Stair(_))
        );
        if on_stair {
            points.push(observation.pose.position);
        } else {
            footprint_points(
                &observation.pose,
                self.config.footprint_free_radius_m,
                self.config.frontier.grid.resolution,
                &mut points,
            );
        }
        let voids = if self.config.voids_from_missing_depth {
            observation.void_points(
                &self.config.depth,
                self.config.occupancy_max_columns,
                observation.pose.position.z,
            )
        } else {
            Vec::new()
        };
        let update = match self.frontiers.update_with_voids(
            &observation.pose.position,
            &origin,
            &points,
            &voids,
        ) {
            Ok(u) => u,
            Err(e) => {
                self.stats.refused_observations += 1;
                return Err(e.into());
            }
        };
        // Where the scan saw through the floor (a stairwell going down).
        if let Some(level) = self.frontiers.level_at(observation.pose.position.z)
            && let Some((floor_z, drop_depth)) = self
                .frontiers
                .level_map(level)
                .map(|m| (m.config().grid.floor_z, m.config().grid.drop_off_depth))
        {
            self.drop_edges.record(
                level,
                &origin,
                &points[..sensor_points as usize],
                floor_z,
                drop_depth,
            );
        }
        let stats = match &observation.sensor {
            Sensor::Depth(d) => Some(self.semantic.integrate_depth(
                &DepthFrame {
                    camera: &d.camera,
                    pose: &d.camera_pose,
                    depth: &d.depth,
                    labels: &d.labels,
                },
                &self.config.depth,
            )?),
            Sensor::Cloud(c) => Some(self.semantic.integrate_points(&c.origin, &c.points)?),
            Sensor::Occupancy(_) => None,
        };
        self.pose = Some(observation.pose);
        if let Some(viewer) = observation.viewer() {
            self.viewer = Some(viewer);
        }
        self.stats.observations += 1;
        let mut report = ObservationReport {
            occupancy_points: sensor_points,
            footprint_points: points.len() as u64 - sensor_points,
            void_points: voids.len() as u64,
            occupancy_rejected,
            objects: self.semantic.cluster_count(),
            frontiers_added: update.frontiers_added,
            frontiers_removed: update.frontiers_removed,
            ..ObservationReport::default()
        };
        let Some(stats) = stats else {
            self.stats.occupancy_observations += 1;
            self.stats.rejected_points += occupancy_rejected;
            report.points = sensor_points + occupancy_rejected;
            return Ok(report);
        };
        let clusters = self.semantic.update_clusters();
        self.stats.rejected_points += stats.rejected() + occupancy_rejected;
        report.points = stats.points;
        report.semantic_accepted = stats.accepted;
        report.semantic_rejected = stats.rejected();
        report.objects = self.semantic.cluster_count();
        if let Some(state) = self.target.as_mut() {
            let pairs: Vec<(ObjectId, ObjectId)> = clusters
                .retired
                .iter()
                .filter_map(|r| r.successor.map(|s| (ObjectId(r.id.0), ObjectId(s.0))))
                .collect();
            if !pairs.is_empty() {
                state.gate.apply_remap(&pairs);
            }
            let now = self.semantic.integrations();
            let reports: Vec<CandidateReport<String>> = self
                .semantic
                .clusters()
                .filter_map(|c| {
                    let category = self.categories.get(&c.label)?.as_ref()?;
                    (*category == state.target.category).then(|| CandidateReport {
                        object: ObjectId(c.id.0),
                        category: category.clone(),
                        voxels: u32::try_from(c.support).unwrap_or(u32::MAX),
                        centre: c.centre,
                        detected: c.last_seen == now,
                    })
                })
                .collect();
            report.target_detections = reports.iter().filter(|r| r.detected).count();
            // Ties on support go to the candidate nearest by path on the
            // multi-level map (over the stairs), never by straight line.
            let cost = MapPathCost::new(&mut self.frontiers, observation.pose.position);
            state.gate.update_with(&reports, &NeverVisible, &cost);
        }
        Ok(report)
    }

    /// The platform's word on a mission: it reached it, failed (no path,
    /// blocked, ...) or gave it up. Arrival is also detected from the pose
    /// at each [`step`](Self::step), so reporting `Reached` is optional.
    ///
    /// # Errors
    /// [`AgentError::UnknownMission`] when `id` is not the active mission.
    pub fn on_mission_outcome(
        &mut self,
        id: MissionId,
        status: MissionStatus,
    ) -> Result<(), AgentError> {
        let Some((active, mission)) = self.executor.active() else {
            return Err(AgentError::UnknownMission(id));
        };
        if active != id {
            return Err(AgentError::UnknownMission(id));
        }
        let kind = mission.kind;
        // Collect earlier events first, then replace the executor's
        // cancellation by the platform's outcome.
        self.process_events();
        self.executor.cancel();
        let _cancelled = self.executor.drain_events();
        let at = self.last_step.unwrap_or_default();
        self.handle_outcome(MissionOutcome {
            id,
            kind,
            status,
            at,
        });
        Ok(())
    }

    fn process_events(&mut self) {
        for event in self.executor.drain_events() {
            if let ExecutorEvent::Finished(outcome) = event {
                self.handle_outcome(outcome);
            }
        }
    }

    fn exclude(&mut self, frontier: FrontierId) {
        if self.excluded.insert(frontier) {
            self.stats.excluded_frontiers += 1;
        }
    }

    fn handle_outcome(&mut self, outcome: MissionOutcome) {
        // Stuck where it was dispatched from: the place is at fault, not
        // the goal; back off instead of excluding the goal.
        let backing_off = matches!(
            outcome.status,
            MissionStatus::Failed(FailureReason::Stuck { .. })
        ) && matches!(
            outcome.kind,
            MissionKind::Explore { .. } | MissionKind::Relocate { .. }
        ) && self
            .pose
            .is_some_and(|p| self.back_off.on_stuck(outcome.id, &p.position));
        let failed = matches!(outcome.status, MissionStatus::Failed(_)) && !backing_off;
        let reached = outcome.status == MissionStatus::Reached;
        match outcome.kind {
            MissionKind::NavToObject { object } => {
                if let Some(state) = self.target.as_mut() {
                    // Wrong-phase errors mean the gate already moved on
                    // (candidate dropped); nothing to do then.
                    let _ = if reached {
                        state.gate.on_arrived(ObjectId(object.0))
                    } else if failed {
                        state.gate.on_approach_failed(ObjectId(object.0))
                    } else {
                        Ok(Vec::new())
                    };
                }
            }
            MissionKind::Explore { frontier } => {
                // A frontier that is still there once its viewpoint is
                // reached cannot be observed away from there (floor below
                // the camera's view, a shadow behind furniture): excluding
                // it keeps the robot from returning to it forever. A
                // frontier that changes gets a new id and is eligible again.
                // A frontier is excluded once the robot has stood at it
                // for a moment (the platform looks at it on arrival, down
                // if its floor is below the camera's view) and it is still
                // there. An open stair end gets more arrivals: standing
                // there shows the next steps (the stair grows and its end
                // gets a new id) unless the camera cannot see them.
                // A failed climb is retried a few times (a re-plan on the
                // grown map often succeeds) before the end is excluded.
                let id = FrontierId(frontier.0);
                let stair = self.frontiers.is_stair_frontier(id);
                if reached
                    && !stair
                    && let Some(pose) = self.pose
                {
                    self.visits.record(pose.position);
                }
                if failed && !stair {
                    self.exclude(id);
                } else if failed || (reached && !self.short_of_stair_end(id)) {
                    let (n, first) = self.arrivals.entry(id).or_insert((0, outcome.at));
                    *n += 1;
                    let (needed, look) = if stair {
                        (STAIR_END_ARRIVALS, STAIR_LOOK_TIME)
                    } else {
                        (2, LOOK_TIME)
                    };
                    if *n >= needed && outcome.at.saturating_sub(*first) >= look {
                        self.exclude(id);
                    }
                } else {
                    // Short of a stair end, or given up for another goal,
                    // again and again (an end the robot cannot stand at; two
                    // goals it switches between): bounded like any
                    // re-dispatch.
                    let n = self.unfinished.entry(id).or_insert(0);
                    *n += 1;
                    if *n >= UNFINISHED_MISSIONS_LIMIT {
                        self.exclude(id);
                    }
                }
            }
            MissionKind::Relocate { .. } => {
                if let Some(r) = self.relocation.take()
                    && r.mission == outcome.id
                    && failed
                {
                    self.exclude(r.waypoint_frontier);
                }
            }
        }
        self.last_outcome = Some(outcome);
    }

    /// Excludes the frontiers (not stair ends) of G_F whose viewpoints lie
    /// at a place exploration missions reached [`REVISIT_LIMIT`] times.
    ///
    /// # Complexity
    /// O(n p) for n frontiers and p visited places.
    fn exclude_revisited(&mut self) {
        if !self.visits.any_spent() {
            return;
        }
        let ids: Vec<FrontierId> = self
            .frontiers
            .graph()
            .nodes()
            .filter(|f| !self.excluded.contains(&f.id) && self.visits.is_spent(&f.viewpoint3()))
            .map(|f| f.id)
            .filter(|&id| !self.frontiers.is_stair_frontier(id))
            .collect();
        for id in ids {
            self.exclude(id);
            self.stats.revisit_exclusions += 1;
        }
    }

    /// Once per target: when the floor is exhausted while stair ends of
    /// G_F are excluded (failed climbs, arrivals that showed nothing), they
    /// are made eligible again. Returns whether any was.
    fn retry_stairs(&mut self) -> bool {
        if self.stairs_retried {
            return false;
        }
        let stairs: Vec<FrontierId> = self
            .frontiers
            .graph()
            .nodes()
            .map(|n| n.id)
            .filter(|&id| self.frontiers.is_stair_frontier(id))
            .collect();
        let mut any = false;
        for id in stairs {
            if self.excluded.remove(&id) {
                self.arrivals.remove(&id);
                self.unfinished.remove(&id);
                any = true;
            }
        }
        self.stairs_retried = any;
        any
    }

    /// Whether `frontier` is a stair end the robot has not stood at yet
    /// (the mission's arrival radius is reached a few steps early on a
    /// stair; only standing at the end shows what lies beyond it).
    fn short_of_stair_end(&self, frontier: FrontierId) -> bool {
        self.at_stair_end(frontier) == Some(false)
    }

    /// `Some(whether the robot stands at it)` when `frontier` is an open
    /// stair end of G_F (within [`STAIR_END_REACH`] horizontally of its
    /// viewpoint, and vertically within the rise the map accepts between
    /// neighbouring stair columns: a step, or `max_stair_column_rise` on a
    /// flight whose treads are shallower than a column, where the end
    /// column's top is a tread or two above the one the robot stands on),
    /// `None` otherwise or before the first observation.
    fn at_stair_end(&self, frontier: FrontierId) -> Option<bool> {
        if !self.frontiers.is_stair_frontier(frontier) {
            return None;
        }
        let (pose, node) = (self.pose?, self.frontiers.graph().frontier(frontier)?);
        let end = node.viewpoint3();
        let frontier_config = &self.config.frontier;
        let rise = frontier_config
            .grid
            .step_height
            .max(frontier_config.levels.max_stair_column_rise);
        Some(
            (end.xy() - pose.position.xy()).norm() <= STAIR_END_REACH
                && (end.z - pose.position.z).abs() <= rise,
        )
    }

    /// Whether the active mission explores an open stair end and the robot
    /// stands at it: a platform turns around there (the next flight of a
    /// switchback starts behind or beside its landing); the end is excluded
    /// after a full turn (6 s) if it shows nothing new.
    pub fn at_open_stair_end(&self) -> bool {
        match self.executor.active() {
            Some((_, m)) => match m.kind {
                MissionKind::Explore { frontier } => {
                    self.at_stair_end(FrontierId(frontier.0)) == Some(true)
                }
                _ => false,
            },
            None => false,
        }
    }

    fn decide(
        &mut self,
        at: Duration,
        step: DecisionStep,
        action: DecisionAction,
        mission: Option<MissionId>,
        reason: impl Into<String>,
    ) {
        let decision = Decision {
            at,
            step,
            action,
            mission,
            reason: reason.into(),
        };
        self.last_decision = Some(decision.clone());
        self.decisions.push(decision);
    }

    /// Records a decision that keeps the active mission and returns
    /// [`AgentCommand::Continue`].
    fn keep_going(
        &mut self,
        now: Duration,
        step: DecisionStep,
        reason: impl Into<String>,
    ) -> AgentCommand {
        let mission = self.executor.active().map(|(id, _)| id);
        self.decide(now, step, DecisionAction::Continue, mission, reason);
        AgentCommand::Continue { mission }
    }

    /// Submits `mission` (with `path` when not empty) and records the
    /// decision; the step is `TargetAccepted` for `NAV_TO_OBJECT`,
    /// `PolicyEvaluated` otherwise.
    fn dispatch(
        &mut self,
        now: Duration,
        mission: Mission,
        path: Vec<Point3<f64>>,
        action: DecisionAction,
        reason: String,
    ) -> Result<AgentCommand, AgentError> {
        let step = match mission.kind {
            MissionKind::NavToObject { .. } => DecisionStep::TargetAccepted,
            _ => DecisionStep::PolicyEvaluated,
        };
        self.dispatch_as(now, step, mission, path, action, reason)
    }

    /// [`dispatch`](Self::dispatch) with the decision logged under `step`.
    fn dispatch_as(
        &mut self,
        now: Duration,
        step: DecisionStep,
        mut mission: Mission,
        path: Vec<Point3<f64>>,
        action: DecisionAction,
        reason: String,
    ) -> Result<AgentCommand, AgentError> {
        if !path.is_empty() {
            mission = mission.with_path(path);
        }
        let cmd = self.submit(mission)?;
        let id = self.executor.active().map(|(id, _)| id);
        self.decide(now, step, action, id, reason);
        Ok(cmd)
    }

    /// Submits `mission`, turning the executor's answer into a command.
    fn submit(&mut self, mission: Mission) -> Result<AgentCommand, AgentError> {
        let submission = self.executor.submit(mission.clone())?;
        self.process_events();
        Ok(match submission {
            Submission::Started(id) | Submission::Updated(id) => {
                self.stats.dispatched += 1;
                if let Some(pose) = self.pose {
                    self.back_off.started(id, pose.position);
                }
                AgentCommand::Dispatch { id, mission }
            }
            Submission::Refused { .. } => AgentCommand::Continue {
                mission: self.executor.active().map(|(id, _)| id),
            },
        })
    }

    /// One decision cycle at clock reading `now` (seconds of any monotonic
    /// clock: simulated steps or wall time).
    ///
    /// # Algorithm
    /// 1. The executor checks the active mission against the last pose
    ///    (arrival, timeout, stuck); outcomes reach the gate (arrival at a
    ///    candidate starts verification, a failed approach rejects it) and
    ///    failed exploration / relocation targets are excluded.
    /// 2. Target gate first: a confirmed target gives
    ///    [`AgentCommand::Stop`] once the robot is at a view point of it
    ///    (stop in view: otherwise a `NAV_TO_OBJECT` to the nearest
    ///    reachable view point, at most `approach.stop_in_view_attempts`
    ///    times); a candidate being verified gives
    ///    [`AgentCommand::Verify`].
    /// 3. G_F is brought up to date for the pose, G_C is built from it
    ///    (`rho_c`, U_geo, top-K) and the exploration route is planned
    ///    (receding-horizon TSP, or the configured ordering).
    /// 4. The supervisor runs Algorithm 1: an accepted candidate (`N_obs`
    ///    supporting observations) gives `NAV_TO_OBJECT`; an active
    ///    relocation is kept; the rate limit keeps the active mission;
    ///    otherwise the policy relocates to a cluster on `Conflict(g, S_r)`
    ///    or explores the route's first frontier.
    /// 5. The decision becomes a mission for the executor (whose
    ///    pre-emption rules apply) and a command for the platform.
    ///
    /// # Errors
    /// [`AgentError::NoTarget`], [`AgentError::NoObservation`],
    /// [`AgentError::ClockBackwards`], and component errors.
    ///
    /// # Complexity
    /// Dominated by the G_F refresh and the TSP on the `n` reachable
    /// frontiers (see those crates), plus `O(n^2)` for G_C and `O(n M)` for
    /// the contexts of `M` objects.
    pub fn step(&mut self, now: Duration) -> Result<AgentCommand, AgentError> {
        let pose = self.begin_step(now)?;
        // 1. Mission monitoring.
        self.executor.tick(&pose, &AlwaysValid)?;
        self.process_events();
        // 2. Target gate first.
        let gate_command = match self.gate_phase(now, &pose) {
            Ok(command) => command,
            Err(command) => return Ok(command),
        };
        // 3. G_F, G_C and the route.
        let planning = self.planning_phase(&pose)?;
        // 4. Algorithm 1.
        let decided = self.supervision_phase(now, &pose, gate_command, &planning)?;
        self.route = planning.route;
        self.clusters = Some(planning.clusters);
        // 5. Decision -> mission -> command.
        self.action_phase(now, &pose, decided)
    }

    /// Checks the call and advances the clock; the pose to decide from.
    fn begin_step(&mut self, now: Duration) -> Result<RobotPose, AgentError> {
        if self.target.is_none() {
            return Err(AgentError::NoTarget);
        }
        let Some(pose) = self.pose else {
            return Err(AgentError::NoObservation);
        };
        if let Some(previous) = self.last_step
            && now < previous
        {
            return Err(AgentError::ClockBackwards { now, previous });
        }
        self.last_step = Some(now);
        self.stats.steps += 1;
        self.executor.clock_mut().0 = now;
        self.back_off.record(pose.position);
        if let Some(level) = self.current_level() {
            if let Some(from) = self.last_level
                && from != level
                && self.trail.len() > 1
            {
                let mut path = std::mem::take(&mut self.trail);
                path.push(pose.position);
                self.crossing = Some(Crossing {
                    from,
                    to: level,
                    path,
                });
            }
            self.last_level = Some(level);
            self.trail.clear();
            self.trail.push(pose.position);
            self.looking_around = 0;
            self.walked_back = false;
        } else if !self.trail.is_empty()
            && self.trail.len() < TRAIL_MAX
            && self
                .trail
                .last()
                .is_some_and(|p| (p - pose.position).norm() >= TRAIL_SPACING_M)
        {
            self.trail.push(pose.position);
        }

        Ok(pose)
    }

    /// Phase 2 of [`step`](Self::step): follows the target gate. `Err`
    /// carries the command that ends the step (stop at a confirmed target,
    /// verify a candidate); `Ok` the gate's command for the supervisor.
    fn gate_phase(&mut self, now: Duration, pose: &RobotPose) -> Result<GateCommand, AgentCommand> {
        let gate_command = self
            .target
            .as_ref()
            .map_or(GateCommand::Search, |t| t.gate.command());
        if let Some((_, m)) = self.executor.active()
            && let MissionKind::NavToObject { object } = m.kind
            && !matches!(gate_command,
                GateCommand::NavToObject { object: o, .. } | GateCommand::Stop { object: o, .. }
                if o.0 == object.0)
        {
            // The gate dropped or replaced the candidate being approached
            // (a confirmed target's view-point approach is kept).
            self.executor.cancel();
            self.process_events();
        }
        match gate_command {
            GateCommand::Stop { object, centre } => {
                let view = match self.stop_in_view(now, object, centre, pose) {
                    StopView::Move(command) => return Err(command),
                    StopView::InView => "in view",
                    StopView::Glimpse => {
                        self.stats.glimpse_stops += 1;
                        "in view, glimpsed (no clear view point reached)"
                    }
                    StopView::Off => "stop-in-view check off",
                    StopView::GaveUp(why) => {
                        self.stats.stops_out_of_view += 1;
                        why
                    }
                };
                self.decide(
                    now,
                    DecisionStep::TargetConfirmed,
                    DecisionAction::Stop,
                    None,
                    format!(
                        "object {} confirmed: N_obs observations and a fresh detection after arrival; {view}",
                        object.0
                    ),
                );
                return Err(AgentCommand::Stop { object, centre });
            }
            GateCommand::Verify { object, centre } => {
                self.decide(
                    now,
                    DecisionStep::TargetVerification,
                    DecisionAction::Verify,
                    None,
                    format!("arrived at candidate {}: face it and observe", object.0),
                );
                return Err(AgentCommand::Verify {
                    object,
                    look_at: centre,
                });
            }
            GateCommand::Search => {
                if let Some((object, centre)) = self.second_look(pose) {
                    self.stats.second_looks += 1;
                    self.decide(
                        now,
                        DecisionStep::TargetVerification,
                        DecisionAction::Verify,
                        None,
                        format!(
                            "candidate {} seen fewer than N_obs times: face it and observe",
                            object.0
                        ),
                    );
                    return Err(AgentCommand::Verify {
                        object,
                        look_at: centre,
                    });
                }
            }
            GateCommand::NavToObject { .. } => {}
        }
        Ok(gate_command)
    }

    /// A second look while searching: the nearest tracked candidate seen at
    /// least once but fewer than `N_obs` times, not detected in the latest
    /// frame, not cooling down after a rejection, within [`LOOK_RANGE_M`]
    /// horizontally and [`LOOK_HEIGHT_M`] vertically of the robot, that has had fewer
    /// than [`LOOK_BUDGET`] looks at its current support. A candidate seen
    /// in passing (two frames of a turn) otherwise waits for ever while
    /// the robot explores elsewhere: nothing else brings it back into
    /// view. The look turns the camera toward it; a detection adds
    /// support, and at `N_obs` the gate accepts it as usual.
    ///
    /// # Complexity
    /// O(T log T) for T tracked candidates.
    fn second_look(&mut self, pose: &RobotPose) -> Option<(ObjectId, Point3<f64>)> {
        let state = self.target.as_mut()?;
        let tracker = state.gate.tracker();
        let n_obs = tracker.config().n_obs;
        let latest = tracker.updates();
        let feet = pose.position;
        let mut near: Vec<(f64, ObjectId, Point3<f64>, u32)> = tracker
            .tracks()
            .filter(|t| {
                t.evidence.support > 0
                    && t.evidence.support < n_obs
                    && t.last_detected < latest
                    && tracker.rejected_until(t.object).is_none()
                    && (t.centre.z - feet.z).abs() <= LOOK_HEIGHT_M
            })
            .map(|t| {
                let d = (t.centre.xy() - feet.xy()).norm();
                (d, t.object, t.centre, t.evidence.support)
            })
            .filter(|(d, ..)| *d <= LOOK_RANGE_M)
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for (_, object, centre, support) in near {
            let entry = state.looks.entry(object.0).or_insert((support, 0));
            if entry.0 != support {
                *entry = (support, 0);
            }
            if entry.1 < LOOK_BUDGET {
                entry.1 += 1;
                return Some((object, centre));
            }
        }
        None
    }

    /// Phase 3 of [`step`](Self::step): brings G_F up to date for the
    /// pose, builds G_C and plans the exploration route.
    fn planning_phase(&mut self, pose: &RobotPose) -> Result<Planning, AgentError> {
        let objects = self.object_summaries();
        let category = self
            .target
            .as_ref()
            .map(|t| t.target.category.clone())
            .unwrap_or_default();
        self.frontiers.frontier_graph(&pose.position)?;
        self.exclude_revisited();
        // Read after the refresh, which may have found new levels.
        let levels: BTreeMap<LevelId, f64> =
            self.frontiers.levels().map(|l| (l.id, l.floor_z)).collect();
        let graph = self.frontiers.graph();
        // The frontier being explored; when it changed (its cells were
        // observed: a new id), its successor near its viewpoint.
        let mut committed = None;
        if let Some((_, m)) = self.executor.active()
            && let MissionKind::Explore { frontier } = m.kind
        {
            let id = FrontierId(frontier.0);
            committed = if graph.frontier(id).is_some() {
                Some(id)
            } else {
                commitment::successor(graph, &self.excluded, &m.waypoint, &self.config.commitment)
            };
            if committed.is_none() {
                // The frontier was explored away: the mission is done.
                self.executor.cancel();
                for event in self.executor.drain_events() {
                    if let ExecutorEvent::Finished(outcome) = event {
                        self.last_outcome = Some(outcome);
                    }
                }
            }
        }
        let cg = ClusterGraph::build(graph, &self.config.cluster)?;
        let mut route = ordering::choose(
            &self.config.ordering,
            &self.config.horizon,
            &OrderingInput {
                graph,
                excluded: &self.excluded,
                target: &category,
                objects: &objects,
                n_min: self.config.cluster.n_min,
                r_s: self.config.cluster.r_s,
            },
            &mut self.plan,
        )?;
        if let Some(r) = route.as_mut() {
            let first = commitment::committed_frontier(
                graph,
                &self.excluded,
                r,
                committed,
                &self.config.commitment,
            );
            if first != r.first
                && let Some(node) = graph.frontier(first)
            {
                r.first = first;
                r.first_viewpoint = node.viewpoint3();
                r.committed = true;
            }
        }

        Ok(Planning {
            objects,
            category,
            levels,
            clusters: cg,
            route,
        })
    }

    /// Phase 4 of [`step`](Self::step): the supervisor's Algorithm 1 over
    /// the planned route and the region contexts, with the mission each
    /// command would start.
    fn supervision_phase(
        &mut self,
        now: Duration,
        pose: &RobotPose,
        gate_command: GateCommand,
        planning: &Planning,
    ) -> Result<Decided, AgentError> {
        let Planning {
            objects,
            category,
            levels,
            clusters: cg,
            route,
        } = planning;
        let z = pose.position.z;
        let graph = self.frontiers.graph();
        let mission = match self.executor.active() {
            Some((id, m)) => MissionState {
                id: id.0,
                kind: supervisor_kind(&m.kind),
            },
            None => MissionState {
                id: 0,
                kind: SupKind::Idle,
            },
        };
        let target_accepted = match gate_command {
            GateCommand::NavToObject { object, .. } => Some(object.0),
            _ => None,
        };
        let input = StepInput {
            target: category,
            target_accepted,
            mission,
            first_frontier: route.as_ref().map(|r| r.first_viewpoint),
        };
        let excluded = &self.excluded;
        let floors = |l: LevelId| relative_floor(levels, l, z);
        let frontiers = &self.frontiers;
        let new_floors =
            unexplored_floors(graph, excluded, &|id| frontiers.is_stair_frontier(id), z);
        let command = self.supervisor.step(now, &input, || {
            region_context(cg, graph, objects, excluded, &floors, &new_floors)
        })?;

        let explore = match (&command, &route) {
            (
                SupervisorCommand::Explore { .. } | SupervisorCommand::ExploreNewRegion { .. },
                Some(r),
            ) => explore_mission(graph, r.first),
            _ => None,
        };
        let relocation = match &command {
            SupervisorCommand::Relocate { cluster_id, .. }
                if *cluster_id >= FLOOR_CANDIDATE_BASE =>
            {
                usize::try_from(*cluster_id - FLOOR_CANDIDATE_BASE)
                    .ok()
                    .and_then(|i| new_floors.get(i))
                    .map(|f| {
                        (
                            vec![f.frontier],
                            f.frontier,
                            f.waypoint,
                            robot_path(graph, f.frontier).unwrap_or_default(),
                        )
                    })
            }
            SupervisorCommand::Relocate { cluster_id, .. } => {
                usize::try_from(*cluster_id).ok().and_then(|k| {
                    let cluster = cg.cluster(sornav_cluster_graph::ClusterId(k))?;
                    let reloc = cluster.relocation.as_ref()?;
                    let vp = graph.frontier(reloc.waypoint)?.viewpoint3();
                    Some((
                        cluster.members.clone(),
                        reloc.waypoint,
                        vp,
                        robot_path(graph, reloc.waypoint).unwrap_or_default(),
                    ))
                })
            }
            _ => None,
        };
        if route.is_some() {
            self.last_placed = Some(pose.position);
        }

        Ok(Decided {
            command,
            explore,
            relocation,
        })
    }

    /// Phase 5 of [`step`](Self::step): the supervisor's command becomes a
    /// mission for the executor (whose pre-emption rules apply) and a
    /// command for the platform.
    fn action_phase(
        &mut self,
        now: Duration,
        pose: &RobotPose,
        decided: Decided,
    ) -> Result<AgentCommand, AgentError> {
        let Decided {
            command,
            explore,
            relocation,
        } = decided;
        let active = self.executor.active().map(|(id, m)| (id, m.kind));
        let result = match command {
            SupervisorCommand::NavToObject { target_id } => {
                let object = ExecObjectId(target_id);
                if active.is_some_and(|(_, k)| k == MissionKind::NavToObject { object }) {
                    self.keep_going(
                        now,
                        DecisionStep::TargetAccepted,
                        format!("approaching candidate {target_id}"),
                    )
                } else {
                    self.dispatch_approach(now, target_id, pose)?
                }
            }
            SupervisorCommand::KeepRelocation => {
                let reason = self
                    .relocation
                    .as_ref()
                    .map_or_else(String::new, |r| r.reason.clone());
                self.keep_going(
                    now,
                    DecisionStep::RelocationActive,
                    format!("relocation under way: {reason}"),
                )
            }
            SupervisorCommand::ContinueMission => {
                self.keep_going(now, DecisionStep::RateLimited, "supervisor rate limit")
            }
            SupervisorCommand::Relocate { reason, .. } => {
                self.stats.policy_evaluations += 1;
                match relocation {
                    Some((members, waypoint_frontier, waypoint, path)) => {
                        let key = members.first().map_or(0, |f| f.0);
                        let mission = Mission::new(
                            MissionKind::Relocate {
                                cluster: ExecClusterId(key),
                            },
                            waypoint,
                        );
                        let cmd = self.dispatch(
                            now,
                            mission,
                            path,
                            DecisionAction::Relocate,
                            reason.clone(),
                        )?;
                        if let AgentCommand::Dispatch { id, .. } = &cmd {
                            self.stats.relocations += 1;
                            self.relocation = Some(RelocationRecord {
                                mission: *id,
                                cluster_key: key,
                                members,
                                waypoint_frontier,
                                reason,
                            });
                        }
                        cmd
                    }
                    None => self.keep_going(
                        now,
                        DecisionStep::PolicyEvaluated,
                        format!("relocation target vanished ({reason})"),
                    ),
                }
            }
            SupervisorCommand::Explore { .. } | SupervisorCommand::ExploreNewRegion { .. } => {
                let (step, reason) = match command {
                    SupervisorCommand::ExploreNewRegion { remaining_s, .. } => (
                        DecisionStep::RegionDwell,
                        format!(
                            "exploring the region the relocation reached; the policy resumes in {remaining_s:.1} s"
                        ),
                    ),
                    SupervisorCommand::Explore { reason, .. } => {
                        self.stats.policy_evaluations += 1;
                        (DecisionStep::PolicyEvaluated, reason)
                    }
                    _ => unreachable!("matched above"),
                };
                let looking = self
                    .drop_look
                    .is_some_and(|l| l.mission.is_some() && l.mission == active.map(|(id, _)| id));
                let back_off = if active.is_none() && self.back_off.is_pending() {
                    self.back_off.take(&pose.position)
                } else {
                    None
                };
                let near_look = if looking || back_off.is_some() || self.current_level().is_none() {
                    None
                } else {
                    self.drop_look(now, pose, Some(DROP_NEAR_M))?
                };
                match (explore, near_look) {
                    _ if back_off.is_some() => {
                        let path = back_off.unwrap_or_default();
                        self.stats.back_offs += 1;
                        self.back_off_along(now, step, path, &reason)?
                    }
                    _ if looking => self.keep_going(
                        now,
                        step,
                        format!("looking down through the floor's edge ({reason})"),
                    ),
                    (_, Some(LookMove { path, at })) => {
                        self.dispatch_drop_look(now, step, path, at, &reason)?
                    }
                    (Some(mission), None) if !active.is_some_and(|(_, k)| k == mission.kind) => self
                        .dispatch_as(
                            now,
                            step,
                            mission,
                            Vec::new(),
                            DecisionAction::Explore,
                            reason,
                        )?,
                    (Some(_), None) => self.keep_going(now, step, reason),
                    (None, None) if active.is_none() && self.current_level().is_none() => {
                        // Between floors (on a stair, or on a floor not
                        // recognised yet): nothing is known to be
                        // exhausted. Go back to where the map last gave
                        // the robot somewhere to go; without such a place,
                        // look around until the map places the robot.
                        let last_placed = self.last_placed;
                        match last_placed {
                            Some(back) if (back - pose.position).norm() > RETREAT_MIN_M => {
                                self.retreat(
                                    now,
                                    step,
                                    vec![pose.position, back],
                                    None,
                                    format!("no reachable frontier off a known floor: back to the last place with one ({reason})"),
                                )?
                            }
                            _ if self.retry_stairs() => self.keep_going(
                                now,
                                step,
                                format!("no reachable frontier off a known floor: retrying the excluded stair ends once ({reason})"),
                            ),
                            _ if self.looking_around < LOOK_AROUND_LIMIT => {
                                self.looking_around += 1;
                                self.keep_going(
                                    now,
                                    step,
                                    format!("no reachable frontier off a known floor; looking around ({reason})"),
                                )
                            }
                            _ => self.walk_back(now, step, pose, &reason)?,
                        }
                    }
                    (None, None) if active.is_none() && self.retry_stairs() => self.keep_going(
                        now,
                        step,
                        format!(
                            "floor exhausted: retrying the excluded stair ends once ({reason})"
                        ),
                    ),
                    (None, None) if active.is_none()
                        && (self.drop_looks < DROP_LOOK_LIMIT || self.drop_look.is_some()) =>
                    {
                        match self.drop_look(now, pose, None)? {
                            Some(LookMove { path, at }) => self.dispatch_drop_look(
                                now,
                                step,
                                path,
                                at,
                                &format!("no reachable frontier; {reason}"),
                            )?,
                            None => self.keep_going(
                                now,
                                step,
                                format!("no reachable frontier and no drop edge left to look into ({reason})"),
                            ),
                        }
                    }
                    (None, None) if active.is_none() && self.unreached_look_allowed() => {
                        match self.unreached_look(pose)? {
                            Some(LookMove { path, at }) => self.retreat(
                                now,
                                step,
                                path,
                                None,
                                format!(
                                    "no reachable frontier: looking at the unreached frontier at ({:.1}, {:.1}) from the nearest reachable place ({reason})",
                                    at.x, at.y
                                ),
                            )?,
                            None => self.keep_going(
                                now,
                                step,
                                format!("no reachable frontier and no place to look at an unreached one from ({reason})"),
                            ),
                        }
                    }
                    (None, None) if active.is_none() && !self.recheck_done => {
                        match self.recheck_look(pose)? {
                            Some(Recheck {
                                object,
                                centre,
                                path,
                            }) => self.retreat(
                                now,
                                step,
                                path,
                                Some(centre),
                                format!(
                                    "no reachable frontier: back to look at object {object} of the target's category, not confirmed ({reason})"
                                ),
                            )?,
                            None => self.keep_going(
                                now,
                                step,
                                format!("no reachable frontier and no unconfirmed object of the target's category to look at again ({reason})"),
                            ),
                        }
                    }
                    (None, None) if active.is_none() && self.crossing_back().is_some() => {
                        self.cross_back(now, step, pose, &reason)?
                    }
                    (None, None) if active.is_none() => {
                        self.decide(
                            now,
                            step,
                            DecisionAction::Exhausted,
                            None,
                            format!("no reachable frontier ({reason})"),
                        );
                        let stairs = self.stairs_to_unexplored_floors(&pose.position);
                        if stairs.is_empty() {
                            AgentCommand::Exhausted
                        } else {
                            AgentCommand::FloorExhausted { stairs }
                        }
                    }
                    (None, None) => self.keep_going(
                        now,
                        step,
                        format!("no reachable frontier; finishing the active mission ({reason})"),
                    ),
                }
            }
        };
        Ok(result)
    }

    /// The crossing to walk back over when the robot's floor is exhausted:
    /// the last stair it walked, ending on this floor, while the floor it
    /// left still has frontiers to explore (not excluded, stair ends
    /// aside) and fewer than [`CROSSING_BACK_LIMIT`] walks back were made.
    /// `O(F)` for the F frontiers of the floor left.
    fn crossing_back(&self) -> Option<&Crossing> {
        let crossing = self.crossing.as_ref()?;
        let open = self.frontiers.level_map(crossing.from).is_some_and(|map| {
            map.graph()
                .nodes()
                .any(|f| !self.excluded.contains(&f.id) && !self.frontiers.is_stair_frontier(f.id))
        });
        (self.crossings_back < CROSSING_BACK_LIMIT
            && open
            && self.current_level() == Some(crossing.to))
        .then_some(crossing)
    }

    /// Walks the last crossing back to the floor it left (see
    /// [`Crossing`]): on this floor to where the crossing ended (a path on
    /// the map), then the crossing reversed, onto the floor itself (the
    /// arrival radius of a back-off), where that floor's frontiers are
    /// reachable again. Without a path to the crossing's end the crossing
    /// is dropped (the next decision declares the floor exhausted).
    fn cross_back(
        &mut self,
        now: Duration,
        step: DecisionStep,
        pose: &RobotPose,
        reason: &str,
    ) -> Result<AgentCommand, AgentError> {
        let Some(crossing) = self.crossing.clone() else {
            return Ok(self.keep_going(now, step, reason.to_owned()));
        };
        let Some(&end) = crossing.path.last() else {
            return Ok(self.keep_going(now, step, reason.to_owned()));
        };
        let Some(mut path) = self.plan_path(&pose.position, &end)? else {
            self.crossing = None;
            return Ok(self.keep_going(
                now,
                step,
                format!("no path back to the stair the robot came by ({reason})"),
            ));
        };
        self.crossings_back += 1;
        path.extend(crossing.path.iter().rev().skip(1).copied());
        self.retrace(
            now,
            step,
            path,
            format!(
                "floor {} exhausted, floor {} still has frontiers the map gives no way to: back over the stair the robot came by ({reason})",
                crossing.to.0, crossing.from.0
            ),
        )
    }

    /// Whether the exhaustion check may still look at an unreached
    /// frontier (fewer than [`UNREACHED_LOOK_LIMIT`] looks so far).
    fn unreached_look_allowed(&self) -> bool {
        self.unreached_looks < UNREACHED_LOOK_LIMIT
    }

    /// The exhaustion check: before the floor is declared exhausted, a
    /// frontier of G_F that the robot cannot reach (behind a gap narrower
    /// than the robot on the map, a drop-off, a stair head seen from afar)
    /// may still show the way on from closer. Takes the nearest such
    /// frontier on the robot's floor not looked at yet (stair ends and
    /// excluded frontiers aside) and returns the path to the reachable
    /// traversable place nearest to its viewpoint (within
    /// [`UNREACHED_LOOK_RADIUS_M`], further than half a metre from the
    /// robot), with the viewpoint. Each call counts as one of the
    /// [`UNREACHED_LOOK_LIMIT`] attempts per target and marks the frontier
    /// looked at; with no unreached frontier left the attempts end.
    /// `Ok(None)` when no frontier is unreached or none has a reachable
    /// place near it.
    ///
    /// # Complexity
    /// O(n) over the n frontiers, plus up to eight shortest-path searches.
    fn unreached_look(&mut self, pose: &RobotPose) -> Result<Option<LookMove>, AgentError> {
        self.unreached_looks += 1;
        let Some(level) = self.current_level() else {
            return Ok(None);
        };
        let feet = pose.position;
        let graph = self.frontiers.graph();
        let mut unreached: Vec<(f64, Point3<f64>)> = graph
            .nodes()
            .filter(|f| !self.excluded.contains(&f.id) && !self.frontiers.is_stair_frontier(f.id))
            .filter(|f| {
                graph
                    .cost(NodeId::Robot, NodeId::Frontier(f.id))
                    .is_none_or(|c| !c.is_finite())
            })
            .map(|f| f.viewpoint3())
            .filter(|v| (v.z - feet.z).abs() <= REVISIT_RADIUS_M)
            .filter(|v| {
                !self
                    .looked_at
                    .iter()
                    .any(|p| (p.xy() - v.xy()).norm() <= UNREACHED_LOOK_RADIUS_M)
            })
            .map(|v| ((v.xy() - feet.xy()).norm(), v))
            .collect();
        unreached.sort_by(|a, b| a.0.total_cmp(&b.0));
        let Some(&(_, at)) = unreached.first() else {
            // Nothing left to look at: the floor is exhausted.
            self.unreached_looks = UNREACHED_LOOK_LIMIT;
            return Ok(None);
        };
        self.looked_at.push(at);
        Ok(self
            .path_to_place_near(level, &feet, &at, UNREACHED_LOOK_RADIUS_M)?
            .map(|path| LookMove { path, at }))
    }

    /// The exhaustion check's last look: an object of the target's
    /// category on the map that the gate has not confirmed (a verification
    /// that saw nothing from a poor approach point, evidence that lapsed
    /// while the robot looked elsewhere) is looked at again, from the best
    /// reachable view point ([`ViewDemand::Prefer`]: a clear one first),
    /// before the floor is declared exhausted. The nearest
    /// such object with a reachable clear view point, each once, at most
    /// [`RECHECK_LIMIT`] per target; the gate then judges it from the new
    /// frames. `Ok(None)` (and no more rechecks) when none is left.
    ///
    /// # Complexity
    /// O(c) over the c object clusters, plus one view-point search
    /// (see [`approach_waypoint`]) per object tried.
    fn recheck_look(&mut self, pose: &RobotPose) -> Result<Option<Recheck>, AgentError> {
        let Some(state) = self.target.as_ref() else {
            self.recheck_done = true;
            return Ok(None);
        };
        if self.rechecked.len() >= RECHECK_LIMIT || state.gate.is_confirmed() {
            self.recheck_done = true;
            return Ok(None);
        }
        let feet = pose.position;
        let mut objects: Vec<(f64, u64, Point3<f64>, f64)> = self
            .semantic
            .clusters()
            .filter(|c| {
                self.categories
                    .get(&c.label)
                    .and_then(Option::as_ref)
                    .is_some_and(|cat| *cat == state.target.category)
            })
            .filter(|c| !self.rechecked.contains(&c.id.0))
            .map(|c| ((c.centre - feet).norm(), c.id.0, c.centre, c.bounds.min.z))
            .collect();
        objects.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let viewer = self.viewer();
        let arrival = self.view_arrival_m();
        for (_, id, centre, bottom) in objects {
            self.rechecked.push(id);
            let Some(level) = self.object_level(bottom) else {
                continue;
            };
            let Some(view) = self.object_view(id, centre) else {
                continue;
            };
            let target = ApproachTarget {
                object: &view,
                voxels: &self.semantic,
                viewer,
                arrival_radius_m: arrival,
                demand: ViewDemand::Prefer,
            };
            if let Some((_, path)) = approach_waypoint(
                &mut self.frontiers,
                feet,
                level,
                &target,
                &self.config.approach,
            )? {
                return Ok(Some(Recheck {
                    object: id,
                    centre,
                    path,
                }));
            }
            if self.rechecked.len() >= RECHECK_LIMIT {
                break;
            }
        }
        self.recheck_done = true;
        Ok(None)
    }

    /// The path from `feet` to the reachable traversable place of `level`
    /// nearest to `at` within `radius` (and further than half a metre from
    /// the robot): up to eight places are tried, nearest first, each at
    /// least 0.3 m from the ones tried before (the cells right next to an
    /// unreached place are most often unreached too). `Ok(None)` when none
    /// has a path.
    ///
    /// # Complexity
    /// O((radius / resolution)^2) cells plus up to eight shortest-path
    /// searches.
    fn path_to_place_near(
        &mut self,
        level: LevelId,
        feet: &Point3<f64>,
        at: &Point3<f64>,
        radius: f64,
    ) -> Result<Option<Vec<Point3<f64>>>, AgentError> {
        let Some(level_map) = self.frontiers.level_map(level) else {
            return Ok(None);
        };
        let grid = level_map.grid();
        let floor = level_map.config().grid.floor_z;
        let step = grid.resolution().max(0.05);
        let n = (radius / step).ceil() as i64;
        let mut places: Vec<(f64, Point3<f64>)> = Vec::new();
        for i in -n..=n {
            for j in -n..=n {
                let p = Point2::new(at.x + i as f64 * step, at.y + j as f64 * step);
                let d = (p - at.xy()).norm();
                if d > radius || (p - feet.xy()).norm() <= 0.5 {
                    continue;
                }
                if grid.cell_of(&p).is_ok_and(|c| grid.is_traversable(c)) {
                    places.push((d, Point3::new(p.x, p.y, floor)));
                }
            }
        }
        places.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut tried: Vec<Point3<f64>> = Vec::new();
        for (_, p) in places {
            if tried.len() >= 8 {
                break;
            }
            if tried.iter().any(|q| (q.xy() - p.xy()).norm() < 0.3) {
                continue;
            }
            tried.push(p);
            if let Some(edge) = self.frontiers.path(feet, &p)? {
                return Ok(Some(edge.path));
            }
        }
        Ok(None)
    }

    /// Looks down through drop edges (see [`DropEdges`]): a stair going
    /// down is seen only from its head, looking down. Only for a robot
    /// that climbs stairs (`frontier.levels.allow_stairs`). Used before the
    /// floor is declared exhausted (`within` = `None`: any unseen edge of
    /// the robot's level, up to [`DROP_LOOK_LIMIT`] looks per target) and,
    /// while exploring, for deep edges ([`DEEP_DROP_M`]) within
    /// [`DROP_NEAR_M`] of the robot (`within` = that distance, up to
    /// [`NEAR_LOOK_LIMIT`] looks per target).
    ///
    /// While a look is under way and the robot stands at its place, the
    /// same place is returned again until [`DROP_LOOK_TIME`] has passed
    /// there (facing the edge and tilting a camera take a few steps). Otherwise the nearest
    /// unseen edge not looked into yet (edges within
    /// [`DROP_LOOK_RADIUS_M`] of an earlier look count as looked into)
    /// whose place to look from is reachable: [`DROP_LOOK_STANDOFF_M`]
    /// back from the edge toward where the sensor saw it from (the robot's
    /// own position when that is within half a metre), else the reachable
    /// place nearest to the edge within [`DROP_LOOK_RADIUS_M`]. Each new
    /// edge counts as one look; with no edge left, the exhaustion check's
    /// looks end. Returns the
    /// path to the place and the point to look at.
    ///
    /// # Complexity
    /// O(B log B) over the B drop-edge bins, plus up to six place searches
    /// ([`Self::path_to_place_near`]).
    fn drop_look(
        &mut self,
        now: Duration,
        pose: &RobotPose,
        within: Option<f64>,
    ) -> Result<Option<LookMove>, AgentError> {
        let exhausting = within.is_none();
        // A robot that cannot climb stairs has no use for a stair going
        // down (the single-floor variant, a wheeled base).
        let climbs = self.config.frontier.levels.allow_stairs;
        let Some(level) = self.current_level().filter(|_| climbs) else {
            if exhausting {
                self.drop_looks = DROP_LOOK_LIMIT;
            }
            return Ok(None);
        };
        let feet = pose.position;
        if let Some(look) = self.drop_look.take() {
            let there = (look.place.xy() - feet.xy()).norm() <= REVISIT_RADIUS_M
                && (look.place.z - feet.z).abs() <= REVISIT_RADIUS_M;
            let since = look.since.unwrap_or(now);
            if there && now.saturating_sub(since) < DROP_LOOK_TIME {
                self.drop_look = Some(DropLook {
                    mission: None,
                    since: Some(since),
                    ..look
                });
                return Ok(Some(LookMove {
                    path: vec![feet, look.place],
                    at: look.edge,
                }));
            }
        }
        let (used, limit) = if exhausting {
            (self.drop_looks, DROP_LOOK_LIMIT)
        } else {
            (self.near_looks, NEAR_LOOK_LIMIT)
        };
        if used >= limit {
            return Ok(None);
        }
        let unseen: Vec<_> = self
            .drop_edges
            .unseen(level, &feet.xy())
            .into_iter()
            .filter(|e| {
                within.is_none_or(|r| {
                    (e.at.xy() - feet.xy()).norm() <= r && e.max_depth >= DEEP_DROP_M
                })
            })
            .take(6)
            .collect();
        if unseen.is_empty() {
            if exhausting {
                self.drop_looks = DROP_LOOK_LIMIT;
            }
            return Ok(None);
        }
        for edge in unseen {
            self.drop_edges.mark_looked(level, &edge.at);
            // The floor ends somewhere between where the sensor stood and
            // the edge point (where the ray passed the floor's height): at
            // the last mapped floor surface on the way back.
            let (floor_end, back) = self.floor_end(&edge.at, &edge.from);
            let near = floor_end + back * DROP_LOOK_STANDOFF_M;
            let path = if (near - feet.xy()).norm() <= 0.5 {
                Some(vec![feet])
            } else {
                let near = Point3::new(near.x, near.y, edge.at.z);
                match self.path_to_place_near(level, &feet, &near, 0.5)? {
                    Some(p) => Some(p),
                    None => self.path_to_place_near(level, &feet, &edge.at, DROP_LOOK_RADIUS_M)?,
                }
            };
            if let Some(path) = path
                && let Some(&place) = path.last()
            {
                let look = Point3::new(floor_end.x, floor_end.y, edge.at.z);
                if exhausting {
                    self.drop_looks += 1;
                } else {
                    self.near_looks += 1;
                }
                self.drop_look = Some(DropLook {
                    edge: look,
                    place,
                    mission: None,
                    since: None,
                });
                return Ok(Some(LookMove { path, at: look }));
            }
        }
        Ok(None)
    }

    /// Where the floor ends on the way from the drop edge point `at` back
    /// to `from` (where the sensor stood when it saw it): the first
    /// position, in 0.1 m steps from `at`, whose surface column holds a
    /// walkable surface within 0.1 m of `at`'s height (the floor); `from`
    /// when none does. Also the unit direction toward `from` (zero when
    /// the two coincide).
    ///
    /// # Complexity
    /// O(d / 0.1) surface-column look-ups for the distance d.
    fn floor_end(
        &self,
        at: &Point3<f64>,
        from: &Point2<f64>,
    ) -> (Point2<f64>, nalgebra::Vector2<f64>) {
        let start = at.xy();
        let d = from - start;
        let len = d.norm();
        if len <= 1e-6 {
            return (start, nalgebra::Vector2::zeros());
        }
        let dir = d / len;
        let steps = (len / 0.1).ceil() as usize;
        for i in 0..=steps {
            let p = start + dir * (i as f64 * 0.1).min(len);
            if self
                .frontiers
                .surfaces_at(p.x, p.y)
                .iter()
                .any(|h| (h - at.z).abs() <= 0.1)
            {
                return (p, dir);
            }
        }
        (*from, dir)
    }

    /// Dispatches the look of [`Self::drop_look`]: a retreat along `path`
    /// facing a point [`DROP_LOOK_BELOW_M`] under the edge `at` (a
    /// platform that can tilt its camera looks down there).
    fn dispatch_drop_look(
        &mut self,
        now: Duration,
        step: DecisionStep,
        path: Vec<Point3<f64>>,
        at: Point3<f64>,
        reason: &str,
    ) -> Result<AgentCommand, AgentError> {
        let cmd = self.retreat(
            now,
            step,
            path,
            Some(Point3::new(at.x, at.y, at.z - DROP_LOOK_BELOW_M)),
            format!(
                "looking down through the floor's edge at ({:.1}, {:.1}): a stair going down is only seen from its head ({reason})",
                at.x, at.y
            ),
        )?;
        if let (AgentCommand::Dispatch { id, .. }, Some(look)) = (&cmd, self.drop_look.as_mut()) {
            look.mission = Some(*id);
        }
        Ok(cmd)
    }

    /// Dispatches a retreat (a relocation outside any cluster) along
    /// `path` to its last point, facing `look_at` there when given (a
    /// platform that can tilt its camera looks down at a point below its
    /// view).
    fn retreat(
        &mut self,
        now: Duration,
        step: DecisionStep,
        path: Vec<Point3<f64>>,
        look_at: Option<Point3<f64>>,
        reason: String,
    ) -> Result<AgentCommand, AgentError> {
        let Some(&back) = path.last() else {
            return Ok(self.keep_going(now, step, reason));
        };
        let mut mission = retreat_mission(back);
        if let Some(look) = look_at {
            // A look needs the robot at its place, not anywhere within a
            // relocation's arrival radius.
            mission = mission
                .with_look_at(look)
                .with_arrival_radius(DROP_LOOK_ARRIVAL_M);
        }
        self.dispatch_as(now, step, mission, path, DecisionAction::Retreat, reason)
    }

    /// A mission failed stuck where it started: drives `path` (the way the
    /// robot came, see [`BackOff`]) and plans again from its end, keeping
    /// the failed mission's goal.
    fn back_off_along(
        &mut self,
        now: Duration,
        step: DecisionStep,
        path: Vec<Point3<f64>>,
        reason: &str,
    ) -> Result<AgentCommand, AgentError> {
        self.retrace(
            now,
            step,
            path,
            format!("stuck where the last mission started: backing off along the way the robot came ({reason})"),
        )
    }

    /// Drives `path`, a way the robot came, to its last point and arrives
    /// there (within [`BACK_OFF_ARRIVAL_M`], not anywhere within a
    /// relocation's radius): a back-off, a walk back along the trail, a
    /// crossing walked back.
    fn retrace(
        &mut self,
        now: Duration,
        step: DecisionStep,
        path: Vec<Point3<f64>>,
        reason: String,
    ) -> Result<AgentCommand, AgentError> {
        let Some(&back) = path.last() else {
            return Ok(self.keep_going(now, step, reason));
        };
        let mission = retreat_mission(back).with_arrival_radius(BACK_OFF_ARRIVAL_M);
        self.dispatch_as(now, step, mission, path, DecisionAction::Retreat, reason)
    }

    /// Off a known floor, nothing reachable, looked around: walks back
    /// along the trail to the last floor the robot stood on, once; with no
    /// trail, already there, or when the walk back did not bring the robot
    /// onto a known floor, there is nothing left to do: exhausted.
    fn walk_back(
        &mut self,
        now: Duration,
        step: DecisionStep,
        pose: &RobotPose,
        reason: &str,
    ) -> Result<AgentCommand, AgentError> {
        self.looking_around = 0;
        match self.trail.first().copied() {
            Some(back) if !self.walked_back && (back - pose.position).norm() > RETREAT_MIN_M => {
                self.walked_back = true;
                // The place that last gave the robot somewhere to go is
                // where it found nothing (the excluded stair end it
                // climbed to): going back there would undo this walk.
                self.last_placed = None;
                let mut path = vec![pose.position];
                path.extend(self.trail.iter().rev().copied());
                // Onto the floor itself: within a relocation's radius of
                // the trail's start the robot may still stand on the stair,
                // where no floor's frontiers are reachable.
                self.retrace(
                    now,
                    step,
                    path,
                    format!("nothing reachable off a known floor after looking around: back along the trail to the last floor ({reason})"),
                )
            }
            _ => {
                self.decide(
                    now,
                    step,
                    DecisionAction::Exhausted,
                    None,
                    format!("nothing reachable off a known floor, no way back ({reason})"),
                );
                Ok(AgentCommand::Exhausted)
            }
        }
    }

    /// Arrival radius (m) of a move to a view point: the smaller of
    /// `approach.view_arrival_m` and the `NAV_TO_OBJECT` rule's.
    fn view_arrival_m(&self) -> f64 {
        self.config
            .approach
            .view_arrival_m
            .min(self.config.executor.nav_to_object.arrival.radius_m)
    }

    /// The view of object `id` (a semantic-map cluster); the voxel at
    /// `centre` when the cluster is gone.
    fn object_view(&self, id: u64, centre: Point3<f64>) -> Option<ObjectView> {
        let res = self.semantic.resolution();
        match self
            .semantic
            .cluster_voxels(sornav_semantic_map::ClusterId(id))
        {
            Some(keys) => ObjectView::new(keys, res),
            None => ObjectView::new(&[VoxelKey::from_point(&centre, res)], res),
        }
    }

    /// The sensor model of the view check: learned from the frames, or a
    /// camera at the robot's height without a vertical limit before any.
    fn viewer(&self) -> Viewer {
        self.viewer.unwrap_or(Viewer {
            eye_height: self.config.frontier.grid.robot_height,
            half_vfov: None,
        })
    }

    /// Stop in view (issue 20): a confirmed target ends the episode only
    /// from a view point ([`ObjectView::seen_from`]); otherwise the robot
    /// moves to the nearest reachable one, at most
    /// `approach.stop_in_view_attempts` times.
    fn stop_in_view(
        &mut self,
        now: Duration,
        object: ObjectId,
        centre: Point3<f64>,
        pose: &RobotPose,
    ) -> StopView {
        let attempts = self.config.approach.stop_in_view_attempts;
        if attempts == 0 {
            return StopView::Off;
        }
        if let Some((id, m)) = self.executor.active()
            && m.kind
                == (MissionKind::NavToObject {
                    object: ExecObjectId(object.0),
                })
        {
            return StopView::Move(AgentCommand::Continue { mission: Some(id) });
        }
        let bottom = self
            .semantic
            .cluster(sornav_semantic_map::ClusterId(object.0))
            .map_or(centre.z, |c| c.bounds.min.z);
        let Some(level) = self.object_level(bottom) else {
            return StopView::GaveUp("the object's floor is not mapped");
        };
        let Some(view) = self.object_view(object.0, centre) else {
            return StopView::GaveUp("no observed voxel of the object on the map");
        };
        let viewer = self.viewer();
        let on_floor = self
            .frontiers
            .level_map(level)
            .is_some_and(|m| pose.position.z - m.config().grid.floor_z <= FLOOR_TOLERANCE_M);
        let arrival = self.view_arrival_m();
        let here = if on_floor {
            let rule = self.config.approach.view_rule();
            view.sight(&self.semantic, &pose.position, &viewer, &rule)
        } else {
            Sight::Hidden
        };
        let demand = match here {
            Sight::Clear => return StopView::InView,
            Sight::Glimpse if self.stop_moves >= attempts => return StopView::Glimpse,
            Sight::Glimpse => ViewDemand::RequireClear,
            Sight::Hidden if self.stop_moves >= attempts => {
                return StopView::GaveUp(
                    "not at a view point after the allowed view-point approaches",
                );
            }
            Sight::Hidden => ViewDemand::Require,
        };
        let target = ApproachTarget {
            object: &view,
            voxels: &self.semantic,
            viewer,
            arrival_radius_m: arrival,
            demand,
        };
        let approach = approach_waypoint(
            &mut self.frontiers,
            pose.position,
            level,
            &target,
            &self.config.approach,
        );
        if here == Sight::Glimpse && !matches!(approach, Ok(Some(_))) {
            return StopView::Glimpse;
        }
        self.stop_moves += 1;
        let Ok(Some((waypoint, path))) = approach else {
            return StopView::GaveUp("no reachable view point");
        };
        self.stats.stop_in_view_moves += 1;
        let mission = Mission::new(
            MissionKind::NavToObject {
                object: ExecObjectId(object.0),
            },
            waypoint,
        )
        .with_look_at(centre)
        .with_arrival_radius(arrival);
        let (seen, goal) = if here == Sight::Glimpse {
            ("only glimpsed", "a clear view point")
        } else {
            ("not in view", "a view point")
        };
        let reason = format!(
            "object {} confirmed but {seen} from here: move to {goal}",
            object.0
        );
        match self.dispatch_as(
            now,
            DecisionStep::StopInView,
            mission,
            path,
            DecisionAction::NavToObject,
            reason,
        ) {
            Ok(command) => StopView::Move(command),
            Err(_) if here == Sight::Glimpse => StopView::Glimpse,
            Err(_) => StopView::GaveUp("the view-point approach was refused"),
        }
    }

    /// Dispatches `NAV_TO_OBJECT` toward candidate `target_id`, or rejects
    /// the candidate when no approach waypoint is reachable.
    fn dispatch_approach(
        &mut self,
        now: Duration,
        target_id: u64,
        pose: &RobotPose,
    ) -> Result<AgentCommand, AgentError> {
        let gate_centre = self
            .target
            .as_ref()
            .and_then(|t| t.gate.tracker().track(ObjectId(target_id)))
            .map(|t| t.centre);
        let bounds = self
            .semantic
            .cluster(sornav_semantic_map::ClusterId(target_id))
            .map(|c| (c.bounds.min, c.bounds.max));
        let Some(centre) = gate_centre else {
            return Ok(AgentCommand::Continue { mission: None });
        };
        let (lo, hi) = bounds.unwrap_or((centre, centre));
        // The object's level: the floor below its lowest point, unless
        // that is a floor or more below it (see `object_level`).
        let level = self.object_level(lo.z);
        let view = level.and_then(|level| Some((level, self.object_view(target_id, centre)?)));
        let viewer = self.viewer();
        let approach = match &view {
            Some((level, view)) => approach_waypoint(
                &mut self.frontiers,
                pose.position,
                *level,
                &ApproachTarget {
                    object: view,
                    voxels: &self.semantic,
                    viewer,
                    // No reach margin for the arrival radius: a stop short
                    // of the view point is caught by the stop-in-view
                    // check, and the margin cost path length (procedural
                    // seeds 1 and 2: SPL 57.6 / 58.2 without, 55.9 / 55.8
                    // with, same SR).
                    arrival_radius_m: 0.0,
                    demand: ViewDemand::Prefer,
                },
                &self.config.approach,
            )?,
            None => None,
        };
        match approach {
            Some((waypoint, path)) => {
                let mission = Mission::new(
                    MissionKind::NavToObject {
                        object: ExecObjectId(target_id),
                    },
                    waypoint,
                )
                .with_look_at(centre);
                self.dispatch(
                    now,
                    mission,
                    path,
                    DecisionAction::NavToObject,
                    format!("candidate {target_id} has N_obs supporting observations"),
                )
            }
            None if self.unmapped_floor(&lo, &hi) => self.explore_toward_floor(now, target_id, &lo),
            None => Ok(self.reject_candidate(now, target_id, "no reachable approach waypoint")),
        }
    }

    /// Rejects an unreachable candidate (the gate drops it) and keeps the
    /// active mission.
    fn reject_candidate(&mut self, now: Duration, target_id: u64, why: &str) -> AgentCommand {
        self.stats.unreachable_candidates += 1;
        if let Some(state) = self.target.as_mut() {
            let _ = state.gate.on_approach_failed(ObjectId(target_id));
        }
        self.decide(
            now,
            DecisionStep::TargetAccepted,
            DecisionAction::RejectCandidate,
            None,
            format!("candidate {target_id}: {why}"),
        );
        AgentCommand::Continue {
            mission: self.executor.active().map(|(id, _)| id),
        }
    }

    /// An executable path on the agent's own traversability map from `from`
    /// to `to` (horizontal coordinates; `z` is copied from `from`), for
    /// platforms that re-plan a mission's path as the map grows. Both
    /// points are snapped to the nearest traversable cell within the
    /// frontier map's snap radius. `Ok(None)` when they are not connected
    /// on the current map.
    ///
    /// # Errors
    /// [`AgentError::Frontier`] for non-finite or out-of-range points.
    ///
    /// # Complexity
    /// One early-terminating grid search: O(N log N) in the traversable
    /// cells nearer to `from` than `to` is.
    pub fn plan_path(
        &mut self,
        from: &Point3<f64>,
        to: &Point3<f64>,
    ) -> Result<Option<Vec<Point3<f64>>>, AgentError> {
        Ok(self.frontiers.path(from, to)?.map(|edge| edge.path))
    }

    /// Where stairs leave the robot's floor toward a floor the robot does
    /// not use (it cannot climb: the stairs are seen but not planned over),
    /// nearest first. Empty when the robot climbs (stairs are then part of
    /// G_F) or no stair was seen.
    fn stairs_to_unexplored_floors(&self, feet: &Point3<f64>) -> Vec<Point3<f64>> {
        if self.config.frontier.levels.allow_stairs {
            return Vec::new();
        }
        let tol = self.config.frontier.levels.robot_level_tolerance;
        let mut ends: Vec<Point3<f64>> = self
            .frontiers
            .stairs()
            .iter()
            .filter_map(|s| {
                [&s.lower, &s.upper]
                    .into_iter()
                    .find(|e| e.level.is_some() && (e.position.z - feet.z).abs() <= tol)
                    .map(|e| e.position)
            })
            .collect();
        ends.sort_by(|a, b| (a - feet).norm().total_cmp(&(b - feet).norm()));
        ends
    }

    /// Whether an object with bounds `[lo, hi]` stands on a floor the agent
    /// has not mapped: above the highest known floor or below the lowest
    /// by at least half the minimum level separation (seen up or down a
    /// stairwell).
    fn unmapped_floor(&self, lo: &Point3<f64>, hi: &Point3<f64>) -> bool {
        let half = self.config.frontier.levels.min_level_separation / 2.0;
        let floors: Vec<f64> = self.frontiers.levels().map(|l| l.floor_z).collect();
        let top = floors.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let bottom = floors.iter().copied().fold(f64::INFINITY, f64::min);
        self.config.frontier.levels.allow_stairs
            && (lo.z >= top + half || hi.z <= bottom - half || self.object_level(lo.z).is_none())
    }

    /// The level of an object whose lowest observed point is at height
    /// `bottom`: the floor below it
    /// ([`MultiLevelMap::level_containing`]), unless that floor lies at
    /// least `min_level_separation` below (the map's own distance between
    /// two floors): the object then stands on a floor above it that is
    /// not mapped yet (seen up a stairwell), and a view point on the
    /// floor below, under the object, would be no view point at all.
    /// Without stairs every object is on the one level.
    fn object_level(&self, bottom: f64) -> Option<LevelId> {
        let level = self.frontiers.level_containing(bottom)?;
        if !self.config.frontier.levels.allow_stairs {
            return Some(level);
        }
        let separation = self.config.frontier.levels.min_level_separation;
        self.frontiers
            .levels()
            .find(|l| l.id == level)
            .filter(|l| bottom - l.floor_z < separation)
            .map(|l| l.id)
    }

    /// A candidate on an unmapped floor is approached over the stairs: the
    /// open stair end whose height is nearest to the object is explored
    /// (the candidate is kept). When no stair leads there, the candidate is
    /// rejected like any unreachable one.
    fn explore_toward_floor(
        &mut self,
        now: Duration,
        target_id: u64,
        lo: &Point3<f64>,
    ) -> Result<AgentCommand, AgentError> {
        let graph = self.frontiers.graph();
        let best = graph
            .nodes()
            .filter(|n| self.frontiers.is_stair_frontier(n.id) && !self.excluded.contains(&n.id))
            .filter(|n| graph.cost(NodeId::Robot, NodeId::Frontier(n.id)).is_some())
            .min_by(|a, b| (a.z - lo.z).abs().total_cmp(&(b.z - lo.z).abs()))
            .map(|n| n.id);
        let mission = best.and_then(|id| explore_mission(graph, id));
        match mission {
            Some(mission) => {
                if self
                    .executor
                    .active()
                    .is_some_and(|(_, m)| m.kind == mission.kind)
                {
                    return Ok(self.keep_going(
                        now,
                        DecisionStep::TargetAccepted,
                        format!("candidate {target_id} is on another floor: climbing the stairs"),
                    ));
                }
                self.dispatch_as(
                    now,
                    DecisionStep::TargetAccepted,
                    mission,
                    Vec::new(),
                    DecisionAction::Explore,
                    format!("candidate {target_id} is on another floor: taking the stairs to it"),
                )
            }
            None => Ok(self.reject_candidate(
                now,
                target_id,
                "on another floor and no stair leads there",
            )),
        }
    }

    /// Objects of the semantic map with their normalised categories.
    fn object_summaries(&self) -> Vec<ObjectSummary> {
        self.semantic
            .clusters()
            .filter_map(|c| {
                let label = self.categories.get(&c.label)?.clone()?;
                Some(ObjectSummary {
                    label,
                    support: c.support,
                    centre: c.centre,
                    level: self.frontiers.level_containing(c.bounds.min.z).map(|l| l.0),
                })
            })
            .collect()
    }

    /// Everything needed to draw the agent's state: occupancy, objects,
    /// frontiers, clusters, route, active mission, gate, last decision.
    ///
    /// # Complexity
    /// O(grid cells + objects + frontier cells + clusters).
    pub fn snapshot(&self) -> AgentSnapshot {
        AgentSnapshot {
            target: self.target.as_ref().map(|t| t.target.clone()),
            pose: self.pose,
            at: self.last_step,
            occupancy: self
                .frontiers
                .level_map(self.current_level().unwrap_or_default())
                .map(|m| OccupancyRaster::from_grid(m.grid()))
                .unwrap_or_default(),
            objects: self
                .semantic
                .clusters()
                .map(|c| ObjectRecord {
                    id: c.id.0,
                    label: self.categories.get(&c.label).cloned().flatten(),
                    support: c.support,
                    centre: c.centre,
                    min: c.bounds.min,
                    max: c.bounds.max,
                    observations: c.observations,
                })
                .collect(),
            frontiers: self.frontiers.graph().nodes().cloned().collect(),
            clusters: self.clusters.clone(),
            route: self.route.clone(),
            active_mission: self.executor.active().map(|(id, m)| (id, m.clone())),
            relocation: self.relocation.clone(),
            gate_phase: self.target.as_ref().map(|t| t.gate.phase()),
            candidates: self
                .target
                .as_ref()
                .map(|t| t.gate.tracker().tracks().cloned().collect())
                .unwrap_or_default(),
            excluded_frontiers: self.excluded.iter().copied().collect(),
            last_outcome: self.last_outcome.clone(),
            last_decision: self.last_decision.clone(),
            stats: self.stats,
        }
    }
}
