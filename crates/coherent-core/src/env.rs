//! The `Environment` interface planners talk to, and the symbolic environment that runs
//! the rules. A physical world or a real-robot bridge implements the same trait.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::feasibility::{self, Infeasible};
use crate::graph::{NodeId, State};
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

    fn observe(&self, robot: NodeId) -> Result<Observation> {
        let r = self.task().robot_by_id(robot)?;
        Ok(rules::observe(self.task(), self.state(), r.node))
    }

    /// The action strings `robot` may use now.
    fn actions(&self, robot: NodeId) -> Result<Vec<String>> {
        let r = self.task().robot_by_id(robot)?;
        Ok(rules::actions(self.task(), self.state(), r)
            .iter()
            .map(|a| a.render(self.task()))
            .collect())
    }

    fn goal_satisfied(&self) -> bool {
        self.task().goal_satisfied(self.state())
    }

    /// Why no further step can be trusted, once the environment has stopped (a robot
    /// that no longer answers, a world that disagrees with the rules); an episode ends
    /// with the round in which it stops. The rules and physics never stop.
    fn stopped(&self) -> Option<String> {
        None
    }
}

/// The rules of docs/semantics.md, nothing else.
#[derive(Clone, Debug)]
pub struct SymbolicEnv {
    task: Arc<Task>,
    state: State,
}

impl SymbolicEnv {
    pub fn new(task: Arc<Task>) -> SymbolicEnv {
        let state = task.init.clone();
        SymbolicEnv { task, state }
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

    fn reset(&mut self) {
        self.state = self.task.init.clone();
    }
}
