//! The `coherent` command line: `run`, `bench`, `plan`, `validate`, `import`, `export`,
//! `generate`, `render`, `view`, `prompts`. One implementation serves the `coherent` binary and the console script
//! that `pip install` puts on the PATH (which also loads methods written in Python,
//! [`LoadMethod`]).

mod args;
mod bench;
mod export;
mod generate;
mod pddl;
mod prompts;
mod render;
mod robots;
mod run;
mod signals;
mod status;
mod view;

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Parser, Subcommand};

use crate::session::engine::{
    Analysis, Limits, Makespan, Stop, Task, TaskError, clock, shown, shown_lines,
};
use crate::session::{Error, check, tasks};

pub use args::LoadMethod;

#[derive(Parser)]
#[command(
    name = "coherent",
    version,
    about = "Heterogeneous multi-robot task planning with LLMs (COHERENT)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Draw a task's scene from above as SVG: rooms, doors and their state, furniture
    /// with heights, objects, robots; with --plan or --transcript, each robot's path.
    Render(render::RenderArgs),
    /// Run a planning method on one task: one line per step, a summary, a transcript.
    /// Exit 0 when the goal is reached, 1 when the budget runs out, 2 on bad input,
    /// 3 when the model's server fails for good or a replay diverges, 4 when a method
    /// written in Python raised, 5 when a robot over ROS 2 stops answering, 70 when
    /// coherent itself fails (its async runtime cannot start), 130 on Ctrl-C.
    Run(Box<run::RunArgs>),
    /// Show an episode (its transcript), two side by side, or a benchmark's results as
    /// pages in the browser; `--serve` follows a results file as it grows. Exit 2 on an
    /// error.
    View(view::ViewArgs),
    /// Robots over ROS 2: `serve` starts a task's reference robot servers.
    Robots(robots::RobotsArgs),
    /// Run methods x tasks x seeds concurrently into a resumable results file, then print
    /// the paper's tables; with --report FILE, only the tables. Exit 0 when the run
    /// finished (whatever the success rate), 2 on bad input, 70 when coherent itself
    /// fails, 130 on Ctrl-C.
    Bench(Box<bench::BenchArgs>),
    /// Generate a task set: scenes from a catalogue, any team, goals with their proven
    /// optimum, written to a folder with a manifest and a datasheet. Exit 2 on a request
    /// that cannot be met (the message names the knob), 130 on Ctrl-C.
    Generate(Box<generate::GenerateArgs>),
    /// Check task files: exit 2 on malformed input, 1 on semantic problems or a file with
    /// no tasks, 0 when clean.
    Validate {
        /// Original env files, native task files or folders of them; `native`: the
        /// project's own benchmark, compiled in.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Most states one search may visit.
        #[arg(long, default_value_t = Limits::DEFAULT_MAX_STATES)]
        max_states: usize,
        /// Most memory one search's tables may take, in MiB (an estimate).
        #[arg(long, value_name = "MIB", default_value_t = Limits::DEFAULT_MAX_MEMORY >> 20)]
        max_memory: usize,
    },
    /// Write tasks in another format: `--format pddl`, a PDDL domain per rule set and a
    /// problem per task (docs/pddl.md); `--format original`, the paper's env lists (one
    /// file per scene, `<out>/<scene>.json`), which `coherent import` reads back. Exit 1
    /// when a task cannot be written, 2 on malformed input.
    Export(Box<export::ExportCommand>),
    /// Convert original env files into native task files, one per task.
    Import {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Folder to write `<scene>/task-<id>.json` into.
        #[arg(short, long)]
        out: PathBuf,
    },
    /// The prompt templates: `export DIR` writes the built-in ones, to edit and pass back
    /// with `--prompts DIR` to run and bench. Exit 2 on an error.
    Prompts(prompts::PromptsArgs),
    /// Plan optimally: shortest plan, task type, or why a task cannot be solved. Exit 1
    /// when a plan fails in physics (--physics) or a file holds no tasks, 2 on malformed
    /// input.
    Plan {
        /// Original env files, native task files or folders of them; `native`: the
        /// project's own benchmark, compiled in.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Only these task ids (repeatable).
        #[arg(long = "task")]
        tasks: Vec<i64>,
        /// One JSON object per task per line.
        #[arg(long)]
        json: bool,
        /// Most states one search may visit.
        #[arg(long, default_value_t = Limits::DEFAULT_MAX_STATES)]
        max_states: usize,
        /// Most memory one search's tables may take, in MiB (an estimate).
        #[arg(long, value_name = "MIB", default_value_t = Limits::DEFAULT_MAX_MEMORY >> 20)]
        max_memory: usize,
        /// Also execute each plan in Rapier and check it against the rules after every
        /// step (adds physics_ok, physics_error, sim_seconds, physics_wall_ms); with
        /// --parallel, the makespan plan too, after every joint step (adds the same keys
        /// with makespan_ before them).
        #[arg(long)]
        physics: bool,
        /// Also find the fewest joint steps, robots acting at once (adds makespan,
        /// makespan_proven, makespan_lower, makespan_stop, parallel_plan,
        /// makespan_states_expanded, makespan_ms).
        #[arg(long)]
        parallel: bool,
        /// Instead of planning, play this PDDL plan (a planner's output, one action a
        /// line) through the rules of the one task chosen: exit 0 when every action is
        /// allowed in turn and the goal holds after the last.
        #[arg(long, value_name = "PLAN", conflicts_with_all = ["physics", "parallel"])]
        check: Option<PathBuf>,
    },
}

