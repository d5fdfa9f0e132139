//! The session layer: the one way through the engine that every front end takes.
//!
//! The `coherent` command (`crate::cli`) and the Python package (`coherent-py`) parse
//! their arguments and print or convert results; everything between — resolving the
//! model endpoint, choosing the backend, reading tasks, building the environment, running,
//! replaying and benchmarking episodes, validating and planning, drawing a scene — is
//! here, written once:
//!
//! - [`endpoint`]: the model endpoint from explicit settings and the environment;
//! - [`backend`]: which backend answers the model's roles (built-in, simulated,
//!   OpenAI-compatible, replay), with the rules that tie the settings together;
//! - [`tasks`]: reading task files, the compiled-in benchmark, picking one task;
//! - [`episode`]: one episode, run or replayed, in a symbolic or physical environment or
//!   with robots over ROS 2;
//! - [`prompts`]: the prompt set and the price table a run is given, checked up front;
//! - [`bench`]: methods x tasks x seeds into a resumable results file;
//! - [`check`]: validation findings (rules and geometry), optimal plans, import;
//! - [`render`]: the scene from above and the robots' paths;
//! - [`lines`]: the line `coherent run` prints for each step;
//! - [`view`]: episodes and results as pages in the browser.

pub mod backend;
pub mod bench;
pub mod check;
pub mod endpoint;
pub mod episode;
pub mod lines;
pub mod prompts;
pub mod render;
pub mod tasks;
pub mod view;

use std::future::Future;

/// Runs `future` to completion on a runtime made for it.
pub fn block_on<F: Future>(future: F) -> Result<F::Output, String> {
    Ok(runtime()?.block_on(future))
}

/// The one place the engine's async work (model calls, timers, concurrent episodes)
/// gets a runtime. Multi-threaded, so that a benchmark's episodes use every core.
pub fn runtime() -> Result<tokio::runtime::Runtime, String> {
    tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the async runtime: {e}"))
}
