//! The record of a decision: what a round keeps of the action a method chose (the
//! central and dialogue baselines, MCTS, the optimal plan and a method written outside
//! the crate alike; PEFA's executor answers a [`Decision`] of its own), and the action a
//! round ran, as the baselines' history recalls it.

use coherent_core::{Environment, NodeId, Task};

use crate::episode::environment::execute;
use crate::methods::feedback;
use crate::methods::prompt::robot_label;
use crate::records::transcript::{Decision, Round, RoundOutcome};

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
    round.feedback = feedback::joint(&line, &round.outcome);
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
    round.feedback = feedback::joint("", &round.outcome);
}

/// The `<robot>: <action>` line the round ran, when its action ran: what the baselines'
/// history recalls.
pub(crate) fn executed_line(round: &Round) -> Option<String> {
    match round.outcome {
        RoundOutcome::Executed => round.decision.as_ref().and_then(|d| d.action.clone()),
        _ => None,
    }
}
