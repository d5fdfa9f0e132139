//! The world the reference robot servers act in: the project's own engine, the rules or
//! Rapier checked against them. An adapter for a real robot replaces it with the robot's
//! own controller (docs/robots.md, "An adapter for a real robot").

use std::sync::Arc;

use coherent_core::feasibility::{Infeasible, Reason};
use coherent_core::{Environment, NodeId, State, SymbolicEnv, Task};
use coherent_sim::PhysicalEnv;

use crate::error::Error;

/// The world the robots act in: the rules, or Rapier checked against them.
#[derive(Debug)]
pub enum World {
    Rules(SymbolicEnv),
    Physics(Box<PhysicalEnv>),
}

impl World {
    pub fn new(task: &Arc<Task>, physics: bool) -> Result<World, Error> {
        Ok(if physics {
            let env = PhysicalEnv::new(Arc::clone(task)).map_err(Error::Physics)?;
            World::Physics(Box::new(env))
        } else {
            World::Rules(SymbolicEnv::new(Arc::clone(task)))
        })
    }

    pub fn state(&self) -> &State {
        match self {
            World::Rules(env) => env.state(),
            World::Physics(env) => env.state(),
        }
    }

    /// The task as events have left it: its team and its passable doors.
    pub fn task(&self) -> &Task {
        match self {
            World::Rules(env) => env.task(),
            World::Physics(env) => env.task(),
        }
    }

    /// Puts the world where events left it: `task`, a variant of the task served, and
    /// `state` (see `Environment::befall`); why not, in words.
    pub fn befall(&mut self, task: Arc<Task>, state: State) -> Result<(), String> {
        match self {
            World::Rules(env) => env.befall(task, state),
            World::Physics(env) => env.befall(task, state),
        }
        .map_err(|e| e.to_string())
    }

    /// Carries `action` out for `robot`: what happened in words, or why it could not.
    pub fn act(&mut self, robot: NodeId, action: &str) -> Result<String, Infeasible> {
        let task = self.task();
        let me = task
            .idx(robot)
            .map(|n| task.node(n).label())
            .unwrap_or_default();
        let wrong = |e: coherent_core::Error| Infeasible {
            reason: Reason::NoSuchNode,
            message: e.to_string(),
        };
        match self {
            World::Rules(env) => match env.step(robot, action).map_err(wrong)?.infeasible {
                None => Ok(format!("{me} did {action}")),
                Some(why) => Err(why),
            },
            World::Physics(env) => match env.step_physical(robot, action) {
                Ok(Ok(done)) => Ok(format!(
                    "{me} did {} in {:.2} s of simulated time",
                    done.action, done.sim_seconds
                )),
                Ok(Err(why)) => Err(why),
                Err(e) => Err(Infeasible {
                    reason: Reason::Physics,
                    message: format!("physics: {}", e.message),
                }),
            },
        }
    }
}
