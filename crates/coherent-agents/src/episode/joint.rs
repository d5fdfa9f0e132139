//! A parallel round's joint step, as the loop carries it out: the actions its robots'
//! parts decided on, at once through [`Environment::step_joint`], each part's outcome
//! recorded, and what the step as a whole came to; and what a method hears of it.

use coherent_core::{Environment, NodeId, Task};

use crate::records::transcript::{Reason, RobotPart, RoundOutcome};

/// Carries out the joint step of `parts`, put in team order first: every part whose
/// decision names an action acts, at once; one whose decision names none is `declined`,
/// and one without a decision keeps the outcome the method gave it (why there is none).
/// Each acting part gets its outcome (executed, or the rules' reason, a refused step
/// refusing all of them) and what its robot said. Returns what the step came to:
/// `executed` when it ran, `infeasible` with the refusal when the rules refused it,
/// `declined` when no part had an action. A part of a robot that is not in the team
/// refuses the step as the rules refuse any step with an action that cannot be
/// (`unknown_robot`, every other part `step_refused`), the parts left in the order given.
/// A part whose action `fails` (a failing-actions event of the task, with why) does not
/// act: `action_failed`; the others' step runs without it.
pub(crate) fn carry_out(
    env: &mut dyn Environment,
    task: &Task,
    parts: &mut [RobotPart],
    fails: &dyn Fn(NodeId) -> Option<String>,
) -> RoundOutcome {
    if let Some(refused) = unknown_robots(task, parts) {
        return refused;
    }
    parts.sort_by_key(|p| task.robots.iter().position(|r| task.id(r.node) == p.robot));
    let mut failed = 0;
    let mut acting = Vec::new();
    for (i, part) in parts.iter_mut().enumerate() {
        if part.decision.is_some() && part.action().is_none() {
            part.outcome = RoundOutcome::Declined;
        } else if part.action().is_some() {
            match fails(part.robot) {
                Some(message) => {
                    part.outcome = RoundOutcome::Infeasible {
                        reason: Reason::ActionFailed,
                        message,
                    };
                    failed += 1;
                }
                None => acting.push(i),
            }
        }
    }
    if acting.is_empty() {
        return match failed {
            0 => RoundOutcome::Declined,
            n => RoundOutcome::Infeasible {
                reason: Reason::ActionFailed,
                message: format!(
                    "every action of the step failed ({n}, by an event); nothing changed"
                ),
            },
        };
    }
    let step: Vec<(NodeId, String)> = acting
        .iter()
        .map(|&i| {
            (
                parts[i].robot,
                parts[i].action().unwrap_or_default().to_owned(),
            )
        })
        .collect();
    let pairs: Vec<(NodeId, &str)> = step.iter().map(|(r, a)| (*r, a.as_str())).collect();
    match env.step_joint(&pairs) {
        Ok(outcome) => {
            for (&i, part) in acting.iter().zip(outcome.parts) {
                parts[i].report = part.report;
                parts[i].outcome = match part.infeasible {
                    None => RoundOutcome::Executed,
                    Some(why) => RoundOutcome::Infeasible {
                        reason: why.reason.into(),
                        message: why.message,
                    },
                };
            }
            match outcome.refused {
                None => RoundOutcome::Executed,
                Some(refusal) => RoundOutcome::Infeasible {
                    reason: coherent_core::Reason::StepRefused.into(),
                    message: refusal.to_string(),
                },
            }
        }
        // The environment could not take the step at all.
        Err(e) => {
            for &i in &acting {
                parts[i].outcome = RoundOutcome::Infeasible {
                    reason: Reason::Error,
                    message: e.to_string(),
                };
            }
            RoundOutcome::Infeasible {
                reason: Reason::Error,
                message: e.to_string(),
            }
        }
    }
}

/// The refusal of a joint step whose parts name robots that are not in the team, with
/// each part's outcome set, or `None` when every robot is the team's.
fn unknown_robots(task: &Task, parts: &mut [RobotPart]) -> Option<RoundOutcome> {
    let unknown: Vec<NodeId> = parts
        .iter()
        .map(|p| p.robot)
        .filter(|r| task.robot_by_id(*r).is_err())
        .collect();
    if unknown.is_empty() {
        return None;
    }
    for p in parts.iter_mut() {
        p.outcome = match task.robot_by_id(p.robot) {
            Err(e) => RoundOutcome::Infeasible {
                reason: Reason::UnknownRobot,
                message: e.to_string(),
            },
            Ok(_) => RoundOutcome::Infeasible {
                reason: coherent_core::Reason::StepRefused.into(),
                message: "not carried out: the joint step names a robot that is not in the team"
                    .into(),
            },
        };
    }
    let ids: Vec<String> = unknown.iter().map(ToString::to_string).collect();
    Some(RoundOutcome::Infeasible {
        reason: Reason::UnknownRobot,
        message: format!("robot {} is not in the team", ids.join(", ")),
    })
}

/// The sentence of each part and, first, the one about the step as a whole (if any),
/// as one paragraph: what a method hears of a parallel round.
pub(crate) fn paragraph(step: Option<String>, parts: &[RobotPart]) -> String {
    step.into_iter()
        .chain(parts.iter().map(|p| p.feedback.clone()))
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}
