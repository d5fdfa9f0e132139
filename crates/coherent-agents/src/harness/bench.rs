//! The benchmark harness: methods x tasks x seeds, run concurrently, one JSON line per
//! finished episode appended to a results file (flushed as each ends), resumable after a
//! crash or Ctrl-C. [`crate::harness::report`] turns the lines into the paper's tables.
//!
//! The harness's other parts are reachable here too, as one namespace:
//! [`crate::harness::subset`] (which tasks), [`crate::harness::results`] (the results
//! file) and [`crate::harness::progress`] (what a run reports).

use std::collections::{HashMap, HashSet};
use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_core::planner::{self, Limits};
use coherent_core::{SymbolicEnv, Task};
use tokio::sync::{OnceCell, Semaphore};
use tokio::task::JoinSet;

use crate::backends::builtin::BuiltinBackend;
use crate::backends::llm::{Backend, BackendInfo};
use crate::backends::openai::OpenAiClient;
use crate::backends::simulated::ErrorRates;
use crate::episode::cancel::Cancel;
use crate::episode::rounds::Episode;
use crate::episode::run::{run as run_episode, transcript_path};
use crate::episode::settings::{Budget, MethodSpec, Settings};
use crate::harness::prices::PriceTable;
use crate::methods::templates::Prompts;
use crate::records::replay::Replay;
use crate::records::transcript;

pub use crate::harness::progress::{Event, Progress};
pub use crate::harness::results::{
    EpisodeKey, ResultLine, ResultsFile, mark_orphans, read_results, repair, transcripts_dir,
};
pub use crate::harness::subset::{PAPER40, Selection, Subset, select};

/// Which backend answers the model-using methods.
#[derive(Clone, Debug)]
pub enum BackendChoice {
    /// The optimal planner in every role.
    Builtin,
    /// The planner with seeded mistakes; each episode gets its own seed.
    Simulated(ErrorRates),
    /// One client shared by every episode (its own concurrency limit holds across them).
    OpenAi(Arc<OpenAiClient>),
    /// The transcripts of an earlier run: each episode answers from the recording with
    /// its method, task and seed, with the recorded settings, and must come out the same.
    Replay(Arc<Recorded>),
}

/// An earlier run's finished episodes, by key: the transcripts a replay answers from.
#[derive(Debug)]
pub struct Recorded {
    /// The earlier results file.
    pub results: PathBuf,
    pub transcripts: HashMap<EpisodeKey, PathBuf>,
    /// The backend of the recordings (the first one's, when they differ).
    pub backend: BackendInfo,
}

impl Recorded {
    /// The final episodes of the results file `results`.
    pub fn read(results: &Path) -> Result<Recorded, String> {
        let file = read_results(results)?;
        let mut backend = None;
        let mut transcripts = HashMap::new();
        for line in file.lines.iter().filter(|l| l.is_final()) {
            if line.uses_model {
                backend.get_or_insert_with(|| line.backend.clone());
            }
            transcripts.insert(line.key(), PathBuf::from(&line.transcript));
        }
        if transcripts.is_empty() {
            return Err(format!(
                "{}: no finished episodes to replay",
                results.display()
            ));
        }
        Ok(Recorded {
            results: results.to_owned(),
            transcripts,
            backend: backend.unwrap_or(BackendInfo {
                kind: "none".into(),
                model: String::new(),
                base_url: None,
            }),
        })
    }
}

impl BackendChoice {
    /// The backend of one episode with seed `seed` (the simulated backend's mistakes are
    /// seeded per episode); `None` for a replay, whose backend depends on the episode's
    /// recording.
    pub fn for_episode(&self, limits: &Limits, seed: u64) -> Option<Arc<dyn Backend>> {
        Some(match self {
            BackendChoice::Builtin => Arc::new(BuiltinBackend::new(limits.clone())),
            BackendChoice::Simulated(rates) => {
                Arc::new(BuiltinBackend::simulated(limits.clone(), *rates, seed))
            }
            BackendChoice::OpenAi(client) => Arc::clone(client) as Arc<dyn Backend>,
            BackendChoice::Replay(_) => return None,
        })
    }

