//! The compatible rule set of docs/semantics.md ("Observations", "Actions"): what a robot observes, the
//! actions it may take, and how one action changes the state. Imported original tasks
//! run under these rules exactly, quirks included (see `docs/semantics-notes.md`).

use std::cell::OnceCell;

use smallvec::SmallVec;

use crate::action::{Action, Verb};
pub use crate::graph::NodeSet;
use crate::graph::{Edge, Idx, NodeKind, RobotKind, State};
use crate::task::{Robot, RuleSet, Task};
use crate::vocab::{PropSet, Relation, StateSet};

/// What one robot observes: the visible nodes and every edge between two of them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Observation {
    /// The room the robot is in (target of its `INSIDE` edge), if any.
    pub room: Option<Idx>,
    pub nodes: Vec<Idx>,
    pub edges: Vec<Edge>,
}

/// The room `n` is in: the target of its `INSIDE` edge that is a room.
pub fn room_of(task: &Task, s: &State, n: Idx) -> Option<Idx> {
    s.targets(n, Relation::Inside)
        .find(|&t| task.node(t).kind == NodeKind::Room)
}

/// The location edges (`ON`, `INSIDE`) of one state grouped by target: what stands on
/// or in each node. Visibility and the arm's reach walk down these lists instead of
/// passing over every edge once per level; the planner builds them once per expanded
/// state for the views of all its robots, which then also share what each room shows.
pub(crate) struct Contents {
    /// `start` (`n + 2` words), then the location edges by target:
    /// `edges[start[p]..start[p + 1]]` point at node `p`. One block, as the search
    /// builds one of these per state it expands.
    data: Vec<u32>,
    /// Where the edges begin in `data`: `n + 2`.
    edges_at: usize,
    /// What a robot in each room of `Task::rooms` sees, besides itself and what it
    /// holds; found when a robot there first looks.
    sights: SmallVec<[OnceCell<NodeSet>; 8]>,
    /// Every node `INSIDE` a container, not a room, that is neither `OPEN` nor
    /// `OPEN_FOREVER`: hidden from view wherever it is.
    hidden: NodeSet,
    /// `(robot, room)` for each robot's `INSIDE` edge to a room.
    robot_rooms: SmallVec<[(Idx, Idx); 4]>,
}

impl Contents {
    pub fn new(task: &Task, s: &State) -> Contents {
        let n = task.nodes.len();
        let locations = || s.edges().iter().filter(|e| e.rel().is_location());
        // Counting sort by target: count, prefix sums, then place in edge order.
        let mut data = Vec::with_capacity(n + 2 + s.edges().len());
        data.resize(n + 2, 0u32);
        for e in locations() {
            data[e.to().get() + 2] += 1;
        }
        for p in 2..n + 2 {
            data[p] += data[p - 1];
        }
        let total = data[n + 1] as usize;
        data.resize(n + 2 + total, 0);
        let (start, edges) = data.split_at_mut(n + 2);
        let mut hidden = NodeSet::new(n);
        let mut robot_rooms = SmallVec::new();
        for e in locations() {
            let at = &mut start[e.to().get() + 1];
            edges[*at as usize] = e.bits();
            *at += 1;
            if e.rel() == Relation::Inside {
                if !task.room_set().contains(e.to()) {
                    if !s.states(e.to()).is_open() {
                        hidden.insert(e.from());
                    }
                } else if task.robot_set().contains(e.from()) {
                    robot_rooms.push((e.from(), e.to()));
                }
            }
        }
        // `start[p]` now holds where `p`'s edges begin, `start[n]` where they end.
        Contents {
            data,
            edges_at: n + 2,
            robot_rooms,
            sights: (0..task.rooms().len()).map(|_| OnceCell::new()).collect(),
            hidden,
        }
    }

    /// The location edges pointing at `p`, in edge order.
    pub fn of(&self, p: Idx) -> &[Edge] {
        let (lo, hi) = (self.data[p.get()] as usize, self.data[p.get() + 1] as usize);
        bytemuck::cast_slice(&self.data[self.edges_at + lo..self.edges_at + hi])
    }
}

/// The visible set of docs/semantics.md, "Observations".
pub fn visible(task: &Task, s: &State, robot: Idx) -> NodeSet {
    look(task, s, robot, &Contents::new(task, s)).1
}

