//! The exception tree: `CoherentError` and a few subclasses, each raised for one kind of
//! failure, with the attributes a caller needs to act on it. The session's errors
//! ([`session_err`]) and the ways an episode ends ([`ending_err`]) map to them by kind,
//! one class each; [`PyCoherentErr`] carries the engine's errors to Python, so that the
//! bindings convert them with `?`.

use std::fmt::Display;

use coherent::session::Error;
use coherent::session::engine::{AgentsError, LlmError, PromptError, Setting, TaskError};
use coherent::session::episode::Ending;
use coherent::session::error::settings_differ;
use pyo3::exceptions::{PyException, PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyString, PyTuple, PyType};

/// The native module's name, which its exceptions report as their `__module__`.
const MODULE: &str = "coherent._coherent";

/// Built with `type(...)` rather than `create_exception!` because several of them also
/// derive from `ValueError` (bad input), which needs two bases.
pub(crate) struct Exceptions {
    pub base: Py<PyType>,
    pub argument: Py<PyType>,
    pub task_format: Py<PyType>,
    pub unknown_robot: Py<PyType>,
    pub action_parse: Py<PyType>,
    pub physics: Py<PyType>,
    pub backend: Py<PyType>,
    pub replay_mismatch: Py<PyType>,
    pub prompt: Py<PyType>,
    pub method: Py<PyType>,
    pub robot: Py<PyType>,
    pub data_file: Py<PyType>,
}

static EXCEPTIONS: PyOnceLock<Exceptions> = PyOnceLock::new();

pub(crate) fn exceptions(py: Python<'_>) -> PyResult<&'static Exceptions> {
    EXCEPTIONS.get_or_try_init(py, || {
        let make = |name: &str, bases: Vec<Bound<'_, PyType>>, doc: &str| -> PyResult<Py<PyType>> {
            let namespace = PyDict::new(py);
            namespace.set_item("__module__", MODULE)?;
            namespace.set_item("__doc__", doc)?;
            let bases = PyTuple::new(py, bases)?;
            let ty = py.get_type::<PyType>().call1((name, bases, namespace))?;
            Ok(ty.cast_into::<PyType>()?.unbind())
        };
        let value_error = py.get_type::<PyValueError>();
        let base = make(
            "CoherentError",
            vec![py.get_type::<PyException>()],
            "Base class of every error raised by coherent; raised itself when coherent\n\
             fails whatever the input (its async runtime cannot start: the process may\n\
             open no more files or start no more threads; an episode's thread panicked).",
        )?;
        let sub = |name: &str, value: bool, doc: &str| {
            let mut bases = vec![base.bind(py).clone()];
            if value {
                bases.push(value_error.clone());
            }
            make(name, bases, doc)
        };
        Ok(Exceptions {
            argument: sub(
                "ArgumentError",
                true,
                "An argument of the right type whose value cannot be used: an int out of\n\
                 range, a float that is not finite, text with a lone surrogate, an empty\n\
                 name, an unknown choice. The message names the argument and shows the value.",
            )?,
            task_format: sub(
                "TaskFormatError",
                true,
                "A task file or folder that cannot be read or does not follow its format.\n\n\
                 The message names the file, the JSON path and the offending value; the\n\
                 attributes `file` and `json_path` (None when the file could not be read at\n\
                 all) hold the first two.",
            )?,
            unknown_robot: sub(
                "UnknownRobotError",
                false,
                "A robot id that is not a robot of the task; the message lists its robots.",
            )?,
            action_parse: sub(
                "ActionParseError",
                true,
                "An action string that does not follow the grammar `[verb] <name>(id)`.\n\n\
                 Attributes: `action` (the text) and `reason`.",
            )?,
            physics: sub(
                "PhysicsError",
                false,
                "The physical simulation cannot build a task's scene; the message says why,\n\
                 with the numbers.",
            )?,
            backend: sub(
                "BackendError",
                false,
                "The language model's endpoint is misconfigured, or its server failed for\n\
                 good during an episode. Attribute `episode`: the episode up to there (its\n\
                 transcript is on disk), or None when no episode started.",
            )?,
            replay_mismatch: sub(
                "ReplayMismatchError",
                false,
                "A replayed episode did not come out as recorded. Attribute `episode`: the\n\
                 replayed episode.",
            )?,
            prompt: sub(
                "PromptError",
                true,
                "A prompt template that cannot be used, raised before any model call: a\n\
                 file that cannot be read, a file named after no template, or a placeholder\n\
                 the template's method does not fill. Attributes: `file` (None when the\n\
                 error is about no one file), `line` and `placeholder` (None unless the\n\
                 error is an unknown placeholder).",
            )?,
            method: sub(
                "MethodError",
                false,
                "A method written in Python raised an error during an episode (in its\n\
                 act, or when it was made). Attribute `episode`: the episode up to there\n\
                 (status \"error\"; the transcript has the traceback); the method's own\n\
                 exception is the `__cause__`.",
            )?,
            robot: sub(
                "RobotError",
                false,
                "Robots over ROS 2 could not be reached (no action server for some of them\n\
                 within the wait, DDS could not start), or one stopped answering during an\n\
                 episode. Attribute `episode`: the episode up to there (status\n\
                 \"interrupted\"), or None when no episode started.",
            )?,
            data_file: sub(
                "DataFileError",
                true,
                "A file of coherent's own formats other than tasks and prompt templates (a\n\
                 transcript, a results file, a price table, a subset list) that cannot be\n\
                 read or written, or does not follow its format. Attributes: `file` and\n\
                 `line` (None when the fault is not on one line).",
            )?,
            base,
        })
    })
}

