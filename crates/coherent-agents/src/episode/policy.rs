//! A method written outside the crate (a Python class, say) as the episode loop sees it:
//! a [`Policy`] that is asked once per step for one decision (in a parallel episode, one
//! per robot that acts), given a [`StepView`] of where the episode stands. The loop that asks it is [`crate::methods::external`]; everything
//! else (the step budget, the feasibility check, the transcript, the benchmark) is the
//! same as for the built-in methods.

use std::sync::Arc;

use coherent_core::rules::Observation;
use coherent_core::{Environment, Execution, NodeId, RobotKind, State, Task, describe};

use crate::llm::BoxFuture;
use crate::records::transcript::Call;

/// One robot as a method sees it at a step.
#[derive(Clone, Debug)]
pub struct RobotView {
    pub id: NodeId,
    pub kind: RobotKind,
    /// What it sees: the nodes and edges of its observation.
    pub observation: Observation,
    /// The action strings it may use now, in the rules' order.
    pub actions: Vec<String>,
}

/// One earlier step as a method is shown it: who acted, what, whether it ran, and why
/// not (of a parallel step, one for each robot that was given an action).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PastStep {
    /// `None` when the method chose no action.
    pub robot: Option<NodeId>,
    pub action: Option<String>,
    pub ok: bool,
    /// Why it did not run (the feasibility check's words), when it did not.
    pub reason: Option<String>,
}

/// What a method is shown when it is asked for a step: where the episode stands.
#[derive(Clone, Debug)]
pub struct StepView {
    pub task: Arc<Task>,
    /// The step about to be taken, from 1.
    pub step: u32,
    /// The step budget (2 x GT unless set; 2 x the makespan in joint steps).
    pub max_steps: u32,
    /// One decision a step, or joint steps (a decision per robot that acts).
    pub execution: Execution,
    /// The team, in the task's order.
    pub robots: Vec<RobotView>,
    /// Every earlier step, oldest first.
    pub history: Vec<PastStep>,
    /// The symbolic state, for the observations' text.
    pub state: State,
    /// What happened since the last step that the team did not do (the task's events,
    /// docs/dynamic.md), a sentence each; empty without events.
    pub news: Vec<String>,
}

impl StepView {
    /// Where `env` stands before step `step` of `max_steps` of an episode of
    /// `execution`, after `history`.
    pub fn now(
        env: &(dyn Environment + Send),
        task: &Arc<Task>,
        (step, max_steps): (u32, u32),
        execution: Execution,
        history: &[PastStep],
    ) -> StepView {
        let robots = task
            .robots
            .iter()
            .map(|r| {
                let id = task.id(r.node);
                RobotView {
                    id,
                    kind: r.kind,
                    observation: env.observe(id).unwrap_or_else(|_| Observation {
                        room: None,
                        nodes: Vec::new(),
                        edges: Vec::new(),
                    }),
                    actions: env.actions(id).unwrap_or_default(),
                }
            })
            .collect();
        StepView {
            task: Arc::clone(task),
            step,
            max_steps,
            execution,
            robots,
            history: history.to_vec(),
            state: env.state().clone(),
            news: Vec::new(),
        }
    }

    /// The robot `id` of the team.
    pub fn robot(&self, id: NodeId) -> Option<&RobotView> {
        self.robots.iter().find(|r| r.id == id)
    }

    /// The observation of `robot` as relation facts, one per line, in one block (the
    /// paper's layout of the executors' prompts: `describe::facts`), or with `None` every
    /// robot's merged, as the assigner's and the central prompts have it; `None` for a
    /// robot that is not in the team.
    pub fn observation_text(&self, robot: Option<NodeId>) -> Option<String> {
        let seen: Vec<&Observation> = match robot {
            Some(id) => vec![&self.robot(id)?.observation],
            None => self.robots.iter().map(|r| &r.observation).collect(),
        };
        Some(describe::facts(&self.task, &self.state, &seen))
    }
}

/// What a method decided for one step: the very record the transcript keeps of it.
pub use crate::records::transcript::ExternalDecision as Choice;

/// Why a method written outside the crate could not be made or could not decide a step,
/// in its own words (a Python method's traceback, say), which the transcript keeps as
/// they are; the episode ends there with status `error`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MethodFailure(pub String);

impl From<String> for MethodFailure {
    fn from(words: String) -> MethodFailure {
        MethodFailure(words)
    }
}

impl From<&str> for MethodFailure {
    fn from(words: &str) -> MethodFailure {
        MethodFailure(words.to_owned())
    }
}

impl std::fmt::Display for MethodFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// A step's answer: the choices (one in a sequential episode, where none is no action;
/// one per robot that acts in a parallel one), or why the method failed, and the calls it
/// made through the project's client meanwhile.
#[derive(Clone, Debug, PartialEq)]
pub struct Act {
    pub choices: Result<Vec<Choice>, MethodFailure>,
    pub calls: Vec<Call>,
}

/// A method written outside the crate: asked once per step.
pub trait Policy: Send {
    /// The decision for the step `view` describes (shared, so that a policy may keep it).
    fn act(&mut self, view: Arc<StepView>) -> BoxFuture<'_, Act>;
}

/// Makes the policy of one episode, or says why it cannot.
pub type MakePolicy = dyn Fn(&Arc<Task>) -> Result<Box<dyn Policy>, MethodFailure> + Send + Sync;
