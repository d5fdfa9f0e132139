//! A client for any OpenAI-compatible chat completions endpoint (OpenAI, vLLM, Ollama,
//! llama.cpp's server, LM Studio, OpenRouter...): timeouts, retries with backoff,
//! a concurrency limit, token accounting, and structured outputs with fallbacks. Several
//! endpoints serving one model share the requests (`endpoints.rs`).

use std::fmt;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU8, Ordering};
use std::time::{Duration, Instant, SystemTime};

use reqwest::StatusCode;
use serde::Deserialize;
use serde_json::{Value, json};
use tokio::sync::Semaphore;

use coherent_core::text::cut;

use crate::backends::address::{Address, redacted};
use crate::backends::endpoints::{Endpoints, Lease};
use crate::backends::retry::{Backoff, parse_retry_after};
use crate::llm::{
    Answer, Backend, BackendInfo, BackendKind, BoxFuture, Finish, LlmError, LlmErrorKind,
    MAX_ANSWER_BYTES, Message, OutputMode, Query, Response, Usage,
};
use crate::rng::Rng;

/// An API key. It is sent in the `Authorization` header and nowhere else: it has no
/// `Serialize`, its `Debug` hides it, and every text from the server is scrubbed of it.
#[derive(Clone, PartialEq, Eq)]
pub struct ApiKey(String);

impl ApiKey {
    pub fn new(key: impl Into<String>) -> ApiKey {
        ApiKey(key.into())
    }

    /// `text` with every occurrence of the key replaced: as it is, in any letter case,
    /// and base64-encoded (as in basic auth, at any of the three alignments a longer
    /// encoded text puts it at, in the standard and the URL-safe alphabets).
    pub fn scrub(&self, text: &str) -> String {
        if self.0.is_empty() {
            return text.to_owned();
        }
        let mut out = replace_ignoring_case(text, &self.0);
        for spelling in base64_spellings(self.0.as_bytes()) {
            out = out.replace(&spelling, "[api key]");
        }
        out
    }
}

/// `text` with every ASCII-case-insensitive occurrence of `needle` replaced.
fn replace_ignoring_case(text: &str, needle: &str) -> String {
    let (lower, wanted) = (text.to_ascii_lowercase(), needle.to_ascii_lowercase());
    // ASCII lower-casing keeps every byte offset, so the matches of the lowered text are
    // the matches of the text.
    let mut out = String::with_capacity(text.len());
    let mut from = 0;
    for (at, _) in lower.match_indices(&wanted) {
        if at < from {
            continue;
        }
        out.push_str(&text[from..at]);
        out.push_str("[api key]");
        from = at + wanted.len();
    }
    out.push_str(&text[from..]);
    out
}

/// The base64 text that encodes `key` wherever it sits in a longer encoded text: for each
/// alignment (0, 1 or 2 bytes before it in its group of three), the characters that
/// depend on the key's bytes alone; in both alphabets. Too short a key has none.
fn base64_spellings(key: &[u8]) -> Vec<String> {
    const STANDARD: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut spellings = Vec::new();
    for offset in 0..3usize {
        // With `offset` bytes before the key, its first whole group starts at the next
        // multiple of three; the groups that hold key bytes only encode to fixed text.
        let skip = (3 - offset) % 3;
        let whole = (key.len().saturating_sub(skip)) / 3;
        if whole < 2 {
            continue;
        }
        let bytes = &key[skip..skip + 3 * whole];
        let mut text = String::with_capacity(4 * whole);
        for group in bytes.chunks(3) {
            let n = u32::from(group[0]) << 16 | u32::from(group[1]) << 8 | u32::from(group[2]);
            for shift in [18, 12, 6, 0] {
                text.push(char::from(STANDARD[(n >> shift & 63) as usize]));
            }
        }
        let url_safe = text.replace('+', "-").replace('/', "_");
        if url_safe != text {
            spellings.push(url_safe);
        }
        spellings.push(text);
    }
    spellings
}

