//! A method written outside the crate ([`crate::episode::policy`]): each step its
//! [`Policy`] gets a [`StepView`] and answers one robot and one action, or none; the action
//! is checked and run through the same [`Environment`] as every method's, the round is
//! recorded with the method's decision, note and model calls, and the episode goes on
//! under the same budget.
//!
//! Faults are steps like any: an action outside the robot's list is run as written, so
//! that the feasibility check gives the reason; a robot that is not in the team is a
//! failed step that says so; no robot is no action (the step still counts). A policy
//! that fails (raises, in Python) ends the episode with status `error` and its words,
//! and so does a step that takes longer than the method's step limit.

use std::io;
use std::sync::Arc;
use std::time::{Duration, Instant};

use coherent_core::text::{cut, cut_front, number};
use coherent_core::{Environment, NodeId, Task};

use crate::episode::cancel::Cancel;
use crate::episode::policy::{Act, Choice, MethodFailure, PastStep, Policy, StepView};
use crate::episode::rounds::{Episode, History, rounds};
use crate::methods::{decision, feedback};
use crate::records::transcript::{Round, RoundOutcome};

/// Runs the policy `made` for the episode on `env` until the goal holds, `max_steps` are
/// spent, the policy fails or a step takes longer than `step_timeout`, or `cancel`
/// fires. A policy that could not be made fails the first step.
pub async fn run(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    made: Result<Box<dyn Policy>, MethodFailure>,
    max_steps: u32,
    step_timeout: Option<Duration>,
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
                let act = policy.act(view);
                // Without a limit, a step may take as long as it takes (a sleep of
                // Duration::MAX would overflow the clock).
                let limit = async {
                    match step_timeout {
                        Some(limit) => tokio::time::sleep(limit).await,
                        None => std::future::pending().await,
                    }
                };
                tokio::select! {
                    biased;
                    () = cancel.cancelled() => return Ok(None),
                    act = act => act,
                    () = limit => Act {
                        choice: Err(out_of_time(step_timeout.unwrap_or_default())),
                        calls: Vec::new(),
                    },
                }
            }
            Err(why) => Act {
                choice: Err(why.clone()),
                calls: Vec::new(),
            },
        };
        let mut round = Round::new(step);
        round.calls = act.calls;
        match bounded(act.choice) {
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

/// The failure of a step that took longer than `limit`.
fn out_of_time(limit: Duration) -> MethodFailure {
    MethodFailure(format!(
        "the step took longer than its time limit of {} s (--step-timeout, step_timeout=), \
         and was stopped",
        number(limit.as_secs_f64())
    ))
}

/// The most of a method's note, action or error a round keeps: what a method says is
/// text of any length, and the transcript must stay readable.
pub const MAX_TEXT_BYTES: usize = 64 << 10;

/// `choice` with its texts cut at [`MAX_TEXT_BYTES`]: the note and the action at their
/// end, an error at its start (a traceback ends with the exception).
fn bounded(choice: Result<Choice, MethodFailure>) -> Result<Choice, MethodFailure> {
    match choice {
        Ok(mut c) => {
            c.note = cut(&c.note, MAX_TEXT_BYTES).into_owned();
            c.action = c.action.map(|a| cut(&a, MAX_TEXT_BYTES).into_owned());
            Ok(c)
        }
        Err(MethodFailure(why)) => Err(MethodFailure(cut_front(&why, MAX_TEXT_BYTES).into_owned())),
    }
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
