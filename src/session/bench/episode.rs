//! One benchmark episode, known by its key (method, scene, task id, seed index): sized,
//! set up and run by the session's one episode runner with the settings every episode
//! of the run shares, its transcript written, its results line returned. The local
//! executor runs every episode through here, and so does a worker of a distributed one,
//! so that both give the same lines.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use coherent_agents::Settings;
use coherent_agents::bench::{self, EpisodeKey, EpisodeResult, ResultLine, same_key_twice};
use coherent_agents::episode::{Budget, NoPlan, PlannedMakespan};
use coherent_agents::llm::Backend;
use coherent_agents::{BackendInfo, BackendKind, Cancel, MethodSpec, Replay, transcript};
use coherent_core::Execution;
use coherent_core::Task;
use coherent_core::makespan;
use coherent_core::planner::{self, Limits};
use coherent_core::text::cut;
use tokio::sync::OnceCell;

use super::settings::EpisodeSettings;
use crate::session::backend::BackendChoice;
use crate::session::episode::{self, EpisodeSpec, Ran};
use crate::session::error::{Error, panic_message};
use crate::session::waiting::Waiting;

/// What the planner says about a task, once per task: its type and optimum for the
/// results lines, and why it has no plan when it has none; in a run with parallel
/// episodes, its makespan too (their budget, and the lines' `optimal_makespan`).
#[derive(Clone, Debug)]
struct TaskInfo {
    task_type: Option<String>,
    /// The robots of its team.
    team_size: u32,
    optimal: Result<u32, NoPlan>,
    /// `None` when the run has no parallel episode (not searched).
    makespan: Option<Result<PlannedMakespan, NoPlan>>,
}

/// What the planner says about a task, once the first of its episodes has asked.
type Planned = Arc<OnceCell<TaskInfo>>;

/// The tasks of a run by scene and task id, each with what the planner says about it,
/// worked out by the first of its episodes to start and kept for the others.
#[derive(Clone, Debug)]
pub struct RunTasks {
    tasks: Vec<Arc<Task>>,
    by_key: HashMap<(String, i64), (Arc<Task>, Planned)>,
}

impl RunTasks {
    /// `tasks`, in their order; two with the same scene and task id are refused, since
    /// results could not tell their episodes apart.
    pub fn new(tasks: &[Arc<Task>]) -> Result<RunTasks, Error> {
        let mut by_key = HashMap::new();
        for t in tasks {
            let key = (t.meta.scene.clone(), t.meta.task_id);
            if by_key.contains_key(&key) {
                return Err(Error::Invalid(same_key_twice(&key)));
            }
            by_key.insert(key, (Arc::clone(t), Arc::new(OnceCell::new())));
        }
        Ok(RunTasks {
            tasks: tasks.to_vec(),
            by_key,
        })
    }

