//! Files one process owns while it writes them: a benchmark's results file and its
//! transcripts folder (a second run on them would append the same episodes twice and
//! take the first run's transcripts for orphans), and each transcript while its episode
//! runs (so that no run renames it as left over). The locks are `flock(2)` locks, which
//! the system releases when the process ends, however it ends.

use std::fs::File;
use std::io;

/// Takes an exclusive lock on `file` without waiting: `Ok(false)` when another open
/// file (another process, or another part of this one) holds a lock on it.
pub fn try_exclusive(file: &File) -> io::Result<bool> {
    use rustix::fs::{FlockOperation, flock};
    match flock(file, FlockOperation::NonBlockingLockExclusive) {
        Ok(()) => Ok(true),
        Err(e) if e == rustix::io::Errno::WOULDBLOCK => Ok(false),
        Err(e) => Err(io::Error::from(e)),
    }
}
