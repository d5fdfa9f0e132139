//! `coherent bench`: many methods on many tasks, concurrently and resumably, then the
//! paper's tables; `coherent bench --report FILE` prints the tables of a results file.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::Arc;

use clap::{Args, ValueEnum};
use coherent_agents::bench::{self, BackendChoice, BenchConfig, Event, Progress, Recorded, Subset};
use coherent_agents::episode::Method;
use coherent_agents::{ApiKey, Cancel, OpenAiClient, report};
use coherent_core::planner::Limits;

use super::llm::{AnswerFormat, Endpoint, Patience, sim_errors};
use super::method_names;

/// Exit status after Ctrl-C, as shells report SIGINT.
const INTERRUPTED: u8 = 130;

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
    /// Comma-separated methods.
    #[arg(long, value_delimiter = ',', required_unless_present = "report", value_parser = method_names())]
    methods: Vec<String>,
    /// Who answers the model-using methods; `auto`: an OpenAI-compatible endpoint when one
    /// is configured (flags or environment), else `simulated` with --sim-errors, else `builtin`;
    /// `replay`: the transcripts of --replay-from.
    #[arg(long, value_enum, default_value_t = BackendKind::Auto)]
    backend: BackendKind,
    /// With `--backend replay`: an earlier results file, whose episodes are replayed from
    /// their transcripts (no network) and checked against them.
    #[arg(long)]
    replay_from: Option<PathBuf>,
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
    /// Print the tables of this results file and run nothing.
    #[arg(long, conflicts_with_all = ["tasks", "methods", "out"])]
    report: Option<PathBuf>,
    /// Table format.
    #[arg(long, value_enum, default_value_t = TableFormat::Markdown)]
    format: TableFormat,
    /// Rounds of history the task assigner sees (executed actions for the baselines).
    #[arg(long, default_value_t = 5)]
    history: usize,
    /// Most states one search of the built-in planner may visit.
    #[arg(long, default_value_t = Limits::DEFAULT_MAX_STATES)]
    max_states: usize,
    #[command(flatten)]
    llm: LlmArgs,
}

