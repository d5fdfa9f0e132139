//! The planning methods, one file each, every one a [`crate::episode::Method`] that the
//! one loop ([`crate::episode::play()`]) asks each round:
//!
//! - [`pefa`]: COHERENT's Proposal-Execution-Feedback-Adjustment loop, sequential and in
//!   joint steps, with its two roles, the [`assigner::TaskAssigner`] and the
//!   [`executor::RobotExecutor`].
//! - The paper's baselines: [`cmrs`] (one central model, its prompt [`central`]),
//!   [`dmrs`] (decentralised dialogue), [`mcts`] (primitive MCTS and LLM-MCTS).
//! - [`llm_pddl`]: LLM+P, the model writing the goal once and the optimal planner
//!   planning for it.
//! - [`optimal`]: the optimal planner's plan, the tables' ground-truth row; [`random`]:
//!   a random feasible action each round, the floor.
//! - [`external`]: a method written outside the crate (a Python class, say), asked once
//!   per step through [`crate::episode::policy::Policy`].
//!
//! What they share: `decision`, the record of the action a method chose and what such
//! a method hears of a round; [`feedback`], what the next rounds hear of a round.

pub mod assigner;
pub mod central;
pub mod cmrs;
pub(crate) mod decision;
pub mod dmrs;
pub mod executor;
pub mod external;
pub mod feedback;
pub mod llm_pddl;
pub mod mcts;
pub mod optimal;
pub mod pefa;
pub mod random;
