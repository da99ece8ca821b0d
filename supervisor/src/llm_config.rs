//! Settings of the LLM policy. Always compiled (without the `llm` feature
//! too), so that configuration files naming the LLM policy parse and are
//! validated the same way whatever the features; only the policy itself
//! (`LlmPolicy`, cargo feature `llm`) needs the HTTP client.

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
    /// Request timeout, seconds.
    pub timeout_s: f64,
    /// Sampling temperature.
    pub temperature: f64,
    /// Token budget of the answer (`None`: server default).
    pub max_tokens: Option<u32>,
    /// At most one request every this many seconds (on the supervisor clock).
    pub min_interval_s: f64,
    /// Run requests on a background thread.
    pub asynchronous: bool,
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
            timeout_s: 10.0,
            temperature: 0.0,
            max_tokens: Some(256),
            min_interval_s: 5.0,
            asynchronous: false,
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
