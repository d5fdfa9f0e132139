//! The optimal planner: A* over the full state with an admissible, consistent
//! heuristic, one robot acting per step, with duplicate detection on the compact
//! [`State`]; the first plan found is a shortest one (`docs/planner.md`). Also the task
//! type (the fewest robot types with which the goal is reachable) and the reason a task
//! cannot be solved.

use std::hash::BuildHasher;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use rustc_hash::FxBuildHasher;
use smallvec::SmallVec;

use crate::action::{Action, Verb};
use crate::graph::{Idx, NodeKind, RobotKind, State};
use crate::rules;
use crate::tables::{Info, Tables};
use crate::task::{GoalPredicate, Robot, Task, predicate_holds};
use crate::vocab::{PropSet, Relation};

/// One step of a plan: which robot does what.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step {
    pub robot: Idx,
    pub action: Action,
}

/// Bounds on one search.
#[derive(Clone, Debug)]
pub struct Limits {
    /// Stop after this many distinct states; the answer is then "unknown", not "unsolvable".
    pub max_states: usize,
    /// Stop before the search's tables (the states seen, what is known of each, the
    /// duplicate table and the queue) would take more than this many bytes, as
    /// [`Search::memory`] estimates them; the answer is then "unknown" too. The states
    /// of a task take from a few hundred bytes to some kilobytes each (they grow with its
    /// nodes and edges), so this, not [`Limits::max_states`], is what bounds a search of
    /// a large task.
    pub max_memory: usize,
    /// Set from another thread to stop early (Ctrl-C in Python, say); the answer is then
    /// "unknown" too.
    pub cancel: Option<Arc<AtomicBool>>,
}

impl Limits {
    pub const DEFAULT_MAX_STATES: usize = 5_000_000;
    /// 1 GiB: room for a few million states of the released tasks (some 400 bytes
    /// each), and a bound a laptop can afford whatever the task.
    pub const DEFAULT_MAX_MEMORY: usize = 1 << 30;

    /// At most `max_states` states and the default memory bound.
    pub fn max_states(max_states: usize) -> Limits {
        Limits {
            max_states,
            max_memory: Limits::DEFAULT_MAX_MEMORY,
            cancel: None,
        }
    }

    pub fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

impl Default for Limits {
    fn default() -> Limits {
        Limits::max_states(Limits::DEFAULT_MAX_STATES)
    }
}

/// Why a search stopped before it could decide.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// It met [`Limits::max_states`] states.
    States,
    /// Its tables would have outgrown [`Limits::max_memory`].
    Memory,
    /// [`Limits::cancel`] was set.
    Cancelled,
    /// Every state it could hold was expanded, but some lie deeper than the 65,535
    /// steps its costs count.
    Depth,
}

/// The result of one search.
#[derive(Clone, Debug)]
pub struct Search {
    /// A shortest plan, if the goal is reachable.
    pub plan: Option<Vec<Step>>,
    /// States taken off the queue and expanded.
    pub states_expanded: usize,
    /// Whether the search stopped before it could finish (`stop` says why).
    pub truncated: bool,
    pub stop: Option<Stop>,
    /// Distinct states met (expanded or queued).
    pub states_seen: usize,
    /// The search's tables at the end, in bytes: an estimate from their sizes, the
    /// allocator's own bookkeeping included (about 16 bytes a state).
    pub memory: usize,
}

/// A* search for a shortest plan reaching `goal` from the task's initial state with only
/// `robots` acting; see [`search_from`].
pub fn search(task: &Task, robots: &[Robot], goal: &[GoalPredicate], limits: &Limits) -> Search {
    search_from(task, &task.init, robots, goal, limits)
}

impl Tables<Option<Step>> {
    /// The steps from the start to state `at`.
    fn plan_to(&self, at: usize) -> Vec<Step> {
        self.unwind(at).into_iter().flatten().collect()
    }

    fn result(&self, plan: Option<Vec<Step>>, expanded: usize, stop: Option<Stop>) -> Search {
        Search {
            plan,
            states_expanded: expanded,
            truncated: stop.is_some(),
            stop,
            states_seen: self.states.len(),
            memory: self.bytes(None),
        }
    }
}

