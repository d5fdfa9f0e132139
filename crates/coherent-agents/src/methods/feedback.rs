//! Feedback: what a method's next rounds hear about a round, in words. PEFA's assigner
//! hears the executor's self-reflection on the checked outcome ([`pefa`]; a robot's part
//! of a parallel round, [`pefa_part`]), with the engine's reasons when the executor
//! declined or gave no usable answer ([`obstacles`]), and keeps the last rounds as
//! history lines ([`assigner_history`]); the central and dialogue baselines hear what ran
//! ([`team`]); MCTS records what its chosen action did ([`mcts`]). A transcript keeps
//! each round's feedback, and a replay must give it back word for word.

use coherent_core::reach::{self, Reach};
use coherent_core::{NodeId, State, Task};

use crate::prompts::fill::robot_label;
use crate::records::transcript::{Decision, Proposal, RobotPart, Round, RoundOutcome};

/// The most things of a subtask whose obstacles the feedback lists.
pub const MAX_OBSTACLES: usize = 6;

/// What the assigner hears about a round, PEFA's Feedback: self-reflection built from
/// the executor's answer and the checked outcome (or why the round never got that far),
/// in state `s` (where the round left the world). When the executor declined or its
/// answer could not be used, one line more for each thing the subtask names that its
/// robot cannot act on now ([`obstacles`]).
pub fn pefa(task: &Task, s: &State, round: &Round, outcome: &RoundOutcome) -> String {
    let said = reflection(
        task,
        round.proposal.as_ref().map(|p| p.robot),
        &round.actions,
        round.decision.as_ref(),
        outcome,
    );
    explained(task, s, round.proposal.as_ref(), said, outcome)
}

/// What the assigner hears about one robot's part of a parallel round, in state `s`
/// (where the step left the world), as [`pefa`] tells a sequential round.
pub fn pefa_part(task: &Task, s: &State, part: &RobotPart) -> String {
    let said = reflection(
        task,
        Some(part.robot),
        &part.actions,
        part.decision.as_ref(),
        &part.outcome,
    );
    explained(task, s, part.proposal.as_ref(), said, &part.outcome)
}

/// `said`, with the obstacles of the subtask when the executor declined it or gave no
/// usable answer.
fn explained(
    task: &Task,
    s: &State,
    proposal: Option<&Proposal>,
    said: String,
    outcome: &RoundOutcome,
) -> String {
    let explained = matches!(
        outcome,
        RoundOutcome::Declined | RoundOutcome::NoDecision { .. }
    );
    match proposal {
        Some(p) if explained => {
            let lines = obstacles(task, s, p.robot, &p.subtask);
            if lines.is_empty() {
                said
            } else {
                format!("{said}\n{}", lines.join("\n"))
            }
        }
        _ => said,
    }
}

/// For each thing `subtask` names (as `<name>(id)`, at most [`MAX_OBSTACLES`]) that
/// `robot` cannot act on in state `s`, one line: the engine's reason
/// ([`reach::why_not`]) and which other robots of the team, by type, could get at it
/// ([`reach::reach`]): now, or after moves of their own.
pub fn obstacles(task: &Task, s: &State, robot: NodeId, subtask: &str) -> Vec<String> {
    let Ok(me) = task.robot_by_id(robot) else {
        return Vec::new();
    };
    reach::things_named(task, subtask)
        .into_iter()
        .filter_map(|x| {
            let why = reach::why_not(task, s, me, x)?;
            let others: Vec<String> = task
                .robots
                .iter()
                .filter(|r| r.node != me.node)
                .filter_map(|r| {
                    let who = format!("{} ({})", task.node(r.node).label(), r.kind);
                    match reach::reach(task, s, *r, x) {
                        Reach::Now => Some(format!("{who} can get at it now")),
                        Reach::After(1) => Some(format!("{who} could after 1 move of its own")),
                        Reach::After(n) => Some(format!("{who} could after {n} moves of its own")),
                        Reach::Never => None,
                    }
                })
                .collect();
            let others = if others.is_empty() {
                "No other robot of the team could get at it.".to_owned()
            } else {
                format!("{}.", others.join("; "))
            };
            Some(format!(
                "- {}: {} ({}). {others}",
                task.node(x).label(),
                why.message,
                why.reason.name()
            ))
        })
        .take(MAX_OBSTACLES)
        .collect()
}

