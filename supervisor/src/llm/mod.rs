//! The LLM policy (cargo feature `llm`): an OpenAI-compatible
//! `/v1/chat/completions` client deciding `continue_explore` or
//! `relocate_cluster`.
//!
//! * The model sees only a compact JSON snapshot ([`wire::snapshot_json`]):
//!   target first, the objects around the robot counted per label, and the
//!   candidates as `{cluster_id, floor, distance_m, objects}` with the
//!   objects within `candidate_radius_m` (3 m) of each candidate, counted
//!   per label. Never images or maps.
//! * It is asked for strict JSON-schema output ([`wire::answer_schema`],
//!   generated with schemars from [`wire::LlmAnswer`]); when a server
//!   rejects `json_schema` (HTTP 400, 415, 422, or a 5xx that a
//!   `json_object` retry does not get) the request is repeated with
//!   `json_object` and the schema in the prompt, and that endpoint stays on
//!   `json_object` for the rest of the process (every policy of it).
//! * Everything is validated ([`wire::parse_answer`],
//!   [`wire::validate_answer`]): any failure — disabled policy, transport
//!   error, timeout, HTTP error, malformed body, invalid JSON, extra fields,
//!   unknown action, unknown cluster id — means *continue exploring*, with
//!   the failure in the reason, in [`LlmPolicy::last_failure`] and counted
//!   by cause in [`LlmStats`] (with latencies and token counts).
//! * Identical snapshots are answered from a cache (valid answers only).
//! * Rate limit: at most one request every `min_interval_s` (5 s).
//! * Asynchronous mode (the default): the request runs on a background
//!   thread and the policy keeps answering *continue exploring* meanwhile;
//!   the answer takes effect when it is due ([`LlmLatency`]: on arrival, or
//!   after the measured or a fixed latency in simulated time) and only if it
//!   still fits the state: unless the question, as the model sees it, is
//!   unchanged (then the answer stands, as a cached one would), a relocation
//!   whose candidate is no longer offered under its cluster id, or is
//!   offered with other surroundings or on another floor, is dropped.
//! * [`transport::RecordingTransport`] writes every exchange (with its
//!   latency) to JSONL and [`transport::ReplayTransport`] serves them back,
//!   so an evaluation with a model re-runs offline bit-for-bit (with
//!   [`LlmLatency::Measured`] or [`LlmLatency::Fixed`] in asynchronous
//!   mode too: the answers take effect at the same simulated times).
//! * [`transport::check_endpoint`] checks a server before a run (reachable,
//!   serves the model).
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

use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock, PoisonError};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};
use tracing::{info, warn};

pub use crate::llm_config::{LlmConfig, LlmLatency, LlmStats};

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

impl LlmFailure {
    /// The cause's name for counters ([`LlmStats::failures_by_cause`]):
    /// `disabled`, `invalid_snapshot`, `timeout`, `transport`,
    /// `http_status`, `malformed_response`, `invalid_answer`,
    /// `unknown_cluster` or `worker_lost`.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Disabled => "disabled",
            Self::InvalidSnapshot(_) => "invalid_snapshot",
            Self::Timeout => "timeout",
            Self::Transport(_) => "transport",
            Self::HttpStatus { .. } => "http_status",
            Self::MalformedResponse(_) => "malformed_response",
            Self::InvalidAnswer(_) => "invalid_answer",
            Self::UnknownCluster(_) => "unknown_cluster",
            Self::WorkerLost => "worker_lost",
        }
    }
}

impl From<TransportError> for LlmFailure {
    fn from(e: TransportError) -> Self {
        match e {
            TransportError::Timeout => Self::Timeout,
            other => Self::Transport(other.to_string()),
        }
    }
}

/// Endpoints (base URL) known to reject `json_schema` and to accept
/// `json_object`: remembered for the whole process, so that a run that
/// builds a policy per episode pays the rejected request once.
fn json_object_endpoints() -> &'static Mutex<HashSet<String>> {
    static ENDPOINTS: OnceLock<Mutex<HashSet<String>>> = OnceLock::new();
    ENDPOINTS.get_or_init(|| Mutex::new(HashSet::new()))
}

/// What one exchange with the model produced, with its own counters (they
/// enter the policy's [`LlmStats`] when the policy takes the result, so
/// that a request still in flight at the end of an episode is not half
/// counted, and live runs and replays count alike).
#[derive(Clone, Debug)]
struct Exchanged {
    result: Result<LlmAnswer, LlmFailure>,
    /// Latency of the exchange (all its requests), ms.
    latency_ms: u64,
    /// Requests sent (a json_object retry counts).
    requests: u64,
    /// Latency of every request that got a reply, ms.
    latencies_ms: Vec<u64>,
    prompt_tokens: u64,
    completion_tokens: u64,
}