/// What `robot` sees from where it is: its room ([`room_of`]), its visible set, and what
/// it holds (its first `HOLD` target, which it always sees).
fn look(
    task: &Task,
    s: &State,
    robot: Idx,
    contents: &Contents,
) -> (Option<Idx>, NodeSet, Option<Idx>) {
    // The robot's own edges, found once: a few, sorted by relation and target.
    let mine = s.out(robot);
    let room = mine
        .iter()
        .filter(|e| e.rel() == Relation::Inside)
        .map(|e| e.to())
        .find(|&t| task.room_set().contains(t));
    let mut v = match room.and_then(|room| sight(task, room, contents)) {
        Some(sight) => sight.clone(),
        None => task.room_set().clone(),
    };
    v.insert(robot);
    let mut holding = None;
    for e in mine.iter().filter(|e| e.rel() == Relation::Hold) {
        v.insert(e.to());
        holding.get_or_insert(e.to());
    }
    (room, v, holding)
}

/// What any robot in `room` sees (the rooms included), computed once per state; none
/// when `room` is not one of the task's rooms.
fn sight<'c>(task: &Task, room: Idx, contents: &'c Contents) -> Option<&'c NodeSet> {
    let at = task.rooms().iter().position(|&r| r == room)?;
    Some(contents.sights[at].get_or_init(|| {
        let mut v = NodeSet::new(task.nodes.len());
        // Everything INSIDE the room, then whatever is ON or INSIDE something seen, at
        // any depth: the least set closed under location edges, found by a walk down.
        let words = v.words_mut();
        let mut insert = |n: Idx| {
            let (w, bit) = (n.get() / 64, 1u64 << (n.get() % 64));
            let new = words[w] & bit == 0;
            words[w] |= bit;
            new
        };
        // Each node enters the stack once, so it never holds more than the nodes.
        let n = task.nodes.len();
        let mut inline = [Idx(0); 256];
        let mut heap = Vec::new();
        let stack: &mut [Idx] = if n <= inline.len() {
            &mut inline[..n]
        } else {
            heap.resize(n, Idx(0));
            &mut heap
        };
        let mut top = 0;
        for e in contents.of(room) {
            if e.rel() == Relation::Inside && insert(e.from()) {
                stack[top] = e.from();
                top += 1;
            }
        }
        while top > 0 {
            top -= 1;
            for e in contents.of(stack[top]) {
                if insert(e.from()) {
                    stack[top] = e.from();
                    top += 1;
                }
            }
        }
        // Only a thing's direct container is checked: what stands ON a hidden thing
        // stays visible, as in the original.
        v.remove_all(&contents.hidden);
        v.insert(room);
        for &(door, r) in task.doors() {
            if r == room {
                v.insert(door);
            }
        }
        for &(robot, _) in contents.robot_rooms.iter().filter(|(_, r)| *r == room) {
            v.insert(robot);
            if let Some(basket) = task.basket_of(robot) {
                v.insert(basket);
                for e in contents.of(basket) {
                    if e.rel() == Relation::Inside {
                        v.insert(e.from());
                    }
                }
            }
        }
        v.insert_all(task.room_set());
        v
    }))
}

/// The robot's observation: visible nodes and the edges between them.
pub fn observe(task: &Task, s: &State, robot: Idx) -> Observation {
    let v = visible(task, s, robot);
    Observation {
        room: room_of(task, s, robot),
        nodes: v.iter().collect(),
        edges: s
            .edges()
            .iter()
            .copied()
            .filter(|e| v.contains(e.from()) && v.contains(e.to()))
            .collect(),
    }
}

/// One robot's view of a state: its observation and the sets the action rules use.
pub(crate) struct View<'a> {
    pub task: &'a Task,
    pub s: &'a State,
    pub robot: Robot,
    pub contents: &'a Contents,
    pub visible: NodeSet,
    pub room: Option<Idx>,
    pub holding: Option<Idx>,
}

