//! The record of a decision: what a round keeps of the action a method chose (the
//! central and dialogue baselines, MCTS, the optimal plan and a method written outside
//! the crate alike; PEFA's executor answers a [`Decision`] of its own), in a parallel
//! round the part of each robot a method chose an action for, and the actions a round
//! ran, as the baselines' history recalls them.

use coherent_core::{Environment, NodeId, Task};

use crate::episode::environment::execute;
use crate::episode::joint;
use crate::methods::feedback;
use crate::methods::prompt::robot_label;
use crate::records::transcript::{Decision, RobotPart, Round, RoundOutcome};

/// Runs `robot`'s `action` as the round's decision: checks and executes it, then records
/// it with what came of it ([`decided`]).
pub(crate) fn act(
    env: &mut (dyn Environment + Send),
    task: &Task,
    round: &mut Round,
    robot: NodeId,
    action: &str,
    note: String,
) {
    let outcome = execute(env, round, robot, action);
    decided(task, round, robot, action, outcome, note);
}

/// Records `robot`'s `action` as the round's decision (its `<robot>: <action>` line),
/// with what came of it (`outcome`) and the sentence that says so.
pub(crate) fn decided(
    task: &Task,
    round: &mut Round,
    robot: NodeId,
    action: &str,
    outcome: RoundOutcome,
    note: String,
) {
    let line = format!("{}: {action}", robot_label(task, robot));
    round.outcome = outcome;
    round.feedback = feedback::team(&line, &round.outcome);
    round.decision = Some(Decision {
        can_do: true,
        action: Some(line),
        subtask_complete: true,
        note,
    });
}

/// Records that the method chose no action this round (the step still counts).
pub(crate) fn no_action(round: &mut Round, note: String) {
    round.decision = Some(Decision {
        can_do: false,
        action: None,
        subtask_complete: false,
        note,
    });
    round.outcome = RoundOutcome::Declined;
    round.feedback = feedback::team("", &round.outcome);
}

/// The part of `robot` in a parallel round whose method chose `action` for it (with its
/// action list where `env` stands, before the step).
pub(crate) fn part(
    env: &(dyn Environment + Send),
    robot: NodeId,
    action: &str,
    note: String,
) -> RobotPart {
    RobotPart {
        actions: env.actions(robot).unwrap_or_default(),
        decision: Some(Decision {
            can_do: true,
            action: Some(action.to_owned()),
            subtask_complete: true,
            note,
        }),
        ..RobotPart::new(robot)
    }
}

/// Carries out the joint step of `parts` (in team order) as the round's, each part told
/// what came of its action in a sentence ([`feedback::team`]), the round told of the step
/// after `step_note` (what of the method's answer was not used, say).
pub(crate) fn act_jointly(
    env: &mut (dyn Environment + Send),
    task: &Task,
    round: &mut Round,
    mut parts: Vec<RobotPart>,
    step_note: Option<String>,
) {
    parts.sort_by_key(|p| task.robots.iter().position(|r| task.id(r.node) == p.robot));
    let outcome = joint::carry_out(env, &mut parts);
    for p in &mut parts {
        let line = match p.action() {
            Some(action) => format!("{}: {action}", robot_label(task, p.robot)),
            None => String::new(),
        };
        p.feedback = feedback::team(&line, &p.outcome);
    }
    let paragraph = joint::paragraph(step_note, &parts);
    let feedback = if paragraph.is_empty() {
        feedback::team("", &outcome)
    } else {
        paragraph
    };
    joint::close(env, round, parts, outcome, feedback);
}

/// What the round ran, as the baselines' history recalls it: its `<robot>: <action>`
/// line, or of a parallel round the lines of the joint step's actions that ran, joined
/// by `; `; `None` when nothing ran.
pub(crate) fn executed_line(task: &Task, round: &Round) -> Option<String> {
    if !round.parts.is_empty() {
        let ran: Vec<String> = round
            .parts
            .iter()
            .filter(|p| p.outcome == RoundOutcome::Executed)
            .filter_map(|p| Some(format!("{}: {}", robot_label(task, p.robot), p.action()?)))
            .collect();
        return (!ran.is_empty()).then(|| ran.join("; "));
    }
    match round.outcome {
        RoundOutcome::Executed => round.decision.as_ref().and_then(|d| d.action.clone()),
        _ => None,
    }
}
