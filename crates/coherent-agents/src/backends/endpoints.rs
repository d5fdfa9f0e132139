//! Several endpoints serving one model (vLLM, llama.cpp or Ollama replicas): each request
//! goes to the endpoint with the fewest requests in flight; one that fails (no
//! connection, a timeout, 408, 429 or 5xx) rests, with backoff, while the others carry
//! on, and comes back after its rest. With one endpoint this is that endpoint, always.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};

use crate::backends::address::Address;
use crate::backends::retry::Backoff;

/// The endpoints of a client and how busy and healthy each is.
#[derive(Debug)]
pub(crate) struct Endpoints {
    targets: Vec<Address>,
    loads: Mutex<Vec<Load>>,
    /// Where the search for the least busy endpoint starts, moved on at each pick, so
    /// that endpoints equally busy take turns.
    turn: AtomicUsize,
    backoff: Backoff,
}

#[derive(Debug, Default)]
struct Load {
    in_flight: usize,
    /// Failures in a row; 0 once it answers.
    failures: u32,
    /// Resting until then after a failure.
    rest_until: Option<Instant>,
}

impl Load {
    /// Whether it may take a request at `now`: awake, and, after a failure, only one
    /// request at a time until it answers again.
    fn ready(&self, now: Instant) -> bool {
        self.rest_until.is_none_or(|t| t <= now) && (self.failures == 0 || self.in_flight == 0)
    }
}

/// One request's hold on an endpoint: counted in flight until dropped.
#[derive(Debug)]
pub(crate) struct Lease<'a> {
    pool: &'a Endpoints,
    index: usize,
}

impl Endpoints {
    /// The endpoints of `targets`, at least one.
    pub(crate) fn new(targets: Vec<Address>, backoff: Backoff) -> Endpoints {
        let loads = targets.iter().map(|_| Load::default()).collect();
        Endpoints {
            targets,
            loads: Mutex::new(loads),
            turn: AtomicUsize::new(0),
            backoff,
        }
    }

    /// Every base URL, as transcripts record them.
    pub(crate) fn shown(&self) -> Vec<&str> {
        self.targets.iter().map(|t| t.shown.as_str()).collect()
    }

    fn loads(&self) -> MutexGuard<'_, Vec<Load>> {
        self.loads.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The endpoint for the next request: of those ready, the one with the fewest
    /// requests in flight; when none is ready, the one whose rest ends first.
    pub(crate) fn pick(&self) -> Lease<'_> {
        let now = Instant::now();
        let mut loads = self.loads();
        let n = loads.len();
        let start = self.turn.fetch_add(1, Ordering::Relaxed) % n;
        let order = (0..n).map(|k| (start + k) % n);
        let index = order
            .clone()
            .filter(|&i| loads[i].ready(now))
            .min_by_key(|&i| loads[i].in_flight)
            .or_else(|| order.min_by_key(|&i| (loads[i].rest_until, loads[i].in_flight)))
            .unwrap_or(0);
        loads[index].in_flight += 1;
        Lease { pool: self, index }
    }
}

impl Lease<'_> {
    /// The endpoint's address: where to post, and whether its URL carries credentials.
    pub(crate) fn address(&self) -> &Address {
        &self.pool.targets[self.index]
    }

    /// The base URL, as the transcript records it.
    pub(crate) fn shown(&self) -> &str {
        &self.pool.targets[self.index].shown
    }

    /// It answered: healthy again.
    pub(crate) fn answered(&self) {
        let mut loads = self.pool.loads();
        loads[self.index].failures = 0;
        loads[self.index].rest_until = None;
    }

    /// It failed: it rests for the backoff's ceiling after as many failures in a row
    /// (or `retry_after`, when the server said), from now.
    pub(crate) fn failed(&self, retry_after: Option<Duration>) {
        let mut loads = self.pool.loads();
        let load = &mut loads[self.index];
        let rest = self.pool.backoff.pause(load.failures, retry_after, 1.0);
        load.failures = load.failures.saturating_add(1);
        load.rest_until = Some(Instant::now() + rest);
    }

    /// Whether another endpoint could take a request right now, so that a retry need not
    /// wait for this one.
    pub(crate) fn another_ready(&self) -> bool {
        let now = Instant::now();
        let loads = self.pool.loads();
        (0..loads.len()).any(|i| i != self.index && loads[i].ready(now))
    }
}

impl Drop for Lease<'_> {
    fn drop(&mut self) {
        let mut loads = self.pool.loads();
        loads[self.index].in_flight = loads[self.index].in_flight.saturating_sub(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pool(n: usize) -> Endpoints {
        let targets = (0..n)
            .map(|i| Address::parse(&format!("http://e{i}/v1")).expect("a URL"))
            .collect();
        Endpoints::new(
            targets,
            Backoff {
                max_retries: 2,
                base: Duration::from_millis(200),
                cap: Duration::from_secs(10),
            },
        )
    }

    #[test]
    fn the_least_busy_endpoint_takes_the_next_request_and_ties_take_turns() {
        let p = pool(3);
        let a = p.pick();
        let b = p.pick();
        let c = p.pick();
        let mut first: Vec<&str> = vec![a.shown(), b.shown(), c.shown()];
        first.sort_unstable();
        assert_eq!(first, ["http://e0/v1", "http://e1/v1", "http://e2/v1"]);
        let busy = b.shown().to_owned();
        drop(a);
        drop(c);
        // Two are idle, one busy: the next two go to the idle ones.
        let d = p.pick();
        let e = p.pick();
        assert_ne!(d.shown(), busy);
        assert_ne!(e.shown(), busy);
        assert_ne!(d.shown(), e.shown());
    }

    #[test]
    fn a_failed_endpoint_rests_then_comes_back_one_request_at_a_time() {
        let p = pool(2);
        let first = p.pick();
        let failed = first.shown().to_owned();
        first.failed(None);
        assert!(first.another_ready());
        drop(first);
        // Resting: every request goes to the other one, however busy it gets.
        let held: Vec<Lease<'_>> = (0..4).map(|_| p.pick()).collect();
        assert!(held.iter().all(|l| l.shown() != failed));
        // After its rest, one request probes it; a second waits for its answer.
        std::thread::sleep(Duration::from_millis(220));
        let probe = p.pick();
        assert_eq!(probe.shown(), failed);
        assert_ne!(p.pick().shown(), failed);
        probe.answered();
        drop(probe);
        drop(held);
        // Healthy again: it takes its share.
        let (x, y) = (p.pick(), p.pick());
        assert_ne!(x.shown(), y.shown());
    }

    #[test]
    fn rests_grow_with_failures_in_a_row_and_when_all_rest_the_first_to_wake_is_used() {
        let p = pool(2);
        let a = p.pick();
        let b = p.pick();
        let (name_a, name_b) = (a.shown().to_owned(), b.shown().to_owned());
        a.failed(None);
        a.failed(None);
        b.failed(None);
        drop((a, b));
        // a rests 400 ms from its second failure, b 200 ms from its first: b wakes first.
        assert_eq!(p.pick().shown(), name_b);
        let loads = p.loads();
        let index = |name: &str| usize::from(name != "http://e0/v1");
        assert_eq!(loads[index(&name_a)].failures, 2);
        assert!(loads[index(&name_a)].rest_until > loads[index(&name_b)].rest_until);
    }

    #[test]
    fn one_endpoint_is_always_picked() {
        let p = pool(1);
        let a = p.pick();
        a.failed(Some(Duration::from_secs(5)));
        assert!(!a.another_ready());
        assert_eq!(p.pick().shown(), "http://e0/v1");
    }
}
