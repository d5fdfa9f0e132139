//! What an episode leaves behind: its [`transcript`] (one JSON line per round, written as
//! it runs), and the [`replay`] of a recorded episode from it; [`lock`] keeps a file
//! being written from a second writer.

pub mod lock;
pub mod replay;
pub mod transcript;