impl<'a> View<'a> {
    /// The view with the state's [`Contents`] built already.
    pub fn with(task: &'a Task, s: &'a State, robot: Robot, contents: &'a Contents) -> View<'a> {
        let (room, visible, holding) = look(task, s, robot.node, contents);
        View {
            task,
            s,
            robot,
            contents,
            room,
            visible,
            holding,
        }
    }

    pub fn sees(&self, n: Idx) -> bool {
        self.visible.contains(n)
    }

    pub fn has(&self, n: Idx, p: PropSet) -> bool {
        self.task.has(self.s, n, p)
    }

    pub fn kind(&self, n: Idx) -> NodeKind {
        self.task.node(n).kind
    }

    pub fn states(&self, n: Idx) -> StateSet {
        self.s.states(n)
    }

    /// The observed target of the robot's `rel` edge.
    pub fn own(&self, rel: Relation) -> Option<Idx> {
        self.s.targets(self.robot.node, rel).find(|&t| self.sees(t))
    }

    /// Targets of the robot's observed `CLOSE` edges.
    pub fn reachable(&self) -> impl Iterator<Item = Idx> + '_ {
        self.s
            .targets(self.robot.node, Relation::Close)
            .filter(|&t| self.sees(t))
    }

    pub fn close_to(&self, n: Idx) -> bool {
        self.sees(n) && self.s.has(Edge::new(self.robot.node, Relation::Close, n))
    }

    /// The quadrotor's `ABOVE` target, when it is a landable surface.
    pub fn above(&self) -> Option<Idx> {
        self.own(Relation::Above)
            .filter(|&t| self.has(t, PropSet::LANDABLE))
    }

    /// `(room, door)` for each visible door and each room it leads to other than ours.
    pub fn next_rooms(&self) -> impl Iterator<Item = (Idx, Idx)> + '_ {
        self.task.doors().iter().filter_map(move |&(door, room)| {
            (self.sees(door) && Some(room) != self.room).then_some((room, door))
        })
    }

    /// Rooms reachable now through an open door.
    pub fn open_next_rooms(&self) -> impl Iterator<Item = Idx> + '_ {
        self.next_rooms()
            .filter(|&(_, door)| self.states(door).is_open())
            .map(|(room, _)| room)
    }

    /// What a fixed arm reaches: things on its surface, then three levels of things
    /// ON/INSIDE those, then the direct children of surfaces and containers among them.
    /// Each level is in node order, as one pass over the sorted edges finds it.
    pub fn arm_reach(&self) -> Vec<Idx> {
        let mut set = NodeSet::new(self.task.nodes.len());
        let mut reach = Vec::with_capacity(16);
        let Some(surface) = self.own(Relation::On) else {
            return reach;
        };
        // Contents are in edge order, which is node order of the sources.
        for e in self.contents.of(surface) {
            let x = e.from();
            if e.rel() == Relation::On && x != self.robot.node && self.sees(x) && set.insert(x) {
                reach.push(x);
            }
        }
        // The seen children of the parents reach[from..to] (and of those `holds`), added
        // in node order.
        let grow =
            |reach: &mut Vec<Idx>, set: &mut NodeSet, from: usize, holds: &dyn Fn(Idx) -> bool| {
                let (to, first) = (reach.len(), reach.len());
                for i in from..to {
                    let p = reach[i];
                    if !holds(p) {
                        continue;
                    }
                    for e in self.contents.of(p) {
                        if self.sees(e.from()) && set.insert(e.from()) {
                            reach.push(e.from());
                        }
                    }
                }
                reach[first..].sort_unstable();
            };
        // Children of earlier levels are in already: each level grows from the last one.
        let mut level = 0;
        for _ in 0..3 {
            let next = reach.len();
            grow(&mut reach, &mut set, level, &|_| true);
            level = next;
        }
        let holder = |o: Idx| self.has(o, PropSet::SURFACES) || self.has(o, PropSet::CONTAINERS);
        grow(&mut reach, &mut set, 0, &holder);
        reach
    }
}

/// Every action `robot` may take in state `s`, without duplicates.
pub fn actions(task: &Task, s: &State, robot: Robot) -> Vec<Action> {
    View::with(task, s, robot, &Contents::new(task, s)).actions()
}

/// Every action `robot` may take in state `s`, each written as the prompts and the
/// environments list it (`[grab] <mug>(7)`).
pub fn action_texts(task: &Task, s: &State, robot: Robot) -> Vec<String> {
    actions(task, s, robot)
        .iter()
        .map(|a| a.render(task))
        .collect()
}

