//! Makespan-optimal plans: the fewest joint steps (docs/planner.md, "Parallel plans").
//!
//! A joint step lets every robot act at once, each at most once, when no two of the
//! actions interfere ([`crate::joint`]). The search is A* over the same states as the
//! sequential planner, one joint step per edge; a state's successors are enumerated
//! robot by robot (operator decomposition, Standley 2010): the first robot's choices
//! (an action, or none), then the second's among the actions that do not interfere with
//! the first's, and so on, with the state after the actions chosen so far at each level.
//! A partial step is dropped as soon as no completion of it can beat the best plan
//! known. The heuristic is admissible and consistent: one joint step of `n` robots does
//! at most `n` of the actions [`crate::planner::lower_bound`] counts, at most one of the
//! actions one goal subject still needs (they follow one another), and at most one link
//! of a goal thing's chain across robots (`chain.rs`: grabs, puts, flights, walks).
//!
//! Among the plans of the fewest joint steps it finds one of the fewest actions: costs
//! and `f` are compared joint steps first, then actions (lexicographic A*), the actions'
//! heuristic being the sequential planner's, which one action lowers by at most one. A
//! plan is never longer in joint steps for it, and no robot acts where it need not (a
//! quadrotor landing and taking off again while it waits).
//!
//! The search starts from an upper bound, the sequential optimum scheduled as soon as
//! possible ([`schedule`]), and looks only for cheaper plans; when it stops at a limit
//! it still has that plan, and the frontier's `f` is a lower bound. A limit met only
//! while it looked among the plans of the fewest joint steps for fewer actions leaves
//! the joint steps proven.

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use smallvec::SmallVec;

use crate::action::Action;
use crate::chain::Chains;
use crate::footprint::{self, Footprint};
use crate::graph::State;
use crate::planner::{self, Limits, Step, Stop, Useful};
use crate::rules::{self, Contents, View};
use crate::tables::Tables;
use crate::task::{GoalPredicate, Robot, Task, predicate_holds};

/// One joint step: the actions of the robots that act, in team order.
pub type JointStep = Vec<Step>;

/// The result of a makespan search.
#[derive(Clone, Debug)]
pub struct Makespan {
    /// The best plan known, one joint step at a time; `None` when the goal is out of
    /// reach, or no plan was found before a limit.
    pub plan: Option<Vec<JointStep>>,
    /// Whether no plan has fewer joint steps (or, without a plan, none exists).
    pub proven: bool,
    /// No plan has fewer joint steps than this: the plan's length when proven.
    pub lower: usize,
    /// The limit that stopped the search, if one did.
    pub stop: Option<Stop>,
    pub states_expanded: usize,
    /// Distinct states met (expanded or queued).
    pub states_seen: usize,
    /// The search's tables at the end, in bytes, as for the sequential search.
    pub memory: usize,
    pub elapsed: Duration,
}

impl Makespan {
    /// The number of joint steps of the plan found.
    pub fn makespan(&self) -> Option<usize> {
        self.plan.as_ref().map(Vec::len)
    }
}

/// The fewest joint steps reaching `goal` from the task's initial state with `robots`;
/// see [`search_with`].
pub fn search(task: &Task, robots: &[Robot], goal: &[GoalPredicate], limits: &Limits) -> Makespan {
    let sequential = planner::search(task, robots, goal, limits);
    search_with(
        task,
        &task.init,
        robots,
        goal,
        sequential.plan.as_deref(),
        limits,
    )
}

/// The fewest joint steps reaching `goal` from `start` with `robots` acting, A* from
/// the upper bound that `sequential` (a plan from `start`, the shortest one for the
/// best bound) gives when scheduled. Stops, with the best plan known and a lower
/// bound, at the limits of [`Limits`].
pub fn search_with(
    task: &Task,
    start: &State,
    robots: &[Robot],
    goal: &[GoalPredicate],
    sequential: Option<&[Step]>,
    limits: &Limits,
) -> Makespan {
    let clock = Instant::now();
    let mut search = Search::new(task, start, robots, goal, sequential, limits);
    let stop = search.run();
    search.finish(stop, clock.elapsed())
}