    /// The tasks, in their order.
    pub fn tasks(&self) -> &[Arc<Task>] {
        &self.tasks
    }
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
/// `seed<N>` subfolder of `transcripts` (the run's
/// [`coherent_agents::bench::transcripts_dir`]), on the current tokio runtime
/// (multi-threaded; the episode itself runs on a thread of its own). `cancel` ends it as
/// interrupted, or keeps it from starting. With `waiting`, its model calls are kept
/// there while they run.
pub async fn run_one(
    tasks: &RunTasks,
    key: &EpisodeKey,
    settings: &EpisodeSettings,
    transcripts: &Path,
    cancel: &Cancel,
    waiting: Option<&Arc<Waiting>>,
) -> Result<EpisodeResult, Error> {
    let method = settings
        .methods
        .iter()
        .find(|m| m.name() == key.method)
        .ok_or_else(|| Error::Invalid(format!("no method {:?} in this run", key.method)))?;
    let (task, info) = tasks
        .by_key
        .get(&(key.scene.clone(), key.task_id))
        .ok_or_else(|| {
            Error::Invalid(format!("no task {} {} in this run", key.scene, key.task_id))
        })?;
    if cancel.is_cancelled() {
        return Ok(EpisodeResult::NotStarted);
    }
    let limits = Limits {
        cancel: Some(cancel.flag()),
        ..Limits::max_states(settings.max_states)
    };
    let parallel = settings.executions.contains(&Execution::Parallel);
    let info = info
        .get_or_try_init(|| async {
            let (task, limits) = (Arc::clone(task), limits.clone());
            tokio::task::spawn_blocking(move || task_info(&task, &limits, parallel))
                .await
                .map_err(|e| Error::Internal(format!("the planner failed: {e}")))
        })
        .await?
        .clone();
    let name = format!("{} task {}", task.meta.scene, task.meta.task_id);
    let budget = match key.execution {
        Execution::Sequential => Budget::of(task, settings.max_steps, || info.optimal.clone()),
        Execution::Parallel => Budget::parallel(task, settings.max_steps, || {
            let unsearched = || Err(NoPlan("the makespan was not searched".into()));
            info.makespan.clone().unwrap_or_else(unsearched)
        }),
    };
    let budget = match budget {
        Ok(budget) => budget,
        Err(why) => return Ok(EpisodeResult::TaskSkipped(format!("{name}: {why}"))),
    };
    if cancel.is_cancelled() {
        return Ok(EpisodeResult::NotStarted);
    }
    let seed = episode_seed(key.seed, method.name(), &task.meta.scene, task.meta.task_id);
    let dir = transcripts.join(format!("seed{}", key.seed));
    let spec = match &settings.backend {
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
            let read = transcript::read_within(path, recorded.max_transcript_bytes)?;
            let replay = Replay::prepare(&read, path)?;
            EpisodeSpec {
                task: Arc::clone(task),
                settings: replay.settings.clone(),
                budget: replay.budget,
                backend: Arc::clone(&replay.backend) as Arc<dyn Backend>,
                robots: settings.robots.clone(),
                out: dir,
                prices: settings.prices.clone(),
                recording: Some((replay, path.clone())),
                choice: Some(settings.backend.clone()),
            }
        }
        choice => EpisodeSpec {
            task: Arc::clone(task),
            settings: Settings {
                method: method.clone(),
                execution: key.execution,
                history: settings.history,
                temperature: choice.temperature(),
                seed: Some(seed),
                physics: settings.physics,
                robots: settings.robots.record(),
                prompts: settings.prompts.clone(),
                max_states: limits.max_states,
            },
            budget,
            backend: match waiting {
                Some(waiting) => waiting.watch(choice.for_episode(&limits, seed)?),
                None => choice.for_episode(&limits, seed)?,
            },
            robots: settings.robots.clone(),
            out: dir,
            prices: settings.prices.clone(),
            recording: None,
            choice: Some(choice.clone()),
        },
    };
    let max_steps = spec.budget.steps();
    let ran = on_its_own_thread(spec, cancel.clone()).await??;
    match ran {
        Built::Ran(ran) => Ok(EpisodeResult::Line(Box::new(line(
            key, method, seed, &info, &ran, settings,
        )))),
        Built::NoWorld(why) => Ok(EpisodeResult::TaskSkipped(format!("{name}: {why}"))),
        Built::NoTranscript { file, message } => {
            let not_run = NotRun {
                seed,
                max_steps,
                why: format!("no transcript: {file}: {message}"),
                transcript: file,
            };
            Ok(EpisodeResult::Line(Box::new(
                not_run.line(key, method, task, &info, settings),
            )))
        }
    }
}

/// What came of running an episode on its thread.
enum Built {
    Ran(Box<Ran>),
    /// The task's physical world could not be built: the task cannot run in physics.
    NoWorld(String),
    /// The episode's transcript could not be created (its folder cannot be made or
    /// allows no new file): the episode did not run, the others may.
    NoTranscript {
        file: String,
        message: String,
    },
}

/// Prepares and runs the episode `spec` on a thread of its own, driven by the current
/// (multi-thread) runtime, and waits for it without holding a runtime thread: an
/// episode's future holds `&dyn Environment` across awaits, so it is not `Send`, and
/// one thread per episode lets as many run at once as the run allows (not as many as
/// tokio's blocking pool holds). Its model calls, timers and planner searches still use
/// the runtime. A panic comes back as an error with its message.
async fn on_its_own_thread(
    spec: EpisodeSpec,
    cancel: Cancel,
) -> Result<Result<Built, Error>, Error> {
    let handle = tokio::runtime::Handle::current();
    let (done, result) = tokio::sync::oneshot::channel();
    let work = move || {
        handle.block_on(async move {
            let prepared = match episode::prepare(spec, &cancel) {
                Ok(prepared) => prepared,
                Err(Error::Physics(e)) => {
                    return Ok(Built::NoWorld(format!("physics: {}", e.message)));
                }
                Err(e) => return Err(e),
            };
            match prepared.run(&cancel, &mut |_| {}).await {
                Ok(ran) => Ok(Built::Ran(Box::new(ran))),
                Err(Error::NoTranscript { file, message }) => {
                    Ok(Built::NoTranscript { file, message })
                }
                Err(e) => Err(e),
            }
        })
    };
    std::thread::Builder::new()
        .name("coherent-episode".into())
        .spawn(move || {
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(work));
            let _ = done.send(outcome);
        })
        .map_err(|e| Error::Internal(format!("cannot start an episode's thread: {e}")))?;
    match result.await {
        Ok(Ok(value)) => Ok(value),
        Ok(Err(panic)) => Err(Error::Internal(format!(
            "an episode panicked: {}",
            panic_message(panic.as_ref())
        ))),
        Err(_) => Err(Error::Internal(
            "an episode's thread ended without a result".into(),
        )),
    }
}

