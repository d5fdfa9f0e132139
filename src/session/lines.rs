//! The lines an episode is told in: `coherent run` prints them as the rounds end, and
//! `coherent view` shows the same lines for a recorded episode.

use coherent_agents::prompts::fill::action_line;
use coherent_agents::transcript::{RobotPart, Round, RoundOutcome};
use coherent_core::text::shown;
use coherent_core::{Execution, NodeId, Task};

/// The lines `coherent run` prints for round `r` of an episode of `task` in `execution`
/// with the budget `max`: [`step`]'s one line for a sequential round, [`joint_step`]'s
/// for a parallel one.
pub fn round(task: &Task, r: &Round, max: u32, execution: Execution) -> Vec<String> {
    match execution {
        Execution::Sequential => vec![step(task, r, max)],
        Execution::Parallel => joint_step(task, r, max),
    }
}

/// The line `coherent run` prints for round `r` of a sequential episode of `task` with
/// the budget `max`: the step, the robot, the subtask (unless it is the action itself),
/// the action and what came of it, every text from outside [`shown`]. A method without a
/// proposal (every one but PEFA) is shown choosing `<robot>: <action>`, as it chose.
pub fn step(task: &Task, r: &Round, max: u32) -> String {
    let decision = r.decision.as_ref();
    let action = decision.and_then(|d| d.action.as_deref());
    let chosen = match (&r.proposal, decision.and_then(|d| d.robot), action) {
        (None, Some(robot), Some(action)) => Some(action_line(task, robot, action)),
        _ => action.map(str::to_owned),
    };
    let said = part_text(
        task,
        r.proposal.as_ref().map(|p| p.robot),
        r.proposal.as_ref().map(|p| p.subtask.as_str()),
        chosen.as_deref(),
        &outcome_text(&r.outcome, r.done),
    );
    format!("{}  {said}", head(r, max))
}

/// The lines of a parallel round: one for the step (how many robots acted, what the step
/// came to), then an indented line per robot's part, in team order ([`part`]).
pub fn joint_step(task: &Task, r: &Round, max: u32) -> Vec<String> {
    let acting = r.parts.iter().filter(|p| p.action().is_some()).count();
    let robots = if acting == 1 { "robot" } else { "robots" };
    let mut out = vec![format!(
        "{}  joint step, {acting} {robots}  -> {}",
        head(r, max),
        outcome_text(&r.outcome, r.done)
    )];
    out.extend(r.parts.iter().map(|p| format!("  {}", part(task, p))));
    out
}

/// One robot's part of a joint step: `<robot>  "subtask"  action  -> outcome`, the
/// subtask marked ` (kept)` when it was given in an earlier round.
pub fn part(task: &Task, p: &RobotPart) -> String {
    let subtask = p.proposal.as_ref().map(|proposal| {
        if p.kept {
            format!("{} (kept)", proposal.subtask)
        } else {
            proposal.subtask.clone()
        }
    });
    let action = p.decision.as_ref().and_then(|d| d.action.as_deref());
    let outcome = outcome_text(&p.outcome, false);
    part_text(task, Some(p.robot), subtask.as_deref(), action, &outcome)
}

fn head(r: &Round, max: u32) -> String {
    let width = max.to_string().len();
    format!("step {:>width$}/{max}", r.step)
}

/// `<robot>  "subtask"  action  -> outcome`, the subtask in quotes left out when it is
/// the action itself (the built-in backend's).
fn part_text(
    task: &Task,
    robot: Option<NodeId>,
    subtask: Option<&str>,
    action: Option<&str>,
    outcome: &str,
) -> String {
    let robot = robot.and_then(|r| task.idx(r)).map_or("-".to_owned(), |i| {
        shown(&task.node(i).label()).into_owned()
    });
    let action = action.map_or("-".to_owned(), |a| shown(a).into_owned());
    let subtask = subtask
        .filter(|s| shown(s) != action)
        .map_or(String::new(), |s| format!("{s:?}  "));
    format!("{robot}  {subtask}{action}  -> {outcome}")
}

fn outcome_text(outcome: &RoundOutcome, done: bool) -> String {
    match outcome {
        RoundOutcome::Executed if done => "ok, goal reached".to_owned(),
        RoundOutcome::Executed => "ok".to_owned(),
        RoundOutcome::Infeasible { reason, .. } => format!("infeasible ({})", reason.name()),
        RoundOutcome::Declined => "declined".to_owned(),
        RoundOutcome::NoProposal { why } => format!("no usable proposal: {}", shown(why)),
        RoundOutcome::NoDecision { why } => format!("no usable decision: {}", shown(why)),
        RoundOutcome::BackendError { message } => format!("backend failed: {}", shown(message)),
        // The last line of the error (a Python traceback ends with the exception).
        RoundOutcome::MethodError { message } => format!(
            "the method failed: {}",
            shown(message.trim_end().lines().last().unwrap_or(""))
        ),
    }
}
