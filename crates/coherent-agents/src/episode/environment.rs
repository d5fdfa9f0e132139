//! What every method does with the [`Environment`]: observe the whole team, and check
//! and run one robot's action.

use coherent_core::{Environment, NodeId, Task};

use crate::prompts::fill::Sight;
use crate::records::transcript::{Reason, Round, RoundOutcome};

/// Checks and runs `action` for `robot`: executed, or why not; what a robot outside this
/// process said about it goes into `round`.
pub(crate) fn execute(
    env: &mut dyn Environment,
    round: &mut Round,
    robot: NodeId,
    action: &str,
) -> RoundOutcome {
    match env.step(robot, action) {
        Ok(o) => {
            round.robot = o.report;
            match o.infeasible {
                None => RoundOutcome::Executed,
                Some(why) => RoundOutcome::Infeasible {
                    reason: why.reason.into(),
                    message: why.message,
                },
            }
        }
        Err(e) => RoundOutcome::Infeasible {
            reason: Reason::Error,
            message: e.to_string(),
        },
    }
}

/// What the whole team sees: every robot's observation, after `news` (what happened
/// since the last round that the team did not do).
pub(crate) fn team_sight<'a>(
    env: &'a dyn Environment,
    task: &'a Task,
    news: &'a [String],
) -> Sight<'a> {
    Sight {
        task,
        news,
        state: env.state(),
        observations: task
            .robots
            .iter()
            .filter_map(|r| env.observe(task.id(r.node)).ok())
            .collect(),
    }
}
