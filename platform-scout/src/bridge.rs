//! The robot node's logic as a pure state machine: decoded messages in,
//! messages to publish out. No DDS here, so all of it is testable with plain
//! function calls; [`crate::node`] only moves messages between this and
//! ROS 2.
//!
//! * **Odometry** (`/state_estimation`) gives the base pose (through the
//!   LiDAR extrinsic when the odometry is the sensor's) and the sensor
//!   origin. The agent is created at the first odometry message, with the
//!   floor at the base height unless `inputs.floor_z` is set. A message
//!   whose header stamp is more than `rates.odometry_max_age_s` older, or
//!   `rates.odometry_max_future_s` newer, than the wall clock on receipt
//!   (a delayed, replayed or zero-stamped pose; clock skew) is rejected
//!   ([`BridgeError::StaleOdometry`], [`BridgeError::FutureOdometry`]) and
//!   its pose is not used.
//! * **Clouds**: `/semantic_scan` points (with their `label`) are buffered;
//!   `/registered_scan` returns and `/terrain_map` cells (re-projected to the
//!   floor plus their height above ground) are buffered as *unlabelled*
//!   returns. At `observe_hz` the buffers become at most two observations
//!   from the same pose: a [`CloudObservation`] of the labelled points
//!   (semantic map, target gate and occupancy grid) and an
//!   [`OccupancyObservation`] of the unlabelled returns (occupancy grid
//!   only). So the grid sees every return, and a 360-degree scan never
//!   dilutes the label evidence of voxels the segmentation saw, nor counts
//!   as a detection or a miss of a target candidate.
//! * **Agent**: [`Agent::step`] runs at `control_hz` (1 Hz); its executor
//!   computes arrival from the odometry pose (the CMU stack has no "reached"
//!   signal). Every dispatched mission's waypoint is published on
//!   `/way_point` and re-published every `waypoint_republish_s`; `Verify`,
//!   `Stop`, `Exhausted` and `FloorExhausted` hold the robot (a waypoint at
//!   its own position).
//! * **Floors**: a robot that cannot climb (`robot.can_climb_stairs =
//!   false`) never plans over stairs; when its floor is exhausted while
//!   stairs it has seen lead to another floor, the state is
//!   [`NodeState::FloorExhausted`] with the stairs in the status and one log
//!   line per change: "not found on this floor; stairs at (x, y, z) lead to
//!   an unexplored floor". Re-checked at every step like `exhausted`.
//! * **Targets** (`/sornav/target`) switch the agent's target and keep its
//!   maps, so targets can follow one another; a confirmed target is kept in
//!   the status.
//! * **Start** publishes the `/joy` message that puts the CMU local planner
//!   in autonomy mode (`axes[2] = -1`, `axes[4] = 1`) and releases `/stop`;
//!   **shutdown** holds the robot and publishes `/stop = 2`.
//! * **Relay** (optional): the path follower's `TwistStamped` becomes the
//!   Scout driver's `Twist`, clamped to the configured speed limits, with a
//!   watchdog that sends one zero twist when commands stop.

use std::collections::{BTreeMap, VecDeque};
use std::time::Duration;

use nalgebra::{Isometry3, Point3, Translation3};
use serde::{Deserialize, Serialize};
use sornav::executor::{Mission, MissionId, RobotPose};
use sornav::semantic_map::LabeledPoint;
use sornav::{
    Agent, AgentCommand, AgentError, AgentStats, CloudObservation, DecisionStep, Observation,
    OccupancyObservation, Sensor,
};

use crate::config::{ConfigError, OdometryFrame, ScoutConfig};
use crate::markers::markers_from_snapshot;
use crate::msg::{
    Header, Int8, Joy, MarkerArray, Odometry, Path, Point, PointCloud2, PointStamped, Pose,
    PoseStamped, Quaternion, RosString, Time, Twist, TwistStamped, Vector3,
};
use crate::pointcloud::{CloudError, CloudView};
use crate::streams::{SampleSource, Silence, StreamMonitor, StreamStatus};

/// A message the node should publish.
#[derive(Debug, Clone, PartialEq)]
pub enum Outgoing {
    /// `/way_point`.
    WayPoint(PointStamped),
    /// `/joy`.
    Joy(Joy),
    /// `/stop`.
    Stop(Int8),
    /// `/sornav/status` (JSON of [`Status`]).
    Status(RosString),
    /// `/sornav/markers`.
    Markers(MarkerArray),
    /// `/sornav/path`.
    Path(Path),
    /// Relay output (the Scout driver's `Twist`).
    CmdVel(Twist),
}

