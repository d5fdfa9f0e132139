//! The benchmark harness: methods x tasks x seeds, run concurrently, one JSON line per
//! finished episode appended to a results file (flushed as each ends), resumable after a
//! crash or Ctrl-C. [`crate::harness::report`] turns the lines into the paper's tables.
//!
//! [`run`] is the local executor: every episode on this machine's tokio runtime. The
//! parts it is made of serve other executors too: the [`Ledger`] is the driver's side
//! (the results file, the episodes still to run, each result written once), and
//! [`run_one`] runs one episode by its key, as a worker of a distributed executor does.
//!
//! The harness's other parts are reachable here too, as one namespace:
//! [`crate::harness::subset`] (which tasks), [`crate::harness::results`] (the results
//! file), [`crate::harness::progress`] (what a run reports), [`crate::harness::choice`]
//! (which backend), [`crate::harness::job`] (one episode) and
//! [`crate::harness::ledger`] (the driver's side).

use std::path::PathBuf;
use std::sync::Arc;

use coherent_core::Task;
use tokio::sync::Semaphore;
use tokio::task::JoinSet;

use crate::episode::cancel::Cancel;

pub use crate::harness::choice::{BackendChoice, Recorded};
pub use crate::harness::job::{EpisodeResult, EpisodeSettings, RunTasks, episode_seed, run_one};
pub use crate::harness::ledger::{BenchOutcome, Ledger};
pub use crate::harness::progress::{Event, Progress};
pub use crate::harness::results::DEFAULT_MAX_BYTES as DEFAULT_MAX_RESULTS_BYTES;
pub use crate::harness::results::{
    EpisodeKey, ReadLimits, ResultLine, ResultsFile, mark_orphans, read_results,
    read_results_within, repair, transcripts_dir,
};
pub use crate::harness::subset::{PAPER40, Selection, Subset, select};

/// What to run: the episodes (methods, backend, settings), how many seeds, how many at
/// once, and where the results go.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    /// The methods and what every episode shares.
    pub episodes: EpisodeSettings,
    /// Seed indices `0..seeds`.
    pub seeds: u32,
    /// Episodes at once.
    pub concurrency: usize,
    /// The results file; transcripts go to [`transcripts_dir`] of it.
    pub out: PathBuf,
    /// The most the results file may hold when read back to resume.
    pub max_results_bytes: u64,
}

/// Runs every method on every task for every seed, `config.concurrency` at once, skipping
/// those already finished in `config.out`, appending one flushed line per episode.
/// `cancel` stops the run: episodes in flight end as interrupted (and are written so),
/// those not started are not started.
pub async fn run(
    tasks: &[Arc<Task>],
    config: &BenchConfig,
    cancel: &Cancel,
    progress: &mut (dyn FnMut(Event<'_>) + Send),
) -> Result<BenchOutcome, String> {
    let tasks = Arc::new(RunTasks::new(tasks)?);
    let mut ledger = Ledger::open(&config.out, config.max_results_bytes)?;
    let keys = ledger.plan(&tasks, &config.episodes.methods, config.seeds);
    progress(Event::Start {
        to_run: keys.len(),
        skipped: ledger.outcome().skipped,
    });
    let settings = Arc::new(config.episodes.clone());
    let transcripts = Arc::new(transcripts_dir(&config.out));
    let permits = Arc::new(Semaphore::new(config.concurrency.max(1)));
    let mut set = JoinSet::new();
    for key in keys {
        let (tasks, settings) = (Arc::clone(&tasks), Arc::clone(&settings));
        let transcripts = Arc::clone(&transcripts);
        let (permits, cancel) = (Arc::clone(&permits), cancel.clone());
        set.spawn(async move {
            let _permit = tokio::select! {
                p = permits.acquire() => p.map_err(|e| e.to_string())?,
                () = cancel.cancelled() => return Ok(EpisodeResult::NotStarted),
            };
            run_one(&tasks, &key, &settings, &transcripts, &cancel).await
        });
    }
    let mut first_error = None;
    while let Some(joined) = set.join_next().await {
        let result = joined.map_err(|e| format!("an episode panicked: {e}"));
        // A transcript or a line that cannot be written would lose data: stop everything.
        match result.and_then(|r| r).and_then(|r| ledger.record(r)) {
            Ok(Some(line)) => progress(Event::Finished(&line)),
            Ok(None) => {}
            Err(e) => {
                first_error.get_or_insert(e);
                cancel.cancel();
            }
        }
    }
    let outcome = ledger.finish(cancel.is_cancelled() && first_error.is_none());
    match first_error {
        Some(e) => Err(e),
        None => Ok(outcome),
    }
}