    pub fn info(&self) -> BackendInfo {
        match self {
            BackendChoice::Builtin => BuiltinBackend::new(Limits::default()).info(),
            BackendChoice::Simulated(rates) => {
                BuiltinBackend::simulated(Limits::default(), *rates, 0).info()
            }
            BackendChoice::OpenAi(client) => client.info(),
            BackendChoice::Replay(recorded) => BackendInfo {
                kind: "replay".into(),
                model: recorded.backend.model.clone(),
                base_url: None,
            },
        }
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    /// Built-in methods and methods written outside the crate, each by its own name.
    pub methods: Vec<MethodSpec>,
    /// Seed indices `0..seeds`.
    pub seeds: u32,
    /// Episodes at once.
    pub concurrency: usize,
    pub backend: BackendChoice,
    /// Rounds of history (see [`Settings::history`]).
    pub history: usize,
    /// Recorded in the episodes' settings for an HTTP backend.
    pub temperature: Option<f32>,
    /// Most states one planner search may visit.
    pub max_states: usize,
    /// The step budget of every episode; `None` for the paper's 2 x GT.
    pub max_steps: Option<u32>,
    /// The results file; transcripts go to [`transcripts_dir`] of it.
    pub out: PathBuf,
    /// The templates the methods' prompts are rendered from (a replay renders the
    /// recorded ones).
    pub prompts: Prompts,
    /// Prices each line's tokens (`cost_usd`).
    pub prices: PriceTable,
}

/// The seed of one episode: a hash of the seed index, the method and the task, so that
/// results do not depend on the order episodes run in (FNV-1a, then SplitMix64's mixer).
pub fn episode_seed(seed: u32, method: &str, scene: &str, task_id: i64) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        // A separator, so that ("ab", "c") and ("a", "bc") differ.
        h ^= 0xff;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    };
    eat(&seed.to_le_bytes());
    eat(method.as_bytes());
    eat(scene.as_bytes());
    eat(&task_id.to_le_bytes());
    let mut z = h.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// What the planner says about a task, once per task.
#[derive(Clone, Debug)]
struct TaskInfo {
    task_type: Option<String>,
    optimal: Option<u32>,
    budget: Result<Budget, String>,
}

/// One episode to run.
#[derive(Clone, Debug)]
struct Job {
    method: MethodSpec,
    task: Arc<Task>,
    info: Arc<OnceCell<TaskInfo>>,
    seed: u32,
}

/// What a run did.
#[derive(Debug, Default)]
pub struct BenchOutcome {
    /// Episodes in the plan (methods x tasks x seeds).
    pub total: usize,
    /// Already finished in the results file before this run.
    pub skipped: usize,
    /// Lines written by this run (any status).
    pub written: usize,
    /// Episodes this run did not finish for good: interrupted, backend errors, or never
    /// started because of Ctrl-C.
    pub unfinished: usize,
    /// Whether Ctrl-C (the `cancel` handle) stopped the run.
    pub interrupted: bool,
    /// Tasks that could not be run and why (no ground truth and no plan to size a budget).
    pub skipped_tasks: Vec<String>,
    /// Lines dropped from a cut-off last line.
    pub repaired_bytes: u64,
    /// Transcripts that no results line points to (episodes killed mid-run), renamed to
    /// `*.jsonl.unfinished` before this run; their episodes run again.
    pub orphaned: Vec<PathBuf>,
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
    let out = &config.out;
    let mut outcome = BenchOutcome::default();
    let mut done: HashSet<EpisodeKey> = HashSet::new();
    if out.exists() {
        let file = read_results(out)?;
        if file.truncated_bytes > 0 {
            outcome.repaired_bytes = file.truncated_bytes;
        }
        repair(out, &file)?;
        done.extend(
            file.lines
                .iter()
                .filter(|l| l.is_final())
                .map(ResultLine::key),
        );
        outcome.orphaned = mark_orphans(out, &file.lines)?;
    } else if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let mut file = OpenOptions::new()
        .create(true)
        .append(true)
        .open(out)
        .map_err(|e| format!("{}: {e}", out.display()))?;

    let mut jobs = Vec::new();
    for task in tasks {
        let info = Arc::new(OnceCell::new());
        for seed in 0..config.seeds {
            for method in &config.methods {
                outcome.total += 1;
                let key = EpisodeKey {
                    method: method.name().to_owned(),
                    scene: task.meta.scene.clone(),
                    task_id: task.meta.task_id,
                    seed,
                };
                if done.contains(&key) {
                    outcome.skipped += 1;
                    continue;
                }
                jobs.push(Job {
                    method: method.clone(),
                    task: Arc::clone(task),
                    info: Arc::clone(&info),
                    seed,
                });
            }
        }
    }
    progress(Event::Start {
        to_run: jobs.len(),
        skipped: outcome.skipped,
    });

