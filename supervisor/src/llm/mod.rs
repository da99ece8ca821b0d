//! The LLM policy (cargo feature `llm`): an OpenAI-compatible
//! `/v1/chat/completions` client deciding `continue_explore` or
//! `relocate_cluster`.
//!
//! * The model sees only a compact JSON snapshot ([`wire::snapshot_json`]):
//!   target, local context as label/support pairs, candidates as
//!   `{cluster_id, distance_m, context}`. Never images or maps.
//! * It is asked for strict JSON-schema output ([`wire::answer_schema`],
//!   generated with schemars from [`wire::LlmAnswer`]); when a server
//!   rejects `json_schema` (HTTP 400, 415 or 422) the request is repeated
//!   with `json_object` and the policy stays on `json_object` afterwards.
//! * Everything is validated ([`wire::parse_answer`],
//!   [`wire::validate_answer`]): any failure — disabled policy, transport
//!   error, timeout, HTTP error, malformed body, invalid JSON, extra fields,
//!   unknown action, unknown cluster id — means *continue exploring*, with
//!   the failure in the reason, in [`LlmPolicy::last_failure`] and counted
//!   in [`LlmStats`].
//! * Identical snapshots are answered from a cache (valid answers only).
//! * Rate limit: at most one request every `min_interval_s` (5 s).
//! * Asynchronous mode: the request runs on a background thread and the
//!   policy keeps answering *continue exploring* meanwhile, so the control
//!   loop never blocks; an answer that arrives after the mission changed
//!   (a new mission or a started relocation) is dropped.
//! * [`transport::RecordingTransport`] writes every exchange to JSONL and
//!   [`transport::ReplayTransport`] serves them back, so an evaluation with a
//!   model re-runs offline bit-for-bit (use the synchronous mode for that:
//!   asynchronous answers depend on wall-clock timing).
//!
//! # Example
//! ```no_run
//! use sornav_supervisor::{LlmConfig, LlmPolicy, Supervisor, SupervisorConfig};
//! let config = LlmConfig {
//!     base_url: "http://127.0.0.1:8000/v1".into(),
//!     model: "qwen2.5-7b-instruct".into(),
//!     ..LlmConfig::default()
//! };
//! let policy = LlmPolicy::http(config)?;
//! let supervisor: Supervisor<_, std::time::Instant> = Supervisor::new(policy, SupervisorConfig::default())?;
//! # Ok::<(), sornav_supervisor::SupervisorError>(())
//! ```

pub mod transport;
pub mod wire;

use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, TryRecvError};

use serde::{Deserialize, Serialize};
use tracing::{info, warn};

pub use crate::llm_config::LlmConfig;

use crate::context::RegionSnapshot;
use crate::error::SupervisorError;
use crate::policy::{ContextPolicy, PolicyDecision, Situation};
use transport::{HttpTransport, Transport, TransportError};
use wire::{LlmAnswer, ResponseFormat};

/// Why a model answer could not be used (the decision is then
/// *continue exploring*).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, thiserror::Error)]
#[serde(rename_all = "snake_case")]
pub enum LlmFailure {
    /// The policy is disabled.
    #[error("LLM policy disabled")]
    Disabled,
    /// The snapshot failed validation.
    #[error("invalid snapshot: {0}")]
    InvalidSnapshot(String),
    /// The request timed out.
    #[error("request timed out")]
    Timeout,
    /// No reply (connection, replay miss, ...).
    #[error("transport: {0}")]
    Transport(String),
    /// The server answered with an error status.
    #[error("HTTP status {status}: {body}")]
    HttpStatus {
        /// Status code.
        status: u16,
        /// Body (truncated to 200 bytes).
        body: String,
    },
    /// The body is not a chat completion with string content.
    #[error("malformed response: {0}")]
    MalformedResponse(String),
    /// The content is not a valid answer.
    #[error("invalid answer: {0}")]
    InvalidAnswer(String),
    /// The answer names a cluster that was not offered.
    #[error("unknown cluster id {0}")]
    UnknownCluster(u64),
    /// The background worker vanished.
    #[error("background request lost")]
    WorkerLost,
}

impl From<TransportError> for LlmFailure {
    fn from(e: TransportError) -> Self {
        match e {
            TransportError::Timeout => Self::Timeout,
            other => Self::Transport(other.to_string()),
        }
    }
}

/// Counters of the LLM policy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
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
    /// Calls answered "rate limited".
    pub rate_limited: u64,
    /// Asynchronous answers dropped because the mission changed.
    pub dropped_late_answers: u64,
    /// Whether the server rejected json_schema (json_object in use).
    pub json_object_fallback: bool,
}

/// The HTTP-facing half, shared with the worker thread.
struct Client {
    config: LlmConfig,
    transport: Arc<dyn Transport>,
    json_object: AtomicBool,
    requests: std::sync::atomic::AtomicU64,
}

