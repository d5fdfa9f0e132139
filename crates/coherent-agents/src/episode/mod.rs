//! The episode: what every method shares, and the one way to run any of them.
//!
//! - [`settings`]: the method names ([`Method`]), a method written outside the crate
//!   ([`External`]) beside them ([`MethodSpec`]) and the settings a transcript records
//!   ([`Settings`]).
//! - [`execution`]: sequential or parallel ([`Execution`]).
//! - [`budget`]: the step budget ([`Budget`]), the paper's 2 x GT rule.
//! - [`policy`]: what a method written outside the crate answers each step
//!   ([`Policy`]) and what it is shown ([`StepView`]).
//! - [`rounds`]: the round loop and its result ([`Episode`]): one round per step until
//!   the goal holds, the budget is spent, the backend fails for good or [`Cancel`] fires;
//!   and the history window ([`HISTORY_WINDOW`]), what a method keeps of its earlier
//!   rounds ([`History`]).
//! - `ask`: asking a backend one question and recording the call.
//! - [`prefix`]: how much of each prompt is the same as the previous one of its role and
//!   robot ([`prefix::shared_prefix`]), recorded in every call.
//! - `environment`: observing the whole team and executing one action.
//! - `joint`: a parallel round's joint step, carried out and recorded part by part.
//! - [`cancel`]: stopping an episode from outside.
//! - [`run`](mod@run): the front door above the methods: writes the transcript and
//!   runs the method the settings name.
//!
//! Every method of [`crate::methods`] is built on `rounds`, `ask`, `environment` (in
//! parallel, `joint`) and `cancel` (`methods::external` on `policy` too); only [`run()`] looks at the methods.

pub(crate) mod ask;
pub mod budget;
pub mod cancel;
pub(crate) mod environment;
pub mod execution;
pub(crate) mod joint;
pub mod policy;
pub mod prefix;
pub mod rounds;
pub mod run;
pub mod settings;

// For callers that set up a replay piece by piece; `records::replay::Replay` does it in
// one call.
pub use crate::records::replay::{recorded_settings, recorded_task};
pub use budget::{Budget, NoPlan, PlannedMakespan};
pub use cancel::Cancel;
pub use policy::{Act, Choice, MakePolicy, MethodFailure, PastStep, Policy, RobotView, StepView};
pub use rounds::{Episode, HISTORY_WINDOW, History};
pub use run::{run, transcript_path};
pub use settings::{Execution, External, Method, MethodSpec, Settings};
