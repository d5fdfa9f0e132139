//! `coherent run`: one episode of a planning method on one task, one line per step, a
//! summary, and a transcript. The episode itself is the session layer's
//! ([`crate::session::episode`]); this file has the flags and the printing.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use clap::Args;
use serde_json::json;

use super::args::{
    AnswerFormat, ExecutionFlag, LlmArgs, LoadMethod, PromptPriceArgs, RobotFlags, method_name,
    method_spec, sim_errors,
};
use super::signals::Stop;
use super::status;
use crate::session::backend::{BackendChoice, BackendRequest};
use crate::session::engine::{
    Budget, Cancel, DEFAULT_MAX_TRANSCRIPT_BYTES, Execution, HISTORY_WINDOW, Limits, MIB,
    MethodSpec, Round, Status, Summary, executed_actions, shown, worth_a_line,
};
use crate::session::episode::{Ending, Prepared, ReplayRequest, RunRequest};
use crate::session::events::EventsSource;
use crate::session::tasks::TaskSource;
use crate::session::waiting::{SLOW, Waiting, waiting_text};
use crate::session::{self, Error, prompts};

#[derive(Args)]
pub(crate) struct RunArgs {
    /// A native task file, or an original env file with --task (not needed with --replay).
    #[arg(required_unless_present = "replay")]
    task_file: Option<PathBuf>,
    /// Which task of the file (its task_id).
    #[arg(long = "task")]
    task_id: Option<i64>,
    /// The planning method: pefa, pefa-no-history, cmrs, dmrs-1d, dmrs-2d, mcts,
    /// llm-mcts, optimal, random, llm-pddl, or MODULE:CLASS, a method written in Python (a module or
    /// a .py file, and its class; from the Python package's `coherent` only).
    #[arg(long, default_value = "pefa", value_parser = method_name)]
    method: String,
    /// sequential: one robot's action a step, as in the paper; parallel: joint steps, every
    /// robot at most one action, all at once (the budget is then 2 x the fewest joint
    /// steps).
    #[arg(long, value_enum, default_value_t = ExecutionFlag::Sequential)]
    execution: ExecutionFlag,
    /// The longest one step of a method written in Python may take, in seconds (its
    /// act, and making it at the first step); a longer step ends as the method's error.
    #[arg(long, value_name = "SECONDS")]
    step_timeout: Option<f64>,
    /// Rounds of history the task assigner sees; 0 is the paper's "w/o history".
    #[arg(long, default_value_t = HISTORY_WINDOW)]
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
    /// With --replay: the most the transcript may hold, in MiB.
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_MAX_TRANSCRIPT_BYTES / MIB)]
    max_transcript_mib: u64,
    /// Print a JSON summary on stdout (step lines go to stderr).
    #[arg(long)]
    json: bool,
    /// Execute every action in Rapier too; a physical failure is an infeasible step
    /// whose message has the numbers.
    #[arg(long)]
    physics: bool,
    #[command(flatten)]
    llm: LlmArgs,
    #[command(flatten)]
    inputs: PromptPriceArgs,
    #[command(flatten)]
    robots: RobotFlags,
    /// The old spelling of --answer-format (hidden; for one release).
    #[arg(long = "format", value_enum, hide = true)]
    old_format: Option<AnswerFormat>,
    /// The old spelling of --requests (hidden; for one release).
    #[arg(long = "concurrency", hide = true)]
    old_concurrency: Option<usize>,
    /// Without an endpoint: the simulated backend instead of the built-in one, making
    /// these mistakes (`hallucinate=0.1,wrong_robot=0.1,malformed=0.1,suboptimal=0.1`,
    /// or `all=0.1`), seeded by --seed.
    #[arg(long)]
    sim_errors: Option<String>,
    /// Most states one search of the built-in planner may visit.
    #[arg(long, default_value_t = Limits::DEFAULT_MAX_STATES)]
    max_states: usize,
    /// Events that happen mid-task (a robot down, a thing moved, the goal changed, a door
    /// locked, failing actions), in place of the task file's: a JSON list, or an object
    /// with an `events` list (docs/dynamic.md)
    #[arg(long, value_name = "FILE")]
    events: Option<PathBuf>,
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

