//! Settings of the LLM policy. Always compiled (without the `llm` feature
//! too), so that configuration files naming the LLM policy parse and are
//! validated the same way whatever the features; only the policy itself
//! (`LlmPolicy`, cargo feature `llm`) needs the HTTP client.

use std::collections::BTreeMap;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::error::SupervisorError;

/// Settings of the LLM policy (serde-serialisable).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LlmConfig {
    /// Whether the policy asks the model at all (`false`: always continue).
    pub enabled: bool,
    /// Base URL of the OpenAI-compatible API, up to `/v1`.
    pub base_url: String,
    /// Model name.
    pub model: String,
    /// Environment variable holding the API key (`None`: no key; an unset
    /// variable sends no key, for local servers).
    pub api_key_env: Option<String>,
    /// Request timeout, seconds (default 60: a small model on a 2-core
    /// CPU needs 2-10 s for one decision, a 10 s limit left none usable).
    pub timeout_s: f64,
    /// Sampling temperature.
    pub temperature: f64,
    /// Token budget of the answer (`None`: server default; default 128,
    /// room for the three keys and a short reason).
    pub max_tokens: Option<u32>,
    /// At most one request every this many seconds (on the supervisor clock).
    pub min_interval_s: f64,
    /// Run requests on a background thread while the robot keeps exploring
    /// (default), as on the robot; `false` blocks the decision until the
    /// answer is there.
    pub asynchronous: bool,
    /// When an asynchronous answer takes effect ([`LlmLatency`]).
    pub latency: LlmLatency,
    /// Candidate regions are described to the model by their objects within
    /// this radius (m) of the candidate; `S_k` reaches `R_s` = 10 m, which
    /// for a near candidate repeats the robot's own region (the embedded
    /// prior uses 3 m for the same reason).
    pub candidate_radius_m: f64,
    /// Cached answers kept (the cache is cleared when full).
    pub max_cache_entries: usize,
    /// Honour `HTTP(S)_PROXY` / `NO_PROXY`.
    pub use_env_proxy: bool,
}

impl Default for LlmConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            base_url: "http://127.0.0.1:8000/v1".into(),
            model: "gpt-4o-mini".into(),
            api_key_env: Some("OPENAI_API_KEY".into()),
            timeout_s: 60.0,
            temperature: 0.0,
            max_tokens: Some(128),
            min_interval_s: 5.0,
            asynchronous: true,
            latency: LlmLatency::Arrival,
            candidate_radius_m: 3.0,
            max_cache_entries: 4096,
            use_env_proxy: true,
        }
    }
}

impl LlmConfig {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`SupervisorError::InvalidConfig`] for a non-positive, non-finite or
    /// unrepresentable (beyond [`Duration::MAX`]) timeout, a negative or non-finite interval or temperature, or an
    /// empty base URL or model.
    pub fn validate(&self) -> Result<(), SupervisorError> {
        let ok = self.timeout_s.is_finite()
            && self.timeout_s > 0.0
            && Duration::try_from_secs_f64(self.timeout_s).is_ok()
            && self.min_interval_s.is_finite()
            && self.min_interval_s >= 0.0
            && self.latency.is_valid()
            && self.candidate_radius_m.is_finite()
            && self.candidate_radius_m >= 0.0
            && self.temperature.is_finite()
            && self.temperature >= 0.0
            && !self.base_url.trim().is_empty()
            && !self.model.trim().is_empty();
        if ok {
            Ok(())
        } else {
            Err(SupervisorError::InvalidConfig(format!("{self:?}")))
        }
    }
}

/// When an asynchronous answer takes effect, on the supervisor's clock.
///
/// A question asked at time `t` is answered after a latency `L`; the answer
/// is applied at the first decision at or after `t + L` (if it still fits
/// the state then). On a robot the supervisor's clock is the wall clock and
/// [`LlmLatency::Arrival`] applies an answer as soon as it arrives. In a
/// simulator the clock is simulated time: [`LlmLatency::Measured`] and
/// [`LlmLatency::Fixed`] account the latency in simulated time (the policy
/// waits for an answer that is due in simulated time but not there yet), so
/// results do not depend on how fast the machine steps the simulation, and
/// a replay of a recording applies every answer at the same step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LlmLatency {
    /// As soon as it arrives (wall clock; a robot).
    #[default]
    Arrival,
    /// `L` = the exchange's measured latency (recorded, so replays are
    /// exact).
    Measured,
    /// `L` = this many seconds whatever the exchange took.
    Fixed {
        /// Seconds (finite, >= 0).
        seconds: f64,
    },
}

