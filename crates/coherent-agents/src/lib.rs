//! `coherent-agents`: the COHERENT planning loop over language models, and the methods
//! the paper compares it with.
//!
//! The crate is in layers, each a module of the crate root; a module imports only from
//! the modules listed before it (`scripts/check-layout` holds the crate to this order):
//!
//! 1. [`rng`] and [`digest`]: the crate's one random number generator and hash.
//! 2. [`llm`]: the vocabulary of a model call ([`Query`](llm::Query),
//!    [`Answer`], the [`Backend`] trait).
//! 3. [`prompts`]: the prompt set ([`Prompts`]: the built-in templates, or files given at
//!    run time), filling a template with what a role is shown, reading a model's answer,
//!    and the team's action lines that the central and dialogue methods choose from.
//! 4. [`setting`] and [`error`]: the settings a run can differ in, and [`Error`], what a
//!    caller outside the crate gets when something cannot be done.
//! 5. [`records`]: what an episode leaves behind, its [`transcript`].
//! 6. [`backends`]: who answers the methods' questions: an OpenAI-compatible server
//!    ([`openai`], with [`retry`]), the optimal planner ([`builtin`]; with seeded
//!    mistakes, the simulated backend) and a recorded transcript ([`replay`]).
//! 7. [`episode`]: the one loop every method runs under ([`episode::play()`]) and the
//!    [`Method`] trait it asks each round; asking a backend, carrying actions out on the
//!    `coherent_core::Environment`, one at a time or as a joint step; the history window,
//!    the step [`Budget`], [`Cancel`], and a method written outside the crate as the loop
//!    sees it ([`Policy`], [`StepView`]).
//! 8. [`methods`]: the planning methods, one file each: the paper's [`pefa`] loop with
//!    its two roles, [`TaskAssigner`] and [`RobotExecutor`]; the baselines [`cmrs`],
//!    [`dmrs`] and [`mcts`]; the [`optimal`] plan, the tables' ground-truth row;
//!    [`random`], the floor; and [`external`], a method written outside the crate.
//! 9. [`run`](mod@run): running one episode by its settings: the methods by name
//!    ([`Builtin`], [`MethodSpec`], each built into a [`Method`] in one place), the
//!    transcript written as it goes ([`run()`]), and [`Replay`], which sets up the replay
//!    of a recorded episode and compares it with the recording.
//! 10. [`harness`] (also named [`bench`](mod@bench)): the benchmark's bookkeeping: the
//!     results file and the [`Ledger`](bench::Ledger) that resumes it, the subsets, what an
//!     episode costs ([`prices`]: a [`PriceTable`] and [`ModelUse`]), and [`report`], the
//!     paper's tables. Running the episodes is the session's (the root package).
//! 11. [`training`]: training data from the optimal planner: each question a method's
//!     roles ask in an episode, with the planner's answer at that state in the method's
//!     own format ([`training::Teacher`]), read back with the method's parser.
//!
//! The modules are also reachable at the crate root by their short names
//! (`coherent_agents::pefa`, `coherent_agents::bench`, ...).

// Layers, lowest first: each module names only those above it (scripts/check-layout holds
// the crate to it). The comment above each also keeps rustfmt from sorting them.
// Seeded random numbers.
pub mod rng;
// Hashes of what runs are compared by.
pub mod digest;
// The vocabulary of a model call.
pub mod llm;
// The prompt set, filling it, reading answers.
pub mod prompts;
// The settings a benchmark run can differ in.
pub mod setting;
// What goes wrong, by kind.
pub mod error;
// What an episode leaves behind.
pub mod records;
// Who answers.
pub mod backends;
// The one loop and the shape of a method.
pub mod episode;
// The methods.
pub mod methods;
// One episode by its settings; replays.
pub mod run;
// The benchmark's bookkeeping.
pub mod harness;
// Training data from the optimal planner.
pub mod training;

pub use backends::{builtin, openai, replay, retry};
pub use harness as bench;
pub use harness::{prices, report};
pub use methods::{central, cmrs, dmrs, external, feedback, mcts, optimal, pefa, random};
pub use prompts::{answer, team_actions, templates};
pub use records::transcript;

pub use backends::builtin::BuiltinBackend;
pub use backends::openai::{ApiKey, Chat, OpenAiClient, OpenAiConfig};
pub use backends::replay::ReplayBackend;
pub use backends::simulated::ErrorRates;
pub use episode::{Budget, Cancel, Episode, HISTORY_WINDOW, History, Method, Policy, StepView};
pub use error::Error;
pub use harness::prices::{ModelUse, PriceTable};
pub use llm::{Answer, Backend, BackendInfo, BackendKind, LlmError, LlmErrorKind, OutputMode};
pub use methods::assigner::TaskAssigner;
pub use methods::executor::RobotExecutor;
pub use prompts::templates::{PromptError, Prompts};
pub use records::VERSION;
pub use records::transcript::{Reason, RobotPart, RoundOutcome, Status, Summary, Transcript};
pub use run::replay::{Replay, recorded_settings};
pub use run::run;
pub use run::settings::{Builtin, External, MethodSpec, Settings};
