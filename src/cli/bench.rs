//! `coherent bench`: many methods on many tasks, concurrently and resumably, then the
//! paper's tables; `coherent bench --report FILE` prints the tables of a results file.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::args::{
    ExecutionFlag, LlmArgs, LoadMethod, PromptPriceArgs, RobotFlags, method_name, method_spec,
    sim_errors,
};
use super::signals::Stop;
use super::status;
use crate::session::backend::{BackendName, BackendRequest};
use crate::session::bench::{
    self as session_bench, BenchConfig, EpisodesRequest, TableFormat as Tables,
};
use crate::session::engine::{
    BenchOutcome, Cancel, DEFAULT_MAX_RESULTS_BYTES, DEFAULT_MAX_TRANSCRIPT_BYTES, Event,
    HISTORY_WINDOW, Limits, MIB, Progress, ReadLimits, ResultLine, Setting, Style, Subset,
    read_results_within, shown, shown_lines, transcripts_dir,
};
use crate::session::error::{BackendProblem, settings_differ};
use crate::session::{self, Error, prompts};

#[derive(Args)]
pub struct BenchArgs {
    /// Original env files, native task files, or a folder of them; `native`: the project's
    /// own benchmark, compiled in.
    #[arg(long, required_unless_present = "report")]
    tasks: Option<PathBuf>,
    /// `all` (every well-formed task), `paper40` (the paper's 40-task subset of its
    /// released tasks), `native40` (the 40-task subset of our own benchmark) or a FILE of
    /// `scene task_id` lines.
    #[arg(long, default_value = "all")]
    subset: String,
    /// Comma-separated methods: pefa, pefa-no-history, cmrs, dmrs-1d, dmrs-2d, mcts,
    /// llm-mcts, optimal, random, llm-pddl, or MODULE:CLASS, a method written in Python (a module or
    /// a .py file, and its class; from the Python package's `coherent` only).
    #[arg(long, value_delimiter = ',', required_unless_present = "report", value_parser = method_name)]
    methods: Vec<String>,
    /// Comma-separated: sequential (one robot's action a step, the paper's), parallel
    /// (joint steps, every robot at once), or both: each method runs in each, and the
    /// tables compare them.
    #[arg(long, value_delimiter = ',', value_enum, default_value = "sequential")]
    execution: Vec<ExecutionFlag>,
    /// Who answers the model-using methods; `auto`: an OpenAI-compatible endpoint when one
    /// is configured (flags or environment), else `simulated` with --sim-errors, else `builtin`;
    /// `replay`: the transcripts of --replay-from.
    #[arg(long, value_enum, default_value_t = BackendFlag::Auto)]
    backend: BackendFlag,
    /// With `--backend replay`: an earlier results file, whose episodes are replayed from
    /// their transcripts (no network) and checked against them.
    #[arg(long)]
    replay_from: Option<PathBuf>,
    /// The most a results file may hold (--out when resuming, --report, --replay-from),
    /// in MiB.
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_MAX_RESULTS_BYTES / MIB)]
    max_results_mib: u64,
    /// With `--backend replay`: the most each transcript may hold, in MiB.
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_MAX_TRANSCRIPT_BYTES / MIB)]
    max_transcript_mib: u64,
    /// The longest one step of a method written in Python may take, in seconds (its
    /// act, and making it at the first step); a longer step ends that episode as the
    /// method's error, and the run goes on.
    #[arg(long, value_name = "SECONDS")]
    step_timeout: Option<f64>,
    /// The simulated backend's error rates: `hallucinate=0.1,wrong_robot=0.1,malformed=0.1,suboptimal=0.1`
    /// or `all=0.1`; kinds not named are 0.
    #[arg(long)]
    sim_errors: Option<String>,
    /// Seeds per (method, task): seed indices 0..N.
    #[arg(long, default_value_t = 1)]
    seeds: u32,
    /// Episodes at once.
    #[arg(long, default_value_t = 4)]
    concurrency: usize,
    /// Results file (JSON lines), appended to; re-running skips finished episodes.
    #[arg(long, required_unless_present = "report")]
    out: Option<PathBuf>,
    /// Print the tables of this results file and run nothing (with --prices, its lines'
    /// tokens priced anew).
    #[arg(long, conflicts_with_all = ["tasks", "methods", "out", "prompts"])]
    report: Option<PathBuf>,
    /// Table format.
    #[arg(long, value_enum, default_value_t = TableFormat::Markdown)]
    format: TableFormat,
    /// Rounds of history the task assigner sees (executed actions for the baselines).
    #[arg(long, default_value_t = HISTORY_WINDOW)]
    history: usize,
    /// Most states one search of the built-in planner may visit.
    #[arg(long, default_value_t = Limits::DEFAULT_MAX_STATES)]
    max_states: usize,
    /// Step budget of every episode; by default 2 x the task's ground truth (2 x the
    /// optimum without one).
    #[arg(long)]
    max_steps: Option<u32>,
    /// Execute every action in Rapier too; a physical failure is an infeasible step
    /// whose message has the numbers.
    #[arg(long)]
    physics: bool,
    #[command(flatten)]
    robots: RobotFlags,
    #[command(flatten)]
    llm: LlmArgs,
    #[command(flatten)]
    inputs: PromptPriceArgs,
    /// The old spelling of --seed (hidden; for one release).
    #[arg(long = "llm-seed", hide = true)]
    old_llm_seed: Option<u64>,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendFlag {
    Auto,
    Builtin,
    Simulated,
    Openai,
    Replay,
}

