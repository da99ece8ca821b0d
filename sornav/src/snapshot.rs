//! Serialisable views of the agent for figures and logs.

use std::time::Duration;

use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};
use sornav_cluster_graph::ClusterGraph;
use sornav_executor::{Mission, MissionId, MissionOutcome, RobotPose};
use sornav_frontier_graph::{CellState, FrontierId, FrontierNode, OccupancyGrid};
use sornav_target_gate::{Phase, Track};

use crate::ordering::Route;
use crate::target::Target;

/// Which rule of the decision loop produced a [`Decision`], in the order
/// the loop checks them (Algorithm 1 with the target gate in front).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DecisionStep {
    /// The gate confirmed the target: STOP.
    TargetConfirmed,
    /// The target is confirmed but the robot is not at a view point of
    /// it: move to one before STOP (`approach.stop_in_view_attempts`).
    StopInView,
    /// Arrived at a candidate: face it and observe again.
    TargetVerification,
    /// A candidate reached `N_obs`: `NAV_TO_OBJECT` (Algorithm 1, line 1).
    TargetAccepted,
    /// A relocation is under way and is kept (line 2).
    RelocationActive,
    /// The supervisor's rate limit held the active mission (line 3).
    RateLimited,
    /// The context policy was asked: relocate or explore (lines 4-8).
    PolicyEvaluated,
    /// A relocation just ended: its region is explored (the route's first
    /// frontier) before the policy is asked again
    /// (`supervisor.region_dwell_s`).
    RegionDwell,
}

/// What a [`Decision`] did. Serialises as the snake-case name
/// (`"nav_to_object"`), compares equal to that name (`action == "relocate"`)
/// and parses from it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DecisionAction {
    /// The target is confirmed: STOP.
    Stop,
    /// Face the candidate and observe it again.
    Verify,
    /// Approach a target candidate (`NAV_TO_OBJECT`).
    NavToObject,
    /// Relocate to another cluster.
    Relocate,
    /// Explore a frontier.
    Explore,
    /// Keep the active mission.
    Continue,
    /// Nothing reachable is left to explore.
    Exhausted,
    /// Walk back along the robot's own trail to the last floor it stood on
    /// (a relocation outside any cluster).
    Retreat,
    /// A target candidate could not be approached and was set aside.
    RejectCandidate,
}

impl DecisionAction {
    /// Every action, in declaration order.
    pub const ALL: [DecisionAction; 9] = [
        DecisionAction::Stop,
        DecisionAction::Verify,
        DecisionAction::NavToObject,
        DecisionAction::Relocate,
        DecisionAction::Explore,
        DecisionAction::Continue,
        DecisionAction::Exhausted,
        DecisionAction::Retreat,
        DecisionAction::RejectCandidate,
    ];
}

snake_case_names!(DecisionAction {
    Stop => "stop",
    Verify => "verify",
    NavToObject => "nav_to_object",
    Relocate => "relocate",
    Explore => "explore",
    Continue => "continue",
    Exhausted => "exhausted",
    Retreat => "retreat",
    RejectCandidate => "reject_candidate",
});

/// A name that is no [`DecisionAction`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown decision action {0:?}")]
pub struct UnknownDecisionAction(pub String);

impl std::str::FromStr for DecisionAction {
    type Err = UnknownDecisionAction;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        DecisionAction::ALL
            .into_iter()
            .find(|a| a.as_str() == s)
            .ok_or_else(|| UnknownDecisionAction(s.to_owned()))
    }
}

/// One decision of [`Agent::step`](crate::Agent::step).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Decision {
    /// Clock reading of the step.
    pub at: Duration,
    /// The rule that decided.
    pub step: DecisionStep,
    /// What was done.
    pub action: DecisionAction,
    /// The mission dispatched or kept, if any.
    pub mission: Option<MissionId>,
    /// Why (the policy's reason for policy decisions).
    pub reason: String,
}

/// A relocation under way.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RelocationRecord {
    /// The relocation mission.
    pub mission: MissionId,
    /// Stable key of the cluster: its smallest member frontier id.
    pub cluster_key: u64,
    /// Member frontiers when the decision was taken.
    pub members: Vec<FrontierId>,
    /// The relocation waypoint frontier.
    pub waypoint_frontier: FrontierId,
    /// The policy's reason.
    pub reason: String,
}

/// A top-down raster of the occupancy grid.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct OccupancyRaster {
    /// World position of the centre of cell (0, 0) (m).
    pub origin: Point2<f64>,
    /// Cell edge (m).
    pub resolution: f64,
    /// Columns (x).
    pub width: usize,
    /// Rows (y).
    pub height: usize,
    /// Row-major (row = y index), `0` unknown, `1` free, `2` occupied.
    pub cells: Vec<u8>,
}

