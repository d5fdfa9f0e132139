//! The types of the crates below the session that the front ends use, re-exported here
//! on purpose and nowhere else, so that the command line (`src/cli`) and the Python
//! bindings (`crates/coherent-py`) name nothing below the session
//! (`scripts/check-layout` checks it; `docs/architecture.md`, "What the session
//! re-exports", says why each is here).

// Tasks and the rules: what a front end reads, shows, plans and steps by hand; the task
// formats and the feasibility check, which Python's `Task` and `Env` give as they are.
pub use coherent_core::action::most_actions;
pub use coherent_core::action::{Mention, parse as parse_action};
pub use coherent_core::load::load_tasks;
pub use coherent_core::makespan::Makespan;
pub use coherent_core::planner::{Analysis, Limits, Stop};
pub use coherent_core::task::predicate_holds;
pub use coherent_core::text::{number, shown, shown_lines};
pub use coherent_core::{Environment, Error as TaskError, Execution, NodeId, RawGraph, Task};
pub use coherent_core::{feasibility, native, original};

// What a run records: the transcript, its rounds and summary, the step budget.
pub use coherent_agents::episode::{Budget, HISTORY_WINDOW};
pub use coherent_agents::transcript::{
    Reason, RobotPart, Round, RoundOutcome, Status, Summary, Transcript,
    actions as executed_actions,
};

// The limits on what is read back, in MiB as their flags give them: a transcript, a
// results file.
pub use coherent_agents::bench::{DEFAULT_MAX_RESULTS_BYTES, ReadLimits, read_results_within};
pub use coherent_agents::transcript::DEFAULT_MAX_BYTES as DEFAULT_MAX_TRANSCRIPT_BYTES;
pub use coherent_core::files::MIB;

// Which method runs: a built-in one, or one written outside the crates (Python), with
// what it is shown each step and what it answers.
pub use coherent_agents::episode::{
    Act, Choice, MakePolicy, MethodFailure, Policy, RobotView, StepView,
};
pub use coherent_agents::{Builtin, External, MethodSpec};

// Reaching a model: the endpoint settings, the client that methods written in Python
// call directly, what a call sends and gets back.
pub use coherent_agents::llm::{Answer, BoxFuture, Finish, LlmError, Message, Role};
pub use coherent_agents::retry::Backoff;
pub use coherent_agents::transcript::Call;
pub use coherent_agents::{ApiKey, Backend, Chat, OpenAiClient, OpenAiConfig, OutputMode};
// A base URL as it may be shown: no user or password, query values redacted.
pub use coherent_agents::backends::address::redacted;

// What a run is given besides its task: the simulated backend's mistakes, the prompt
// set and its errors, the price table.
pub use coherent_agents::{ErrorRates, PriceTable, PromptError, Prompts};

// Benchmarks: the results file, its lines and the driver's ledger, the subsets, the
// progress lines, the paper's tables.
pub use coherent_agents::bench::progress::clock;
// What the ledger, the results file's readers and an `External`'s constructor return,
// which the Python bindings convert into their exceptions by kind.
pub use coherent_agents::Error as AgentsError;
pub use coherent_agents::bench::{
    BenchOutcome, Difference, EpisodeKey, EpisodeResult, Event, Group, Ledger, Progress,
    ResultLine, RunSettings, Setting, Style, Subset, read_results, select, transcripts_dir,
    worth_a_line,
};
pub use coherent_agents::report::{Mixed, Report};
pub use coherent_agents::setting::field as setting_field;

// Stopping work from outside (Ctrl-C).
pub use coherent_agents::Cancel;

// Robots over ROS 2: the namespace their actions live under unless told otherwise, the
// names robots go by there (also the agents of `coherent.marl`), and the memory the
// reference servers limit themselves to unless told otherwise.
pub use coherent_ros::SERVE_MEMORY_LIMIT;
pub use coherent_ros::wire::{DEFAULT_NAMESPACE, robot_names};