impl Exchanged {
    /// No exchange: the worker never delivered (nothing sent, nothing
    /// counted).
    fn lost() -> Self {
        Self {
            result: Err(LlmFailure::WorkerLost),
            latency_ms: 0,
            requests: 0,
            latencies_ms: Vec::new(),
            prompt_tokens: 0,
            completion_tokens: 0,
        }
    }
}

/// One request's reply and latency.
type Sent = (Result<transport::HttpReply, LlmFailure>, u64);

/// The HTTP-facing half, shared with the worker thread.
struct Client {
    config: LlmConfig,
    transport: Arc<dyn Transport>,
    json_object: AtomicBool,
}

impl Client {
    fn uses_json_object(&self) -> bool {
        self.json_object.load(Ordering::Relaxed)
            || json_object_endpoints()
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .contains(&self.config.base_url)
    }

    fn remember_json_object(&self) {
        self.json_object.store(true, Ordering::Relaxed);
        json_object_endpoints()
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .insert(self.config.base_url.clone());
    }

    /// One request; the reply's latency is the transport's measurement, or
    /// the time the call took (a timeout counts as the timeout).
    fn send(&self, snapshot_json: &str, format: ResponseFormat) -> Sent {
        let body = wire::request_body(
            &self.config.model,
            self.config.temperature,
            self.config.max_tokens,
            snapshot_json,
            format,
        );
        let t0 = Instant::now();
        let reply = self.transport.post(&body);
        let latency_ms = match &reply {
            Ok(r) => r.latency_ms.unwrap_or_else(|| transport::millis_since(t0)),
            Err(TransportError::Timeout) => (self.config.timeout_s * 1e3).round() as u64,
            // A request the recorded run never saw answered (it was still in
            // flight when the episode ended): with a measured latency it is
            // never due, as it was not then.
            Err(TransportError::NotRecorded) => u64::MAX,
            Err(_) => transport::millis_since(t0),
        };
        (reply.map_err(LlmFailure::from), latency_ms)
    }

    /// One exchange including the json_object fallback.
    fn exchange(&self, snapshot_json: &str) -> Exchanged {
        let mut exchanged = Exchanged::lost();
        let mut count = |(reply, latency_ms): Sent| {
            exchanged.requests += 1;
            exchanged.latency_ms = exchanged.latency_ms.saturating_add(latency_ms);
            if let Ok(r) = &reply {
                exchanged.latencies_ms.push(latency_ms);
                let (prompt, completion) = wire::parse_usage(&r.body);
                exchanged.prompt_tokens += prompt;
                exchanged.completion_tokens += completion;
            }
            reply
        };
        let json_object = self.uses_json_object();
        let format = if json_object {
            ResponseFormat::JsonObject
        } else {
            ResponseFormat::JsonSchema
        };
        let mut reply = count(self.send(snapshot_json, format));
        // A rejected json_schema: 400/415/422, or a 5xx (llama-cpp-python's
        // server answers 500); the json_object retry tells a server that
        // cannot do schemas from one that is failing.
        if !json_object
            && let Ok(r) = &reply
            && (matches!(r.status, 400 | 415 | 422) || (500..600).contains(&r.status))
        {
            warn!(target: "sornav_supervisor::llm", status = r.status, "server rejected json_schema; retrying with json_object");
            let retry = count(self.send(snapshot_json, ResponseFormat::JsonObject));
            if retry.as_ref().is_ok_and(|r| r.status == 200) {
                self.remember_json_object();
            }
            reply = retry;
        }
        exchanged.result = reply.and_then(|reply| {
            if reply.status != 200 {
                return Err(LlmFailure::HttpStatus {
                    status: reply.status,
                    body: transport::truncate_bytes(reply.body, 200),
                });
            }
            wire::parse_answer(&reply.body)
        });
        exchanged
    }
}

/// The slot a background exchange delivers into.
type Slot = Arc<(Mutex<Option<Exchanged>>, Condvar)>;

/// An asynchronous question in flight.
struct Pending {
    /// The question (for the fit check) and its cache key.
    snapshot: RegionSnapshot,
    key: String,
    /// When it was asked, on the supervisor's clock (s) and on the wall.
    asked_s: f64,
    sent: Instant,
    slot: Slot,
}