impl Client {
    fn send(
        &self,
        snapshot_json: &str,
        format: ResponseFormat,
    ) -> Result<transport::HttpReply, LlmFailure> {
        let body = wire::request_body(
            &self.config.model,
            self.config.temperature,
            self.config.max_tokens,
            snapshot_json,
            format,
        );
        self.requests.fetch_add(1, Ordering::Relaxed);
        Ok(self.transport.post(&body)?)
    }

    /// One exchange including the json_object fallback.
    fn exchange(&self, snapshot_json: &str) -> Result<LlmAnswer, LlmFailure> {
        let mut reply = if self.json_object.load(Ordering::Relaxed) {
            self.send(snapshot_json, ResponseFormat::JsonObject)?
        } else {
            self.send(snapshot_json, ResponseFormat::JsonSchema)?
        };
        if matches!(reply.status, 400 | 415 | 422) && !self.json_object.load(Ordering::Relaxed) {
            warn!(target: "sornav_supervisor::llm", status = reply.status, "server rejected json_schema; falling back to json_object");
            let retry = self.send(snapshot_json, ResponseFormat::JsonObject)?;
            if retry.status == 200 {
                self.json_object.store(true, Ordering::Relaxed);
            }
            reply = retry;
        }
        if reply.status != 200 {
            let mut body = reply.body;
            if body.len() > 200 {
                let mut cut = 200;
                while !body.is_char_boundary(cut) {
                    cut -= 1;
                }
                body.truncate(cut);
            }
            return Err(LlmFailure::HttpStatus {
                status: reply.status,
                body,
            });
        }
        wire::parse_answer(&reply.body)
    }
}

struct Pending {
    mission_id: u64,
    key: String,
    receiver: Receiver<Result<LlmAnswer, LlmFailure>>,
}

/// The LLM policy.
pub struct LlmPolicy {
    client: Arc<Client>,
    cache: HashMap<String, LlmAnswer>,
    pending: Option<Pending>,
    last_request_s: Option<f64>,
    last_failure: Option<LlmFailure>,
    stats: LlmStats,
}

impl std::fmt::Debug for LlmPolicy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LlmPolicy")
            .field("config", &self.client.config)
            .field("stats", &self.stats())
            .field("pending", &self.pending.is_some())
            .finish_non_exhaustive()
    }
}

impl LlmPolicy {
    /// A policy talking HTTP to `config.base_url`.
    ///
    /// # Errors
    /// [`SupervisorError::InvalidConfig`] for an invalid configuration.
    pub fn http(config: LlmConfig) -> Result<Self, SupervisorError> {
        config.validate()?;
        let transport = HttpTransport::from_config(&config)?;
        Self::with_transport(config, Arc::new(transport))
    }

