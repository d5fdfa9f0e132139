//! The thread on which a method written in Python is made and asked for its steps, one
//! per episode. The episode waits for each answer without being inside the call, so that
//! Ctrl-C and the step's time limit (`--step-timeout`, `step_timeout=`) end the wait
//! whatever the method does; a call the episode no longer waits for is interrupted by
//! `coherent._methods.StepStopped`, raised in it (a call blocked in C code, a long
//! `time.sleep` say, ends only when that returns, and only its thread waits for it).
//! One thread all episode long, as a method run on the episode's own thread had.

use std::sync::mpsc;
use std::sync::{Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use pyo3::prelude::*;
use tokio::sync::oneshot;

/// A job for the thread, run with the GIL held.
type Job = Box<dyn FnOnce(Python<'_>) + Send>;

/// One episode's thread for its method's calls; it ends when the stepper is dropped
/// (once the call it is in, if any, returns).
pub(crate) struct Stepper {
    jobs: mpsc::Sender<Job>,
    /// Python's id of the thread (`threading.get_ident()`), to interrupt it.
    ident: u64,
}

impl Stepper {
    /// A thread of its own, kept in `threads`.
    pub(crate) fn start(threads: &Threads) -> Result<Stepper, String> {
        let (jobs, queue) = mpsc::channel::<Job>();
        let (tell, told) = mpsc::channel();
        let handle = std::thread::Builder::new()
            .name("coherent-method".into())
            .spawn(move || {
                let ident = Python::attach(|py| -> PyResult<u64> {
                    py.import("threading")?.call_method0("get_ident")?.extract()
                });
                let _ = tell.send(ident.map_err(|e| e.to_string()));
                while let Ok(job) = queue.recv() {
                    Python::attach(job);
                }
            })
            .map_err(|e| format!("cannot start the method's thread: {e}"))?;
        threads.add(handle);
        let ident = told
            .recv()
            .map_err(|_| "the method's thread ended at once".to_owned())??;
        Ok(Stepper { jobs, ident })
    }

    /// Runs `job` on the thread and waits for its answer; `None` when the thread is gone.
    /// Dropped before the answer comes (the episode cancelled, or out of time), the
    /// wait interrupts the job.
    pub(crate) async fn run<T: Send + 'static>(
        &self,
        job: impl FnOnce(Python<'_>) -> T + Send + 'static,
    ) -> Option<T> {
        let (answer, answered) = oneshot::channel();
        let job: Job = Box::new(move |py| {
            let _ = answer.send(job(py));
        });
        self.jobs.send(job).ok()?;
        let mut waiting = Interrupt(Some(self.ident));
        let got = answered.await.ok();
        waiting.0 = None;
        got
    }
}

/// A method's threads, so that the end of a run can let those finishing a stopped call
/// end before the interpreter might shut down under them.
#[derive(Default)]
pub(crate) struct Threads(Mutex<Vec<JoinHandle<()>>>);

impl Threads {
    fn add(&self, handle: JoinHandle<()>) {
        let mut threads = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        threads.retain(|t| !t.is_finished());
        threads.push(handle);
    }

    /// Waits until `deadline` for the threads to end (an interrupted call ends at its
    /// next bytecode; one blocked in C code may not), then lets the rest go on alone.
    pub(crate) fn settle(&self, deadline: Instant) {
        let mut threads =
            std::mem::take(&mut *self.0.lock().unwrap_or_else(PoisonError::into_inner));
        while threads.iter().any(|t| !t.is_finished()) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
        }
        for t in threads.drain(..).filter(|t| t.is_finished()) {
            let _ = t.join();
        }
    }
}

/// Interrupts the thread `.0` when dropped while still set.
struct Interrupt(Option<u64>);

impl Drop for Interrupt {
    fn drop(&mut self) {
        if let Some(ident) = self.0.take() {
            // From a thread of its own: the GIL may be slow to come while the call runs,
            // and whoever dropped the wait must not wait for it.
            let _ = std::thread::Builder::new()
                .name("coherent-interrupt".into())
                .spawn(move || {
                    Python::attach(|py| {
                        let helpers = py.import("coherent._methods");
                        let _ = helpers.and_then(|h| h.call_method1("interrupt", (ident,)));
                    });
                });
        }
    }
}