/// Wall-time margin (s) of the simulated-time wait for a measured latency:
/// an answer not delivered this long after it would have been due is taken
/// as not due yet (covers the hand-over from the worker thread).
const DUE_MARGIN_S: f64 = 0.25;

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

    /// The counters (of the exchanges whose result the policy took: a
    /// request still in flight is not counted yet).
    pub fn stats(&self) -> LlmStats {
        LlmStats {
            json_object_fallback: self.client.uses_json_object(),
            ..self.stats.clone()
        }
    }

    /// Adds an exchange's counters to the policy's.
    fn count(&mut self, exchanged: &Exchanged) {
        self.stats.requests += exchanged.requests;
        self.stats
            .latency_ms
            .extend_from_slice(&exchanged.latencies_ms);
        self.stats.prompt_tokens += exchanged.prompt_tokens;
        self.stats.completion_tokens += exchanged.completion_tokens;
    }

    /// Whether an asynchronous request is in flight.
    pub fn is_pending(&self) -> bool {
        self.pending.is_some()
    }

    fn fail(&mut self, failure: LlmFailure) -> PolicyDecision {
        warn!(target: "sornav_supervisor::llm", %failure, "LLM answer unusable; continue exploring");
        self.stats.failures += 1;
        *self
            .stats
            .failures_by_cause
            .entry(failure.kind().to_owned())
            .or_insert(0) += 1;
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
                self.remember(key, answer);
                decision
            }
            Err(failure) => self.fail(failure),
        }
    }

    /// Caches a valid answer (the cache is cleared when full).
    fn remember(&mut self, key: String, answer: LlmAnswer) {
        if self.cache.len() >= self.client.config.max_cache_entries {
            self.cache.clear();
        }
        if self.client.config.max_cache_entries > 0 {
            self.cache.insert(key, answer);
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

    /// The answer of the pending question if it is due at `now_s`
    /// ([`LlmLatency`]), waiting for it when it is due in simulated time
    /// but not delivered yet; `None` when it is not due.
    fn due_answer(&mut self, now_s: f64) -> Option<Exchanged> {
        let pending = self.pending.as_ref()?;
        let (lock, ready) = &*pending.slot;
        let waited = Instant::now();
        let mut slot = lock.lock().unwrap_or_else(PoisonError::into_inner);
        let since_asked_s = now_s - pending.asked_s;
        // The worker always delivers within the request timeout; the cap
        // only guards against a transport that ignores it.
        let secs = |s: f64| Duration::try_from_secs_f64(s.max(0.0)).unwrap_or(Duration::MAX);
        let cap = secs(self.client.config.timeout_s * 2.0 + 5.0);
        let due = match self.client.config.latency {
            LlmLatency::Arrival => slot.is_some(),
            LlmLatency::Fixed { seconds } => {
                if since_asked_s >= seconds {
                    let (guard, _) = ready
                        .wait_timeout_while(slot, cap, |s| s.is_none())
                        .unwrap_or_else(PoisonError::into_inner);
                    slot = guard;
                    true
                } else {
                    false
                }
            }
            LlmLatency::Measured => {
                // Wait while it could still turn out due: until it arrives or
                // the wall time since sending passes the simulated time
                // since asking.
                let limit = secs(since_asked_s + DUE_MARGIN_S).min(cap);
                let left = limit.saturating_sub(pending.sent.elapsed());
                if slot.is_none() && !left.is_zero() {
                    let (guard, _) = ready
                        .wait_timeout_while(slot, left, |s| s.is_none())
                        .unwrap_or_else(PoisonError::into_inner);
                    slot = guard;
                }
                slot.as_ref()
                    .is_some_and(|e| e.latency_ms as f64 / 1e3 <= since_asked_s)
            }
        };
        let answer = if due { slot.take() } else { None };
        drop(slot);
        if !matches!(self.client.config.latency, LlmLatency::Arrival) {
            self.stats.waited_ms += transport::millis_since(waited);
        }
        if due && answer.is_none() {
            // Due, but the worker never delivered.
            return Some(Exchanged::lost());
        }
        answer
    }

    /// Applies a due asynchronous answer to the current snapshot: a
    /// relocation must still fit ([`wire::still_fits`]), and is re-expressed
    /// for the current snapshot's candidates.
    fn apply_due(
        &mut self,
        pending: Pending,
        exchanged: Exchanged,
        snapshot: &RegionSnapshot,
    ) -> Option<PolicyDecision> {
        self.count(&exchanged);
        if wire::snapshot_json(snapshot, self.client.config.candidate_radius_m) == pending.key {
            // The question is unchanged: the answer stands as it is.
            return Some(self.conclude(pending.key, exchanged.result, snapshot));
        }
        let mut result = exchanged.result;
        let asked = result.clone();
        if let Ok(answer) = &mut result
            && answer.action == wire::LlmAction::RelocateCluster
            && let Some(id) = answer.cluster_id
        {
            if wire::named_candidate(&pending.snapshot, id).is_none() {
                return Some(self.fail(LlmFailure::UnknownCluster(id)));
            }
            match wire::still_fits(
                id,
                &pending.snapshot,
                snapshot,
                self.client.config.candidate_radius_m,
            ) {
                Some(now) => answer.cluster_id = Some(now),
                None => {
                    // Valid for the question asked: cached, counted, not applied.
                    let _ = self.conclude(pending.key, result, &pending.snapshot);
                    self.stats.dropped_late_answers += 1;
                    info!(target: "sornav_supervisor::llm", cluster_id = id, "late LLM answer dropped: its candidate no longer fits");
                    return None;
                }
            }
        }
        let original = asked.ok().filter(|a| result.as_ref().is_ok_and(|r| r != a));
        let decision = self.conclude(pending.key.clone(), result, snapshot);
        // Cached under the question asked, in its numbering.
        if let Some(answer) = original {
            self.remember(pending.key, answer);
        }
        Some(decision)
    }

    /// Starts an asynchronous exchange.
    fn ask_in_background(
        &mut self,
        snapshot: &RegionSnapshot,
        key: String,
        now_s: f64,
    ) -> PolicyDecision {
        let slot: Slot = Arc::new((Mutex::new(None), Condvar::new()));
        let client = Arc::clone(&self.client);
        let snapshot_json = key.clone();
        let worker_slot = Arc::clone(&slot);
        let spawned = std::thread::Builder::new()
            .name("sornav-llm".into())
            .spawn(move || {
                let exchanged = client.exchange(&snapshot_json);
                let (lock, ready) = &*worker_slot;
                *lock.lock().unwrap_or_else(PoisonError::into_inner) = Some(exchanged);
                ready.notify_all();
            });
        if let Err(e) = spawned {
            return self.fail(LlmFailure::Transport(format!(
                "cannot start worker thread: {e}"
            )));
        }
        self.pending = Some(Pending {
            snapshot: snapshot.clone(),
            key,
            asked_s: now_s,
            sent: Instant::now(),
            slot,
        });
        PolicyDecision::explore("LLM request sent; keep exploring meanwhile")
    }
}

impl ContextPolicy for LlmPolicy {
    fn name(&self) -> &str {
        "llm"
    }

    /// # Complexity
    /// O(snapshot size) plus, at most once per `min_interval_s`, one HTTP
    /// round trip (synchronous mode) or a thread spawn (asynchronous mode);
    /// with a simulated-time latency, a wait for an answer that is due but
    /// not delivered yet.
    fn decide(&mut self, snapshot: &RegionSnapshot, situation: &Situation) -> PolicyDecision {
        self.stats.calls += 1;
        if !self.client.config.enabled {
            return self.fail(LlmFailure::Disabled);
        }
        if let Err(e) = snapshot.validate() {
            return self.fail(LlmFailure::InvalidSnapshot(e.to_string()));
        }
        let now_s = situation.elapsed_s;
        if let Some(pending) = &self.pending {
            if now_s < pending.asked_s {
                // The clock restarted (a new episode): the question is moot.
                self.pending = None;
                self.stats.dropped_late_answers += 1;
            } else {
                match self.due_answer(now_s) {
                    None => {
                        return PolicyDecision::explore("LLM answer pending; keep exploring");
                    }
                    Some(exchanged) => {
                        let pending = self.pending.take();
                        if let Some(decision) =
                            pending.and_then(|p| self.apply_due(p, exchanged, snapshot))
                        {
                            return decision;
                        }
                    }
                }
            }
        }
        let key = wire::snapshot_json(snapshot, self.client.config.candidate_radius_m);
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
        if self.rate_limited(now_s) {
            return PolicyDecision::explore("LLM rate limit; keep exploring");
        }
        if self.client.config.asynchronous {
            return self.ask_in_background(snapshot, key, now_s);
        }
        let exchanged = self.client.exchange(&key);
        self.count(&exchanged);
        self.conclude(key, exchanged.result, snapshot)
    }

    fn llm_stats(&self) -> Option<LlmStats> {
        Some(self.stats())
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
