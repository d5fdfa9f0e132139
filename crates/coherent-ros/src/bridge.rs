//! [`Ros2Env`]: the rules decide what may be done, a robot's ROS 2 action server does it,
//! and the symbolic state moves only when the robot reports success and what it then
//! observes agrees with the rules.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use coherent_core::feasibility::{self, Infeasible, Reason};
use coherent_core::{Action, Environment, NodeId, Outcome, Robot, RobotReport, State, Task, rules};
use ros2_client::action::GoalStatusEnum;

use crate::error::Error;
use crate::link::{Exchange, Link};
use crate::relations;
use crate::wire::{self, ExecuteResult, Goal};

/// Where the robots are and how long to wait for them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BridgeOptions {
    /// The namespace of the robots' actions (absolute, see [`wire::namespace`]).
    pub namespace: String,
    /// The longest a robot may stay silent during a step (no answer to the goal, no
    /// feedback, no result) before the step fails and the episode stops.
    pub robot_timeout: Duration,
    /// How long to wait for every robot's server before the first step.
    pub server_wait: Duration,
}

impl Default for BridgeOptions {
    fn default() -> BridgeOptions {
        BridgeOptions {
            namespace: wire::DEFAULT_NAMESPACE.to_owned(),
            robot_timeout: Duration::from_secs(10),
            server_wait: Duration::from_secs(10),
        }
    }
}

/// An environment whose actions robots carry out, one ROS 2 action server per robot.
#[derive(Debug)]
pub struct Ros2Env {
    task: Arc<Task>,
    state: State,
    options: BridgeOptions,
    /// The robots' ROS names, in the task's order.
    names: Vec<String>,
    link: Link,
    /// The episode's cancel flag (Ctrl-C): a goal in flight is cancelled when it rises.
    cancel: Option<Arc<AtomicBool>>,
    /// Actions tried since the start or the last reset (the goals' `step`).
    steps: u32,
    /// Why the bridge stopped, once it has.
    stopped: Option<(Reason, String)>,
}

impl Ros2Env {
    /// Connects to the servers of `task`'s robots, waiting up to
    /// [`BridgeOptions::server_wait`] for all of them; `cancel` is the episode's flag,
    /// `runtime` the one DDS work is spun on.
    pub fn connect(
        task: Arc<Task>,
        options: BridgeOptions,
        cancel: Option<Arc<AtomicBool>>,
        runtime: tokio::runtime::Handle,
    ) -> Result<Ros2Env, Error> {
        let names = wire::robot_names(&task);
        let link = Link::connect(&options.namespace, &names, options.server_wait, runtime)?;
        Ok(Ros2Env {
            state: task.init.clone(),
            task,
            options,
            names,
            link,
            cancel,
            steps: 0,
            stopped: None,
        })
    }

    pub fn options(&self) -> &BridgeOptions {
        &self.options
    }

    /// The robots' ROS names, in the task's order.
    pub fn robot_names(&self) -> &[String] {
        &self.names
    }

    fn refuse(&self, reason: Reason, message: String, report: RobotReport) -> Outcome {
        Outcome {
            infeasible: Some(Infeasible { reason, message }),
            done: self.goal_satisfied(),
            report: Some(report),
        }
    }

    /// Stops the bridge: no later step is sent, and the episode ends.
    fn stop(&mut self, reason: Reason, why: &str) {
        self.stopped.get_or_insert_with(|| (reason, why.to_owned()));
    }
}

impl Environment for Ros2Env {
    fn task(&self) -> &Task {
        &self.task
    }

    fn state(&self) -> &State {
        &self.state
    }

    /// Nothing the rules refuse is sent. A feasible action goes to its robot's server;
    /// the step is executed when the robot reports success and every relation it then
    /// observes holds in the rules' state after the action. A failure is refused with
    /// the robot's reason and message; silence, a DDS failure or a disagreement stop the
    /// bridge, since the world can no longer be known; a cancelled goal is refused.
    fn step(&mut self, robot: NodeId, action: &str) -> coherent_core::Result<Outcome> {
        let r = self.task.robot_by_id(robot)?;
        self.steps += 1;
        let a = match feasibility::check(&self.task, &self.state, r, action) {
            Ok(a) => a,
            Err(why) => {
                return Ok(Outcome {
                    infeasible: Some(why),
                    done: self.goal_satisfied(),
                    report: None,
                });
            }
        };
        let n = self
            .task
            .robots
            .iter()
            .position(|x| x.node == r.node)
            .expect("robot_by_id found it among the robots");
        let name = self.names[n].clone();
        let mut report = RobotReport {
            robot: name.clone(),
            via: format!("ros2 {}", wire::action_name(&self.options.namespace, &name)),
            message: String::new(),
        };
        if let Some((reason, why)) = &self.stopped {
            report.message = format!("not sent: the bridge has stopped ({why})");
            return Ok(self.refuse(*reason, report.message.clone(), report));
        }
        let text = a.render(&self.task);
        let goal = Goal {
            action: text.clone(),
            step: self.steps,
        };
        let exchange =
            self.link
                .exchange(n, goal, self.options.robot_timeout, self.cancel.as_deref());
        let (reason, message) = match exchange {
            Exchange::Result { status, result } => {
                report.message = result.message.clone();
                let succeeded = status == GoalStatusEnum::Succeeded;
                match judge(&self.task, &self.state, &name, r, a, succeeded, result) {
                    Verdict::Done(after) => {
                        self.state = after;
                        return Ok(Outcome {
                            infeasible: None,
                            done: self.goal_satisfied(),
                            report: Some(report),
                        });
                    }
                    Verdict::Failed(reason, message) => (reason, message),
                    Verdict::Disagrees(why) => {
                        self.stop(Reason::Disagreement, &why);
                        (Reason::Disagreement, why)
                    }
                }
            }
            Exchange::Rejected => (Reason::Rejected, format!("{name} refused the goal {text}")),
            Exchange::Silent { last } => {
                let why = format!(
                    "{name} did not answer {text} within {:.1} s (last heard: {last})",
                    self.options.robot_timeout.as_secs_f64()
                );
                self.stop(Reason::Timeout, &why);
                (Reason::Timeout, why)
            }
            // The episode that raised the flag ends; the bridge itself need not stop.
            Exchange::Cancelled { acknowledged } => (
                Reason::Cancelled,
                format!(
                    "{text} was cancelled ({}) before {name} reported a result",
                    if acknowledged {
                        "the robot acknowledged it"
                    } else {
                        "without the robot's acknowledgement"
                    }
                ),
            ),
            Exchange::Failed(why) => {
                let why = format!("{name}: {why}");
                self.stop(Reason::Robot, &why);
                (Reason::Robot, why)
            }
        };
        if report.message.is_empty() {
            report.message.clone_from(&message);
        }
        Ok(self.refuse(reason, message, report))
    }

