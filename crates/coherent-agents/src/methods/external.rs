//! A method written outside the crate ([`crate::episode::policy`]): each step its
//! [`Policy`] gets a [`StepView`] and answers one robot and one action, or none; the action
//! is checked and run through the same [`Environment`] as every method's, the round is
//! recorded with the method's decision, note and model calls, and the episode goes on
//! under the same budget.
//!
//! Faults are steps like any: an action outside the robot's list is run as written, so
//! that the feasibility check gives the reason; a robot that is not in the team is a
//! failed step that says so; no robot is no action (the step still counts). A policy
//! that fails (raises, in Python) ends the episode with status `error` and its words.

use std::io;
use std::sync::Arc;
use std::time::Instant;

use coherent_core::{Environment, NodeId, Task};

use crate::episode::cancel::Cancel;
use crate::episode::policy::{Act, MethodFailure, PastStep, Policy, StepView};
use crate::episode::rounds::{Episode, History, rounds};
use crate::methods::{decision, feedback};
use crate::records::transcript::{Round, RoundOutcome};

/// Runs the policy `made` for the episode on `env` until the goal holds, `max_steps` are
/// spent, the policy fails, or `cancel` fires. A policy that could not be made fails
/// the first step.
pub async fn run(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    made: Result<Box<dyn Policy>, MethodFailure>,
    max_steps: u32,
    cancel: &Cancel,
    on_round: &mut (dyn FnMut(&Round) -> io::Result<()> + Send),
) -> io::Result<Episode> {
    let mut policy = made;
    let mut history = History::whole();
    let play = async |env: &mut (dyn Environment + Send), step: u32| {
        let start = Instant::now();
        let act = match &mut policy {
            Ok(policy) => {
                let view = Arc::new(StepView::now(
                    env,
                    task,
                    step,
                    max_steps,
                    &history.entries(),
                ));
                tokio::select! {
                    biased;
                    () = cancel.cancelled() => return Ok(None),
                    act = policy.act(view) => act,
                }
            }
            Err(why) => Act {
                choice: Err(why.clone()),
                calls: Vec::new(),
            },
        };
        let mut round = Round::new(step);
        round.calls = act.calls;
        match act.choice {
            Ok(choice) => {
                round.external = Some(choice.clone());
                let action = choice.action.unwrap_or_default();
                match choice.robot {
                    Some(robot) => take(env, task, &mut round, robot, &action, choice.note),
                    None => decision::no_action(&mut round, choice.note),
                }
            }
            Err(MethodFailure(message)) => {
                round.outcome = RoundOutcome::MethodError { message };
                round.feedback = feedback::joint("", &round.outcome);
            }
        }
        history.push(past_step(&round));
        round.done = env.goal_satisfied();
        round.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(Some(round))
    };
    rounds(env, task, max_steps, cancel, on_round, play).await
}

/// Runs `robot`'s `action` as the round's decision; a robot that is not in the team is a
/// refused step (`unknown_robot`) with the team in its message.
fn take(
    env: &mut (dyn Environment + Send),
    task: &Task,
    round: &mut Round,
    robot: NodeId,
    action: &str,
    note: String,
) {
    match task.robot_by_id(robot) {
        Ok(_) => {
            round.actions = env.actions(robot).unwrap_or_default();
            decision::act(env, task, round, robot, action, note);
        }
        Err(e) => {
            let outcome = RoundOutcome::Infeasible {
                reason: "unknown_robot".into(),
                message: e.to_string(),
            };
            decision::decided(task, round, robot, action, outcome, note);
        }
    }
}

/// The round as the next steps' views show it.
fn past_step(round: &Round) -> PastStep {
    let chosen = round.external.as_ref();
    let (ok, reason) = match &round.outcome {
        RoundOutcome::Executed => (true, None),
        RoundOutcome::Infeasible { message, .. } => (false, Some(message.clone())),
        RoundOutcome::Declined => (false, Some("no action was chosen".to_owned())),
        RoundOutcome::NoProposal { why } | RoundOutcome::NoDecision { why } => {
            (false, Some(why.clone()))
        }
        RoundOutcome::BackendError { message } | RoundOutcome::MethodError { message } => {
            (false, Some(message.clone()))
        }
    };
    PastStep {
        robot: chosen.and_then(|c| c.robot),
        action: chosen.and_then(|c| c.action.clone()),
        ok,
        reason,
    }
}