/// The action lists of several robots in state `s`, in the order of `robots`: what one
/// planning round asks of the rules. The state's `Contents` is built once for all, and
/// the lists share one block.
pub fn team_actions(task: &Task, s: &State, robots: &[Robot]) -> TeamActions {
    let contents = Contents::new(task, s);
    let mut lists = TeamActions {
        actions: Vec::with_capacity(32 * robots.len()),
        ends: SmallVec::with_capacity(robots.len()),
    };
    for &robot in robots {
        View::with(task, s, robot, &contents).actions_into(&mut lists.actions);
        lists.ends.push(lists.actions.len() as u32);
    }
    lists
}

/// Every robot's action list in one state ([`team_actions`]), one after the other in one
/// vector; robot `i`'s list is [`TeamActions::get`]`(i)`, and iterating gives the lists
/// in order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TeamActions {
    actions: Vec<Action>,
    /// Where each robot's list ends in `actions`.
    ends: SmallVec<[u32; 4]>,
}

impl TeamActions {
    /// Robot `i`'s list.
    pub fn get(&self, i: usize) -> &[Action] {
        let start = if i == 0 { 0 } else { self.ends[i - 1] as usize };
        &self.actions[start..self.ends[i] as usize]
    }

    /// How many robots' lists there are.
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }

    /// The lists, in the robots' order.
    pub fn iter(&self) -> Lists<'_> {
        Lists {
            lists: self,
            next: 0,
        }
    }
}

impl<'a> IntoIterator for &'a TeamActions {
    type Item = &'a [Action];
    type IntoIter = Lists<'a>;

    fn into_iter(self) -> Lists<'a> {
        self.iter()
    }
}

/// The lists as vectors of their own, for callers that keep or consume them (the same
/// iteration as the `Vec<Vec<Action>>` this function returned before).
impl IntoIterator for TeamActions {
    type Item = Vec<Action>;
    type IntoIter = std::vec::IntoIter<Vec<Action>>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
            .map(<[Action]>::to_vec)
            .collect::<Vec<_>>()
            .into_iter()
    }
}

/// The lists of a [`TeamActions`], in the robots' order.
#[derive(Clone, Debug)]
pub struct Lists<'a> {
    lists: &'a TeamActions,
    next: usize,
}

impl<'a> Iterator for Lists<'a> {
    type Item = &'a [Action];

    fn next(&mut self) -> Option<&'a [Action]> {
        (self.next < self.lists.len()).then(|| {
            self.next += 1;
            self.lists.get(self.next - 1)
        })
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.lists.len() - self.next;
        (left, Some(left))
    }
}

impl ExactSizeIterator for Lists<'_> {}

impl View<'_> {
    /// The robot's action list, from this view.
    pub fn actions(&self) -> Vec<Action> {
        // Room for a long list at once: growing it step by step cost more than the rest.
        let mut out = Vec::with_capacity(32);
        self.actions_into(&mut out);
        out
    }

    /// Appends the robot's action list to `all`.
    pub fn actions_into(&self, all: &mut Vec<Action>) {
        let start = all.len();
        let out = all;
        match self.robot.kind {
            RobotKind::Quadrotor => quadrotor_actions(self, out, start),
            RobotKind::RobotDog => dog_actions(self, out, start),
            RobotKind::RobotArm => {
                arm_actions(self, out);
                // The put on its own surface may come again from what it reaches. Lists
                // are short: a quadratic pass in place beats hashing.
                let mut kept = start;
                for i in start..out.len() {
                    if !out[start..kept].contains(&out[i]) {
                        out[kept] = out[i];
                        kept += 1;
                    }
                }
                out.truncate(kept);
            }
        }
    }
}

/// The quadrotor's list, appended to `out` (its own list begins at `start`).
fn quadrotor_actions(v: &View<'_>, out: &mut Vec<Action>, start: usize) {
    let me = v.states(v.robot.node);
    if me.contains(StateSet::FLYING) {
        if let Some(above) = v.above() {
            out.push(Action::new(Verb::LandOn, above));
            let mut landables = v.visible.clone();
            landables.keep_only(v.task.landable_set());
            landables.remove(above);
            out.extend(landables.iter().map(|n| Action::new(Verb::MoveTowards, n)));
        }
        room_moves(v, out, start);
    }
    if me.contains(StateSet::LAND)
        && let Some(surface) = v.own(Relation::On)
    {
        out.push(Action::new(Verb::TakeoffFrom, surface));
    }
}