pub(crate) fn run(mut args: RunArgs, load: Option<&LoadMethod<'_>>) -> Result<u8, Error> {
    if let Some(format) = args.old_format {
        args.llm.answer_format = format;
    }
    if let Some(n) = args.old_concurrency {
        args.llm.requests = n;
    }
    let cancel = Cancel::default();
    let prepared = prepare(&args, &cancel, load)?;
    session::block_on(run_prepared(prepared, &args, cancel))?
}

/// The episode the flags ask for, ready to run: a replay of a transcript, or a new one.
fn prepare(
    args: &RunArgs,
    cancel: &Cancel,
    load: Option<&LoadMethod<'_>>,
) -> Result<Prepared, Error> {
    let task = args.task_file.as_ref().map(|file| TaskSource::File {
        path: file.clone(),
        task_id: args.task_id,
    });
    if let Some(transcript) = &args.replay {
        args.inputs.no_prompts_for_a_replay("--replay")?;
        if args.events.is_some() {
            return Err(Error::Invalid(
                "--replay runs the episode as recorded, events included: --events does not go \
                 with it"
                    .into(),
            ));
        }
        if args.execution != ExecutionFlag::Sequential {
            return Err(Error::Invalid(
                "--replay runs the episode as recorded: --execution does not go with it".into(),
            ));
        }
        let request = ReplayRequest {
            transcript: transcript.clone(),
            task,
            prices: args.inputs.price_source(),
            out: args.out.clone(),
            max_bytes: args.max_transcript_mib.saturating_mul(MIB),
        };
        return request.prepare();
    }
    let task =
        task.ok_or_else(|| Error::Invalid("a task file is needed without --replay".into()))?;
    let request = RunRequest {
        backend: BackendRequest {
            endpoint: args.llm.endpoint()?,
            sim_errors: sim_errors(args.sim_errors.as_deref())?,
            ..BackendRequest::default()
        },
        prompts: args.inputs.prompt_source(),
        prices: args.inputs.price_source(),
        robots: args.robots.robots()?,
        physics: args.physics,
        max_steps: args.max_steps,
        history: args.history,
        seed: args.llm.seed,
        max_states: args.max_states,
        out: args.out.clone(),
        execution: args.execution.into(),
        events: args.events.clone().map(EventsSource::File),
        ..RunRequest::new(
            task,
            method_spec(&args.method, load, args.step_timeout, None)?,
        )
    };
    request.prepare(cancel)
}

