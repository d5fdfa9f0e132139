//! Joint steps (docs/semantics.md, "Parallel steps"), on states reached on the released
//! tasks and on the project's own benchmark: a prefix of the task's shortest plan, then
//! random offered actions.
//!
//! - Actions a joint step accepts apply in every order, each offered at its turn, and
//!   every order ends in the state the joint step gives.
//! - A refused step names the two actions and what they share, and the pair alone is
//!   refused as well (the test is pairwise).
//! - Two actions' footprints meet exactly when the two do not commute (on random
//!   states, and on every state near each shortest plan); and the writes of an action
//!   that change something are exactly what it changes.

use std::sync::{Arc, OnceLock};

use coherent_core::footprint::{Atom, Footprint};
use coherent_core::joint::{self, Part, Refusal};
use coherent_core::planner::{self, Limits, Step};
use coherent_core::{
    Action, Environment, Idx, NodeId, Reason, Robot, State, SymbolicEnv, Task, benchmark,
    feasibility, rules,
};
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{FileFailurePersistence, TestCaseError};

mod common;

/// The 81 released tasks, then the 100 of the project's benchmark.
fn tasks() -> &'static [Task] {
    static TASKS: OnceLock<Vec<Task>> = OnceLock::new();
    TASKS.get_or_init(|| {
        let mut all = common::released_tasks();
        all.extend(benchmark::tasks().expect("the benchmark reads"));
        all
    })
}

/// The shortest plan of task `i` (empty when it has none), found once.
fn plan(i: usize) -> &'static [Step] {
    static PLANS: OnceLock<Vec<OnceLock<Vec<Step>>>> = OnceLock::new();
    let plans = PLANS.get_or_init(|| (0..tasks().len()).map(|_| OnceLock::new()).collect());
    plans[i].get_or_init(|| {
        let task = &tasks()[i];
        planner::search(task, &task.robots, &task.goal, &Limits::default())
            .plan
            .unwrap_or_default()
    })
}

/// Where a case starts: a task, how much of its plan to play, then random actions.
type Start = (Index, Index, Vec<(Index, Index)>);

fn starts() -> impl Strategy<Value = Start> {
    (
        any::<Index>(),
        any::<Index>(),
        prop::collection::vec((any::<Index>(), any::<Index>()), 0..=6),
    )
}

/// The task and the state a case starts from, with the steps that led there.
fn reach((task_ix, played, walk): Start) -> (&'static Task, State, Vec<String>) {
    let i = task_ix.index(tasks().len());
    let task = &tasks()[i];
    let plan = plan(i);
    let mut s = task.init.clone();
    let mut trace = Vec::new();
    for step in &plan[..played.index(plan.len() + 1)] {
        let robot = *task.robot(step.robot).expect("a plan's robot");
        trace.push(format!(
            "{} {}",
            task.id(robot.node),
            step.action.render(task)
        ));
        rules::apply(task, &mut s, robot, step.action);
    }
    for (robot_ix, action_ix) in walk {
        let robot = *robot_ix.get(&task.robots);
        let offered = rules::actions(task, &s, robot);
        if offered.is_empty() {
            continue;
        }
        let a = *action_ix.get(&offered);
        trace.push(format!("{} {}", task.id(robot.node), a.render(task)));
        rules::apply(task, &mut s, robot, a);
    }
    (task, s, trace)
}

fn context(task: &Task, trace: &[String]) -> String {
    format!("{} after [{}]", common::name(task), trace.join("; "))
}

