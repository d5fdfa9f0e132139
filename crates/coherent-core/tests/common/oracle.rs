//! Two checks of the makespan search that share nothing with it but the rules, for the
//! tests of this crate and the generated sets' (`tests/generate.rs`, which includes this
//! file by its path):
//! - a breadth-first search over every joint step, the reference for short tasks;
//! - the search's bound along a plan: never above the joint steps left, and lowered by
//!   at most one by any joint step of two robots' actions.

use std::collections::{HashMap, VecDeque};

use coherent_core::footprint::Footprint;
use coherent_core::joint::{self, Part};
use coherent_core::makespan::{JointStep, LowerBound};
use coherent_core::{State, Task, rules};

/// Breadth-first over every joint step (every offered action, each set of robots whose
/// actions pairwise do not interfere): the fewest joint steps and, among the plans of
/// that many, the fewest actions; or none within `max` states. A state's fewest actions
/// at its depth are final once the depth before it is expanded, as the queue takes the
/// depths in turn.
pub fn breadth_first(task: &Task, max: usize) -> Option<(usize, usize)> {
    let mut cost: HashMap<State, (usize, usize)> = HashMap::from([(task.init.clone(), (0, 0))]);
    let mut queue = VecDeque::from([task.init.clone()]);
    while let Some(s) = queue.pop_front() {
        let (d, acts) = cost[&s];
        if task.goal_satisfied(&s) {
            return cost
                .iter()
                .filter(|(t, c)| c.0 == d && task.goal_satisfied(t))
                .map(|(_, &c)| c)
                .min();
        }
        let lists = rules::team_actions(task, &s, &task.robots);
        // Every choice of at most one action per robot, as (part, footprint) lists.
        let mut steps: Vec<Vec<(Part, Footprint)>> = vec![Vec::new()];
        for (&robot, actions) in task.robots.iter().zip(&lists) {
            let mut more = Vec::new();
            for &a in actions {
                let print = Footprint::of(task, &s, robot, a);
                for step in &steps {
                    if step.iter().all(|(_, p)| p.conflict(&print).is_none()) {
                        let mut bigger = step.clone();
                        bigger.push(((robot, a), print.clone()));
                        more.push(bigger);
                    }
                }
            }
            steps.extend(more);
        }
        for step in steps.iter().filter(|st| !st.is_empty()) {
            let parts: Vec<Part> = step.iter().map(|(p, _)| *p).collect();
            let mut next = s.clone();
            joint::apply(task, &mut next, &parts);
            let here = (d + 1, acts + parts.len());
            match cost.get_mut(&next) {
                Some(known) => *known = (*known).min(here),
                None => {
                    if cost.len() >= max {
                        return None;
                    }
                    cost.insert(next.clone(), here);
                    queue.push_back(next);
                }
            }
        }
    }
    None
}

/// The actions of a joint plan.
pub fn actions(plan: &[JointStep]) -> usize {
    plan.iter().map(Vec::len).sum()
}

/// Walks `plan` (a plan from the start of `task`, of the fewest joint steps) and checks
/// the makespan search's bound in every state on it: at most the joint steps left, 0 at
/// the end, and at least its value less one after every joint step of two robots'
/// actions that do not interfere. Answers how many such steps it tried.
pub fn bound_along(task: &Task, plan: &[JointStep], name: &str) -> usize {
    let bound = LowerBound::new(task, &task.init, &task.robots, &task.goal);
    let mut checked = 0;
    let mut s = task.init.clone();
    for (k, step) in plan.iter().enumerate() {
        let h = bound.of(&s);
        assert!(
            usize::from(h) <= plan.len() - k,
            "{name}: h = {h}, {} steps left",
            plan.len() - k
        );
        let lists = rules::team_actions(task, &s, &task.robots);
        for (i, (&r1, l1)) in task.robots.iter().zip(&lists).enumerate() {
            for (&r2, l2) in task.robots.iter().zip(&lists).skip(i + 1) {
                for &a in l1 {
                    for &b in l2 {
                        let pair = [(r1, a), (r2, b)];
                        if joint::check(task, &s, &pair).is_ok() {
                            let mut next = s.clone();
                            joint::apply(task, &mut next, &pair);
                            let h2 = bound.of(&next);
                            assert!(
                                h <= h2 + 1,
                                "{name}: joint step {k}, {} and {}, drops h from {h} to {h2}",
                                a.render(task),
                                b.render(task)
                            );
                            checked += 1;
                        }
                    }
                }
            }
        }
        let parts: Vec<Part> = step
            .iter()
            .map(|st| (*task.robot(st.robot).expect("a plan's robot"), st.action))
            .collect();
        joint::apply(task, &mut s, &parts);
    }
    assert_eq!(bound.of(&s), 0, "{name}: the bound at the goal");
    checked
}