/// `sequential`, a plan from `start`, as joint steps: each action joins the earliest
/// step at which it is offered, interferes with no other action of that step, and the
/// rest of the plan still plays after it and reaches `goal`. Never longer than the plan.
pub fn schedule(
    task: &Task,
    start: &State,
    sequential: &[Step],
    goal: &[GoalPredicate],
) -> Vec<JointStep> {
    schedule_within(task, start, sequential, goal, &Limits::default())
}

/// [`schedule`], which replays the rest of the plan for every action it tries to move
/// (its work grows with the cube of the plan's length): once `limits` is cancelled, the
/// actions not yet scheduled follow one a step, which plays as well.
fn schedule_within(
    task: &Task,
    start: &State,
    sequential: &[Step],
    goal: &[GoalPredicate],
    limits: &Limits,
) -> Vec<JointStep> {
    let mut s = start.clone();
    let mut rest: Vec<Step> = sequential.to_vec();
    let mut steps = Vec::new();
    while !rest.is_empty() {
        let mut chosen: Vec<usize> = Vec::new();
        let mut prints: Vec<Footprint> = Vec::new();
        for j in 0..rest.len() {
            // What was chosen so far is a step that plays; with none, the rest follows.
            if limits.cancelled() {
                break;
            }
            let Some(&robot) = task.robot(rest[j].robot) else {
                continue;
            };
            let a = rest[j].action;
            if chosen.iter().any(|&c| rest[c].robot == robot.node)
                || !rules::actions(task, &s, robot).contains(&a)
            {
                continue;
            }
            let print = Footprint::of(task, &s, robot, a);
            if prints.iter().any(|p| p.conflict(&print).is_some()) {
                continue;
            }
            chosen.push(j);
            if plays(task, &s, &rest, &chosen, goal) {
                prints.push(print);
            } else {
                chosen.pop();
            }
        }
        if chosen.is_empty() {
            // The plan does not play from `s`, or the search was cancelled: keep its
            // order, one action a step.
            steps.extend(rest.drain(..).map(|st| vec![st]));
            break;
        }
        let mut step: JointStep = chosen.iter().map(|&j| rest[j]).collect();
        // In team order, as the search gives its steps (the order is free: they commute).
        step.sort_by_key(|st| task.robots.iter().position(|r| r.node == st.robot));
        for st in &step {
            if let Some(&robot) = task.robot(st.robot) {
                rules::apply(task, &mut s, robot, st.action);
            }
        }
        let mut k = 0;
        rest.retain(|_| {
            k += 1;
            !chosen.contains(&(k - 1))
        });
        steps.push(step);
    }
    steps
}

/// Whether, from `s`, the joint step `rest[chosen]` and then the rest of `rest` in its
/// order are each offered at their turn and end with `goal` holding.
fn plays(task: &Task, s: &State, rest: &[Step], chosen: &[usize], goal: &[GoalPredicate]) -> bool {
    let mut t = s.clone();
    let order = chosen
        .iter()
        .copied()
        .chain((0..rest.len()).filter(|j| !chosen.contains(j)));
    for j in order {
        let Some(&robot) = task.robot(rest[j].robot) else {
            return false;
        };
        if !rules::actions(task, &t, robot).contains(&rest[j].action) {
            return false;
        }
        rules::apply(task, &mut t, robot, rest[j].action);
    }
    goal.iter().all(|p| predicate_holds(&t, p))
}

/// A lower bound on the joint steps to `goal` with a team of `robots` acting from a start
/// state, admissible and consistent (one joint step lowers it by at most one): the
/// search's heuristic.
#[derive(Debug)]
pub struct LowerBound<'a> {
    task: &'a Task,
    goal: &'a [GoalPredicate],
    robots: u16,
    chains: Chains,
}

impl<'a> LowerBound<'a> {
    /// The bound for states reachable from `start` when `robots` act.
    pub fn new(
        task: &'a Task,
        start: &State,
        robots: &[Robot],
        goal: &'a [GoalPredicate],
    ) -> LowerBound<'a> {
        LowerBound {
            task,
            goal,
            robots: robots.len() as u16,
            chains: Chains::new(task, start, robots, goal),
        }
    }

    /// The bound at `s`, a state reachable from the start.
    pub fn of(&self, s: &State) -> u16 {
        bound(self.needs(s), self.robots, 0)
    }

    /// What `s` still needs: [`planner::needs`], and the longest chain of actions one
    /// goal thing needs ([`Chains`]).
    fn needs(&self, s: &State) -> Needs {
        let (sum, most) = planner::needs(self.task, s, self.goal);
        (sum, most.max(self.chains.bound(self.task, s)))
    }
}