/// How to reach an OpenAI-compatible endpoint, as for `coherent run`.
#[derive(Args)]
struct LlmArgs {
    /// OpenAI-compatible endpoint up to the version [env: OPENAI_BASE_URL]
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
    /// The model's sampling seed (sent to the server).
    #[arg(long)]
    llm_seed: Option<u64>,
    /// Answer format asked for first; a server that refuses it gets the next one.
    #[arg(long, value_enum, default_value_t = AnswerFormat::JsonSchema)]
    answer_format: AnswerFormat,
    #[command(flatten)]
    patience: Patience,
    /// Requests in flight at once, across all episodes.
    #[arg(long, default_value_t = 4)]
    requests: usize,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendKind {
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

pub fn bench(args: BenchArgs) -> Result<u8, String> {
    if let Some(path) = &args.report {
        let file = bench::read_results(path)?;
        if file.truncated_bytes > 0 {
            eprintln!(
                "note: {}: the last line is cut off ({} bytes) and is ignored",
                path.display(),
                file.truncated_bytes
            );
        }
        print_tables(&file.lines, args.format);
        return Ok(0);
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the async runtime: {e}"))?;
    runtime.block_on(run_async(args))
}

fn print_tables(lines: &[bench::ResultLine], format: TableFormat) {
    let r = report::build(lines);
    let text = match format {
        TableFormat::Markdown => report::markdown(&r),
        TableFormat::Csv => report::csv(&r),
        TableFormat::Json => report::json(&r) + "\n",
    };
    let _ = std::io::stdout().write_all(text.as_bytes());
}

async fn run_async(args: BenchArgs) -> Result<u8, String> {
    let (Some(tasks_path), Some(out)) = (&args.tasks, &args.out) else {
        return Err("--tasks, --methods and --out are needed to run".into());
    };
    let methods: Vec<Method> = args
        .methods
        .iter()
        .map(|m| Method::from_name(m).ok_or_else(|| format!("unknown method {m:?}")))
        .collect::<Result<_, _>>()?;
    if args.seeds == 0 {
        return Err("--seeds must be at least 1".into());
    }
    let backend = backend(&args)?;
    let subset = match Subset::named(&args.subset) {
        Some(named) => named,
        None => Subset::read_file(std::path::Path::new(&args.subset))?,
    };
    let mut tasks = Vec::new();
    let mut malformed = 0;
    for r in super::read_tasks(tasks_path).map_err(|e| e.to_string())? {
        match r {
            Ok(t) => tasks.push(t),
            Err(e) => {
                malformed += 1;
                eprintln!("skipped a malformed task: {e}");
            }
        }
    }
    let selection = bench::select(tasks, &subset)?;
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
            .map(|(s, id)| format!("{s} task {id}"))
            .collect();
        println!(
            "missing: {} of {wanted} are not in {}: {}",
            selection.missing.len(),
            tasks_path.display(),
            listed.join(", ")
        );
    }
    if selection.tasks.is_empty() {
        return Err("no tasks to run".into());
    }
    let config = BenchConfig {
        methods,
        seeds: args.seeds,
        concurrency: args.concurrency.max(1),
        history: args.history,
        temperature: matches!(backend, BackendChoice::OpenAi(_)).then_some(args.llm.temperature),
        max_states: args.max_states,
        out: out.clone(),
        backend,
    };
    let info = config.backend.info();
    println!(
        "backend: {} ({}){}",
        info.kind,
        info.model,
        info.base_url.map_or(String::new(), |u| format!(" at {u}"))
    );
    let cancel = Cancel::default();
    let ctrl_c = {
        let cancel = cancel.clone();
        tokio::spawn(async move {
            if tokio::signal::ctrl_c().await.is_ok() {
                cancel.cancel();
            }
        })
    };
    let terminal = std::io::stderr().is_terminal();
    let mut progress = Progress::new(terminal);
    let mut show = |e: Event<'_>| {
        if let Some(text) = progress.line(&e) {
            let mut err = std::io::stderr();
            let _ = err.write_all(text.as_bytes());
            let _ = err.flush();
        }
    };
    let result = bench::run(&selection.tasks, &config, &cancel, &mut show).await;
    ctrl_c.abort();
    if terminal {
        eprintln!();
    }
    let outcome = result?;
    if outcome.repaired_bytes > 0 {
        eprintln!(
            "note: {}: dropped a last line cut off mid-write ({} bytes)",
            out.display(),
            outcome.repaired_bytes
        );
    }
    for why in &outcome.skipped_tasks {
        eprintln!("skipped: {why}");
    }
    println!(
        "{} episodes: {} already finished, {} run now, {} unfinished; results in {}, transcripts in {}",
        outcome.total,
        outcome.skipped,
        outcome.written,
        outcome.unfinished,
        out.display(),
        bench::transcripts_dir(out).display()
    );
    let lines = bench::read_results(out)?.lines;
    print_tables(&lines, args.format);
    if outcome.interrupted {
        eprintln!("interrupted: re-run the same command to finish the rest");
        return Ok(INTERRUPTED);
    }
    Ok(0)
}

/// The backend the flags and environment ask for.
fn backend(args: &BenchArgs) -> Result<BackendChoice, String> {
    let rates = sim_errors(args.sim_errors.as_deref())?;
    let l = &args.llm;
    let http = Endpoint {
        base_url: l.base_url.clone(),
        api_key: l.api_key.clone().map(ApiKey::new),
        model: l.model.clone(),
        temperature: l.temperature,
        seed: l.llm_seed,
        format: l.answer_format.into(),
        patience: l.patience,
        requests: l.requests,
    }
    .config()?;
    let kind = match args.backend {
        BackendKind::Auto if rates.is_some() => BackendKind::Simulated,
        BackendKind::Auto if http.is_some() => BackendKind::Openai,
        BackendKind::Auto => BackendKind::Builtin,
        k => k,
    };
    if rates.is_some() && kind != BackendKind::Simulated {
        return Err("--sim-errors needs --backend simulated".into());
    }
    Ok(match (kind, &args.replay_from) {
        (BackendKind::Replay, Some(file)) => BackendChoice::Replay(Arc::new(Recorded::read(file)?)),
        (BackendKind::Replay, None) | (_, Some(_)) => {
            return Err("--backend replay and --replay-from FILE go together".into());
        }
        (BackendKind::Simulated, None) => BackendChoice::Simulated(rates.unwrap_or_default()),
        (BackendKind::Openai, None) => {
            let config = http.ok_or(
                "--backend openai needs an endpoint: --base-url or OPENAI_BASE_URL, and a model (--model or COHERENT_MODEL)",
            )?;
            BackendChoice::OpenAi(Arc::new(
                OpenAiClient::new(config).map_err(|e| e.to_string())?,
            ))
        }
        (BackendKind::Auto | BackendKind::Builtin, None) => BackendChoice::Builtin,
    })
}
