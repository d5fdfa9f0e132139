//! Makespan-optimal plans (docs/planner.md, "Parallel plans"):
//! - every plan of the released tasks and of our benchmark's 100 is proven optimal
//!   within the default limits, and its joint steps are valid: their actions apply in
//!   every order through the sequential rules, each offered at its turn, all orders
//!   ending alike, and the last step reaches the goal; no plan is longer than the
//!   sequential optimum, and (on the released tasks and tasks 0 to 4 of each of our
//!   scenes) the proven makespans agree with a breadth-first search over every joint step on the
//!   tasks small enough for it;
//! - the heuristic never overestimates along each plan and one joint step lowers it by
//!   at most one;
//! - a search stopped at a limit says so, keeps the scheduled sequential optimum and a
//!   lower bound below it.

use coherent_core::joint::{self, Part};
use coherent_core::makespan::{self, JointStep};
use coherent_core::planner::{self, Limits, Step, Stop};
use coherent_core::{State, Task, benchmark, feasibility, rules};

mod common;
#[path = "common/oracle.rs"]
mod oracle;

/// The released tasks, and tasks 0 to 4 of each scene of our benchmark (`every`: all of
/// its tasks).
fn tasks(every: bool) -> Vec<Task> {
    let mut all = common::released_tasks();
    all.extend(
        benchmark::tasks()
            .expect("the benchmark reads")
            .into_iter()
            .filter(|t| every || t.meta.task_id < 5),
    );
    all
}

fn parts(task: &Task, step: &[Step]) -> Vec<Part> {
    step.iter()
        .map(|st| (*task.robot(st.robot).expect("a plan's robot"), st.action))
        .collect()
}

/// Every permutation of `0..n`.
fn orders(n: usize) -> Vec<Vec<usize>> {
    if n == 0 {
        return vec![Vec::new()];
    }
    let mut out = Vec::new();
    for rest in orders(n - 1) {
        for at in 0..=rest.len() {
            let mut o = rest.clone();
            o.insert(at, n - 1);
            out.push(o);
        }
    }
    out
}

/// Plays a joint plan from the start, each step in every order through the sequential
/// rules (the actions as text, as an episode sends them); the state at the end.
fn play(task: &Task, plan: &[JointStep]) -> State {
    let name = common::name(task);
    let mut s = task.init.clone();
    for (k, step) in plan.iter().enumerate() {
        assert!(!step.is_empty(), "{name}: joint step {k} is empty");
        let mut ends: Vec<State> = Vec::new();
        for order in orders(step.len()) {
            let mut t = s.clone();
            for &i in &order {
                let robot = *task.robot(step[i].robot).expect("a plan's robot");
                let text = step[i].action.render(task);
                let a = feasibility::check(task, &t, robot, &text).unwrap_or_else(|e| {
                    panic!(
                        "{name}: joint step {k}, order {order:?}: {text}: {}",
                        e.message
                    )
                });
                rules::apply(task, &mut t, robot, a);
            }
            ends.push(t);
        }
        assert!(
            ends.iter().all(|e| *e == ends[0]),
            "{name}: joint step {k} ends differently by order"
        );
        assert_eq!(
            joint::check(task, &s, &parts(task, step)),
            Ok(()),
            "{name}: step {k}"
        );
        s = ends.swap_remove(0);
    }
    s
}

#[test]
fn parallel_plans_are_valid_in_every_order_and_never_longer_than_the_sequential_optimum() {
    let mut shorter = 0;
    for task in tasks(true) {
        let name = common::name(&task);
        let sequential = planner::search(&task, &task.robots, &task.goal, &Limits::default());
        let found = makespan::search_with(
            &task,
            &task.init,
            &task.robots,
            &task.goal,
            sequential.plan.as_deref(),
            &Limits::default(),
        );
        let Some(seq) = sequential.plan else {
            assert!(
                found.plan.is_none(),
                "{name}: a parallel plan without a sequential one"
            );
            continue;
        };
        assert!(found.proven, "{name}: not proven within the default limits");
        let plan = found
            .plan
            .expect("a plan when the sequential search has one");
        assert!(
            plan.len() <= seq.len(),
            "{name}: {} joint steps, {} sequential",
            plan.len(),
            seq.len()
        );
        assert_eq!(
            found.lower,
            plan.len(),
            "{name}: proven, so the bound is the makespan"
        );
        let end = play(&task, &plan);
        assert!(
            task.goal_satisfied(&end),
            "{name}: the plan does not reach the goal"
        );
        // The heuristic never overestimates along the optimal plan.
        let bound = makespan::LowerBound::new(&task, &task.init, &task.robots, &task.goal);
        let mut s = task.init.clone();
        for (k, step) in plan.iter().enumerate() {
            let h = usize::from(bound.of(&s));
            assert!(h <= plan.len() - k, "{name}: h = {h} at joint step {k}");
            joint::apply(&task, &mut s, &parts(&task, step));
        }
        let scheduled = makespan::schedule(&task, &task.init, &seq, &task.goal);
        assert!(
            task.goal_satisfied(&play(&task, &scheduled)),
            "{name}: the schedule"
        );
        assert!(plan.len() <= scheduled.len());
        shorter += usize::from(plan.len() < seq.len());
    }
    // Robots that act at once finish some tasks sooner, not all.
    assert!(shorter > 20, "only {shorter} tasks are faster in parallel");
}

