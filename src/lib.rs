//! The `coherent` package: the command line over `coherent-core` (and, as they land,
//! `coherent-sim` and `coherent-agents`).

pub mod cli;
