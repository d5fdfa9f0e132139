//! The record of a decision, for the methods that choose robots' actions themselves (the
//! central and dialogue baselines, MCTS, the optimal plan, the random floor and a method
//! written outside the crate; PEFA's executor answers a [`Decision`] of its own): the
//! robot and action a round chose, in a parallel round each robot's part, what such a
//! method hears of a round, and the actions a round ran, as the baselines' history
//! recalls them.

use coherent_core::{Environment, NodeId, Task};

use crate::episode::joint;
use crate::methods::feedback;
use crate::prompts::fill::action_line;
use crate::records::transcript::{Decision, RobotPart, Round};

/// Records `robot`'s `action` as the round's decision, for the loop to carry out.
pub(crate) fn choose(round: &mut Round, robot: NodeId, action: &str, note: String) {
    round.decision = Some(Decision {
        robot: Some(robot),
        can_do: true,
        action: Some(action.to_owned()),
        subtask_complete: true,
        note,
    });
}

/// Records that the method chose no action this round (the step still counts).
pub(crate) fn nothing(round: &mut Round, note: String) {
    round.decision = Some(Decision {
        robot: None,
        can_do: false,
        action: None,
        subtask_complete: false,
        note,
    });
}

/// The part of `robot` in a parallel round whose method chose `action` for it (with its
/// action list where `env` stands, before the step).
pub(crate) fn part(env: &dyn Environment, robot: NodeId, action: &str, note: String) -> RobotPart {
    RobotPart {
        actions: env.actions(robot).unwrap_or_default(),
        decision: Some(Decision {
            robot: Some(robot),
            can_do: true,
            action: Some(action.to_owned()),
            subtask_complete: true,
            note,
        }),
        ..RobotPart::new(robot)
    }
}

/// What such a method hears of a closed round, in [`Round::feedback`]: of a sequential
/// round, what came of its `<robot>: <action>` ([`feedback::team`]); of a parallel one,
/// each part's sentence (in its own feedback too) after `step_note` (what of the
/// method's answer was not used, say), or what came of the step when no part says
/// anything.
pub(crate) fn team_feedback(task: &Task, round: &mut Round, step_note: Option<String>) {
    let line = |robot: Option<NodeId>, action: Option<&str>| match (robot, action) {
        (Some(robot), Some(action)) => action_line(task, robot, action),
        _ => String::new(),
    };
    if round.parts.is_empty() {
        let d = round.decision.as_ref();
        let said = line(d.and_then(|d| d.robot), d.and_then(|d| d.action.as_deref()));
        round.feedback = feedback::team(&said, &round.outcome);
        return;
    }
    for p in &mut round.parts {
        p.feedback = feedback::team(&line(Some(p.robot), p.action()), &p.outcome);
    }
    let paragraph = joint::paragraph(step_note, &round.parts);
    round.feedback = if paragraph.is_empty() {
        feedback::team("", &round.outcome)
    } else {
        paragraph
    };
}

/// What the round ran, as the baselines' history recalls it: its `<robot>: <action>`
/// line, or of a parallel round the lines of the joint step's actions that ran, joined
/// by `; `; `None` when nothing ran.
pub(crate) fn executed_line(task: &Task, round: &Round) -> Option<String> {
    let ran: Vec<String> = round
        .carried_out()
        .into_iter()
        .map(|(robot, action)| action_line(task, robot, action))
        .collect();
    (!ran.is_empty()).then(|| ran.join("; "))
}
