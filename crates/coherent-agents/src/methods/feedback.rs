//! Feedback: what a method's next rounds hear about a round, in words. PEFA's assigner
//! hears the executor's self-reflection on the checked outcome ([`pefa`]) and keeps the
//! last rounds as history lines ([`assigner_history`]); the central and dialogue
//! baselines hear what ran ([`team`]); MCTS records what its chosen action did
//! ([`mcts`]). A transcript keeps each round's feedback, and a replay must give it back
//! word for word.

use coherent_core::{NodeId, Task};

use crate::methods::prompt::robot_label;
use crate::records::transcript::{Decision, RobotPart, Round, RoundOutcome};

/// What the assigner hears about a round, PEFA's Feedback: self-reflection built from
/// the executor's answer and the checked outcome (or why the round never got that far).
/// `robot` is the one the proposal named, `actions` its list, `decision` its executor's;
/// in a parallel round, a robot's part ([`pefa_part`]).
pub fn pefa(
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

/// What the assigner hears about one robot's part of a parallel round ([`pefa`]).
pub fn pefa_part(task: &Task, part: &RobotPart) -> String {
    pefa(
        task,
        Some(part.robot),
        &part.actions,
        part.decision.as_ref(),
        &part.outcome,
    )
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
