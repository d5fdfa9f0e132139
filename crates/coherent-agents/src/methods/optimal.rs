//! The ground-truth row of the paper's tables: the optimal planner's shortest plan,
//! executed step by step through the same `Environment` and loop as every method; in a
//! parallel episode the makespan search's plan (`coherent_core::makespan`), joint step by
//! joint step. No model; a task without a plan spends its budget on rounds that say why.

use std::io;
use std::sync::Arc;
use std::time::Instant;

use coherent_core::makespan::{self, JointStep};
use coherent_core::planner::{self, Limits};
use coherent_core::{Environment, Task};

use crate::episode::cancel::Cancel;
use crate::episode::rounds::{Episode, rounds};
use crate::methods::decision;
use crate::records::transcript::{Execution, Round, RoundOutcome};

/// Runs the shortest plan from the environment's state (found once, by `limits`), or in
/// a parallel episode the plan of the fewest joint steps.
pub async fn run(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    limits: &Limits,
    execution: Execution,
    max_steps: u32,
    cancel: &Cancel,
    on_round: &mut (dyn FnMut(&Round) -> io::Result<()> + Send),
) -> io::Result<Episode> {
    if execution == Execution::Parallel {
        return parallel(env, task, limits, max_steps, cancel, on_round).await;
    }
    let (t, s, l) = (Arc::clone(task), env.state().clone(), limits.clone());
    let search =
        tokio::task::spawn_blocking(move || planner::search_from(&t, &s, &t.robots, &t.goal, &l))
            .await
            .map_err(io::Error::other)?;
    let plan = search.plan.ok_or(if search.truncated {
        "the search stopped before it found a plan"
    } else {
        "no plan reaches the goal"
    });
    let play = async |env: &mut (dyn Environment + Send), step: u32| {
        let start = Instant::now();
        let mut round = Round::new(step);
        match plan.as_ref().map(|p| p.get(step as usize - 1)) {
            Ok(Some(s)) => {
                let robot = task.id(s.robot);
                let action = s.action.render(task);
                decision::act(env, task, &mut round, robot, &action, String::new());
            }
            Ok(None) => {
                round.outcome = RoundOutcome::NoDecision {
                    why: "the plan is over".into(),
                }
            }
            Err(why) => {
                round.outcome = RoundOutcome::NoDecision {
                    why: (*why).to_owned(),
                }
            }
        }
        round.done = env.goal_satisfied();
        round.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(Some(round))
    };
    rounds(env, task, max_steps, cancel, on_round, play).await
}

/// Runs the plan of the fewest joint steps from the environment's state (the best one
/// found within `limits`: the sequential optimum scheduled, when the search stops early).
async fn parallel(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    limits: &Limits,
    max_steps: u32,
    cancel: &Cancel,
    on_round: &mut (dyn FnMut(&Round) -> io::Result<()> + Send),
) -> io::Result<Episode> {
    let (t, s, l) = (Arc::clone(task), env.state().clone(), limits.clone());
    let search = tokio::task::spawn_blocking(move || {
        let sequential = planner::search_from(&t, &s, &t.robots, &t.goal, &l);
        makespan::search_with(&t, &s, &t.robots, &t.goal, sequential.plan.as_deref(), &l)
    })
    .await
    .map_err(io::Error::other)?;
    let plan: Result<Vec<JointStep>, &str> = search.plan.ok_or(if search.stop.is_some() {
        "the search stopped before it found a plan"
    } else {
        "no plan reaches the goal"
    });
    let play = async |env: &mut (dyn Environment + Send), step: u32| {
        let start = Instant::now();
        let mut round = Round::new(step);
        match plan.as_ref().map(|p| p.get(step as usize - 1)) {
            Ok(Some(joint)) => {
                let parts = joint
                    .iter()
                    .map(|s| {
                        let action = s.action.render(task);
                        decision::part(env, task.id(s.robot), &action, String::new())
                    })
                    .collect();
                decision::act_jointly(env, task, &mut round, parts, None);
            }
            Ok(None) => {
                round.outcome = RoundOutcome::NoDecision {
                    why: "the plan is over".into(),
                }
            }
            Err(why) => {
                round.outcome = RoundOutcome::NoDecision {
                    why: (*why).to_owned(),
                }
            }
        }
        round.done = env.goal_satisfied();
        round.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(Some(round))
    };
    rounds(env, task, max_steps, cancel, on_round, play).await
}