async fn run_prepared(prepared: Prepared, args: &RunArgs, cancel: Cancel) -> Result<u8, Error> {
    let lines = Lines { json: args.json };
    let info = prepared.backend_info();
    let method = &prepared.settings().method;
    lines.say(&match method {
        _ if method.asks_backend() => backend_line(&prepared),
        MethodSpec::External(_) => format!(
            "backend: none ({} is a method written in Python: the models it calls are its own)",
            shown(method.name())
        ),
        MethodSpec::Builtin(_) => format!("backend: none ({} asks no model)", method.name()),
    });
    lines.say(&task_line(&prepared));
    let settings = prepared.settings();
    if let Some(line) = prompts::describe(&settings.prompts, &[settings.execution]) {
        lines.say(&line);
    }
    if let Some(dir) = &args.inputs.prompts {
        for warning in prompts::blank_warnings(dir, &prepared.settings().prompts) {
            eprintln!("warning: {}", shown(&warning));
        }
    }
    let stop = Stop::watch(&cancel);
    let task = Arc::clone(prepared.task());
    let max = prepared.budget().steps();
    let execution = prepared.settings().execution;
    let mut prepared = prepared;
    let drawn = Arc::new(AtomicBool::new(false));
    let ticker = tokio::spawn(tell_waiting(prepared.watch(), Arc::clone(&drawn)));
    let mut progress = |r: &Round| {
        // A step ends the wait: its line, if drawn in place, goes first.
        if drawn.swap(false, Ordering::Relaxed) {
            eprint!("\r\x1b[2K");
        }
        for line in session::lines::round(&task, r, max, execution) {
            lines.say(&line);
        }
    };
    let result = prepared.run(&cancel, &mut progress).await;
    ticker.abort();
    if drawn.swap(false, Ordering::Relaxed) {
        eprint!("\r\x1b[2K");
    }
    let ran = result?;
    let s = ran.summary();
    let actions = executed_actions(&ran.transcript.rounds);
    lines.say(&summary_line(
        s,
        execution,
        actions,
        ran.goal_satisfied,
        ran.cost_usd,
    ));
    lines.say(&format!(
        "transcript: {}",
        shown(&ran.path.display().to_string())
    ));
    let ending = ran.ending();
    match &ending {
        Ending::ReplayDiffers(why) => lines.say(&format!("replay: {}", shown(why))),
        _ if ran.replay.is_some() => lines.say(&format!(
            "replay: all {} rounds match the recording",
            ran.transcript.rounds.len()
        )),
        _ => {}
    }
    if args.json && !matches!(ending, Ending::ReplayDiffers(_)) {
        println!(
            "{}",
            json!({
                "success": s.success,
                "status": s.status,
                "execution": execution,
                "steps": s.steps,
                "makespan": s.success.then_some(s.steps),
                "actions": actions,
                "gt_steps": s.gt_steps,
                "max_steps": s.max_steps,
                "llm_calls": s.llm_calls,
                "prompt_tokens": s.prompt_tokens,
                "completion_tokens": s.completion_tokens,
                "cached_tokens": s.cached_tokens,
                "cost_usd": ran.cost_usd,
                "wall_ms": s.wall_ms,
                "sim_seconds": s.sim_seconds,
                "error": s.error,
                "backend": info,
                "transcript": ran.path.display().to_string(),
            })
        );
    }
    Ok(match ending {
        // Ctrl-C or SIGTERM: the status the shell gives the signal.
        Ending::Interrupted => stop.status(),
        other => status::of_ending(&other),
    })
}

/// Says on stderr, once a second, which model call the episode waits for once it has
/// run for [`SLOW`]: on a terminal one line redrawn in place (`drawn` says it is there),
/// in a log a line after 5, 15 and 30 s, then every minute.
async fn tell_waiting(waiting: Arc<Waiting>, drawn: Arc<AtomicBool>) {
    let terminal = std::io::stderr().is_terminal();
    let mut tick = tokio::time::interval(Duration::from_secs(1));
    let mut told = 0;
    loop {
        tick.tick().await;
        let Some(longest) = waiting.longest().filter(|l| l.waited >= SLOW) else {
            told = 0;
            continue;
        };
        let text = waiting_text(&longest);
        let secs = longest.waited.as_secs();
        if terminal {
            eprint!("\r\x1b[2K{text}...");
            drawn.store(true, Ordering::Relaxed);
        } else if worth_a_line(secs, told) {
            eprintln!("{text}...");
            told = secs;
        }
    }
}

fn task_line(p: &Prepared) -> String {
    let task = p.task();
    let gt = task
        .meta
        .gt_steps
        .map_or("none".to_owned(), |g| g.to_string());
    let budget_note = match p.budget() {
        Budget::TwiceGroundTruth(n) => format!("{n} steps (2 x GT)"),
        Budget::Given(n) => format!("{n} steps"),
        Budget::TwiceOptimum(n) => format!("{n} steps (no GT: 2 x the planner's optimum)"),
        Budget::TwiceMakespan(n) => format!("{n} joint steps (2 x the optimal makespan)"),
        Budget::TwiceMakespanBound(n) => format!(
            "{n} joint steps (2 x the best makespan found; the search stopped before proving it)"
        ),
    };
    let execution = match p.settings().execution {
        Execution::Sequential => String::new(),
        Execution::Parallel => " | execution parallel".to_owned(),
    };
    format!(
        "task: {} task {} \"{}\" | method {}{execution} | GT {gt} | budget {budget_note}",
        shown(&task.meta.scene),
        task.meta.task_id,
        shown(&task.meta.instruction),
        shown(p.settings().method.name())
    )
}

