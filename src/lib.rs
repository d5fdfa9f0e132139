//! The `coherent` package: the session layer over `coherent-core`, `coherent-sim` and
//! `coherent-agents` ([`session`]), and the command line on top of it ([`cli`]). The
//! Python bindings (`coherent-py`) call the same session layer.

pub mod cli;
pub mod session;
