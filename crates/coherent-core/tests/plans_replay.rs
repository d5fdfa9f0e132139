//! Shortest plans with the whole team replay exactly: through `planner::replay` and
//! through `SymbolicEnv::step` with the rendered action strings, every step executes and
//! the goal holds after exactly `plan.len()` steps, not before.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use coherent_core::planner::{self, Limits};
use coherent_core::{Edge, Environment, SymbolicEnv, Task};

mod common;

/// What the planner said about one task.
enum Verdict {
    /// Unsolvable for a reason visible without search; not searched.
    Obstacle(String),
    /// The search with the whole team exhausted the reachable states.
    Unsolvable,
    /// A shortest plan of this length was found and replayed.
    Solved(usize),
}

/// Plans `task` with the whole team and replays the plan; panics on any mismatch.
fn plan_and_replay(task: &Task) -> Verdict {
    // A task that cannot be solved for a reason visible without search (a goal
    // container that is no container...) is not searched: its whole reachable state
    // space can exceed the state limit, which is why `analyse` checks this first.
    let why: Vec<String> = task
        .goal
        .iter()
        .filter(|p| !task.init.has(Edge::new(p.subject, p.relation, p.target)))
        .filter_map(|p| planner::static_obstacle(task, p))
        .collect();
    if !why.is_empty() {
        return Verdict::Obstacle(why.join("; "));
    }
    let search = planner::search(task, &task.robots, &task.goal, &Limits::default());
    assert!(
        !search.truncated,
        "{}: search hit the state limit",
        common::name(task)
    );
    let Some(plan) = search.plan else {
        return Verdict::Unsolvable;
    };

    // Through planner::replay: every prefix replays, and the goal holds after the whole
    // plan and after no shorter prefix.
    for k in 0..=plan.len() {
        let state = planner::replay(task, &plan[..k]).unwrap_or_else(|(i, why)| {
            panic!(
                "{}: step {i} of the plan does not replay: {why}",
                common::name(task)
            )
        });
        assert_eq!(
            task.goal_satisfied(&state),
            k == plan.len(),
            "{}: goal after {k} of {} steps",
            common::name(task),
            plan.len()
        );
    }
    let end = planner::replay(task, &plan).expect("replayed above");

    // Through the environment, with action strings as a planner would send them.
    let mut env = SymbolicEnv::new(Arc::new(task.clone()));
    assert_eq!(
        env.goal_satisfied(),
        plan.is_empty(),
        "{}: goal at the start",
        common::name(task)
    );
    for (i, step) in plan.iter().enumerate() {
        let robot = task.id(step.robot);
        let text = step.action.render(task);
        let offered = env.actions(robot).expect("a robot of the task");
        assert!(
            offered.contains(&text),
            "{}: step {i} {text:?} is not offered to {robot}",
            common::name(task)
        );
        let outcome = env.step(robot, &text).expect("a robot of the task");
        assert!(
            outcome.executed(),
            "{}: step {i} ({robot} {text}) not executed: {:?}",
            common::name(task),
            outcome.infeasible
        );
        assert_eq!(
            outcome.done,
            i + 1 == plan.len(),
            "{}: goal after step {i}",
            common::name(task)
        );
        assert_eq!(env.goal_satisfied(), outcome.done);
    }
    assert!(
        env.goal_satisfied(),
        "{}: goal after the plan",
        common::name(task)
    );
    assert_eq!(
        env.state(),
        &end,
        "{}: env and replay end in the same state",
        common::name(task)
    );
    env.reset();
    assert_eq!(env.state(), &task.init, "{}: reset", common::name(task));
    Verdict::Solved(plan.len())
}

/// `f` over every task, on all cores; results in task order.
fn par_map<T: Send>(tasks: &[Task], f: impl Fn(&Task) -> T + Sync) -> Vec<T> {
    let next = AtomicUsize::new(0);
    let workers = std::thread::available_parallelism()
        .map_or(2, |n| n.get())
        .min(tasks.len());
    let mut out: Vec<(usize, T)> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                scope.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(task) = tasks.get(i) else { break done };
                        done.push((i, f(task)));
                    }
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    });
    out.sort_by_key(|(i, _)| *i);
    out.into_iter().map(|(_, t)| t).collect()
}

fn listing(items: &[String]) -> String {
    if items.is_empty() {
        String::new()
    } else {
        format!(":\n  {}", items.join("\n  "))
    }
}

#[test]
fn optimal_plans_replay_and_reach_the_goal_exactly_at_the_end() {
    let start = Instant::now();
    let tasks = common::released_tasks();
    let verdicts = par_map(&tasks, plan_and_replay);
    let mut obstacles = Vec::new();
    let mut unsolvable = Vec::new();
    let mut differ = Vec::new();
    let mut no_gt = Vec::new();
    let mut solvable = 0;
    for (task, verdict) in tasks.iter().zip(&verdicts) {
        match verdict {
            Verdict::Obstacle(why) => obstacles.push(format!("{} ({why})", common::name(task))),
            Verdict::Unsolvable => unsolvable.push(common::name(task)),
            Verdict::Solved(len) => {
                solvable += 1;
                match task.meta.gt_steps {
                    Some(gt) if gt as usize != *len => {
                        differ.push(format!("{} (gt {gt}, optimal {len})", common::name(task)));
                    }
                    Some(_) => {}
                    None => no_gt.push(common::name(task)),
                }
            }
        }
    }
    eprintln!(
        "{} tasks unsolvable for a static reason{}",
        obstacles.len(),
        listing(&obstacles)
    );
    eprintln!(
        "{} tasks searched: {solvable} solvable, {} unsolvable with the whole team{}",
        solvable + unsolvable.len(),
        unsolvable.len(),
        listing(&unsolvable)
    );
    eprintln!(
        "{} of {solvable} solvable tasks have an optimal length different from the file's ground truth{}",
        differ.len(),
        listing(&differ)
    );
    if !no_gt.is_empty() {
        eprintln!("no ground truth: {}", no_gt.join(", "));
    }
    eprintln!(
        "planned and replayed in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert_eq!(obstacles.len() + unsolvable.len() + solvable, 81);
}

/// A goal that holds at the start needs an empty plan, and the environment reports it
/// done before any step.
#[test]
fn goal_holding_at_the_start_gives_an_empty_plan() {
    let mut found = 0;
    for task in common::released_tasks() {
        if task.goal_satisfied(&task.init) {
            found += 1;
            let search = planner::search(&task, &task.robots, &task.goal, &Limits::default());
            assert_eq!(
                search.plan.as_deref(),
                Some(&[][..]),
                "{}",
                common::name(&task)
            );
            let state = planner::replay(&task, &[]).expect("the empty plan replays");
            assert_eq!(state, task.init);
            assert!(SymbolicEnv::new(Arc::new(task)).goal_satisfied());
        }
    }
    eprintln!("{found} tasks whose goal already holds at the start");
}

/// An infeasible step is not executed and leaves the state as it was.
#[test]
fn infeasible_steps_do_not_change_the_state() {
    for task in common::released_tasks().into_iter().step_by(7) {
        let mut env = SymbolicEnv::new(Arc::new(task.clone()));
        for r in &task.robots {
            let id = task.id(r.node);
            for text in [
                "[grab] <nothing>(99999)",
                "hello",
                "[land_on] <bedroom>(0)",
                "",
            ] {
                let before = env.state().clone();
                let outcome = env.step(id, text).expect("a robot of the task");
                assert!(
                    !outcome.executed(),
                    "{}: {text:?} executed",
                    common::name(&task)
                );
                assert_eq!(env.state(), &before);
            }
        }
    }
}
