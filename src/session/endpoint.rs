//! The model endpoint: what a front end was told (flags, keyword arguments), completed
//! from the environment (`OPENAI_BASE_URL`, `OPENAI_API_KEY`, `COHERENT_MODEL`) and
//! resolved into the HTTP client's settings. Several base URLs serve one model from
//! several servers (the client spreads the requests over them).

use std::time::Duration;

use coherent_agents::backends::address::redacted;
use coherent_agents::retry::Backoff;
use coherent_agents::{ApiKey, OpenAiConfig, OutputMode};
use coherent_core::text::number;

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
    /// The servers of the model, up to the version; none given: `OPENAI_BASE_URL`, a
    /// comma-separated list.
    pub base_urls: Vec<String>,
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
        let mut base_urls: Vec<String> = self
            .base_urls
            .iter()
            .flat_map(|list| url_list(list))
            .collect();
        if base_urls.is_empty() {
            base_urls = from_env("OPENAI_BASE_URL").map_or_else(Vec::new, |v| url_list(&v));
        }
        if base_urls.is_empty() {
            if key.is_none() || model.is_none() {
                return Ok(None);
            }
            base_urls.push("https://api.openai.com/v1".to_owned());
        }
        let model = model.ok_or_else(|| {
            format!(
                "an endpoint is configured ({}) but no model: pass --model or set COHERENT_MODEL",
                base_urls
                    .iter()
                    .map(|u| redacted(u))
                    .collect::<Vec<_>>()
                    .join(",")
            )
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
            base_urls,
            ..OpenAiConfig::new(String::new(), model)
        }))
    }
}

/// The base URLs of a comma-separated list (`OPENAI_BASE_URL`, a `--base-url` value),
/// blanks left out.
pub fn url_list(list: &str) -> Vec<String> {
    list.split(',')
        .map(str::trim)
        .filter(|u| !u.is_empty())
        .map(str::to_owned)
        .collect()
}

fn seconds(s: f64, what: &str) -> Result<Duration, String> {
    Duration::try_from_secs_f64(s).map_err(|_| {
        format!(
            "--{what} {}: not a number of seconds from 0 to 1.8e19",
            number(s)
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn endpoint(base_urls: &[&str]) -> Endpoint {
        Endpoint {
            base_urls: base_urls.iter().map(|&u| u.to_owned()).collect(),
            api_key: None,
            model: Some("m".into()),
            temperature: 0.0,
            seed: None,
            format: OutputMode::JsonSchema,
            patience: Patience::default(),
            requests: 4,
            max_response_bytes: OpenAiConfig::DEFAULT_MAX_RESPONSE_BYTES,
        }
    }

    #[test]
    fn base_urls_are_repeated_or_listed_with_commas() {
        assert_eq!(
            url_list(" http://a/v1, ,http://b/v1,"),
            ["http://a/v1", "http://b/v1"]
        );
        let config = endpoint(&["http://a/v1,http://b/v1", "http://c/v1"])
            .config()
            .expect("valid")
            .expect("an endpoint");
        assert_eq!(
            config.base_urls,
            ["http://a/v1", "http://b/v1", "http://c/v1"]
        );
        assert_eq!(config.model, "m");
    }
}
