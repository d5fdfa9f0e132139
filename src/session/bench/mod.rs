//! Benchmarks: the tasks a subset picks, methods x tasks x seeds run concurrently into a
//! resumable results file, and the paper's tables of it.
//!
//! A front end fills an [`EpisodesRequest`] (what every episode shares) and prepares it
//! into [`EpisodeSettings`]. Two executors run the episodes: [`run`], every episode on
//! this machine, and a distributed one (`coherent.bench(..., executor="ray")`), whose
//! driver keeps the results file (`coherent_agents::bench::Ledger`) and whose workers
//! each run episodes through a [`Worker`]. Both run each episode with
//! [`episode::run_one`], through the session's one episode runner, so that they write
//! the same lines.

pub mod episode;
pub mod settings;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::Cancel;
use coherent_agents::bench::{
    self, BenchOutcome, EpisodeKey, EpisodeResult, Event, Ledger, ResultLine, Selection, Subset,
};
use coherent_agents::report::{self, Report};
use coherent_core::Task;
use tokio::sync::Semaphore;
use tokio::task::JoinSet;

pub use episode::{RunTasks, episode_seed, run_one};
pub use settings::{EpisodeSettings, EpisodesRequest, distinct_names};

use crate::session::error::Error;
use crate::session::robots::Robots;

/// A subset by name (`all`, `paper40`, `native40`), else a file of `scene task_id` lines.
pub fn subset(name_or_file: &str) -> Result<Subset, Error> {
    match Subset::named(name_or_file) {
        Some(named) => Ok(named),
        None => subset_file(Path::new(name_or_file)),
    }
}

/// The subset a file of `scene task_id` lines lists.
pub fn subset_file(path: &Path) -> Result<Subset, Error> {
    Ok(Subset::read_file(path)?)
}

/// The tasks a subset picks from the tasks at a path, and the malformed tasks left out.
#[derive(Debug)]
pub struct Chosen {
    pub selection: Selection,
    pub malformed: Vec<coherent_core::Error>,
}

/// The tasks `subset` picks from every well-formed task at `path`.
pub fn choose(path: &Path, subset: &Subset) -> Result<Chosen, Error> {
    let mut tasks = Vec::new();
    let mut malformed = Vec::new();
    for r in super::tasks::read_tasks(path)? {
        match r {
            Ok(t) => tasks.push(t),
            Err(e) => malformed.push(e),
        }
    }
    Ok(Chosen {
        selection: bench::select(tasks, subset)?,
        malformed,
    })
}

/// What to run: the episodes' settings, how many seeds, how many at once, and where the
/// results go.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    pub episodes: EpisodeSettings,
    /// Seed indices `0..seeds`.
    pub seeds: u32,
    /// Episodes at once (robots over ROS 2 take one at a time: [`BenchConfig::at_once`]).
    pub concurrency: usize,
    /// The results file; transcripts go to [`bench::transcripts_dir`] of it.
    pub out: PathBuf,
}

impl BenchConfig {
    /// Episodes at once: `concurrency`, but one at a time with robots over ROS 2 (the
    /// robots of a namespace carry out one episode's actions).
    pub fn at_once(&self) -> usize {
        match self.episodes.robots {
            Robots::Local => self.concurrency.max(1),
            Robots::Ros2(_) => 1,
        }
    }

    /// What to tell the user when the run takes fewer episodes at once than asked.
    pub fn concurrency_note(&self) -> Option<String> {
        (self.at_once() < self.concurrency).then(|| {
            format!(
                "robots over ROS 2 carry out one episode at a time (the robots of a \
                 namespace serve one episode): concurrency {} is not used",
                self.concurrency
            )
        })
    }
}