/// Runs the command line `args` (program name first) and returns the exit status:
/// 0 success, 1 semantic problems found, 2 malformed input or a usage error.
pub fn run<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    run_with(args, None)
}

/// [`run()`], with `load` to load the methods written in Python that `--method` and
/// `--methods` name as `MODULE:CLASS` (without it, such a name is an error that says
/// what is needed).
pub fn run_with<I, T>(args: I, load: Option<&LoadMethod<'_>>) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() { 2 } else { 0 };
        }
    };
    let result = match cli.command {
        Command::Render(args) => render::render(&args),
        Command::Run(args) => run::run(*args, load),
        Command::View(args) => view::view(args),
        Command::Robots(args) => robots::robots(args),
        Command::Bench(args) => bench::bench(*args, load),
        Command::Generate(args) => generate::generate(&args),
        Command::Prompts(args) => prompts::prompts(&args),
        Command::Validate {
            files,
            max_states,
            max_memory,
        } => validate_files(&files, &limits(max_states, max_memory)),
        Command::Import { files, out } => import(&files, &out),
        Command::Export(command) => match (command.data, command.tasks) {
            (Some(export::ExportData::Sft(args)), _) => export::sft(&args),
            (None, Some(args)) => {
                let limits = limits(Limits::DEFAULT_MAX_STATES, Limits::DEFAULT_MAX_MEMORY >> 20);
                chosen(&args.files, &args.tasks).and_then(|(tasks, malformed)| {
                    Ok(export::export(&tasks, &args, &limits)?.max(malformed))
                })
            }
            (None, None) => Err(Error::Invalid(
                "coherent export: give task files and --format, or `sft`".into(),
            )),
        },
        Command::Plan {
            files,
            tasks,
            json,
            check: Some(plan_file),
            ..
        } => chosen(&files, &tasks).and_then(|(chosen, malformed)| {
            Ok(pddl::check(&chosen, &plan_file, json)?.max(malformed))
        }),
        Command::Plan {
            files,
            tasks,
            json,
            max_states,
            max_memory,
            physics,
            parallel,
            check: None,
        } => plan(
            &files,
            &tasks,
            json,
            check::PlanOptions { physics, parallel },
            &limits(max_states, max_memory),
        ),
    };
    result.unwrap_or_else(|e| {
        error(&e);
        status::of_error(&e)
    })
}

/// Says `error: ...` on stderr, each line of the message escaped ([`shown`]): a message
/// may quote a task file or a server.
fn error(message: &dyn std::fmt::Display) {
    eprintln!("error: {}", shown_lines(&message.to_string()));
}

/// The search bounds of `--max-states` and `--max-memory` (MiB).
fn limits(max_states: usize, max_memory_mib: usize) -> Limits {
    Limits {
        max_memory: max_memory_mib.saturating_mul(1 << 20),
        ..Limits::max_states(max_states)
    }
}

/// Tasks of every file; malformed ones are reported on stderr and counted, and so is a
/// file or folder that holds no task at all (an empty list) as `empty`, with a warning.
fn read_all(files: &[PathBuf], malformed: &mut usize, empty: &mut usize) -> Vec<Task> {
    let read = tasks::read_all(files);
    for path in &read.empty {
        eprintln!(
            "warning: {}: no tasks (an empty list)",
            shown(&path.display().to_string())
        );
    }
    for e in &read.malformed {
        error(&e);
    }
    *malformed += read.malformed.len();
    *empty += read.empty.len();
    read.tasks
}

