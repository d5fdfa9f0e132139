//! `coherent-agents`: the COHERENT planning loop over language models.
//!
//! [`pefa`] runs the paper's Proposal-Execution-Feedback-Adjustment loop on any
//! `coherent_core::Environment`, asking its two roles through a [`Backend`]: an
//! OpenAI-compatible server ([`openai`]), a recorded transcript ([`replay`]) or the
//! optimal planner ([`builtin`]). Prompts are template files ([`prompt`]); answers are
//! parsed robustly ([`answer`]); every episode writes a [`transcript`].

pub mod answer;
pub mod bench;
pub mod builtin;
pub mod cmrs;
pub mod dmrs;
pub mod episode;
pub mod joint;
pub mod llm;
pub mod mcts;
pub mod openai;
pub mod optimal;
pub mod pefa;
pub mod prompt;
pub mod replay;
pub mod report;
pub mod retry;
pub mod rng;
pub mod transcript;

pub use builtin::{BuiltinBackend, ErrorRates};
pub use episode::{Budget, Method, Settings};
pub use llm::{Answer, Backend, BackendInfo, LlmError, LlmErrorKind, OutputMode};
pub use openai::{ApiKey, OpenAiClient, OpenAiConfig};
pub use pefa::{Cancel, Episode, PefaConfig};
pub use replay::ReplayBackend;
pub use transcript::{Status, Summary, Transcript};
