//! The model calls in flight, so that a front end can show a sign of life while a model
//! is slow ("waiting 12 s for the assigner"): [`Waiting::watch`] wraps an episode's
//! backend and keeps each of its calls here from its start to its answer.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use coherent_agents::llm::Role;
use coherent_agents::llm::{Answer, Backend, BackendInfo, BoxFuture, LlmError, Query, Response};
use coherent_core::NodeId;

/// How long a call runs before the front ends say they are waiting for it.
pub const SLOW: Duration = Duration::from_secs(5);

/// A call in flight: since when, and for whom (the role, and the executor's robot).
type Call = (Instant, Role, Option<NodeId>);

/// The calls in flight of the backends it watches.
#[derive(Debug, Default)]
pub struct Waiting {
    calls: Mutex<HashMap<u64, Call>>,
    next: AtomicU64,
}

/// The call waited for longest: for how long, whom, and how many are in flight.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Longest {
    pub waited: Duration,
    /// `the assigner`, `the executor of robot 13`.
    pub whom: String,
    pub in_flight: usize,
}

impl Waiting {
    /// `backend`, its calls kept here while they run.
    pub fn watch(self: &Arc<Self>, backend: Arc<dyn Backend>) -> Arc<dyn Backend> {
        Arc::new(Watched {
            inner: backend,
            waiting: Arc::clone(self),
        })
    }

    /// The call in flight for the longest time, if any.
    pub fn longest(&self) -> Option<Longest> {
        let calls = self.calls.lock().unwrap_or_else(PoisonError::into_inner);
        let (start, role, robot) = calls.values().min_by_key(|(start, ..)| *start)?;
        Some(Longest {
            waited: start.elapsed(),
            whom: match (role, robot) {
                (Role::Assigner, _) => "the assigner".to_owned(),
                (Role::Executor, Some(robot)) => format!("the executor of robot {}", robot.0),
                (Role::Executor, None) => "an executor".to_owned(),
            },
            in_flight: calls.len(),
        })
    }

    /// Keeps the call of `query` until the returned guard drops.
    fn start(self: &Arc<Self>, query: &Query) -> Guard {
        let id = self.next.fetch_add(1, Ordering::Relaxed);
        self.calls
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .insert(id, (Instant::now(), query.role, query.robot));
        Guard {
            waiting: Arc::clone(self),
            id,
        }
    }
}

/// Removes its call when dropped: answered, failed or cancelled.
struct Guard {
    waiting: Arc<Waiting>,
    id: u64,
}

impl Drop for Guard {
    fn drop(&mut self) {
        self.waiting
            .calls
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .remove(&self.id);
    }
}

/// A backend whose calls [`Waiting`] keeps while they run.
struct Watched {
    inner: Arc<dyn Backend>,
    waiting: Arc<Waiting>,
}

impl Backend for Watched {
    fn info(&self) -> BackendInfo {
        self.inner.info()
    }

    fn ask(&self, query: Query) -> BoxFuture<'_, Result<Answer, LlmError>> {
        Box::pin(async move {
            let _call = self.waiting.start(&query);
            self.inner.ask(query).await
        })
    }

    fn respond(&self, query: Query) -> BoxFuture<'_, Response> {
        Box::pin(async move {
            let _call = self.waiting.start(&query);
            self.inner.respond(query).await
        })
    }
}

/// `waiting 12s for the assigner` (and how many calls are in flight when more than one).
pub fn waiting_text(longest: &Longest) -> String {
    let others = match longest.in_flight {
        0 | 1 => String::new(),
        n => format!(" ({n} model calls in flight)"),
    };
    format!(
        "waiting {}s for {}{others}",
        longest.waited.as_secs(),
        longest.whom
    )
}
