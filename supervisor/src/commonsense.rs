//! The embedded commonsense policy: relocate only on `Conflict(g, S_r)`, then
//! choose the candidate whose context is most compatible with the target,
//! discounted by graph distance.
//!
//! # Algorithm
//! 1. Keep the local objects with support `>= min_support`; count the
//!    distinct labels the prior knows (*informative* labels).
//! 2. `Conflict(g, S_r)` holds when there are at least
//!    `min_informative_objects` informative labels, the target is not among
//!    them, and `P(g | S_r) < conflict_max_posterior`
//!    ([`CooccurrencePrior::posterior`]). Otherwise — relevance, mixed
//!    evidence, too few observations, an unknown target — keep exploring.
//! 3. Only under conflict: for each candidate `k`, `P_k = P(g | S_k)` over its
//!    objects with enough support within `candidate_radius_m`; a candidate is
//!    eligible when `P_k >= P(g | S_r) + margin`; pick the eligible candidate
//!    maximising `P_k * exp(-d_k / distance_scale_m)` (ties: nearer, then
//!    smaller id). No eligible candidate keeps exploring. A candidate with
//!    no usable objects yet (an unexplored region) scores the target's base
//!    rate, so under a clear conflict an unexplored region can be preferred
//!    to staying in a contradicting one; one on another floor (an
//!    unexplored floor reached by stairs) scores
//!    `1 - (1 - base rate)^REGIONS_PER_FLOOR`.
//!
//! A distant cluster that merely looks more promising can never trigger a
//! relocation: step 3 is only reached through step 2.
//!
//! # Complexity
//! O((m + sum_k m_k) log V) for m local objects, m_k objects of candidate k
//! and a vocabulary of V labels.

use serde::{Deserialize, Serialize};
use tracing::debug;

use crate::context::RegionSnapshot;
use crate::error::SupervisorError;
use crate::policy::{ContextPolicy, PolicyDecision, Situation};
use crate::prior::{CooccurrencePrior, Posterior};

/// Regions (rooms) per floor in HM3D: the median of `num_rooms /
/// num_floors` over the 800 train scenes of
/// `hm3d-sem-stats/hm3d_scene_metadata.csv` (HM3D-Semantics, Ramakrishnan
/// et al.; derived figure) is 5.67; over the 100 val scenes it is 5.17.
/// An unexplored floor (a candidate on another floor with no objects seen
/// yet) holds the target with probability `1 - (1 - b)^REGIONS_PER_FLOOR`
/// for the target's per-region base rate `b`. The statistics give no floor
/// per region, so no "bedrooms upstairs" cue can be learned from them.
pub const REGIONS_PER_FLOOR: f64 = 5.67;

/// Thresholds of the commonsense policy (serde-serialisable, all configurable).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CommonsenseConfig {
    /// Minimum support of an object to count as evidence (the paper's
    /// `N_min` = 10 voxels).
    pub min_support: f64,
    /// Minimum number of distinct informative labels before a conflict can
    /// be declared.
    pub min_informative_objects: usize,
    /// `Conflict` needs `P(g | S_r)` below this.
    pub conflict_max_posterior: f64,
    /// Candidate objects farther than this from their cluster are not
    /// evidence about the candidate region (metres; default 3). `S_k`
    /// lists objects up to `R_s` = 10 m away (what an LLM is shown, with
    /// distances to weigh); this policy reads presence only, and with a
    /// 10 m radius every candidate of a small house would share the
    /// current context's objects, so none could ever beat it.
    pub candidate_radius_m: f64,
    /// Graph-distance discount scale, metres: score = `P_k exp(-d_k / scale)`.
    pub distance_scale_m: f64,
    /// A candidate must beat the current context's posterior by this much.
    pub margin: f64,
}

impl Default for CommonsenseConfig {
    fn default() -> Self {
        Self {
            min_support: 10.0,
            min_informative_objects: 3,
            conflict_max_posterior: 0.05,
            candidate_radius_m: 3.0,
            distance_scale_m: 20.0,
            margin: 0.1,
        }
    }
}

impl CommonsenseConfig {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`SupervisorError::InvalidConfig`] for a non-finite value, a negative
    /// support, radius or margin, a non-positive distance scale or a
    /// posterior threshold outside `[0, 1]`.
    pub fn validate(&self) -> Result<(), SupervisorError> {
        let ok = self.min_support.is_finite()
            && self.min_support >= 0.0
            && (0.0..=1.0).contains(&self.conflict_max_posterior)
            && self.candidate_radius_m >= 0.0
            && !self.candidate_radius_m.is_nan()
            && self.distance_scale_m.is_finite()
            && self.distance_scale_m > 0.0
            && self.margin.is_finite()
            && self.margin >= 0.0;
        if ok {
            Ok(())
        } else {
            Err(SupervisorError::InvalidConfig(format!("{self:?}")))
        }
    }
}

/// The outcome of the conflict test on the robot's context.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConflictAssessment {
    /// `Conflict(g, S_r)`.
    pub conflict: bool,
    /// The posterior, when the prior knows the target.
    pub posterior: Option<Posterior>,
    /// Why.
    pub reason: String,
}

/// The commonsense policy over a [`CooccurrencePrior`].
#[derive(Clone, Debug)]
pub struct CommonsensePolicy<'p> {
    prior: &'p CooccurrencePrior,
    config: CommonsenseConfig,
}