fn render(task: &Task, step: &[Part]) -> String {
    let parts: Vec<String> = step
        .iter()
        .map(|(r, a)| format!("{} {}", task.id(r.node), a.render(task)))
        .collect();
    parts.join(" | ")
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

/// Applies `step` in every order through the sequential rules (each action checked as
/// text, as an episode would): every order ends in `expected`.
fn every_order(
    task: &Task,
    s: &State,
    step: &[Part],
    expected: &State,
    ctx: &str,
) -> Result<(), TestCaseError> {
    for order in orders(step.len()) {
        let mut t = s.clone();
        for &k in &order {
            let (robot, a) = step[k];
            let text = a.render(task);
            match feasibility::check(task, &t, robot, &text) {
                Ok(found) => rules::apply(task, &mut t, robot, found),
                Err(why) => {
                    return Err(TestCaseError::fail(format!(
                        "{ctx}: step [{}] in order {order:?}: {} {text} is refused at its turn: {}",
                        render(task, step),
                        task.id(robot.node),
                        why.message
                    )));
                }
            }
        }
        prop_assert!(
            &t == expected,
            "{ctx}: step [{}] in order {order:?} ends elsewhere than the joint step",
            render(task, step)
        );
    }
    Ok(())
}

/// Builds a step robot by robot from the drawn actions, keeping each action the step
/// accepts; checks every refusal, then the step in every order.
fn grow_step(start: Start, picks: Vec<(Index, u8)>) -> Result<(), TestCaseError> {
    let (task, s, trace) = reach(start);
    let ctx = context(task, &trace);
    let lists = rules::team_actions(task, &s, &task.robots);
    let mut step: Vec<Part> = Vec::new();
    for ((&robot, offered), (pick, skip)) in task.robots.iter().zip(&lists).zip(picks) {
        if offered.is_empty() || skip % 5 == 0 {
            continue;
        }
        let a = *pick.get(offered);
        let mut tried = step.clone();
        tried.push((robot, a));
        match joint::check(task, &s, &tried) {
            Ok(()) => step = tried,
            Err(Refusal::Interference(x)) => {
                refusal_names_the_pair(task, &s, &tried, &x, &ctx)?;
            }
            Err(other) => {
                return Err(TestCaseError::fail(format!(
                    "{ctx}: [{}] refused for an offered action: {other}",
                    render(task, &tried)
                )));
            }
        }
    }
    let mut expected = s.clone();
    joint::apply(task, &mut expected, &step);
    every_order(task, &s, &step, &expected, &ctx)
}

/// A refusal names the newest action and one before it, both as text, and what they
/// share; that pair alone is refused too.
fn refusal_names_the_pair(
    task: &Task,
    s: &State,
    tried: &[Part],
    x: &joint::Interference,
    ctx: &str,
) -> Result<(), TestCaseError> {
    let last = tried.len() - 1;
    prop_assert!(
        x.second == last && x.first < last,
        "{ctx}: [{}]: the refusal names parts {} and {}",
        render(task, tried),
        x.first,
        x.second
    );
    for k in [x.first, x.second] {
        let (robot, a) = tried[k];
        for text in [a.render(task), task.node(robot.node).label()] {
            prop_assert!(
                x.message.contains(&text),
                "{ctx}: the refusal does not name {text}: {}",
                x.message
            );
        }
    }
    prop_assert!(
        x.message.contains(&task.node(x.shared).label()),
        "{ctx}: the refusal does not name what is shared, {}: {}",
        task.node(x.shared).label(),
        x.message
    );
    let pair = [tried[x.first], tried[x.second]];
    prop_assert!(
        matches!(joint::check(task, s, &pair), Err(Refusal::Interference(_))),
        "{ctx}: [{}] is refused, but not its pair [{}]",
        render(task, tried),
        render(task, &pair)
    );
    Ok(())
}

/// The atoms that differ between `a` and `b`.
fn changed(a: &State, b: &State, nodes: usize) -> Vec<Atom> {
    let mut out = Vec::new();
    for n in (0..nodes).map(|i| Idx(i as u16)) {
        if a.states(n) != b.states(n) {
            out.push(Atom::states(n));
        }
        if a.on_high_surface(n) != b.on_high_surface(n) {
            out.push(Atom::high(n));
        }
    }
    for e in a.edges().iter().filter(|e| !b.has(**e)) {
        out.push(Atom::edge(*e));
    }
    for e in b.edges().iter().filter(|e| !a.has(**e)) {
        out.push(Atom::edge(*e));
    }
    out
}

fn after(task: &Task, s: &State, robot: Robot, a: Action) -> State {
    let mut t = s.clone();
    rules::apply(task, &mut t, robot, a);
    t
}

/// Every pair of offered actions of two robots in `s`: their footprints do not meet
/// exactly when both orders apply and agree. Every action's writes that change an atom are
/// exactly the atoms it changes, with the values it leaves. Returns the number of pairs
/// and of pairs whose footprints meet.
fn every_pair(task: &Task, s: &State, ctx: &str) -> Result<(usize, usize), TestCaseError> {
    let lists = rules::team_actions(task, s, &task.robots);
    let mut offered: Vec<(Robot, Action, Footprint, State)> = Vec::new();
    for (&robot, actions) in task.robots.iter().zip(&lists) {
        for &a in actions {
            let print = Footprint::of(task, s, robot, a);
            let next = after(task, s, robot, a);
            let mut changes: Vec<Atom> = print
                .writes
                .iter()
                .filter(|w| w.changes)
                .map(|w| w.atom)
                .collect();
            let mut changed = changed(s, &next, task.nodes.len());
            changes.sort();
            changed.sort();
            prop_assert_eq!(
                &changes,
                &changed,
                "{}: {} {}: the writes that change something are not what changes",
                ctx,
                task.id(robot.node),
                a.render(task)
            );
            offered.push((robot, a, print, next));
        }
    }
    let (mut pairs, mut meet) = (0, 0);
    for (i, (r1, a1, f1, s1)) in offered.iter().enumerate() {
        for (r2, a2, f2, s2) in &offered[i + 1..] {
            if r1 == r2 {
                continue;
            }
            pairs += 1;
            let pair = format!(
                "{} {} | {} {}",
                task.id(r1.node),
                a1.render(task),
                task.id(r2.node),
                a2.render(task)
            );
            let second_after_first = rules::actions(task, s1, *r2).contains(a2);
            let first_after_second = rules::actions(task, s2, *r1).contains(a1);
            let agree = second_after_first
                && first_after_second
                && after(task, s1, *r2, *a2) == after(task, s2, *r1, *a1);
            if let Some(c) = f1.conflict(f2) {
                meet += 1;
                prop_assert!(
                    !agree,
                    "{ctx}: [{pair}]: the footprints meet ({c:?}), yet both orders agree"
                );
                continue;
            }
            prop_assert!(
                second_after_first,
                "{ctx}: [{pair}]: the second is not offered after the first"
            );
            prop_assert!(
                first_after_second,
                "{ctx}: [{pair}]: the first is not offered after the second"
            );
            prop_assert!(
                agree,
                "{ctx}: [{pair}]: the two orders end in different states"
            );
        }
    }
    Ok((pairs, meet))
}

/// Every state within a few actions of each state along every task's shortest plan,
/// and every pair of actions there: the pairwise test is sound and exact on them all.
#[test]
fn footprints_meet_exactly_when_two_actions_do_not_commute_near_every_shortest_plan() {
    const AROUND: usize = 8;
    let (mut pairs, mut meet) = (0, 0);
    for (i, task) in tasks().iter().enumerate() {
        let mut s = task.init.clone();
        let mut trace = Vec::new();
        for step in std::iter::once(None).chain(plan(i).iter().map(Some)) {
            if let Some(step) = step {
                let robot = *task.robot(step.robot).expect("a plan's robot");
                trace.push(format!(
                    "{} {}",
                    task.id(robot.node),
                    step.action.render(task)
                ));
                rules::apply(task, &mut s, robot, step.action);
            }
            // Breadth-first from the plan's state, AROUND states.
            let mut queue = std::collections::VecDeque::from([s.clone()]);
            let mut seen = vec![s.clone()];
            while let Some(t) = queue.pop_front() {
                let (p, m) =
                    every_pair(task, &t, &context(task, &trace)).unwrap_or_else(|e| panic!("{e}"));
                (pairs, meet) = (pairs + p, meet + m);
                let lists = rules::team_actions(task, &t, &task.robots);
                for (&robot, actions) in task.robots.iter().zip(&lists) {
                    for &a in actions {
                        let next = after(task, &t, robot, a);
                        if seen.len() < AROUND && !seen.contains(&next) {
                            seen.push(next.clone());
                            queue.push_back(next);
                        }
                    }
                }
            }
        }
    }
    // The test saw both kinds of pairs, and many.
    assert!(
        pairs > 100_000 && meet > 1_000,
        "{pairs} pairs, {meet} meeting"
    );
}

/// `cases` cases; failures are saved next to this file, as in `invariants.rs`.
fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource(
            "proptest-regressions",
        ))),
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config(512))]

    #[test]
    fn accepted_joint_steps_apply_in_every_order_and_refusals_name_the_pair(
        start in starts(),
        picks in prop::collection::vec((any::<Index>(), any::<u8>()), 4),
    ) {
        grow_step(start, picks)?;
    }

    #[test]
    fn footprints_meet_exactly_when_two_actions_do_not_commute(start in starts()) {
        let (task, s, trace) = reach(start);
        every_pair(task, &s, &context(task, &trace))?;
    }
}

