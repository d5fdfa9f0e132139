//! What the planning loop asks of a language model, and what comes back, whatever
//! answers: an OpenAI-compatible server ([`crate::backends::openai`]), a recorded
//! transcript ([`crate::backends::replay`]) or the optimal planner
//! ([`crate::backends::builtin`]).

use std::fmt;
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;

use coherent_core::{Environment, NodeId, State, Task};
use serde::{Deserialize, Serialize};

pub type BoxFuture<'a, T> = Pin<Box<dyn Future<Output = T> + Send + 'a>>;

/// The two roles of PEFA.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// The Task Assigner: proposes one subtask for one robot.
    Assigner,
    /// A Robot Executor: picks one action from its list for the subtask.
    Executor,
}

/// One chat message.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Message {
    /// `system` or `user`.
    pub role: String,
    pub content: String,
}

impl Message {
    pub fn system(content: String) -> Message {
        Message {
            role: "system".into(),
            content,
        }
    }
    pub fn user(content: String) -> Message {
        Message {
            role: "user".into(),
            content,
        }
    }
}

/// Where the episode stands when a role is asked; backends that are not language models
/// (the built-in planner) answer from this instead of the prompt.
#[derive(Clone, Debug)]
pub struct Situation {
    pub task: Arc<Task>,
    pub state: State,
    /// The executor's subtask, as the assigner wrote it.
    pub subtask: Option<String>,
    /// The robots the answer is about, when not the whole team: a parallel assigner's
    /// idle robots (those it may give a subtask).
    pub robots: Vec<NodeId>,
}

impl Situation {
    /// Where `env` stands now.
    pub fn now(task: &Arc<Task>, env: &dyn Environment, subtask: Option<String>) -> Situation {
        Situation {
            task: Arc::clone(task),
            state: env.state().clone(),
            subtask,
            robots: Vec::new(),
        }
    }
}

/// One request to a role.
#[derive(Clone, Debug)]
pub struct Query {
    pub role: Role,
    /// The executor's robot.
    pub robot: Option<NodeId>,
    pub messages: Vec<Message>,
    /// The JSON schema the answer must follow (structured outputs).
    pub schema_name: &'static str,
    pub schema: serde_json::Value,
    pub max_tokens: u32,
    pub situation: Situation,
}

/// How the answer's format was asked for: a strict JSON schema, any JSON object, or
/// free text (each a fallback for servers that refuse the one before).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OutputMode {
    JsonSchema,
    JsonObject,
    Text,
}

/// Why generation stopped.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Finish {
    Stop,
    /// Cut at `max_tokens`: the answer is incomplete.
    Length,
    /// The model declined; its words are kept.
    Refusal(String),
    ContentFilter,
    Other(String),
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Usage {
    pub prompt_tokens: u64,
    pub completion_tokens: u64,
    /// The part of `prompt_tokens` the server read from its prompt cache (priced lower
    /// by most providers); 0 when it does not say.
    #[serde(default)]
    pub cached_tokens: u64,
}

/// The most bytes of an answer's text that the loop reads and a round keeps: far more
/// than any `max_tokens` the methods ask for produces, so only a runaway server's answer
/// is cut (with a note of its whole length).
pub const MAX_ANSWER_BYTES: usize = 64 << 10;

/// What a role answered.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Answer {
    /// The raw text, parsed by the loop whatever the backend.
    pub text: String,
    pub finish: Finish,
    pub usage: Usage,
    pub latency_ms: f64,
    /// HTTP attempts it took (1 without retries).
    pub attempts: u32,
    pub mode: OutputMode,
}

/// A backend that could not produce an answer at all.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct LlmError {
    pub kind: LlmErrorKind,
    pub message: String,
    /// HTTP attempts made before giving up.
    pub attempts: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LlmErrorKind {
    /// No connection, or the connection closed before a full response.
    Connect,
    Timeout,
    /// An HTTP status that is not success.
    Status(u16),
    /// A success status with a body that is not a chat completion.
    Malformed,
    /// The replayed episode asked something the transcript does not hold.
    Replay,
    /// A setting is missing or wrong.
    Config,
    /// The backend itself failed (a bug).
    Internal,
}

