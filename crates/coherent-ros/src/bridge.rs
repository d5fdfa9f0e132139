//! [`Ros2Env`]: the rules decide what may be done, a robot's ROS 2 action server does it,
//! and the symbolic state moves only when the robot reports success and what it then
//! observes agrees with the rules. A joint step's goals are in flight together, one per
//! robot, and the step lasts as long as its slowest robot.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use coherent_core::env::{refused_outcome, resolve_joint};
use coherent_core::feasibility::{self, Infeasible, Reason};
use coherent_core::joint::Part;
use coherent_core::{
    Action, Environment, JointOutcome, NodeId, Outcome, PartOutcome, Robot, RobotReport, State,
    Task, rules,
};
use ros2_client::action::GoalStatusEnum;

use crate::befall;
use crate::error::Error;
use crate::link::{Befell, Exchange};
use crate::link_process::{LinkCommand, LinkProcess};
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
    /// How to start the process that holds the DDS side ([`crate::link_process`]).
    pub link: LinkCommand,
}

/// An environment whose actions robots carry out, one ROS 2 action server per robot.
#[derive(Debug)]
pub struct Ros2Env {
    /// The task as connected: its robots are the servers', in [`Ros2Env::names`]' order.
    base: Arc<Task>,
    /// The task as events have left it (its team, its doors): the rules' world.
    task: Arc<Task>,
    state: State,
    /// The team and the locked doors the world's service was last told of; `None` until
    /// it is told (a world served before may hold anything).
    told: Option<(Vec<String>, Vec<String>)>,
    options: BridgeOptions,
    /// The robots' ROS names, in the task's order.
    names: Vec<String>,
    /// The DDS side, in a process of its own.
    link: LinkProcess,
    /// The episode's cancel flag (Ctrl-C): a goal in flight is cancelled when it rises.
    cancel: Option<Arc<AtomicBool>>,
    /// Actions tried since the start or the last reset (the goals' `step`).
    steps: u32,
    /// Why the bridge stopped, once it has.
    stopped: Option<(Reason, String)>,
}