/// A task by the name the docs give it: `env0 task 2`, `s1-apartment task 13`.
fn task_named(name: &str) -> usize {
    tasks()
        .iter()
        .position(|t| common::name(t) == name)
        .unwrap_or_else(|| panic!("no task {name}"))
}

/// `23 [movetowards] <kitchen>(6)`: a robot id and an action string.
fn robot_action(cell: &str) -> (NodeId, String) {
    let cell = cell.trim().trim_matches('`');
    let (id, action) = cell.split_once(' ').expect("`<robot id> <action>`");
    (NodeId(id.parse().expect("a robot id")), action.to_owned())
}

/// Every row of the examples in docs/semantics.md, "Parallel steps": the state after
/// the first k steps of the task's shortest plan, the joint step of the two actions
/// through `Environment::step_joint`, allowed (the state the two give in sequence) or
/// refused over what the row names (nothing changes, both robots told why).
#[test]
fn the_parallel_steps_of_the_docs_are_allowed_or_refused_as_written() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/semantics.md");
    let docs = std::fs::read_to_string(path).expect("docs/semantics.md reads");
    let table = docs
        .split("| Task, after k plan steps |")
        .nth(1)
        .expect("the examples table of \"Parallel steps\"");
    let rows: Vec<&str> = table
        .lines()
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .collect();
    assert!(rows.len() >= 6, "{} rows", rows.len());
    for row in rows {
        let cells: Vec<&str> = row.trim_matches('|').split('|').map(str::trim).collect();
        let (name, k) = cells[0].split_once(", k = ").expect("`<task>, k = <n>`");
        let i = task_named(name);
        let task = &tasks()[i];
        let mut env = SymbolicEnv::new(Arc::new(task.clone()));
        for step in &plan(i)[..k.parse::<usize>().expect("k")] {
            let text = step.action.render(task);
            assert!(
                env.step(task.id(step.robot), &text)
                    .expect("a robot")
                    .executed()
            );
        }
        let before = env.state().clone();
        let (r1, a1) = robot_action(cells[1]);
        let (r2, a2) = robot_action(cells[2]);
        let outcome = env
            .step_joint(&[(r1, &a1), (r2, &a2)])
            .expect("robots of the task");
        match cells[3].strip_prefix("refused: ") {
            None => {
                assert!(cells[3].starts_with("allowed"), "{row}");
                assert!(outcome.refused.is_none(), "{row}: {:?}", outcome.refused);
                assert!(outcome.parts.iter().all(|p| p.executed()), "{row}");
                let mut s = before.clone();
                for (r, a) in [(r1, &a1), (r2, &a2)] {
                    let robot = task.robot_by_id(r).expect("a robot");
                    let found = feasibility::check(task, &s, robot, a).expect("offered");
                    rules::apply(task, &mut s, robot, found);
                }
                assert_eq!(env.state(), &s, "{row}");
            }
            Some(verdict) => {
                let shared = verdict.split([',', ':']).next().expect("what is shared");
                let Some(Refusal::Interference(x)) = &outcome.refused else {
                    panic!("{row}: {:?}", outcome.refused);
                };
                assert!(
                    x.message.contains(&format!("interfere over {shared}")),
                    "{row}: {}",
                    x.message
                );
                for part in &outcome.parts {
                    let why = part.infeasible.as_ref().expect("not executed");
                    assert_eq!(why.reason, Reason::Interference, "{row}");
                }
                assert_eq!(env.state(), &before, "{row}");
            }
        }
    }
}

