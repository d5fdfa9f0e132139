//! What an episode leaves behind: its [`transcript`] (one JSON line per round, written as
//! it runs), and the [`replay`] of a recorded episode from it.

pub mod replay;
pub mod transcript;
