//! The planning methods, each a loop of rounds over the shared episode loop
//! ([`crate::episode`]):
//!
//! - [`pefa`]: COHERENT's Proposal-Execution-Feedback-Adjustment loop, with its two
//!   roles, the [`assigner::TaskAssigner`] and the [`executor::RobotExecutor`];
//!   [`pefa_parallel`], the same loop in joint steps (robots acting at once).
//! - The paper's baselines: [`cmrs`] (one central model), [`dmrs`] (decentralised
//!   dialogue), [`mcts`] (primitive MCTS and LLM-MCTS); [`team_actions`] is the team's
//!   action space they choose from, [`central`] the central prompt.
//! - [`optimal`]: the optimal planner's plan, the tables' ground-truth row.
//! - [`external`]: a method written outside the crate (a Python class, say), asked once
//!   per step through [`crate::episode::policy::Policy`].
//!
//! What they share: [`templates`], the prompt set their prompts are rendered from, and
//! [`prompt`], filling it; [`answer`], reading a model's answer; `decision`, the
//! record of the action a method chose; [`feedback`], what the next rounds hear of a
//! round.

pub mod answer;
pub mod assigner;
pub mod central;
pub mod cmrs;
pub(crate) mod decision;
pub mod dmrs;
pub mod executor;
pub mod external;
pub mod feedback;
pub mod mcts;
pub mod optimal;
pub mod pefa;
pub mod pefa_parallel;
pub mod prompt;
pub mod team_actions;
pub mod templates;
