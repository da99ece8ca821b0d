//! One line of `episodes.jsonl`: the result of one (variant, episode) run.

use serde::{Deserialize, Serialize};
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
    /// Agent errors (first few messages).
    pub errors: Vec<String>,
    /// The decision log (runs of identical decisions merged).
    pub decisions: DecisionLog,
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
            errors: trace.errors,
            decisions: trace.decisions,
        }
    }
}
