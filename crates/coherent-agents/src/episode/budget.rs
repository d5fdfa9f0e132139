//! The step budget of an episode, the paper's rule: 2 x the task's ground truth (GT),
//! unless the caller sets one; a task without a GT gets 2 x the optimum the planner
//! finds. Every episode, run alone or in a benchmark, is sized here.

use coherent_core::Task;
use coherent_core::planner::{self, Limits};

use crate::error::Error;

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
}

impl Budget {
    pub fn steps(self) -> u32 {
        match self {
            Budget::TwiceGroundTruth(n) | Budget::Given(n) | Budget::TwiceOptimum(n) => n,
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

    /// [`Budget::of`], searching for the optimum within `limits` when it is needed.
    pub fn searched(task: &Task, max_steps: Option<u32>, limits: &Limits) -> Result<Budget, Error> {
        Budget::of(task, max_steps, || {
            let search = planner::search(task, &task.robots, &task.goal, limits);
            match search.plan {
                Some(plan) => Ok(u32::try_from(plan.len()).unwrap_or(u32::MAX)),
                None if search.truncated => Err(NoPlan("the search stopped".into())),
                None => Err(NoPlan("no plan reaches the goal".into())),
            }
        })
    }
}
