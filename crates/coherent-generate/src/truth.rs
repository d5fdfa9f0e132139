//! A task's ground truth, from the engine's own searches with their limits: the optimal
//! sequential plan and the task type (`planner::analyse`), the fewest joint steps
//! (`makespan::search_with`, from that plan), and the fewest robots with which the goal
//! is reachable. A search that a limit stops proves nothing, and the truth says so: an
//! unproven makespan carries its bounds, an undecided type or robot count is `None`.

use std::time::Instant;

use coherent_core::makespan;
use coherent_core::planner::{self, Limits, Step, Stop, TaskType};
use coherent_core::relaxed::may_reach_with;
use coherent_core::{Robot, RobotKind, Task};

/// What the searches prove of a solvable task.
#[derive(Clone, Debug)]
pub struct Truth {
    /// A shortest sequential plan: proven, as every plan the A* search returns is.
    pub plan: Vec<Step>,
    /// The fewest robot types; `None` when a limit stopped a smaller team's search.
    pub task_type: Option<TaskType>,
    /// The fewest robots; `None` when a limit stopped a smaller team's search.
    pub needed: Option<usize>,
    /// The best parallel plan found: the fewest joint steps when proven.
    pub joint_plan: Vec<Vec<Step>>,
    /// No parallel plan has fewer joint steps than this.
    pub makespan_lower: usize,
    pub makespan_proven: bool,
    /// The limit that stopped the makespan search, if one did.
    pub makespan_stop: Option<Stop>,
    /// States the sequential and the makespan search expanded.
    pub states: usize,
    pub makespan_states: usize,
    /// Milliseconds of the whole: plan, type, makespan, robots needed.
    pub ms: f64,
}

impl Truth {
    pub fn steps(&self) -> usize {
        self.plan.len()
    }

    pub fn makespan(&self) -> usize {
        self.joint_plan.len()
    }

    /// Sequential steps over joint steps: how much acting at once pays.
    pub fn ratio(&self) -> f64 {
        self.steps() as f64 / self.makespan().max(1) as f64
    }
}

/// What the searches say of a drawn task.
#[derive(Clone, Debug)]
pub enum Verdict {
    Solved(Box<Truth>),
    /// No plan reaches the goal (the search exhausted every state, or the goal is
    /// impossible on its face), or it holds at the start.
    Unsolvable,
    /// The sequential search stopped at a limit before it found a plan.
    Undecided(Stop),
}

/// The ground truth of `task` within `limits`.
pub fn ground_truth(task: &Task, limits: &Limits) -> Verdict {
    let t0 = Instant::now();
    if task.goal_satisfied(&task.init) {
        return Verdict::Unsolvable;
    }
    let analysis = planner::analyse(task, limits);
    let Some(plan) = analysis.plan else {
        return match analysis.stop {
            Some(stop) => Verdict::Undecided(stop),
            None => Verdict::Unsolvable,
        };
    };
    let m = makespan::search_with(
        task,
        &task.init,
        &task.robots,
        &task.goal,
        Some(&plan),
        limits,
    );
    // The makespan search starts from the sequential plan scheduled: it always has one.
    let joint_plan = m
        .plan
        .clone()
        .unwrap_or_else(|| plan.iter().map(|s| vec![*s]).collect());
    let needed = fewest_robots(task, &plan, limits);
    Verdict::Solved(Box::new(Truth {
        task_type: analysis.task_type,
        needed,
        makespan_lower: m.lower.min(joint_plan.len()),
        makespan_proven: m.proven,
        makespan_stop: m.stop,
        joint_plan,
        states: analysis.states_expanded,
        makespan_states: m.states_expanded,
        plan,
        ms: t0.elapsed().as_secs_f64() * 1e3,
    }))
}

/// The fewest robots of the team with which the goal is reachable: the robots of the
/// shortest plan bound it from above; smaller teams are tried smallest first, each
/// ruled out by the relaxed analysis (`relaxed::may_reach_with`) or by a search that
/// exhausts its states. A search stopped by a limit leaves the number undecided.
///
/// The legged robots count as one: each can walk into every room (stairs are always
/// open, and it opens every door itself), so any one of them reaches what another
/// does, and a team with one of them is tried with the first. Quadrotors and arms
/// differ by where they stand and are tried each.
fn fewest_robots(task: &Task, plan: &[Step], limits: &Limits) -> Option<usize> {
    let mut used: Vec<coherent_core::Idx> = plan.iter().map(|s| s.robot).collect();
    used.sort_unstable();
    used.dedup();
    let upper = used.len();
    let dogs: Vec<Robot> = task
        .robots
        .iter()
        .copied()
        .filter(|r| r.kind == RobotKind::RobotDog)
        .collect();
    let others: Vec<Robot> = task
        .robots
        .iter()
        .copied()
        .filter(|r| r.kind != RobotKind::RobotDog)
        .collect();
    for k in 1..upper {
        for with_dog in [false, true] {
            if with_dog && dogs.is_empty() {
                continue;
            }
            let rest = k - usize::from(with_dog);
            if rest > others.len() {
                continue;
            }
            for pick in combinations(others.len(), rest) {
                let mut team: Vec<Robot> = pick.iter().map(|&i| others[i]).collect();
                if with_dog {
                    team.push(dogs[0]);
                }
                if !may_reach_with(task, &team, &task.goal) {
                    continue;
                }
                let found = planner::search(task, &team, &task.goal, limits);
                if found.plan.is_some() {
                    return Some(k);
                }
                if found.truncated {
                    return None;
                }
            }
        }
    }
    Some(upper)
}

/// Every way of choosing `k` of `n` indices, in lexicographic order.
fn combinations(n: usize, k: usize) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    let mut pick: Vec<usize> = (0..k).collect();
    if k > n {
        return out;
    }
    loop {
        out.push(pick.clone());
        // The rightmost index that can still move right.
        let Some(i) = (0..k).rev().find(|&i| pick[i] < n - k + i) else {
            return out;
        };
        pick[i] += 1;
        for j in i + 1..k {
            pick[j] = pick[j - 1] + 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::combinations;

    #[test]
    fn combinations_are_all_there() {
        assert_eq!(combinations(4, 2).len(), 6);
        assert_eq!(combinations(3, 0), vec![Vec::<usize>::new()]);
        assert_eq!(combinations(2, 3).len(), 0);
        assert_eq!(combinations(3, 3), vec![vec![0, 1, 2]]);
    }
}