/// Open, close and grab with an empty hand; putinto and puton with a full one.
fn hand_actions(v: &View<'_>, r: Idx, doors_too: bool, out: &mut Vec<Action>) {
    let states = v.states(r);
    let openable = v.has(r, PropSet::CONTAINERS) || (doors_too && v.kind(r) == NodeKind::Door);
    match v.holding {
        None => {
            if openable && states.contains(StateSet::CLOSED) {
                out.push(Action::new(Verb::Open, r));
            }
            if openable && states.contains(StateSet::OPEN) {
                out.push(Action::new(Verb::Close, r));
            }
            if v.has(r, PropSet::GRABABLE) {
                out.push(Action::new(Verb::Grab, r));
            }
        }
        Some(h) => {
            if v.has(r, PropSet::CONTAINERS) && states.is_open() {
                out.push(Action::with_target(Verb::PutInto, h, r));
            }
            if v.has(r, PropSet::SURFACES) {
                out.push(Action::with_target(Verb::PutOn, h, r));
            }
        }
    }
}

fn dog_actions(v: &View<'_>, out: &mut Vec<Action>, start: usize) {
    let mut close = NodeSet::new(v.task.nodes.len());
    for r in v.reachable() {
        close.insert(r);
        hand_actions(v, r, true, out);
    }
    // What it may walk up to (`View::unreached`), as set operations: what it sees, less
    // what it is close to, holds, can never approach, or is on a high surface.
    let mut unreached = v.visible.clone();
    unreached.remove_all(&close);
    unreached.remove_all(v.task.never_approached());
    unreached.remove_words32(v.s.high_words());
    if let Some(h) = v.holding {
        unreached.remove(h);
    }
    out.extend(unreached.iter().map(|n| Action::new(Verb::MoveTowards, n)));
    room_moves(v, out, start);
}

/// `movetowards` each room an open door leads to, once: two doors may lead to one room
/// (the other moves of a list name distinct nodes, none a room for the dog).
fn room_moves(v: &View<'_>, out: &mut Vec<Action>, start: usize) {
    for room in v.open_next_rooms() {
        let a = Action::new(Verb::MoveTowards, room);
        if !out[start..].contains(&a) {
            out.push(a);
        }
    }
}

fn arm_actions(v: &View<'_>, out: &mut Vec<Action>) {
    if let (Some(h), Some(surface)) = (v.holding, v.own(Relation::On)) {
        out.push(Action::with_target(Verb::PutOn, h, surface));
    }
    for o in v.arm_reach() {
        hand_actions(v, o, false, out);
    }
}

/// Applies an action that [`actions`] offered to `robot` (docs/semantics.md, "Actions").
pub fn apply(task: &Task, s: &mut State, robot: Robot, a: Action) {
    let me = robot.node;
    let x = a.object;
    match (robot.kind, a.verb) {
        (RobotKind::Quadrotor, Verb::LandOn) => {
            s.set_states(me, StateSet::LAND);
            s.remove(Edge::new(me, Relation::Above, x));
            s.add(Edge::new(me, Relation::On, x));
            if let Some(b) = task.basket_of(me) {
                s.add(Edge::new(b, Relation::On, x));
                if task.has(s, x, PropSet::HIGH_HEIGHT) {
                    set_basket_high(s, b, true);
                } else if task.has(s, x, PropSet::LOW_HEIGHT) && s.on_high_surface(b) {
                    set_basket_high(s, b, false);
                }
            }
        }
        (RobotKind::Quadrotor, Verb::TakeoffFrom) => {
            s.set_states(me, StateSet::FLYING);
            s.remove(Edge::new(me, Relation::On, x));
            s.add(Edge::new(me, Relation::Above, x));
            if let Some(b) = task.basket_of(me) {
                s.remove(Edge::new(b, Relation::On, x));
                lift_basket(s, b);
            }
        }
        (RobotKind::Quadrotor, Verb::MoveTowards) => {
            s.remove_out(me, Relation::Above);
            if task.node(x).kind == NodeKind::Room {
                if let Some(floor) = task.floor_of(x) {
                    s.add(Edge::new(me, Relation::Above, floor));
                }
                move_to_room(task, s, me, x);
            } else {
                s.add(Edge::new(me, Relation::Above, x));
            }
        }
        (_, Verb::Open) => s.set_states(x, StateSet::OPEN),
        (_, Verb::Close) => s.set_states(x, StateSet::CLOSED),
        (_, Verb::Grab) => {
            s.remove(Edge::new(me, Relation::Close, x));
            s.add(Edge::new(me, Relation::Hold, x));
            if let Some(e) = first_location(task, s, x) {
                s.remove(e);
            }
        }
        (kind, Verb::PutInto | Verb::PutOn) => {
            let rel = if a.verb == Verb::PutInto {
                Relation::Inside
            } else {
                Relation::On
            };
            s.remove(Edge::new(me, Relation::Hold, x));
            if let Some(t) = a.target {
                s.add(Edge::new(x, rel, t));
            }
            if kind == RobotKind::RobotArm {
                // Compatible: always; geometric: when the place is high (a basket
                // carries its own flag, see `set_basket_high`).
                let high = match (task.meta.rules, a.target) {
                    (RuleSet::Geometric, Some(t)) => {
                        task.has(s, t, PropSet::HIGH_HEIGHT) || s.on_high_surface(t)
                    }
                    _ => true,
                };
                s.set_on_high_surface(x, high);
            } else {
                s.add(Edge::new(me, Relation::Close, x));
            }
        }
        (_, Verb::MoveTowards) => {
            s.remove_out(me, Relation::Close);
            if task.node(x).kind == NodeKind::Room {
                s.remove_out(me, Relation::On);
                if let Some(floor) = task.floor_of(x) {
                    s.add(Edge::new(me, Relation::On, floor));
                }
                move_to_room(task, s, me, x);
            } else {
                dog_approach(task, s, me, x);
            }
        }
        // The action list never offers these (a quadrotor verb to another robot type).
        (_, Verb::LandOn | Verb::TakeoffFrom) => {}
    }
}