impl fmt::Debug for ApiKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ApiKey([hidden])")
    }
}

/// How to reach an OpenAI-compatible endpoint and how patiently: the one set of endpoint
/// settings, filled by the command line's flags and by Python's `LLM`, completed from the
/// environment by the session (`OPENAI_BASE_URL`, `OPENAI_API_KEY`, `COHERENT_MODEL` for
/// what was not given), and used as it is by the client. The defaults are
/// [`OpenAiConfig::default`]'s.
#[derive(Clone, Debug, PartialEq)]
pub struct OpenAiConfig {
    /// Up to and including the version, e.g. `https://api.openai.com/v1`; several when
    /// replicas serve the model: each request goes to the one with the fewest requests in
    /// flight, and one that fails rests while the others carry on. Empty until given.
    pub base_urls: Vec<String>,
    pub api_key: Option<ApiKey>,
    /// Empty until given; the client refuses an empty one.
    pub model: String,
    pub temperature: f32,
    /// The model's sampling seed, sent to the server.
    pub seed: Option<u64>,
    pub connect_timeout: Duration,
    /// Longest silence while reading a response.
    pub read_timeout: Duration,
    /// Longest one attempt may take in all.
    pub total_timeout: Duration,
    pub backoff: Backoff,
    /// Requests in flight at once, across all episodes sharing the client and all its
    /// endpoints.
    pub concurrency: usize,
    /// The answer format to ask for first; a server that refuses it gets the next one.
    pub output: OutputMode,
    /// The most bytes a response body may have; a longer one is a failed call (read no
    /// further than the limit, whatever the server sends).
    pub max_response_bytes: usize,
}

impl Default for OpenAiConfig {
    /// No endpoint or model yet; 10 s to connect, 120 s of silence while reading, 300 s
    /// for an attempt in all, [`Backoff::default`]'s retries, 4 requests in flight, a
    /// JSON schema asked for first, responses of at most 4 MiB (hundreds of times what
    /// a chat answer of a few thousand tokens takes).
    fn default() -> OpenAiConfig {
        OpenAiConfig {
            base_urls: Vec::new(),
            api_key: None,
            model: String::new(),
            temperature: 0.0,
            seed: None,
            connect_timeout: Duration::from_secs(10),
            read_timeout: Duration::from_secs(120),
            total_timeout: Duration::from_secs(300),
            backoff: Backoff::default(),
            concurrency: 4,
            output: OutputMode::JsonSchema,
            max_response_bytes: 4 << 20,
        }
    }
}

impl OpenAiConfig {
    /// The default settings for `model` at `base_url`.
    pub fn new(base_url: impl Into<String>, model: impl Into<String>) -> OpenAiConfig {
        OpenAiConfig {
            base_urls: vec![base_url.into()],
            model: model.into(),
            ..OpenAiConfig::default()
        }
    }
}

/// One chat request as the client sends it: a role's [`Query`], or a question of a
/// method written outside the crate ([`OpenAiClient::chat`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Chat {
    pub messages: Vec<Message>,
    /// The name and JSON schema the answer must follow (structured outputs, with the
    /// client's fallbacks); `None` asks for free text.
    pub schema: Option<(String, Value)>,
    pub max_tokens: u32,
}

impl Chat {
    fn of(q: Query) -> Chat {
        Chat {
            messages: q.messages,
            schema: Some((q.schema_name.to_owned(), q.schema)),
            max_tokens: q.max_tokens,
        }
    }
}

/// The HTTP backend.
#[derive(Debug)]
pub struct OpenAiClient {
    http: reqwest::Client,
    config: OpenAiConfig,
    /// The config's backoff, its pauses capped at the longest a request may take.
    backoff: Backoff,
    /// The key and the secrets of the base URLs, scrubbed from every text kept.
    secrets: Vec<ApiKey>,
    endpoints: Endpoints,
    limit: Semaphore,
    /// The answer format currently asked for (an [`OutputMode`] index); it only ever
    /// moves down, once a server has refused the one above.
    mode: AtomicU8,
    jitter: Mutex<Rng>,
}