/// The actions [`planner::lower_bound`] counts, and the longest chain of actions that
/// follow one another.
type Needs = (u16, u16);

/// A lower bound on the joint steps from a state that needs `needs`, with `robots`
/// robots, when `left` of them may still act in the current step: the actions of
/// [`planner::lower_bound`] less the `left` these robots can do, `robots` a step; and the
/// longest chain, less one when someone may still act.
fn bound(needs: Needs, robots: u16, left: u16) -> u16 {
    let (sum, most) = needs;
    let chain = if left > 0 {
        most.saturating_sub(1)
    } else {
        most
    };
    sum.saturating_sub(left).div_ceil(robots.max(1)).max(chain)
}

/// Why an expansion ends early: a limit, or the best plan is proven optimal.
enum Halt {
    Limit(Stop),
    Proven,
}

/// Where one joint step of a stored plan lies in [`Search::arena`].
#[derive(Clone, Copy)]
struct Span {
    at: u32,
    len: u32,
}

/// A cost or an estimate, compared joint steps first, then actions.
type Cost = (usize, usize);

/// The open states by `f` in joint steps, then by `f` in actions: `layers[steps][actions]`
/// holds the indices of the states queued at that cost, popped from the lowest.
#[derive(Default)]
struct Open {
    layers: Vec<Vec<Vec<u32>>>,
    /// Every bucket below it is empty.
    at: Cost,
    bytes: usize,
}

impl Open {
    fn push(&mut self, f: Cost, i: u32) {
        let (steps, actions) = f;
        if self.layers.len() <= steps {
            self.bytes += (steps + 1 - self.layers.len()) * size_of::<Vec<Vec<u32>>>();
            self.layers.resize_with(steps + 1, Vec::new);
        }
        let layer = &mut self.layers[steps];
        if layer.len() <= actions {
            self.bytes += (actions + 1 - layer.len()) * size_of::<Vec<u32>>();
            layer.resize_with(actions + 1, Vec::new);
        }
        let bucket = &mut layer[actions];
        let before = bucket.capacity();
        bucket.push(i);
        self.bytes += (bucket.capacity() - before) * size_of::<u32>();
        // A consistent heuristic never queues below the state expanded; kept safe anyway.
        self.at = self.at.min(f);
    }

    /// A state of the lowest cost queued, with that cost.
    fn pop(&mut self) -> Option<(u32, Cost)> {
        loop {
            let (steps, actions) = self.at;
            let layer = self.layers.get_mut(steps)?;
            match layer.get_mut(actions) {
                None => self.at = (steps + 1, 0),
                Some(bucket) => match bucket.pop() {
                    Some(i) => return Some((i, self.at)),
                    None => self.at.1 += 1,
                },
            }
        }
    }
}

/// One search: its tables, the best plan known, its counters.
struct Search<'a> {
    task: &'a Task,
    robots: &'a [Robot],
    goal: &'a [GoalPredicate],
    limits: &'a Limits,
    useful: Useful,
    bound: LowerBound<'a>,
    /// The states; `g` and `h` of their info count joint steps.
    t: Tables<Span>,
    /// Per state as in `t`: the actions of the best path known to it, and the fewest
    /// actions still needed ([`planner::lower_bound`]).
    actions: Vec<(u16, u16)>,
    open: Open,
    /// The actions of every joint step stored, one after the other.
    arena: Vec<Step>,
    /// The best plan known, and its cost (`usize::MAX` each while there is none).
    best: Option<Vec<JointStep>>,
    best_cost: Cost,
    expanded: usize,
    /// The joint steps of the lowest `f` still open when the search stopped.
    frontier: usize,
}

