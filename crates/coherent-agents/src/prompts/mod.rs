//! What the methods' prompts are made of, below every method and backend:
//!
//! - [`templates`]: the prompt set ([`templates::Prompts`]): the built-in templates, the
//!   paper's layout, or files given at run time, and what a transcript records of it.
//! - [`fill`]: filling a template with what a role is shown (`Sight`), the team
//!   list and robot labels.
//! - [`answer`]: reading a model's answer (JSON, fenced, or free text) and the line it
//!   names or comes nearest to.
//! - [`team_actions`]: the team's actions as `<robot>: <action>` lines, which the central
//!   and dialogue methods choose from and the built-in backend answers with.

pub mod answer;
pub mod fill;
pub mod team_actions;
pub mod templates;
