//! Who answers the methods' questions, behind one trait ([`crate::llm::Backend`]):
//!
//! - [`openai`]: any OpenAI-compatible chat completions server, with [`retry`]'s backoff;
//!   several servers of one model share its requests (`endpoints.rs`); [`address`] is
//!   how a base URL is posted to and shown.
//! - [`builtin`]: the optimal planner in every role, no model; with [`simulated`]
//!   mistakes at seeded rates, the simulated backend.
//! - [`replay`]: the answers recorded in a transcript, no network.

pub mod address;
pub mod builtin;
mod endpoints;
pub mod openai;
pub mod replay;
pub mod retry;
pub mod simulated;
