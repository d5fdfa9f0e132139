//! `coherent-agents`: the COHERENT planning loop over language models.
//!
//! [`pefa`] runs the paper's Proposal-Execution-Feedback-Adjustment loop on any
//! `coherent_core::Environment`, asking its two roles through a [`Backend`]: an
//! OpenAI-compatible server ([`openai`]), a recorded transcript ([`replay`]) or the
//! optimal planner ([`builtin`]). Prompts are template files ([`prompt`]); answers are
//! parsed robustly ([`answer`]); every episode writes a [`transcript`].

pub mod backends;
pub mod episode;
pub mod harness;
pub mod methods;
pub mod records;
pub mod rng;

pub use backends::{builtin, llm, openai, replay, retry};
pub use harness::{bench, report};
pub use methods::{answer, cmrs, dmrs, joint, mcts, optimal, pefa, prompt};
pub use records::transcript;

pub use builtin::{BuiltinBackend, ErrorRates};
pub use episode::{Budget, Method, Settings};
pub use llm::{Answer, Backend, BackendInfo, LlmError, LlmErrorKind, OutputMode};
pub use openai::{ApiKey, OpenAiClient, OpenAiConfig};
pub use pefa::{Cancel, Episode, PefaConfig};
pub use replay::ReplayBackend;
pub use transcript::{Status, Summary, Transcript};
