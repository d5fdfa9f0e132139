//! `coherent render`: a top-down SVG of a task's scene, with the robots' paths of its
//! optimal plan or of a recorded episode carried out in physics.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use coherent_agents::episode;
use coherent_agents::transcript::{self, Outcome};
use coherent_core::planner::{self, Limits};
use coherent_core::{Environment, Task};
use coherent_sim::{PhysicalEnv, layout, render};

use super::pick_task;

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
}

pub(crate) fn render(args: &RenderArgs) -> Result<u8, String> {
    let recorded = match &args.transcript {
        Some(path) => Some((transcript::read(path)?, path)),
        None => None,
    };
    let task = match (&recorded, &args.task_file) {
        (Some((t, path)), _) => episode::recorded_task(t, path)?,
        (None, Some(file)) => pick_task(file, args.task_id)?,
        (None, None) => return Err("a task file is needed without --transcript".into()),
    };
    let task = Arc::new(task);
    let paths = if args.plan {
        Some(plan_paths(&task, &Limits::default())?)
    } else if let Some((t, _)) = &recorded {
        Some(replay_paths(&task, t)?)
    } else {
        None
    };
    let svg = svg(&task, paths.as_deref())?;
    std::fs::write(&args.out, svg).map_err(|e| format!("{}: {e}", args.out.display()))?;
    println!("wrote {}", args.out.display());
    Ok(0)
}

/// The task's scene at its start from above, with `paths` drawn when given.
pub fn svg(task: &Task, paths: Option<&[RobotPath]>) -> Result<String, String> {
    let layout = layout::for_task(task).map_err(|e| format!("layout: {}", e.0))?;
    Ok(render::svg(task, &layout, &task.init, paths))
}

/// A robot's track, `[x, y, z]` points, as `coherent_sim` records it.
pub type RobotPath = (coherent_core::NodeId, Vec<[f32; 3]>);

/// The robots' paths when the task's optimal plan is carried out in physics (up to a
/// physical failure, which is reported on stderr).
pub fn plan_paths(task: &Arc<Task>, limits: &Limits) -> Result<Vec<RobotPath>, String> {
    let analysis = planner::analyse(task, limits);
    let plan = analysis.plan.ok_or_else(|| {
        format!(
            "no plan to draw: {}",
            analysis
                .reason
                .unwrap_or_else(|| "the search stopped".into())
        )
    })?;
    let report = coherent_sim::execute_plan(task, &plan);
    if let Some(e) = &report.physics_error {
        eprintln!("warning: the plan failed in physics, paths drawn up to there: {e}");
    }
    Ok(report.paths)
}

/// The robots' paths when the transcript's executed actions are carried out in physics.
pub fn replay_paths(
    task: &Arc<Task>,
    t: &transcript::Transcript,
) -> Result<Vec<RobotPath>, String> {
    let mut env =
        PhysicalEnv::new(Arc::clone(task)).map_err(|e| format!("physics: {}", e.message))?;
    for round in &t.rounds {
        let (Outcome::Executed, Some(p), Some(d)) =
            (&round.outcome, &round.proposal, &round.decision)
        else {
            continue;
        };
        let Some(action) = &d.action else { continue };
        let outcome = env.step(p.robot, action).map_err(|e| e.to_string())?;
        if let Some(why) = outcome.infeasible {
            eprintln!(
                "warning: round {}: {action} failed in physics, paths drawn up to there: {why}",
                round.step
            );
            break;
        }
    }
    Ok(env.world().paths.clone())
}