impl LlmError {
    pub fn new(kind: LlmErrorKind, message: impl Into<String>) -> LlmError {
        LlmError {
            kind,
            message: message.into(),
            attempts: 0,
        }
    }

    /// Worth another try after a pause: 408, 429, 5xx, no connection, timeouts.
    pub fn retryable(&self) -> bool {
        match self.kind {
            LlmErrorKind::Connect | LlmErrorKind::Timeout => true,
            LlmErrorKind::Status(code) => code == 408 || code == 429 || code >= 500,
            LlmErrorKind::Malformed
            | LlmErrorKind::Replay
            | LlmErrorKind::Config
            | LlmErrorKind::Internal => false,
        }
    }

    /// A bad answer costs the round but the episode goes on; anything else (the server
    /// is gone, refuses us, or the replay diverged) ends it.
    pub fn ends_episode(&self) -> bool {
        self.kind != LlmErrorKind::Malformed
    }
}

impl LlmError {
    /// What kind of failure it is, in words: `HTTP 429`, `timed out`.
    pub fn kind_text(&self) -> String {
        match self.kind {
            LlmErrorKind::Connect => "connection failed".to_owned(),
            LlmErrorKind::Timeout => "timed out".to_owned(),
            LlmErrorKind::Status(code) => format!("HTTP {code}"),
            LlmErrorKind::Malformed => "malformed response".to_owned(),
            LlmErrorKind::Replay => "replay diverged".to_owned(),
            LlmErrorKind::Config => "configuration".to_owned(),
            LlmErrorKind::Internal => "internal error".to_owned(),
        }
    }
}

impl fmt::Display for LlmError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.kind_text(), self.message)?;
        if self.attempts > 1 {
            write!(f, " (after {} attempts)", self.attempts)?;
        }
        Ok(())
    }
}

/// What kind of backend answers, as transcripts and results files name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BackendKind {
    /// `builtin`: the optimal planner in every role.
    Builtin,
    /// `simulated`: the planner with seeded mistakes.
    Simulated,
    /// `openai`: an OpenAI-compatible server.
    #[serde(rename = "openai")]
    OpenAi,
    /// `replay`: the answers recorded in a transcript.
    Replay,
    /// `none`: nothing answers; the method asks no backend.
    None,
}

impl BackendKind {
    /// The name transcripts and results files use.
    pub fn name(self) -> &'static str {
        match self {
            BackendKind::Builtin => "builtin",
            BackendKind::Simulated => "simulated",
            BackendKind::OpenAi => "openai",
            BackendKind::Replay => "replay",
            BackendKind::None => "none",
        }
    }
}

impl fmt::Display for BackendKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which backend answers, for the first line of output and the transcript header.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BackendInfo {
    pub kind: BackendKind,
    pub model: String,
    /// The endpoint, for HTTP backends (never with credentials).
    pub base_url: Option<String>,
}

impl BackendInfo {
    /// No backend: the method asks none.
    pub fn none() -> BackendInfo {
        BackendInfo {
            kind: BackendKind::None,
            model: String::new(),
            base_url: None,
        }
    }
}

/// What a backend gave for one query, and which of its endpoints gave it.
#[derive(Clone, Debug, PartialEq)]
pub struct Response {
    pub result: Result<Answer, LlmError>,
    /// The base URL that answered (the last one tried, when none did), for backends with
    /// endpoints; the transcript records it with the call.
    pub endpoint: Option<String>,
}

/// Anything that can play the assigner and executor roles.
pub trait Backend: Send + Sync {
    fn info(&self) -> BackendInfo;
    fn ask(&self, query: Query) -> BoxFuture<'_, Result<Answer, LlmError>>;

    /// [`Backend::ask`], naming the endpoint that answered; backends without endpoints
    /// name none.
    fn respond(&self, query: Query) -> BoxFuture<'_, Response> {
        Box::pin(async move {
            Response {
                result: self.ask(query).await,
                endpoint: None,
            }
        })
    }
}