fn backend_line(p: &Prepared) -> String {
    let info = p.backend_info();
    match (p.backend_choice(), p.replaying()) {
        (_, Some(path)) => replay_line(path, &info.model),
        (Some(BackendChoice::Simulated(rates)), _) => format!(
            "backend: simulated (the optimal planner with seeded mistakes: {}; not a language model)",
            shown(&rates.label())
        ),
        (Some(BackendChoice::OpenAi(_)), _) => format!(
            "backend: OpenAI-compatible endpoint {} with model {}",
            shown(&info.base_url.clone().unwrap_or_default()),
            shown(&info.model)
        ),
        _ => "backend: built-in (the optimal planner plays the assigner and the executors; \
              to use a model, set OPENAI_BASE_URL, COHERENT_MODEL and OPENAI_API_KEY, \
              or pass --base-url, --model and --api-key)"
            .to_owned(),
    }
}

fn replay_line(path: &Path, model: &str) -> String {
    format!(
        "backend: replay of {} (recorded with model {}; no network)",
        shown(&path.display().to_string()),
        shown(model)
    )
}

fn summary_line(
    s: &Summary,
    execution: Execution,
    actions: u32,
    goal_satisfied: bool,
    cost_usd: Option<f64>,
) -> String {
    let result = match (s.status, &s.error) {
        (Status::Success, _) => "success".to_owned(),
        (Status::Failure, _) => "failure: step budget spent".to_owned(),
        (Status::BackendError, _) => "stopped: the backend failed".to_owned(),
        // Stopped by the environment, not by a signal: what happened (a robot's
        // silence, say).
        (Status::Interrupted, Some(why)) => format!("stopped: {}", shown(why)),
        (Status::Interrupted, None) => "interrupted".to_owned(),
        (Status::Error, _) => "stopped: the method raised an error".to_owned(),
        (Status::Conceded, _) => {
            "right: an event put the goal out of reach, and the team stopped".to_owned()
        }
    };
    let gt = s.gt_steps.map_or("-".to_owned(), |g| g.to_string());
    let goal = if goal_satisfied {
        "holds"
    } else {
        "not reached"
    };
    // A price for the model, and calls to price.
    let cost = cost_usd
        .filter(|_| s.llm_calls > 0)
        .map_or(String::new(), |c| format!(" | cost ${c:.6}"));
    let steps = match execution {
        Execution::Sequential => format!("steps {} (GT {gt}, budget {})", s.steps, s.max_steps),
        Execution::Parallel => format!(
            "makespan {} joint steps, {actions} actions (GT {gt} sequential steps, budget {})",
            s.steps, s.max_steps
        ),
    };
    let sim = s
        .sim_seconds
        .map_or(String::new(), |t| format!(" | simulated {t:.2} s"));
    // With events: what the episode is measured against (docs/dynamic.md).
    let steps = match s.reference.as_deref() {
        None => steps,
        Some(r) => match (r.steps, &r.unreachable) {
            (Some(n), _) => format!("{steps} | reference {n}"),
            (None, Some(why)) => format!("{steps} | reference: out of reach ({})", shown(why)),
            (None, None) => format!("{steps} | reference unknown"),
        },
    };
    // The cached part, which the cost prices apart, so that it can be checked by hand.
    let cached = if s.cached_tokens > 0 {
        format!(" ({} cached)", s.cached_tokens)
    } else {
        String::new()
    };
    format!(
        "{result} | goal {goal} | {steps} | LLM calls {} | tokens {} prompt{cached} + {} completion{cost}{sim} | wall {:.2} s",
        s.llm_calls,
        s.prompt_tokens,
        s.completion_tokens,
        s.wall_ms / 1e3
    )
}
