//! `coherent-agents`: the COHERENT planning loop over language models, and the methods
//! the paper compares it with.
//!
//! The crate is in five folders, by layer:
//!
//! - [`methods`]: the planning methods. The paper's [`pefa`] loop
//!   (Proposal-Execution-Feedback-Adjustment) with its two roles, [`TaskAssigner`]
//!   (`methods/assigner.rs`) and [`RobotExecutor`] (`methods/executor.rs`); the baselines
//!   [`cmrs`], [`dmrs`] and [`mcts`] over the [`team_actions`], the team's action space; the
//!   [`optimal`] plan, the tables' ground-truth row; and [`external`], the loop of a
//!   method written outside the crate (a Python class) that answers through a
//!   [`Policy`]. Their prompts are rendered from a prompt set, [`Prompts`]
//!   ([`templates`]): the built-in templates, or files given at run time.
//! - [`episode`]: what every method shares. The round loop and its [`Episode`], asking
//!   a backend, executing on the `coherent_core::Environment`, [`Cancel`], the step
//!   [`Budget`], the [`Method`] names, a method written outside the crate
//!   ([`External`], its [`Policy`] and the [`StepView`] it is shown) and their
//!   [`Settings`]; and [`episode::run()`], the front door that writes the transcript and
//!   runs the method the settings name.
//! - [`backends`]: who answers the methods' questions. The [`Backend`] trait ([`llm`])
//!   and an OpenAI-compatible server ([`openai`], with [`retry`]), the optimal planner
//!   ([`builtin`]; with seeded mistakes, the simulated backend) and a recorded transcript
//!   ([`replay`]).
//! - [`records`]: what an episode leaves behind. Its [`transcript`], and [`Replay`],
//!   which sets up the replay of a recorded episode and compares it with the recording.
//! - [`harness`] (also named [`bench`](mod@bench)): the benchmark's bookkeeping. The
//!   results file and the [`Ledger`](bench::Ledger) that resumes it, the subsets, what an
//!   episode costs ([`prices`]: a [`PriceTable`] and [`ModelUse`]), and [`report`], the
//!   paper's tables. Running the episodes is the session's (the root package).
//!
//! [`Error`] is what a caller outside the crate gets when something cannot be done.
//!
//! No file reaches back to one that uses it. From the bottom: [`llm`] is the vocabulary
//! of a model call; the transcript records calls in it; the backends answer them (the
//! replay one from a transcript; the built-in one picks from the [`team_actions`]
//! space); the episode loop asks backends and fills the records; the methods are built
//! on the loop, and [`episode::run()`] on the methods; [`Replay`] prepares a run of it,
//! and the harness keeps the books of many. [`rng`] is the crate's one random number
//! generator.
//!
//! The modules are also reachable at the crate root by their short names
//! (`coherent_agents::pefa`, `coherent_agents::bench`, ...).

/// The version of coherent, as transcripts and results lines record it.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

pub mod backends;
pub mod digest;
pub mod episode;
pub mod error;
pub mod harness;
pub mod methods;
pub mod records;
pub mod rng;

pub use backends::{builtin, llm, openai, replay, retry};
pub use harness as bench;
pub use harness::{prices, report};
pub use methods::{
    answer, central, cmrs, dmrs, external, feedback, mcts, optimal, pefa, pefa_parallel, prompt,
    team_actions, templates,
};
pub use records::transcript;

pub use backends::builtin::BuiltinBackend;
pub use backends::llm::{
    Answer, Backend, BackendInfo, BackendKind, LlmError, LlmErrorKind, OutputMode,
};
pub use backends::openai::{ApiKey, Chat, OpenAiClient, OpenAiConfig};
pub use backends::replay::ReplayBackend;
pub use backends::simulated::ErrorRates;
pub use episode::{
    Budget, Cancel, Episode, Execution, External, HISTORY_WINDOW, History, Method, MethodSpec,
    Policy, Settings, StepView,
};
pub use error::Error;
pub use harness::prices::{ModelUse, PriceTable};
pub use methods::assigner::TaskAssigner;
pub use methods::executor::RobotExecutor;
pub use methods::pefa::PefaConfig;
pub use methods::templates::{PromptError, Prompts};
pub use records::replay::{Replay, recorded_settings};
pub use records::transcript::{RobotPart, RoundOutcome, Status, Summary, Transcript};