#[test]
fn proven_makespans_and_their_fewest_actions_agree_with_a_breadth_first_search() {
    let mut compared = 0;
    for task in tasks(false) {
        // The short tasks: a breadth-first search over every joint step stays small.
        let sequential = planner::search(&task, &task.robots, &task.goal, &Limits::default());
        if sequential.plan.is_none_or(|p| p.len() > 5) {
            continue;
        }
        let Some(bfs) = oracle::breadth_first(&task, 20_000) else {
            continue;
        };
        let found = makespan::search(&task, &task.robots, &task.goal, &Limits::default());
        let plan = found.plan.expect("a plan where breadth-first finds one");
        assert_eq!(
            (plan.len(), oracle::actions(&plan)),
            bfs,
            "{}: (joint steps, actions)",
            common::name(&task)
        );
        compared += 1;
    }
    assert!(compared >= 4, "only {compared} tasks small enough");
}

#[test]
fn the_makespan_heuristic_is_admissible_and_consistent_along_parallel_plans() {
    let mut checked = 0;
    for task in tasks(false).into_iter().filter(|t| t.meta.task_id % 4 == 0) {
        let name = common::name(&task);
        let Some(plan) = makespan::search(&task, &task.robots, &task.goal, &Limits::default()).plan
        else {
            continue;
        };
        checked += oracle::bound_along(&task, &plan, &name);
    }
    assert!(checked > 10_000, "only {checked} joint steps checked");
}

#[test]
fn a_search_stopped_at_a_limit_keeps_the_scheduled_plan_and_a_lower_bound() {
    let task = common::released_tasks()
        .into_iter()
        .find(|t| common::name(t) == "env1 task 14")
        .expect("env1 task 14");
    let sequential = planner::search(&task, &task.robots, &task.goal, &Limits::default())
        .plan
        .expect("solvable");
    let full = makespan::search_with(
        &task,
        &task.init,
        &task.robots,
        &task.goal,
        Some(&sequential),
        &Limits::default(),
    );
    let stopped = makespan::search_with(
        &task,
        &task.init,
        &task.robots,
        &task.goal,
        Some(&sequential),
        &Limits::max_states(50),
    );
    assert_eq!(stopped.stop, Some(Stop::States));
    assert!(!stopped.proven);
    let plan = stopped.plan.expect("the scheduled sequential optimum");
    let best = full.makespan().expect("a plan");
    assert!(stopped.lower <= best && best <= plan.len() && plan.len() <= sequential.len());
    assert!(
        stopped.lower < plan.len(),
        "the bounds meet: it would be proven"
    );
    assert!(task.goal_satisfied(&play(&task, &plan)));
}

/// Among the plans of the fewest joint steps the search gives one of the fewest actions.
/// env2 task 13 takes 16 actions one robot at a time and 14 joint steps at once; counting
/// joint steps alone, a plan of 14 carried 27 actions (a quadrotor landing and taking off
/// again, an arm moving things back and forth while another robot finished). Its plan now
/// does the sequential optimum's 16 actions, no more, and stays proven the fewest steps.
#[test]
fn among_the_fewest_joint_steps_the_plan_has_the_fewest_actions() {
    let task = common::released_tasks()
        .into_iter()
        .find(|t| common::name(t) == "env2 task 13")
        .expect("env2 task 13");
    let sequential = planner::search(&task, &task.robots, &task.goal, &Limits::default())
        .plan
        .expect("solvable");
    assert_eq!(sequential.len(), 16);
    let found = makespan::search(&task, &task.robots, &task.goal, &Limits::default());
    assert!(found.proven && found.stop.is_none());
    let plan = found.plan.expect("a plan");
    assert_eq!((plan.len(), found.lower), (14, 14));
    assert_eq!(
        oracle::actions(&plan),
        16,
        "no more actions than the sequential optimum"
    );
    assert!(task.goal_satisfied(&play(&task, &plan)));
}

/// The demo task with a chain of `depth` open boxes, each inside the next and the last on
/// the kitchen floor: the robot dog sees every box and may walk up to each, and a walk
/// to the innermost depends on every edge up to the kitchen.
fn chain(depth: i64) -> Task {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/tasks/demo.json"
    );
    let text = std::fs::read_to_string(path).expect("the demo task");
    let mut value: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let graph = &mut value["graph"];
    for i in 0..depth {
        let id = 100 + i;
        graph["nodes"].as_array_mut().expect("nodes").push(
            serde_json::json!({"id": id, "category": "Containers", "class_name": "box",
                "properties": ["CONTAINERS"], "states": ["OPEN"]}),
        );
        let (to, relation) = if i + 1 < depth {
            (id + 1, "INSIDE")
        } else {
            (1, "ON")
        };
        graph["edges"]
            .as_array_mut()
            .expect("edges")
            .push(serde_json::json!({"from_id": id, "to_id": to, "relation_type": relation}));
    }
    coherent_core::native::read("chain.json", &value).expect("the chain task")
}

/// A search's limits cover its whole work. 10,000 boxes deep, the dog's walk to a box
/// reads the chain up to the room, so that the footprints of its 10,000 walks are 50
/// million reads: taken all before the first state was stored, they took 325 s and 675
/// MB that neither the state nor the memory limit saw. A footprint is now taken when an
/// action is compared with another, in time linear in its reads: at 1,000 states, or
/// 32 MiB, the search stops at once.
#[test]
fn a_scene_deep_in_containers_stops_at_its_limits_at_once() {
    let task = chain(10_000);
    let limited = [
        (Limits::max_states(1000), Stop::States),
        (
            Limits {
                max_memory: 32 << 20,
                ..Limits::default()
            },
            Stop::Memory,
        ),
    ];
    for (limits, stop) in limited {
        let found =
            makespan::search_with(&task, &task.init, &task.robots, &task.goal, None, &limits);
        assert_eq!(found.stop, Some(stop));
        assert!(found.plan.is_none() && !found.proven);
        assert!(
            found.elapsed < std::time::Duration::from_secs(10),
            "{:?} to its limit",
            found.elapsed
        );
        assert!(found.memory <= limits.max_memory, "{} bytes", found.memory);
    }
}