impl Default for CommonsensePolicy<'static> {
    fn default() -> Self {
        Self {
            prior: CooccurrencePrior::embedded(),
            config: CommonsenseConfig::default(),
        }
    }
}

impl CommonsensePolicy<'static> {
    /// The policy over the embedded HM3D prior.
    ///
    /// # Errors
    /// [`SupervisorError::InvalidConfig`] for an invalid configuration.
    pub fn embedded(config: CommonsenseConfig) -> Result<Self, SupervisorError> {
        Self::new(CooccurrencePrior::embedded(), config)
    }
}

impl<'p> CommonsensePolicy<'p> {
    /// The policy over any prior table.
    ///
    /// # Errors
    /// [`SupervisorError::InvalidConfig`] for an invalid configuration.
    pub fn new(
        prior: &'p CooccurrencePrior,
        config: CommonsenseConfig,
    ) -> Result<Self, SupervisorError> {
        config.validate()?;
        Ok(Self { prior, config })
    }

    /// The configuration.
    pub fn config(&self) -> &CommonsenseConfig {
        &self.config
    }

    /// Evaluates `Conflict(g, S_r)` (steps 1-2 of the module's algorithm).
    ///
    /// # Complexity
    /// O(m log V).
    pub fn assess(&self, snapshot: &RegionSnapshot) -> ConflictAssessment {
        let labels = snapshot
            .local_context
            .iter()
            .filter(|o| o.support >= self.config.min_support)
            .map(|o| o.label.as_str());
        let Some(post) = self.prior.posterior(&snapshot.target, labels) else {
            return ConflictAssessment {
                conflict: false,
                posterior: None,
                reason: format!("no prior knowledge about target {:?}", snapshot.target),
            };
        };
        let (conflict, reason) = if post.target_observed {
            (
                false,
                "the target's own category is in the local context".to_owned(),
            )
        } else if post.informative_labels < self.config.min_informative_objects {
            (
                false,
                format!(
                    "too little evidence: {} informative objects (< {})",
                    post.informative_labels, self.config.min_informative_objects
                ),
            )
        } else if post.probability >= self.config.conflict_max_posterior {
            (
                false,
                format!(
                    "context is compatible or mixed: P({}|S_r) = {:.3} >= {:.3} (base rate {:.3})",
                    snapshot.target,
                    post.probability,
                    self.config.conflict_max_posterior,
                    post.base_rate
                ),
            )
        } else {
            (
                true,
                format!(
                    "conflict: P({}|S_r) = {:.3} < {:.3} from {} informative objects (base rate {:.3})",
                    snapshot.target,
                    post.probability,
                    self.config.conflict_max_posterior,
                    post.informative_labels,
                    post.base_rate
                ),
            )
        };
        ConflictAssessment {
            conflict,
            posterior: Some(post),
            reason,
        }
    }

    fn choose(&self, snapshot: &RegionSnapshot, current: f64) -> Option<(u64, f64, f64)> {
        let mut best: Option<(u64, f64, f64, f64)> = None; // id, P_k, d_k, score
        for c in &snapshot.candidates {
            let labels = c
                .context
                .iter()
                .filter(|o| {
                    o.support >= self.config.min_support
                        && o.distance_m <= self.config.candidate_radius_m
                })
                .map(|o| o.label.as_str());
            let labels: Vec<&str> = labels.collect();
            let Some(post) = self
                .prior
                .posterior(&snapshot.target, labels.iter().copied())
            else {
                continue;
            };
            // An unexplored floor holds several regions: the target is on
            // it unless it is in none of them.
            let probability = if c.floor != 0 && labels.is_empty() {
                1.0 - (1.0 - post.base_rate).powf(REGIONS_PER_FLOOR)
            } else {
                post.probability
            };
            if probability < current + self.config.margin {
                continue;
            }
            let score = probability * (-c.distance_m / self.config.distance_scale_m).exp();
            let better = match best {
                None => true,
                Some((id, _, d, s)) => {
                    score > s
                        || (score == s
                            && (c.distance_m < d || (c.distance_m == d && c.cluster_id < id)))
                }
            };
            if better {
                best = Some((c.cluster_id, probability, c.distance_m, score));
            }
        }
        best.map(|(id, p, d, _)| (id, p, d))
    }
}

impl ContextPolicy for CommonsensePolicy<'_> {
    fn name(&self) -> &str {
        "commonsense"
    }

    fn decide(&mut self, snapshot: &RegionSnapshot, _situation: &Situation) -> PolicyDecision {
        if let Err(e) = snapshot.validate() {
            return PolicyDecision::explore(format!("invalid snapshot ({e}); keep exploring"));
        }
        let assessment = self.assess(snapshot);
        debug!(target: "sornav_supervisor::commonsense", conflict = assessment.conflict, reason = %assessment.reason);
        let post = match assessment.posterior {
            Some(post) if assessment.conflict => post,
            _ => return PolicyDecision::explore(assessment.reason),
        };
        match self.choose(snapshot, post.probability) {
            Some((id, p, d)) => PolicyDecision::relocate(
                id,
                format!(
                    "{}; cluster {id} at {d:.1} m has P({}|S_k) = {p:.3}",
                    assessment.reason, snapshot.target
                ),
            ),
            None => PolicyDecision::explore(format!(
                "{}; but no candidate beats it by the margin {:.2}",
                assessment.reason, self.config.margin
            )),
        }
    }
}
