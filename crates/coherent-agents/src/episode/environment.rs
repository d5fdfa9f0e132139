//! What every method does with the [`Environment`]: observe the whole team, and check
//! and run one robot's action.

use coherent_core::{Environment, NodeId, Task, describe};

use crate::records::transcript::{Round, RoundOutcome};

/// Checks and runs `action` for `robot`: executed, or why not; what a robot outside this
/// process said about it goes into `round`.
pub(crate) fn execute(
    env: &mut (dyn Environment + Send),
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
                    reason: why.reason.name().to_owned(),
                    message: why.message,
                },
            }
        }
        Err(e) => RoundOutcome::Infeasible {
            reason: "error".into(),
            message: e.to_string(),
        },
    }
}

/// Every robot's observation, merged, as facts.
pub(crate) fn team_observation(env: &(dyn Environment + Send), task: &Task) -> String {
    let observations: Vec<_> = task
        .robots
        .iter()
        .filter_map(|r| env.observe(task.id(r.node)).ok())
        .collect();
    let refs: Vec<_> = observations.iter().collect();
    describe::facts(task, env.state(), &refs)
}
