//! A method written outside the crate ([`crate::episode::policy`]): each step its
//! [`Policy`] gets a [`StepView`] and answers one robot and one action, or none; the action
//! is checked and run through the same environment as every method's, the round is
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

use std::sync::Arc;
use std::time::Duration;

use coherent_core::text::{cut_front_within, cut_within, number};
use coherent_core::{Execution, NodeId, Task};

use crate::episode::method::{Closing, Decided, Deciding, Method, Turn};
use crate::episode::policy::{Act, Choice, MethodFailure, PastStep, Policy, StepView};
use crate::methods::decision;
use crate::records::transcript::{RobotPart, Round, RoundOutcome};

/// A method written outside the crate, for one episode: its policy (or why it could not
/// be made: the first step fails with that), and how long one step may take.
pub struct ExternalMethod {
    policy: Result<Box<dyn Policy>, MethodFailure>,
    step_timeout: Option<Duration>,
}

impl ExternalMethod {
    /// The method asking `policy` each step, each step within `step_timeout` (`None`: no
    /// limit).
    pub fn new(
        policy: Result<Box<dyn Policy>, MethodFailure>,
        step_timeout: Option<Duration>,
    ) -> ExternalMethod {
        ExternalMethod {
            policy,
            step_timeout,
        }
    }

    /// The policy's answer for the step `turn` is about, within the step limit; `None`
    /// when cancelled.
    async fn ask(&mut self, turn: &Turn<'_>) -> Option<Act> {
        let policy = match &mut self.policy {
            Ok(policy) => policy,
            Err(why) => {
                return Some(Act {
                    choices: Err(why.clone()),
                    calls: Vec::new(),
                });
            }
        };
        let past: Vec<PastStep> = turn.rounds.iter().flat_map(past_steps).collect();
        let at = (turn.step, turn.max_steps);
        let view = StepView {
            news: turn.news.to_vec(),
            ..StepView::now(turn.env, turn.task, at, turn.execution, &past)
        };
        let act = policy.act(Arc::new(view));
        let step_timeout = self.step_timeout;
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
            () = turn.cancel.cancelled() => None,
            act = act => Some(act),
            () = limit => Some(Act {
                choices: Err(out_of_time(step_timeout.unwrap_or_default())),
                calls: Vec::new(),
            }),
        }
    }
}

impl std::fmt::Debug for ExternalMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExternalMethod")
            .field("made", &self.policy.is_ok())
            .field("step_timeout", &self.step_timeout)
            .finish_non_exhaustive()
    }
}

impl Method for ExternalMethod {
    fn decide<'a>(&'a mut self, turn: Turn<'a>, round: &'a mut Round) -> Deciding<'a> {
        Box::pin(async move {
            let Some(act) = self.ask(&turn).await else {
                return Ok(None);
            };
            round.calls = act.calls;
            Ok(Some(match (bounded(act.choices), turn.execution) {
                (Ok(choices), Execution::Parallel) => jointly(turn, round, choices),
                (Ok(mut choices), Execution::Sequential) if choices.len() <= 1 => {
                    let choice = choices.pop().unwrap_or_default();
                    round.external = Some(choice.clone());
                    match choice.robot {
                        Some(robot) => {
                            if turn.task.robot_by_id(robot).is_ok() {
                                round.actions = turn.env.actions(robot).unwrap_or_default();
                            }
                            let action = choice.action.unwrap_or_default();
                            decision::choose(round, robot, &action, choice.note);
                        }
                        None => decision::nothing(round, choice.note),
                    }
                    Decided::CarryOut
                }
                (Ok(choices), Execution::Sequential) => Decided::Ends(RoundOutcome::MethodError {
                    message: format!(
                        "act gave {} decisions: a sequential episode takes one a step (run it \
                         with execution parallel for one per robot)",
                        choices.len()
                    ),
                }),
                (Err(MethodFailure(message)), _) => {
                    Decided::Ends(RoundOutcome::MethodError { message })
                }
            }))
        })
    }

    fn conclude(&mut self, closing: Closing<'_>, round: &mut Round) {
        decision::team_feedback(closing.task, round, None);
    }

    /// Nothing: the method is shown every earlier step, and picks its own window.
    fn recall(&self, _: &Task, _: &Round) -> Option<String> {
        None
    }
}

/// A parallel round: each choice that names a robot is that robot's part, for the loop to
/// carry out together (a robot that is not in the team refuses the step); choices that
/// name none are no action, what they report kept in the round's own
/// [`Round::external`].
fn jointly(turn: Turn<'_>, round: &mut Round, choices: Vec<Choice>) -> Decided {
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
    round.parts = acting
        .into_iter()
        .filter_map(|c| {
            let robot = c.robot?;
            let action = c.action.clone().unwrap_or_default();
            Some(RobotPart {
                external: Some(c.clone()),
                ..decision::part(turn.env, robot, &action, c.note)
            })
        })
        .collect();
    Decided::CarryOut
}

/// The failure of a step that took longer than `limit`.
fn out_of_time(limit: Duration) -> MethodFailure {
    MethodFailure(format!(
        "the step took longer than its time limit of {} s (--step-timeout, step_timeout=), \
         and was stopped",
        number(limit.as_secs_f64())
    ))
}

/// The most of a method's note, action or error a round keeps, the note of the whole
/// length included: what a method says is text of any length, and the transcript must
/// stay readable.
pub const MAX_TEXT_BYTES: usize = 64 << 10;

/// `choices` with their texts cut to [`MAX_TEXT_BYTES`]: each note and action at its
/// end, an error at its start (a traceback ends with the exception). The action as cut
/// is the one carried out and recorded, and a replay, which gives the recorded texts
/// back through here, cuts them to themselves ([`cut_within`]): what was carried out is
/// what is recorded, and what is replayed.
fn bounded(choices: Result<Vec<Choice>, MethodFailure>) -> Result<Vec<Choice>, MethodFailure> {
    match choices {
        Ok(choices) => Ok(choices
            .into_iter()
            .map(|mut c| {
                c.note = cut_within(&c.note, MAX_TEXT_BYTES).into_owned();
                c.action = c
                    .action
                    .map(|a| cut_within(&a, MAX_TEXT_BYTES).into_owned());
                c
            })
            .collect()),
        Err(MethodFailure(why)) => Err(MethodFailure(
            cut_front_within(&why, MAX_TEXT_BYTES).into_owned(),
        )),
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
