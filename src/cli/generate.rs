//! `coherent generate`: a task set drawn from generated scenes, each task with its
//! proven optimum, written to a folder ([`crate::session::generate`] makes and writes
//! it). Progress on stderr when it is a terminal; Ctrl-C stops it with the tasks written
//! so far whole, their manifest and datasheet.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use super::signals::Stop;
use super::status;
use crate::session::engine::Limits;
use crate::session::engine::{Cancel, clock, shown};
use crate::session::generate::{GenerateRequest, Knobs, Made, write_variants};
use crate::session::{self, Error};

#[derive(Args)]
pub(crate) struct GenerateArgs {
    /// The folder to write: a native task file per task under `<scene>/`,
    /// `manifest.jsonl` and the datasheet `README.md`. It must be new or empty.
    #[arg(short, long)]
    out: PathBuf,
    /// Instead of drawing a set: the dynamic variants of these tasks (a file, a folder or
    /// `native`), one event each, one per kind where it makes sense (docs/dynamic.md),
    /// with `manifest.jsonl`; only --max-states applies
    #[arg(long, value_name = "TASKS")]
    variants_of: Option<PathBuf>,
    /// How many tasks.
    #[arg(long, default_value_t = Knobs::default().tasks)]
    tasks: usize,
    /// The seed: the same seed and knobs give the same files, byte for byte.
    #[arg(long, default_value_t = Knobs::default().seed)]
    seed: u64,
    /// How many scenes the tasks are spread over (default: one per 25 tasks, at least
    /// 3, so that train, validation and test each have a scene of their own).
    #[arg(long)]
    scenes: Option<usize>,
    /// Rooms per scene, both storeys together: N or N-M (2 to 16).
    #[arg(long, default_value_t = Knobs::default().rooms)]
    rooms: String,
    /// The chance that a scene of four rooms or more has a second storey with stairs.
    #[arg(long, default_value_t = Knobs::default().upstairs)]
    upstairs: f64,
    /// The chance that a door starts closed.
    #[arg(long, default_value_t = Knobs::default().closed)]
    closed: f64,
    /// Robots per kind: `quadrotor=N,legged=N,arm=N`, each N or N-M (a kind left out:
    /// none; without --team, one of each, or 0 up to --robots of each).
    #[arg(long)]
    team: Option<String>,
    /// Robots in a team: N or N-M, the kinds drawn within --team.
    #[arg(long)]
    robots: Option<String>,
    /// Goal predicates per task: N or N-M.
    #[arg(long, default_value_t = Knobs::default().predicates)]
    predicates: String,
    /// Keep only tasks of these types (the fewest robot types that reach the goal):
    /// mono, dual, trio, comma-separated.
    #[arg(long = "type")]
    types: Option<String>,
    /// Keep only tasks whose goal needs this many robots at the fewest: N or N-M.
    #[arg(long)]
    needed: Option<String>,
    /// Keep only tasks whose optimal plan has this many steps: N or N-M.
    #[arg(long)]
    steps: Option<String>,
    /// Keep only tasks whose optimal steps over their makespan lie in this range: X or
    /// X-Y (1.0 and up).
    #[arg(long)]
    ratio: Option<String>,
    /// Keep only tasks whose makespan is proven within the search limits.
    #[arg(long)]
    proven: bool,
    /// Keep only tasks whose optimal plan runs in physics: each kept task's plan is
    /// carried out in Rapier (a fraction of a second a task). Without it, only that the
    /// physics builds each scene is checked.
    #[arg(long)]
    physics: bool,
    /// Most states one search may visit.
    #[arg(long, default_value_t = Knobs::default().max_states)]
    max_states: usize,
    /// Most memory one search's tables may take, in MiB (an estimate); the searches of
    /// --jobs threads run at once.
    #[arg(long, value_name = "MIB", default_value_t = Knobs::default().max_memory)]
    max_memory: usize,
    /// The most candidate tasks drawn before a request that cannot be met is given up
    /// (default: 50 per task asked, and 1,000 more).
    #[arg(long)]
    max_draws: Option<usize>,
    /// Shares of the scenes in train, validation and test.
    #[arg(long, default_value_t = Knobs::default().split)]
    split: String,
    /// Threads that work out ground truths (default: one per core). They change the
    /// time, not the set.
    #[arg(long)]
    jobs: Option<usize>,
}