/// An error on its way to Python: one that Python raised or the bindings built, or one
/// of the engine's, which becomes its exception by kind when it reaches Python. Neither
/// the session's errors nor `PyErr` are this crate's, so `From` between them cannot be
/// written (the orphan rule); this type stands between: functions that meet the
/// engine's errors return it and use `?` on both, and PyO3 (or `?` in a function that
/// returns `PyResult`) turns it into the exception.
pub(crate) enum PyCoherentErr {
    /// Raised by Python, or an exception built here.
    Python(PyErr),
    /// The session's error, raised by its kind ([`session_err`]).
    Session(Error),
    /// A model call's or the model client's, raised as a `BackendError` with no episode
    /// (the words the session gives an endpoint's error).
    Model(LlmError),
}

/// The bindings' results where the engine's errors meet Python's.
pub(crate) type PyCoherentResult<T> = Result<T, PyCoherentErr>;

impl From<PyErr> for PyCoherentErr {
    fn from(e: PyErr) -> PyCoherentErr {
        PyCoherentErr::Python(e)
    }
}

impl From<Error> for PyCoherentErr {
    fn from(e: Error) -> PyCoherentErr {
        PyCoherentErr::Session(e)
    }
}

/// A task file, a task, an action or a robot id: the session's `Error::Task`.
impl From<TaskError> for PyCoherentErr {
    fn from(e: TaskError) -> PyCoherentErr {
        PyCoherentErr::Session(e.into())
    }
}

/// A results file, a transcript, a method's name: as the session words them.
impl From<AgentsError> for PyCoherentErr {
    fn from(e: AgentsError) -> PyCoherentErr {
        PyCoherentErr::Session(e.into())
    }
}

impl From<LlmError> for PyCoherentErr {
    fn from(e: LlmError) -> PyCoherentErr {
        PyCoherentErr::Model(e)
    }
}

impl From<PyCoherentErr> for PyErr {
    fn from(e: PyCoherentErr) -> PyErr {
        match e {
            PyCoherentErr::Python(e) => e,
            // Converted on the way back to Python, where the GIL is held: `attach` is cheap.
            PyCoherentErr::Session(e) => Python::attach(|py| session_err(py, e)),
            PyCoherentErr::Model(e) => Python::attach(|py| backend(py, e.to_string())),
        }
    }
}

/// The exception of the session's error `e`, by its kind.
pub(crate) fn session_err(py: Python<'_>, e: Error) -> PyErr {
    let message = e.to_string();
    match e {
        Error::Invalid(_) | Error::Backend(_) => error(py, Kind::Argument, message, None),
        // Python's words: each knob is an argument of `coherent.generate`.
        Error::Knob(e) => error(py, Kind::Argument, argument_names(&e.to_string()), None),
        Error::Task(e) => core_err(py, e),
        Error::Prompt(e) => prompt(py, &e),
        Error::File { file, line, .. } => data_file(py, message, file, line),
        Error::NoTranscript { file, .. } => data_file(py, message, file, None),
        Error::Endpoint(_) => error(py, Kind::Backend, message, None),
        Error::SettingsDiffer { file, differences } => {
            let message = settings_differ(&file, &differences, |s| argument_of(s).into(), "out=");
            error(py, Kind::Argument, message, None)
        }
        Error::Physics(_) => error(py, Kind::Physics, message, None),
        // Python's words: the wait is the argument `server_wait=`.
        Error::Robots(e) => error(py, Kind::Robot, e.with_wait_named("server_wait="), None),
        Error::Interrupted => PyKeyboardInterrupt::new_err(message),
        Error::Internal(_) => error(py, Kind::Coherent, message, None),
    }
}

