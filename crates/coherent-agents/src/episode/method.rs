//! The shape every planning method has: what it asks in a round and what it makes of the
//! answers ([`Method`]). The loop ([`crate::episode::play()`]) owns everything else: the
//! rounds and the budget, the history window, carrying the decided actions out (one
//! robot's action, or a joint step of several), whether the goal holds, the transcript's
//! rounds and the time they took.

use std::io;
use std::sync::Arc;

use coherent_core::{Environment, Execution, State, Task};

use crate::episode::cancel::Cancel;
use crate::llm::{Backend, BoxFuture};
use crate::records::transcript::{Round, RoundOutcome};

/// Where an episode stands when its method is asked for a round.
#[derive(Clone, Copy)]
pub struct Turn<'a> {
    /// The task as events have left it (its team, goal and instruction; the task itself
    /// without events).
    pub task: &'a Arc<Task>,
    /// The world as it is before the round; a method only looks at it (the loop carries
    /// the actions out).
    pub env: &'a (dyn Environment + Send + Sync),
    /// Who answers the method's questions (unused by the methods that ask no model).
    pub backend: &'a dyn Backend,
    pub cancel: &'a Cancel,
    /// The step about to be taken, from 1, and the budget.
    pub step: u32,
    pub max_steps: u32,
    /// One robot's action a step, or joint steps.
    pub execution: Execution,
    /// What the history window keeps of the earlier rounds ([`Method::recall`]), oldest
    /// first.
    pub history: &'a [String],
    /// Every earlier round, oldest first.
    pub rounds: &'a [Round],
    /// What happened to the world since the last round that the team did not do (the
    /// task's events, docs/dynamic.md), a sentence each: what every role's next prompt
    /// says first. Empty without events.
    pub news: &'a [String],
}

impl std::fmt::Debug for Turn<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Turn")
            .field("task", &self.task.meta.name)
            .field("step", &self.step)
            .field("max_steps", &self.max_steps)
            .field("execution", &self.execution)
            .field("history", &self.history)
            .finish_non_exhaustive()
    }
}

/// Where an episode stands when a round's actions have been carried out.
#[derive(Clone, Copy, Debug)]
pub struct Closing<'a> {
    pub task: &'a Task,
    /// The world after the round.
    pub state: &'a State,
    pub execution: Execution,
}

/// What a method decided in a round.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Decided {
    /// Carry out what the round records: in a sequential round its
    /// [`Round::decision`] (when it names a robot, can do and has an action; else no
    /// action runs and the round is `declined`), in a parallel round the decision of each
    /// of its [`Round::parts`] at once, as one joint step.
    CarryOut,
    /// Nothing is carried out: the round ends with this outcome (an answer that could not
    /// be used, a model that could not be reached, a method that failed).
    Ends(RoundOutcome),
}

/// What [`Method::decide`] gives back when its questions are answered: what the method
/// decided, or `None` when cancelled during the round.
pub type Deciding<'a> = BoxFuture<'a, io::Result<Option<Decided>>>;

/// A planning method. Each round the loop asks it to [`Method::decide`], carries out what
/// it decided, then lets it [`Method::conclude`] the round: the feedback its next rounds
/// hear. Its memory of earlier rounds is the loop's history window, fed by
/// [`Method::recall`]; a method keeps its own state besides (PEFA's subtasks in
/// progress, the optimal method's plan).
pub trait Method: Send {
    /// Asks the round's questions and records them in `round` (the calls, a proposal, the
    /// action list it chose from, its decision or, in a parallel round, each robot's
    /// part). `None` when cancelled during the round: nothing of it is kept.
    fn decide<'a>(&'a mut self, turn: Turn<'a>, round: &'a mut Round) -> Deciding<'a>;

    /// Once the round's actions were carried out (the outcomes are in `round`): the
    /// feedback the method hears of the round from the next one on, in
    /// [`Round::feedback`] (and a parallel round's parts'), and whatever it keeps of it.
    fn conclude(&mut self, closing: Closing<'_>, round: &mut Round);

    /// What the history window keeps of a closed round, if anything (PEFA's assigner reads
    /// the feedback of the last rounds; the baselines recall the last executed actions).
    fn recall(&self, task: &Task, round: &Round) -> Option<String>;
}
