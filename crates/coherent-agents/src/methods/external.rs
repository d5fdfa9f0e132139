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
//!
//! In a parallel episode the policy answers a decision per robot that acts, carried out
//! together as one joint step (two for one robot refuse the step, as the rules do).

use std::io;
use std::sync::Arc;
use std::time::{Duration, Instant};

use coherent_core::text::{cut, cut_front, number};
use coherent_core::{Environment, NodeId, Task};

use crate::episode::cancel::Cancel;
use crate::episode::joint;
use crate::episode::policy::{Act, Choice, MethodFailure, PastStep, Policy, StepView};
use crate::episode::rounds::{Episode, History, rounds};
use crate::methods::prompt::robot_label;
use crate::methods::{decision, feedback};
use crate::records::transcript::{Execution, RobotPart, Round, RoundOutcome};

/// Runs the policy `made` for the episode on `env` until the goal holds, `max_steps` are
/// spent, the policy fails or a step takes longer than `step_timeout`, or `cancel`
/// fires; in a parallel episode each step's choices (one per robot that acts) are
/// carried out as one joint step. A policy that could not be made fails the first step.
pub async fn run(
    env: &mut (dyn Environment + Send),
    task: &Arc<Task>,
    made: Result<Box<dyn Policy>, MethodFailure>,
    (execution, max_steps): (Execution, u32),
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
                let past = history.entries();
                let view = StepView::now(env, task, (step, max_steps), execution, &past);
                let act = policy.act(Arc::new(view));
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
                        choices: Err(out_of_time(step_timeout.unwrap_or_default())),
                        calls: Vec::new(),
                    },
                }
            }
            Err(why) => Act {
                choices: Err(why.clone()),
                calls: Vec::new(),
            },
        };
        let mut round = Round::new(step);
        round.calls = act.calls;
        match (bounded(act.choices), execution) {
            (Ok(choices), Execution::Parallel) => jointly(env, task, &mut round, choices),
            (Ok(mut choices), Execution::Sequential) if choices.len() <= 1 => {
                let choice = choices.pop().unwrap_or_default();
                round.external = Some(choice.clone());
                let action = choice.action.unwrap_or_default();
                match choice.robot {
                    Some(robot) => take(env, task, &mut round, robot, &action, choice.note),
                    None => decision::no_action(&mut round, choice.note),
                }
            }
            (Ok(choices), Execution::Sequential) => failed(
                &mut round,
                format!(
                    "act gave {} decisions: a sequential episode takes one a step (run it \
                     with execution parallel for one per robot)",
                    choices.len()
                ),
            ),
            (Err(MethodFailure(message)), _) => failed(&mut round, message),
        }
        for past in past_steps(&round) {
            history.push(past);
        }
        round.done = env.goal_satisfied();
        round.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(Some(round))
    };
    rounds(env, task, max_steps, cancel, on_round, play).await
}

/// A round in which the method failed: the episode ends with its words.
fn failed(round: &mut Round, message: String) {
    round.outcome = RoundOutcome::MethodError { message };
    round.feedback = feedback::team("", &round.outcome);
}

/// A parallel round: each choice that names a robot is that robot's part, carried out
/// together; choices that name none are no action, what they report kept in the
/// round's own [`Round::external`]. A robot that is not in the team refuses the step
/// (`unknown_robot`, every other part `step_refused`), as the rules refuse any step
/// with an action that cannot be.
fn jointly(
    env: &mut (dyn Environment + Send),
    task: &Task,
    round: &mut Round,
    choices: Vec<Choice>,
) {
    let (acting, idle): (Vec<Choice>, Vec<Choice>) =
        choices.into_iter().partition(|c| c.robot.is_some());
    if !idle.is_empty() {
        round.external = Some(Choice {
            robot: None,
            action: None,
            note: idle
                .iter()
                .map(|c| c.note.as_str())
                .filter(|n| !n.is_empty())
                .collect::<Vec<_>>()
                .join("; "),
            prompt_tokens: idle.iter().map(|c| c.prompt_tokens).sum(),
            completion_tokens: idle.iter().map(|c| c.completion_tokens).sum(),
            calls: idle.iter().map(|c| c.calls).sum(),
        });
    }
    let mut parts: Vec<RobotPart> = acting
        .into_iter()
        .filter_map(|c| {
            let robot = c.robot?;
            let action = c.action.clone().unwrap_or_default();
            Some(RobotPart {
                external: Some(c.clone()),
                ..decision::part(env, robot, &action, c.note)
            })
        })
        .collect();
    let unknown: Vec<NodeId> = parts
        .iter()
        .map(|p| p.robot)
        .filter(|r| task.robot_by_id(*r).is_err())
        .collect();
    if unknown.is_empty() {
        return decision::act_jointly(env, task, round, parts, None);
    }
    for p in &mut parts {
        p.outcome = match task.robot_by_id(p.robot) {
            Err(e) => RoundOutcome::Infeasible {
                reason: "unknown_robot".into(),
                message: e.to_string(),
            },
            Ok(_) => RoundOutcome::Infeasible {
                reason: "step_refused".into(),
                message: "not carried out: the joint step names a robot that is not in the team"
                    .into(),
            },
        };
        let line = format!(
            "{}: {}",
            robot_label(task, p.robot),
            p.action().unwrap_or_default()
        );
        p.feedback = feedback::team(&line, &p.outcome);
    }
    let outcome = RoundOutcome::Infeasible {
        reason: "unknown_robot".into(),
        message: format!(
            "robot {} is not in the team",
            unknown
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let paragraph = joint::paragraph(None, &parts);
    joint::close(env, round, parts, outcome, paragraph);
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

/// `choices` with their texts cut at [`MAX_TEXT_BYTES`]: each note and action at its
/// end, an error at its start (a traceback ends with the exception).
fn bounded(choices: Result<Vec<Choice>, MethodFailure>) -> Result<Vec<Choice>, MethodFailure> {
    match choices {
        Ok(choices) => Ok(choices
            .into_iter()
            .map(|mut c| {
                c.note = cut(&c.note, MAX_TEXT_BYTES).into_owned();
                c.action = c.action.map(|a| cut(&a, MAX_TEXT_BYTES).into_owned());
                c
            })
            .collect()),
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

/// The round as the next steps' views show it: its one decision, or of a parallel round
/// each robot's part.
fn past_steps(round: &Round) -> Vec<PastStep> {
    let seen = |robot: Option<NodeId>, action: Option<String>, outcome: &RoundOutcome| {
        let (ok, reason) = match outcome {
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
            robot,
            action,
            ok,
            reason,
        }
    };
    if !round.parts.is_empty() {
        return round
            .parts
            .iter()
            .map(|p| seen(Some(p.robot), p.action().map(str::to_owned), &p.outcome))
            .collect();
    }
    let chosen = round.external.as_ref();
    vec![seen(
        chosen.and_then(|c| c.robot),
        chosen.and_then(|c| c.action.clone()),
        &round.outcome,
    )]
}
