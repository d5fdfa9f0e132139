//! Benchmarks: the tasks a subset picks, methods x tasks x seeds run concurrently into a
//! resumable results file (`coherent_agents::bench`), and the paper's tables of it.
//!
//! Two executors run the episodes: [`run`], every episode on this machine, and a
//! distributed one (`coherent.bench(..., executor="ray")`), whose driver keeps the
//! results file (`coherent_agents::bench::Ledger`) and whose workers each run episodes
//! through a [`Worker`]. Both run each episode with `coherent_agents::bench::run_one`,
//! so that they write the same lines.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::bench::{
    self, BenchConfig, BenchOutcome, EpisodeKey, EpisodeResult, EpisodeSettings, Event, ResultLine,
    RunTasks, Selection, Subset,
};
use coherent_agents::{Cancel, MethodSpec, report};
use coherent_core::{Error, Task};

/// A subset by name (`all`, `paper40`, `native40`), else a file of `scene task_id` lines.
pub fn subset(name_or_file: &str) -> Result<Subset, String> {
    match Subset::named(name_or_file) {
        Some(named) => Ok(named),
        None => Subset::read_file(Path::new(name_or_file)),
    }
}

/// The tasks a subset picks from the tasks at a path, and the malformed tasks left out.
#[derive(Debug)]
pub struct Chosen {
    pub selection: Selection,
    pub malformed: Vec<Error>,
}

/// The tasks `subset` picks from every well-formed task at `path`.
pub fn choose(path: &Path, subset: &Subset) -> Result<Chosen, String> {
    let mut tasks = Vec::new();
    let mut malformed = Vec::new();
    for r in super::tasks::read_tasks(path).map_err(|e| e.to_string())? {
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

/// Runs the benchmark `config` on `tasks`: every method on every task for every seed,
/// skipping the episodes already finished in the results file, appending one line per
/// episode. `cancel` stops it (episodes in flight end as interrupted).
pub async fn run(
    tasks: &[Arc<Task>],
    config: &BenchConfig,
    cancel: &Cancel,
    progress: &mut (dyn FnMut(Event<'_>) + Send),
) -> Result<BenchOutcome, String> {
    if tasks.is_empty() {
        return Err("no tasks to run".into());
    }
    if config.episodes.methods.is_empty() {
        return Err("no methods to run".into());
    }
    distinct_names(&config.episodes.methods)?;
    if config.seeds == 0 {
        return Err("seeds must be at least 1".into());
    }
    bench::run(tasks, config, cancel, progress).await
}

/// Refuses two methods of one name: results are keyed by the method's name, so one
/// written outside the crate needs its own.
pub fn distinct_names(methods: &[MethodSpec]) -> Result<(), String> {
    let names: Vec<&str> = methods.iter().map(|m| m.name()).collect();
    match methods
        .iter()
        .find(|m| m.builtin().is_none() && names.iter().filter(|&&n| n == m.name()).count() > 1)
    {
        Some(m) => Err(format!(
            "two methods are named {:?}: give each its own name",
            m.name()
        )),
        None => Ok(()),
    }
}

/// Runs benchmark episodes one at a time by their key (method, scene, task id, seed
/// index) with the settings every episode of the run shares, each writing its
/// transcript and giving its results line: what a worker of a distributed executor
/// runs. It keeps one runtime for all its episodes, so that an endpoint's client keeps
/// its connections; several threads may run episodes at once.
#[derive(Debug)]
pub struct Worker {
    runtime: tokio::runtime::Runtime,
    tasks: RunTasks,
    settings: EpisodeSettings,
    transcripts: PathBuf,
}

impl Worker {
    /// A worker for the episodes of `tasks`, writing their transcripts where those of
    /// the results file `out` go (`coherent_agents::bench::transcripts_dir`).
    pub fn new(
        tasks: &[Arc<Task>],
        settings: EpisodeSettings,
        out: &Path,
    ) -> Result<Worker, String> {
        Ok(Worker {
            runtime: super::runtime()?,
            tasks: RunTasks::new(tasks)?,
            settings,
            transcripts: bench::transcripts_dir(out),
        })
    }

    /// Runs the episode `key` to its end on the calling thread; `cancel` ends it as
    /// interrupted.
    pub fn run(&self, key: &EpisodeKey, cancel: &Cancel) -> Result<EpisodeResult, String> {
        self.runtime.block_on(bench::run_one(
            &self.tasks,
            key,
            &self.settings,
            &self.transcripts,
            cancel,
        ))
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

/// The paper's tables (Table I by task type, Table II by scene, the costs) of results
/// lines, as text.
pub fn tables(lines: &[ResultLine], format: TableFormat) -> String {
    let r = report::build(lines);
    match format {
        TableFormat::Markdown => report::markdown(&r),
        TableFormat::Csv => report::csv(&r),
        TableFormat::Json => report::json(&r),
    }
}