impl LlmLatency {
    fn is_valid(&self) -> bool {
        match self {
            Self::Fixed { seconds } => seconds.is_finite() && *seconds >= 0.0,
            Self::Arrival | Self::Measured => true,
        }
    }

    /// Parses `arrival`, `measured` or `fixed:S` (seconds).
    ///
    /// # Errors
    /// [`SupervisorError::InvalidConfig`] for anything else or a negative
    /// or non-finite `S`.
    pub fn parse(text: &str) -> Result<Self, SupervisorError> {
        let bad = || {
            SupervisorError::InvalidConfig(format!(
                "LLM latency '{text}': expected measured, fixed:SECONDS or arrival"
            ))
        };
        let latency = match text.trim() {
            "arrival" => Self::Arrival,
            "measured" => Self::Measured,
            other => {
                let s = other.strip_prefix("fixed:").ok_or_else(bad)?;
                Self::Fixed {
                    seconds: s.trim().parse().map_err(|_| bad())?,
                }
            }
        };
        if latency.is_valid() {
            Ok(latency)
        } else {
            Err(bad())
        }
    }
}

impl std::fmt::Display for LlmLatency {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Arrival => write!(f, "arrival"),
            Self::Measured => write!(f, "measured"),
            Self::Fixed { seconds } => write!(f, "fixed:{seconds}"),
        }
    }
}

/// Counters of the LLM policy over its life (one episode in the
/// simulator). Always compiled, so that reports can carry them whatever the
/// features.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct LlmStats {
    /// `decide` calls.
    pub calls: u64,
    /// Requests sent (a json_object retry counts separately).
    pub requests: u64,
    /// Answers served from the cache.
    pub cache_hits: u64,
    /// Valid model answers used.
    pub answers: u64,
    /// Failures (each fell back to continue exploring).
    pub failures: u64,
    /// Failures by cause ([`LlmFailure::kind`](crate::llm::LlmFailure::kind)
    /// names: `timeout`, `transport`, `http_status`, `malformed_response`,
    /// `invalid_answer`, `unknown_cluster`, ...).
    pub failures_by_cause: BTreeMap<String, u64>,
    /// Calls answered "rate limited".
    pub rate_limited: u64,
    /// Asynchronous answers dropped because they no longer fit the state.
    pub dropped_late_answers: u64,
    /// Whether json_object is in use (the endpoint rejected json_schema).
    pub json_object_fallback: bool,
    /// Latency of every exchange that reached the model (ms, in order).
    pub latency_ms: Vec<u64>,
    /// Prompt tokens reported by the server (`usage.prompt_tokens`), summed.
    pub prompt_tokens: u64,
    /// Completion tokens reported by the server, summed.
    pub completion_tokens: u64,
    /// Wall time spent waiting for answers that were due in simulated time
    /// ([`LlmLatency::Measured`], [`LlmLatency::Fixed`]), ms: a simulator
    /// leaves it out of its wall-clock budget.
    pub waited_ms: u64,
}

impl LlmStats {
    /// Adds `other`'s counters to these (the fallback flag is or-ed,
    /// latencies appended).
    ///
    /// # Complexity
    /// O(latencies + causes of `other`).
    pub fn merge(&mut self, other: &Self) {
        self.calls += other.calls;
        self.requests += other.requests;
        self.cache_hits += other.cache_hits;
        self.answers += other.answers;
        self.failures += other.failures;
        for (cause, n) in &other.failures_by_cause {
            *self.failures_by_cause.entry(cause.clone()).or_insert(0) += n;
        }
        self.rate_limited += other.rate_limited;
        self.dropped_late_answers += other.dropped_late_answers;
        self.json_object_fallback |= other.json_object_fallback;
        self.latency_ms.extend_from_slice(&other.latency_ms);
        self.prompt_tokens += other.prompt_tokens;
        self.completion_tokens += other.completion_tokens;
        self.waited_ms += other.waited_ms;
    }

    /// Share of the model's answers that were usable: valid answers over
    /// valid answers plus failures (`None` before any).
    pub fn valid_rate(&self) -> Option<f64> {
        let n = self.answers + self.failures;
        (n > 0).then(|| self.answers as f64 / n as f64)
    }