/// Errors of the bridge's inputs. Each rejection is counted in
/// [`BridgeStats`] and by cause in [`Status::rejections`], logged at warn
/// (at most once per [`REJECTION_WARN_INTERVAL`] and cause) and reported as
/// `last_error` in the status; none stops the node.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    /// The configuration is invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A cloud's layout is malformed or lacks a needed field.
    #[error("malformed cloud on {topic}: {source}")]
    Cloud {
        /// The topic.
        topic: &'static str,
        /// Why.
        #[source]
        source: CloudError,
    },
    /// A message is in the wrong frame.
    #[error("{topic} is in frame `{got}`, expected `{expected}`")]
    Frame {
        /// The topic.
        topic: &'static str,
        /// Expected frame.
        expected: String,
        /// The message's frame.
        got: String,
    },
    /// The odometry pose is not finite or its quaternion is degenerate.
    #[error("odometry pose is not finite or its orientation is degenerate")]
    BadOdometry,
    /// The odometry header stamp is older than `rates.odometry_max_age_s`
    /// when received (a delayed or replayed message, or a zero stamp).
    #[error("odometry stamp is {age_s:.3} s old, more than rates.odometry_max_age_s = {max_s} s")]
    StaleOdometry {
        /// Age of the stamp on receipt (s).
        age_s: f64,
        /// The tolerance (s).
        max_s: f64,
    },
    /// The odometry header stamp is further ahead of the node's clock than
    /// `rates.odometry_max_future_s` (clock skew between computers).
    #[error(
        "odometry stamp is {ahead_s:.3} s in the future, more than rates.odometry_max_future_s = {max_s} s"
    )]
    FutureOdometry {
        /// How far ahead of the receiving clock the stamp is (s).
        ahead_s: f64,
        /// The tolerance (s).
        max_s: f64,
    },
    /// A cloud arrived before any odometry (no sensor origin yet).
    #[error("cloud on {0} before the first odometry message")]
    NoOdometry(&'static str),
    /// The target request is blank.
    #[error("blank target request")]
    BlankTarget,
    /// The agent refused something (unknown target, bad observation, ...).
    #[error(transparent)]
    Agent(#[from] AgentError),
}

impl BridgeError {
    /// A short stable name of the error's kind (with the topic where it
    /// has one), under which rejections are counted in
    /// [`Status::rejections`]: `frame:<topic>`, `cloud:<topic>`,
    /// `bad_odometry`, `stale_odometry`, `future_odometry`,
    /// `no_odometry:<topic>`, `blank_target`, `agent`, `config`.
    pub fn cause(&self) -> String {
        match self {
            BridgeError::Config(_) => "config".into(),
            BridgeError::Cloud { topic, .. } => format!("cloud:{topic}"),
            BridgeError::Frame { topic, .. } => format!("frame:{topic}"),
            BridgeError::BadOdometry => "bad_odometry".into(),
            BridgeError::StaleOdometry { .. } => "stale_odometry".into(),
            BridgeError::FutureOdometry { .. } => "future_odometry".into(),
            BridgeError::NoOdometry(topic) => format!("no_odometry:{topic}"),
            BridgeError::BlankTarget => "blank_target".into(),
            BridgeError::Agent(_) => "agent".into(),
        }
    }
}

/// What the node is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NodeState {
    /// No odometry yet (or it is stale): holding.
    WaitingForOdometry,
    /// No target requested yet.
    Idle,
    /// Searching for the target.
    Searching,
    /// The target was confirmed; waiting for the next request.
    Confirmed,
    /// No reachable frontier and no confirmed target: holding, while the
    /// agent keeps observing and is re-stepped at the control rate (the
    /// search resumes by itself when a frontier or a candidate appears), or
    /// the next request.
    Exhausted,
    /// Like [`Exhausted`](Self::Exhausted), on the robot's floor, while
    /// stairs seen from it lead to a floor the robot (which cannot climb,
    /// `robot.can_climb_stairs = false`) has not explored: "not found on
    /// this floor; stairs at (x, y, z) lead to an unexplored floor"
    /// ([`Status::stairs`], [`Status::note`]). Holding and re-checked at
    /// every step like `exhausted`.
    FloorExhausted,
    /// Shut down.
    Stopped,
}

/// Counters of the bridge.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct BridgeStats {
    /// Odometry messages used.
    pub odometry: u64,
    /// Semantic clouds used.
    pub semantic_clouds: u64,
    /// Registered scans used.
    pub registered_scans: u64,
    /// Terrain maps used.
    pub terrain_maps: u64,
    /// Messages rejected (malformed cloud, wrong frame, bad odometry, blank
    /// or unknown request); by cause in [`Status::rejections`].
    pub rejected_messages: u64,
    /// Samples that failed to decode before reaching the bridge (for
    /// example a truncated `Odometry`), reported by the node through
    /// [`Bridge::on_undecodable`].
    #[serde(default)]
    pub undecodable_samples: u64,
    /// Clouds dropped because no odometry had arrived yet (no sensor origin
    /// to carve free space from): a start-up race between topics, not a
    /// malformed message, so not counted in `rejected_messages`.
    #[serde(default)]
    pub clouds_before_odometry: u64,
    /// Cloud points skipped (non-finite coordinate or bad label).
    pub skipped_points: u64,
    /// Buffered points dropped by the per-observation cap (whole older
    /// clouds).
    pub dropped_points: u64,
    /// Points thinned out (by a stride) of a single cloud above the
    /// per-observation cap.
    #[serde(default)]
    pub thinned_points: u64,
    /// Observations given to the agent (a labelled cloud and an
    /// occupancy-only frame count as two).
    pub observations: u64,
    /// Observations the agent refused.
    pub refused_observations: u64,
    /// Agent steps.
    pub steps: u64,
    /// Way points published (including re-publications).
    pub waypoints_published: u64,
    /// Relayed velocity commands.
    pub relayed: u64,
}

/// The active mission as reported in the status.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionStatus {
    /// Mission id.
    pub id: u64,
    /// `explore`, `relocate` or `nav_to_object`.
    pub kind: String,
    /// Waypoint (map frame).
    pub waypoint: [f64; 3],
}

/// The last decision as reported in the status.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecisionStatus {
    /// Clock reading (s since the node started).
    pub at_s: f64,
    /// The rule that decided (serialised `policy_evaluated`,
    /// `target_confirmed`, ...).
    pub step: DecisionStep,
    /// What was done (serialised `explore`, `relocate`, `stop`, ...).
    pub action: sornav::DecisionAction,
    /// Why.
    pub reason: String,
}

/// A confirmed target.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConfirmedTarget {
    /// Category searched.
    pub category: String,
    /// The request as given.
    pub request: String,
    /// Semantic-map object id.
    pub object: u64,
    /// Object centre (map frame).
    pub centre: [f64; 3],
    /// When (s since the node started).
    pub at_s: f64,
}

/// The JSON document published on `/sornav/status`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Status {
    /// s since the node started.
    pub time_s: f64,
    /// What the node is doing.
    pub state: NodeState,
    /// Current target category.
    pub target: Option<String>,
    /// Current request text.
    pub request: Option<String>,
    /// The active mission.
    pub active_mission: Option<MissionStatus>,
    /// The last decision and its reason.
    pub last_decision: Option<DecisionStatus>,
    /// Targets confirmed so far, oldest first.
    pub confirmed: Vec<ConfirmedTarget>,
    /// Base pose `[x, y, z, yaw]`.
    pub pose: Option<[f64; 4]>,
    /// Object clusters in the semantic map.
    pub objects: usize,
    /// Frontiers in the frontier map.
    pub frontiers: usize,
    /// Agent counters (maps are never reset between targets, so
    /// `observations` only grows).
    pub agent: Option<AgentStats>,
    /// Bridge counters.
    pub bridge: BridgeStats,
    /// The last input error.
    pub last_error: Option<String>,
    /// Rejected messages and undecodable samples by cause
    /// ([`BridgeError::cause`], `undecodable:<topic>`), since the start.
    #[serde(default)]
    pub rejections: BTreeMap<String, u64>,
    /// In `floor_exhausted`: where each stair leading to an unexplored
    /// floor starts on the robot's floor (map frame, m), nearest first;
    /// empty otherwise.
    #[serde(default)]
    pub stairs: Vec<[f64; 3]>,
    /// Health of each input stream by topic (`odometry`, `semantic_scan`,
    /// `registered_scan`, `terrain_map`), from [`Bridge::on_delivery`]:
    /// samples received, samples lost before decoding (gaps in the
    /// writers' sequence numbers), silences ([`crate::streams`]). DDS does
    /// not report such losses; they show only here.
    #[serde(default)]
    pub streams: BTreeMap<String, StreamStatus>,
    /// A sentence for operators about the outcome (in `floor_exhausted`:
    /// "not found on this floor; stairs at (x, y, z) lead to an unexplored
    /// floor"), `None` otherwise.
    #[serde(default)]
    pub note: Option<String>,
}