/// The executor's self-reflection: `robot` is the one the proposal named, `actions` its
/// list, `decision` its executor's.
fn reflection(
    task: &Task,
    robot: Option<NodeId>,
    actions: &[String],
    decision: Option<&Decision>,
    outcome: &RoundOutcome,
) -> String {
    let robot = robot.map(|r| robot_label(task, r)).unwrap_or_default();
    let action = decision.and_then(|d| d.action.clone()).unwrap_or_default();
    let can_do_now = || {
        if actions.is_empty() {
            format!("{robot} can do nothing now.")
        } else {
            format!("{robot} can do now: {}.", actions.join("; "))
        }
    };
    match outcome {
        RoundOutcome::Executed => {
            let done = decision.is_some_and(|d| d.subtask_complete);
            let note = decision
                .map(|d| d.note.trim().to_owned())
                .unwrap_or_default();
            if done {
                format!("{robot} did {action}. The subtask is complete.")
            } else if note.is_empty() {
                format!("{robot} did {action}. The subtask is not complete yet.")
            } else {
                format!("{robot} did {action}. The subtask is not complete yet: {note}")
            }
        }
        RoundOutcome::Infeasible { message, .. } => {
            format!(
                "{robot} tried {action}, which cannot be done: {message}. {}",
                can_do_now()
            )
        }
        RoundOutcome::Declined => {
            let note = decision
                .map(|d| d.note.trim().to_owned())
                .filter(|n| !n.is_empty())
                .unwrap_or_else(|| "no reason given".into());
            format!(
                "{robot} cannot do this subtask now ({note}). {}",
                can_do_now()
            )
        }
        RoundOutcome::NoProposal { why } => format!(
            "Your answer could not be used ({why}). Name one robot of the team and one subtask."
        ),
        RoundOutcome::NoDecision { why } => {
            format!("{robot} gave no usable answer ({why}). {}", can_do_now())
        }
        RoundOutcome::BackendError { message } => {
            format!("The model could not be reached: {message}")
        }
        RoundOutcome::MethodError { message } => format!("The method failed: {message}"),
    }
}

/// The line PEFA's assigner reads about a round in its history (the Adjustment); of a
/// parallel round, what became of each robot's subtask.
pub fn assigner_history(task: &Task, round: &Round) -> String {
    if !round.parts.is_empty() {
        return format!("Round {}: {}", round.step, round.feedback);
    }
    match &round.proposal {
        Some(p) => format!(
            "Round {}: you asked {} to \"{}\". {}",
            round.step,
            robot_label(task, p.robot),
            p.subtask,
            round.feedback
        ),
        None => format!("Round {}: {}", round.step, round.feedback),
    }
}

/// What a round of a central or dialogue method did (`line` is its `<robot>: <action>`),
/// in a sentence.
pub fn team(line: &str, outcome: &RoundOutcome) -> String {
    match outcome {
        RoundOutcome::Executed => format!("{line} ran."),
        RoundOutcome::Infeasible { message, .. } => format!("{line} could not run: {message}"),
        RoundOutcome::NoProposal { why } | RoundOutcome::NoDecision { why } => {
            format!("No usable answer: {why}")
        }
        RoundOutcome::BackendError { message } => {
            format!("The model could not be reached: {message}")
        }
        RoundOutcome::MethodError { message } => format!("The method failed: {message}"),
        RoundOutcome::Declined => "No action was chosen.".to_owned(),
    }
}

/// What MCTS's chosen action (`robot` label, `action` text) did, or that no robot could
/// act (`None`).
pub fn mcts(chosen: Option<(&str, &str)>, outcome: &RoundOutcome) -> String {
    match (chosen, outcome) {
        (None, _) => "No robot can act now.".to_owned(),
        (Some((robot, action)), RoundOutcome::Infeasible { message, .. }) => {
            format!("{robot} tried {action}, which cannot be done: {message}")
        }
        (Some((robot, action)), _) => format!("{robot} did {action}."),
    }
}
