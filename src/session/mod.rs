//! The session layer: the one way through the engine that every front end takes.
//!
//! The `coherent` command (`crate::cli`) and the Python package (`coherent-py`) parse
//! their arguments into the session's types, call it, and print or convert what comes
//! back; everything between is here, written once:
//!
//! - [`episode`]: an episode as a front end asks for it ([`episode::RunRequest`],
//!   [`episode::ReplayRequest`]), prepared in one call, and the one episode runner under
//!   `run`, `replay` and `bench`, in a symbolic or physical environment or with robots
//!   over ROS 2;
//! - [`bench`](mod@bench): methods x tasks x seeds into a resumable results file, locally or
//!   through a worker of a distributed executor;
//! - [`backend`]: which backend answers, the model endpoint completed from the
//!   environment;
//! - [`robots`]: who carries the actions out, the reference robot servers over ROS 2;
//! - [`tasks`], [`prompts`]: where tasks, prompt sets and prices come from;
//! - [`check`]: validation findings (rules and geometry), optimal plans, import;
//! - [`generate`](mod@generate): generated task sets, written to a folder;
//! - [`pddl`](mod@pddl): the tasks in PDDL, our plans as PDDL plans, PDDL plans checked
//!   against the rules;
//! - [`render`]: the scene from above and the robots' paths;
//! - [`training`]: training data for the methods' models, from the optimal planner;
//! - [`lines`]: the line `coherent run` prints for each step;
//! - [`view`]: episodes and results as pages in the browser;
//! - [`error`]: what goes wrong, by kind;
//! - [`engine`]: the types of the crates below that front ends use on purpose
//!   (`docs/architecture.md`, "What the session re-exports").
//!
//! [`runtime`] is the one place an async runtime is built.

pub mod backend;
pub mod bench;
pub mod check;
pub mod engine;
pub mod episode;
pub mod error;
pub mod events;
pub mod generate;
pub mod lines;
pub mod pddl;
pub mod prompts;
pub mod render;
pub mod robots;
pub mod tasks;
pub mod training;
pub mod view;
pub mod waiting;

use std::future::Future;
use std::sync::OnceLock;

pub use error::{Error, Result};

/// Runs `future` to completion on the session's runtime, from a thread outside it.
pub fn block_on<F: Future>(future: F) -> Result<F::Output> {
    Ok(runtime()?.block_on(future))
}

/// The runtime of the engine's async work (model calls, timers, concurrent episodes, the
/// robots' DDS traffic), built once per process on first use: the one place a runtime
/// is built. Multi-threaded, so that a benchmark's episodes use every core.
///
/// Building it takes file descriptors (epoll, an eventfd, a socket pair and its copy for
/// signals) and threads; when the process may have no more (`ulimit -n`, `ulimit -u`),
/// the error says which part failed and the OS's words, and every later call gets it too.
pub fn runtime() -> Result<&'static tokio::runtime::Runtime> {
    static RUNTIME: OnceLock<Result<tokio::runtime::Runtime>> = OnceLock::new();
    RUNTIME
        .get_or_init(build_runtime)
        .as_ref()
        // Each caller gets the error of the one build, as its own value.
        .map_err(|e| Error::Internal(e.to_string()))
}

/// Builds the runtime, with tokio's panics as errors: tokio returns most failures, but
/// panics on some (the signal driver's socket pair, "failed to create UnixStream"; a
/// worker thread the OS will not start), and a panic must not be what a user sees.
fn build_runtime() -> Result<tokio::runtime::Runtime> {
    // The default hook would print the panic (and a backtrace) before the error that
    // explains it; silenced for the build only, which happens once per process.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let built = std::panic::catch_unwind(|| {
        tokio::runtime::Builder::new_multi_thread()
            .thread_name("coherent")
            .enable_all()
            .build()
    });
    std::panic::set_hook(hook);
    let why = match built {
        Ok(Ok(runtime)) => return Ok(runtime),
        Ok(Err(e)) => e.to_string(),
        Err(panic) => error::panic_message(panic.as_ref()),
    };
    Err(Error::Internal(format!(
        "cannot start the async runtime: {why}"
    )))
}
