//! Dynamic variants of a task (docs/dynamic.md): the task with one event, one variant per
//! kind where the kind makes sense, placed along the task's own optimal plan so that the
//! event meets the team at work. Deterministic: the same task gives the same variants.
//!
//! Along the optimal plan `P` of `n` steps, with `m = n / 2 + 1` the middle step:
//!
//! - `robot_down`: before step `m`, a robot that acts in the rest of the plan goes down:
//!   the first without which the team still reaches the goal, else the robot of step `m`
//!   (the goal then goes out of reach for good);
//! - `robot_up`: the robot that takes the plan's first step joins before step 3 (out of
//!   the team until then), where the task places it; only in a team of two or more;
//! - `object_moved`: before step `m`, the first goal thing not yet in place is put on
//!   another surface (one it is not on, not the goal's, not high and not a floor; in
//!   another room when there is one);
//! - `goal_changed`: before step `m`, the first goal predicate not yet holding gets
//!   another target of its kind (a surface for `ON`, a container for `INSIDE`), chosen as
//!   above, and the instruction says so;
//! - `blocked`: the first door the plan passes is locked for 3 steps before the step that
//!   passes it; none when the plan passes no door;
//! - `action_fails`: every action fails with probability 0.2 from step 1.
//!
//! A variant's ground truth is its reference: the steps of the optimal planner replanning
//! at each event (the oracle of docs/dynamic.md), so that its budget of twice the ground
//! truth leaves a team the same room as the task's; the task's own where the goal goes
//! out of reach for good, and for failing actions (their draws are each episode's).

use std::sync::Arc;

use coherent_core::events::{Event, Happening, Trigger};
use coherent_core::planner::{self, Limits, Step};
use coherent_core::task::predicate_holds;
use coherent_core::{
    GoalPredicate, Idx, NodeKind, PropSet, Relation, Schedule, State, Task, Verb, rules,
};

/// One variant: the kind of its event, and the task with it.
#[derive(Clone, Debug)]
pub struct Variant {
    pub kind: &'static str,
    pub task: Task,
}

/// The chance each action fails in an `action_fails` variant.
pub const FAIL_CHANCE: f64 = 0.2;
/// The most states the search for a plan without a lost robot visits.
pub const LOST_STATES: usize = 200_000;
/// How long a `blocked` variant's door stays locked.
pub const LOCKED_STEPS: u32 = 3;

/// The variants of `task`, one per kind where it makes sense; none when the task has
/// events already, or no optimal plan of two steps or more within `limits`.
pub fn variants(task: &Task, limits: &Limits) -> Vec<Variant> {
    if !task.events.is_empty() {
        return Vec::new();
    }
    let Some(plan) = planner::search(task, &task.robots, &task.goal, limits).plan else {
        return Vec::new();
    };
    if plan.len() < 2 {
        return Vec::new();
    }
    // The states along the plan: states[i] before step i + 1.
    let mut states = vec![task.init.clone()];
    for s in &plan {
        let mut next = states.last().expect("the start").clone();
        if let Some(r) = task.robot(s.robot) {
            rules::apply(task, &mut next, *r, s.action);
        }
        states.push(next);
    }
    let m = plan.len() / 2 + 1;
    let mut out = Vec::new();
    let mut add = |kind, trigger, happening| {
        let mut t = task.clone();
        t.events = vec![Event { trigger, happening }];
        if kind != "action_fails"
            && let Some(steps) = oracle(&t, 4 * plan.len() as u32 + 8, limits)
        {
            t.meta.gt_steps = Some(steps);
        }
        out.push(Variant { kind, task: t });
    };
    let at = |step: usize| Trigger::Step(step as u32);
    add(
        "robot_down",
        at(m),
        Happening::RobotDown {
            robot: lost(task, &plan[m - 1..], &states[m - 1], limits),
        },
    );
    if task.robots.len() >= 2 {
        add(
            "robot_up",
            at(3),
            Happening::RobotUp {
                robot: plan[0].robot,
                room: None,
            },
        );
    }
    let mid = &states[m - 1];
    let open: Vec<&GoalPredicate> = task
        .goal
        .iter()
        .filter(|p| !predicate_holds(mid, p))
        .collect();
    if let Some(p) = open.first() {
        let thing = p.subject;
        let grabable = task.node(thing).properties.contains(PropSet::GRABABLE);
        if let Some(target) = other_place(task, mid, thing, p.target, PropSet::SURFACES)
            && grabable
        {
            add(
                "object_moved",
                at(m),
                Happening::ObjectMoved {
                    thing,
                    relation: Relation::On,
                    target,
                },
            );
        }
        let prop = match p.relation {
            Relation::Inside => PropSet::CONTAINERS,
            _ => PropSet::SURFACES,
        };
        if let Some(target) = other_place(task, mid, thing, p.target, prop) {
            let new = GoalPredicate { target, ..**p };
            let instruction = format!(
                "{} Change of plan: {} goes {} {} instead of {}.",
                task.meta.instruction,
                task.node(thing).label(),
                if p.relation == Relation::Inside {
                    "into"
                } else {
                    "onto"
                },
                task.node(target).label(),
                task.node(p.target).label()
            );
            add(
                "goal_changed",
                at(m),
                Happening::GoalChanged {
                    add: vec![new],
                    remove: vec![**p],
                    instruction,
                },
            );
        }
    }
    if let Some((step, door)) = first_door(task, &plan, &states) {
        add(
            "blocked",
            at(step),
            Happening::Blocked {
                what: door,
                doors: vec![door],
                steps: Some(LOCKED_STEPS),
            },
        );
    }
    add(
        "action_fails",
        at(1),
        Happening::ActionFails {
            probability: FAIL_CHANCE,
            robot: None,
            steps: None,
        },
    );
    out
}