    let shared = Arc::new(Shared {
        backend: config.backend.clone(),
        backend_info: config.backend.info(),
        history: config.history,
        temperature: config.temperature,
        max_states: config.max_states,
        prompts: config.prompts.clone(),
        prices: config.prices.clone(),
        max_steps: config.max_steps,
        transcripts: transcripts_dir(out),
        cancel: cancel.clone(),
        permits: Semaphore::new(config.concurrency.max(1)),
    });
    let mut set = JoinSet::new();
    for job in jobs {
        let shared = Arc::clone(&shared);
        set.spawn(async move { run_job(job, &shared).await });
    }
    let mut first_error = None;
    while let Some(joined) = set.join_next().await {
        let result = joined.map_err(|e| format!("an episode panicked: {e}"));
        match result.and_then(|r| r) {
            Ok(JobResult::Line(line)) => {
                let mut text = serde_json::to_string(&line)
                    .map_err(|e| format!("cannot encode a results line: {e}"))?;
                text.push('\n');
                if let Err(e) = file.write_all(text.as_bytes()).and_then(|()| file.flush()) {
                    first_error.get_or_insert(format!("{}: {e}", out.display()));
                    cancel.cancel();
                    continue;
                }
                outcome.written += 1;
                if !line.is_final() {
                    outcome.unfinished += 1;
                }
                progress(Event::Finished(&line));
            }
            Ok(JobResult::NotStarted) => outcome.unfinished += 1,
            Ok(JobResult::TaskSkipped(why)) => {
                outcome.unfinished += 1;
                if !outcome.skipped_tasks.contains(&why) {
                    outcome.skipped_tasks.push(why);
                }
            }
            Err(e) => {
                // A transcript that cannot be written would lose data: stop everything.
                first_error.get_or_insert(e);
                cancel.cancel();
            }
        }
    }
    outcome.interrupted = cancel.is_cancelled() && first_error.is_none();
    match first_error {
        Some(e) => Err(e),
        None => Ok(outcome),
    }
}

#[derive(Debug)]
struct Shared {
    backend: BackendChoice,
    backend_info: BackendInfo,
    history: usize,
    temperature: Option<f32>,
    max_states: usize,
    prompts: Prompts,
    prices: PriceTable,
    max_steps: Option<u32>,
    transcripts: PathBuf,
    cancel: Cancel,
    permits: Semaphore,
}

enum JobResult {
    Line(Box<ResultLine>),
    NotStarted,
    TaskSkipped(String),
}

async fn run_job(job: Job, shared: &Shared) -> Result<JobResult, String> {
    let permit = tokio::select! {
        p = shared.permits.acquire() => p.map_err(|e| e.to_string())?,
        () = shared.cancel.cancelled() => return Ok(JobResult::NotStarted),
    };
    if shared.cancel.is_cancelled() {
        return Ok(JobResult::NotStarted);
    }
    let limits = Limits {
        cancel: Some(shared.cancel.flag()),
        ..Limits::max_states(shared.max_states)
    };
    let task = &job.task;
    let info = job
        .info
        .get_or_try_init(|| async {
            let (task, limits) = (Arc::clone(task), limits.clone());
            tokio::task::spawn_blocking(move || task_info(&task, &limits))
                .await
                .map_err(|e| format!("the planner failed: {e}"))
        })
        .await?
        .clone();
    let name = format!("{} task {}", task.meta.scene, task.meta.task_id);
    let budget = match (shared.max_steps, &info.budget) {
        (Some(n), _) => Budget::Given(n),
        (None, Ok(b)) => *b,
        (None, Err(why)) => return Ok(JobResult::TaskSkipped(format!("{name}: {why}"))),
    };
    if shared.cancel.is_cancelled() {
        return Ok(JobResult::NotStarted);
    }
    let method = job.method;
    let seed = episode_seed(job.seed, method.name(), &task.meta.scene, task.meta.task_id);
    let mut settings = Settings {
        history: shared.history,
        temperature: shared.temperature,
        seed: Some(seed),
        prompts: shared.prompts.clone(),
        ..Settings::new(method.clone())
    };
    let mut budget = budget;
    let mut recording = None;
    let backend: Arc<dyn Backend> = match &shared.backend {
        BackendChoice::Replay(recorded) => {
            let key = EpisodeKey {
                method: method.name().to_owned(),
                scene: task.meta.scene.clone(),
                task_id: task.meta.task_id,
                seed: job.seed,
            };
            let Some(path) = recorded.transcripts.get(&key) else {
                return Ok(JobResult::TaskSkipped(format!(
                    "{name}: {} seed {} has no finished episode in {}",
                    method.name(),
                    job.seed,
                    recorded.results.display()
                )));
            };
            let replay = Replay::prepare(&transcript::read(path)?, path)?;
            (settings, budget) = (replay.settings.clone(), replay.budget);
            let backend = Arc::clone(&replay.backend) as Arc<dyn Backend>;
            recording = Some(replay);
            backend
        }
        choice => choice
            .for_episode(&limits, seed)
            .expect("every backend but a replay serves any episode"),
    };
    let dir = shared.transcripts.join(format!("seed{}", job.seed));
    let path = transcript_path(&dir, task, method.name());
    // An episode's future holds `&dyn Environment` across awaits, so it is not `Send`:
    // each runs to completion on a blocking-pool thread of the same multi-thread runtime
    // (its model calls, timers and planner searches still use the runtime).
    let handle = tokio::runtime::Handle::current();
    let episode = {
        let (task, path, cancel) = (Arc::clone(task), path.clone(), shared.cancel.clone());
        tokio::task::spawn_blocking(move || {
            handle.block_on(async move {
                let mut env = SymbolicEnv::new(Arc::clone(&task));
                run_episode(
                    &task,
                    &mut env,
                    backend.as_ref(),
                    &settings,
                    budget,
                    &path,
                    &cancel,
                    &mut |_| {},
                )
                .await
            })
        })
        .await
        .map_err(|e| format!("an episode panicked: {e}"))??
        .0
    };
    drop(permit);
    // A replay that comes out differently says so in its line's error.
    let mismatch = recording
        .as_ref()
        .and_then(|r| r.check(&episode).err())
        .map(|why| format!("replay mismatch: {why}"));
    let (backend, uses_model) = line_backend(shared, &method, &episode);
    let s = episode.summary;
    let line = ResultLine {
        method: method.name().to_owned(),
        scene: task.meta.scene.clone(),
        task_id: task.meta.task_id,
        task_type: info.task_type,
        seed: job.seed,
        episode_seed: seed,
        success: s.success,
        status: s.status,
        steps: s.steps,
        gt_steps: s.gt_steps,
        optimal_steps: info.optimal,
        max_steps: s.max_steps,
        llm_calls: s.llm_calls,
        prompt_tokens: s.prompt_tokens,
        completion_tokens: s.completion_tokens,
        cached_tokens: s.cached_tokens,
        cost_usd: None,
        wall_ms: (s.wall_ms * 1e3).round() / 1e3,
        backend,
        uses_model,
        error: mismatch.or(s.error),
        transcript: path.display().to_string(),
    };
    Ok(JobResult::Line(Box::new(line.priced(&shared.prices))))
}