/// A* search for a shortest plan reaching `goal` from `start` with only `robots` acting,
/// with the admissible and consistent heuristic [`lower_bound`] and duplicate detection
/// on the compact state. States are expanded in order of `f = g + h` (a bucket queue,
/// deepest first among equals). Each child is built in one reused buffer, hashed once,
/// and copied out only when it is new. The search stops, undecided, at
/// [`Limits::max_states`] states, before its tables outgrow [`Limits::max_memory`], or
/// when cancelled.
pub fn search_from(
    task: &Task,
    start: &State,
    robots: &[Robot],
    goal: &[GoalPredicate],
    limits: &Limits,
) -> Search {
    let holds = |s: &State| goal.iter().all(|p| predicate_holds(s, p));
    let mut t = Tables::new(start, lower_bound(task, start, goal), None);
    t.queue(0);
    if holds(start) {
        return t.result(Some(Vec::new()), 0, None);
    }
    let useful = Useful::new(task, start, goal);
    let mut child = start.clone();
    let mut expanded = 0usize;
    let mut too_deep = false;
    let mut f = 0usize;
    while f < t.buckets.len() {
        let Some(i) = t.buckets[f].pop() else {
            f += 1;
            continue;
        };
        let i = i as usize;
        let Info { g, h, closed, .. } = t.info[i];
        if closed || usize::from(g) + usize::from(h) != f {
            continue; // expanded already, or re-queued with a better cost
        }
        t.info[i].closed = true;
        expanded += 1;
        if expanded.is_multiple_of(1024) && limits.cancelled() {
            return t.result(None, expanded, Some(Stop::Cancelled));
        }
        if holds(&t.states[i]) {
            return t.result(Some(t.plan_to(i)), expanded, None);
        }
        let Some(gc) = g.checked_add(1) else {
            too_deep = true;
            continue;
        };
        for (&robot, actions) in robots
            .iter()
            .zip(&rules::team_actions(task, &t.states[i], robots))
        {
            for &action in actions.iter().filter(|a| useful.allows(task, a)) {
                child.clone_from(&t.states[i]);
                rules::apply(task, &mut child, robot, action);
                let step = Some(Step {
                    robot: robot.node,
                    action,
                });
                let hash = FxBuildHasher.hash_one(&child);
                let c = match t.find(hash, &child) {
                    Some(j) => {
                        let seen = &mut t.info[j];
                        if seen.closed || seen.g <= gc {
                            continue;
                        }
                        (seen.g, seen.parent, seen.step) = (gc, i as u32, step);
                        t.queue(j as u32);
                        j
                    }
                    None => {
                        let kept = child.clone();
                        if t.bytes(Some(kept.heap_bytes())) > limits.max_memory {
                            return t.result(None, expanded, Some(Stop::Memory));
                        }
                        let h = lower_bound(task, &kept, goal);
                        t.insert(kept, hash, i as u32, step, gc, h);
                        t.queue(t.states.len() as u32 - 1);
                        t.states.len() - 1
                    }
                };
                // A goal at cost f cannot be beaten: every open state has f' >= f.
                if usize::from(gc) <= f && t.info[c].h == 0 && holds(&t.states[c]) {
                    return t.result(Some(t.plan_to(c)), expanded, None);
                }
                if t.states.len() >= limits.max_states {
                    return t.result(None, expanded, Some(Stop::States));
                }
            }
        }
    }
    t.result(None, expanded, too_deep.then_some(Stop::Depth))
}

/// The actions worth searching: every goal is a set of `ON`/`INSIDE` edges, so some
/// shortest plan never closes anything, grabs only goal subjects and targets and what
/// holds them, and opens only doors and containers among those (`docs/planner.md`,
/// "Pruning").
pub(crate) struct Useful {
    /// Goal subjects and targets, and what holds them at the start, transitively.
    things: Vec<bool>,
}

impl Useful {
    pub fn new(task: &Task, start: &State, goal: &[GoalPredicate]) -> Useful {
        let mut things = vec![false; task.nodes.len()];
        let mut todo: Vec<Idx> = goal.iter().flat_map(|p| [p.subject, p.target]).collect();
        while let Some(n) = todo.pop() {
            if !std::mem::replace(&mut things[n.get()], true) {
                todo.extend(start.targets(n, Relation::On));
                todo.extend(start.targets(n, Relation::Inside));
            }
        }
        Useful { things }
    }

