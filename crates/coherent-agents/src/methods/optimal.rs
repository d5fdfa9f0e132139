//! The ground-truth row of the paper's tables: the optimal planner's shortest plan,
//! executed step by step through the same `Environment` and loop as every method. No
//! model; a task without a plan spends its budget on rounds that say why.

use std::io;
use std::sync::Arc;
use std::time::Instant;

use coherent_core::planner::{self, Limits};
use coherent_core::{Environment, Task};

use crate::episode::cancel::Cancel;
use crate::episode::rounds::{Episode, rounds};
use crate::methods::decision;
use crate::records::transcript::{Round, RoundOutcome};

/// Runs the shortest plan from the environment's state (found once, by `limits`).
pub async fn run(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    limits: &Limits,
    max_steps: u32,
    cancel: &Cancel,
    on_round: &mut (dyn FnMut(&Round) -> io::Result<()> + Send),
) -> io::Result<Episode> {
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
