//! `coherent export`: tasks written in another format, PDDL (docs/pddl.md) or the
//! paper's own env lists (docs/task-format.md); `coherent export sft`, training data
//! for a method's models from the optimal planner (docs/training.md).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, Subcommand, ValueEnum};

use super::args::{ExecutionFlag, sim_errors};
use super::signals::Stop;
use super::{pddl, status};
use crate::session::engine::{Builtin, Cancel, HISTORY_WINDOW, Limits, Task, clock, shown};
use crate::session::prompts::PromptSource;
use crate::session::training::{SftRequest, export as export_sft, split_shares};
use crate::session::{self, Error, check};

/// `coherent export`: tasks in another format, or (`sft`) training data.
#[derive(Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct ExportCommand {
    #[command(subcommand)]
    pub data: Option<ExportData>,
    #[command(flatten)]
    pub tasks: Option<ExportArgs>,
}

/// What `coherent export` writes besides tasks.
#[derive(Subcommand)]
pub enum ExportData {
    /// Training data for a method's models: every question its roles ask in episodes
    /// on the tasks given (with the optimal planner's answers, and with the simulated
    /// backend's mistakes), each answered by the optimal planner from the state it was
    /// asked in, in the method's answer format; chat JSONL in train, validation and
    /// test splits by scene, with a datasheet (docs/training.md). Exit 2 on bad input,
    /// 130 on Ctrl-C (nothing half written is left).
    Sft(Box<SftArgs>),
}

#[derive(Args)]
pub struct SftArgs {
    /// Original env files, native task files, generated sets' folders (their splits are
    /// kept) or folders of tasks; `native`: the project's own benchmark.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// The method whose questions are asked: pefa, pefa-no-history, cmrs, dmrs-1d,
    /// dmrs-2d, llm-mcts, llm-pddl.
    #[arg(long)]
    pub method: String,
    /// Comma-separated: sequential, parallel, or both (default: those the method runs).
    #[arg(long, value_delimiter = ',', value_enum)]
    pub execution: Vec<ExecutionFlag>,
    /// Comma-separated roles to keep (pefa: assigner, executor; cmrs: central; dmrs:
    /// speaker; llm-mcts: prior; llm-pddl: goal); default every role of the method.
    #[arg(long, value_delimiter = ',')]
    pub roles: Vec<String>,
    /// The simulated backend's mistakes in the episodes that leave the optimal plans.
    #[arg(long, default_value = "all=0.1")]
    pub sim_errors: String,
    /// Episodes with mistakes per task and execution (seeds 1 to N), besides the one
    /// with the planner's answers; 0: states on optimal plans only.
    #[arg(long, default_value_t = 2)]
    pub seeds: u64,
    /// Rounds of history the prompts recall.
    #[arg(long, default_value_t = HISTORY_WINDOW)]
    pub history: usize,
    /// A folder of prompt templates in place of the built-in ones (`coherent prompts
    /// export`), or `paper-layout`.
    #[arg(long)]
    pub prompts: Option<PathBuf>,
    /// Shares of the scenes in train, validation and test, for tasks of no generated set.
    #[arg(long, default_value = "0.8,0.1,0.1")]
    pub split: String,
    /// Keep the tasks of the evaluation subsets (paper40, native40), left out by default.
    #[arg(long)]
    pub include_eval: bool,
    /// Most states one search may visit.
    #[arg(long, default_value_t = Limits::DEFAULT_MAX_STATES)]
    pub max_states: usize,
    /// Count the examples' tokens with this tokenizer (a Hugging Face name or folder, or
    /// a GGUF file) in the datasheet; needs the Python package's `coherent`.
    #[arg(long)]
    pub tokenizer: Option<String>,
    /// Folder to write the data into.
    #[arg(short, long)]
    pub out: PathBuf,
}

/// The formats `coherent export` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// A PDDL domain per rule set and a PDDL problem per task.
    Pddl,
    /// The paper's released format: a JSON list of tasks per scene, `<scene>.json`
    /// (heights as labels), which the authors' code runs and `coherent import` reads back.
    Original,
}

#[derive(Args)]
#[group(required = false)]
pub struct ExportArgs {
    /// Original env files, native task files or folders of them; `native`: the project's
    /// own benchmark, compiled in.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Only these task ids (repeatable).
    #[arg(long = "task")]
    pub tasks: Vec<i64>,
    /// What to write.
    #[arg(long, value_enum)]
    pub format: Format,
    /// Folder to write the files into.
    #[arg(short, long)]
    pub out: PathBuf,
    /// With `--format pddl`: also write each task's optimal plan as
    /// `<scene>_task-<id>.plan`, a PDDL plan.
    #[arg(long)]
    pub plans: bool,
}

