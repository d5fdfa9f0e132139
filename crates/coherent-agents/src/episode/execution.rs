//! How the robots of an episode take their steps ([`Execution`]): a setting every layer
//! names (the methods, the transcripts, the results lines, the prompt set's hash), kept
//! in a file of its own that names nothing else.

use serde::{Deserialize, Serialize};

/// How the robots of an episode take their steps: one action of one robot per step, as in
/// the paper, or several robots at once, at most one action each, in joint steps
/// (`coherent_core::joint`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Execution {
    #[default]
    Sequential,
    Parallel,
}

impl Execution {
    pub const ALL: [Execution; 2] = [Execution::Sequential, Execution::Parallel];

    /// `sequential` or `parallel`, as flags, transcripts and results lines write it.
    pub fn name(self) -> &'static str {
        match self {
            Execution::Sequential => "sequential",
            Execution::Parallel => "parallel",
        }
    }

    pub fn from_name(name: &str) -> Option<Execution> {
        Execution::ALL.into_iter().find(|e| e.name() == name)
    }

    /// Whether it is the paper's mode (what a transcript or results line written before
    /// parallel episodes means, and what it leaves unsaid).
    pub fn is_sequential(&self) -> bool {
        *self == Execution::Sequential
    }
}

impl std::fmt::Display for Execution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
