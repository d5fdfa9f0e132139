//! The model endpoint: what a front end was told (flags, keyword arguments), completed
//! from the environment (`OPENAI_BASE_URL`, `OPENAI_API_KEY`, `COHERENT_MODEL`) and
//! resolved into the HTTP client's settings.

use std::time::Duration;

use coherent_agents::retry::Backoff;
use coherent_agents::{ApiKey, OpenAiConfig, OutputMode};

/// How long the client waits and how often it retries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patience {
    /// Seconds to wait for a connection.
    pub connect_timeout: f64,
    /// Seconds of silence allowed while reading a response.
    pub read_timeout: f64,
    /// Seconds one request may take in all.
    pub timeout: f64,
    /// Retries of a request after 408, 429, 5xx, connection errors and timeouts.
    pub max_retries: u32,
}

impl Default for Patience {
    fn default() -> Patience {
        Patience {
            connect_timeout: 10.0,
            read_timeout: 120.0,
            timeout: 300.0,
            max_retries: 4,
        }
    }
}

/// What the front end was told of the endpoint; unset parts come from the environment.
#[derive(Debug)]
pub struct Endpoint {
    pub base_url: Option<String>,
    /// Kept as an [`ApiKey`] from the start, so that `Debug` never shows it.
    pub api_key: Option<ApiKey>,
    pub model: Option<String>,
    pub temperature: f32,
    /// The model's sampling seed, sent to the server.
    pub seed: Option<u64>,
    /// The answer format asked for first.
    pub format: OutputMode,
    pub patience: Patience,
    /// Requests in flight at once.
    pub requests: usize,
    /// The most bytes a response body may have.
    pub max_response_bytes: usize,
}

impl Endpoint {
    /// The client's settings when an endpoint is configured: a base URL, or a key and a
    /// model (then OpenAI's own endpoint); `None` when there is none.
    pub fn config(self) -> Result<Option<OpenAiConfig>, String> {
        let from_env = |name: &str| std::env::var(name).ok().filter(|v| !v.trim().is_empty());
        let key = self
            .api_key
            .or_else(|| from_env("OPENAI_API_KEY").map(ApiKey::new));
        let model = self.model.or_else(|| from_env("COHERENT_MODEL"));
        let base_url = match self.base_url.or_else(|| from_env("OPENAI_BASE_URL")) {
            Some(url) => url,
            None if key.is_some() && model.is_some() => "https://api.openai.com/v1".to_owned(),
            None => return Ok(None),
        };
        let model = model.ok_or_else(|| {
            format!("an endpoint is configured ({base_url}) but no model: pass --model or set COHERENT_MODEL")
        })?;
        Ok(Some(OpenAiConfig {
            api_key: key,
            temperature: self.temperature,
            seed: self.seed,
            connect_timeout: seconds(self.patience.connect_timeout, "connect-timeout")?,
            read_timeout: seconds(self.patience.read_timeout, "read-timeout")?,
            total_timeout: seconds(self.patience.timeout, "timeout")?,
            backoff: Backoff {
                max_retries: self.patience.max_retries,
                ..Backoff::default()
            },
            concurrency: self.requests.max(1),
            output: self.format,
            max_response_bytes: self.max_response_bytes,
            ..OpenAiConfig::new(base_url, model)
        }))
    }
}

fn seconds(s: f64, what: &str) -> Result<Duration, String> {
    Duration::try_from_secs_f64(s).map_err(|_| format!("--{what} {s}: not a number of seconds"))
}
