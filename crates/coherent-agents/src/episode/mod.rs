//! The episode loop: what every method shares, and the shape every method has.
//!
//! - [`method`]: the [`Method`] trait (what a method asks in a round and what it makes of
//!   the answers), the [`Turn`] it is asked in and what it decided ([`Decided`]).
//! - [`play`](mod@play): the one loop ([`play()`]): one round per step until the goal
//!   holds, the budget is spent, the backend fails for good, the method fails or
//!   [`Cancel`] fires; carrying out what the method decided (`environment`, or in a
//!   parallel round `joint`); the history window ([`HISTORY_WINDOW`], [`History`]) and
//!   the result ([`Episode`]).
//! - [`budget`]: the step budget ([`Budget`]), the paper's 2 x GT rule.
//! - [`policy`]: what a method written outside the crate answers each step ([`Policy`])
//!   and what it is shown ([`StepView`]).
//! - `ask`: asking a backend one question (or several at once) and recording the call.
//! - [`prefix`]: how much of each prompt is the same as the previous one of its role and
//!   robot ([`prefix::shared_prefix`]), recorded in every call.
//! - [`cancel`]: stopping an episode from outside.
//! - `events`: the task's events along an episode (docs/dynamic.md): carried
//!   out before the rounds they are due, the optimum proven again at each, failing
//!   actions, the recovery measured, the episode's reference.

pub(crate) mod ask;
pub mod budget;
pub mod cancel;
pub(crate) mod environment;
pub(crate) mod events;
pub(crate) mod joint;
pub mod method;
pub mod play;
pub mod policy;
pub mod prefix;

pub use budget::{Budget, NoPlan, PlannedMakespan};
pub use cancel::Cancel;
pub use events::{action_failure, prove};
pub use method::{Closing, Decided, Deciding, Method, Turn};
pub use play::{Course, Episode, HISTORY_WINDOW, History, play};
pub use policy::{Act, Choice, MakePolicy, MethodFailure, PastStep, Policy, RobotView, StepView};