    /// A policy over any transport (recording, replay, tests).
    ///
    /// # Errors
    /// [`SupervisorError::InvalidConfig`] for an invalid configuration.
    pub fn with_transport(
        config: LlmConfig,
        transport: Arc<dyn Transport>,
    ) -> Result<Self, SupervisorError> {
        config.validate()?;
        Ok(Self {
            client: Arc::new(Client {
                config,
                transport,
                json_object: AtomicBool::new(false),
                requests: std::sync::atomic::AtomicU64::new(0),
            }),
            cache: HashMap::new(),
            pending: None,
            last_request_s: None,
            last_failure: None,
            stats: LlmStats::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &LlmConfig {
        &self.client.config
    }

    /// The last failure, if the last model exchange failed.
    pub fn last_failure(&self) -> Option<&LlmFailure> {
        self.last_failure.as_ref()
    }

    /// The counters.
    pub fn stats(&self) -> LlmStats {
        LlmStats {
            requests: self.client.requests.load(Ordering::Relaxed),
            json_object_fallback: self.client.json_object.load(Ordering::Relaxed),
            ..self.stats
        }
    }

    /// Whether an asynchronous request is in flight.
    pub fn is_pending(&self) -> bool {
        self.pending.is_some()
    }

    fn fail(&mut self, failure: LlmFailure) -> PolicyDecision {
        warn!(target: "sornav_supervisor::llm", %failure, "LLM answer unusable; continue exploring");
        self.stats.failures += 1;
        let decision = PolicyDecision::explore(format!("LLM fallback ({failure}); keep exploring"));
        self.last_failure = Some(failure);
        decision
    }

    /// Turns an exchange result into a decision (validation, caching).
    fn conclude(
        &mut self,
        key: String,
        result: Result<LlmAnswer, LlmFailure>,
        snapshot: &RegionSnapshot,
    ) -> PolicyDecision {
        let checked = result.and_then(|a| wire::validate_answer(&a, snapshot).map(|d| (a, d)));
        match checked {
            Ok((answer, decision)) => {
                self.stats.answers += 1;
                self.last_failure = None;
                if self.cache.len() >= self.client.config.max_cache_entries {
                    self.cache.clear();
                }
                if self.client.config.max_cache_entries > 0 {
                    self.cache.insert(key, answer);
                }
                decision
            }
            Err(failure) => self.fail(failure),
        }
    }

    fn rate_limited(&mut self, now_s: f64) -> bool {
        // A clock that restarted (supervisor reset, new episode) is not limited.
        let limited = self
            .last_request_s
            .is_some_and(|last| now_s >= last && now_s - last < self.client.config.min_interval_s);
        if limited {
            self.stats.rate_limited += 1;
        } else {
            self.last_request_s = Some(now_s);
        }
        limited
    }

    fn poll_pending(
        &mut self,
        snapshot: &RegionSnapshot,
        situation: &Situation,
    ) -> Option<PolicyDecision> {
        let pending = self.pending.as_ref()?;
        let result = match pending.receiver.try_recv() {
            Ok(r) => r,
            Err(TryRecvError::Empty) => {
                return Some(PolicyDecision::explore(
                    "LLM answer pending; keep exploring",
                ));
            }
            Err(TryRecvError::Disconnected) => Err(LlmFailure::WorkerLost),
        };
        let pending = self.pending.take()?;
        if pending.mission_id != situation.mission_id {
            self.stats.dropped_late_answers += 1;
            info!(target: "sornav_supervisor::llm", asked = pending.mission_id, now = situation.mission_id, "late LLM answer dropped: the mission changed");
            return None;
        }
        Some(self.conclude(pending.key, result, snapshot))
    }
}

impl ContextPolicy for LlmPolicy {
    fn name(&self) -> &str {
        "llm"
    }

    /// # Complexity
    /// O(snapshot size) plus, at most once per `min_interval_s`, one HTTP
    /// round trip (synchronous mode) or a thread spawn (asynchronous mode).
    fn decide(&mut self, snapshot: &RegionSnapshot, situation: &Situation) -> PolicyDecision {
        self.stats.calls += 1;
        if !self.client.config.enabled {
            return self.fail(LlmFailure::Disabled);
        }
        if let Err(e) = snapshot.validate() {
            return self.fail(LlmFailure::InvalidSnapshot(e.to_string()));
        }
        if let Some(decision) = self.poll_pending(snapshot, situation) {
            return decision;
        }
        let key = wire::snapshot_json(snapshot);
        if let Some(answer) = self.cache.get(&key).cloned() {
            self.stats.cache_hits += 1;
            return match wire::validate_answer(&answer, snapshot) {
                Ok(mut d) => {
                    d.reason = format!("cached: {}", d.reason);
                    d
                }
                Err(failure) => self.fail(failure),
            };
        }
        if self.rate_limited(situation.elapsed_s) {
            return PolicyDecision::explore("LLM rate limit; keep exploring");
        }
        if self.client.config.asynchronous {
            let (sender, receiver) = mpsc::channel();
            let client = Arc::clone(&self.client);
            let snapshot_json = key.clone();
            let spawned = std::thread::Builder::new()
                .name("sornav-llm".into())
                .spawn(move || {
                    // The receiver may be gone (policy dropped): nothing to do then.
                    let _ = sender.send(client.exchange(&snapshot_json));
                });
            if let Err(e) = spawned {
                return self.fail(LlmFailure::Transport(format!(
                    "cannot start worker thread: {e}"
                )));
            }
            self.pending = Some(Pending {
                mission_id: situation.mission_id,
                key,
                receiver,
            });
            return PolicyDecision::explore("LLM request sent; keep exploring meanwhile");
        }
        let result = self.client.exchange(&key);
        self.conclude(key, result, snapshot)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_validation_rejects_bad_values_without_panicking() {
        assert!(LlmConfig::default().validate().is_ok());
        let bad = [
            LlmConfig {
                timeout_s: 0.0,
                ..LlmConfig::default()
            },
            LlmConfig {
                timeout_s: f64::NAN,
                ..LlmConfig::default()
            },
            // Finite but beyond `Duration::MAX`: must be an error, not a
            // panic in `Duration::from_secs_f64`.
            LlmConfig {
                timeout_s: 1e30,
                ..LlmConfig::default()
            },
            LlmConfig {
                min_interval_s: -1.0,
                ..LlmConfig::default()
            },
            LlmConfig {
                temperature: f64::INFINITY,
                ..LlmConfig::default()
            },
            LlmConfig {
                model: " ".into(),
                ..LlmConfig::default()
            },
        ];
        for config in bad {
            assert!(config.validate().is_err(), "{config:?}");
            assert!(matches!(
                LlmPolicy::http(config),
                Err(SupervisorError::InvalidConfig(_))
            ));
        }
    }
}