    /// The rules' state only: the robots' world is theirs to put back (restart
    /// `coherent robots serve`).
    fn reset(&mut self) {
        self.state = self.task.init.clone();
        self.steps = 0;
        self.stopped = None;
    }

    fn stopped(&self) -> Option<String> {
        self.stopped.as_ref().map(|(_, why)| why.clone())
    }
}

/// What a robot's result does to the rules' state.
#[derive(Debug)]
enum Verdict {
    /// The robot succeeded and what it observes holds: the state after the action.
    Done(State),
    /// The robot failed: its reason (a feasibility reason's name, else `robot`) and its
    /// message.
    Failed(Reason, String),
    /// The robot succeeded, but what it observes disagrees with the rules: each relation
    /// with what the rules have.
    Disagrees(String),
}

/// Judges the result of action `a` of robot `r` (ROS name `name`) from `state`;
/// `succeeded` is whether the goal ended as succeeded.
fn judge(
    task: &Task,
    state: &State,
    name: &str,
    r: Robot,
    a: Action,
    succeeded: bool,
    result: ExecuteResult,
) -> Verdict {
    if !succeeded || !result.success {
        let reason = Reason::from_name(&result.reason).unwrap_or(Reason::Robot);
        let message = if result.message.is_empty() {
            format!("{name} did not carry it out")
        } else {
            result.message
        };
        return Verdict::Failed(reason, message);
    }
    let mut after = state.clone();
    rules::apply(task, &mut after, r, a);
    let diffs = relations::disagreements(task, &after, &result.relations);
    if diffs.is_empty() {
        Verdict::Done(after)
    } else {
        Verdict::Disagrees(format!(
            "{name} reports {} done, but what it observes disagrees with the rules: {}",
            a.render(task),
            diffs.join("; ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::relations::tests::demo;

    fn result(success: bool, reason: &str, message: &str) -> ExecuteResult {
        ExecuteResult {
            success,
            reason: reason.into(),
            message: message.into(),
            relations: Vec::new(),
        }
    }

    #[test]
    fn a_result_moves_the_state_only_on_success_with_agreeing_relations() {
        let task = demo();
        let arm = task.robots[0];
        let grab = feasibility::check(&task, &task.init, arm, "[grab] <mug>(7)").expect("feasible");
        let mut expected = task.init.clone();
        rules::apply(&task, &mut expected, arm, grab);
        let seen = relations::observed(&task, &expected, arm.node);
        let ok = ExecuteResult {
            relations: seen.clone(),
            ..result(true, "", "done")
        };
        match judge(
            &task,
            &task.init,
            "robot_arm_6",
            arm,
            grab,
            true,
            ok.clone(),
        ) {
            Verdict::Done(after) => assert!(after == expected),
            other => panic!("{other:?}"),
        }
        // Succeeded by its word but not by the goal's status, or the other way round.
        for (succeeded, r) in [(false, ok), (true, result(false, "", ""))] {
            match judge(&task, &task.init, "robot_arm_6", arm, grab, succeeded, r) {
                Verdict::Failed(Reason::Robot, _) => {}
                other => panic!("{other:?}"),
            }
        }
        // What it observed before grabbing is not what the rules have after it.
        let before = ExecuteResult {
            relations: relations::observed(&task, &task.init, arm.node),
            ..result(true, "", "done")
        };
        match judge(&task, &task.init, "robot_arm_6", arm, grab, true, before) {
            Verdict::Disagrees(why) => assert!(
                why.starts_with("robot_arm_6 reports [grab] <mug>(7) done, but what it observes")
                    && why.contains("<mug>(7) ON "),
                "{why}"
            ),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_failure_keeps_the_robots_reason_and_message() {
        let task = demo();
        let arm = task.robots[0];
        let grab = feasibility::check(&task, &task.init, arm, "[grab] <mug>(7)").expect("feasible");
        let judged =
            |r: ExecuteResult| match judge(&task, &task.init, "robot_arm_6", arm, grab, false, r) {
                Verdict::Failed(reason, message) => (reason, message),
                other => panic!("{other:?}"),
            };
        assert_eq!(
            judged(result(false, "out_of_reach", "the mug is too far")),
            (Reason::OutOfReach, "the mug is too far".to_owned())
        );
        assert_eq!(
            judged(result(false, "gripper_jammed", "the gripper jammed")),
            (Reason::Robot, "the gripper jammed".to_owned())
        );
        assert_eq!(
            judged(result(false, "", "")),
            (Reason::Robot, "robot_arm_6 did not carry it out".to_owned())
        );
    }
}