impl<'a> Search<'a> {
    fn new(
        task: &'a Task,
        start: &State,
        robots: &'a [Robot],
        goal: &'a [GoalPredicate],
        sequential: Option<&[Step]>,
        limits: &'a Limits,
    ) -> Search<'a> {
        let best = sequential.map(|plan| schedule_within(task, start, plan, goal, limits));
        let best_cost = best.as_ref().map_or((usize::MAX, usize::MAX), |plan| {
            (plan.len(), plan.iter().map(Vec::len).sum())
        });
        let lower = LowerBound::new(task, start, robots, goal);
        let needs = lower.needs(start);
        let h = bound(needs, robots.len() as u16, 0);
        let mut open = Open::default();
        open.push((usize::from(h), usize::from(needs.0)), 0);
        Search {
            task,
            robots,
            goal,
            limits,
            useful: Useful::new(task, start, goal),
            bound: lower,
            t: Tables::new(start, h, Span { at: 0, len: 0 }),
            actions: vec![(0, needs.0)],
            open,
            arena: Vec::new(),
            best,
            best_cost,
            expanded: 0,
            frontier: usize::from(h),
        }
    }

    fn holds(&self, s: &State) -> bool {
        self.goal.iter().all(|p| predicate_holds(s, p))
    }

    /// The plan to stored state `at`.
    fn plan_to(&self, at: usize) -> Vec<JointStep> {
        self.t
            .unwind(at)
            .into_iter()
            .map(|span| self.arena[span.at as usize..(span.at + span.len) as usize].to_vec())
            .collect()
    }

    /// State `i`'s `f`: joint steps, then actions.
    fn f(&self, i: usize) -> Cost {
        let (info, (g, h)) = (self.t.info[i], self.actions[i]);
        (
            usize::from(info.g) + usize::from(info.h),
            usize::from(g) + usize::from(h),
        )
    }

    /// A* in order of `f` (joint steps, then actions), below the best plan's cost;
    /// `Break` with the limit that stopped it, or `Continue` when it decided.
    fn run(&mut self) -> ControlFlow<Stop> {
        if self.holds(&self.t.states[0]) {
            self.best = Some(Vec::new());
            self.best_cost = (0, 0);
            return ControlFlow::Continue(());
        }
        // The schedule of the setup may have been cut short by it.
        if self.limits.cancelled() {
            return ControlFlow::Break(Stop::Cancelled);
        }
        while let Some((i, f)) = self.open.pop() {
            if f >= self.best_cost {
                break;
            }
            self.frontier = f.0;
            let i = i as usize;
            let info = self.t.info[i];
            if info.closed || self.f(i) != f {
                continue;
            }
            self.t.info[i].closed = true;
            self.expanded += 1;
            if self.expanded.is_multiple_of(256) && self.limits.cancelled() {
                return ControlFlow::Break(Stop::Cancelled);
            }
            if self.holds(&self.t.states[i]) {
                self.best = Some(self.plan_to(i));
                self.best_cost = (usize::from(info.g), usize::from(self.actions[i].0));
                return ControlFlow::Continue(());
            }
            let Some(gc) = info.g.checked_add(1) else {
                return ControlFlow::Break(Stop::Depth);
            };
            match self.expand(i, gc, f) {
                ControlFlow::Break(Halt::Limit(stop)) => return ControlFlow::Break(stop),
                ControlFlow::Break(Halt::Proven) => return ControlFlow::Continue(()),
                ControlFlow::Continue(_) => {}
            }
        }
        ControlFlow::Continue(())
    }

    /// Every joint step from state `i` whose result may still beat the best plan.
    fn expand(&mut self, i: usize, gc: u16, f: Cost) -> ControlFlow<Halt, Cost> {
        let s = self.t.states[i].clone();
        let contents = Contents::new(self.task, &s);
        let views: Vec<View<'_>> = self
            .robots
            .iter()
            .map(|&robot| View::with(self.task, &s, robot, &contents))
            .collect();
        let choices = Choices::new(self.task, &views, &self.useful);
        let needs = self.bound.needs(&s);
        let levels = vec![(s.clone(), needs); self.robots.len() + 1];
        let held = choices.bytes + levels.iter().map(|(l, _)| l.heap_bytes()).sum::<usize>();
        let mut walk = Walk {
            task: self.task,
            robots: self.robots,
            choices,
            levels,
            chosen: SmallVec::new(),
            parent: (i, gc, f),
            cost: (usize::from(gc), usize::from(self.actions[i].0)),
            limit: self.best_cost,
            held,
            tried: 0,
        };
        walk.level(0, self)
    }

    /// Records the state a joint step leads to (with its [`LowerBound::needs`]), unless it
    /// cannot beat the best plan or is known at no greater cost; `f` is the parent's.
    /// Returns the cost a plan must now beat.
    /// `held`: the bytes the expansion holds besides the tables (its states and
    /// footprints), which count against the memory limit too.
    fn child(
        &mut self,
        (parent, gc, f): (usize, u16, Cost),
        (child, needs): (&State, Needs),
        step: &[Step],
        held: usize,
    ) -> ControlFlow<Halt, Cost> {
        let h = bound(needs, self.robots.len() as u16, 0);
        let ga = usize::from(self.actions[parent].0) + step.len();
        if (usize::from(gc) + usize::from(h), ga + usize::from(needs.0)) >= self.best_cost {
            return ControlFlow::Continue(self.best_cost);
        }
        let Ok(ga16) = u16::try_from(ga) else {
            return ControlFlow::Break(Halt::Limit(Stop::Depth));
        };
        let span = Span {
            at: self.arena.len() as u32,
            len: step.len() as u32,
        };
        let hash = std::hash::BuildHasher::hash_one(&rustc_hash::FxBuildHasher, child);
        let c = match self.t.find(hash, child) {
            Some(j) => {
                let seen = &mut self.t.info[j];
                if seen.closed || (seen.g, self.actions[j].0) <= (gc, ga16) {
                    return ControlFlow::Continue(self.best_cost);
                }
                (seen.g, seen.parent, seen.step) = (gc, parent as u32, span);
                self.actions[j].0 = ga16;
                j
            }
            None => {
                let kept = child.clone();
                if self.bytes(Some(kept.heap_bytes()), step.len()) + held > self.limits.max_memory {
                    return ControlFlow::Break(Halt::Limit(Stop::Memory));
                }
                self.t.insert(kept, hash, parent as u32, span, gc, h);
                self.actions.push((ga16, needs.0));
                self.t.states.len() - 1
            }
        };
        self.arena.extend_from_slice(step);
        self.open.push(self.f(c), c as u32);
        if h == 0 && self.holds(child) {
            self.best = Some(self.plan_to(c));
            self.best_cost = (usize::from(gc), ga);
        }
        // A goal at cost f cannot be beaten: every open state has f' >= f.
        if self.best_cost <= f {
            return ControlFlow::Break(Halt::Proven);
        }
        if self.t.states.len() >= self.limits.max_states {
            return ControlFlow::Break(Halt::Limit(Stop::States));
        }
        ControlFlow::Continue(self.best_cost)
    }

    /// The search's bytes, as [`Tables::bytes`] counts them (with `more`, after adding a
    /// state whose own block takes `more` bytes, reached by a step of `actions` actions).
    fn bytes(&self, more: Option<usize>, actions: usize) -> usize {
        let grown = |len: usize, cap: usize| if len == cap { cap.max(4) * 2 } else { cap };
        let (arena, per_state) = match more {
            Some(_) => (
                (self.arena.capacity() + actions) * size_of::<Step>(),
                grown(self.actions.len(), self.actions.capacity()),
            ),
            None => (
                self.arena.capacity() * size_of::<Step>(),
                self.actions.capacity(),
            ),
        };
        self.t.bytes(more) + arena + per_state * size_of::<(u16, u16)>() + self.open.bytes
    }

    fn finish(self, stop: ControlFlow<Stop>, elapsed: Duration) -> Makespan {
        let stop = match stop {
            ControlFlow::Break(s) => Some(s),
            ControlFlow::Continue(()) => None,
        };
        let lower = match (stop, self.best.as_ref()) {
            (None, Some(plan)) => plan.len(),
            _ => self.frontier.min(self.best_cost.0),
        };
        // A limit met while the search looked among the plans of the fewest joint steps
        // for one of fewer actions leaves the joint steps proven.
        let proven = stop.is_none() || (self.best.is_some() && lower == self.best_cost.0);
        Makespan {
            proven,
            lower,
            stop,
            states_expanded: self.expanded,
            states_seen: self.t.states.len(),
            memory: self.bytes(None, 0),
            plan: self.best,
            elapsed,
        }
    }
}

