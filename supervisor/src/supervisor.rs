//! Algorithm 1 of SOR-Nav as a state machine over a generic clock.
//!
//! ```text
//! 1. update semantic memory and graphs                  (caller, before step)
//! 2. target gate accepts a cluster of category g    ->  NAV_TO_OBJECT
//! 3. a relocation mission is active                  ->  keep its waypoint
//! 4. supervisor interval not elapsed                 ->  continue the frontier mission
//! 5. rank clusters by U_geo, keep the top K; build S_r and {(k, d_k, S_k)}
//! 6. (a_t, k_t) = Pi_sup(g, S_r, candidates)
//! 7. valid relocation to k_t  ->  RELOCATE to C_k's stored waypoint
//!    otherwise                ->  EXPLORE toward the first TSP frontier
//! ```
//!
//! Step 5's inputs are produced lazily by a closure, so the region context is
//! only built when steps 2-4 did not already decide. Every decision is
//! logged with `tracing` (target `sornav_supervisor`).
//!
//! Two additions to the paper's listing:
//! * when no mission is active ([`ActiveMissionKind::Idle`]), step 4 does not hold
//!   the decision back, since there is no frontier mission to continue;
//! * after a relocation ends, the region it reached is explored for
//!   [`SupervisorConfig::region_dwell_s`] before the policy is asked again
//!   (steps 5-7 become "EXPLORE toward the first TSP frontier",
//!   [`SupervisorCommand::ExploreNewRegion`]). Completing a relocation asks
//!   for exploration from the new region; without a dwell, an `S_r` that
//!   still holds the objects of the region just left (its radius is 10 m)
//!   would send the robot straight back out. The default, 0, is the exact
//!   listing.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};
use tracing::{debug, info, warn};

use crate::clock::Timestamp;
use crate::context::{Candidate, ContextObject, RegionSnapshot};
use crate::error::SupervisorError;
use crate::policy::{ContextPolicy, PolicyDecision, Situation};

/// Settings of Algorithm 1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SupervisorConfig {
    /// Minimum time between two policy evaluations (step 4), seconds. The
    /// robot runs the supervisor at 1 Hz.
    pub interval_s: f64,
    /// Number of clusters `K` passed to the policy (step 5).
    pub top_k: usize,
    /// After a relocation mission ends, the region it reached is explored
    /// for this long (seconds) before the policy is asked again (0: the
    /// exact listing; the `sornav` agent uses 20 s).
    pub region_dwell_s: f64,
}

impl SupervisorConfig {
    /// Checks a finite `interval_s >= 0`, `top_k >= 1` and a finite
    /// `region_dwell_s >= 0`.
    ///
    /// # Errors
    /// [`SupervisorError::InvalidConfig`] with the configuration.
    pub fn validate(&self) -> Result<(), SupervisorError> {
        if !(self.interval_s.is_finite() && self.interval_s >= 0.0)
            || self.top_k == 0
            || !(self.region_dwell_s.is_finite() && self.region_dwell_s >= 0.0)
        {
            return Err(SupervisorError::InvalidConfig(format!("{self:?}")));
        }
        Ok(())
    }
}

impl Default for SupervisorConfig {
    fn default() -> Self {
        Self {
            interval_s: 1.0,
            top_k: 10,
            region_dwell_s: 0.0,
        }
    }
}

/// The kind of the executor's active mission, as the supervisor sees it
/// (no payload; named apart from `sornav-executor`'s `MissionKind`, which
/// carries the mission's goal: both crates are re-exported by `sornav`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ActiveMissionKind {
    /// No active mission.
    Idle,
    /// Exploring a frontier.
    Explore,
    /// Relocating to a cluster's stored waypoint.
    Relocate,
    /// Navigating to an accepted target object.
    NavToObject,
}

/// The executor's mission state, as input to a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct MissionState {
    /// Identifier of the active mission (changes with every new mission).
    pub id: u64,
    /// Its kind.
    pub kind: ActiveMissionKind,
}

/// A cluster of the cluster graph as seen by step 5: its geometric utility
/// `U_geo`, its stored relocation waypoint and the policy-facing candidate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClusterCandidate {
    /// Id, graph distance and context `S_k`.
    pub candidate: Candidate,
    /// Geometric utility `U_geo` used for the top-K ranking.
    pub u_geo: f64,
    /// The cluster's stored waypoint.
    pub waypoint: Point3<f64>,
}

/// The region context of step 5, built on demand.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RegionContext {
    /// The robot's context `S_r`.
    pub local_context: Vec<ContextObject>,
    /// All clusters (the supervisor keeps the top K by `U_geo`).
    pub clusters: Vec<ClusterCandidate>,
}

