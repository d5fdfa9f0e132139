//! The `Environment` interface planners talk to, and the symbolic environment that runs
//! the rules. A physical world or a real-robot bridge implements the same trait.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::feasibility::{self, Infeasible};
use crate::graph::{NodeId, State};
use crate::joint::{self, Part, Refusal};
use crate::rules::{self, Observation};
use crate::task::Task;

/// What one `step` did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Outcome {
    /// Why the action was not executed; `None` when it was.
    pub infeasible: Option<Infeasible>,
    /// Whether the goal holds after the step.
    pub done: bool,
    /// What the robot said, when the action was sent to a robot outside this process;
    /// `None` when the rules (and physics) carried it out here, or nothing was sent.
    pub report: Option<RobotReport>,
}

/// What a robot outside this process (behind a bridge such as `coherent-ros`) reported
/// about an action it was sent.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RobotReport {
    /// The robot's name on the other side, e.g. `quadrotor_11`.
    pub robot: String,
    /// How the action reached it, e.g. `ros2 /coherent/quadrotor_11/execute`.
    pub via: String,
    /// The robot's message about the result, or why none came.
    pub message: String,
}

/// What one robot's part of a joint step did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartOutcome {
    pub robot: NodeId,
    /// Why its action was not executed; `None` when it was.
    pub infeasible: Option<Infeasible>,
    /// What the robot said, as in [`Outcome::report`].
    pub report: Option<RobotReport>,
}

impl PartOutcome {
    pub fn executed(&self) -> bool {
        self.infeasible.is_none()
    }
}

/// What one joint step did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct JointOutcome {
    /// One per action of the step, in the order given.
    pub parts: Vec<PartOutcome>,
    /// Why the rules refused the step; a refused step executes nothing, and each
    /// part's `infeasible` says what it means for that robot.
    pub refused: Option<Refusal>,
    /// Whether the goal holds after the step.
    pub done: bool,
}

impl Outcome {
    pub fn executed(&self) -> bool {
        self.infeasible.is_none()
    }
}

/// A world that robots observe and act in, one action of one robot at a time. What a
/// robot sees and may do follow from the symbolic state by the rules, whatever carries
/// the actions out; an implementation provides the state and the step.
pub trait Environment {
    fn task(&self) -> &Task;
    /// The current symbolic state.
    fn state(&self) -> &State;
    /// Checks and, when feasible, executes `action`. An infeasible action is not an
    /// error: the outcome says why. An unknown robot is.
    fn step(&mut self, robot: NodeId, action: &str) -> Result<Outcome>;
    /// Back to the task's initial state.
    fn reset(&mut self);

    /// Checks and, when valid, executes a joint step: several robots' actions at once,
    /// at most one each (docs/semantics.md, "Parallel steps"). A step with an action not
    /// offered, or with two actions that interfere, is refused as a whole; that is not an
    /// error, the outcome says why. An unknown robot is.
    ///
    /// Without an implementation of its own, an environment carries out a valid step's
    /// actions one after the other with [`Environment::step`]: for a valid step every
    /// order ends in the same state, so that is the step's meaning, if not its timing.
    fn step_joint(&mut self, actions: &[(NodeId, &str)]) -> Result<JointOutcome> {
        let step = match resolve_joint(self.task(), self.state(), actions)? {
            Ok(step) => step,
            Err(refused) => return Ok(refused_outcome(self.goal_satisfied(), actions, refused)),
        };
        let mut parts = Vec::with_capacity(step.len());
        let mut done = self.goal_satisfied();
        for &(robot, action) in actions {
            let outcome = self.step(robot, action)?;
            done = outcome.done;
            parts.push(PartOutcome {
                robot,
                infeasible: outcome.infeasible,
                report: outcome.report,
            });
        }
        Ok(JointOutcome {
            parts,
            refused: None,
            done,
        })
    }

    fn observe(&self, robot: NodeId) -> Result<Observation> {
        let r = self.task().robot_by_id(robot)?;
        Ok(rules::observe(self.task(), self.state(), r.node))
    }

    /// The action strings `robot` may use now.
    fn actions(&self, robot: NodeId) -> Result<Vec<String>> {
        let r = self.task().robot_by_id(robot)?;
        Ok(rules::action_texts(self.task(), self.state(), r))
    }

    fn goal_satisfied(&self) -> bool {
        self.task().goal_satisfied(self.state())
    }