#[derive(Clone, Copy, ValueEnum)]
enum TableFormat {
    Markdown,
    Csv,
    Json,
}

impl BenchArgs {
    /// What `--max-results-mib` and `--max-transcript-mib` allow.
    fn limits(&self) -> ReadLimits {
        ReadLimits {
            results_bytes: self.max_results_mib.saturating_mul(MIB),
            transcript_bytes: self.max_transcript_mib.saturating_mul(MIB),
        }
    }
}

pub fn bench(mut args: BenchArgs, load: Option<&LoadMethod<'_>>) -> Result<u8, Error> {
    if let Some(path) = &args.report {
        let file = read_results_within(path, args.limits().results_bytes)?;
        if file.truncated_bytes > 0 {
            eprintln!(
                "note: {}: the last line is cut off ({} bytes) and is ignored",
                path.display(),
                file.truncated_bytes
            );
        }
        let mut lines = file.lines;
        if args.inputs.prices.is_some() {
            lines = session_bench::priced(lines, args.inputs.price_source())?;
        }
        print_tables(&lines, args.format);
        return Ok(status::OK);
    }
    if let Some(seed) = args.old_llm_seed {
        args.llm.seed = Some(seed);
    }
    session::block_on(run_async(args, load))?.map_err(with_flags)
}

/// ` (2 with the method's error, 3 not started, 1 interrupted or a backend error)`, the
/// kinds of unfinished episodes there are; empty without any.
fn unfinished_detail(o: &BenchOutcome) -> String {
    let others = o.unfinished - o.method_errors - o.not_started;
    let parts: Vec<String> = [
        (o.method_errors, "with the method's error"),
        (others, "interrupted or a backend error"),
        (o.not_started, "not started"),
    ]
    .iter()
    .filter(|(n, _)| *n > 0)
    .map(|(n, what)| format!("{n} {what}"))
    .collect();
    if parts.is_empty() {
        String::new()
    } else {
        format!(" ({})", parts.join(", "))
    }
}

/// `e`, the settings of a results file named by the flags that set them.
fn with_flags(e: Error) -> Error {
    let Error::SettingsDiffer { file, differences } = &e else {
        return e;
    };
    Error::Invalid(settings_differ(
        file,
        differences,
        |s| flag_of(s).into(),
        "--out",
    ))
}