const MODES: [OutputMode; 3] = [
    OutputMode::JsonSchema,
    OutputMode::JsonObject,
    OutputMode::Text,
];

impl OpenAiClient {
    pub fn new(config: OpenAiConfig) -> Result<OpenAiClient, LlmError> {
        if config.model.trim().is_empty() {
            return Err(LlmError::new(
                LlmErrorKind::Config,
                "no model name: pass --model or set COHERENT_MODEL",
            ));
        }
        if config.base_urls.is_empty() {
            return Err(LlmError::new(LlmErrorKind::Config, "no base URL"));
        }
        let mut targets = Vec::new();
        let mut secrets: Vec<ApiKey> = config.api_key.iter().cloned().collect();
        for base in &config.base_urls {
            let address =
                Address::parse(base).map_err(|e| LlmError::new(LlmErrorKind::Config, e))?;
            secrets.extend(address.secrets.iter().map(ApiKey::new));
            targets.push(address);
        }
        // reqwest takes rustls's process-wide crypto provider, `ring` here (Cargo.toml says
        // why). Installing it a second time fails harmlessly: one is there already.
        let _ = rustls::crypto::ring::default_provider().install_default();
        // No wait longer than one request may take, whatever a server asks.
        let backoff = Backoff {
            cap: config.backoff.cap.min(config.total_timeout),
            ..config.backoff
        };
        // A redirect would send the whole prompt (and the key) elsewhere, and a 302 would
        // turn the request into a GET: it is the server's answer, an error.
        let http = reqwest::Client::builder()
            .connect_timeout(config.connect_timeout)
            .read_timeout(config.read_timeout)
            .timeout(config.total_timeout)
            .redirect(reqwest::redirect::Policy::none())
            .build()
            .map_err(|e| LlmError::new(LlmErrorKind::Config, e.to_string()))?;
        let seed = SystemTime::now()
            .duration_since(SystemTime::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        let first = MODES.iter().position(|&m| m == config.output).unwrap_or(0);
        Ok(OpenAiClient {
            http,
            endpoints: Endpoints::new(targets, backoff),
            backoff,
            secrets,
            limit: Semaphore::new(config.concurrency.max(1)),
            mode: AtomicU8::new(first as u8),
            jitter: Mutex::new(Rng::new(seed)),
            config,
        })
    }

    /// The settings the client was made with.
    pub fn config(&self) -> &OpenAiConfig {
        &self.config
    }

    /// `text` without the key or any secret of the base URLs.
    fn scrub(&self, text: &str) -> String {
        self.secrets
            .iter()
            .fold(text.to_owned(), |text, secret| secret.scrub(&text))
    }

    fn body(&self, q: &Chat, mode: OutputMode) -> Value {
        let mut body = json!({
            "model": self.config.model,
            "messages": q.messages,
            "temperature": self.config.temperature,
            "max_tokens": q.max_tokens,
        });
        if let Some(seed) = self.config.seed {
            body["seed"] = json!(seed);
        }
        match (mode, &q.schema) {
            (OutputMode::JsonSchema, Some((name, schema))) => {
                body["response_format"] = json!({
                    "type": "json_schema",
                    "json_schema": {"name": name, "strict": true, "schema": schema},
                });
            }
            (OutputMode::JsonObject, Some(_)) => {
                body["response_format"] = json!({"type": "json_object"});
            }
            _ => {}
        }
        body
    }

    /// One POST of `body` to the endpoint at `address`: the status, `Retry-After` if any,
    /// and the whole body (for a redirect, where it points).
    async fn post(&self, address: &Address, body: &Value) -> Result<Exchanged, LlmError> {
        let mut request = self.http.post(address.post.clone()).json(body);
        // One credential: the URL's user and password (basic auth, which the HTTP
        // client takes from the URL), else the key.
        if let (Some(key), false) = (&self.config.api_key, address.has_credentials) {
            request = request.bearer_auth(&key.0);
        }
        let response = request.send().await.map_err(|e| self.transport(e))?;
        let status = response.status();
        if status.is_redirection() {
            let to = response
                .headers()
                .get(reqwest::header::LOCATION)
                .map(|v| redacted(&String::from_utf8_lossy(v.as_bytes())));
            return Ok(Exchanged::Redirect(status, to));
        }
        let retry_after = response
            .headers()
            .get(reqwest::header::RETRY_AFTER)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| parse_retry_after(v, SystemTime::now()));
        let cap = self.config.max_response_bytes;
        let too_large = |what: String| {
            LlmError::new(
                LlmErrorKind::Malformed,
                format!(
                    "the response is {what}, more than the limit of {cap} bytes (--max-response-bytes)"
                ),
            )
        };
        if let Some(length) = response.content_length().filter(|&n| n > cap as u64) {
            return Err(too_large(format!("{length} bytes long")));
        }
        // Read it chunk by chunk, so that a body that never ends stops at the limit.
        let mut body = Vec::new();
        let mut response = response;
        while let Some(chunk) = response.chunk().await.map_err(|e| self.transport(e))? {
            if body.len() + chunk.len() > cap {
                return Err(too_large("longer".into()));
            }
            body.extend_from_slice(&chunk);
        }
        Ok(Exchanged::Body(status, retry_after, body))
    }