/// Writes the files: exit 1 when a task could not be written in the format (or, with
/// `--plans`, has no plan).
pub fn export(tasks: &[Task], args: &ExportArgs, limits: &Limits) -> Result<u8, Error> {
    match args.format {
        Format::Pddl => pddl::export(tasks, &args.out, args.plans, limits),
        Format::Original if args.plans => Err(Error::Invalid(
            "--plans writes PDDL plans: it goes with --format pddl".into(),
        )),
        Format::Original => {
            let written = check::export_original(tasks, &args.out)?;
            println!(
                "wrote {} tasks in {} files of the original format to {}",
                tasks.len(),
                written.len(),
                shown(&args.out.display().to_string())
            );
            Ok(0)
        }
    }
}

/// `coherent export sft`.
pub fn sft(args: &SftArgs) -> Result<u8, Error> {
    if args.tokenizer.is_some() {
        return Err(Error::Invalid(
            "--tokenizer counts tokens in Python: run the `coherent` of the Python package \
             (pip install .), with transformers installed"
                .into(),
        ));
    }
    let method = Builtin::from_name(&args.method).ok_or_else(|| {
        let names: Vec<&str> = Builtin::ALL.iter().map(|m| m.name()).collect();
        Error::Invalid(format!(
            "--method {:?}: not a built-in method ({})",
            args.method,
            names.join(", ")
        ))
    })?;
    let mut req = SftRequest::new(args.files.clone(), method, args.out.clone());
    if !args.execution.is_empty() {
        req.executions = args.execution.iter().map(|&e| e.into()).collect();
        req.executions.dedup();
    }
    req.roles.clone_from(&args.roles);
    req.errors = sim_errors(Some(&args.sim_errors))?.unwrap_or_default();
    req.seeds = args.seeds;
    req.history = args.history;
    req.prompts = args
        .prompts
        .as_deref()
        .map_or(PromptSource::Builtin, PromptSource::from_arg);
    req.split = split_shares(&args.split)?;
    req.include_eval = args.include_eval;
    req.max_states = args.max_states;
    req.command = command(args, &req);
    let cancel = Cancel::default();
    let terminal = std::io::stderr().is_terminal();
    let start = Instant::now();
    let runtime = session::runtime()?;
    let stop = {
        let _inside = runtime.enter();
        Stop::watch(&cancel)
    };
    let written = export_sft(&req, &cancel, &mut |done, all, examples| {
        if terminal {
            eprint!(
                "\r\x1b[2Kexporting: {done}/{all} tasks, {examples} examples, {}",
                clock(start.elapsed())
            );
        }
    });
    if terminal {
        eprint!("\r\x1b[2K");
    }
    let written = match written {
        Err(Error::Interrupted) => {
            eprintln!("interrupted: nothing was written");
            return Ok(stop.status());
        }
        other => other?,
    };
    for e in &written.malformed {
        eprintln!("error: {}", shown(e));
    }
    let counts: Vec<String> = written
        .examples
        .iter()
        .map(|(split, n)| format!("{} {n}", split.name()))
        .collect();
    println!(
        "wrote {} examples from {} tasks ({}) to {} in {:.1} s",
        written.examples.values().sum::<usize>(),
        written.tasks,
        counts.join(", "),
        shown(&args.out.display().to_string()),
        start.elapsed().as_secs_f64()
    );
    Ok(if written.malformed.is_empty() {
        status::OK
    } else {
        eprintln!(
            "{} malformed tasks were left out of the data",
            written.malformed.len()
        );
        status::BAD_INPUT
    })
}

/// The command that makes the same data, every knob written out, for the datasheet.
fn command(args: &SftArgs, req: &SftRequest) -> String {
    let files: Vec<String> = args
        .files
        .iter()
        .map(|f| shown(&f.display().to_string()).into_owned())
        .collect();
    let executions: Vec<String> = req.executions.iter().map(ToString::to_string).collect();
    let mut line = format!(
        "coherent export sft {} --method {} --execution {} --sim-errors {} --seeds {} \
         --history {} --split {} --max-states {}",
        files.join(" "),
        req.method.name(),
        executions.join(","),
        req.errors.label(),
        req.seeds,
        req.history,
        shown(&args.split),
        req.max_states
    );
    if !req.roles.is_empty() {
        line.push_str(&format!(" --roles {}", shown(&req.roles.join(","))));
    }
    if let Some(p) = &args.prompts {
        line.push_str(&format!(" --prompts {}", shown(&p.display().to_string())));
    }
    if req.include_eval {
        line.push_str(" --include-eval");
    }
    line.push_str(&format!(
        " --out {}",
        shown(&args.out.display().to_string())
    ));
    line
}