/// The flag of `coherent bench` that sets `setting`.
fn flag_of(setting: Setting) -> &'static str {
    match setting {
        Setting::Backend => "--backend",
        Setting::Model => "--model",
        Setting::SimErrors => "--sim-errors",
        Setting::Temperature => "--temperature",
        Setting::ModelSeed => "--seed",
        Setting::Seeds => "--seeds",
        Setting::Prompts => "--prompts",
        Setting::History => "--history",
        Setting::MaxSteps => "--max-steps",
        Setting::MaxStates => "--max-states",
        Setting::Physics => "--physics",
        Setting::Robots => "--robots",
        Setting::Execution => "--execution",
        Setting::Version => "coherent's version",
        Setting::Method => "the method's own settings",
        Setting::Unrecorded => "settings",
    }
}

fn print_tables(lines: &[ResultLine], format: TableFormat) {
    let format = match format {
        TableFormat::Markdown => Tables::Markdown,
        TableFormat::Csv => Tables::Csv,
        TableFormat::Json => Tables::Json,
    };
    let mut text = session_bench::tables_by_run(lines, format);
    if format == Tables::Json {
        text.push('\n');
    }
    let _ = std::io::stdout().write_all(text.as_bytes());
}

/// The episodes' settings the flags ask for.
fn episodes(args: &BenchArgs, load: Option<&LoadMethod<'_>>) -> Result<EpisodesRequest, Error> {
    // A replay runs the recorded methods: one written in Python needs no code then.
    let replay_from = match args.backend {
        BackendFlag::Replay => args.replay_from.as_deref().map(|p| (p, args.limits())),
        _ => None,
    };
    let methods = args
        .methods
        .iter()
        .map(|m| method_spec(m, load, args.step_timeout, replay_from))
        .collect::<Result<Vec<_>, _>>()?;
    if args.seeds == 0 {
        return Err(Error::Invalid("--seeds must be at least 1".into()));
    }
    // Before anything else: a bad template must cost no model call.
    if args.backend == BackendFlag::Replay {
        args.inputs.no_prompts_for_a_replay("--backend replay")?;
    }
    Ok(EpisodesRequest {
        backend: BackendRequest {
            name: match args.backend {
                BackendFlag::Auto => BackendName::Auto,
                BackendFlag::Builtin => BackendName::Builtin,
                BackendFlag::Simulated => BackendName::Simulated,
                BackendFlag::Openai => BackendName::OpenAi,
                BackendFlag::Replay => BackendName::Replay,
            },
            endpoint: args.llm.endpoint()?,
            sim_errors: sim_errors(args.sim_errors.as_deref())?,
            replay_from: args.replay_from.clone(),
            limits: args.limits(),
        },
        prompts: args.inputs.prompt_source(),
        prices: args.inputs.price_source(),
        history: args.history,
        max_states: args.max_states,
        max_steps: args.max_steps,
        physics: args.physics,
        robots: args.robots.robots()?,
        executions: args.execution.iter().map(|&e| e.into()).collect(),
        ..EpisodesRequest::new(methods)
    })
}