    /// A failed exchange as an error; the URL is left out (it may hold a secret, and the
    /// call records the endpoint as shown).
    fn transport(&self, e: reqwest::Error) -> LlmError {
        let e = e.without_url();
        let kind = if e.is_timeout() {
            LlmErrorKind::Timeout
        } else {
            LlmErrorKind::Connect
        };
        // The error's own text is terse ("error sending request"); its sources say why.
        let mut message = e.to_string();
        let mut source = std::error::Error::source(&e);
        while let Some(s) = source {
            message.push_str(": ");
            message.push_str(&s.to_string());
            source = s.source();
        }
        LlmError::new(kind, self.scrub(&message))
    }

    /// Sends one chat request to the endpoint with the fewest requests in flight: tried
    /// again after 408, 429, 5xx, no connection and timeouts (at once on another endpoint
    /// when one is ready, else after the backoff's pause, honouring `Retry-After`); with a
    /// schema, in the answer format the server takes (a refusal moves the client to the
    /// next one for good), without one as free text. The answer has its tokens, latency
    /// and attempts, the response names the endpoint of the last attempt; the key is in
    /// no text.
    pub async fn chat(&self, q: &Chat) -> Response {
        let _permit = match self.limit.acquire().await {
            Ok(permit) => permit,
            Err(e) => {
                return Response {
                    result: Err(LlmError::new(LlmErrorKind::Config, e.to_string())),
                    endpoint: None,
                };
            }
        };
        let start = Instant::now();
        let mut attempts = 0;
        let mut retries = 0;
        loop {
            let mode = match q.schema {
                Some(_) => MODES[usize::from(self.mode.load(Ordering::Relaxed))],
                None => OutputMode::Text,
            };
            attempts += 1;
            let lease = self.endpoints.pick();
            let endpoint = Some(lease.shown().to_owned());
            let (mut error, retry_after) = match self.attempt(&lease, q, mode).await {
                Attempt::Answered(mut answer) => {
                    answer.latency_ms = start.elapsed().as_secs_f64() * 1e3;
                    answer.attempts = attempts;
                    answer.mode = mode;
                    let result = Ok(answer);
                    return Response { result, endpoint };
                }
                Attempt::Downgraded => continue,
                Attempt::Failed(error, retry_after) => (error, retry_after),
            };
            error.attempts = attempts;
            if !error.retryable() || retries >= self.backoff.max_retries {
                let result = Err(error);
                return Response { result, endpoint };
            }
            let wait = !lease.another_ready();
            let shown = lease.shown().to_owned();
            drop(lease);
            if wait {
                let unit = self.jitter.lock().map_or(0.5, |mut j| j.unit());
                let pause = self.backoff.pause(retries, retry_after, unit);
                if let Some(asked) = retry_after.filter(|a| *a >= Duration::from_secs(1)) {
                    // Said, so that a long wait is never a silent one.
                    eprintln!(
                        "note: {} answered {} and asked to wait {} s (Retry-After); waiting \
                         {:.1} s, retry {} of {}",
                        shown,
                        error.kind_text(),
                        asked.as_secs(),
                        pause.as_secs_f64(),
                        retries + 1,
                        self.backoff.max_retries
                    );
                }
                tokio::time::sleep(pause).await;
            }
            retries += 1;
        }
    }

