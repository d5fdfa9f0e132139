//! The lines an episode is told in: `coherent run` prints them as the rounds end, and
//! `coherent view` shows the same lines for a recorded episode.

use coherent_agents::transcript::{Round, RoundOutcome};
use coherent_core::Task;
use coherent_core::text::shown;

/// The line `coherent run` prints for round `r` of an episode of `task` with the budget
/// `max`: the step, the robot, the subtask (unless it is the action itself), the action
/// and what came of it, every text from outside [`shown`].
pub fn step(task: &Task, r: &Round, max: u32) -> String {
    let robot = r
        .proposal
        .as_ref()
        .and_then(|p| task.idx(p.robot))
        .map_or("-".to_owned(), |i| {
            shown(&task.node(i).label()).into_owned()
        });
    let action = r
        .decision
        .as_ref()
        .and_then(|d| d.action.as_deref())
        .map_or("-".to_owned(), |a| shown(a).into_owned());
    // The subtask in quotes, unless it is the action itself (the built-in backend's).
    let subtask = r
        .proposal
        .as_ref()
        .filter(|p| shown(&p.subtask) != action)
        .map_or(String::new(), |p| format!("{:?}  ", p.subtask));
    let outcome = match &r.outcome {
        RoundOutcome::Executed if r.done => "ok, goal reached".to_owned(),
        RoundOutcome::Executed => "ok".to_owned(),
        RoundOutcome::Infeasible { reason, .. } => format!("infeasible ({})", shown(reason)),
        RoundOutcome::Declined => "declined".to_owned(),
        RoundOutcome::NoProposal { why } => format!("no usable proposal: {}", shown(why)),
        RoundOutcome::NoDecision { why } => format!("no usable decision: {}", shown(why)),
        RoundOutcome::BackendError { message } => format!("backend failed: {}", shown(message)),
        // The last line of the error (a Python traceback ends with the exception).
        RoundOutcome::MethodError { message } => format!(
            "the method failed: {}",
            shown(message.trim_end().lines().last().unwrap_or(""))
        ),
    };
    let width = max.to_string().len();
    format!(
        "step {:>width$}/{max}  {robot}  {subtask}{action}  -> {outcome}",
        r.step
    )
}
