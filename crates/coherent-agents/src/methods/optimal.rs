//! The ground-truth row of the paper's tables: the optimal planner's shortest plan,
//! carried out step by step under the same loop as every method; in a parallel episode
//! the makespan search's plan (`coherent_core::makespan`), joint step by joint step. No
//! model; a task without a plan spends its budget on rounds that say why.

use std::io;
use std::sync::Arc;

use coherent_core::makespan::{self, JointStep};
use coherent_core::planner::{self, Limits, Step};
use coherent_core::{Execution, State, Task};

use crate::episode::method::{Closing, Decided, Deciding, Method, Turn};
use crate::methods::decision;
use crate::records::transcript::{Round, RoundOutcome};

/// The plan an episode follows: a step per round, or a joint step per round.
#[derive(Debug)]
enum Plan {
    Steps(Vec<Step>),
    JointSteps(Vec<JointStep>),
}

/// The optimal plan for one episode, found at its first round (within `limits`), and
/// found again from where the world stands after each event of the task
/// (docs/dynamic.md) or an action an event made fail: the oracle that knows nothing of
/// events to come.
#[derive(Debug)]
pub struct Optimal {
    limits: Limits,
    /// The plan once found, or why there is none.
    plan: Option<Result<Plan, &'static str>>,
    /// The round whose step is the plan's first.
    first: u32,
}

impl Optimal {
    /// The method; `limits` bound its searches (its cancel flag stops them).
    pub fn new(limits: Limits) -> Optimal {
        Optimal {
            limits,
            plan: None,
            first: 1,
        }
    }
}

/// The shortest plan from `state`, or in a parallel episode the plan of the fewest joint
/// steps (the best found within `limits`: the sequential optimum scheduled, when the
/// search stops early), or why there is none.
fn search(
    task: &Task,
    state: &State,
    limits: &Limits,
    execution: Execution,
) -> Result<Plan, &'static str> {
    let sequential = planner::search_from(task, state, &task.robots, &task.goal, limits);
    let stopped = "the search stopped before it found a plan";
    let none = "no plan reaches the goal";
    match execution {
        Execution::Sequential => sequential
            .plan
            .map(Plan::Steps)
            .ok_or(if sequential.truncated { stopped } else { none }),
        Execution::Parallel => {
            let plan = sequential.plan.as_deref();
            let joint = makespan::search_with(task, state, &task.robots, &task.goal, plan, limits);
            joint
                .plan
                .map(Plan::JointSteps)
                .ok_or(if joint.stop.is_some() { stopped } else { none })
        }
    }
}

impl Method for Optimal {
    fn decide<'a>(&'a mut self, turn: Turn<'a>, round: &'a mut Round) -> Deciding<'a> {
        Box::pin(async move {
            let task = turn.task;
            if !turn.news.is_empty() {
                self.plan = None;
            }
            if self.plan.is_none() {
                self.first = round.step;
            }
            let plan = match &mut self.plan {
                Some(plan) => plan,
                unsearched @ None => {
                    let (t, s) = (Arc::clone(task), turn.env.state().clone());
                    let (l, execution) = (self.limits.clone(), turn.execution);
                    let found = tokio::task::spawn_blocking(move || search(&t, &s, &l, execution))
                        .await
                        .map_err(io::Error::other)?;
                    unsearched.insert(found)
                }
            };
            let at = (round.step - self.first) as usize;
            let why = match plan {
                Ok(Plan::Steps(steps)) => match steps.get(at) {
                    Some(s) => {
                        let action = s.action.render(task);
                        decision::choose(round, task.id(s.robot), &action, String::new());
                        return Ok(Some(Decided::CarryOut));
                    }
                    None => "the plan is over",
                },
                Ok(Plan::JointSteps(steps)) => match steps.get(at) {
                    Some(joint) => {
                        round.parts = joint
                            .iter()
                            .map(|s| {
                                let action = s.action.render(task);
                                decision::part(turn.env, task.id(s.robot), &action, String::new())
                            })
                            .collect();
                        return Ok(Some(Decided::CarryOut));
                    }
                    None => "the plan is over",
                },
                Err(why) => *why,
            };
            let why = why.to_owned();
            Ok(Some(Decided::Ends(RoundOutcome::NoDecision { why })))
        })
    }

    /// What ran, as the team methods hear it; a round past the plan, or of a task without
    /// one, says nothing more than its outcome.
    fn conclude(&mut self, closing: Closing<'_>, round: &mut Round) {
        if round.decision.is_some() || !round.parts.is_empty() {
            decision::team_feedback(closing.task, round, None);
        }
        if round.failed_actions() > 0 {
            self.plan = None;
        }
    }

    fn recall(&self, _: &Task, _: &Round) -> Option<String> {
        None
    }
}