/// The backend of a results line, and whether the method asked a model: the run's
/// backend for a built-in method; for a method written outside the crate, the endpoint
/// its first call through the project's client went to (as a replay labels it when the
/// run replays), or none, and whether it made or reported any call.
fn line_backend(shared: &Shared, method: &MethodSpec, episode: &Episode) -> (BackendInfo, bool) {
    if method.builtin().is_some() {
        return (shared.backend_info.clone(), method.uses_model());
    }
    let client = episode
        .rounds
        .iter()
        .flat_map(|r| &r.calls)
        .find_map(|c| c.client.clone());
    let backend = match (client, &shared.backend) {
        (Some(c), BackendChoice::Replay(_)) => BackendInfo {
            kind: "replay".into(),
            model: c.model,
            base_url: None,
        },
        (Some(c), _) => c,
        (None, _) => BackendInfo {
            kind: "none".into(),
            model: String::new(),
            base_url: None,
        },
    };
    (backend, episode.summary.llm_calls > 0)
}

fn task_info(task: &Task, limits: &Limits) -> TaskInfo {
    let analysis = planner::analyse(task, limits);
    let optimal = analysis.plan.as_ref().map(|p| p.len() as u32);
    let budget = match (task.meta.twice_ground_truth(), optimal) {
        (Some(budget), _) => budget.map(Budget::TwiceGroundTruth),
        (None, Some(n)) => Ok(Budget::TwiceOptimum(n.max(1).saturating_mul(2))),
        (None, None) => Err(format!(
            "no ground truth, and the planner finds no plan to size a budget from ({})",
            analysis.reason.as_deref().unwrap_or("search stopped")
        )),
    };
    TaskInfo {
        task_type: analysis.task_type.map(|t| t.name().to_owned()),
        optimal,
        budget,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_differ_by_every_part_and_are_stable() {
        let a = episode_seed(0, "pefa", "env0", 2);
        assert_eq!(a, episode_seed(0, "pefa", "env0", 2));
        assert_ne!(a, episode_seed(1, "pefa", "env0", 2));
        assert_ne!(a, episode_seed(0, "mcts", "env0", 2));
        assert_ne!(a, episode_seed(0, "pefa", "env1", 2));
        assert_ne!(a, episode_seed(0, "pefa", "env0", 3));
    }
}
