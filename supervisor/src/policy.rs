//! The supervisor policy `Pi_sup(g, S_r, candidates) -> (a_t, k_t)` (step 6
//! of Algorithm 1): the [`ContextPolicy`] trait, its decision type and the
//! [`NeverRelocate`] ablation.

use serde::{Deserialize, Serialize};

use crate::context::RegionSnapshot;
use crate::llm_config::LlmStats;

/// The policy's action `a_t`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(tag = "action", rename_all = "snake_case")]
pub enum PolicyAction {
    /// Keep searching the current context (explore the first TSP frontier).
    ContinueExplore,
    /// Leave the current context for cluster `k_t`.
    RelocateCluster {
        /// The chosen cluster id `k_t`.
        cluster_id: u64,
    },
}

/// A decision with the reason behind it (always filled, for logs and audits).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PolicyDecision {
    /// What to do.
    pub action: PolicyAction,
    /// Why, in words.
    pub reason: String,
}

impl PolicyDecision {
    /// Continue exploring, because `reason`.
    pub fn explore(reason: impl Into<String>) -> Self {
        Self {
            action: PolicyAction::ContinueExplore,
            reason: reason.into(),
        }
    }

    /// Relocate to `cluster_id`, because `reason`.
    pub fn relocate(cluster_id: u64, reason: impl Into<String>) -> Self {
        Self {
            action: PolicyAction::RelocateCluster { cluster_id },
            reason: reason.into(),
        }
    }

    /// The relocation cluster, if this is a relocation.
    pub fn relocation(&self) -> Option<u64> {
        match self.action {
            PolicyAction::RelocateCluster { cluster_id } => Some(cluster_id),
            PolicyAction::ContinueExplore => None,
        }
    }
}

/// What the supervisor tells a policy besides the snapshot: the situation
/// the question is asked in, so that asynchronous policies can drop answers
/// to an outdated question, and the time for policies with their own rate
/// limit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Situation {
    /// Identifier of the current mission (changes whenever the executor
    /// starts a new mission; a started relocation is a new mission).
    pub mission_id: u64,
    /// Seconds since the supervisor's first step, on its clock.
    pub elapsed_s: f64,
}

/// A supervisor policy `Pi_sup`.
///
/// Contract: a relocation names a cluster id among `snapshot.candidates`
/// (the [`Supervisor`](crate::Supervisor) double-checks and falls back to
/// exploring otherwise); every decision carries a reason.
pub trait ContextPolicy {
    /// A short name for logs and reports (`"commonsense"`, `"llm"`, ...).
    fn name(&self) -> &str;

    /// Decides whether to keep exploring the current context or relocate.
    fn decide(&mut self, snapshot: &RegionSnapshot, situation: &Situation) -> PolicyDecision;

    /// The counters of a policy that asks a language model (calls, valid
    /// answers, fallbacks by cause, latencies, tokens), for reports; `None`
    /// (the default) for every other policy.
    fn llm_stats(&self) -> Option<LlmStats> {
        None
    }
}

impl<P: ContextPolicy + ?Sized> ContextPolicy for Box<P> {
    fn name(&self) -> &str {
        (**self).name()
    }
    fn decide(&mut self, snapshot: &RegionSnapshot, situation: &Situation) -> PolicyDecision {
        (**self).decide(snapshot, situation)
    }
    fn llm_stats(&self) -> Option<LlmStats> {
        (**self).llm_stats()
    }
}

/// The ablation "without relocation gate": always continue exploring.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct NeverRelocate;

impl ContextPolicy for NeverRelocate {
    fn name(&self) -> &str {
        "never_relocate"
    }

    /// # Complexity
    /// O(1).
    fn decide(&mut self, _snapshot: &RegionSnapshot, _situation: &Situation) -> PolicyDecision {
        PolicyDecision::explore("relocation disabled (NeverRelocate ablation)")
    }
}