    pub fn allows(&self, task: &Task, a: &Action) -> bool {
        match a.verb {
            Verb::Close => false,
            Verb::Open => task.node(a.object).kind == NodeKind::Door || self.things[a.object.get()],
            Verb::Grab => self.things[a.object.get()],
            _ => true,
        }
    }
}

/// A lower bound on the steps still needed to reach `goal` from `s`, admissible and
/// consistent (one action lowers it by at most one). Each goal subject not yet in place
/// needs actions of its own: an object a grab (unless held) and a put; the quadrotor
/// (and its basket, which only moves with it) a take-off (unless flying), a move
/// (unless above the target) and a landing; the robot dog a move. Per subject the
/// largest need counts, and the needs of different subjects add up.
pub fn lower_bound(task: &Task, s: &State, goal: &[GoalPredicate]) -> u16 {
    needs(task, s, goal).0
}

/// The needs of [`lower_bound`]: their sum, and the largest need of one subject (its
/// actions follow one another, whoever does them).
pub(crate) fn needs(task: &Task, s: &State, goal: &[GoalPredicate]) -> (u16, u16) {
    // (subject whose actions are counted, need); a basket counts as its quadrotor.
    let mut needs: SmallVec<[(Idx, u16); 8]> = SmallVec::new();
    for p in goal
        .iter()
        .filter(|p| p.count == 1 && !predicate_holds(s, p))
    {
        let x = p.subject;
        let (who, need) = match task.node(x).kind {
            NodeKind::Object => (
                x,
                if s.sources(Relation::Hold, x).next().is_some() {
                    1
                } else {
                    2
                },
            ),
            NodeKind::Robot(RobotKind::RobotDog) => (x, 1),
            NodeKind::Robot(RobotKind::Quadrotor) => (x, flight_need(s, x, p)),
            NodeKind::Tool => match task
                .robots
                .iter()
                .find(|r| task.basket_of(r.node) == Some(x))
            {
                Some(q) => (q.node, flight_need(s, q.node, p)),
                None => continue,
            },
            _ => continue,
        };
        match needs.iter_mut().find(|(w, _)| *w == who) {
            Some((_, n)) => *n = (*n).max(need),
            None => needs.push((who, need)),
        }
    }
    let sum = needs.iter().map(|(_, n)| n).sum();
    let most = needs.iter().map(|(_, n)| *n).max().unwrap_or(0);
    (sum, most)
}

/// Actions quadrotor `q` needs before predicate `p` (about it or its basket) holds.
fn flight_need(s: &State, q: Idx, p: &GoalPredicate) -> u16 {
    let flying = s.states(q).contains(crate::StateSet::FLYING);
    match p.relation {
        // Into another room: one move, after a take-off.
        Relation::Inside => {
            if flying {
                1
            } else {
                2
            }
        }
        _ if flying && s.has(crate::Edge::new(q, Relation::Above, p.target)) => 1,
        _ if flying => 2,
        _ => 3,
    }
}

/// Mono, dual or trio: how many robot types the goal needs at the fewest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TaskType {
    Mono,
    Dual,
    Trio,
}

impl TaskType {
    pub fn name(self) -> &'static str {
        match self {
            TaskType::Mono => "mono",
            TaskType::Dual => "dual",
            TaskType::Trio => "trio",
        }
    }
}

/// Everything the planner says about a task.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// A shortest plan with the whole team, if one exists.
    pub plan: Option<Vec<Step>>,
    pub task_type: Option<TaskType>,
    /// Why there is no plan (None when there is one).
    pub reason: Option<String>,
    /// Why the search with the whole team stopped before it could decide whether the
    /// goal is reachable (None when it decided).
    pub stop: Option<Stop>,
    /// States expanded by the search with the whole team.
    pub states_expanded: usize,
    pub elapsed: Duration,
}

impl Analysis {
    /// The analysis as one line of `coherent plan --json`: `scene`, `task_id`,
    /// `gt_steps`, `optimal_steps`, `solvable`, `reason`, `task_type`, `plan` (list of
    /// `{"robot", "action"}`), `states_expanded`, `elapsed_ms`.
    pub fn to_json(&self, task: &Task) -> serde_json::Value {
        let plan: Vec<serde_json::Value> = self
            .plan
            .iter()
            .flatten()
            .map(|s| serde_json::json!({"robot": task.id(s.robot).0, "action": s.action.render(task)}))
            .collect();
        serde_json::json!({
            "scene": task.meta.scene,
            "task_id": task.meta.task_id,
            "gt_steps": task.meta.gt_steps,
            "optimal_steps": self.plan.as_ref().map(Vec::len),
            "solvable": self.plan.is_some(),
            "reason": self.reason,
            "task_type": self.task_type.map(TaskType::name),
            "plan": plan,
            "states_expanded": self.states_expanded,
            "elapsed_ms": (self.elapsed.as_secs_f64() * 1e6).round() / 1e3,
        })
    }
}

