//! The scene from above as SVG, and the robots' paths when a plan or a recorded episode
//! is carried out in physics.

use std::sync::Arc;

use coherent_agents::transcript::Transcript;
use coherent_core::planner::{self, Limits};
use coherent_core::{Environment, Task};
use coherent_sim::{PhysicalEnv, layout, render};

use crate::session::error::Error;

/// A robot's track, `[x, y, z]` points, as `coherent_sim` records it.
pub type RobotPath = (coherent_core::NodeId, Vec<[f32; 3]>);

/// The robots' paths and the warning, when there is one, that the physical run stopped
/// early (the paths go up to there).
#[derive(Debug)]
pub struct Paths {
    pub paths: Vec<RobotPath>,
    pub warning: Option<String>,
}

/// The task's scene at its start from above, with `paths` drawn when given.
pub fn svg(task: &Task, paths: Option<&[RobotPath]>) -> Result<String, Error> {
    Ok(render::svg(task, &scene_layout(task)?, &task.init, paths))
}

/// The geometry of `task`'s scene: its own, or the one generated from its graph.
pub fn scene_layout(task: &Task) -> Result<layout::Layout, Error> {
    layout::for_task(task).map_err(|e| {
        Error::Physics(coherent_sim::PhysicsError {
            kind: coherent_sim::FailureKind::Layout,
            message: format!("layout: {}", e.0),
        })
    })
}

/// The robots' paths when the task's optimal plan is carried out in physics.
pub fn plan_paths(task: &Arc<Task>, limits: &Limits) -> Result<Paths, Error> {
    let analysis = planner::analyse(task, limits);
    let plan = analysis.plan.ok_or_else(|| {
        Error::Invalid(format!(
            "no plan to draw: {}",
            analysis
                .reason
                .unwrap_or_else(|| "the search stopped".into())
        ))
    })?;
    let report = coherent_sim::execute_plan(task, &plan);
    Ok(Paths {
        warning: report
            .physics_error
            .map(|e| format!("the plan failed in physics, paths drawn up to there: {e}")),
        paths: report.paths,
    })
}

/// The robots' paths when the transcript's executed actions are carried out in physics.
pub fn replay_paths(task: &Arc<Task>, t: &Transcript) -> Result<Paths, Error> {
    let mut env = PhysicalEnv::new(Arc::clone(task))?;
    let mut warning = None;
    for round in &t.rounds {
        let actions = round.carried_out();
        // A joint step's robots move at once; a sequential round's one action alone.
        let failed = if round.parts.is_empty() {
            match actions.first() {
                Some(&(robot, action)) => env
                    .step(robot, action)?
                    .infeasible
                    .map(|why| (action.to_owned(), why)),
                None => None,
            }
        } else if actions.is_empty() {
            None
        } else {
            let outcome = env.step_joint(&actions)?;
            outcome
                .parts
                .into_iter()
                .find_map(|p| p.infeasible)
                .map(|why| ("its joint step".to_owned(), why))
        };
        if let Some((what, why)) = failed {
            warning = Some(format!(
                "round {}: {what} failed in physics, paths drawn up to there: {why}",
                round.step
            ));
            break;
        }
    }
    Ok(Paths {
        paths: env.world().paths.clone(),
        warning,
    })
}