fn validate_files(files: &[PathBuf], limits: &Limits) -> Result<u8, Error> {
    let (mut malformed, mut empty) = (0, 0);
    let tasks = read_all(files, &mut malformed, &mut empty);
    let mut with_problems = 0;
    for t in &tasks {
        let found = check::findings(t, limits);
        if !found.is_empty() {
            with_problems += 1;
        }
        for f in found {
            println!("{}: {}", shown(&tasks::task_name(t)), shown(&f));
        }
    }
    println!(
        "{} tasks read: {} clean, {with_problems} with semantic problems, {malformed} malformed",
        tasks.len() + malformed,
        tasks.len() - with_problems
    );
    Ok(if malformed > 0 {
        2
    } else if with_problems > 0 || empty > 0 {
        1
    } else {
        0
    })
}

fn import(files: &[PathBuf], out: &Path) -> Result<u8, Error> {
    let (mut malformed, mut empty) = (0, 0);
    let tasks = read_all(files, &mut malformed, &mut empty);
    let written = check::import(&tasks, out)?;
    println!(
        "wrote {} native task files to {}",
        written.len(),
        out.display()
    );
    Ok(if malformed > 0 { 2 } else { 0 })
}

fn plan(
    files: &[PathBuf],
    only: &[i64],
    as_json: bool,
    options: check::PlanOptions,
    limits: &Limits,
) -> Result<u8, Error> {
    let (mut malformed, mut empty) = (0, 0);
    let tasks = select(read_all(files, &mut malformed, &mut empty), files, only)?;
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let mut total_ms = 0.0;
    let mut physics_failed = false;
    let (start, terminal) = (Instant::now(), std::io::stderr().is_terminal());
    for (done, t) in tasks.iter().enumerate() {
        if options.physics && tasks.len() > 1 {
            tell_planned(done, tasks.len(), start, terminal);
        }
        let planned = check::plan(t, limits, options);
        total_ms += planned.analysis.elapsed.as_secs_f64() * 1e3;
        total_ms += planned
            .makespan
            .as_ref()
            .map_or(0.0, |m| m.elapsed.as_secs_f64() * 1e3);
        physics_failed |= planned.physics_failed();
        let line = if as_json {
            planned.to_json(t).to_string()
        } else {
            let mut text = plan_text(t, &planned.analysis);
            if let Some(m) = &planned.makespan {
                text.push_str(&parallel_text(t, m, limits));
            }
            text.push_str(&planned.physics_text());
            text
        };
        // A closed pipe (e.g. `| head`) ends the listing quietly.
        if writeln!(out, "{line}").is_err() {
            return Ok(0);
        }
    }
    if options.physics && tasks.len() > 1 && terminal {
        eprint!("\r\x1b[2K");
    }
    if !as_json {
        let _ = writeln!(out, "{} tasks planned in {:.1} ms", tasks.len(), total_ms);
    }
    Ok(if malformed > 0 {
        2
    } else if physics_failed || empty > 0 {
        1
    } else {
        0
    })
}

/// The tasks of `files` whose ids are in `only` (all when it is empty), and the exit
/// status the malformed ones call for (2, else 0; a file with no tasks, 1).
fn chosen(files: &[PathBuf], only: &[i64]) -> Result<(Vec<Task>, u8), Error> {
    let (mut malformed, mut empty) = (0, 0);
    let tasks = select(read_all(files, &mut malformed, &mut empty), files, only)?;
    let status = if malformed > 0 {
        2
    } else {
        u8::from(empty > 0)
    };
    Ok((tasks, status))
}

/// The tasks whose ids are in `only` (all when it is empty); an id no task has is an
/// error naming the ids there are.
fn select(mut tasks: Vec<Task>, files: &[PathBuf], only: &[i64]) -> Result<Vec<Task>, Error> {
    if only.is_empty() {
        return Ok(tasks);
    }
    let known = tasks::id_list(tasks.iter().map(|t| t.meta.task_id));
    tasks.retain(|t| only.contains(&t.meta.task_id));
    if let Some(missing) = only
        .iter()
        .find(|id| !tasks.iter().any(|t| t.meta.task_id == **id))
    {
        let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
        return Err(Error::Task(TaskError::Io {
            file: names.join(", "),
            message: format!("no task with task_id {missing}; its task ids: {known}"),
        }));
    }
    Ok(tasks)
}