/// `text` with each command-line knob in it (`--max-draws`, at the start of a word: a
/// value quoted in the message is left as it is) named as the argument of
/// `coherent.generate` is (`max_draws`).
fn argument_names(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find("--") {
        let word_start = out.is_empty() && at == 0
            || rest[..at]
                .chars()
                .next_back()
                .or_else(|| out.chars().next_back())
                .is_some_and(|c| matches!(c, ' ' | '(' | '/'));
        out.push_str(&rest[..at]);
        let after = &rest[at + 2..];
        let name = after
            .find(|c: char| !(c.is_ascii_lowercase() || c == '-'))
            .map_or(after, |end| &after[..end]);
        if word_start && name.starts_with(|c: char| c.is_ascii_lowercase()) {
            out.push_str(&name.replace('-', "_"));
        } else {
            out.push_str("--");
            out.push_str(name);
        }
        rest = &after[name.len()..];
    }
    out.push_str(rest);
    out
}

/// A `DataFileError` with the file and the line (None when the fault is not on one line)
/// as attributes.
fn data_file(py: Python<'_>, message: String, file: String, line: Option<usize>) -> PyErr {
    let built = exceptions(py).and_then(|exc| {
        let value = exc.data_file.bind(py).call1((message.clone(),))?;
        value.setattr("file", file)?;
        value.setattr("line", line)?;
        Ok(PyErr::from_value(value))
    });
    raised(message, built)
}

/// The keyword argument of `coherent.bench` that sets `setting`.
pub(crate) fn argument_of(setting: Setting) -> &'static str {
    match setting {
        Setting::Backend => "backend",
        Setting::Model => "backend (the LLM's model)",
        Setting::SimErrors => "sim_errors",
        Setting::Temperature => "backend (the LLM's temperature)",
        Setting::ModelSeed => "backend (the LLM's seed)",
        Setting::Seeds => "seeds",
        Setting::Prompts => "prompts",
        Setting::History => "history",
        Setting::MaxSteps => "max_steps",
        Setting::MaxStates => "max_states",
        Setting::Physics => "physics",
        Setting::Robots => "robots",
        Setting::Execution => "execution",
        Setting::Version => "coherent's version",
        Setting::Method => "the method's own settings (its `settings`)",
        Setting::Unrecorded => "settings",
    }
}

/// The exception an episode that ended as `ending` raises, with `episode` attached;
/// `None` when it ended as episodes do (the goal reached, the budget spent, Ctrl-C).
pub(crate) fn ending_err(py: Python<'_>, ending: &Ending, episode: Py<PyAny>) -> Option<PyErr> {
    let (kind, why) = match ending {
        Ending::GoalReached | Ending::Conceded | Ending::BudgetSpent | Ending::Interrupted => {
            return None;
        }
        Ending::BackendFailed(why) => (Kind::Backend, why),
        Ending::MethodFailed(why) => (Kind::Method, why),
        Ending::ReplayDiffers(why) => (Kind::ReplayMismatch, why),
        Ending::RobotStopped(why) => (Kind::Robot, why),
    };
    // A traceback's last line is the exception; the whole of it is in the transcript.
    let last = why.trim_end().lines().last().unwrap_or(why);
    let path = episode
        .bind(py)
        .getattr("path")
        .and_then(|p| p.str())
        .map(|p| p.to_string())
        .unwrap_or_default();
    let message = format!("{last} (transcript: {path})");
    Some(error(py, kind, message, Some(episode)))
}

/// Converts a `coherent-core` error into the matching Python exception.
pub(crate) fn core_err(py: Python<'_>, e: TaskError) -> PyErr {
    let message = e.to_string();
    let built = exceptions(py).and_then(|exc| {
        let value = match &e {
            TaskError::Io { file, .. } => {
                let v = exc.task_format.bind(py).call1((message.clone(),))?;
                v.setattr("file", file)?;
                v.setattr("json_path", py.None())?;
                v
            }
            TaskError::Malformed { file, path, .. } => {
                let v = exc.task_format.bind(py).call1((message.clone(),))?;
                v.setattr("file", file)?;
                v.setattr("json_path", path.to_string())?;
                v
            }
            TaskError::UnknownRobot(_) => exc.unknown_robot.bind(py).call1((message.clone(),))?,
            TaskError::BadAction { action, reason } => {
                let v = exc.action_parse.bind(py).call1((message.clone(),))?;
                v.setattr("action", action)?;
                v.setattr("reason", reason)?;
                v
            }
            // Something a world cannot do (events in physics): the arguments, together.
            TaskError::Unsupported(_) => exc.argument.bind(py).call1((message.clone(),))?,
            // A task the PDDL domain cannot express: no file or path is at fault.
            TaskError::Inexpressible { .. } => {
                let v = exc.task_format.bind(py).call1((message.clone(),))?;
                v.setattr("file", py.None())?;
                v.setattr("json_path", py.None())?;
                v
            }
        };
        Ok(PyErr::from_value(value))
    });
    raised(message, built)
}

