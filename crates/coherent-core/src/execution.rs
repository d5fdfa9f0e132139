//! How the robots of an episode take their steps ([`Execution`]): one robot's action a
//! step, as in the paper, or joint steps ([`crate::joint`]). Every layer names it (the
//! planner's makespan, the methods, transcripts, results lines, the prompt set's hash,
//! the command line and Python); this is its one definition and [`Execution::from_str`]
//! its one parser.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// How the robots of an episode take their steps: one action of one robot per step, as in
/// the paper, or several robots at once, at most one action each, in joint steps.
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

    /// Whether it is the paper's mode (what a transcript or results line written before
    /// parallel episodes means, and what it leaves unsaid).
    pub fn is_sequential(&self) -> bool {
        *self == Execution::Sequential
    }
}

/// A name that is no execution's, with the names that are.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownExecution(pub String);

impl fmt::Display for UnknownExecution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: expected \"sequential\" or \"parallel\"",
            crate::text::shown(&self.0)
        )
    }
}

impl std::error::Error for UnknownExecution {}

impl FromStr for Execution {
    type Err = UnknownExecution;

    fn from_str(name: &str) -> Result<Execution, UnknownExecution> {
        Execution::ALL
            .into_iter()
            .find(|e| e.name() == name)
            .ok_or_else(|| UnknownExecution(name.to_owned()))
    }
}

impl fmt::Display for Execution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_others_are_refused_with_the_choices() {
        for e in Execution::ALL {
            assert_eq!(e.name().parse::<Execution>(), Ok(e));
            assert_eq!(serde_json::to_value(e).ok(), Some(e.name().into()));
        }
        let err = "both".parse::<Execution>().expect_err("not a name");
        assert_eq!(
            err.to_string(),
            "both: expected \"sequential\" or \"parallel\""
        );
    }
}