/// How often, in joint steps tried, an expansion looks whether the search was cancelled:
/// one state of a large scene may have hundreds of thousands of them.
const CANCEL_EVERY: usize = 1024;

/// Each robot's actions worth trying in the state expanded, and their footprints. A
/// footprint is taken when the walk first compares its action with another's: many
/// steps are one robot's alone and need none, and a footprint can be as large as the
/// scene (an action on a thing deep in containers reads every edge up to its room), so
/// taking them all first would be work and memory that no limit sees before the first
/// state is stored.
struct Choices<'v> {
    views: &'v [View<'v>],
    actions: Vec<Vec<Action>>,
    prints: Vec<Vec<Option<Footprint>>>,
    /// Where each robot's actions start in one numbering of all of them, and how many
    /// they are.
    first: Vec<usize>,
    all: usize,
    /// Whether two actions meet, by their numbers (`a * all + b`), once compared: 0 not
    /// yet, 1 apart, 2 they meet. The walk compares one pair once per choice of the
    /// robots between them, so a state with `n` robots asks each pair up to the product
    /// of the choices in between. Made at the state's first comparison
    /// ([`Choices::remember`]): many states are expanded by steps of one robot alone and
    /// compare nothing; never made when the actions are more than [`REMEMBERED_ACTIONS`].
    met: Vec<u8>,
    /// What the lists, the footprints taken so far and `met` hold, in bytes.
    bytes: usize,
}

