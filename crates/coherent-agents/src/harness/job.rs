//! One benchmark episode, known by its key (method, scene, task id, seed index): run
//! with the settings every episode of a run shares, its transcript written, its results
//! line returned. The local executor ([`crate::harness::bench::run`]) runs every episode
//! through here, and so does a worker of a distributed one, so that both give the same
//! lines.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use coherent_core::planner::{self, Limits};
use coherent_core::text::cut;
use coherent_core::{SymbolicEnv, Task};
use tokio::sync::OnceCell;

use crate::backends::llm::{Backend, BackendInfo};
use crate::episode::cancel::Cancel;
use crate::episode::rounds::Episode;
use crate::episode::run::{run as run_episode, transcript_path};
use crate::episode::settings::{Budget, MethodSpec, Settings};
use crate::harness::choice::BackendChoice;
use crate::harness::prices::PriceTable;
use crate::harness::results::{ERROR_BYTES, EpisodeKey, ResultLine};
use crate::harness::subset::same_key_twice;
use crate::methods::templates::Prompts;
use crate::records::replay::Replay;
use crate::records::transcript;

/// What every episode of a run shares: the methods, the backend and the settings.
#[derive(Clone, Debug)]
pub struct EpisodeSettings {
    /// The run's methods; an episode's key names its method.
    pub methods: Vec<MethodSpec>,
    pub backend: BackendChoice,
    /// Rounds of history (see [`Settings::history`]).
    pub history: usize,
    /// Recorded in the episodes' settings for an HTTP backend.
    pub temperature: Option<f32>,
    /// Most states one planner search may visit.
    pub max_states: usize,
    /// The step budget of every episode; `None` for the paper's 2 x GT.
    pub max_steps: Option<u32>,
    /// The templates the methods' prompts are rendered from (a replay renders the
    /// recorded ones).
    pub prompts: Prompts,
    /// Prices each line's tokens (`cost_usd`).
    pub prices: PriceTable,
}

impl EpisodeSettings {
    /// `methods` answered by `backend`, with the paper's settings: 5 rounds of history,
    /// the default planner bound, 2 x GT steps, the built-in prompts and prices.
    pub fn new(methods: Vec<MethodSpec>, backend: BackendChoice) -> EpisodeSettings {
        EpisodeSettings {
            methods,
            backend,
            history: 5,
            temperature: None,
            max_states: Limits::DEFAULT_MAX_STATES,
            max_steps: None,
            prompts: Prompts::builtin(),
            prices: PriceTable::builtin(),
        }
    }
}

/// What the planner says about a task, once per task.
#[derive(Clone, Debug)]
struct TaskInfo {
    task_type: Option<String>,
    optimal: Option<u32>,
    budget: Result<Budget, String>,
}

/// The tasks of a run by scene and task id, each with what the planner says about it,
/// worked out by the first of its episodes to start and kept for the others.
#[derive(Clone, Debug)]
pub struct RunTasks {
    tasks: Vec<Arc<Task>>,
    by_key: HashMap<(String, i64), (Arc<Task>, Arc<Planned>)>,
}

/// What the planner says about a task, once it has been asked.
type Planned = OnceCell<TaskInfo>;

impl RunTasks {
    /// `tasks`, in their order; two with the same scene and task id are refused, since
    /// results could not tell their episodes apart.
    pub fn new(tasks: &[Arc<Task>]) -> Result<RunTasks, String> {
        let mut by_key = HashMap::new();
        for t in tasks {
            let key = (t.meta.scene.clone(), t.meta.task_id);
            if by_key.contains_key(&key) {
                return Err(same_key_twice(&key));
            }
            by_key.insert(key, (Arc::clone(t), Arc::new(OnceCell::new())));
        }
        Ok(RunTasks {
            tasks: tasks.to_vec(),
            by_key,
        })
    }

    /// Every episode of `methods` x the tasks x seed indices `0..seeds`, task by task,
    /// seed by seed, method by method.
    pub fn keys(&self, methods: &[MethodSpec], seeds: u32) -> Vec<EpisodeKey> {
        let mut keys = Vec::new();
        for task in &self.tasks {
            for seed in 0..seeds {
                for method in methods {
                    keys.push(EpisodeKey {
                        method: method.name().to_owned(),
                        scene: task.meta.scene.clone(),
                        task_id: task.meta.task_id,
                        seed,
                    });
                }
            }
        }
        keys
    }
}

