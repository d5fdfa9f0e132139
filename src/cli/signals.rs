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
        // Installed now, not when the watching task first runs: a signal that came before
        // (a busy machine, a model call already under way) would end the process the
        // default way, with no transcript closed and no 130.
        let signals = Signals::install();
        let watch = tokio::spawn(async move {
            if signals.first().await == Signal::Term {
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

/// The handlers of Ctrl-C and SIGTERM, installed.
struct Signals {
    #[cfg(unix)]
    int: Option<tokio::signal::unix::Signal>,
    #[cfg(unix)]
    term: Option<tokio::signal::unix::Signal>,
}

impl Signals {
    fn install() -> Signals {
        #[cfg(unix)]
        {
            use tokio::signal::unix::{SignalKind, signal};
            Signals {
                int: signal(SignalKind::interrupt()).ok(),
                term: signal(SignalKind::terminate()).ok(),
            }
        }
        #[cfg(not(unix))]
        Signals {}
    }

    /// Resolves with the first of Ctrl-C and SIGTERM.
    async fn first(self) -> Signal {
        #[cfg(unix)]
        if let (Some(mut int), Some(mut term)) = (self.int, self.term) {
            return tokio::select! {
                _ = int.recv() => Signal::Int,
                _ = term.recv() => Signal::Term,
            };
        }
        let _ = tokio::signal::ctrl_c().await;
        Signal::Int
    }
}