/// Plans `task` optimally, finds its type, or says why it cannot be solved.
pub fn analyse(task: &Task, limits: &Limits) -> Analysis {
    let start = Instant::now();
    let obstacles: Vec<String> = task
        .goal
        .iter()
        .filter(|p| !predicate_holds(&task.init, p))
        .filter_map(|p| {
            static_obstacle(task, p).map(|why| format!("{}: {why}", task.predicate_label(p)))
        })
        .collect();
    if !obstacles.is_empty() {
        return Analysis {
            plan: None,
            task_type: None,
            reason: Some(obstacles.join("; ")),
            stop: None,
            states_expanded: 0,
            elapsed: start.elapsed(),
        };
    }
    let full = search(task, &task.robots, &task.goal, limits);
    let (task_type, reason) = match &full.plan {
        Some(plan) => (task_type(task, plan, limits), None),
        None => (None, Some(why_unsolvable(task, &full, limits))),
    };
    Analysis {
        plan: full.plan,
        task_type,
        reason,
        stop: full.stop,
        states_expanded: full.states_expanded,
        elapsed: start.elapsed(),
    }
}

/// The fewest robot types with which the goal is reachable; none when the goal already
/// holds at the start. The types used by `plan` (a shortest plan of the whole team)
/// bound the answer, so only smaller teams are searched.
fn task_type(task: &Task, plan: &[Step], limits: &Limits) -> Option<TaskType> {
    const TYPES: [TaskType; 3] = [TaskType::Mono, TaskType::Dual, TaskType::Trio];
    let mut used: Vec<RobotKind> = plan
        .iter()
        .filter_map(|s| task.robot(s.robot).map(|r| r.kind))
        .collect();
    used.sort();
    used.dedup();
    if used.is_empty() {
        return None;
    }
    let kinds: Vec<RobotKind> = RobotKind::ALL
        .into_iter()
        .filter(|k| task.robots.iter().any(|r| r.kind == *k))
        .collect();
    for size in 1..used.len() {
        for subset in subsets(&kinds, size) {
            // A sound over-approximation rules most small teams out without a search.
            if !crate::relaxed::may_reach(task, &subset, &task.goal) {
                continue;
            }
            let team: Vec<Robot> = task
                .robots
                .iter()
                .copied()
                .filter(|r| subset.contains(&r.kind))
                .collect();
            let found = search(task, &team, &task.goal, limits);
            if found.plan.is_some() {
                return Some(TYPES[size - 1]);
            }
            // A smaller team might still succeed beyond the limit: undecided.
            if found.truncated {
                return None;
            }
        }
    }
    Some(TYPES[used.len() - 1])
}

fn subsets(kinds: &[RobotKind], size: usize) -> Vec<Vec<RobotKind>> {
    (0u32..1 << kinds.len())
        .filter(|m| m.count_ones() as usize == size)
        .map(|m| {
            kinds
                .iter()
                .enumerate()
                .filter(|(i, _)| m >> i & 1 == 1)
                .map(|(_, k)| *k)
                .collect()
        })
        .collect()
}

/// Why an exhaustive search found no plan: which predicates cannot be reached even
/// alone, or that they cannot be reached together.
fn why_unsolvable(task: &Task, full: &Search, limits: &Limits) -> String {
    match full.stop {
        Some(Stop::Cancelled) => {
            return "planning was cancelled before the search finished".to_owned();
        }
        Some(Stop::States) => {
            return format!(
                "search stopped at the limit of {} states without reaching the goal; raise the limit to decide",
                limits.max_states
            );
        }
        Some(Stop::Memory) => {
            return format!(
                "search stopped at the memory limit of {} ({} states) without reaching the goal; raise the limit to decide",
                mebibytes(limits.max_memory),
                full.states_seen
            );
        }
        Some(Stop::Depth) => {
            return format!(
                "no plan of at most {} steps reaches the goal, and the search counts no further",
                u16::MAX
            );
        }
        None => {}
    }
    let alone: Vec<String> = task
        .goal
        .iter()
        .filter(|p| {
            search(task, &task.robots, std::slice::from_ref(p), limits)
                .plan
                .is_none()
        })
        .map(|p| task.predicate_label(p))
        .collect();
    if alone.is_empty() {
        format!(
            "each goal predicate is reachable alone but not all together (searched all {} reachable states)",
            full.states_expanded
        )
    } else {
        format!(
            "no sequence of actions makes {} hold (searched all reachable states)",
            alone.join(" and ")
        )
    }
}