pub(crate) fn move_to_room(task: &Task, s: &mut State, me: Idx, room: Idx) {
    s.remove_out_if(me, Relation::Inside, |t| {
        task.node(t).kind == NodeKind::Room
    });
    s.add(Edge::new(me, Relation::Inside, room));
}

/// The robot dog moves next to `x`: it is then close to `x`, to what an open container
/// `x` holds, to what `x` stands on or in (floors excepted), and to what stands on a
/// surface `x`.
fn dog_approach(task: &Task, s: &mut State, me: Idx, x: Idx) {
    let mut close: SmallVec<[Idx; 16]> = smallvec::smallvec![x];
    if task.has(s, x, PropSet::CONTAINERS) && s.states(x).is_open() {
        close.extend(s.sources(Relation::Inside, x));
    }
    close.extend(
        s.out(x)
            .iter()
            .filter(|e| e.rel().is_location() && task.node(e.to()).kind != NodeKind::Floor)
            .map(|e| e.to()),
    );
    if task.has(s, x, PropSet::SURFACES) && task.node(x).kind != NodeKind::Floor {
        close.extend(s.sources(Relation::On, x));
    }
    for t in close {
        s.add(Edge::new(me, Relation::Close, t));
    }
}

/// A basket taken up into the air (its quadrotor takes off, or joins the team flying):
/// no robot is next to it or to what is in it any more, and both are marked
/// `ON_HIGH_SURFACE`.
pub(crate) fn lift_basket(s: &mut State, basket: Idx) {
    let inside: SmallVec<[Idx; 8]> = s.sources(Relation::Inside, basket).collect();
    s.retain(|e| !(e.rel() == Relation::Close && (e.to() == basket || inside.contains(&e.to()))));
    mark_high(s, basket, &inside, true);
}

fn set_basket_high(s: &mut State, basket: Idx, on: bool) {
    let inside: SmallVec<[Idx; 8]> = s.sources(Relation::Inside, basket).collect();
    mark_high(s, basket, &inside, on);
}

/// Sets or clears `ON_HIGH_SURFACE` on `basket` and on what is `inside` it.
fn mark_high(s: &mut State, basket: Idx, inside: &[Idx], on: bool) {
    s.set_on_high_surface(basket, on);
    for &y in inside {
        s.set_on_high_surface(y, on);
    }
}

/// `x`'s first ON/INSIDE edge: edges of the initial graph in file order come first,
/// edges added while running after them.
fn first_location(task: &Task, s: &State, x: Idx) -> Option<Edge> {
    s.out(x)
        .iter()
        .copied()
        .filter(|e| e.rel().is_location())
        .min_by_key(|e| {
            task.init_edges
                .iter()
                .position(|i| i == e)
                .unwrap_or(usize::MAX)
        })
}