    /// One attempt at the endpoint `lease` holds, which hears how it went: a failure
    /// worth a retry rests it, any other response counts as an answer.
    async fn attempt(&self, lease: &Lease<'_>, q: &Chat, mode: OutputMode) -> Attempt {
        let (status, retry_after, bytes) =
            match self.post(lease.address(), &self.body(q, mode)).await {
                Ok(Exchanged::Body(status, retry_after, bytes)) => (status, retry_after, bytes),
                Ok(Exchanged::Redirect(status, to)) => {
                    lease.answered();
                    let to =
                        to.map_or_else(|| "nowhere (no Location)".to_owned(), |u| self.scrub(&u));
                    let message = format!("redirect to {to}, not followed");
                    let error = LlmError::new(LlmErrorKind::Status(status.as_u16()), message);
                    return Attempt::Failed(error, None);
                }
                Err(e) => {
                    if e.retryable() {
                        lease.failed(None);
                    }
                    return Attempt::Failed(e, None);
                }
            };
        if status.is_success() {
            lease.answered();
            return match parse_completion(&bytes) {
                Ok(mut answer) => {
                    // What the loop parses is what the transcript keeps, so that a replay
                    // reads the same text: both are cut at the limit of an answer.
                    answer.text = self.scrub(&cut(&answer.text, MAX_ANSWER_BYTES));
                    Attempt::Answered(answer)
                }
                Err(message) => Attempt::Failed(
                    LlmError::new(LlmErrorKind::Malformed, self.scrub(&message)),
                    None,
                ),
            };
        }
        let text = String::from_utf8_lossy(&bytes);
        let error = LlmError::new(
            LlmErrorKind::Status(status.as_u16()),
            self.scrub(text.chars().take(400).collect::<String>().trim()),
        );
        if error.retryable() {
            lease.failed(retry_after);
        } else {
            lease.answered();
        }
        if refuses_format(status, &text) && self.downgrade(mode) {
            return Attempt::Downgraded;
        }
        Attempt::Failed(error, retry_after)
    }

    /// Asks for the next, looser answer format from now on; false when there is none.
    fn downgrade(&self, from: OutputMode) -> bool {
        let i = MODES.iter().position(|&m| m == from).unwrap_or(MODES.len());
        if i + 1 >= MODES.len() {
            return false;
        }
        // Another request may have moved it already; either way it is now lower.
        let _ = self.mode.compare_exchange(
            i as u8,
            (i + 1) as u8,
            Ordering::Relaxed,
            Ordering::Relaxed,
        );
        true
    }
}

/// What one HTTP exchange gave.
enum Exchanged {
    /// The status, the server's `Retry-After` if any, and the body.
    Body(StatusCode, Option<Duration>, Vec<u8>),
    /// A redirect (3xx), not followed, and where it pointed (as shown).
    Redirect(StatusCode, Option<String>),
}

/// How one attempt went.
enum Attempt {
    Answered(Answer),
    /// The server refused the answer format; the next one is asked for from now on.
    Downgraded,
    /// No answer, and maybe the server's `Retry-After`.
    Failed(LlmError, Option<Duration>),
}