/// The operator's sentence for a floor exhausted with `stairs` leading to
/// unexplored floors: "not found on this floor; stairs at (x, y, z) lead to
/// an unexplored floor" (map frame, metres, 2 decimals; every stair, joined
/// by `and`).
pub fn floor_exhausted_note(stairs: &[[f64; 3]]) -> String {
    let at: Vec<String> = stairs
        .iter()
        .map(|p| format!("({:.2}, {:.2}, {:.2})", p[0], p[1], p[2]))
        .collect();
    format!(
        "not found on this floor; stairs at {} lead to an unexplored floor",
        at.join(" and ")
    )
}

/// The robot pose from one odometry message.
#[derive(Debug, Clone, Copy, PartialEq)]
struct OdomSample {
    base: Isometry3<f64>,
    sensor: Point3<f64>,
    at: Duration,
}

/// The robot node's logic; see the [module docs](self).
pub struct Bridge {
    config: ScoutConfig,
    agent: Option<Agent>,
    pending_target: Option<String>,
    state: NodeState,
    /// The state to return to when odometry is fresh again.
    paused: Option<NodeState>,
    odom: Option<OdomSample>,
    labelled: VecDeque<Vec<LabeledPoint>>,
    unlabelled: VecDeque<Vec<Point3<f64>>>,
    last_observe: Option<Duration>,
    last_step: Option<Duration>,
    last_waypoint: Option<Duration>,
    last_markers: Option<Duration>,
    /// The last relayed command, until the watchdog has sent its zero twist.
    last_cmd_vel: Option<Duration>,
    holding: bool,
    confirmed: Vec<ConfirmedTarget>,
    /// In `floor_exhausted`: the stairs leading to unexplored floors.
    stairs: Vec<[f64; 3]>,
    /// In `floor_exhausted`: the operator's sentence (also the last one
    /// logged, so that it is logged once per change).
    note: Option<String>,
    stats: BridgeStats,
    last_error: Option<String>,
    /// Rejections by cause ([`BridgeError::cause`]).
    rejections: BTreeMap<String, Rejections>,
    /// Health of each input stream (gaps, silence), by topic.
    streams: BTreeMap<&'static str, Stream>,
}

/// One input stream's monitor and its rate-limited gap warning.
#[derive(Debug, Clone, Default)]
struct Stream {
    monitor: StreamMonitor,
    warn: WarnLimit,
}

/// Rejections of one cause, and their rate-limited warning.
#[derive(Debug, Clone, Copy, Default)]
struct Rejections {
    count: u64,
    warn: WarnLimit,
}

/// A warning logged at most once per [`REJECTION_WARN_INTERVAL`].
#[derive(Debug, Clone, Copy, Default)]
struct WarnLimit {
    last: Option<Duration>,
    /// Events since the last warning, not logged.
    suppressed: u64,
}

impl WarnLimit {
    /// Whether to log an event at `now`: `Some(events not logged since the
    /// last warning)` when the interval has passed, else `None` (counted as
    /// not logged).
    fn allow(&mut self, now: Duration) -> Option<u64> {
        if self
            .last
            .is_none_or(|t| now.saturating_sub(t) >= REJECTION_WARN_INTERVAL)
        {
            self.last = Some(now);
            Some(std::mem::take(&mut self.suppressed))
        } else {
            self.suppressed += 1;
            None
        }
    }
}

/// Least time between two warnings of one rejection cause: a burst of bad
/// messages logs one line per cause and interval, and the status counts
/// every one ([`Status::rejections`]).
pub const REJECTION_WARN_INTERVAL: Duration = Duration::from_secs(5);

