//! The planning methods, each a loop of rounds over the shared episode loop
//! ([`crate::episode`]):
//!
//! - [`pefa`]: COHERENT's Proposal-Execution-Feedback-Adjustment loop, with its two
//!   roles, the [`assigner::TaskAssigner`] and the [`executor::RobotExecutor`].
//! - The paper's baselines: [`cmrs`] (one central model), [`dmrs`] (decentralised
//!   dialogue), [`mcts`] (primitive MCTS and LLM-MCTS); [`joint`] is the team's joint
//!   action space they choose from, as text.
//! - [`optimal`]: the optimal planner's plan, the tables' ground-truth row.
//! - [`external`]: a method written outside the crate (a Python class, say), asked once
//!   per step through [`crate::episode::policy::Policy`].
//!
//! [`templates`] is the prompt set the methods render their prompts from; [`prompt`] and
//! `answer` are what the methods' prompts and answer readers share.

pub(crate) mod answer;
pub mod assigner;
pub mod cmrs;
pub mod dmrs;
pub mod executor;
pub mod external;
pub mod joint;
pub mod mcts;
pub mod optimal;
pub mod pefa;
pub mod prompt;
pub mod templates;