async fn run_async(args: BenchArgs, load: Option<&LoadMethod<'_>>) -> Result<u8, Error> {
    let (Some(tasks_path), Some(out)) = (&args.tasks, &args.out) else {
        return Err(Error::Invalid(
            "--tasks, --methods and --out are needed to run".into(),
        ));
    };
    let settings = episodes(&args, load)?.prepare().map_err(worded)?;
    let subset = session_bench::subset(&args.subset)?;
    let chosen = session_bench::choose(tasks_path, &subset)?;
    for e in &chosen.malformed {
        eprintln!("skipped a malformed task: {}", shown_lines(&e.to_string()));
    }
    let malformed = chosen.malformed.len();
    let selection = chosen.selection;
    let name = match &subset {
        Subset::All => "all".to_owned(),
        Subset::Paper40 => "paper40".to_owned(),
        Subset::Listed(pairs) => format!("{} ({} listed)", args.subset, pairs.len()),
    };
    let wanted = selection.tasks.len() + selection.missing.len();
    println!(
        "tasks: {} of subset {name} present{}",
        selection.tasks.len(),
        if malformed > 0 {
            format!(" ({malformed} malformed tasks skipped)")
        } else {
            String::new()
        }
    );
    if !selection.missing.is_empty() {
        let listed: Vec<String> = selection
            .missing
            .iter()
            .map(|(s, id)| format!("{} task {id}", shown(s)))
            .collect();
        println!(
            "missing: {} of {wanted} are not in {}: {}",
            selection.missing.len(),
            tasks_path.display(),
            listed.join(", ")
        );
    }
    if selection.tasks.is_empty() {
        return Err(Error::Invalid("no tasks to run".into()));
    }
    let config = BenchConfig {
        episodes: settings,
        seeds: args.seeds,
        concurrency: args.concurrency.max(1),
        out: out.clone(),
        max_results_bytes: args.limits().results_bytes,
    };
    let info = config.episodes.backend.info();
    println!(
        "backend: {} ({}){}",
        info.kind,
        shown(&info.model),
        info.base_url
            .map_or(String::new(), |u| format!(" at {}", shown(&u)))
    );
    if let Some(line) = prompts::describe(&config.episodes.prompts, &config.episodes.executions) {
        println!("{line}");
    }
    if let Some(dir) = &args.inputs.prompts {
        for warning in prompts::blank_warnings(dir, &config.episodes.prompts) {
            eprintln!("warning: {}", shown(&warning));
        }
    }
    if let Some(note) = config.concurrency_note() {
        eprintln!("note: {note}");
    }
    let cancel = Cancel::default();
    let stop = Stop::watch(&cancel);
    let terminal = std::io::stderr().is_terminal();
    let mut progress = Progress::new(if terminal { Style::Bar } else { Style::Lines });
    let mut show = |e: Event<'_>| {
        if let Some(text) = progress.line(&e) {
            let mut err = std::io::stderr();
            let _ = err.write_all(text.as_bytes());
            let _ = err.flush();
        }
    };
    let result = session_bench::run(&selection.tasks, &config, &cancel, &mut show).await;
    if terminal {
        eprintln!();
    }
    let outcome = result?;
    if let Some(first) = outcome.orphaned.first() {
        eprintln!(
            "note: {} transcripts of episodes killed mid-run had no results line; renamed to \
             *.jsonl.unfinished (e.g. {}), and their episodes ran again",
            outcome.orphaned.len(),
            shown(&first.display().to_string())
        );
    }
    if outcome.repaired_bytes > 0 {
        eprintln!(
            "note: {}: dropped a last line cut off mid-write ({} bytes)",
            out.display(),
            outcome.repaired_bytes
        );
    }
    for why in &outcome.skipped_tasks {
        eprintln!("skipped: {}", shown(why));
    }
    println!(
        "{} episodes: {} already finished, {} finished now, {} unfinished{}; results in {}, transcripts in {}",
        outcome.total,
        outcome.skipped,
        outcome.finished,
        outcome.unfinished,
        unfinished_detail(&outcome),
        out.display(),
        transcripts_dir(out).display()
    );
    let lines = read_results_within(out, args.limits().results_bytes)?.lines;
    print_tables(&lines, args.format);
    if outcome.interrupted {
        eprintln!("interrupted: re-run the same command to finish the rest");
        return Ok(stop.status());
    }
    Ok(status::OK)
}

/// `e`, a backend problem worded with the flags that set it.
fn worded(e: Error) -> Error {
    let Error::Backend(problem) = e else { return e };
    Error::Invalid(
        match problem {
            BackendProblem::RatesNeedSimulated | BackendProblem::RatesAndEndpoint => {
                "--sim-errors needs --backend simulated"
            }
            BackendProblem::ReplayNeedsFile | BackendProblem::FileNeedsReplay => {
                "--backend replay and --replay-from FILE go together"
            }
            BackendProblem::NoEndpoint => {
                "--backend openai needs an endpoint: --base-url or OPENAI_BASE_URL, and a model (--model or COHERENT_MODEL)"
            }
            BackendProblem::ReplayIsForBenchmarks => return Error::Backend(problem),
        }
        .into(),
    )
}