/// The most actions (all robots' together) in one state whose comparisons the walk
/// remembers: a megabyte at most. A state of a larger scene compares anew each time.
const REMEMBERED_ACTIONS: usize = 1024;

impl<'v> Choices<'v> {
    fn new(task: &Task, views: &'v [View<'v>], useful: &Useful) -> Choices<'v> {
        let actions: Vec<Vec<Action>> = views
            .iter()
            .map(|view| {
                view.actions()
                    .into_iter()
                    .filter(|a| useful.allows(task, a))
                    .collect()
            })
            .collect();
        let prints: Vec<Vec<Option<Footprint>>> =
            actions.iter().map(|list| vec![None; list.len()]).collect();
        let first: Vec<usize> = actions
            .iter()
            .scan(0, |at, list| {
                let start = *at;
                *at += list.len();
                Some(start)
            })
            .collect();
        let all: usize = actions.iter().map(Vec::len).sum();
        let bytes = actions
            .iter()
            .map(|list| list.capacity() * (size_of::<Action>() + size_of::<Option<Footprint>>()))
            .sum::<usize>()
            + first.capacity() * size_of::<usize>();
        Choices {
            views,
            actions,
            prints,
            first,
            all,
            met: Vec::new(),
            bytes,
        }
    }

    /// Makes the table of remembered comparisons, unless it is made or the state has more
    /// than [`REMEMBERED_ACTIONS`] actions; counted in [`Choices::bytes`].
    fn remember(&mut self) {
        if self.met.is_empty() && self.all <= REMEMBERED_ACTIONS {
            self.met = vec![0; self.all * self.all];
            self.bytes += self.met.capacity();
        }
    }

    /// Whether robot `r`'s action `i` and robot `k`'s action `j` meet; both footprints
    /// taken. Remembered once [`Choices::remember`] has made its table.
    fn meet(&mut self, (r, i): (usize, usize), (k, j): (usize, usize)) -> bool {
        let (a, b) = (self.first[r] + i, self.first[k] + j);
        match self.met.get(a * self.all + b) {
            Some(1) => false,
            Some(2) => true,
            known => {
                let meets = self.print(r, i).conflict(self.print(k, j)).is_some();
                if known.is_some() {
                    self.met[a * self.all + b] = 1 + u8::from(meets);
                }
                meets
            }
        }
    }

    /// Takes the footprint of robot `r`'s action `j`, unless it was taken already.
    fn take(&mut self, r: usize, j: usize) {
        if self.prints[r][j].is_none() {
            let print = footprint::in_view(&self.views[r], self.actions[r][j]);
            self.bytes += print.heap_bytes();
            self.prints[r][j] = Some(print);
        }
    }

    /// The footprint of robot `r`'s action `j`, once [`Choices::take`] has taken it.
    fn print(&self, r: usize, j: usize) -> &Footprint {
        self.prints[r][j]
            .as_ref()
            .expect("taken before it is compared")
    }
}