/// A 400 or 422 whose body names the answer format: the server does not support it.
fn refuses_format(status: StatusCode, body: &str) -> bool {
    let body = body.to_ascii_lowercase();
    matches!(status.as_u16(), 400 | 422)
        && ["response_format", "json_schema", "json_object", "schema"]
            .iter()
            .any(|w| body.contains(w))
}

#[derive(Deserialize)]
struct Completion {
    choices: Vec<Choice>,
    usage: Option<UsageBody>,
}

#[derive(Deserialize)]
struct Choice {
    message: Option<MessageBody>,
    finish_reason: Option<String>,
}

#[derive(Deserialize)]
struct MessageBody {
    content: Option<String>,
    refusal: Option<String>,
}

#[derive(Deserialize)]
struct UsageBody {
    prompt_tokens: Option<u64>,
    completion_tokens: Option<u64>,
    prompt_tokens_details: Option<PromptTokensDetails>,
}

#[derive(Deserialize)]
struct PromptTokensDetails {
    cached_tokens: Option<u64>,
}

/// A chat completion body as an answer (latency, attempts and mode filled in later).
fn parse_completion(bytes: &[u8]) -> Result<Answer, String> {
    let completion: Completion = serde_json::from_slice(bytes).map_err(|e| {
        let excerpt: String = String::from_utf8_lossy(bytes).chars().take(200).collect();
        format!("not a chat completion ({e}): {excerpt:?}")
    })?;
    let choice = completion
        .choices
        .into_iter()
        .next()
        .ok_or("the response has no choices")?;
    let message = choice.message.ok_or("the first choice has no message")?;
    let finish = match (message.refusal, choice.finish_reason.as_deref()) {
        (Some(words), _) => Finish::Refusal(words),
        (None, Some("stop") | None) => Finish::Stop,
        (None, Some("length")) => Finish::Length,
        (None, Some("content_filter")) => Finish::ContentFilter,
        (None, Some(other)) => Finish::Other(other.to_owned()),
    };
    let usage = completion.usage.map_or(Usage::default(), |u| Usage {
        prompt_tokens: u.prompt_tokens.unwrap_or(0),
        completion_tokens: u.completion_tokens.unwrap_or(0),
        cached_tokens: u
            .prompt_tokens_details
            .and_then(|d| d.cached_tokens)
            .unwrap_or(0),
    });
    Ok(Answer {
        text: message.content.unwrap_or_default(),
        finish,
        usage,
        latency_ms: 0.0,
        attempts: 0,
        mode: OutputMode::Text,
    })
}

impl Backend for OpenAiClient {
    fn info(&self) -> BackendInfo {
        BackendInfo {
            kind: BackendKind::OpenAi,
            model: self.config.model.clone(),
            base_url: Some(self.endpoints.shown().join(",")),
        }
    }