/// `bytes` in MiB, as the command line's `--max-memory` takes them.
fn mebibytes(bytes: usize) -> String {
    const MIB: usize = 1 << 20;
    if bytes.is_multiple_of(MIB) {
        format!("{} MiB", bytes / MIB)
    } else {
        format!("{:.1} MiB", bytes as f64 / MIB as f64)
    }
}

/// A reason visible without search why predicate `p` can never come to hold.
pub fn static_obstacle(task: &Task, p: &GoalPredicate) -> Option<String> {
    let (x, y) = (task.node(p.subject), task.node(p.target));
    let has = |n: Idx, prop: PropSet| task.node(n).properties.contains(prop);
    match p.count {
        0 => return None,
        1 => {}
        n => {
            return Some(format!(
                "asks for {n} such edges, but edges form a set: at most one can exist"
            ));
        }
    }
    if p.subject == p.target {
        return Some(format!(
            "{} cannot be {} itself",
            x.label(),
            p.relation.name()
        ));
    }
    let never_moves = |what: &str| Some(format!("{} is {what} and never moves", x.label()));
    match x.kind {
        NodeKind::Room | NodeKind::Floor | NodeKind::Door => never_moves("part of the building"),
        NodeKind::Robot(RobotKind::RobotArm) => never_moves("a fixed robot arm"),
        NodeKind::Robot(RobotKind::RobotDog) => match (p.relation, y.kind) {
            (Relation::On, NodeKind::Floor) | (Relation::Inside, NodeKind::Room) => None,
            _ => Some(format!(
                "a robot dog only ever stands ON a floor and INSIDE a room, and {} is neither target",
                y.label()
            )),
        },
        NodeKind::Robot(RobotKind::Quadrotor) | NodeKind::Tool => match p.relation {
            Relation::On if has(p.target, PropSet::LANDABLE) => None,
            Relation::On => Some(format!(
                "{} is not LANDABLE, and the quadrotor and its basket only come to rest on landable surfaces",
                y.label()
            )),
            _ => Some(format!(
                "{} never goes INSIDE anything but a room",
                x.label()
            )),
        },
        NodeKind::Object => {
            if !has(p.subject, PropSet::GRABABLE) {
                return Some(format!(
                    "{} is not GRABABLE, so no robot can move it",
                    x.label()
                ));
            }
            match p.relation {
                Relation::Inside if !has(p.target, PropSet::CONTAINERS) => Some(format!(
                    "{} has no CONTAINERS property, so nothing can be put inside it",
                    y.label()
                )),
                Relation::Inside
                    if !task.init.states(p.target).is_open()
                        && !task.init.states(p.target).contains(crate::StateSet::CLOSED) =>
                {
                    Some(format!(
                        "{} is neither open nor closed, so it can never be opened",
                        y.label()
                    ))
                }
                Relation::On if !has(p.target, PropSet::SURFACES) => Some(format!(
                    "{} is not a surface (no SURFACES property)",
                    y.label()
                )),
                _ => None,
            }
        }
    }
}

/// Replays `plan` through the rules from the initial state: the state after each
/// step, or the index and reason of the first step that is not allowed.
pub fn replay(task: &Task, plan: &[Step]) -> Result<State, (usize, String)> {
    let mut s = task.init.clone();
    for (i, step) in plan.iter().enumerate() {
        let robot = task
            .robot(step.robot)
            .copied()
            .ok_or((i, "not a robot".to_owned()))?;
        let text = step.action.render(task);
        let action =
            crate::feasibility::check(task, &s, robot, &text).map_err(|e| (i, e.message))?;
        rules::apply(task, &mut s, robot, action);
    }
    Ok(s)
}
