//! `coherent run`: one episode of a planning method on one task, one line per step, a
//! summary, and a transcript.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use clap::Args;
use coherent_agents::episode::{self, Budget, Method, Settings};
use coherent_agents::llm::Backend;
use coherent_agents::transcript::{self, Outcome, Round, Status};
use coherent_agents::{
    ApiKey, BuiltinBackend, Cancel, Episode, ErrorRates, OpenAiClient, ReplayBackend,
};
use coherent_core::planner::Limits;
use coherent_core::{Environment, SymbolicEnv, Task};

use serde_json::json;

use super::llm::{AnswerFormat, Endpoint, Patience, sim_errors};
use super::{method_names, pick_task};

/// Exit status when the episode ran but the goal was not reached.
const FAILED: u8 = 1;
/// Exit status when the model's server failed for good or a replay diverged.
const BACKEND_FAILED: u8 = 3;
/// Exit status after Ctrl-C, as shells report SIGINT.
const INTERRUPTED: u8 = 130;

#[derive(Args)]
pub(crate) struct RunArgs {
    /// A native task file, or an original env file with --task (not needed with --replay).
    #[arg(required_unless_present = "replay")]
    task_file: Option<PathBuf>,
    /// Which task of the file (its task_id).
    #[arg(long = "task")]
    task_id: Option<i64>,
    /// The planning method.
    #[arg(long, default_value = "pefa", value_parser = method_names())]
    method: String,
    /// Rounds of history the task assigner sees; 0 is the paper's "w/o history".
    #[arg(long, default_value_t = 5)]
    history: usize,
    /// Step budget; by default 2 x the task's ground truth (2 x the optimum without one).
    #[arg(long)]
    max_steps: Option<u32>,
    /// Folder for the transcript.
    #[arg(long, default_value = "runs")]
    out: PathBuf,
    /// Re-run the episode of a transcript, answering from it (no network), and check
    /// that every round comes out the same.
    #[arg(long)]
    replay: Option<PathBuf>,
    /// Print a JSON summary on stdout (step lines go to stderr).
    #[arg(long)]
    json: bool,
    /// Execute every action in Rapier too; a physical failure is an infeasible step
    /// whose message has the numbers.
    #[arg(long)]
    physics: bool,
    /// OpenAI-compatible endpoint up to the version, e.g. http://127.0.0.1:8080/v1
    /// [env: OPENAI_BASE_URL]
    #[arg(long)]
    base_url: Option<String>,
    /// API key [env: OPENAI_API_KEY]. Prefer the variable: flags show up in `ps`.
    #[arg(long)]
    api_key: Option<String>,
    /// Model name [env: COHERENT_MODEL].
    #[arg(long)]
    model: Option<String>,
    #[arg(long, default_value_t = 0.0)]
    temperature: f32,
    #[arg(long)]
    seed: Option<u64>,
    /// Answer format asked for first; a server that refuses it gets the next one.
    #[arg(long, value_enum, default_value_t = AnswerFormat::JsonSchema)]
    format: AnswerFormat,
    #[command(flatten)]
    patience: Patience,
    /// Requests in flight at once.
    #[arg(long, default_value_t = 4)]
    concurrency: usize,
    /// Without an endpoint: the simulated backend instead of the built-in one, making
    /// these mistakes (`hallucinate=0.1,wrong_robot=0.1,malformed=0.1,suboptimal=0.1`,
    /// or `all=0.1`), seeded by --seed.
    #[arg(long)]
    sim_errors: Option<String>,
    /// Most states one search of the built-in planner may visit.
    #[arg(long, default_value_t = Limits::DEFAULT_MAX_STATES)]
    max_states: usize,
}

/// Where human-readable lines go: stdout, or stderr when stdout carries JSON.
struct Lines {
    json: bool,
}

impl Lines {
    fn say(&self, line: &str) {
        if self.json {
            eprintln!("{line}");
        } else {
            let _ = writeln!(std::io::stdout(), "{line}");
        }
    }
}

pub(crate) fn run(args: RunArgs) -> Result<u8, String> {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the async runtime: {e}"))?;
    runtime.block_on(run_async(args))
}

