//! The one error type of `coherent-core`. Every message about input names the file,
//! the JSON path and the offending value, cut to [`ECHO_CHARS`] characters when it is
//! longer ([`clip`], [`quoted`]).

use std::fmt;

#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Error {
    /// A file or folder could not be read or written.
    #[error("{file}: {message}")]
    Io { file: String, message: String },
    /// Input that does not follow the format: bad JSON, unknown ids, duplicates...
    #[error("{file}: {path}: {message}")]
    Malformed {
        file: String,
        path: JsonPath,
        message: String,
    },
    /// A robot id that is not a robot of the task.
    #[error("{0}")]
    UnknownRobot(String),
    /// An action string that does not follow the grammar `[verb] <name>(id)`.
    #[error("cannot parse action {}: {reason}", quoted(action))]
    BadAction { action: String, reason: String },
    /// Something this world cannot do (an event in physics, say).
    #[error("{0}")]
    Unsupported(String),
    /// A task the PDDL domain cannot express exactly (docs/pddl.md, "What is refused").
    #[error("{task} cannot be written in PDDL: {reason}")]
    Inexpressible { task: String, reason: String },
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A JSON path in the `$.a[3].b` notation.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct JsonPath(String);

impl JsonPath {
    pub fn root() -> JsonPath {
        JsonPath::default()
    }
    /// The member `key` of this object; a key longer than [`ECHO_CHARS`] is cut.
    pub fn key(&self, key: &str) -> JsonPath {
        JsonPath(format!("{}.{}", self.0, clip(key)))
    }
    pub fn index(&self, i: usize) -> JsonPath {
        JsonPath(format!("{}[{i}]", self.0))
    }
}

/// The most characters of a value from the input that a message repeats.
pub const ECHO_CHARS: usize = 80;

/// `text` itself when it has at most [`ECHO_CHARS`] characters, otherwise its first
/// ones, an ellipsis and its full length: `abc… (100000 chars)`.
pub fn clip(text: &str) -> String {
    match text.char_indices().nth(ECHO_CHARS) {
        None => text.to_owned(),
        Some((end, _)) => format!("{}… ({} chars)", &text[..end], text.chars().count()),
    }
}

/// `text` in double quotes with Rust's escapes (as `{:?}` writes it), cut like [`clip`]:
/// `"abc…" (100000 chars)`.
pub fn quoted(text: &str) -> String {
    match text.char_indices().nth(ECHO_CHARS) {
        None => format!("{text:?}"),
        Some((end, _)) => {
            let head = format!("{:?}", &text[..end]);
            format!(
                "{}…\" ({} chars)",
                &head[..head.len() - 1],
                text.chars().count()
            )
        }
    }
}

impl fmt::Display for JsonPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "${}", self.0)
    }
}

/// Where in which file a value was read: builds [`Error::Malformed`] in one line.
#[derive(Clone, Debug)]
pub(crate) struct Site<'a> {
    pub file: &'a str,
    pub path: JsonPath,
}

impl<'a> Site<'a> {
    pub fn new(file: &'a str, path: JsonPath) -> Site<'a> {
        Site { file, path }
    }
    pub fn key(&self, key: &str) -> Site<'a> {
        Site {
            file: self.file,
            path: self.path.key(key),
        }
    }
    pub fn index(&self, i: usize) -> Site<'a> {
        Site {
            file: self.file,
            path: self.path.index(i),
        }
    }
    pub fn error(&self, message: impl Into<String>) -> Error {
        Error::Malformed {
            file: self.file.to_owned(),
            path: self.path.clone(),
            message: message.into(),
        }
    }
}

/// Returns early with a [`Error::Malformed`] at `site` when `cond` fails.
macro_rules! ensure {
    ($cond:expr, $site:expr, $($msg:tt)+) => {
        if !$cond {
            return Err($site.error(format!($($msg)+)));
        }
    };
}
pub(crate) use ensure;
