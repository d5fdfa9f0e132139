//! What a caller outside the crate gets when something cannot be done: one variant per
//! kind of failure, so that a front end decides by the kind (an exception class, an exit
//! status) and never by the words.

use std::fmt;

use crate::llm::LlmError;
use crate::prompts::templates::PromptError;
use crate::setting::{Difference, field};

/// Why the crate could not do what it was asked.
#[derive(Clone, Debug, PartialEq)]
pub enum Error {
    /// A file that cannot be read or written: a transcript, a results file, a price
    /// table, a subset list, their folders.
    Io { file: String, message: String },
    /// An episode's transcript that cannot be created (its folder cannot be made, or
    /// allows no new file): nothing of the episode ran, so a benchmark can go on.
    NoTranscript { file: String, message: String },
    /// A file of one of the crate's formats (a transcript, a results file, a price table,
    /// a subset list) that does not follow it; `line` when the fault is on one line.
    Format {
        file: String,
        line: Option<usize>,
        message: String,
    },
    /// A prompt template that cannot be used.
    Prompt(PromptError),
    /// The model endpoint's client cannot be set up (no model, a base URL that is no
    /// URL).
    Endpoint(LlmError),
    /// A value given that cannot be used: a method's name, error rates, two tasks alike.
    Invalid(String),
    /// A task with no ground truth and no plan to size a step budget from.
    NoBudget(String),
    /// A task (one recorded in a transcript) that cannot be read.
    Task(coherent_core::Error),
    /// A results file whose lines were run with other settings than the run that would
    /// resume it: each setting that differs.
    SettingsDiffer {
        file: String,
        differences: Vec<Difference>,
    },
}

impl Error {
    /// An [`Error::Io`] about `file`.
    pub fn io(file: &std::path::Path, e: &std::io::Error) -> Error {
        Error::Io {
            file: file.display().to_string(),
            message: e.to_string(),
        }
    }

    /// A file of the crate's formats that `coherent_core::files` could not read (gone, a
    /// folder, more than its limit): an [`Error::Io`] about it.
    pub fn file(e: coherent_core::Error) -> Error {
        match e {
            coherent_core::Error::Io { file, message } => Error::Io { file, message },
            other => Error::Task(other),
        }
    }

    /// An [`Error::Format`] about line `line` (counted from 1) of `file`.
    pub fn at_line(file: &std::path::Path, line: usize, message: impl Into<String>) -> Error {
        Error::Format {
            file: file.display().to_string(),
            line: Some(line),
            message: message.into(),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Io { file, message } | Error::NoTranscript { file, message } => {
                write!(f, "{file}: {message}")
            }
            Error::Format {
                file,
                line: Some(line),
                message,
            } => write!(f, "{file}: line {line}: {message}"),
            Error::Format {
                file,
                line: None,
                message,
            } => write!(f, "{file}: {message}"),
            Error::Prompt(e) => e.fmt(f),
            Error::Endpoint(e) => e.fmt(f),
            Error::Invalid(why) | Error::NoBudget(why) => f.write_str(why),
            Error::Task(e) => e.fmt(f),
            Error::SettingsDiffer { file, differences } => {
                write!(f, "{file} holds episodes run with other settings (")?;
                for (i, d) in differences.iter().enumerate() {
                    let sep = if i == 0 { "" } else { "; " };
                    write!(f, "{sep}{}: {d}", field(d.setting))?;
                }
                f.write_str(
                    "): give this run another results file, or run it with the file's settings",
                )
            }
        }
    }
}

impl std::error::Error for Error {}

impl From<PromptError> for Error {
    fn from(e: PromptError) -> Error {
        Error::Prompt(e)
    }
}

impl From<coherent_core::Error> for Error {
    fn from(e: coherent_core::Error) -> Error {
        Error::Task(e)
    }
}

/// The crate's results.
pub type Result<T, E = Error> = std::result::Result<T, E>;
