//! How requests reach a model: plain HTTP (ureq), recording to JSONL, and
//! offline replay of a recording.

use std::collections::{HashMap, VecDeque};
use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use super::LlmConfig;
use crate::error::SupervisorError;

/// An HTTP reply: status, body text and how long it took.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct HttpReply {
    /// HTTP status code.
    pub status: u16,
    /// Body text.
    pub body: String,
    /// Time from sending the request to the end of the reply, ms (`None`:
    /// not measured, e.g. a recording made before latencies were kept).
    /// Recorded and replayed, so that latency-dependent behaviour (the
    /// simulated-time latency of asynchronous decisions) replays exactly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub latency_ms: Option<u64>,
}

impl HttpReply {
    /// A reply without a measured latency.
    pub fn new(status: u16, body: impl Into<String>) -> Self {
        Self {
            status,
            body: body.into(),
            latency_ms: None,
        }
    }
}

/// Milliseconds since `t0`, saturating.
pub(crate) fn millis_since(t0: Instant) -> u64 {
    u64::try_from(t0.elapsed().as_millis()).unwrap_or(u64::MAX)
}

/// Why no reply arrived.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TransportError {
    /// The request did not complete within the timeout.
    Timeout,
    /// Connection, DNS, TLS or protocol failure.
    Connection(String),
    /// Replay: this request is not in the recording.
    NotRecorded,
}

impl std::fmt::Display for TransportError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Timeout => write!(f, "timeout"),
            Self::Connection(m) => write!(f, "connection failed: {m}"),
            Self::NotRecorded => write!(f, "request not in the replay recording"),
        }
    }
}

/// Something that POSTs a chat-completions body and returns the reply.
/// Implementations must be shareable with the asynchronous worker thread.
pub trait Transport: Send + Sync {
    /// Sends `body` (JSON text) and waits for the reply.
    fn post(&self, body: &str) -> Result<HttpReply, TransportError>;
}

/// HTTP via ureq to `<base_url>/chat/completions`.
#[derive(Debug)]
pub struct HttpTransport {
    agent: ureq::Agent,
    url: String,
    api_key: Option<String>,
}

impl HttpTransport {
    /// A client for `base_url` (e.g. `http://127.0.0.1:8000/v1`).
    ///
    /// `api_key` is sent as a bearer token when present; `use_env_proxy`
    /// honours `HTTP(S)_PROXY` / `NO_PROXY`.
    pub fn new(
        base_url: &str,
        api_key: Option<String>,
        timeout: Duration,
        use_env_proxy: bool,
    ) -> Self {
        let mut config = ureq::Agent::config_builder()
            .timeout_global(Some(timeout))
            .http_status_as_error(false);
        if !use_env_proxy {
            config = config.proxy(None);
        }
        Self {
            agent: config.build().into(),
            url: format!("{}/chat/completions", base_url.trim_end_matches('/')),
            api_key,
        }
    }

    /// A client for `config.base_url` with its timeout and proxy setting;
    /// the API key is read from the variable `config.api_key_env` (none when
    /// unset, unset in the environment, or empty).
    ///
    /// Only the transport settings are checked here;
    /// [`LlmConfig::validate`] checks the rest.
    ///
    /// # Errors
    /// [`SupervisorError::InvalidConfig`] when `config.timeout_s` is not a
    /// representable duration (negative, non-finite or too large).
    pub fn from_config(config: &LlmConfig) -> Result<Self, SupervisorError> {
        let timeout = Duration::try_from_secs_f64(config.timeout_s).map_err(|e| {
            SupervisorError::InvalidConfig(format!("timeout_s {}: {e}", config.timeout_s))
        })?;
        let api_key = config
            .api_key_env
            .as_deref()
            .and_then(|var| std::env::var(var).ok())
            .filter(|k| !k.is_empty());
        Ok(Self::new(
            &config.base_url,
            api_key,
            timeout,
            config.use_env_proxy,
        ))
    }
}

fn map_ureq(e: ureq::Error) -> TransportError {
    match e {
        ureq::Error::Timeout(_) => TransportError::Timeout,
        ureq::Error::Io(io)
            if matches!(
                io.kind(),
                std::io::ErrorKind::TimedOut | std::io::ErrorKind::WouldBlock
            ) =>
        {
            TransportError::Timeout
        }
        other => TransportError::Connection(other.to_string()),
    }
}

impl Transport for HttpTransport {
    fn post(&self, body: &str) -> Result<HttpReply, TransportError> {
        let mut request = self
            .agent
            .post(&self.url)
            .header("content-type", "application/json");
        if let Some(key) = &self.api_key {
            request = request.header("authorization", format!("Bearer {key}"));
        }
        let t0 = Instant::now();
        let mut response = request.send(body).map_err(map_ureq)?;
        let status = response.status().as_u16();
        let body = response.body_mut().read_to_string().map_err(map_ureq)?;
        Ok(HttpReply {
            status,
            body,
            latency_ms: Some(millis_since(t0)),
        })
    }
}