async fn run_async(args: RunArgs) -> Result<u8, String> {
    let lines = Lines { json: args.json };
    let cancel = Cancel::default();
    let limits = Limits {
        cancel: Some(cancel.flag()),
        ..Limits::max_states(args.max_states)
    };
    let recorded = match &args.replay {
        Some(path) => Some(transcript::read(path)?),
        None => None,
    };
    let (task, settings, budget, backend): (Task, Settings, Budget, Box<dyn Backend>) =
        match (&recorded, &args.replay) {
            (Some(t), Some(path)) => {
                let task = episode::recorded_task(t, path)?;
                if let Some(file) = &args.task_file {
                    let given = pick_task(file, args.task_id)?;
                    if coherent_core::native::to_value(&given) != t.header.task {
                        return Err(format!(
                            "{}: the task differs from the one recorded in {}",
                            file.display(),
                            path.display()
                        ));
                    }
                }
                let (settings, budget) = episode::recorded_settings(t)?;
                (task, settings, budget, Box::new(ReplayBackend::new(t)))
            }
            _ => {
                let file = args
                    .task_file
                    .as_deref()
                    .ok_or("a task file is needed without --replay")?;
                let task = pick_task(file, args.task_id)?;
                let method = Method::from_name(&args.method)
                    .ok_or_else(|| format!("unknown method {:?}", args.method))?;
                let budget = Budget::of(&task, args.max_steps, &limits)?;
                let http = http_backend(&args)?;
                let settings = Settings {
                    method,
                    history: args.history,
                    temperature: http.as_ref().map(|_| args.temperature),
                    seed: args.seed,
                    physics: args.physics,
                };
                let rates = sim_errors(args.sim_errors.as_deref())?;
                let backend = backend(http, rates, args.seed, &limits)?;
                (task, settings, budget, backend)
            }
        };
    lines.say(&if settings.method.uses_model() {
        backend_line(backend.as_ref(), args.replay.as_deref())
    } else {
        format!("backend: none ({} asks no model)", settings.method.name())
    });
    let task = Arc::new(task);
    let gt = task
        .meta
        .gt_steps
        .map_or("none".to_owned(), |g| g.to_string());
    let budget_note = match budget {
        Budget::TwiceGroundTruth(n) => format!("{n} steps (2 x GT)"),
        Budget::Given(n) => format!("{n} steps"),
        Budget::TwiceOptimum(n) => format!("{n} steps (no GT: 2 x the planner's optimum)"),
    };
    lines.say(&format!(
        "task: {} task {} \"{}\" | method {} | GT {gt} | budget {budget_note}",
        task.meta.scene,
        task.meta.task_id,
        task.meta.instruction,
        settings.method.name()
    ));
    let ctrl_c = {
        let cancel = cancel.clone();
        tokio::spawn(async move {
            if tokio::signal::ctrl_c().await.is_ok() {
                cancel.cancel();
            }
        })
    };
    let max = budget.steps();
    let mut progress = |r: &Round| lines.say(&step_line(&task, r, max));
    let mut env =
        environment(&task, settings.physics).map_err(|e| format!("physics: {}", e.message))?;
    let result = run_episode(
        &task,
        env.as_mut(),
        backend.as_ref(),
        &settings,
        budget,
        &args.out,
        &cancel,
        &mut progress,
    )
    .await;
    ctrl_c.abort();
    let Ran {
        episode,
        transcript: path,
        goal_satisfied,
    } = result?;
    let s = &episode.summary;
    lines.say(&summary_line(&episode, goal_satisfied));
    lines.say(&format!("transcript: {}", path.display()));
    if let Some(t) = &recorded {
        match episode::check_replay(t, &episode) {
            Ok(()) => lines.say(&format!(
                "replay: all {} rounds match the recording",
                episode.rounds.len()
            )),
            Err(why) => {
                lines.say(&format!("replay: {why}"));
                return Ok(BACKEND_FAILED);
            }
        }
    }
    if args.json {
        println!(
            "{}",
            json!({
                "success": s.success,
                "status": s.status,
                "steps": s.steps,
                "gt_steps": s.gt_steps,
                "max_steps": s.max_steps,
                "llm_calls": s.llm_calls,
                "prompt_tokens": s.prompt_tokens,
                "completion_tokens": s.completion_tokens,
                "wall_ms": s.wall_ms,
                "error": s.error,
                "backend": backend.info(),
                "transcript": path.display().to_string(),
            })
        );
    }
    Ok(match s.status {
        Status::Success => 0,
        Status::Failure => FAILED,
        Status::BackendError => BACKEND_FAILED,
        Status::Interrupted => INTERRUPTED,
    })
}

/// The backend that answers the model's roles: the HTTP client when there is one, else
/// the simulated backend when error rates are given (seeded by `seed`), else the built-in
/// planner.
pub fn backend(
    http: Option<OpenAiClient>,
    sim_errors: Option<ErrorRates>,
    seed: Option<u64>,
    limits: &Limits,
) -> Result<Box<dyn Backend>, String> {
    Ok(match (http, sim_errors) {
        (Some(_), Some(_)) => {
            return Err(
                "simulated errors are for the simulated backend: leave out the endpoint".into(),
            );
        }
        (Some(client), None) => Box::new(client),
        (None, Some(rates)) => Box::new(BuiltinBackend::simulated(
            limits.clone(),
            rates,
            seed.unwrap_or(0),
        )),
        (None, None) => Box::new(BuiltinBackend::new(limits.clone())),
    })
}

/// An episode as it ran: the rounds and summary, where its transcript is, and whether
/// the goal holds at the end.
#[derive(Debug)]
pub struct Ran {
    pub episode: Episode,
    pub transcript: PathBuf,
    pub goal_satisfied: bool,
}