/// Runs the benchmark `config` on `tasks`: every method on every task for every seed,
/// [`BenchConfig::at_once`] at a time, skipping the episodes already finished in the
/// results file, appending one flushed line per episode. `cancel` stops it: episodes in
/// flight end as interrupted (and are written so), those not started are not started.
pub async fn run(
    tasks: &[Arc<Task>],
    config: &BenchConfig,
    cancel: &Cancel,
    progress: &mut (dyn FnMut(Event<'_>) + Send),
) -> Result<BenchOutcome, Error> {
    if tasks.is_empty() {
        return Err(Error::Invalid("no tasks to run".into()));
    }
    if config.seeds == 0 {
        return Err(Error::Invalid("seeds must be at least 1".into()));
    }
    let run_tasks = Arc::new(RunTasks::new(tasks)?);
    let mut ledger = Ledger::open(&config.out)?;
    let episodes = &config.episodes;
    let keys = ledger.plan(tasks, &episodes.methods, &episodes.executions, config.seeds);
    progress(Event::Start {
        to_run: keys.len(),
        skipped: ledger.outcome().skipped,
    });
    let settings = Arc::new(config.episodes.clone());
    let transcripts = Arc::new(bench::transcripts_dir(&config.out));
    let permits = Arc::new(Semaphore::new(config.at_once()));
    let mut set = JoinSet::new();
    for key in keys {
        let (tasks, settings) = (Arc::clone(&run_tasks), Arc::clone(&settings));
        let transcripts = Arc::clone(&transcripts);
        let (permits, cancel) = (Arc::clone(&permits), cancel.clone());
        set.spawn(async move {
            let _permit = tokio::select! {
                p = permits.acquire() => p.map_err(|e| Error::Internal(e.to_string()))?,
                () = cancel.cancelled() => return Ok(EpisodeResult::NotStarted),
            };
            run_one(&tasks, &key, &settings, &transcripts, &cancel).await
        });
    }
    let mut first_error = None;
    while let Some(joined) = set.join_next().await {
        let result = joined.map_err(|e| Error::Internal(format!("an episode panicked: {e}")));
        // A transcript or a line that cannot be written would lose data: stop everything.
        match result
            .and_then(|r| r)
            .and_then(|r| ledger.record(r).map_err(Error::from))
        {
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

/// Runs benchmark episodes one at a time by their key (method, scene, task id, seed
/// index) with the settings every episode of the run shares, each writing its
/// transcript and giving its results line: what a worker of a distributed executor
/// runs. Its episodes share the session's runtime, so that an endpoint's client keeps
/// its connections; several threads may run episodes at once.
#[derive(Debug)]
pub struct Worker {
    tasks: RunTasks,
    settings: EpisodeSettings,
    transcripts: PathBuf,
}

impl Worker {
    /// A worker for the episodes of `tasks`, writing their transcripts where those of
    /// the results file `out` go (`coherent_agents::bench::transcripts_dir`). Robots over
    /// ROS 2 are for the local executor: workers on several machines would share them.
    pub fn new(
        tasks: &[Arc<Task>],
        settings: EpisodeSettings,
        out: &Path,
    ) -> Result<Worker, Error> {
        if let Robots::Ros2(_) = settings.robots {
            return Err(Error::Invalid(
                "robots over ROS 2 carry out one episode at a time from one machine: run \
                 the benchmark with the local executor"
                    .into(),
            ));
        }
        Ok(Worker {
            tasks: RunTasks::new(tasks)?,
            settings,
            transcripts: bench::transcripts_dir(out),
        })
    }

    /// Runs the episode `key` to its end on the calling thread; `cancel` ends it as
    /// interrupted.
    pub fn run(&self, key: &EpisodeKey, cancel: &Cancel) -> Result<EpisodeResult, Error> {
        super::block_on(run_one(
            &self.tasks,
            key,
            &self.settings,
            &self.transcripts,
            cancel,
        ))?
    }
}

/// How the tables are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableFormat {
    Markdown,
    Csv,
    Json,
}

impl TableFormat {
    pub fn from_name(name: &str) -> Option<TableFormat> {
        match name {
            "markdown" => Some(TableFormat::Markdown),
            "csv" => Some(TableFormat::Csv),
            "json" => Some(TableFormat::Json),
            _ => None,
        }
    }
}

/// The paper's tables of results lines: Table I by task type, Table II by scene, the
/// costs.
pub fn report(lines: &[ResultLine]) -> Report {
    report::build(lines)
}

/// The paper's tables ([`report`]) as text.
pub fn tables(lines: &[ResultLine], format: TableFormat) -> String {
    let r = report(lines);
    match format {
        TableFormat::Markdown => report::markdown(&r),
        TableFormat::Csv => report::csv(&r),
        TableFormat::Json => report::json(&r),
    }
}
