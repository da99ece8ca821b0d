//! How requests reach a model: plain HTTP (ureq), recording to JSONL, and
//! offline replay of a recording.

use std::collections::{HashMap, VecDeque};
use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::sync::Mutex;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::LlmConfig;
use crate::error::SupervisorError;

/// An HTTP reply: status and body text.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct HttpReply {
    /// HTTP status code.
    pub status: u16,
    /// Body text.
    pub body: String,
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
        let mut response = request.send(body).map_err(map_ureq)?;
        let status = response.status().as_u16();
        let body = response.body_mut().read_to_string().map_err(map_ureq)?;
        Ok(HttpReply { status, body })
    }
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
        for (i, line) in BufReader::new(file).lines().enumerate() {
            let line = line.map_err(io)?;
            if line.trim().is_empty() {
                continue;
            }
            let ex: Exchange = serde_json::from_str(&line).map_err(|e| {
                SupervisorError::MalformedData(format!("{}:{}: {e}", path.display(), i + 1))
            })?;
            replies.entry(ex.request).or_default().push_back(ex.reply);
        }
        Ok(Self {
            replies: Mutex::new(replies),
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
