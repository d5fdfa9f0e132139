//! What every method does with a parallel round's joint step: the actions its robots'
//! parts decided on, carried out at once through [`Environment::step_joint`], each part's
//! outcome recorded, and what the step as a whole came to.

use coherent_core::{Environment, NodeId};

use crate::records::transcript::{RobotPart, Round, RoundOutcome};

/// Carries out the joint step of `parts`: every part whose decision names an action acts,
/// at once; one whose decision names none is `declined`, and one without a decision keeps
/// the outcome the method gave it (why there is none). Each acting part gets its outcome
/// (executed, or the rules' reason, a refused step refusing all of them) and what its
/// robot said. Returns what the step came to: `executed` when it ran, `infeasible` with
/// the refusal when the rules refused it, `declined` when no part had an action.
pub(crate) fn carry_out(
    env: &mut (dyn Environment + Send),
    parts: &mut [RobotPart],
) -> RoundOutcome {
    let acting: Vec<usize> = (0..parts.len())
        .filter(|&i| parts[i].action().is_some())
        .collect();
    for part in parts.iter_mut() {
        if part.decision.is_some() && part.action().is_none() {
            part.outcome = RoundOutcome::Declined;
        }
    }
    if acting.is_empty() {
        return RoundOutcome::Declined;
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
                        reason: why.reason.name().to_owned(),
                        message: why.message,
                    },
                };
            }
            match outcome.refused {
                None => RoundOutcome::Executed,
                Some(refusal) => RoundOutcome::Infeasible {
                    reason: "step_refused".into(),
                    message: refusal.to_string(),
                },
            }
        }
        // A robot the team does not have (the methods check theirs first).
        Err(e) => {
            for &i in &acting {
                parts[i].outcome = RoundOutcome::Infeasible {
                    reason: "error".into(),
                    message: e.to_string(),
                };
            }
            RoundOutcome::Infeasible {
                reason: "error".into(),
                message: e.to_string(),
            }
        }
    }
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

/// Closes a parallel round: its parts, the step's outcome, what is heard of it, and
/// whether the goal holds.
pub(crate) fn close(
    env: &(dyn Environment + Send),
    round: &mut Round,
    parts: Vec<RobotPart>,
    outcome: RoundOutcome,
    feedback: String,
) {
    round.parts = parts;
    round.outcome = outcome;
    round.feedback = feedback;
    round.done = env.goal_satisfied();
}