/// The results line of the episode `key` as it ran.
fn line(
    key: &EpisodeKey,
    method: &MethodSpec,
    seed: u64,
    info: &TaskInfo,
    ran: &Ran,
    settings: &EpisodeSettings,
) -> ResultLine {
    let s = ran.summary();
    // A replay that comes out differently says so in its line's error.
    let mismatch = match ran.ending() {
        episode::Ending::ReplayDiffers(why) => Some(format!("replay mismatch: {why}")),
        _ => None,
    };
    ResultLine {
        method: method.name().to_owned(),
        execution: key.execution,
        scene: key.scene.clone(),
        task_id: key.task_id,
        task_type: info.task_type.clone(),
        team_size: Some(info.team_size),
        seed: key.seed,
        episode_seed: seed,
        success: s.success,
        status: s.status,
        steps: s.steps,
        gt_steps: s.gt_steps,
        optimal_steps: info.optimal.clone().ok(),
        max_steps: s.max_steps,
        makespan: s.success.then_some(s.steps),
        optimal_makespan: optimal_makespan(info),
        actions: Some(transcript::actions(&ran.transcript.rounds)),
        llm_calls: s.llm_calls,
        prompt_tokens: s.prompt_tokens,
        completion_tokens: s.completion_tokens,
        cached_tokens: s.cached_tokens,
        cost_usd: ran.cost_usd,
        wall_ms: (s.wall_ms * 1e3).round() / 1e3,
        sim_seconds: s.sim_seconds,
        backend: line_backend(&settings.backend, method, ran),
        uses_model: ran.model_use.uses_model(),
        // Cut, so that the line stays within what a results file may hold.
        error: mismatch
            .or_else(|| s.error.clone())
            .map(|e| cut(&e, bench::ERROR_BYTES).into_owned()),
        transcript: ran.path.display().to_string(),
        // The run's settings are the driver's to record (`Ledger::record`).
        settings: None,
        reference: s.reference.as_deref().cloned(),
    }
}

/// An episode that did not run, and why, as its results line says it.
struct NotRun {
    seed: u64,
    max_steps: u32,
    why: String,
    /// The transcript it would have written.
    transcript: String,
}

impl NotRun {
    /// Its results line: status `interrupted` with the reason in `error`, so that it is
    /// no final result (a resume runs it again) and the report lists it as failed; no
    /// step, no model call.
    fn line(
        self,
        key: &EpisodeKey,
        method: &MethodSpec,
        task: &Task,
        info: &TaskInfo,
        settings: &EpisodeSettings,
    ) -> ResultLine {
        ResultLine {
            method: method.name().to_owned(),
            execution: key.execution,
            scene: key.scene.clone(),
            task_id: key.task_id,
            task_type: info.task_type.clone(),
            team_size: Some(info.team_size),
            seed: key.seed,
            episode_seed: self.seed,
            success: false,
            status: transcript::Status::Interrupted,
            steps: 0,
            gt_steps: task.meta.gt_steps,
            optimal_steps: info.optimal.clone().ok(),
            max_steps: self.max_steps,
            makespan: None,
            optimal_makespan: optimal_makespan(info),
            actions: Some(0),
            llm_calls: 0,
            prompt_tokens: 0,
            completion_tokens: 0,
            cached_tokens: 0,
            cost_usd: Some(0.0),
            wall_ms: 0.0,
            sim_seconds: None,
            backend: match method.builtin() {
                Some(_) => settings.backend.info(),
                None => BackendInfo::none(),
            },
            uses_model: false,
            error: Some(cut(&self.why, bench::ERROR_BYTES).into_owned()),
            transcript: self.transcript,
            settings: None,
            reference: None,
        }
    }
}

/// The task's fewest joint steps, in a run with parallel episodes and a plan.
fn optimal_makespan(info: &TaskInfo) -> Option<u32> {
    info.makespan
        .as_ref()
        .and_then(|m| m.as_ref().ok())
        .map(|m| m.steps)
}

/// The backend of a results line: the run's backend for a built-in method (even one
/// that asks no model: `uses_model` says whether it did); for a method written outside
/// the crate, the client its calls went through ([`coherent_agents::ModelUse`]),
/// labelled as a replay when the run replays.
fn line_backend(choice: &BackendChoice, method: &MethodSpec, ran: &Ran) -> BackendInfo {
    if method.builtin().is_some() {
        return choice.info();
    }
    let used = ran.model_use.backend.clone();
    match choice {
        BackendChoice::Replay(_) if used.kind != BackendKind::None => BackendInfo {
            kind: BackendKind::Replay,
            model: used.model,
            base_url: None,
        },
        _ => used,
    }
}

fn task_info(task: &Task, limits: &Limits, parallel: bool) -> TaskInfo {
    let analysis = planner::analyse(task, limits);
    let makespan = parallel.then(|| {
        let (robots, goal) = (&task.robots, &task.goal);
        let plan = analysis.plan.as_deref();
        PlannedMakespan::of(&makespan::search_with(
            task, &task.init, robots, goal, plan, limits,
        ))
    });
    TaskInfo {
        makespan,
        task_type: analysis.task_type.map(|t| t.name().to_owned()),
        team_size: u32::try_from(task.robots.len()).unwrap_or(u32::MAX),
        optimal: match &analysis.plan {
            Some(plan) => Ok(u32::try_from(plan.len()).unwrap_or(u32::MAX)),
            None => Err(NoPlan(
                analysis
                    .reason
                    .unwrap_or_else(|| "the search stopped".to_owned()),
            )),
        },
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