impl Ros2Env {
    /// Starts the link process ([`BridgeOptions::link`]), which connects to the servers
    /// of `task`'s robots, waiting up to [`BridgeOptions::server_wait`] for all of them;
    /// `cancel` is the episode's flag.
    pub fn connect(
        task: Arc<Task>,
        options: BridgeOptions,
        cancel: Option<Arc<AtomicBool>>,
    ) -> Result<Ros2Env, Error> {
        let names = wire::robot_names(&task);
        let link = LinkProcess::connect(
            &options.link,
            &options.namespace,
            (&names, !task.events.is_empty()),
            options.server_wait,
            options.robot_timeout,
        )?;
        Ok(Ros2Env {
            state: task.init.clone(),
            base: Arc::clone(&task),
            task,
            told: None,
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

    /// How robot number `n`'s actions reach it, before it has said anything.
    fn report(&self, n: usize) -> RobotReport {
        let name = &self.names[n];
        RobotReport {
            robot: name.clone(),
            via: format!("ros2 {}", wire::action_name(&self.options.namespace, name)),
            message: String::new(),
        }
    }

    /// Counts `tried` more actions tried (the goals' `step`).
    fn count(&mut self, tried: usize) {
        let tried = u32::try_from(tried).unwrap_or(u32::MAX);
        self.steps = self.steps.saturating_add(tried);
    }

    /// Stops the bridge: no later step is sent, and the episode ends.
    fn stop(&mut self, reason: Reason, why: &str) {
        self.stopped.get_or_insert_with(|| (reason, why.to_owned()));
    }

    /// Sends the actions of one step to their robots at once (each allowed by the rules
    /// in the current state, no two interfering: a valid joint step, or one action) and
    /// awaits them all; the state moves by the actions the robots carried out and agree
    /// on. For each action, in order: why it was not executed, if it was not, and what
    /// its robot said. Silence, a DDS failure or a disagreement stop the bridge, since
    /// the world can no longer be known; a cancelled goal is refused.
    fn carry_out(&mut self, step: &[Part]) -> Vec<(Option<Infeasible>, RobotReport)> {
        let first = self.steps.saturating_add(1);
        self.count(step.len());
        let sent: Vec<Sent> = step
            .iter()
            .zip(first..)
            .map(|(&(robot, action), count)| {
                let n = self
                    .base
                    .robots
                    .iter()
                    .position(|x| x.node == robot.node)
                    .expect("the rules resolved it among the robots");
                Sent {
                    n,
                    robot,
                    action,
                    text: action.render(&self.task),
                    count,
                }
            })
            .collect();
        if let Some((reason, why)) = &self.stopped {
            let message = format!("not sent: the bridge has stopped ({why})");
            return sent
                .iter()
                .map(|p| {
                    let report = RobotReport {
                        message: message.clone(),
                        ..self.report(p.n)
                    };
                    let why = Infeasible {
                        reason: *reason,
                        message: message.clone(),
                    };
                    (Some(why), report)
                })
                .collect();
        }
        let goals = sent
            .iter()
            .map(|p| {
                let goal = Goal {
                    action: p.text.clone(),
                    step: p.count,
                };
                (p.n, goal)
            })
            .collect();
        let exchanges =
            self.link
                .exchange(goals, self.options.robot_timeout, self.cancel.as_deref());
        // The state after every action its robot reports done: what a robot of the step
        // may see of the others' actions by the time its own is over.
        let mut joint = self.state.clone();
        for (p, exchange) in sent.iter().zip(&exchanges) {
            if exchange.succeeded() {
                rules::apply(&self.task, &mut joint, p.robot, p.action);
            }
        }
        let before = self.state.clone();
        let mut out = Vec::with_capacity(sent.len());
        for (p, exchange) in sent.iter().zip(exchanges) {
            let (infeasible, report) = self.hear(&before, &joint, p, exchange);
            if infeasible.is_none() {
                rules::apply(&self.task, &mut self.state, p.robot, p.action);
            }
            out.push((infeasible, report));
        }
        out
    }

    /// What one goal's exchange means for its action `p`, sent in state `before` in a
    /// step whose robots' reported successes lead to `joint`.
    fn hear(
        &mut self,
        before: &State,
        joint: &State,
        p: &Sent,
        exchange: Exchange,
    ) -> (Option<Infeasible>, RobotReport) {
        let mut report = self.report(p.n);
        let name = report.robot.clone();
        let text = &p.text;
        let (reason, message) = match exchange {
            Exchange::Result { status, result } => {
                report.message = result.message.clone();
                let succeeded = status == GoalStatusEnum::Succeeded;
                let mut alone = before.clone();
                rules::apply(&self.task, &mut alone, p.robot, p.action);
                match judge(&self.task, &name, text, succeeded, result, &[&alone, joint]) {
                    Verdict::Done => return (None, report),
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
        (Some(Infeasible { reason, message }), report)
    }
}

/// One action of a step on its way to its robot.
#[derive(Debug)]
struct Sent {
    /// The robot's number, in the task's order.
    n: usize,
    robot: Robot,
    action: Action,
    text: String,
    /// The goal's `step`: the count of the actions tried, this one included.
    count: u32,
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
    /// bridge; a cancelled goal is refused.
    fn step(&mut self, robot: NodeId, action: &str) -> coherent_core::Result<Outcome> {
        let r = self.task.robot_by_id(robot)?;
        let a = match feasibility::check(&self.task, &self.state, r, action) {
            Ok(a) => a,
            Err(why) => {
                self.count(1);
                return Ok(Outcome {
                    infeasible: Some(why),
                    done: self.goal_satisfied(),
                    report: None,
                });
            }
        };
        let (infeasible, report) = self
            .carry_out(&[(r, a)])
            .pop()
            .expect("one report per action sent");
        Ok(Outcome {
            infeasible,
            done: self.goal_satisfied(),
            report: Some(report),
        })
    }

    /// Nothing of a step the rules refuse is sent. A valid step's goals are sent at
    /// once, one per robot, and awaited together: the step takes as long as its slowest
    /// robot. Each action is judged as [`Ros2Env::step`] judges one, with what its robot
    /// observes allowed to show the other robots' actions of the step; the state moves
    /// by the actions carried out (any of a valid step's actions are a valid step too).
    /// A robot that fails, refuses or falls silent is that robot's part of the outcome;
    /// Ctrl-C cancels every goal in flight.
    fn step_joint(&mut self, actions: &[(NodeId, &str)]) -> coherent_core::Result<JointOutcome> {
        let step = match resolve_joint(&self.task, &self.state, actions)? {
            Ok(step) => step,
            Err(refused) => {
                self.count(actions.len());
                return Ok(refused_outcome(self.goal_satisfied(), actions, refused));
            }
        };
        let parts = actions
            .iter()
            .zip(self.carry_out(&step))
            .map(|(&(robot, _), (infeasible, report))| PartOutcome {
                robot,
                infeasible,
                report: Some(report),
            })
            .collect();
        Ok(JointOutcome {
            parts,
            refused: None,
            done: self.goal_satisfied(),
        })
    }

    /// The rules' state only: the robots' world is theirs to put back (restart
    /// `coherent robots serve`).
    fn reset(&mut self) {
        self.task = Arc::clone(&self.base);
        self.state = self.task.init.clone();
        self.told = None;
        self.steps = 0;
        self.stopped = None;
    }

    /// What the events changed in the robots' world goes to the world's service
    /// (`crate::befall`): the team, the locked doors, each thing moved and where. The
    /// world must accept it and then observe each thing where the rules have it; a world
    /// that refuses, disagrees or falls silent stops the bridge as a robot would, and
    /// the episode ends with the next round, saying why. A change of the task's words
    /// alone (its goal) is the planner's: nothing is sent.
    fn befall(&mut self, task: Arc<Task>, state: State) -> coherent_core::Result<()> {
        let asked = || {
            let next = self.steps.saturating_add(1);
            let states = (&self.state, &state);
            befall::asked(
                &self.base,
                &self.names,
                self.told.as_ref(),
                &task,
                states,
                next,
            )
        };
        if self.stopped.is_none()
            && let Some(request) = asked()
        {
            let now = (request.team.clone(), request.locked.clone());
            let service = wire::service_name(&self.options.namespace);
            match self.link.befall(request, self.options.robot_timeout) {
                Befell::Answered(answer) if answer.accepted => {
                    let diffs = relations::disagreements(&task, &[&state], &answer.relations);
                    if diffs.is_empty() {
                        self.told = Some(now);
                    } else {
                        let why = format!(
                            "the world ({service}) carried the events out, but what it observes \
                             disagrees with the rules: {}",
                            diffs.join("; ")
                        );
                        self.stop(Reason::Disagreement, &why);
                    }
                }
                Befell::Answered(answer) => {
                    let why = format!(
                        "the world ({service}) refused the events: {}",
                        coherent_core::text::shown(&answer.message)
                    );
                    self.stop(Reason::Robot, &why);
                }
                Befell::Silent => {
                    let why = format!(
                        "the world ({service}) did not answer the events within {:.1} s",
                        self.options.robot_timeout.as_secs_f64()
                    );
                    self.stop(Reason::Timeout, &why);
                }
                Befell::Failed(why) => self.stop(Reason::Robot, &format!("{service}: {why}")),
            }
        }
        self.task = task;
        self.state = state;
        Ok(())
    }

    fn stopped(&self) -> Option<String> {
        self.stopped.as_ref().map(|(_, why)| why.clone())
    }
}

/// What a robot's result does to the rules' state.
#[derive(Debug)]
enum Verdict {
    /// The robot succeeded and what it observes holds.
    Done,
    /// The robot failed: its reason (a feasibility reason's name, else `robot`) and its
    /// message.
    Failed(Reason, String),
    /// The robot succeeded, but what it observes disagrees with the rules: each relation
    /// with what the rules have.
    Disagrees(String),
}

/// Judges the result of `action` by robot `name`; `succeeded` is whether the goal ended
/// as succeeded, and each relation the robot observes must hold in one of `states` (see
/// [`relations::disagreements`]).
fn judge(
    task: &Task,
    name: &str,
    action: &str,
    succeeded: bool,
    result: ExecuteResult,
    states: &[&State],
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
    let diffs = relations::disagreements(task, states, &result.relations);
    if diffs.is_empty() {
        Verdict::Done
    } else {
        Verdict::Disagrees(format!(
            "{name} reports {action} done, but what it observes disagrees with the rules: {}",
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
    fn a_result_is_done_only_on_success_with_agreeing_relations() {
        let task = demo();
        let arm = task.robots[0];
        let grab = feasibility::check(&task, &task.init, arm, "[grab] <mug>(7)").expect("feasible");
        let mut after = task.init.clone();
        rules::apply(&task, &mut after, arm, grab);
        let ok = ExecuteResult {
            relations: relations::observed(&task, &after, arm.node),
            ..result(true, "", "done")
        };
        let judged = |succeeded: bool, r: ExecuteResult| {
            judge(
                &task,
                "robot_arm_6",
                "[grab] <mug>(7)",
                succeeded,
                r,
                &[&after],
            )
        };
        assert!(matches!(judged(true, ok.clone()), Verdict::Done));
        // Succeeded by its word but not by the goal's status, or the other way round.
        for (succeeded, r) in [(false, ok), (true, result(false, "", ""))] {
            match judged(succeeded, r) {
                Verdict::Failed(Reason::Robot, _) => {}
                other => panic!("{other:?}"),
            }
        }
        // What it observed before grabbing is not what the rules have after it.
        let before = ExecuteResult {
            relations: relations::observed(&task, &task.init, arm.node),
            ..result(true, "", "done")
        };
        match judged(true, before) {
            Verdict::Disagrees(why) => assert!(
                why.starts_with("robot_arm_6 reports [grab] <mug>(7) done, but what it observes")
                    && why.contains("<mug>(7) ON "),
                "{why}"
            ),
            other => panic!("{other:?}"),
        }
    }

    /// In a joint step a robot's report may show what another robot of the step has done
    /// by then: each relation is judged against the state after its own action and the
    /// state after the whole step, and one that holds in neither still disagrees.
    #[test]
    fn a_robot_of_a_joint_step_may_see_the_others_actions_done() {
        let task = demo();
        let plan = coherent_core::makespan::search(
            &task,
            &task.robots,
            &task.goal,
            &coherent_core::Limits::default(),
        )
        .plan
        .expect("the demo has a joint plan");
        let mut s = task.init.clone();
        let mut seen_others = 0;
        for joint_step in &plan {
            let parts: Vec<Part> = joint_step
                .iter()
                .map(|step| (*task.robot(step.robot).expect("a robot"), step.action))
                .collect();
            let mut joint = s.clone();
            coherent_core::joint::apply(&task, &mut joint, &parts);
            for &(robot, action) in &parts {
                let mut alone = s.clone();
                rules::apply(&task, &mut alone, robot, action);
                let late = ExecuteResult {
                    relations: relations::observed(&task, &joint, robot.node),
                    ..result(true, "", "done")
                };
                let text = action.render(&task);
                let judged =
                    |states: &[&State]| judge(&task, "r", &text, true, late.clone(), states);
                assert!(matches!(judged(&[&alone, &joint]), Verdict::Done), "{text}");
                if !matches!(judged(&[&alone]), Verdict::Done) {
                    seen_others += 1;
                    // Neither before the step nor after it is what it saw then.
                    assert!(matches!(judged(&[&s]), Verdict::Disagrees(_)));
                }
            }
            s = joint;
        }
        assert!(
            seen_others > 0,
            "some robot of the demo's plan sees another act"
        );
    }

    #[test]
    fn a_failure_keeps_the_robots_reason_and_message() {
        let task = demo();
        let arm = task.robots[0];
        let grab = feasibility::check(&task, &task.init, arm, "[grab] <mug>(7)").expect("feasible");
        let mut after = task.init.clone();
        rules::apply(&task, &mut after, arm, grab);
        let judged = |r: ExecuteResult| match judge(
            &task,
            "robot_arm_6",
            "[grab] <mug>(7)",
            false,
            r,
            &[&after],
        ) {
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