impl std::fmt::Debug for Bridge {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bridge")
            .field("state", &self.state)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

fn secs(d: Duration) -> f64 {
    d.as_secs_f64()
}

/// `a - b` in seconds (exact in integer nanoseconds, then converted; a
/// malformed `nanosec` of 1e9 or more is taken as it is).
fn stamp_difference_s(a: Time, b: Time) -> f64 {
    let ns = |t: Time| i64::from(t.sec) * 1_000_000_000 + i64::from(t.nanosec);
    (ns(a) - ns(b)) as f64 / 1e9
}

fn due(last: Option<Duration>, now: Duration, period_s: f64) -> bool {
    last.is_none_or(|t| now.saturating_sub(t).as_secs_f64() + 1e-9 >= period_s)
}

impl Bridge {
    /// A bridge for `config` (validated).
    ///
    /// # Errors
    /// [`BridgeError::Config`].
    pub fn new(config: ScoutConfig) -> Result<Self, BridgeError> {
        config.validate()?;
        let pending_target = config.initial_target.clone();
        Ok(Self {
            config,
            agent: None,
            pending_target,
            state: NodeState::WaitingForOdometry,
            paused: None,
            odom: None,
            labelled: VecDeque::new(),
            unlabelled: VecDeque::new(),
            last_observe: None,
            last_step: None,
            last_waypoint: None,
            last_markers: None,
            last_cmd_vel: None,
            holding: false,
            confirmed: Vec::new(),
            stairs: Vec::new(),
            note: None,
            stats: BridgeStats::default(),
            last_error: None,
            rejections: BTreeMap::new(),
            streams: BTreeMap::new(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &ScoutConfig {
        &self.config
    }

    /// The agent (after the first odometry message).
    pub fn agent(&self) -> Option<&Agent> {
        self.agent.as_ref()
    }

    /// What the node is doing.
    pub fn state(&self) -> NodeState {
        self.state
    }

    /// Counters.
    pub fn stats(&self) -> BridgeStats {
        self.stats
    }

    /// Targets confirmed so far.
    pub fn confirmed(&self) -> &[ConfirmedTarget] {
        &self.confirmed
    }

    /// A header in the map frame, stamped with the wall clock.
    fn header(&self) -> Header {
        Header::new(Time::now(), self.config.ros.map_frame.clone())
    }

    /// The `/joy` message that switches the CMU local planner and path
    /// follower to autonomy mode: `axes[2] = -1` (autonomy), `axes[4] = 1`
    /// (full autonomy speed; 0 would stop the robot), `axes[5] = 1`
    /// (obstacle checking on), eight axes and eleven buttons like the CMU
    /// RViz waypoint tool.
    pub fn autonomy_joy() -> Joy {
        Joy {
            header: Header::new(Time::now(), "sornav"),
            axes: vec![0.0, 0.0, -1.0, 0.0, 1.0, 1.0, 0.0, 0.0],
            buttons: vec![0; 11],
        }
    }

    /// Messages to publish at start: autonomy mode, release `/stop`, status.
    pub fn start(&mut self, now: Duration) -> Vec<Outgoing> {
        vec![
            Outgoing::Joy(Self::autonomy_joy()),
            Outgoing::Stop(Int8 { data: 0 }),
            self.status_message(now),
        ]
    }

    /// Messages to publish at shutdown: hold at the current pose, `/stop = 2`
    /// (stop translation and rotation; the next start releases it), a zero
    /// twist when relaying, and the final status.
    pub fn shutdown(&mut self, now: Duration) -> Vec<Outgoing> {
        self.state = NodeState::Stopped;
        let mut out = Vec::new();
        if let Some(w) = self.hold_waypoint() {
            out.push(w);
        }
        out.push(Outgoing::Stop(Int8 { data: 2 }));
        if self.config.relay.enabled {
            out.push(Outgoing::CmdVel(Twist::default()));
        }
        out.push(self.status_message(now));
        out
    }

    fn reject(&mut self, e: BridgeError, now: Duration) -> BridgeError {
        self.stats.rejected_messages += 1;
        let message = e.to_string();
        self.note_rejection(e.cause(), &message, now);
        self.last_error = Some(message);
        e
    }

    /// Counts a rejection under `cause` and logs it at warn, at most once
    /// per [`REJECTION_WARN_INTERVAL`] and cause (with the number of
    /// rejections of that cause not logged since the last warning).
    fn note_rejection(&mut self, cause: String, message: &str, now: Duration) {
        let r = self.rejections.entry(cause).or_default();
        r.count += 1;
        if let Some(not_logged) = r.warn.allow(now) {
            tracing::warn!(total = r.count, not_logged, "message rejected: {message}");
        }
    }

    /// A sample of `topic` was taken from DDS at `now`, from `source` (its
    /// writer and sequence number; `None` when unknown). Call it for every
    /// sample taken, before the message handler ([`crate::node`] does):
    /// samples lost before decoding, which DDS does not report, are
    /// counted from gaps in each writer's numbering and logged at warn
    /// (rate-limited per topic), and silent streams are detected; see
    /// [`crate::streams`] and [`Status::streams`].
    pub fn on_delivery(
        &mut self,
        topic: &'static str,
        source: Option<SampleSource>,
        now: Duration,
    ) {
        let stream = self.streams.entry(topic).or_default();
        let (gap, silence) = stream.monitor.on_sample(source, now);
        if let Some(Silence::Ended { lasted_s }) = silence {
            tracing::info!(
                topic,
                "{topic}: samples again after {lasted_s:.1} s of silence"
            );
        }
        if let Some(gap) = gap {
            let total = stream.monitor.status(now).lost;
            if let Some(gaps_not_logged) = stream.warn.allow(now) {
                tracing::warn!(
                    topic,
                    total_lost = total,
                    gaps_not_logged,
                    "{topic}: {} sample(s) lost before decoding (writer's sequence {} -> {}); \
                     DDS does not report it: large clouds on a best-effort reader lose \
                     fragments, or the reader's history overflowed",
                    gap.missing,
                    gap.after,
                    gap.next
                );
            }
        }
    }

    /// Streams that delivered samples and then fell silent: counted and
    /// logged at warn once per silence.
    fn check_streams(&mut self, now: Duration) {
        for (topic, stream) in &mut self.streams {
            if let Some(Silence::Began { for_s }) = stream.monitor.check_silence(now) {
                tracing::warn!(
                    topic,
                    "{topic}: no sample for {for_s:.1} s: the publisher stopped, or its \
                     samples are lost before decoding (DDS does not report it; clouds of \
                     more than about 10 MB on a best-effort reader are)"
                );
            }
        }
    }

    /// A sample on `topic` that failed to decode (CDR) before reaching the
    /// bridge: counted in [`BridgeStats::undecodable_samples`] and under the
    /// cause `undecodable:<topic>`, logged like a rejection, and reported
    /// as `last_error`.
    pub fn on_undecodable(&mut self, topic: &'static str, error: &str, now: Duration) {
        self.stats.undecodable_samples += 1;
        let message = format!("{topic}: a sample failed to decode: {error}");
        self.note_rejection(format!("undecodable:{topic}"), &message, now);
        self.last_error = Some(message);
    }

    fn check_frame(
        &mut self,
        topic: &'static str,
        header: &Header,
        now: Duration,
    ) -> Result<(), BridgeError> {
        let expected = &self.config.ros.map_frame;
        if !header.frame_id.is_empty() && header.frame_id.trim_start_matches('/') != expected {
            let e = BridgeError::Frame {
                topic,
                expected: expected.clone(),
                got: header.frame_id.clone(),
            };
            return Err(self.reject(e, now));
        }
        Ok(())
    }

    /// `/state_estimation`, received now: [`on_odometry_at`](Self::on_odometry_at)
    /// with the wall clock ([`Time::now`]) as the time of receipt.
    ///
    /// # Errors
    /// As [`on_odometry_at`](Self::on_odometry_at).
    pub fn on_odometry(&mut self, msg: &Odometry, now: Duration) -> Result<(), BridgeError> {
        self.on_odometry_at(msg, now, Time::now())
    }

    /// `/state_estimation`, received at wall-clock time `received` (the
    /// clock its header stamp is compared with; `now` is the node's
    /// monotonic clock, as everywhere in the bridge).
    ///
    /// # Errors
    /// [`BridgeError::Frame`]; [`BridgeError::StaleOdometry`] when the
    /// stamp is more than `rates.odometry_max_age_s` older than `received`
    /// (a zero stamp is); [`BridgeError::FutureOdometry`] when it is more
    /// than `rates.odometry_max_future_s` ahead (neither when
    /// `rates.check_odometry_stamps` is false); [`BridgeError::BadOdometry`].
    /// Each is counted by cause and the pose is not used.
    pub fn on_odometry_at(
        &mut self,
        msg: &Odometry,
        now: Duration,
        received: Time,
    ) -> Result<(), BridgeError> {
        self.check_frame("odometry", &msg.header, now)?;
        let age_s = stamp_difference_s(received, msg.header.stamp);
        let rates = self.config.rates;
        if rates.check_odometry_stamps && age_s > rates.odometry_max_age_s {
            let e = BridgeError::StaleOdometry {
                age_s,
                max_s: rates.odometry_max_age_s,
            };
            return Err(self.reject(e, now));
        }
        if rates.check_odometry_stamps && -age_s > rates.odometry_max_future_s {
            let e = BridgeError::FutureOdometry {
                ahead_s: -age_s,
                max_s: rates.odometry_max_future_s,
            };
            return Err(self.reject(e, now));
        }
        let p = msg.pose.pose.position;
        let Some(q) = msg.pose.pose.orientation.to_unit() else {
            return Err(self.reject(BridgeError::BadOdometry, now));
        };
        if ![p.x, p.y, p.z].iter().all(|c| c.is_finite()) {
            return Err(self.reject(BridgeError::BadOdometry, now));
        }
        let odom = Isometry3::from_parts(Translation3::new(p.x, p.y, p.z), q);
        let lidar = self.config.sensors.lidar.isometry();
        let base = match self.config.sensors.odometry_frame {
            OdometryFrame::Lidar => odom * lidar.inverse(),
            OdometryFrame::Base => odom,
        };
        let sensor = Point3::from((base * lidar).translation.vector);
        self.odom = Some(OdomSample {
            base,
            sensor,
            at: now,
        });
        self.stats.odometry += 1;
        if self.agent.is_none() {
            let floor = self
                .config
                .inputs
                .floor_z
                .unwrap_or(base.translation.vector.z);
            let config = self.config.agent_config(floor)?;
            self.agent = Some(Agent::new(config)?);
            self.state = NodeState::Idle;
            if let Some(request) = self.pending_target.take() {
                // A bad initial target is reported; the node stays idle.
                let _ = self.apply_target(&request, now);
            }
        } else if self.state == NodeState::WaitingForOdometry {
            self.resume();
        }
        Ok(())
    }

    /// Odometry is fresh again: back to the state it interrupted (a confirmed
    /// target stays confirmed, an exhausted search keeps re-checking), or
    /// searching when a target was requested meanwhile.
    fn resume(&mut self) {
        self.state = self.paused.take().unwrap_or_else(|| {
            if self.agent.as_ref().is_some_and(|a| a.target().is_some()) {
                NodeState::Searching
            } else {
                NodeState::Idle
            }
        });
    }

    fn base_pose(&self) -> Option<RobotPose> {
        let o = self.odom?;
        let t = o.base.translation.vector;
        let (_, _, yaw) = o.base.rotation.euler_angles();
        Some(RobotPose::new(Point3::new(t.x, t.y, t.z), yaw))
    }

    fn odometry_fresh(&self, now: Duration) -> bool {
        self.odom.is_some_and(|o| {
            now.saturating_sub(o.at).as_secs_f64() <= self.config.rates.odometry_timeout_s
        })
    }

    /// Keeps the buffered points within `inputs.max_points_per_observation`:
    /// drops the oldest cloud of the larger buffer while it holds several,
    /// and thins a buffer's single cloud by a stride (every k-th point)
    /// instead of dropping it, so that one cloud above the cap still
    /// reaches the agent, spread over its whole extent.
    fn trim_buffers(&mut self) {
        let cap = self.config.inputs.max_points_per_observation;
        loop {
            let l: usize = self.labelled.iter().map(Vec::len).sum();
            let u: usize = self.unlabelled.iter().map(Vec::len).sum();
            if l + u <= cap {
                break;
            }
            let excess = l + u - cap;
            let from_labelled = l >= u;
            let clouds = if from_labelled {
                self.labelled.len()
            } else {
                self.unlabelled.len()
            };
            if clouds > 1 {
                // Drop the oldest cloud of the larger buffer. Empty clouds
                // (every point skipped) are dropped like any other.
                let n = if from_labelled {
                    self.labelled.pop_front().map_or(0, |c| c.len())
                } else {
                    self.unlabelled.pop_front().map_or(0, |c| c.len())
                };
                self.stats.dropped_points += n as u64;
                continue;
            }
            // The larger buffer holds one cloud (of at least half the
            // points): thin it to what the cap leaves, or to half when the
            // other buffer alone exceeds the cap (that one is thinned next).
            let removed = if from_labelled {
                self.labelled.front_mut().map_or(0, |c| thin(c, excess))
            } else {
                self.unlabelled.front_mut().map_or(0, |c| thin(c, excess))
            };
            if removed == 0 {
                break;
            }
            self.stats.thinned_points += removed as u64;
        }
    }

    /// Checks the frame of the cloud on `topic` and that odometry arrived,
    /// then validates its layout and decodes it with `decode`; every error
    /// is rejected (counted) with the topic, except a cloud before the first
    /// odometry (counted in `clouds_before_odometry`).
    fn decode_cloud<T>(
        &mut self,
        topic: &'static str,
        msg: &PointCloud2,
        now: Duration,
        decode: impl FnOnce(&CloudView<'_>) -> Result<T, CloudError>,
    ) -> Result<T, BridgeError> {
        self.check_frame(topic, &msg.header, now)?;
        if self.odom.is_none() {
            self.stats.clouds_before_odometry += 1;
            return Err(BridgeError::NoOdometry(topic));
        }
        CloudView::new(msg)
            .and_then(|view| decode(&view))
            .map_err(|source| self.reject(BridgeError::Cloud { topic, source }, now))
    }

    /// `/semantic_scan`: points with a `label` channel. Returns the number
    /// of points buffered.
    ///
    /// # Errors
    /// [`BridgeError::Frame`], [`BridgeError::NoOdometry`],
    /// [`BridgeError::Cloud`] (counted; the cloud is dropped).
    pub fn on_semantic_scan(
        &mut self,
        msg: &PointCloud2,
        now: Duration,
    ) -> Result<usize, BridgeError> {
        let field = self.config.inputs.label_field.clone();
        let decoded = self.decode_cloud("semantic_scan", msg, now, |view| {
            view.labelled_points(&field)
        })?;
        self.stats.semantic_clouds += 1;
        self.stats.skipped_points += (decoded.non_finite + decoded.bad_label) as u64;
        let n = decoded.points.len();
        self.labelled.push_back(decoded.points);
        self.trim_buffers();
        Ok(n)
    }

    /// `/registered_scan`: unlabelled returns for the occupancy grid (ignored
    /// when `inputs.use_registered_scan` is false). Returns the number of
    /// points buffered.
    ///
    /// # Errors
    /// As [`on_semantic_scan`](Self::on_semantic_scan).
    pub fn on_registered_scan(
        &mut self,
        msg: &PointCloud2,
        now: Duration,
    ) -> Result<usize, BridgeError> {
        if !self.config.inputs.use_registered_scan {
            return Ok(0);
        }
        let (points, skipped) =
            self.decode_cloud("registered_scan", msg, now, |view| view.xyz())?;
        self.stats.registered_scans += 1;
        self.stats.skipped_points += skipped as u64;
        let n = points.len();
        self.unlabelled.push_back(points);
        self.trim_buffers();
        Ok(n)
    }

    /// `/terrain_map`: cells with their height above ground (intensity),
    /// re-projected to `floor + height` so that the grid's floor / obstacle
    /// bands apply to the height above the local ground (ignored when
    /// `inputs.use_terrain_map` is false). Returns the number of points
    /// buffered.
    ///
    /// # Errors
    /// As [`on_semantic_scan`](Self::on_semantic_scan).
    pub fn on_terrain_map(
        &mut self,
        msg: &PointCloud2,
        now: Duration,
    ) -> Result<usize, BridgeError> {
        if !self.config.inputs.use_terrain_map {
            return Ok(0);
        }
        let field = self.config.inputs.terrain_height_field.clone();
        let decoded =
            self.decode_cloud("terrain_map", msg, now, |view| view.points_with(&field))?;
        let floor = self
            .agent
            .as_ref()
            .map_or(0.0, |a| a.config().frontier.grid.floor_z);
        self.stats.terrain_maps += 1;
        self.stats.skipped_points += decoded.non_finite as u64;
        let n = decoded.points.len();
        self.unlabelled.push_back(
            decoded
                .points
                .into_iter()
                .map(|(p, h)| Point3::new(f64::from(p.x), f64::from(p.y), floor + f64::from(h)))
                .collect(),
        );
        self.trim_buffers();
        Ok(n)
    }

    /// `/sornav/target`: a new request ("find the television"). The maps are
    /// kept. A request for the category already being searched for
    /// (`searching` or `exhausted`) does not restart the search (the target
    /// gate keeps its evidence; operators and scripts re-send requests);
    /// like any request it re-enables autonomy mode.
    ///
    /// # Errors
    /// [`BridgeError::BlankTarget`], [`BridgeError::Agent`] for a request no
    /// category matches (the previous target is kept).
    pub fn on_target(
        &mut self,
        msg: &RosString,
        now: Duration,
    ) -> Result<Vec<Outgoing>, BridgeError> {
        let request = msg.data.trim().to_owned();
        if request.is_empty() {
            return Err(self.reject(BridgeError::BlankTarget, now));
        }
        if self.agent.is_none() {
            self.pending_target = Some(request);
            return Ok(vec![self.status_message(now)]);
        }
        if self.is_current_search(&request) {
            tracing::info!(request, "already searching for this category");
        } else {
            self.apply_target(&request, now)?;
        }
        // Autonomy mode and the `/stop` release again, as at start.
        Ok(self.start(now))
    }

    /// Whether `request` names the category of the search under way.
    fn is_current_search(&self, request: &str) -> bool {
        // While odometry is stale, the state it interrupted.
        let state = match self.state {
            NodeState::WaitingForOdometry => self.paused,
            s => Some(s),
        };
        let searching = matches!(
            state,
            Some(NodeState::Searching | NodeState::Exhausted | NodeState::FloorExhausted)
        );
        let Some(agent) = self.agent.as_ref().filter(|_| searching) else {
            return false;
        };
        match (agent.target(), agent.vocabulary().resolve(request)) {
            (Some(current), Ok(new)) => current.category == new.category,
            _ => false,
        }
    }

    fn apply_target(&mut self, request: &str, now: Duration) -> Result<(), BridgeError> {
        let Some(agent) = self.agent.as_mut() else {
            self.pending_target = Some(request.to_owned());
            return Ok(());
        };
        match agent.set_target(request) {
            Ok(t) => {
                tracing::info!(request, category = %t.category, "new target");
                self.state = if self.odometry_fresh(now) {
                    NodeState::Searching
                } else {
                    NodeState::WaitingForOdometry
                };
                self.paused = None;
                self.holding = false;
                self.stairs.clear();
                self.note = None;
                // Step at the next tick.
                self.last_step = None;
                Ok(())
            }
            Err(e) => Err(self.reject(e.into(), now)),
        }
    }

    /// The relay: the path follower's `TwistStamped` as a `Twist` clamped to
    /// the robot's limits (`None` when the relay is disabled). Non-finite
    /// components become 0.
    pub fn on_cmd_vel(&mut self, msg: &TwistStamped, now: Duration) -> Option<Outgoing> {
        if !self.config.relay.enabled || self.state == NodeState::Stopped {
            return None;
        }
        self.last_cmd_vel = Some(now);
        self.stats.relayed += 1;
        Some(Outgoing::CmdVel(clamp_twist(
            &msg.twist,
            self.config.robot.max_speed_mps,
            self.config.robot.max_yaw_rate_dps.to_radians(),
        )))
    }

    /// A `/way_point` message at `p` (map frame), counted as published.
    fn waypoint_msg(&mut self, p: Point3<f64>) -> PointStamped {
        self.stats.waypoints_published += 1;
        PointStamped {
            header: self.header(),
            point: Point::from(p),
        }
    }

    /// A waypoint at the robot's own position (the CMU planner stops there).
    fn hold_waypoint(&mut self) -> Option<Outgoing> {
        let pose = self.base_pose()?;
        Some(Outgoing::WayPoint(self.waypoint_msg(pose.position)))
    }

    fn mission_messages(&mut self, mission: &Mission, now: Duration) -> Vec<Outgoing> {
        let waypoint = self.waypoint_msg(mission.waypoint);
        self.last_waypoint = Some(now);
        self.holding = false;
        let header = waypoint.header.clone();
        let mut out = vec![Outgoing::WayPoint(waypoint)];
        let poses = mission
            .path
            .as_deref()
            .unwrap_or(&[])
            .iter()
            .chain(std::iter::once(&mission.waypoint))
            .map(|p| PoseStamped {
                header: header.clone(),
                pose: Pose {
                    position: Point::from(*p),
                    orientation: Quaternion::IDENTITY,
                },
            })
            .collect();
        out.push(Outgoing::Path(Path { header, poses }));
        out
    }

    fn hold(&mut self, out: &mut Vec<Outgoing>) {
        if !self.holding {
            self.holding = true;
            if let Some(w) = self.hold_waypoint() {
                out.push(w);
            }
        }
    }

    /// Builds one observation from the buffered clouds and gives it to the
    /// agent.
    fn observe(&mut self, now: Duration) {
        let (Some(pose), Some(odom)) = (self.base_pose(), self.odom) else {
            return;
        };
        let Some(agent) = self.agent.as_mut() else {
            return;
        };
        if self.labelled.is_empty() && self.unlabelled.is_empty() {
            return;
        }
        let labelled: Vec<LabeledPoint> = self.labelled.drain(..).flatten().collect();
        let unlabelled: Vec<Point3<f64>> = self.unlabelled.drain(..).flatten().collect();
        self.last_observe = Some(now);
        let origin = odom.sensor;
        let frames = [
            (!labelled.is_empty()).then_some(Sensor::Cloud(CloudObservation {
                origin,
                points: labelled,
            })),
            (!unlabelled.is_empty()).then_some(Sensor::Occupancy(OccupancyObservation {
                origin,
                points: unlabelled,
            })),
        ];
        for sensor in frames.into_iter().flatten() {
            match agent.observe(&Observation { pose, sensor }) {
                Ok(_) => self.stats.observations += 1,
                Err(e) => {
                    self.stats.refused_observations += 1;
                    self.last_error = Some(format!("observation refused: {e}"));
                }
            }
        }
    }

    /// Runs whatever is due at clock reading `now` (monotonic, since the node
    /// started): the relay watchdog, an observation (`observe_hz`), an agent
    /// step (`control_hz`) with its waypoint and status, waypoint
    /// re-publication and markers. Call it often (e.g. every 10-50 ms).
    pub fn tick(&mut self, now: Duration) -> Vec<Outgoing> {
        let mut out = Vec::new();
        if self.state == NodeState::Stopped {
            return out;
        }
        self.check_streams(now);
        if self.config.relay.enabled
            && self
                .last_cmd_vel
                .is_some_and(|t| now.saturating_sub(t).as_secs_f64() > self.config.relay.watchdog_s)
        {
            self.last_cmd_vel = None;
            out.push(Outgoing::CmdVel(Twist::default()));
        }
        let fresh = self.odometry_fresh(now);
        if !fresh {
            if self.odom.is_some()
                && !matches!(self.state, NodeState::WaitingForOdometry)
                && self.agent.is_some()
            {
                self.paused = Some(self.state);
                self.state = NodeState::WaitingForOdometry;
                self.last_error = Some("odometry is stale: holding".into());
                self.holding = false;
                self.hold(&mut out);
            }
            if due(self.last_step, now, 1.0 / self.config.rates.control_hz) {
                self.last_step = Some(now);
                out.push(self.status_message(now));
            }
            return out;
        }
        if self.state == NodeState::WaitingForOdometry && self.agent.is_some() {
            self.resume();
        }
        if due(self.last_observe, now, 1.0 / self.config.rates.observe_hz) {
            self.observe(now);
        }
        if due(self.last_step, now, 1.0 / self.config.rates.control_hz) {
            self.last_step = Some(now);
            // An exhausted search (on this floor or everywhere) is
            // re-checked at every step: the maps keep growing while the
            // robot holds (a door opens, the terrain map fills in, a
            // candidate gathers its N_obs observations).
            if matches!(
                self.state,
                NodeState::Searching | NodeState::Exhausted | NodeState::FloorExhausted
            ) {
                self.step_agent(now, &mut out);
            }
            out.push(self.status_message(now));
        } else if self.state == NodeState::Searching
            && due(
                self.last_waypoint,
                now,
                self.config.rates.waypoint_republish_s,
            )
            && let Some(waypoint) = self
                .agent
                .as_ref()
                .and_then(|a| a.active_mission())
                .map(|(_, m)| m.waypoint)
        {
            // Re-publish: the planner may have started late or dropped it.
            let msg = self.waypoint_msg(waypoint);
            self.last_waypoint = Some(now);
            out.push(Outgoing::WayPoint(msg));
        }
        if due(self.last_markers, now, self.config.rates.markers_period_s)
            && let Some(agent) = self.agent.as_ref()
        {
            self.last_markers = Some(now);
            let snapshot = agent.snapshot();
            out.push(Outgoing::Markers(markers_from_snapshot(
                &snapshot,
                &self.confirmed,
                &self.config,
                &self.header(),
            )));
        }
        out
    }

    fn step_agent(&mut self, now: Duration, out: &mut Vec<Outgoing>) {
        let Some(agent) = self.agent.as_mut() else {
            return;
        };
        if agent.pose().is_none() {
            return; // no observation yet
        }
        let clock = agent.last_step().map_or(now, |t| t.max(now));
        let result = agent.step(clock);
        self.stats.steps += 1;
        // The node runs for hours: the agent's decision log is drained here
        // (to the log) so that it does not grow without bound; the status
        // reports `Agent::last_decision`.
        for d in agent.take_decisions() {
            tracing::debug!(step = ?d.step, action = %d.action, reason = %d.reason, "decision");
        }
        if result
            .as_ref()
            .is_ok_and(|c| !matches!(c, AgentCommand::FloorExhausted { .. }))
        {
            self.stairs.clear();
            self.note = None;
        }
        match result {
            Ok(AgentCommand::Dispatch { mission, .. }) => {
                self.state = NodeState::Searching;
                out.extend(self.mission_messages(&mission, now));
            }
            Ok(AgentCommand::Continue { mission: None }) => self.hold(out),
            Ok(AgentCommand::Continue { mission: Some(_) }) => {}
            Ok(AgentCommand::Verify { .. }) => {
                self.state = NodeState::Searching;
                self.hold(out);
            }
            Ok(AgentCommand::Stop { object, centre }) => {
                let (category, request) = agent
                    .target()
                    .map(|t| (t.category.clone(), t.request.clone()))
                    .unwrap_or_default();
                tracing::info!(%category, object = object.0, "target confirmed");
                self.confirmed.push(ConfirmedTarget {
                    category,
                    request,
                    object: object.0,
                    centre: [centre.x, centre.y, centre.z],
                    at_s: secs(now),
                });
                self.state = NodeState::Confirmed;
                self.hold(out);
            }
            Ok(AgentCommand::Exhausted) => {
                if self.state != NodeState::Exhausted {
                    tracing::info!("search exhausted: holding and re-checking at every step");
                }
                self.state = NodeState::Exhausted;
                self.hold(out);
            }
            Ok(AgentCommand::FloorExhausted { stairs }) => {
                self.stairs = stairs.iter().map(|p| [p.x, p.y, p.z]).collect();
                let note = floor_exhausted_note(&self.stairs);
                // Once per change (state or stairs at the logged precision),
                // not at every step.
                if self.state != NodeState::FloorExhausted
                    || self.note.as_deref() != Some(note.as_str())
                {
                    tracing::info!(
                        stairs = self.stairs.len(),
                        "{note}: holding and re-checking at every step"
                    );
                }
                self.note = Some(note);
                self.state = NodeState::FloorExhausted;
                self.hold(out);
            }
            Err(AgentError::NoObservation) => {}
            Err(e) => self.last_error = Some(format!("agent step failed: {e}")),
        }
    }

    /// The current status document.
    pub fn status(&self, now: Duration) -> Status {
        let agent = self.agent.as_ref();
        let active = agent.and_then(|a| a.active_mission());
        Status {
            time_s: secs(now),
            state: self.state,
            target: agent
                .and_then(|a| a.target())
                .map(|t| t.category.clone())
                .or_else(|| self.pending_target.clone()),
            request: agent.and_then(|a| a.target()).map(|t| t.request.clone()),
            active_mission: active.map(|(id, m): (MissionId, &Mission)| MissionStatus {
                id: id.0,
                kind: m.kind.name().to_owned(),
                waypoint: [m.waypoint.x, m.waypoint.y, m.waypoint.z],
            }),
            last_decision: agent
                .and_then(Agent::last_decision)
                .map(|d| DecisionStatus {
                    at_s: d.at.as_secs_f64(),
                    step: d.step,
                    action: d.action,
                    reason: d.reason.clone(),
                }),
            confirmed: self.confirmed.clone(),
            pose: self
                .base_pose()
                .map(|p| [p.position.x, p.position.y, p.position.z, p.yaw]),
            objects: agent.map_or(0, |a| a.semantic_map().cluster_count()),
            frontiers: agent.map_or(0, |a| a.frontier_map().graph().nodes().len()),
            agent: agent.map(Agent::stats),
            bridge: self.stats,
            last_error: self.last_error.clone(),
            rejections: self
                .rejections
                .iter()
                .map(|(k, r)| (k.clone(), r.count))
                .collect(),
            stairs: self.stairs.clone(),
            note: self.note.clone(),
            streams: self
                .streams
                .iter()
                .map(|(topic, s)| ((*topic).to_owned(), s.monitor.status(now)))
                .collect(),
        }
    }

    fn status_message(&self, now: Duration) -> Outgoing {
        Outgoing::Status(RosString {
            data: serde_json::to_string(&self.status(now)).unwrap_or_default(),
        })
    }
}

/// Removes `excess` points of `cloud` (at most half of them per call, at
/// least one), keeping the rest evenly spread over the cloud's order (a
/// fractional stride); returns how many were removed.
fn thin<T>(cloud: &mut Vec<T>, excess: usize) -> usize {
    let n = cloud.len();
    if n < 2 || excess == 0 {
        return 0;
    }
    let keep = n.saturating_sub(excess).max(n / 2).max(1);
    // Point i is kept when floor((i + 1) keep / n) steps past floor(i keep / n):
    // exactly `keep` points, one per stride of n / keep.
    let step = |i: usize| (i as u128 * keep as u128) / n as u128;
    let mut i = 0;
    cloud.retain(|_| {
        let kept = step(i + 1) > step(i);
        i += 1;
        kept
    });
    n - cloud.len()
}

/// Clamps a twist to a ground robot's limits: planar linear velocity to
/// `max_speed` (m/s, keeping its direction), yaw rate to `max_yaw_rate`
/// (rad/s); roll/pitch rates, vertical speed and non-finite components
/// become 0.
pub fn clamp_twist(t: &Twist, max_speed: f64, max_yaw_rate: f64) -> Twist {
    let f = |v: f64| if v.is_finite() { v } else { 0.0 };
    let (vx, vy) = (f(t.linear.x), f(t.linear.y));
    let speed = vx.hypot(vy);
    let scale = if speed > max_speed {
        max_speed / speed
    } else {
        1.0
    };
    Twist {
        linear: Vector3::new(vx * scale, vy * scale, 0.0),
        angular: Vector3::new(0.0, 0.0, f(t.angular.z).clamp(-max_yaw_rate, max_yaw_rate)),
    }
}