/// The robot-by-robot enumeration of one state's joint steps.
struct Walk<'w> {
    task: &'w Task,
    robots: &'w [Robot],
    /// Each robot's actions worth trying, with their footprints in the state expanded.
    choices: Choices<'w>,
    /// `levels[k]`: the state after the actions chosen for robots `0..k`, and its
    /// [`LowerBound::needs`].
    levels: Vec<(State, Needs)>,
    /// `(robot, action index)` of the actions chosen so far.
    chosen: SmallVec<[(usize, usize); 4]>,
    /// The state expanded, the joint steps to its children and its `f`.
    parent: (usize, u16, Cost),
    /// The joint steps of the states the steps lead to, and the actions before the step.
    cost: Cost,
    /// The cost a plan must beat.
    limit: Cost,
    /// The bytes the walk holds besides [`Choices::bytes`]: its states.
    held: usize,
    /// Joint steps (whole or partial) tried so far.
    tried: usize,
}

impl Walk<'_> {
    /// Whether a step completed from level `k` (its state and needs in `levels[k]`,
    /// robots `k..` still free, `chosen` actions in the step so far) could still lead
    /// to a plan cheaper than the limit: fewer joint steps, or as many and fewer actions.
    fn promising(&self, k: usize, chosen: usize) -> bool {
        let left = (self.robots.len() - k) as u16;
        let needs = self.levels[k].1;
        let h = bound(needs, self.robots.len() as u16, left);
        let f = (
            self.cost.0 + usize::from(h),
            self.cost.1 + chosen + usize::from(needs.0),
        );
        f < self.limit
    }

    /// Whether robot `k`'s action `j` interferes with an action chosen so far; the
    /// footprints it compares are taken within the search's memory limit.
    fn interferes(&mut self, k: usize, j: usize, search: &Search<'_>) -> ControlFlow<Halt, bool> {
        if self.chosen.is_empty() {
            return ControlFlow::Continue(false);
        }
        self.choices.take(k, j);
        for &(r, i) in &self.chosen {
            self.choices.take(r, i);
        }
        self.choices.remember();
        if search.bytes(None, 0) + self.held + self.choices.bytes > search.limits.max_memory {
            return ControlFlow::Break(Halt::Limit(Stop::Memory));
        }
        let chosen = &self.chosen;
        let choices = &mut self.choices;
        ControlFlow::Continue(chosen.iter().any(|&(r, i)| choices.meet((r, i), (k, j))))
    }

    /// Chooses for robot `k` and those after it; each complete, non-empty joint step is
    /// recorded with the state it leads to ([`Search::child`]). Answers the cost to beat.
    fn level(&mut self, k: usize, search: &mut Search<'_>) -> ControlFlow<Halt, Cost> {
        self.tried += 1;
        if self.tried.is_multiple_of(CANCEL_EVERY) && search.limits.cancelled() {
            return ControlFlow::Break(Halt::Limit(Stop::Cancelled));
        }
        if k == self.robots.len() {
            if !self.chosen.is_empty() {
                let step: SmallVec<[Step; 4]> = self
                    .chosen
                    .iter()
                    .map(|&(r, j)| Step {
                        robot: self.robots[r].node,
                        action: self.choices.actions[r][j],
                    })
                    .collect();
                let (state, needs) = &self.levels[k];
                let held = self.held + self.choices.bytes;
                self.limit = search.child(self.parent, (state, *needs), &step, held)?;
            }
            return ControlFlow::Continue(self.limit);
        }
        // Robot k does nothing.
        let (done, next) = self.levels.split_at_mut(k + 1);
        next[0].0.clone_from(&done[k].0);
        next[0].1 = done[k].1;
        if self.promising(k + 1, self.chosen.len()) {
            self.level(k + 1, search)?;
        }
        for j in 0..self.choices.actions[k].len() {
            if self.interferes(k, j, search)? {
                continue;
            }
            let a = self.choices.actions[k][j];
            let (done, next) = self.levels.split_at_mut(k + 1);
            next[0].0.clone_from(&done[k].0);
            rules::apply(self.task, &mut next[0].0, self.robots[k], a);
            next[0].1 = search.bound.needs(&next[0].0);
            if !self.promising(k + 1, self.chosen.len() + 1) {
                continue;
            }
            self.chosen.push((k, j));
            let flow = self.level(k + 1, search);
            self.chosen.pop();
            flow?;
        }
        ControlFlow::Continue(self.limit)
    }
}