/// Says on stderr how far `plan --physics` is through its tasks (each is planned, then
/// run in Rapier: a second or so each), with the rate and the time left: on a terminal
/// one line redrawn before each task, in a log a line before every tenth of them.
fn tell_planned(done: usize, total: usize, start: Instant, terminal: bool) {
    let tenth = total.div_ceil(10);
    if !terminal && !done.is_multiple_of(tenth) {
        return;
    }
    let elapsed = start.elapsed();
    let (rate, left) = match done {
        0 => ("-".to_owned(), "-".to_owned()),
        _ => (
            format!("{:.1} s/task", elapsed.as_secs_f64() / done as f64),
            clock(elapsed.mul_f64((total - done) as f64 / done as f64)),
        ),
    };
    let text = format!("planning in physics: {done}/{total} tasks, {rate}, {left} left");
    if terminal {
        eprint!("\r\x1b[2K{text}");
    } else {
        eprintln!("{text}");
    }
}

/// The fewest joint steps, one line each: `  step 1  22 [takeoff_from] ... | 23 ...`.
fn parallel_text(t: &Task, m: &Makespan, limits: &Limits) -> String {
    let Some(plan) = &m.plan else {
        return match m.stop {
            None => "\n  parallel: no plan".to_owned(),
            Some(stop) => format!(
                "\n  parallel: no plan found before {}",
                stopped_at(stop, limits)
            ),
        };
    };
    // Stopped early, the plan is an upper bound (at worst the sequential optimum
    // scheduled by its dependencies) and the open frontier a lower one.
    let verdict = match (m.stop, m.proven) {
        (None, _) => "the fewest".to_owned(),
        // Stopped while it looked among the plans of this many joint steps for fewer
        // actions: the joint steps are proven, the actions may not be the fewest.
        (Some(stop), true) => format!(
            "the fewest; the search for fewer actions stopped at {}",
            stopped_at(stop, limits)
        ),
        (Some(stop), false) => format!(
            "not proven the fewest: at least {}; the search stopped at {}",
            m.lower,
            stopped_at(stop, limits)
        ),
    };
    let steps: Vec<String> = plan
        .iter()
        .enumerate()
        .map(|(k, step)| {
            let parts: Vec<String> = step
                .iter()
                .map(|s| format!("{} {}", t.id(s.robot), shown(&s.action.render(t))))
                .collect();
            format!("  {:>4}  {}", k + 1, parts.join("  |  "))
        })
        .collect();
    format!(
        "\n  parallel: {} joint steps ({verdict}), {} states, {:.1} ms\n{}",
        plan.len(),
        m.states_expanded,
        m.elapsed.as_secs_f64() * 1e3,
        steps.join("\n")
    )
}

/// The limit a search met, in words.
fn stopped_at(stop: Stop, limits: &Limits) -> String {
    match stop {
        Stop::States => format!("the limit of {} states", limits.max_states),
        Stop::Memory => format!("the memory limit of {} MiB", limits.max_memory >> 20),
        Stop::Cancelled => "a cancel".to_owned(),
        Stop::Depth => "the deepest cost it counts".to_owned(),
    }
}

fn plan_text(t: &Task, a: &Analysis) -> String {
    let gt = t
        .meta
        .gt_steps
        .map(|g| g.to_string())
        .unwrap_or_else(|| "-".to_owned());
    let head = format!("{} task {}", shown(&t.meta.scene), t.meta.task_id);
    match &a.plan {
        None => format!(
            "{head}: no plan: {}",
            shown(a.reason.as_deref().unwrap_or(""))
        ),
        Some(plan) => {
            let steps: Vec<String> = plan
                .iter()
                .map(|s| format!("  {:>4}  {}", t.id(s.robot), shown(&s.action.render(t))))
                .collect();
            format!(
                "{head}: {} steps (gt {gt}), {}, {} states, {:.1} ms\n{}",
                plan.len(),
                a.task_type.map(|k| k.name()).unwrap_or("no robot needed"),
                a.states_expanded,
                a.elapsed.as_secs_f64() * 1e3,
                steps.join("\n")
            )
        }
    }
}