/// What came of one episode.
#[derive(Debug)]
pub enum EpisodeResult {
    /// It ran (to any end): its results line, its transcript written.
    Line(Box<ResultLine>),
    /// Cancelled before it started.
    NotStarted,
    /// Its task cannot run, and why (no ground truth and no plan to size a budget, or no
    /// recording to replay).
    TaskSkipped(String),
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

/// Runs the episode `key` of `tasks` with `settings`, writing its transcript to the
/// `seed<N>` subfolder of `transcripts` (the run's [`crate::harness::results::transcripts_dir`]),
/// on the current tokio runtime (multi-threaded; the episode itself runs on a thread of
/// its own). `cancel` ends it as interrupted, or keeps it from starting.
pub async fn run_one(
    tasks: &RunTasks,
    key: &EpisodeKey,
    settings: &EpisodeSettings,
    transcripts: &Path,
    cancel: &Cancel,
) -> Result<EpisodeResult, String> {
    let method = settings
        .methods
        .iter()
        .find(|m| m.name() == key.method)
        .ok_or_else(|| format!("no method {:?} in this run", key.method))?;
    let (task, info) = tasks
        .by_key
        .get(&(key.scene.clone(), key.task_id))
        .ok_or_else(|| format!("no task {} {} in this run", key.scene, key.task_id))?;
    if cancel.is_cancelled() {
        return Ok(EpisodeResult::NotStarted);
    }
    let limits = Limits {
        cancel: Some(cancel.flag()),
        ..Limits::max_states(settings.max_states)
    };
    let info = info
        .get_or_try_init(|| async {
            let (task, limits) = (Arc::clone(task), limits.clone());
            tokio::task::spawn_blocking(move || task_info(&task, &limits))
                .await
                .map_err(|e| format!("the planner failed: {e}"))
        })
        .await?
        .clone();
    let name = format!("{} task {}", task.meta.scene, task.meta.task_id);
    let budget = match (settings.max_steps, &info.budget) {
        (Some(n), _) => Budget::Given(n),
        (None, Ok(b)) => *b,
        (None, Err(why)) => return Ok(EpisodeResult::TaskSkipped(format!("{name}: {why}"))),
    };
    if cancel.is_cancelled() {
        return Ok(EpisodeResult::NotStarted);
    }
    let seed = episode_seed(key.seed, method.name(), &task.meta.scene, task.meta.task_id);
    let settings_of_episode = Settings {
        history: settings.history,
        temperature: settings.temperature,
        seed: Some(seed),
        prompts: settings.prompts.clone(),
        ..Settings::new(method.clone())
    };
    let (backend, recording, settings_of_episode, budget) = match &settings.backend {
        BackendChoice::Replay(recorded) => {
            let Some(path) = recorded.transcripts.get(key) else {
                return Ok(EpisodeResult::TaskSkipped(format!(
                    "{name}: {} seed {} has no finished episode in {}",
                    method.name(),
                    key.seed,
                    recorded.results.display()
                )));
            };
            // A replay runs with the recorded settings and budget.
            let replay = Replay::prepare(
                &transcript::read_within(path, recorded.max_transcript_bytes)?,
                path,
            )?;
            let backend = Arc::clone(&replay.backend) as Arc<dyn Backend>;
            let (recorded_settings, recorded_budget) = (replay.settings.clone(), replay.budget);
            (backend, Some(replay), recorded_settings, recorded_budget)
        }
        choice => {
            let backend = choice
                .for_episode(&limits, seed)
                .expect("every backend but a replay serves any episode");
            (backend, None, settings_of_episode, budget)
        }
    };
    let dir = transcripts.join(format!("seed{}", key.seed));
    let path = transcript_path(&dir, task, method.name());
    // An episode's future holds `&dyn Environment` across awaits, so it is not `Send`:
    // it runs to completion on a thread of its own, driven by the same multi-thread
    // runtime (its model calls, timers and planner searches still use the runtime).
    let handle = tokio::runtime::Handle::current();
    let episode = {
        let (task, path, cancel) = (Arc::clone(task), path.clone(), cancel.clone());
        let settings = settings_of_episode;
        on_its_own_thread(move || {
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
        .await??
        .0
    };
    // A replay that comes out differently says so in its line's error.
    let mismatch = recording
        .as_ref()
        .and_then(|r| r.check(&episode).err())
        .map(|why| format!("replay mismatch: {why}"));
    let (backend, uses_model) = line_backend(&settings.backend, method, &episode);
    let s = episode.summary;
    let line = ResultLine {
        method: method.name().to_owned(),
        scene: task.meta.scene.clone(),
        task_id: task.meta.task_id,
        task_type: info.task_type,
        seed: key.seed,
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
        error: mismatch
            .or(s.error)
            .map(|e| cut(&e, ERROR_BYTES).into_owned()),
        transcript: path.display().to_string(),
    };
    Ok(EpisodeResult::Line(Box::new(line.priced(&settings.prices))))
}

/// The backend of a results line, and whether the method asked a model: the run's
/// backend for a built-in method; for a method written outside the crate, the endpoint
/// its first call through the project's client went to (as a replay labels it when the
/// run replays), or none, and whether it made or reported any call.
fn line_backend(
    choice: &BackendChoice,
    method: &MethodSpec,
    episode: &Episode,
) -> (BackendInfo, bool) {
    if method.builtin().is_some() {
        return (choice.info(), method.uses_model());
    }
    let client = episode
        .rounds
        .iter()
        .flat_map(|r| &r.calls)
        .find_map(|c| c.client.clone());
    let backend = match (client, choice) {
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

/// Runs `work` on a thread of its own and waits for it without holding a runtime thread:
/// one thread per episode, so that as many episodes run at once as the run allows, not
/// as many as tokio's blocking pool holds (512). A panic comes back as an error with its
/// message.
async fn on_its_own_thread<T: Send + 'static>(
    work: impl FnOnce() -> T + Send + 'static,
) -> Result<T, String> {
    let (done, result) = tokio::sync::oneshot::channel();
    std::thread::Builder::new()
        .name("coherent-episode".into())
        .spawn(move || {
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(work));
            let _ = done.send(outcome);
        })
        .map_err(|e| format!("cannot start an episode's thread: {e}"))?;
    match result.await {
        Ok(Ok(value)) => Ok(value),
        Ok(Err(panic)) => {
            let message = panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Err(format!("an episode panicked: {message}"))
        }
        Err(_) => Err("an episode's thread ended without a result".into()),
    }
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
