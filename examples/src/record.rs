//! One line of `episodes.jsonl`: the result of one (variant, episode) run.

use serde::{Deserialize, Serialize};
use sornav::supervisor::LlmStats;
use sornav_platform_sim::EpisodeResult;

use crate::adapter::EpisodeTrace;
use crate::decision_log::DecisionLog;
use crate::histogram::Histogram;

/// A relocation dispatched during an episode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RelocationEvent {
    /// Action index.
    pub step: usize,
    /// Robot position when it was decided (x, y).
    pub from: [f32; 2],
    /// Relocation waypoint (x, y).
    pub to: [f32; 2],
}

/// The result of one variant on one episode (one line of `episodes.jsonl`):
/// the simulator's scores and what the adapter logged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeRecord {
    /// Variant name (`sornav`, `no-gate`, ...).
    pub variant: String,
    /// The simulator's result (scene, episode, success, SPL, soft SPL,
    /// distances, actions, collisions, outcome class, wall time).
    #[serde(flatten)]
    pub result: EpisodeResult,
    /// Decision latency (observe + step) per action, ms (histogram).
    pub decision_ms: Histogram,
    /// Time between decisions spent outside the agent (render and
    /// simulator), ms (histogram).
    pub frame_ms: Histogram,
    /// How the agent ended: `stop`, `exhausted`, or empty (budget).
    pub agent_end: String,
    /// Relocations dispatched.
    pub relocations: Vec<RelocationEvent>,
    /// Candidates verified (arrival at a target candidate).
    pub verifications: usize,
    /// Missions dispatched.
    pub missions: usize,
    /// Missions the motion layer reported stuck or without a path.
    pub blocked_missions: usize,
    /// Frontiers excluded after exploration missions had reached their
    /// place three times (thrashing bounded; see `sornav`'s agent).
    #[serde(default)]
    pub revisit_exclusions: usize,
    /// Agent errors (first few messages).
    pub errors: Vec<String>,
    /// The decision log (runs of identical decisions merged).
    pub decisions: DecisionLog,
    /// The LLM policy's counters (requests, valid answers, fallbacks by
    /// cause, latencies, tokens), when the agent asked a model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub llm: Option<LlmStats>,
}

impl EpisodeRecord {
    /// The resume / merge key: variant, scene and episode.
    pub fn key(&self) -> (String, String, String) {
        (
            self.variant.clone(),
            self.result.scene_id.clone(),
            self.result.episode_id.clone(),
        )
    }

    /// A record from the simulator's result and, for agent variants, the
    /// adapter's trace.
    pub fn new(variant: &str, result: EpisodeResult, trace: Option<EpisodeTrace>) -> Self {
        let trace = trace.unwrap_or_default();
        Self {
            variant: variant.to_owned(),
            result,
            decision_ms: trace.decision_ms,
            frame_ms: trace.frame_ms,
            agent_end: trace.agent_end,
            relocations: trace
                .relocations
                .iter()
                .map(|&(step, from, to)| RelocationEvent { step, from, to })
                .collect(),
            verifications: trace.verifications.len(),
            missions: trace.missions,
            blocked_missions: trace.blocked_missions,
            revisit_exclusions: trace.revisit_exclusions,
            errors: trace.errors,
            decisions: trace.decisions,
            llm: trace.llm,
        }
    }
}

/// A record of one finished episode for unit tests: scene `s`, target
/// `bed`, 10 actions over 3 m, start 3 m from the goal, `floors` floors
/// between start and goal.
#[cfg(test)]
pub(crate) fn test_record(
    episode_id: &str,
    outcome: sornav_platform_sim::Outcome,
    spl: f64,
    floors: usize,
) -> EpisodeRecord {
    let success = outcome == sornav_platform_sim::Outcome::Success;
    EpisodeRecord::new(
        "v",
        EpisodeResult {
            episode_id: episode_id.to_owned(),
            scene_id: "s".into(),
            object_category: "bed".into(),
            success,
            success_1m: success,
            spl: if success { spl } else { 0.0 },
            soft_spl: 0.0,
            start_geodesic_m: 3.0,
            dtg_m: Some(1.0),
            path_length_m: 3.0,
            actions: 10,
            collisions: 0,
            start_level: 0,
            goal_level: floors,
            floors_between: floors,
            cross_floor: floors > 0,
            outcome,
            wall_s: 0.0,
            timed_s: 0.0,
            step_ms_p50: 0.0,
        },
        None,
    )
}