    /// Simulated seconds since the task started, where the environment simulates time
    /// (the physical world: a step takes as long as its motions, a joint step as long
    /// as its slowest robot's); `None` where it does not (the rules alone).
    fn sim_seconds(&self) -> Option<f64> {
        None
    }

    /// Puts the world where an event left it (docs/dynamic.md): `task` is the task as
    /// the event left it (its team, goal and doors), `state` the state. The rules take
    /// any, physics what it can carry out, robots over ROS 2 what their world's service
    /// carries out; a world that cannot follow says why.
    fn befall(&mut self, task: Arc<Task>, state: State) -> Result<()> {
        let _ = (task, state);
        Err(crate::Error::Unsupported(
            "this world does not take events (the rules and physics do)".into(),
        ))
    }

    /// Why no further step can be trusted, once the environment has stopped (a robot
    /// that no longer answers, a world that disagrees with the rules); an episode ends
    /// with the round in which it stops. The rules and physics never stop.
    fn stopped(&self) -> Option<String> {
        None
    }
}

/// A joint step's actions resolved against the rules in state `s`, or why the step is
/// refused; an error for an unknown robot.
pub fn resolve_joint(
    task: &Task,
    s: &State,
    actions: &[(NodeId, &str)],
) -> Result<Result<Vec<Part>, Refusal>> {
    let mut step = Vec::with_capacity(actions.len());
    let mut infeasible = Vec::new();
    for (i, &(robot, text)) in actions.iter().enumerate() {
        let r = task.robot_by_id(robot)?;
        match feasibility::check(task, s, r, text) {
            Ok(a) => step.push((r, a)),
            Err(why) => infeasible.push((i, why)),
        }
    }
    if !infeasible.is_empty() {
        return Ok(Err(Refusal::Infeasible(infeasible)));
    }
    Ok(joint::check(task, s, &step).map(|()| step))
}

/// The outcome of a refused joint step: nothing executed, each part told why.
pub fn refused_outcome(done: bool, actions: &[(NodeId, &str)], refused: Refusal) -> JointOutcome {
    JointOutcome {
        parts: actions
            .iter()
            .enumerate()
            .map(|(i, &(robot, _))| PartOutcome {
                robot,
                infeasible: Some(refused.part(i)),
                report: None,
            })
            .collect(),
        refused: Some(refused),
        done,
    }
}

/// The rules of docs/semantics.md, nothing else.
#[derive(Clone, Debug)]
pub struct SymbolicEnv {
    /// The task as events have left it (the task itself without events).
    task: Arc<Task>,
    /// The task as given, which a reset goes back to.
    base: Arc<Task>,
    state: State,
}

impl SymbolicEnv {
    pub fn new(task: Arc<Task>) -> SymbolicEnv {
        let state = task.init.clone();
        SymbolicEnv {
            base: Arc::clone(&task),
            task,
            state,
        }
    }
}

impl Environment for SymbolicEnv {
    fn task(&self) -> &Task {
        &self.task
    }

    fn state(&self) -> &State {
        &self.state
    }

    fn step(&mut self, robot: NodeId, action: &str) -> Result<Outcome> {
        let r = self.task.robot_by_id(robot)?;
        let infeasible = match feasibility::check(&self.task, &self.state, r, action) {
            Ok(a) => {
                rules::apply(&self.task, &mut self.state, r, a);
                None
            }
            Err(why) => Some(why),
        };
        Ok(Outcome {
            infeasible,
            done: self.goal_satisfied(),
            report: None,
        })
    }

    fn step_joint(&mut self, actions: &[(NodeId, &str)]) -> Result<JointOutcome> {
        let step = match resolve_joint(&self.task, &self.state, actions)? {
            Ok(step) => step,
            Err(refused) => return Ok(refused_outcome(self.goal_satisfied(), actions, refused)),
        };
        joint::apply(&self.task, &mut self.state, &step);
        Ok(JointOutcome {
            parts: actions
                .iter()
                .map(|&(robot, _)| PartOutcome {
                    robot,
                    infeasible: None,
                    report: None,
                })
                .collect(),
            refused: None,
            done: self.goal_satisfied(),
        })
    }

    fn reset(&mut self) {
        self.task = Arc::clone(&self.base);
        self.state = self.task.init.clone();
    }

    fn befall(&mut self, task: Arc<Task>, state: State) -> Result<()> {
        self.task = task;
        self.state = state;
        Ok(())
    }
}
