//! `coherent render`: a top-down SVG of a task's scene, with the robots' paths of its
//! optimal plan or of a recorded episode carried out in physics (drawn by
//! [`crate::session::render`]).

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;

use crate::session::engine::{DEFAULT_MAX_TRANSCRIPT_BYTES, Limits, MIB, shown};
use crate::session::{Error, episode, render, tasks};

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
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_MAX_TRANSCRIPT_BYTES / MIB)]
    max_transcript_mib: u64,
}

pub(crate) fn render(args: &RenderArgs) -> Result<u8, Error> {
    let max_bytes = args.max_transcript_mib.saturating_mul(MIB);
    let recorded = args
        .transcript
        .as_deref()
        .map(|path| episode::recorded(path, max_bytes))
        .transpose()?;
    let task = match (&recorded, &args.task_file) {
        (Some(recorded), _) => Arc::clone(&recorded.task),
        (None, Some(file)) => Arc::new(tasks::pick_task(file, args.task_id)?),
        (None, None) => {
            return Err(Error::Invalid(
                "a task file is needed without --transcript".into(),
            ));
        }
    };
    let paths = if args.plan {
        Some(render::plan_paths(&task, &Limits::default())?)
    } else if let Some(recorded) = &recorded {
        Some(render::replay_paths(&task, &recorded.transcript)?)
    } else {
        None
    };
    if let Some(why) = paths.as_ref().and_then(|p| p.warning.as_ref()) {
        eprintln!("warning: {}", shown(why));
    }
    let svg = render::svg(&task, paths.as_ref().map(|p| p.paths.as_slice()))?;
    std::fs::write(&args.out, svg).map_err(|e| Error::File {
        file: args.out.display().to_string(),
        line: None,
        message: e.to_string(),
    })?;
    println!("wrote {}", args.out.display());
    Ok(0)
}