/// The robot to lose before the `rest` of the plan, from `s`: the first of its robots
/// without which the team still reaches the goal, so that the team must replan; else the
/// robot of its first step (the goal then goes out of reach, for a team to say so). A
/// plan without a robot is looked for in at most [`LOST_STATES`] states: proving that
/// none exists can take the whole state space.
fn lost(task: &Task, rest: &[Step], s: &State, limits: &Limits) -> Idx {
    let limits = Limits {
        max_states: limits.max_states.min(LOST_STATES),
        ..limits.clone()
    };
    let mut robots: Vec<Idx> = Vec::new();
    for step in rest {
        if !robots.contains(&step.robot) {
            robots.push(step.robot);
        }
    }
    robots
        .iter()
        .copied()
        .find(|&r| {
            let team: Vec<_> = task
                .robots
                .iter()
                .copied()
                .filter(|t| t.node != r)
                .collect();
            planner::search_from(task, s, &team, &task.goal, &limits)
                .plan
                .is_some()
        })
        .unwrap_or(rest[0].robot)
}

/// The steps of the oracle on `task` (docs/dynamic.md, "The reference"): the optimal
/// planner, replanning at each event, waiting while the goal is out of reach for now;
/// `None` when the goal goes out of reach for good, a search stops at `limits`, or
/// `most` steps pass.
fn oracle(task: &Task, most: u32, limits: &Limits) -> Option<u32> {
    let task = Arc::new(task.clone());
    let mut schedule = Schedule::new(Arc::clone(&task));
    let mut s = task.init.clone();
    let mut world = schedule.world();
    let mut plan: Option<(Vec<Step>, usize)> = None;
    for step in 1..=most {
        if !schedule.before_step(step, &mut s).is_empty() {
            world = schedule.world();
            plan = None;
        }
        if world.goal_satisfied(&s) {
            return Some(step - 1);
        }
        if plan.is_none() {
            let search = planner::search_from(&world, &s, &world.robots, &world.goal, limits);
            match search.plan {
                Some(p) => plan = Some((p, 0)),
                None if !search.truncated && schedule.may_help_later() => continue,
                None => return None,
            }
        }
        let (steps, at) = plan.as_mut().expect("a plan");
        let next = steps.get(*at)?;
        *at += 1;
        let robot = *world.robot(next.robot)?;
        rules::apply(&world, &mut s, robot, next.action);
    }
    None
}

/// A place with property `prop` for `thing` other than where it is and than `goal`:
/// not high, not a floor, not a robot's basket, in another room than the thing's when
/// there is one; the lowest id first.
fn other_place(task: &Task, s: &State, thing: Idx, goal: Idx, prop: PropSet) -> Option<Idx> {
    let here: Vec<Idx> = s
        .out(thing)
        .iter()
        .filter(|e| e.rel().is_location())
        .map(|e| e.to())
        .collect();
    let room_of = |n: Idx| rules::room_of(task, s, n);
    let thing_room = room_of(thing);
    let fits = |n: Idx| {
        let node = task.node(n);
        n != thing
            && n != goal
            && !here.contains(&n)
            && node.kind == NodeKind::Object
            && node.properties.contains(prop)
            && !node.properties.contains(PropSet::HIGH_HEIGHT)
            && !s.on_high_surface(n)
    };
    let candidates: Vec<Idx> = task.indices().filter(|&n| fits(n)).collect();
    candidates
        .iter()
        .copied()
        .find(|&n| room_of(n).is_some() && room_of(n) != thing_room)
        .or_else(|| candidates.first().copied())
}

/// The first step of `plan` that passes a door (a move into another room), and the door.
fn first_door(task: &Task, plan: &[Step], states: &[State]) -> Option<(usize, Idx)> {
    plan.iter().enumerate().find_map(|(i, s)| {
        let to = s.action.object;
        if s.action.verb != Verb::MoveTowards || task.node(to).kind != NodeKind::Room {
            return None;
        }
        let from = rules::room_of(task, &states[i], s.robot)?;
        let joins = |d: Idx, r: Idx| task.doors().iter().any(|&(x, y)| x == d && y == r);
        task.doors()
            .iter()
            .map(|&(d, _)| d)
            .find(|&d| joins(d, from) && joins(d, to))
            .map(|d| (i + 1, d))
    })
}