impl GenerateArgs {
    /// The session's request; an error names the flag.
    fn request(&self) -> Result<GenerateRequest, Error> {
        let knobs = Knobs {
            tasks: self.tasks,
            seed: self.seed,
            scenes: self.scenes,
            rooms: self.rooms.clone(),
            upstairs: self.upstairs,
            closed: self.closed,
            team: self.team.clone(),
            robots: self.robots.clone(),
            predicates: self.predicates.clone(),
            types: self.types.clone(),
            needed: self.needed.clone(),
            steps: self.steps.clone(),
            ratio: self.ratio.clone(),
            proven: self.proven,
            physics: self.physics,
            max_states: self.max_states,
            max_memory: self.max_memory,
            max_draws: self.max_draws,
            split: self.split.clone(),
            jobs: self.jobs,
        };
        knobs.request(Some(self.out.clone()))
    }
}

pub(crate) fn generate(args: &GenerateArgs) -> Result<u8, Error> {
    if let Some(tasks) = &args.variants_of {
        return variants(args, tasks);
    }
    let request = args.request()?;
    let cancel = Cancel::default();
    let terminal = std::io::stderr().is_terminal();
    let start = Instant::now();
    let (made, stopped) = session::block_on(async {
        let stop = Stop::watch(&cancel);
        let made = tokio::task::block_in_place(|| {
            request.run(&cancel, &mut |_| {}, &mut |p| {
                if terminal {
                    let rate = p.kept as f64 / start.elapsed().as_secs_f64().max(1e-3);
                    let left = if p.kept == 0 {
                        "-".to_owned()
                    } else {
                        clock(start.elapsed().mul_f64((p.wanted - p.kept) as f64 / p.kept as f64))
                    };
                    eprint!(
                        "\r\x1b[2Kgenerating: {}/{} tasks, {} draws, {rate:.1} tasks/s, {left} left",
                        p.kept, p.wanted, p.drawn
                    );
                }
            })
        });
        (made, stop.status())
    })?;
    if terminal {
        eprint!("\r\x1b[2K");
    }
    let made: Made = made?;
    let t = &made.tally;
    println!(
        "wrote {} tasks in {} scenes to {}: the makespan proven for {} of them; {} draws in {:.1} s",
        t.kept,
        made.scenes,
        shown(&args.out.display().to_string()),
        t.proven,
        t.drawn,
        start.elapsed().as_secs_f64()
    );
    Ok(if made.interrupted {
        eprintln!("interrupted: the set has the tasks written so far");
        stopped
    } else {
        status::OK
    })
}

/// `--variants-of`: the dynamic variants of the tasks, written to `--out`.
fn variants(args: &GenerateArgs, tasks: &std::path::Path) -> Result<u8, Error> {
    let limits = Limits::max_states(args.max_states);
    let written = write_variants(tasks, &args.out, &limits)?;
    let kinds: Vec<String> = written
        .by_kind
        .iter()
        .map(|(k, n)| format!("{n} {k}"))
        .collect();
    println!(
        "wrote {} variants of {} tasks to {}: {}",
        written.by_kind.iter().map(|(_, n)| n).sum::<usize>(),
        written.tasks,
        shown(&args.out.display().to_string()),
        kinds.join(", ")
    );
    for name in &written.skipped {
        println!(
            "no variant of {}: no optimal plan of two steps or more",
            shown(name)
        );
    }
    Ok(status::OK)
}