/// Why the endpoint check ([`check_endpoint`]) failed.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum EndpointError {
    /// Nothing answered at the URL.
    #[error(
        "cannot reach the LLM endpoint {url}: {message} (is the server running and listening there? the URL is the base up to /v1, e.g. http://127.0.0.1:8080/v1)"
    )]
    Unreachable {
        /// The URL asked.
        url: String,
        /// The client's message.
        message: String,
    },
    /// The server lists its models and the configured one is not among them.
    #[error("the LLM endpoint {url} does not serve the model '{model}'; it serves: {available}")]
    UnknownModel {
        /// The URL asked.
        url: String,
        /// The configured model.
        model: String,
        /// The models the server lists.
        available: String,
    },
    /// The server answered with an error status.
    #[error("the LLM endpoint {url} answered HTTP {status}: {body}")]
    Status {
        /// The URL asked.
        url: String,
        /// The status code.
        status: u16,
        /// The body, cut to 200 bytes.
        body: String,
    },
}

/// `text` cut to at most `max` bytes at a character boundary.
pub(crate) fn truncate_bytes(mut text: String, max: usize) -> String {
    if text.len() > max {
        let mut cut = max;
        while !text.is_char_boundary(cut) {
            cut -= 1;
        }
        text.truncate(cut);
    }
    text
}

/// Model ids of an OpenAI `GET /models` body (`{"data": [{"id": ...}]}`);
/// `None` when the body is not such a list.
fn model_ids(body: &str) -> Option<Vec<String>> {
    let v: serde_json::Value = serde_json::from_str(body).ok()?;
    v.get("data")?
        .as_array()?
        .iter()
        .map(|m| m.get("id").and_then(|id| id.as_str()).map(str::to_owned))
        .collect()
}

/// Checks, before a run, that `config.base_url` is an OpenAI-compatible
/// endpoint serving `config.model`: `GET <base_url>/models` must answer, and
/// when it lists models the configured one must be among them. A server
/// without a models list (404 / 405) is asked one tiny chat completion
/// (`max_tokens` 1) instead, which must succeed.
///
/// Returns the models the server lists (empty when it lists none).
///
/// # Errors
/// [`EndpointError::Unreachable`] when nothing answers (connection refused,
/// DNS, timeout), [`EndpointError::UnknownModel`] for a model the server
/// does not list, [`EndpointError::Status`] for an error status (a wrong
/// path, a missing API key).
pub fn check_endpoint(config: &LlmConfig) -> Result<Vec<String>, EndpointError> {
    let base = config.base_url.trim_end_matches('/').to_owned();
    // Listing models is quick even on a busy server; a tiny completion may
    // take a prompt's time.
    let timeout =
        Duration::try_from_secs_f64(config.timeout_s.min(30.0)).unwrap_or(Duration::from_secs(30));
    let mut agent_config = ureq::Agent::config_builder()
        .timeout_global(Some(timeout))
        .http_status_as_error(false);
    if !config.use_env_proxy {
        agent_config = agent_config.proxy(None);
    }
    let agent: ureq::Agent = agent_config.build().into();
    let key = config
        .api_key_env
        .as_deref()
        .and_then(|var| std::env::var(var).ok())
        .filter(|k| !k.is_empty());
    let unreachable = |url: &str, e: ureq::Error| EndpointError::Unreachable {
        url: url.to_owned(),
        message: e.to_string(),
    };
    let url = format!("{base}/models");
    let mut get = agent.get(&url);
    if let Some(k) = &key {
        get = get.header("authorization", format!("Bearer {k}"));
    }
    let mut response = get.call().map_err(|e| unreachable(&url, e))?;
    let status = response.status().as_u16();
    let body = response
        .body_mut()
        .read_to_string()
        .map_err(|e| unreachable(&url, e))?;
    if status == 200
        && let Some(models) = model_ids(&body)
    {
        if models.is_empty() || models.iter().any(|m| m == &config.model) {
            return Ok(models);
        }
        return Err(EndpointError::UnknownModel {
            url: base,
            model: config.model.clone(),
            available: models.join(", "),
        });
    }
    if !matches!(status, 404 | 405) {
        return Err(EndpointError::Status {
            url,
            status,
            body: truncate_bytes(body, 200),
        });
    }
    // No models list: one tiny completion.
    let url = format!("{base}/chat/completions");
    let ping = serde_json::json!({
        "model": config.model,
        "max_tokens": 1,
        "messages": [{"role": "user", "content": "ping"}],
    })
    .to_string();
    let mut post = agent.post(&url).header("content-type", "application/json");
    if let Some(k) = &key {
        post = post.header("authorization", format!("Bearer {k}"));
    }
    let mut response = post.send(ping.as_str()).map_err(|e| unreachable(&url, e))?;
    let status = response.status().as_u16();
    if status == 200 {
        return Ok(Vec::new());
    }
    let body = response.body_mut().read_to_string().unwrap_or_default();
    Err(EndpointError::Status {
        url,
        status,
        body: truncate_bytes(body, 200),
    })
}

