//! The step budget of an episode, the paper's rule: 2 x the task's ground truth (GT),
//! unless the caller sets one; a task without a GT gets 2 x the optimum the planner
//! finds. A parallel episode gets 2 x the fewest joint steps the makespan search finds
//! (2 x the best plan's when the search stops before proving it optimal), since its GT
//! counts one action a step; when that search finds no plan, the sequential rule (2 x GT).
//! Every episode, run alone or in a benchmark, is sized here.

use coherent_core::planner::{self, Limits};
use coherent_core::{Execution, Task, makespan};

use crate::error::Error;

/// What the makespan search found for a task: the joint steps of its best plan, and
/// whether no plan has fewer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlannedMakespan {
    pub steps: u32,
    pub proven: bool,
}

impl PlannedMakespan {
    /// What `search` found, or why it found no plan.
    pub fn of(search: &makespan::Makespan) -> Result<PlannedMakespan, NoPlan> {
        match search.makespan() {
            Some(n) => Ok(PlannedMakespan {
                steps: u32::try_from(n).unwrap_or(u32::MAX),
                proven: search.proven,
            }),
            None if search.stop.is_some() => Err(NoPlan("the search stopped".into())),
            None => Err(NoPlan("no plan reaches the goal".into())),
        }
    }
}

/// Why the planner has no optimum to size a budget from, in the search's words.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NoPlan(pub String);

/// A step budget and where it came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Budget {
    /// 2 x the task's ground truth, the paper's rule.
    TwiceGroundTruth(u32),
    /// Set by the caller.
    Given(u32),
    /// The task has no ground truth: 2 x the optimum the planner finds.
    TwiceOptimum(u32),
    /// A parallel episode: 2 x the fewest joint steps (the optimal makespan).
    TwiceMakespan(u32),
    /// A parallel episode whose makespan search stopped before proving its best plan
    /// optimal: 2 x that plan's joint steps, an upper bound of the makespan.
    TwiceMakespanBound(u32),
}

impl Budget {
    pub fn steps(self) -> u32 {
        match self {
            Budget::TwiceGroundTruth(n)
            | Budget::Given(n)
            | Budget::TwiceOptimum(n)
            | Budget::TwiceMakespan(n)
            | Budget::TwiceMakespanBound(n) => n,
        }
    }

    /// The budget of `task`: `max_steps` when given, else 2 x GT, else 2 x the optimum
    /// that `optimum` gives, asked only then (its error says why the planner has none).
    pub fn of(
        task: &Task,
        max_steps: Option<u32>,
        optimum: impl FnOnce() -> Result<u32, NoPlan>,
    ) -> Result<Budget, Error> {
        if let Some(n) = max_steps {
            return Ok(Budget::Given(n));
        }
        if let Some(budget) = task.meta.twice_ground_truth() {
            return budget
                .map(Budget::TwiceGroundTruth)
                .map_err(Error::NoBudget);
        }
        match optimum() {
            Ok(n) => Ok(Budget::TwiceOptimum(n.max(1).saturating_mul(2))),
            Err(NoPlan(why)) => Err(Error::NoBudget(format!(
                "the task has no ground truth and the planner finds no plan to size a budget \
                 from ({why}): pass a step budget (--max-steps, max_steps=)"
            ))),
        }
    }

    /// The budget of a parallel episode of `task`: `max_steps` when given, else 2 x the
    /// makespan that `makespan` gives, asked only then (2 x its best plan's when not
    /// proven). When it finds no plan (a task that cannot be solved fails within the
    /// budget a sequential episode has), 2 x GT: a plan of GT actions is one of at most GT
    /// joint steps.
    pub fn parallel(
        task: &Task,
        max_steps: Option<u32>,
        makespan: impl FnOnce() -> Result<PlannedMakespan, NoPlan>,
    ) -> Result<Budget, Error> {
        if let Some(n) = max_steps {
            return Ok(Budget::Given(n));
        }
        match makespan() {
            Ok(m) => {
                let n = m.steps.max(1).saturating_mul(2);
                Ok(if m.proven {
                    Budget::TwiceMakespan(n)
                } else {
                    Budget::TwiceMakespanBound(n)
                })
            }
            Err(NoPlan(why)) => match task.meta.twice_ground_truth() {
                Some(budget) => budget
                    .map(Budget::TwiceGroundTruth)
                    .map_err(Error::NoBudget),
                None => Err(Error::NoBudget(format!(
                    "the task has no ground truth and the makespan search finds no plan to \
                     size a parallel episode's budget from ({why}): pass a step budget \
                     (--max-steps, max_steps=)"
                ))),
            },
        }
    }

    /// The budget of an episode of `execution`: [`Budget::of`] or [`Budget::parallel`],
    /// searching within `limits` for the optimum or the makespan when it is needed.
    pub fn searched(
        task: &Task,
        execution: Execution,
        max_steps: Option<u32>,
        limits: &Limits,
    ) -> Result<Budget, Error> {
        match execution {
            Execution::Sequential => Budget::of(task, max_steps, || {
                let search = planner::search(task, &task.robots, &task.goal, limits);
                match search.plan {
                    Some(plan) => Ok(u32::try_from(plan.len()).unwrap_or(u32::MAX)),
                    None if search.truncated => Err(NoPlan("the search stopped".into())),
                    None => Err(NoPlan("no plan reaches the goal".into())),
                }
            }),
            Execution::Parallel => Budget::parallel(task, max_steps, || {
                PlannedMakespan::of(&makespan::search(task, &task.robots, &task.goal, limits))
            }),
        }
    }
}
