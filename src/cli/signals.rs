//! Ctrl-C and SIGTERM stop `run` and `bench` the same way: the episodes in flight end as
//! interrupted (their transcripts and results lines say so) and the command exits with
//! the status shells give the signal, 130 or 143.

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

use tokio::task::JoinHandle;

use super::status::{INTERRUPTED, TERMINATED};
use crate::session::engine::Cancel;

/// Watches for the signals while a command runs; dropped, it stops watching.
pub(crate) struct Stop {
    watch: JoinHandle<()>,
    status: Arc<AtomicU8>,
}

impl Stop {
    /// Cancels `cancel` on the first Ctrl-C or SIGTERM. Inside a tokio runtime.
    pub(crate) fn watch(cancel: &Cancel) -> Stop {
        let status = Arc::new(AtomicU8::new(INTERRUPTED));
        let (cancel, seen) = (cancel.clone(), Arc::clone(&status));
        let watch = tokio::spawn(async move {
            if signalled().await == Signal::Term {
                seen.store(TERMINATED, Ordering::SeqCst);
            }
            cancel.cancel();
        });
        Stop { watch, status }
    }

    /// The exit status for a command the signal stopped.
    pub(crate) fn status(&self) -> u8 {
        self.status.load(Ordering::SeqCst)
    }
}

impl Drop for Stop {
    fn drop(&mut self) {
        self.watch.abort();
    }
}

#[derive(PartialEq, Eq)]
enum Signal {
    Int,
    Term,
}

/// Resolves with the first of Ctrl-C and SIGTERM.
async fn signalled() -> Signal {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{SignalKind, signal};
        if let Ok(mut term) = signal(SignalKind::terminate()) {
            return tokio::select! {
                _ = tokio::signal::ctrl_c() => Signal::Int,
                _ = term.recv() => Signal::Term,
            };
        }
    }
    let _ = tokio::signal::ctrl_c().await;
    Signal::Int
}