/// One line of a JSONL recording.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Exchange {
    /// The exact request body.
    pub request: String,
    /// The reply or the transport failure.
    pub reply: Result<HttpReply, TransportError>,
}

/// Wraps a transport and appends every exchange to a JSONL file.
#[derive(Debug)]
pub struct RecordingTransport<T> {
    inner: T,
    file: Mutex<File>,
}

impl<T: Transport> RecordingTransport<T> {
    /// Records `inner`'s exchanges to `path` (appending).
    ///
    /// # Errors
    /// [`SupervisorError::Io`] when the file cannot be opened.
    pub fn new(inner: T, path: &Path) -> Result<Self, SupervisorError> {
        let file = File::options()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|source| SupervisorError::Io {
                path: path.display().to_string(),
                source,
            })?;
        Ok(Self {
            inner,
            file: Mutex::new(file),
        })
    }
}

impl<T: Transport> Transport for RecordingTransport<T> {
    fn post(&self, body: &str) -> Result<HttpReply, TransportError> {
        let reply = self.inner.post(body);
        let line = serde_json::to_string(&Exchange {
            request: body.to_owned(),
            reply: reply.clone(),
        })
        .unwrap_or_default();
        let mut file = self
            .file
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Err(e) = writeln!(file, "{line}") {
            tracing::warn!(target: "sornav_supervisor::llm", error = %e, "could not record an LLM exchange");
        }
        reply
    }
}

/// Serves replies from a JSONL recording, keyed by the exact request body:
/// identical requests get their recorded replies in order (the last one
/// repeats); unknown requests fail with [`TransportError::NotRecorded`].
#[derive(Debug, Default)]
pub struct ReplayTransport {
    replies: Mutex<HashMap<String, VecDeque<Result<HttpReply, TransportError>>>>,
    first_request: Option<String>,
}

/// The request settings a recording was made with (from its first
/// request), so that a replay can repeat them byte for byte.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecordedSettings {
    /// `model`.
    pub model: String,
    /// `temperature`.
    pub temperature: f64,
    /// `max_tokens` (`None`: not sent).
    pub max_tokens: Option<u32>,
}

impl ReplayTransport {
    /// Loads a recording.
    ///
    /// # Errors
    /// [`SupervisorError::Io`] when the file cannot be read,
    /// [`SupervisorError::MalformedData`] for a line that is not an
    /// [`Exchange`] (with its line number).
    pub fn open(path: &Path) -> Result<Self, SupervisorError> {
        let io = |source| SupervisorError::Io {
            path: path.display().to_string(),
            source,
        };
        let file = File::open(path).map_err(io)?;
        let mut replies: HashMap<String, VecDeque<_>> = HashMap::new();
        let mut first_request = None;
        for (i, line) in BufReader::new(file).lines().enumerate() {
            let line = line.map_err(io)?;
            if line.trim().is_empty() {
                continue;
            }
            let ex: Exchange = serde_json::from_str(&line).map_err(|e| {
                SupervisorError::MalformedData(format!("{}:{}: {e}", path.display(), i + 1))
            })?;
            first_request.get_or_insert_with(|| ex.request.clone());
            replies.entry(ex.request).or_default().push_back(ex.reply);
        }
        Ok(Self {
            replies: Mutex::new(replies),
            first_request,
        })
    }

    /// The settings of the recording's first request (`None` for an empty
    /// recording or a request without a model).
    pub fn recorded_settings(&self) -> Option<RecordedSettings> {
        let v: serde_json::Value = serde_json::from_str(self.first_request.as_deref()?).ok()?;
        Some(RecordedSettings {
            model: v.get("model")?.as_str()?.to_owned(),
            temperature: v.get("temperature").and_then(serde_json::Value::as_f64)?,
            max_tokens: v
                .get("max_tokens")
                .and_then(serde_json::Value::as_u64)
                .and_then(|m| u32::try_from(m).ok()),
        })
    }
}

impl Transport for ReplayTransport {
    fn post(&self, body: &str) -> Result<HttpReply, TransportError> {
        let mut replies = self
            .replies
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        match replies.get_mut(body) {
            Some(queue) if queue.len() > 1 => queue
                .pop_front()
                .unwrap_or(Err(TransportError::NotRecorded)),
            Some(queue) => queue
                .front()
                .cloned()
                .unwrap_or(Err(TransportError::NotRecorded)),
            None => Err(TransportError::NotRecorded),
        }
    }
}