/// The exception `built`, or when Python itself failed to build it (e.g. out of memory), a
/// `RuntimeError` that says so, keeping the message.
fn raised(message: String, built: PyResult<PyErr>) -> PyErr {
    built.unwrap_or_else(|inner| {
        PyRuntimeError::new_err(format!("{message} (while raising it: {inner})"))
    })
}

/// Which class of the tree an error message belongs to.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Kind {
    Coherent,
    Argument,
    Physics,
    Backend,
    ReplayMismatch,
    Method,
    Robot,
}

/// An exception of class `kind` with `message`, and `episode` as its attribute for the
/// classes that carry one.
pub(crate) fn error(
    py: Python<'_>,
    kind: Kind,
    message: impl Into<String>,
    episode: Option<Py<PyAny>>,
) -> PyErr {
    let message = message.into();
    let built = exceptions(py).and_then(|exc| {
        let class = match kind {
            Kind::Coherent => &exc.base,
            Kind::Argument => &exc.argument,
            Kind::Physics => &exc.physics,
            Kind::Backend => &exc.backend,
            Kind::ReplayMismatch => &exc.replay_mismatch,
            Kind::Method => &exc.method,
            Kind::Robot => &exc.robot,
        };
        let value = class.bind(py).call1((message.clone(),))?;
        if matches!(
            kind,
            Kind::Backend | Kind::ReplayMismatch | Kind::Method | Kind::Robot
        ) {
            value.setattr("episode", episode)?;
        }
        Ok(PyErr::from_value(value))
    });
    raised(message, built)
}

/// A `BackendError` with `message`, no episode.
pub(crate) fn backend(py: Python<'_>, message: impl Into<String>) -> PyErr {
    error(py, Kind::Backend, message, None)
}

/// An `ArgumentError`: argument `name` cannot be `value` (shown cut down), because `why`.
pub(crate) fn argument(name: &str, value: &Bound<'_, PyAny>, why: impl Display) -> PyErr {
    let message = format!("{name}={}: {why}", short_repr(value));
    error(value.py(), Kind::Argument, message, None)
}

/// An `ArgumentError` whose message says it all: arguments that do not fit together, an
/// argument refused with the engine's own words.
pub(crate) fn invalid(py: Python<'_>, message: impl Into<String>) -> PyErr {
    error(py, Kind::Argument, message, None)
}

/// An `ArgumentError`: text argument `name` is `value`, none of its choices (`expected`).
pub(crate) fn choice(py: Python<'_>, name: &str, value: &str, expected: &str) -> PyErr {
    argument(name, PyString::new(py, value).as_any(), expected)
}

/// An `ActionParseError` for a str that Rust cannot hold as text (one with a lone
/// surrogate): its `action` attribute is the str as given.
pub(crate) fn not_text_action(action: &Bound<'_, PyString>, reason: String) -> PyErr {
    let py = action.py();
    let message = format!("cannot parse action {}: {reason}", short_repr(action));
    let built = exceptions(py).and_then(|exc| {
        let value = exc.action_parse.bind(py).call1((message.clone(),))?;
        value.setattr("action", action)?;
        value.setattr("reason", reason)?;
        Ok(PyErr::from_value(value))
    });
    raised(message, built)
}

/// `repr(value)`, cut in the middle to about 60 characters: enough to recognise a value
/// in a message, whatever its length.
pub(crate) fn short_repr(value: &Bound<'_, PyAny>) -> String {
    const HEAD: usize = 40;
    const TAIL: usize = 16;
    let full = value
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| format!("<{}>", value.get_type()));
    let chars = full.chars().count();
    if chars <= HEAD + TAIL + 3 {
        return full;
    }
    let head: String = full.chars().take(HEAD).collect();
    let tail: String = full.chars().skip(chars - TAIL).collect();
    format!("{head}...{tail}")
}

/// A `PromptError` with the file, the line and the placeholder as attributes.
pub(crate) fn prompt(py: Python<'_>, e: &PromptError) -> PyErr {
    let message = e.to_string();
    let built = exceptions(py).and_then(|exc| {
        let value = exc.prompt.bind(py).call1((message.clone(),))?;
        value.setattr("file", e.file())?;
        let (line, placeholder) = match e {
            PromptError::UnknownPlaceholder {
                line, placeholder, ..
            } => (Some(*line), Some(placeholder.as_str())),
            _ => (None, None),
        };
        value.setattr("line", line)?;
        value.setattr("placeholder", placeholder)?;
        Ok(PyErr::from_value(value))
    });
    raised(message, built)
}