impl OccupancyRaster {
    /// Rasterises `grid`.
    ///
    /// # Complexity
    /// O(cells of the grid's bounding box).
    pub fn from_grid(grid: &OccupancyGrid) -> Self {
        let Some((min, max)) = grid.bounds() else {
            return Self {
                resolution: grid.resolution(),
                ..Self::default()
            };
        };
        let width = (max.x - min.x + 1) as usize;
        let height = (max.y - min.y + 1) as usize;
        let mut cells = Vec::with_capacity(width * height);
        for y in min.y..=max.y {
            for x in min.x..=max.x {
                cells.push(match grid.state(sornav_frontier_graph::Cell::new(x, y)) {
                    CellState::Unknown => 0,
                    CellState::Free => 1,
                    CellState::Occupied => 2,
                });
            }
        }
        Self {
            origin: grid.cell_center(min),
            resolution: grid.resolution(),
            width,
            height,
            cells,
        }
    }
}

/// An object cluster of the semantic map, with its normalised category.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectRecord {
    /// Cluster id in the semantic map.
    pub id: u64,
    /// Normalised category (`None` for an unnamed label).
    pub label: Option<String>,
    /// Voxel support `N_j`.
    pub support: usize,
    /// Centre `p_j`.
    pub centre: Point3<f64>,
    /// Lower corner of the bounds `B_j`.
    pub min: Point3<f64>,
    /// Upper corner of the bounds `B_j`.
    pub max: Point3<f64>,
    /// Updates in which the object was hit.
    pub observations: u64,
}

/// Counters of one agent.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct AgentStats {
    /// Observations integrated (all kinds).
    pub observations: u64,
    /// Of those, occupancy-only observations ([`Sensor::Occupancy`](crate::Sensor::Occupancy)).
    #[serde(default)]
    pub occupancy_observations: u64,
    /// Observations refused.
    pub refused_observations: u64,
    /// Steps taken.
    pub steps: u64,
    /// Missions dispatched (new or re-dispatched).
    pub dispatched: u64,
    /// Relocations dispatched.
    pub relocations: u64,
    /// Context-policy evaluations.
    pub policy_evaluations: u64,
    /// Frontiers excluded after a failed mission toward them.
    pub excluded_frontiers: u64,
    /// Candidates with no reachable approach waypoint.
    pub unreachable_candidates: u64,
    /// Points left out of the maps (non-finite, out of range).
    pub rejected_points: u64,
    /// Moves to a view point of a confirmed target before STOP.
    #[serde(default)]
    pub stop_in_view_moves: u64,
    /// STOPs away from any view point of the target (no reachable view
    /// point, or the allowed moves used up).
    #[serde(default)]
    pub stops_out_of_view: u64,
    /// Frontiers excluded because exploration missions had reached their
    /// viewpoint's place three times (re-dispatches of the same goal under
    /// new frontier ids: thrashing bounded).
    #[serde(default)]
    pub revisit_exclusions: u64,
    /// STOPs at a view point that only glimpses the target (no clear view
    /// point reachable, or the allowed moves used up).
    #[serde(default)]
    pub glimpse_stops: u64,
    /// Back-offs along the way the robot came, after a mission failed
    /// stuck where it started (the goal kept instead of excluded).
    #[serde(default)]
    pub back_offs: u64,
    /// Second looks: turns toward a candidate seen fewer than `N_obs`
    /// times while searching (returned as [`AgentCommand::Verify`](crate::AgentCommand::Verify)).
    #[serde(default)]
    pub second_looks: u64,
}

/// Everything needed to draw the agent's state (serde).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AgentSnapshot {
    /// The target.
    pub target: Option<Target>,
    /// Last robot pose.
    pub pose: Option<RobotPose>,
    /// Clock reading of the last step.
    pub at: Option<Duration>,
    /// Occupancy grid.
    pub occupancy: OccupancyRaster,
    /// Object clusters of the semantic map.
    pub objects: Vec<ObjectRecord>,
    /// Frontier nodes of G_F.
    pub frontiers: Vec<FrontierNode>,
    /// Cluster graph G_C of the last step.
    pub clusters: Option<ClusterGraph<FrontierId>>,
    /// Exploration route of the last step.
    pub route: Option<Route>,
    /// The active mission.
    pub active_mission: Option<(MissionId, Mission)>,
    /// The relocation under way.
    pub relocation: Option<RelocationRecord>,
    /// Target gate phase.
    pub gate_phase: Option<Phase>,
    /// Tracked target candidates (`s_t`, `m_t`).
    pub candidates: Vec<Track>,
    /// Frontiers excluded after failed missions.
    pub excluded_frontiers: Vec<FrontierId>,
    /// Last mission outcome.
    pub last_outcome: Option<MissionOutcome>,
    /// Last decision and its reason.
    pub last_decision: Option<Decision>,
    /// Counters.
    pub stats: AgentStats,
}

#[cfg(test)]
mod decision_action_tests {
    use super::DecisionAction;

    #[test]
    fn names_round_trip_through_serde_and_from_str() {
        for a in DecisionAction::ALL {
            let json = serde_json::to_string(&a).unwrap();
            assert_eq!(json, format!("\"{}\"", a.as_str()));
            assert_eq!(a.as_str().parse::<DecisionAction>().unwrap(), a);
            assert!(a == a.as_str());
        }
        assert!("jump".parse::<DecisionAction>().is_err());
    }
}
