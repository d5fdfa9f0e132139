//! The team's actions: every `(robot, action)` the rules offer any robot of the team, one
//! line each as the prompts list them, `<robot dog>(13): [grab] <mug>(7)`. The methods
//! that choose robots' actions centrally or in dialogue (CMRS, DMRS, MCTS and LLM-MCTS)
//! choose from them: one line a step, or in a parallel episode one line per robot at
//! most (a joint step, `coherent_core::joint`).
//! The central prompt is [`crate::methods::central`]'s; reading an answer back to a line
//! is [`crate::prompts::answer`]'s.

use coherent_core::{Action, Robot, State, Task, rules};

use crate::prompts::fill::action_line;

/// One robot's action: an element of the team action space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TeamAction {
    pub robot: Robot,
    pub action: Action,
}

impl TeamAction {
    /// `<robot label>: <action>`, as the prompt lists it.
    pub fn line(&self, task: &Task) -> String {
        action_line(task, task.id(self.robot.node), &self.action.render(task))
    }
}

/// Every action of every robot in `s`: robots in team order, each robot's actions in
/// [`rules::actions`] order.
pub fn offered(task: &Task, s: &State) -> Vec<TeamAction> {
    task.robots
        .iter()
        .zip(rules::team_actions(task, s, &task.robots))
        .flat_map(|(&robot, actions)| {
            actions
                .into_iter()
                .map(move |action| TeamAction { robot, action })
        })
        .collect()
}
