//! What a front end gets when the session cannot do what it was asked: one variant per
//! kind of failure. The command line derives its exit status from the kind and Python
//! its exception class (`docs/architecture.md`, "Errors"); neither reads the words.

use std::fmt;

use coherent_agents::PromptError;
use coherent_agents::bench::{Difference, Setting};
use coherent_core::text::shown;

/// Why the session could not do what it was asked.
#[derive(Debug)]
pub enum Error {
    /// An argument or setting that cannot be used: a method's name, error rates, a
    /// namespace, two tasks alike, a task with no step budget to size.
    Invalid(String),
    /// A knob of a generated set that cannot be read, or a request its draws cannot
    /// meet: the knob as the command line names it (`--rooms`; Python says `rooms`).
    Knob(coherent_generate::KnobError),
    /// The backend's settings do not fit together (each front end words these in its
    /// own terms, flags or keyword arguments).
    Backend(BackendProblem),
    /// A task file, a task, an action or a robot id.
    Task(coherent_core::Error),
    /// A prompt template.
    Prompt(PromptError),
    /// A file of coherent's other formats (a transcript, a results file, a price table,
    /// a subset list) that cannot be read or written, or does not follow its format;
    /// `line` when the fault is on one line.
    File {
        file: String,
        line: Option<usize>,
        message: String,
    },
    /// An episode's transcript that cannot be created (its folder cannot be made, or
    /// allows no new file); nothing of the episode ran. A benchmark records it in the
    /// episode's line and goes on.
    NoTranscript { file: String, message: String },
    /// The model endpoint is misconfigured: no model, a base URL that is no URL.
    Endpoint(String),
    /// A results file whose lines were run with other settings than the run that would
    /// resume it (each front end names the settings as its flags or arguments).
    SettingsDiffer {
        file: String,
        differences: Vec<Difference>,
    },
    /// The physical world cannot be built for the task.
    Physics(coherent_sim::PhysicsError),
    /// Robots over ROS 2 cannot be reached (no server within the wait, no DDS).
    Robots(coherent_ros::Error),
    /// Stopped from outside (Ctrl-C) before it could finish.
    Interrupted,
    /// The engine itself failed: a runtime that does not start, an episode's thread
    /// that panicked.
    Internal(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Invalid(why) | Error::Endpoint(why) | Error::Internal(why) => f.write_str(why),
            Error::Backend(problem) => problem.fmt(f),
            Error::Knob(e) => e.fmt(f),
            Error::Task(e) => e.fmt(f),
            Error::Prompt(e) => e.fmt(f),
            Error::File {
                file,
                line: Some(line),
                message,
            } => write!(f, "{file}: line {line}: {message}"),
            Error::File {
                file,
                line: None,
                message,
            }
            | Error::NoTranscript { file, message } => write!(f, "{file}: {message}"),
            Error::SettingsDiffer { file, differences } => {
                let name = |s| coherent_agents::setting::field(s).to_owned();
                f.write_str(&settings_differ(file, differences, name, "results file"))
            }
            Error::Physics(e) => write!(f, "physics: {}", e.message),
            Error::Robots(e) => e.fmt(f),
            Error::Interrupted => f.write_str("interrupted"),
        }
    }
}

impl std::error::Error for Error {}

impl From<coherent_agents::Error> for Error {
    fn from(e: coherent_agents::Error) -> Error {
        use coherent_agents::Error as A;
        match e {
            A::Io { file, message } => Error::File {
                file,
                line: None,
                message,
            },
            A::Format {
                file,
                line,
                message,
            } => Error::File {
                file,
                line,
                message,
            },
            A::NoTranscript { file, message } => Error::NoTranscript { file, message },
            A::Prompt(e) => Error::Prompt(e),
            A::Endpoint(e) => Error::Endpoint(e.to_string()),
            A::Invalid(why) | A::NoBudget(why) => Error::Invalid(why),
            A::Task(e) => Error::Task(e),
            A::SettingsDiffer { file, differences } => Error::SettingsDiffer { file, differences },
        }
    }
}

impl From<coherent_core::Error> for Error {
    fn from(e: coherent_core::Error) -> Error {
        Error::Task(e)
    }
}

impl From<PromptError> for Error {
    fn from(e: PromptError) -> Error {
        Error::Prompt(e)
    }
}

impl From<coherent_sim::PhysicsError> for Error {
    fn from(e: coherent_sim::PhysicsError) -> Error {
        Error::Physics(e)
    }
}

impl From<coherent_ros::Error> for Error {
    fn from(e: coherent_ros::Error) -> Error {
        Error::Robots(e)
    }
}

impl From<BackendProblem> for Error {
    fn from(p: BackendProblem) -> Error {
        Error::Backend(p)
    }
}

/// What a front end says when a results file holds episodes of other settings: each
/// setting by `name` (a flag, a keyword argument) with its two values, and the two ways
/// on (`out`: how the front end names the results file).
pub fn settings_differ(
    file: &str,
    differences: &[Difference],
    name: impl Fn(Setting) -> String,
    out: &str,
) -> String {
    let mut text = format!("{file} holds episodes run with other settings:");
    for d in differences {
        let method = d
            .method
            .as_ref()
            .map_or(String::new(), |m| format!(" of {}", shown(m)));
        text.push_str(&format!("\n  {}{method}: {d}", name(d.setting)));
    }
    text.push_str(&format!(
        "\nnothing ran: to keep both runs, give this one another {out}; to resume the \
         file, run with its settings."
    ));
    text
}

/// Why the backend's settings do not fit together. Each front end words these in its own
/// terms (flags or keyword arguments); [`Display`](fmt::Display) has the neutral text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BackendProblem {
    /// Error rates were given for a backend other than the simulated one.
    RatesNeedSimulated,
    /// Error rates and an endpoint were both given without naming a backend.
    RatesAndEndpoint,
    /// A replay without the results file it answers from.
    ReplayNeedsFile,
    /// A results file to replay from, for a backend other than replay.
    FileNeedsReplay,
    /// The OpenAI-compatible backend without an endpoint.
    NoEndpoint,
    /// A single episode asked for a benchmark's replay (`run` replays a transcript).
    ReplayIsForBenchmarks,
}

impl fmt::Display for BackendProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BackendProblem::RatesNeedSimulated => {
                "simulated error rates need the simulated backend"
            }
            BackendProblem::RatesAndEndpoint => {
                "simulated errors are for the simulated backend: leave out the endpoint"
            }
            BackendProblem::ReplayNeedsFile => "a replay needs the earlier results file",
            BackendProblem::FileNeedsReplay => "a results file to replay from needs the replay backend",
            BackendProblem::NoEndpoint => {
                "the OpenAI-compatible backend needs an endpoint: a base URL (OPENAI_BASE_URL) and a model (COHERENT_MODEL)"
            }
            BackendProblem::ReplayIsForBenchmarks => {
                "a benchmark's replay backend answers benchmark episodes only"
            }
        })
    }
}

/// What a caught panic said: its message, when it has one (`panic!` with text does).
pub(crate) fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".to_owned())
}

/// The session's results.
pub type Result<T, E = Error> = std::result::Result<T, E>;
