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

use coherent_agents::bench::{
    self, BenchOutcome, EpisodeKey, EpisodeResult, Event, Ledger, ReadLimits, ResultLine,
    Selection, Subset,
};
use coherent_agents::report::{self, Mixed, Report};
use coherent_agents::{Cancel, MethodSpec};
use coherent_core::Task;
use tokio::sync::Semaphore;
use tokio::task::JoinSet;

pub use episode::{RunTasks, episode_seed, run_one};
pub use settings::{EpisodeSettings, EpisodesRequest, distinct_names};

use crate::session::backend::RecordedRun;
use crate::session::error::Error;
use crate::session::prompts::PriceSource;
use crate::session::robots::Robots;
use crate::session::waiting::{SLOW, Waiting, waiting_text};

/// A subset by name (`all`, `paper40`, `native40`), else a file of `scene task_id` lines;
/// a name that is neither says which names there are.
pub fn subset(name_or_file: &str) -> Result<Subset, Error> {
    if let Some(named) = Subset::named(name_or_file) {
        return Ok(named);
    }
    let path = Path::new(name_or_file);
    if !path.exists() {
        return Err(Error::Invalid(format!(
            "subset {name_or_file:?}: no subset of that name ({}) and no file of that name \
             (a file lists `scene task_id` lines)",
            Subset::NAMES.join(", ")
        )));
    }
    subset_file(path)
}

/// The subset a file of `scene task_id` lines lists.
pub fn subset_file(path: &Path) -> Result<Subset, Error> {
    Ok(Subset::read_file(path)?)
}

