//! `coherent render`: a top-down SVG of a task's scene, with the robots' paths of its
//! optimal plan or of a recorded episode carried out in physics (drawn by
//! [`crate::session::render`]).

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use coherent_agents::episode;
use coherent_agents::transcript;
use coherent_core::files::MIB;
use coherent_core::planner::Limits;

use coherent_core::text::shown;

use crate::session::{render, tasks};

#[derive(Args)]
pub(crate) struct RenderArgs {
    /// A native task file, or an original env file with --task (not needed with
    /// --transcript).
    #[arg(required_unless_present = "transcript")]
    task_file: Option<PathBuf>,
    /// Which task of the file (its task_id).
    #[arg(long = "task")]
    task_id: Option<i64>,
    /// The SVG file to write.
    #[arg(short, long)]
    out: PathBuf,
    /// Draw each robot's path along the optimal plan, carried out in physics.
    #[arg(long, conflicts_with = "transcript")]
    plan: bool,
    /// Draw each robot's path along the executed actions of a `coherent run` transcript.
    #[arg(long)]
    transcript: Option<PathBuf>,
    /// The most the transcript may hold, in MiB.
    #[arg(long, value_name = "MIB", default_value_t = transcript::DEFAULT_MAX_BYTES / MIB)]
    max_transcript_mib: u64,
}

pub(crate) fn render(args: &RenderArgs) -> Result<u8, String> {
    let recorded = match &args.transcript {
        Some(path) => Some((
            transcript::read_within(path, args.max_transcript_mib.saturating_mul(MIB))?,
            path,
        )),
        None => None,
    };
    let task = match (&recorded, &args.task_file) {
        (Some((t, path)), _) => episode::recorded_task(t, path)?,
        (None, Some(file)) => tasks::pick_task(file, args.task_id)?,
        (None, None) => return Err("a task file is needed without --transcript".into()),
    };
    let task = Arc::new(task);
    let paths = if args.plan {
        Some(render::plan_paths(&task, &Limits::default())?)
    } else if let Some((t, _)) = &recorded {
        Some(render::replay_paths(&task, t)?)
    } else {
        None
    };
    if let Some(why) = paths.as_ref().and_then(|p| p.warning.as_ref()) {
        eprintln!("warning: {}", shown(why));
    }
    let svg = render::svg(&task, paths.as_ref().map(|p| p.paths.as_slice()))?;
    std::fs::write(&args.out, svg).map_err(|e| format!("{}: {e}", args.out.display()))?;
    println!("wrote {}", args.out.display());
    Ok(0)
}