    /// The `q`-quantile (nearest rank, `q` in [0, 1]) of the latencies, ms
    /// (`None` without any).
    ///
    /// # Complexity
    /// O(n log n) for n latencies.
    pub fn latency_quantile_ms(&self, q: f64) -> Option<u64> {
        let mut sorted = self.latency_ms.clone();
        sorted.sort_unstable();
        let n = sorted.len();
        if n == 0 {
            return None;
        }
        let rank = (q.clamp(0.0, 1.0) * n as f64).ceil() as usize;
        sorted.get(rank.clamp(1, n) - 1).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn latency_parses_and_round_trips() {
        for (text, latency) in [
            ("measured", LlmLatency::Measured),
            ("arrival", LlmLatency::Arrival),
            ("fixed:2.5", LlmLatency::Fixed { seconds: 2.5 }),
            ("fixed:0", LlmLatency::Fixed { seconds: 0.0 }),
        ] {
            assert_eq!(LlmLatency::parse(text).unwrap(), latency);
            assert_eq!(LlmLatency::parse(&latency.to_string()).unwrap(), latency);
        }
        for bad in ["", "fast", "fixed:", "fixed:-1", "fixed:nan", "fixed:inf"] {
            assert!(LlmLatency::parse(bad).is_err(), "{bad}");
        }
        let bad = LlmConfig {
            latency: LlmLatency::Fixed { seconds: -1.0 },
            ..LlmConfig::default()
        };
        assert!(bad.validate().is_err());
    }

    #[test]
    fn latency_quantiles_are_nearest_rank() {
        let stats = LlmStats {
            latency_ms: vec![40, 10, 30, 20],
            ..LlmStats::default()
        };
        assert_eq!(stats.latency_quantile_ms(0.5), Some(20));
        assert_eq!(stats.latency_quantile_ms(0.99), Some(40));
        assert_eq!(stats.latency_quantile_ms(0.0), Some(10));
        assert_eq!(LlmStats::default().latency_quantile_ms(0.5), None);
        assert_eq!(LlmStats::default().valid_rate(), None);
    }

    fn stats() -> impl Strategy<Value = LlmStats> {
        (
            0u64..50,
            0u64..50,
            prop::collection::vec(0u64..10_000, 0..8),
            prop::collection::btree_map("[a-c]", 1u64..5, 0..3),
            any::<bool>(),
        )
            .prop_map(
                |(answers, failures, latency_ms, causes, fallback)| LlmStats {
                    calls: answers + failures,
                    requests: latency_ms.len() as u64,
                    answers,
                    failures,
                    failures_by_cause: causes,
                    json_object_fallback: fallback,
                    prompt_tokens: 3 * answers,
                    latency_ms,
                    ..LlmStats::default()
                },
            )
    }

    proptest! {
        /// Merging episodes' counters adds them up: totals, causes and
        /// latencies are those of the parts, in any grouping.
        #[test]
        fn merge_adds_up(parts in prop::collection::vec(stats(), 0..6)) {
            let mut total = LlmStats::default();
            for p in &parts {
                total.merge(p);
            }
            prop_assert_eq!(total.answers, parts.iter().map(|p| p.answers).sum::<u64>());
            prop_assert_eq!(total.failures, parts.iter().map(|p| p.failures).sum::<u64>());
            prop_assert_eq!(total.latency_ms.len(), parts.iter().map(|p| p.latency_ms.len()).sum::<usize>());
            prop_assert_eq!(
                total.failures_by_cause.values().sum::<u64>(),
                parts.iter().flat_map(|p| p.failures_by_cause.values()).sum::<u64>()
            );
            prop_assert_eq!(total.json_object_fallback, parts.iter().any(|p| p.json_object_fallback));
            if let Some(rate) = total.valid_rate() {
                prop_assert!((0.0..=1.0).contains(&rate));
            }
            // Grouping does not matter.
            let mut halves = LlmStats::default();
            let (a, b) = parts.split_at(parts.len() / 2);
            let (mut left, mut right) = (LlmStats::default(), LlmStats::default());
            a.iter().for_each(|p| left.merge(p));
            b.iter().for_each(|p| right.merge(p));
            halves.merge(&left);
            halves.merge(&right);
            prop_assert_eq!(halves, total);
        }
    }
}