/// The method `name` of the earlier results file `results`, as its replay runs it: the
/// recorded one, so that a method written in Python replays by its name, without its
/// code. An error names the methods the file has when it has none of that name. The
/// results file and the transcript are read within `limits`.
pub fn recorded_method(
    results: &Path,
    name: &str,
    limits: ReadLimits,
) -> Result<MethodSpec, Error> {
    let recorded = RecordedRun::read(results, limits)?;
    let Some((_, path)) = recorded.transcripts.iter().find(|(k, _)| k.method == name) else {
        return Err(Error::Invalid(format!(
            "method {name:?}: {} has no finished episode of it; its methods are {}",
            results.display(),
            recorded.methods().join(", ")
        )));
    };
    let transcript = coherent_agents::transcript::read_within(path, limits.transcript_bytes)?;
    Ok(coherent_agents::recorded_settings(&transcript)?.0.method)
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

/// The results file a run of `settings` with `seeds` seeds writes when it is given none:
/// `results-<backend>[-<model>]-<8 hex digits of the settings>.jsonl` in the current
/// folder, so that runs of other settings never share a file and the same call resumes
/// its own.
pub fn default_out(settings: &EpisodeSettings, seeds: u32) -> PathBuf {
    let record = settings.record(seeds);
    let Some(any) = record.values().next() else {
        return PathBuf::from("results.jsonl");
    };
    let safe = |s: &str| -> String {
        s.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || matches!(c, '.' | '_') {
                    c
                } else {
                    '-'
                }
            })
            .take(40)
            .collect()
    };
    let model = any
        .model
        .as_deref()
        .map_or(String::new(), |m| format!("-{}", safe(m)));
    PathBuf::from(format!(
        "results-{}{model}-{}.jsonl",
        any.backend,
        any.digest()
    ))
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
    /// The most the results file may hold when read back to resume.
    pub max_results_bytes: u64,
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
    let mut ledger = Ledger::open(
        &config.out,
        config.max_results_bytes,
        &config.episodes.record(config.seeds),
    )?;
    let episodes = &config.episodes;
    let keys = ledger.plan(tasks, &episodes.methods, &episodes.executions, config.seeds);
    progress(Event::Start {
        to_run: keys.len(),
        skipped: ledger.outcome().skipped,
    });
    let settings = Arc::new(config.episodes.clone());
    let transcripts = Arc::new(bench::transcripts_dir(&config.out));
    let permits = Arc::new(Semaphore::new(config.at_once()));
    let waiting = Arc::new(Waiting::default());
    let mut set = JoinSet::new();
    for key in keys {
        let (tasks, settings) = (Arc::clone(&run_tasks), Arc::clone(&settings));
        let (transcripts, waiting) = (Arc::clone(&transcripts), Arc::clone(&waiting));
        let (permits, cancel) = (Arc::clone(&permits), cancel.clone());
        set.spawn(async move {
            let _permit = tokio::select! {
                p = permits.acquire() => p.map_err(|e| Error::Internal(e.to_string()))?,
                () = cancel.cancelled() => return Ok(EpisodeResult::NotStarted),
            };
            run_one(
                &tasks,
                &key,
                &settings,
                &transcripts,
                &cancel,
                Some(&waiting),
            )
            .await
        });
    }
    let mut first_error = None;
    // Once a second, a sign of life while a model call is slow.
    let mut tick = tokio::time::interval(std::time::Duration::from_secs(1));
    loop {
        let joined = tokio::select! {
            joined = set.join_next() => match joined {
                Some(joined) => joined,
                None => break,
            },
            _ = tick.tick() => {
                if let Some(longest) = waiting.longest().filter(|l| l.waited >= SLOW) {
                    let text = waiting_text(&longest);
                    progress(Event::Waiting { waited: longest.waited, text: &text });
                }
                continue;
            }
        };
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
            None,
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

/// `lines` with each `cost_usd` worked out anew from its recorded tokens at `prices`.
pub fn priced(lines: Vec<ResultLine>, prices: PriceSource) -> Result<Vec<ResultLine>, Error> {
    let prices = prices.read()?;
    Ok(lines.into_iter().map(|l| l.priced(&prices)).collect())
}

/// The paper's tables of results lines of one set of settings: Table I by task type,
/// Table II by scene, the costs; lines of several sets are refused ([`Mixed`]).
pub fn report(lines: &[ResultLine]) -> Result<Report, Mixed> {
    report::build(lines)
}

/// The paper's tables ([`report()`]) as text.
pub fn tables(lines: &[ResultLine], format: TableFormat) -> Result<String, Mixed> {
    report(lines).map(|r| text(&r, format))
}

/// A report as text.
pub fn text(r: &Report, format: TableFormat) -> String {
    match format {
        TableFormat::Markdown => report::markdown(r),
        TableFormat::Csv => report::csv(r),
        TableFormat::Json => report::json(r),
    }
}

/// The tables of every set of settings in `lines`, one after the other ([`report::groups`]):
/// in Markdown each under a heading that says which run it is, in CSV one header for all
/// (each row names its settings), in JSON one report, or an array of one per set.
pub fn tables_by_run(lines: &[ResultLine], format: TableFormat) -> String {
    // Each group has one set of settings, so each builds.
    let reports: Vec<Report> = report::groups(lines)
        .iter()
        .filter_map(|g| report::build(&g.lines).ok())
        .collect();
    let n = reports.len();
    if n <= 1 {
        let one = reports.into_iter().next();
        return text(&one.unwrap_or_else(report::empty), format);
    }
    match format {
        TableFormat::Markdown => {
            let mut out = format!(
                "The results hold {n} runs of different settings; each has its own tables.\n\n"
            );
            for (i, r) in reports.iter().enumerate() {
                out.push_str(&format!("## Run {} of {n}\n\n", i + 1));
                out.push_str(&report::markdown(r));
                out.push('\n');
            }
            out
        }
        TableFormat::Csv => {
            let mut out = String::new();
            for (i, r) in reports.iter().enumerate() {
                let csv = report::csv(r);
                let body = if i == 0 {
                    csv.as_str()
                } else {
                    csv.split_once('\n').map_or("", |(_, rest)| rest)
                };
                out.push_str(body);
            }
            out
        }
        TableFormat::Json => serde_json::to_string_pretty(&reports).unwrap_or_default(),
    }
}