    fn ask(&self, query: Query) -> BoxFuture<'_, Result<Answer, LlmError>> {
        Box::pin(async move { self.chat(&Chat::of(query)).await.result })
    }

    fn respond(&self, query: Query) -> BoxFuture<'_, Response> {
        Box::pin(async move { self.chat(&Chat::of(query)).await })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn completions_parse_with_their_finish_reason_and_usage() {
        let body = br#"{"choices":[{"message":{"role":"assistant","content":"{\"a\":1}"},"finish_reason":"length"}],"usage":{"prompt_tokens":12,"completion_tokens":3}}"#;
        let a = parse_completion(body).expect("a completion");
        assert_eq!(a.text, "{\"a\":1}");
        assert_eq!(a.finish, Finish::Length);
        assert_eq!(a.usage.prompt_tokens, 12);
        assert_eq!(a.usage.completion_tokens, 3);
        assert_eq!(a.usage.cached_tokens, 0);
        let cached = br#"{"choices":[{"message":{"content":"x"}}],"usage":{"prompt_tokens":12,"completion_tokens":3,"prompt_tokens_details":{"cached_tokens":8}}}"#;
        let a = parse_completion(cached).expect("a completion");
        assert_eq!((a.usage.prompt_tokens, a.usage.cached_tokens), (12, 8));
    }

    #[test]
    fn refusals_and_empty_bodies_are_not_panics() {
        let refusal = br#"{"choices":[{"message":{"content":null,"refusal":"I can't help"},"finish_reason":"stop"}]}"#;
        assert_eq!(
            parse_completion(refusal).expect("parsed").finish,
            Finish::Refusal("I can't help".into())
        );
        assert!(parse_completion(br#"{"choices":[]}"#).is_err());
        assert!(parse_completion(b"{\"choices\": [").is_err());
        assert!(parse_completion(b"").is_err());
    }

    #[test]
    fn the_key_is_scrubbed_in_other_spellings() {
        let key = ApiKey::new("sk-test-0123456789-SECRET");
        let upper = "echo: SK-TEST-0123456789-SECRET.";
        assert_eq!(key.scrub(upper), "echo: [api key].");
        // Basic auth: base64 of "user:<key>", and of the key at the other alignments.
        for prefix in ["user:", "", "x", "xy"] {
            let encoded = encode(format!("{prefix}sk-test-0123456789-SECRET").as_bytes());
            let scrubbed = key.scrub(&format!("Authorization: Basic {encoded}"));
            assert!(scrubbed.contains("[api key]"), "{prefix:?}: {scrubbed}");
            assert!(
                !scrubbed.contains(&encoded[8..encoded.len() - 8]),
                "{scrubbed}"
            );
        }
    }

    /// Standard base64 with padding, written out for the test.
    fn encode(bytes: &[u8]) -> String {
        const ALPHABET: &[u8; 64] =
            b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for group in bytes.chunks(3) {
            let b = [
                group[0],
                *group.get(1).unwrap_or(&0),
                *group.get(2).unwrap_or(&0),
            ];
            let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
            for (i, shift) in [18, 12, 6, 0].into_iter().enumerate() {
                out.push(if i <= group.len() {
                    char::from(ALPHABET[(n >> shift & 63) as usize])
                } else {
                    '='
                });
            }
        }
        out
    }

    #[test]
    fn the_key_is_scrubbed_and_hidden_from_debug() {
        let key = ApiKey::new("sk-secret-123");
        assert_eq!(key.scrub("echo sk-secret-123!"), "echo [api key]!");
        assert!(!format!("{key:?}").contains("secret"));
    }

    #[test]
    fn a_chat_without_a_schema_asks_for_text_in_any_mode() {
        let client =
            OpenAiClient::new(OpenAiConfig::new("http://127.0.0.1:9/v1", "m")).expect("a client");
        let mut chat = Chat {
            messages: vec![Message::user("hi".into())],
            schema: None,
            max_tokens: 7,
        };
        for mode in MODES {
            let body = client.body(&chat, mode);
            assert!(body.get("response_format").is_none(), "{mode:?}");
            assert_eq!(body["max_tokens"], 7);
        }
        chat.schema = Some(("answer".into(), json!({"type": "object"})));
        let body = client.body(&chat, OutputMode::JsonSchema);
        assert_eq!(body["response_format"]["json_schema"]["name"], "answer");
        let body = client.body(&chat, OutputMode::JsonObject);
        assert_eq!(body["response_format"]["type"], "json_object");
    }

    #[test]
    fn only_format_complaints_downgrade() {
        assert!(refuses_format(
            StatusCode::BAD_REQUEST,
            "{\"error\":\"response_format json_schema is not supported\"}"
        ));
        assert!(!refuses_format(StatusCode::BAD_REQUEST, "context too long"));
        assert!(!refuses_format(StatusCode::INTERNAL_SERVER_ERROR, "schema"));
    }
}
