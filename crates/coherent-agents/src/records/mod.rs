//! What an episode leaves behind: its [`transcript`] (one JSON line per round, written as
//! it runs, read back by every version since the first); [`lock`] keeps a file being
//! written from a second writer.

/// The version of coherent, as transcripts and results lines record it.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

pub mod lock;
pub mod transcript;