/// A step with an action not offered and another that is fine: nothing happens, the
/// first robot hears its own reason, the second that the step was refused; the same
/// step without the bad action is carried out; an unknown robot is an error.
#[test]
fn a_refused_step_tells_each_robot_why_and_changes_nothing() {
    let task = Arc::new(tasks()[task_named("env0 task 2")].clone());
    let mut env = SymbolicEnv::new(task.clone());
    let (dog, arm) = (NodeId(23), NodeId(24));
    let outcome = env
        .step_joint(&[
            (dog, "[grab] <microwave>(15)"),
            (arm, "[open] <microwave>(15)"),
        ])
        .expect("robots of the task");
    assert_eq!(env.state(), &task.init);
    let reasons: Vec<Reason> = outcome
        .parts
        .iter()
        .map(|p| p.infeasible.as_ref().expect("refused").reason)
        .collect();
    assert_eq!(reasons[1], Reason::StepRefused);
    assert!(!matches!(
        reasons[0],
        Reason::StepRefused | Reason::Interference
    ));
    assert!(
        matches!(outcome.refused, Some(Refusal::Infeasible(ref v)) if v.len() == 1 && v[0].0 == 0)
    );
    let ok = env
        .step_joint(&[
            (arm, "[open] <microwave>(15)"),
            (dog, "[movetowards] <kitchen>(6)"),
        ])
        .expect("robots of the task");
    assert!(ok.refused.is_none() && ok.parts.iter().all(|p| p.executed()));
    assert_ne!(env.state(), &task.init);
    assert!(
        env.step_joint(&[(NodeId(15), "[open] <microwave>(15)")])
            .is_err()
    );
}