/// The environment an episode runs in: Rapier with `physics`, else the rules alone.
pub fn environment(
    task: &Arc<Task>,
    physics: bool,
) -> Result<Box<dyn Environment + Send>, coherent_sim::PhysicsError> {
    Ok(if physics {
        Box::new(coherent_sim::PhysicalEnv::new(Arc::clone(task))?)
    } else {
        Box::new(SymbolicEnv::new(Arc::clone(task)))
    })
}

/// Runs one episode as `coherent run` does, in `env` (see [`environment`]), writing its
/// transcript into `out`.
#[allow(clippy::too_many_arguments)]
pub async fn run_episode(
    task: &Arc<Task>,
    env: &mut (dyn Environment + Send),
    backend: &dyn Backend,
    settings: &Settings,
    budget: Budget,
    out: &Path,
    cancel: &Cancel,
    progress: &mut (dyn FnMut(&Round) + Send),
) -> Result<Ran, String> {
    let path = episode::transcript_path(out, task, settings.method);
    let episode = episode::run(
        task, env, backend, settings, budget, &path, cancel, progress,
    )
    .await?;
    Ok(Ran {
        episode,
        transcript: path,
        goal_satisfied: env.goal_satisfied(),
    })
}

/// The HTTP backend when an endpoint is configured.
fn http_backend(args: &RunArgs) -> Result<Option<OpenAiClient>, String> {
    let endpoint = Endpoint {
        base_url: args.base_url.clone(),
        api_key: args.api_key.clone().map(ApiKey::new),
        model: args.model.clone(),
        temperature: args.temperature,
        seed: args.seed,
        format: args.format.into(),
        patience: args.patience,
        requests: args.concurrency,
    };
    match endpoint.config()? {
        Some(config) => OpenAiClient::new(config)
            .map(Some)
            .map_err(|e| e.to_string()),
        None => Ok(None),
    }
}

fn backend_line(backend: &dyn Backend, replay: Option<&Path>) -> String {
    let info = backend.info();
    match (info.kind.as_str(), replay) {
        ("replay", Some(path)) => format!(
            "backend: replay of {} (recorded with model {}; no network)",
            path.display(),
            info.model
        ),
        ("simulated", _) => format!(
            "backend: simulated (the optimal planner with seeded mistakes: {}; not a language model)",
            info.model
                .trim_start_matches("optimal-planner with errors ")
        ),
        ("openai", _) => format!(
            "backend: OpenAI-compatible endpoint {} with model {}",
            info.base_url.unwrap_or_default(),
            info.model
        ),
        _ => "backend: built-in (the optimal planner plays the assigner and the executors; \
              to use a model, set OPENAI_BASE_URL, COHERENT_MODEL and OPENAI_API_KEY, \
              or pass --base-url, --model and --api-key)"
            .to_owned(),
    }
}

fn step_line(task: &Task, r: &Round, max: u32) -> String {
    let robot = r
        .proposal
        .as_ref()
        .and_then(|p| task.idx(p.robot))
        .map_or("-".to_owned(), |i| task.node(i).label());
    let action = r
        .decision
        .as_ref()
        .and_then(|d| d.action.clone())
        .unwrap_or_else(|| "-".to_owned());
    // The subtask in quotes, unless it is the action itself (the built-in backend's).
    let subtask = r
        .proposal
        .as_ref()
        .filter(|p| p.subtask != action)
        .map_or(String::new(), |p| format!("{:?}  ", p.subtask));
    let outcome = match &r.outcome {
        Outcome::Executed if r.done => "ok, goal reached".to_owned(),
        Outcome::Executed => "ok".to_owned(),
        Outcome::Infeasible { reason, .. } => format!("infeasible ({reason})"),
        Outcome::Declined => "declined".to_owned(),
        Outcome::NoProposal { why } => format!("no usable proposal: {why}"),
        Outcome::NoDecision { why } => format!("no usable decision: {why}"),
        Outcome::BackendError { message } => format!("backend failed: {message}"),
    };
    let width = max.to_string().len();
    format!(
        "step {:>width$}/{max}  {robot}  {subtask}{action}  -> {outcome}",
        r.step
    )
}

fn summary_line(e: &Episode, goal_satisfied: bool) -> String {
    let s = &e.summary;
    let result = match s.status {
        Status::Success => "success",
        Status::Failure => "failure: step budget spent",
        Status::BackendError => "stopped: the backend failed",
        Status::Interrupted => "interrupted",
    };
    let gt = s.gt_steps.map_or("-".to_owned(), |g| g.to_string());
    let goal = if goal_satisfied {
        "holds"
    } else {
        "not reached"
    };
    format!(
        "{result} | goal {goal} | steps {} (GT {gt}, budget {}) | LLM calls {} | tokens {} prompt + {} completion | wall {:.2} s",
        s.steps,
        s.max_steps,
        s.llm_calls,
        s.prompt_tokens,
        s.completion_tokens,
        s.wall_ms / 1e3
    )
}
