//! The team's joint action space, for the methods that choose one robot's action
//! centrally or in dialogue (CMRS, DMRS, MCTS and LLM-MCTS): every `(robot, action)` the
//! rules offer, one line each as the prompts list them, `<robot dog>(13): [grab] <mug>(7)`.
//! The central prompt is [`crate::methods::central`]'s; reading an answer back to a line
//! is [`crate::methods::answer`]'s.

use coherent_core::{Action, Robot, State, Task, rules};

/// One robot's action: an element of the joint action space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JointAction {
    pub robot: Robot,
    pub action: Action,
}

impl JointAction {
    /// `<robot label>: <action>`, as the prompt lists it.
    pub fn line(&self, task: &Task) -> String {
        format!(
            "{}: {}",
            task.node(self.robot.node).label(),
            self.action.render(task)
        )
    }
}

/// Every action of every robot in `s`: robots in team order, each robot's actions in
/// [`rules::actions`] order.
pub fn joint_actions(task: &Task, s: &State) -> Vec<JointAction> {
    task.robots
        .iter()
        .zip(rules::team_actions(task, s, &task.robots))
        .flat_map(|(&robot, actions)| {
            actions
                .into_iter()
                .map(move |action| JointAction { robot, action })
        })
        .collect()
}