/// The per-step input of Algorithm 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepInput<'a> {
    /// The target category `g`.
    pub target: &'a str,
    /// Step 2: the id of the target cluster the target gate accepted, if any.
    pub target_accepted: Option<u64>,
    /// The executor's active mission.
    pub mission: MissionState,
    /// The first frontier of the TSP route (exploration goal), if any.
    pub first_frontier: Option<Point3<f64>>,
}

/// Which line of Algorithm 1 produced a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AlgorithmStep {
    /// Step 2.
    TargetAccepted,
    /// Step 3.
    RelocationActive,
    /// Step 4.
    RateLimited,
    /// Steps 5-7.
    PolicyEvaluated,
    /// Steps 5-7 replaced by exploration of the region a relocation reached
    /// ([`SupervisorConfig::region_dwell_s`]).
    RegionDwell,
}

/// The supervisor's command to the executor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "command", rename_all = "snake_case")]
pub enum SupervisorCommand {
    /// NAV_TO_OBJECT toward the accepted target.
    NavToObject {
        /// The accepted target cluster id.
        target_id: u64,
    },
    /// Keep the active relocation mission and its waypoint.
    KeepRelocation,
    /// Keep the current frontier mission.
    ContinueMission,
    /// RELOCATE to a cluster's stored waypoint.
    Relocate {
        /// The chosen cluster `k_t`.
        cluster_id: u64,
        /// Its stored waypoint.
        waypoint: Point3<f64>,
        /// The policy's reason.
        reason: String,
    },
    /// EXPLORE toward the first frontier of the TSP route, without asking
    /// the policy: a relocation just ended and its region is being explored
    /// ([`SupervisorConfig::region_dwell_s`]).
    ExploreNewRegion {
        /// The first TSP frontier.
        frontier: Option<Point3<f64>>,
        /// Seconds until the policy is asked again.
        remaining_s: f64,
    },
    /// EXPLORE toward the first frontier of the TSP route (`None` when no
    /// frontier is left).
    Explore {
        /// The first TSP frontier.
        frontier: Option<Point3<f64>>,
        /// Why not relocating.
        reason: String,
    },
}

/// Counters over the supervisor's life (for reports).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SupervisorStats {
    /// Steps taken.
    pub steps: u64,
    /// Policy evaluations (steps 5-7).
    pub policy_calls: u64,
    /// Relocations commanded.
    pub relocations: u64,
    /// Policy relocations rejected (cluster id not among the top-K
    /// candidates) and turned into exploration.
    pub rejected_relocations: u64,
    /// Clusters left out of the ranking because their `U_geo` was NaN or
    /// infinite.
    pub unranked_clusters: u64,
}

/// Algorithm 1 over a policy `P` and a clock `T`.
#[derive(Debug)]
pub struct Supervisor<P, T> {
    policy: P,
    config: SupervisorConfig,
    start: Option<T>,
    last_evaluation: Option<T>,
    /// Kind of the mission at the previous step (relocation end detection).
    previous_kind: Option<ActiveMissionKind>,
    /// Elapsed time (s) until which the region reached by the last
    /// relocation is explored without asking the policy.
    dwell_until_s: Option<f64>,
    stats: SupervisorStats,
}

impl<P: ContextPolicy, T: Timestamp> Supervisor<P, T> {
    /// A supervisor with a policy.
    ///
    /// # Errors
    /// [`SupervisorError::InvalidConfig`] when `config` fails
    /// [`SupervisorConfig::validate`].
    pub fn new(policy: P, config: SupervisorConfig) -> Result<Self, SupervisorError> {
        config.validate()?;
        Ok(Self {
            policy,
            config,
            start: None,
            last_evaluation: None,
            previous_kind: None,
            dwell_until_s: None,
            stats: SupervisorStats::default(),
        })
    }

    /// The policy.
    pub fn policy(&self) -> &P {
        &self.policy
    }

    /// The policy, mutably.
    pub fn policy_mut(&mut self) -> &mut P {
        &mut self.policy
    }

    /// The counters.
    pub fn stats(&self) -> SupervisorStats {
        self.stats
    }

    /// Forgets the timing state (new episode). Counters are kept.
    pub fn reset(&mut self) {
        self.start = None;
        self.last_evaluation = None;
        self.previous_kind = None;
        self.dwell_until_s = None;
    }

