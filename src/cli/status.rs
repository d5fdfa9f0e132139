//! The command line's exit statuses, each derived from the kind of what happened: how an
//! episode ended ([`Ending`]) or why nothing ran ([`Error`]). README.md lists them.

use crate::session::Error;
use crate::session::episode::Ending;

/// The goal was reached (or a command did what it was asked).
pub(crate) const OK: u8 = 0;
/// The episode ran but the goal was not reached (the step budget is spent).
pub(crate) const FAILED: u8 = 1;
/// Bad input: arguments, task files, prompt templates, transcripts, results files, an
/// endpoint that cannot be set up, robots that cannot be reached, a world that cannot
/// be built; nothing ran.
pub(crate) const BAD_INPUT: u8 = 2;
/// The model's server failed for good, or a replay did not come out as recorded.
pub(crate) const BACKEND_FAILED: u8 = 3;
/// A method written in Python raised an error.
pub(crate) const METHOD_FAILED: u8 = 4;
/// A robot over ROS 2 stopped answering (the environment stopped the episode).
pub(crate) const ROBOT_STOPPED: u8 = 5;
/// Coherent itself failed, whatever the input: its async runtime did not start (no file
/// descriptors or threads left to the process), an episode's thread panicked. The
/// number is `EX_SOFTWARE` of BSD's sysexits.h ("an internal software error").
pub(crate) const INTERNAL: u8 = 70;
/// Ctrl-C, as shells report SIGINT.
pub(crate) const INTERRUPTED: u8 = 130;
/// SIGTERM, as shells report it; it stops a run as Ctrl-C does (`super::signals`).
pub(crate) const TERMINATED: u8 = 143;

/// The exit status of an episode that ended as `ending`.
pub(crate) fn of_ending(ending: &Ending) -> u8 {
    match ending {
        Ending::GoalReached | Ending::Conceded => OK,
        Ending::BudgetSpent => FAILED,
        Ending::BackendFailed(_) | Ending::ReplayDiffers(_) => BACKEND_FAILED,
        Ending::MethodFailed(_) => METHOD_FAILED,
        Ending::RobotStopped(_) => ROBOT_STOPPED,
        Ending::Interrupted => INTERRUPTED,
    }
}

/// The exit status when `error` kept a command from running.
pub(crate) fn of_error(error: &Error) -> u8 {
    match error {
        Error::Interrupted => INTERRUPTED,
        Error::Invalid(_)
        | Error::Knob(_)
        | Error::Backend(_)
        | Error::Task(_)
        | Error::Prompt(_)
        | Error::File { .. }
        | Error::NoTranscript { .. }
        | Error::Endpoint(_)
        | Error::SettingsDiffer { .. }
        | Error::Physics(_)
        | Error::Robots(_) => BAD_INPUT,
        Error::Internal(_) => INTERNAL,
    }
}