    /// One pass of Algorithm 1 at time `now`; `region` builds step 5's inputs
    /// and is only called when steps 2-4 did not decide.
    ///
    /// # Errors
    /// [`SupervisorError::InvalidNumber`] when `now` yields a NaN elapsed
    /// time (a NaN `f64` clock reading); the state is left unchanged.
    ///
    /// # Complexity
    /// O(c log c) for c clusters plus the policy's cost.
    pub fn step(
        &mut self,
        now: T,
        input: &StepInput<'_>,
        region: impl FnOnce() -> RegionContext,
    ) -> Result<SupervisorCommand, SupervisorError> {
        let start = *self.start.get_or_insert(now);
        let elapsed_s = now.seconds_since(&start);
        if elapsed_s.is_nan() {
            return Err(SupervisorError::InvalidNumber {
                what: "clock reading",
                value: elapsed_s,
            });
        }
        self.stats.steps += 1;
        // A relocation that ended starts the exploration of its region.
        let previous = self.previous_kind.replace(input.mission.kind);
        if previous == Some(ActiveMissionKind::Relocate)
            && input.mission.kind != ActiveMissionKind::Relocate
        {
            self.dwell_until_s = Some(elapsed_s + self.config.region_dwell_s);
        }
        // Step 2: reliable target evidence pre-empts everything.
        if let Some(target_id) = input.target_accepted {
            debug!(target: "sornav_supervisor", step = ?AlgorithmStep::TargetAccepted, target_id, "NAV_TO_OBJECT");
            return Ok(SupervisorCommand::NavToObject { target_id });
        }
        // Step 3: an active relocation is kept (and region reasoning suppressed).
        if input.mission.kind == ActiveMissionKind::Relocate {
            debug!(target: "sornav_supervisor", step = ?AlgorithmStep::RelocationActive, "keep relocation");
            return Ok(SupervisorCommand::KeepRelocation);
        }
        // Step 4: rate limit.
        if input.mission.kind != ActiveMissionKind::Idle
            && let Some(last) = self.last_evaluation
            && now.seconds_since(&last) < self.config.interval_s
        {
            return Ok(SupervisorCommand::ContinueMission);
        }
        self.last_evaluation = Some(now);
        if let Some(until) = self.dwell_until_s
            && elapsed_s < until
        {
            debug!(target: "sornav_supervisor", step = ?AlgorithmStep::RegionDwell, remaining_s = until - elapsed_s, "explore the new region");
            return Ok(SupervisorCommand::ExploreNewRegion {
                frontier: input.first_frontier,
                remaining_s: until - elapsed_s,
            });
        }
        // Step 5: top-K clusters by U_geo and the snapshot.
        let RegionContext {
            local_context,
            mut clusters,
        } = region();
        clusters.sort_by(|a, b| {
            b.u_geo
                .total_cmp(&a.u_geo)
                .then(a.candidate.cluster_id.cmp(&b.candidate.cluster_id))
        });
        let before = clusters.len();
        clusters.retain(|c| c.u_geo.is_finite());
        self.stats.unranked_clusters += (before - clusters.len()) as u64;
        clusters.truncate(self.config.top_k);
        let snapshot = RegionSnapshot {
            target: input.target.to_owned(),
            local_context,
            candidates: clusters.iter().map(|c| c.candidate.clone()).collect(),
        };
        let situation = Situation {
            mission_id: input.mission.id,
            elapsed_s,
        };
        // Step 6.
        self.stats.policy_calls += 1;
        let decision = match snapshot.validate() {
            Ok(()) => self.policy.decide(&snapshot, &situation),
            Err(e) => PolicyDecision::explore(format!("invalid snapshot ({e}); keep exploring")),
        };
        // Step 7.
        let command = match decision.relocation() {
            Some(k) => match clusters.iter().find(|c| c.candidate.cluster_id == k) {
                Some(c) => {
                    self.stats.relocations += 1;
                    // The relocation may start and end between two steps:
                    // its end is detected at the next step either way.
                    self.previous_kind = Some(ActiveMissionKind::Relocate);
                    SupervisorCommand::Relocate {
                        cluster_id: k,
                        waypoint: c.waypoint,
                        reason: decision.reason,
                    }
                }
                None => {
                    self.stats.rejected_relocations += 1;
                    warn!(target: "sornav_supervisor", policy = self.policy.name(), cluster_id = k, "relocation to a cluster outside the candidates; exploring");
                    SupervisorCommand::Explore {
                        frontier: input.first_frontier,
                        reason: format!(
                            "policy chose unknown cluster {k} ({}); keep exploring",
                            decision.reason
                        ),
                    }
                }
            },
            None => SupervisorCommand::Explore {
                frontier: input.first_frontier,
                reason: decision.reason,
            },
        };
        info!(target: "sornav_supervisor", policy = self.policy.name(), mission_id = input.mission.id, elapsed_s, ?command, "supervisor decision");
        Ok(command)
    }
}
