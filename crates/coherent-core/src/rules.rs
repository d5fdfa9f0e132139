//! The compatible rule set of SEMANTICS.md sections 2-4: what a robot observes, the
//! actions it may take, and how one action changes the state. Imported original tasks
//! run under these rules exactly, quirks included (see `docs/semantics-notes.md`).

use crate::action::{Action, Verb};
use crate::graph::{Edge, Idx, NodeKind, RobotKind, State};
use crate::task::{Robot, RuleSet, Task};
use crate::vocab::{PropSet, Relation, StateSet};

/// A set of node indices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeSet(Vec<u64>);

impl NodeSet {
    pub fn new(n: usize) -> NodeSet {
        NodeSet(vec![0; n.div_ceil(64)])
    }
    pub fn contains(&self, n: Idx) -> bool {
        self.0[n.get() / 64] >> (n.get() % 64) & 1 == 1
    }
    /// Inserts `n`; returns whether it was new.
    pub fn insert(&mut self, n: Idx) -> bool {
        let new = !self.contains(n);
        self.0[n.get() / 64] |= 1 << (n.get() % 64);
        new
    }
    pub fn remove(&mut self, n: Idx) {
        self.0[n.get() / 64] &= !(1 << (n.get() % 64));
    }
    pub fn iter(&self) -> impl Iterator<Item = Idx> + '_ {
        self.0.iter().enumerate().flat_map(|(w, &word)| {
            (0..64)
                .filter(move |b| word >> b & 1 == 1)
                .map(move |b| Idx((w * 64 + b) as u16))
        })
    }
}

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

/// The visible set of SEMANTICS.md section 2.
pub fn visible(task: &Task, s: &State, robot: Idx) -> NodeSet {
    let mut v = NodeSet::new(task.nodes.len());
    if let Some(room) = room_of(task, s, robot) {
        for e in s.edges() {
            if e.rel() == Relation::Inside && e.to() == room {
                v.insert(e.from());
            }
        }
        let mut grew = true;
        while grew {
            grew = false;
            for e in s.edges() {
                if e.rel().is_location() && v.contains(e.to()) {
                    grew |= v.insert(e.from());
                }
            }
        }
        // Only a thing's direct container is checked: what stands ON a hidden thing
        // stays visible, as in the original.
        for e in s.edges() {
            if e.rel() == Relation::Inside
                && v.contains(e.from())
                && task.node(e.to()).kind != NodeKind::Room
                && !s.states(e.to()).is_open()
            {
                v.remove(e.from());
            }
        }
        v.insert(room);
        for &(door, r) in task.doors() {
            if r == room {
                v.insert(door);
            }
        }
        for r in &task.robots {
            if s.has(Edge::new(r.node, Relation::Inside, room)) {
                v.insert(r.node);
                if let Some(basket) = task.basket_of(r.node) {
                    v.insert(basket);
                    for y in s.sources(Relation::Inside, basket) {
                        v.insert(y);
                    }
                }
            }
        }
    }
    v.insert(robot);
    for h in s.targets(robot, Relation::Hold) {
        v.insert(h);
    }
    for &r in task.rooms() {
        v.insert(r);
    }
    v
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
    pub visible: NodeSet,
    pub room: Option<Idx>,
    pub holding: Option<Idx>,
}

impl<'a> View<'a> {
    pub fn new(task: &'a Task, s: &'a State, robot: Robot) -> View<'a> {
        let visible = visible(task, s, robot.node);
        let holding = s
            .targets(robot.node, Relation::Hold)
            .find(|&h| visible.contains(h));
        View {
            task,
            s,
            robot,
            room: room_of(task, s, robot.node),
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

    /// What the robot dog may move towards (`unreached` of SEMANTICS.md section 3).
    pub fn unreached(&self, n: Idx) -> bool {
        self.sees(n)
            && Some(n) != self.holding
            && !self.close_to(n)
            && !matches!(
                self.kind(n),
                NodeKind::Room | NodeKind::Robot(_) | NodeKind::Floor
            )
            && !self.has(n, PropSet::HIGH_HEIGHT)
            && !self.has(n, PropSet::ON_HIGH_SURFACE)
    }

    /// What a fixed arm reaches: things on its surface, then three levels of things
    /// ON/INSIDE those, then the direct children of surfaces and containers among them.
    pub fn arm_reach(&self) -> Vec<Idx> {
        let mut set = NodeSet::new(self.task.nodes.len());
        let mut reach = Vec::new();
        let Some(surface) = self.own(Relation::On) else {
            return reach;
        };
        for x in self.s.sources(Relation::On, surface) {
            if x != self.robot.node && self.sees(x) && set.insert(x) {
                reach.push(x);
            }
        }
        // One pass over the edges per level: the children of every member so far.
        let grow = |from: &NodeSet, set: &mut NodeSet, reach: &mut Vec<Idx>| {
            for e in self.s.edges() {
                if e.rel().is_location()
                    && from.contains(e.to())
                    && self.sees(e.from())
                    && set.insert(e.from())
                {
                    reach.push(e.from());
                }
            }
        };
        for _ in 0..3 {
            let level = set.clone();
            grow(&level, &mut set, &mut reach);
        }
        let mut holders = NodeSet::new(self.task.nodes.len());
        for &o in &reach {
            if self.has(o, PropSet::SURFACES) || self.has(o, PropSet::CONTAINERS) {
                holders.insert(o);
            }
        }
        grow(&holders, &mut set, &mut reach);
        reach
    }
}

/// Every action `robot` may take in state `s`, without duplicates.
pub fn actions(task: &Task, s: &State, robot: Robot) -> Vec<Action> {
    View::new(task, s, robot).actions()
}

impl View<'_> {
    /// The robot's action list, from this view.
    pub fn actions(&self) -> Vec<Action> {
        let mut out = Vec::new();
        match self.robot.kind {
            RobotKind::Quadrotor => quadrotor_actions(self, &mut out),
            RobotKind::RobotDog => dog_actions(self, &mut out),
            RobotKind::RobotArm => arm_actions(self, &mut out),
        }
        // Lists are short: a quadratic pass beats hashing.
        let mut unique = Vec::with_capacity(out.len());
        for a in out {
            if !unique.contains(&a) {
                unique.push(a);
            }
        }
        unique
    }
}

fn quadrotor_actions(v: &View<'_>, out: &mut Vec<Action>) {
    let me = v.states(v.robot.node);
    if me.contains(StateSet::FLYING) {
        if let Some(above) = v.above() {
            out.push(Action::new(Verb::LandOn, above));
            for n in v.visible.iter() {
                if n != above && v.has(n, PropSet::LANDABLE) {
                    out.push(Action::new(Verb::MoveTowards, n));
                }
            }
        }
        out.extend(
            v.open_next_rooms()
                .map(|room| Action::new(Verb::MoveTowards, room)),
        );
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

fn dog_actions(v: &View<'_>, out: &mut Vec<Action>) {
    for r in v.reachable() {
        hand_actions(v, r, true, out);
    }
    for n in v.visible.iter() {
        if v.unreached(n) {
            out.push(Action::new(Verb::MoveTowards, n));
        }
    }
    out.extend(
        v.open_next_rooms()
            .map(|room| Action::new(Verb::MoveTowards, room)),
    );
}

fn arm_actions(v: &View<'_>, out: &mut Vec<Action>) {
    if let (Some(h), Some(surface)) = (v.holding, v.own(Relation::On)) {
        out.push(Action::with_target(Verb::PutOn, h, surface));
    }
    for o in v.arm_reach() {
        hand_actions(v, o, false, out);
    }
}

/// Applies an action that [`actions`] offered to `robot` (SEMANTICS.md section 4).
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
                let inside: Vec<Idx> = s.sources(Relation::Inside, b).collect();
                s.retain(|e| {
                    !(e.rel() == Relation::Close && (e.to() == b || inside.contains(&e.to())))
                });
                set_basket_high(s, b, true);
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

fn move_to_room(task: &Task, s: &mut State, me: Idx, room: Idx) {
    let old: Vec<Idx> = s
        .targets(me, Relation::Inside)
        .filter(|&t| task.node(t).kind == NodeKind::Room)
        .collect();
    for r in old {
        s.remove(Edge::new(me, Relation::Inside, r));
    }
    s.add(Edge::new(me, Relation::Inside, room));
}

/// The robot dog moves next to `x`: it is then close to `x`, to what an open container
/// `x` holds, to what `x` stands on or in (floors excepted), and to what stands on a
/// surface `x`.
fn dog_approach(task: &Task, s: &mut State, me: Idx, x: Idx) {
    let mut close = vec![x];
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

fn set_basket_high(s: &mut State, basket: Idx, on: bool) {
    s.set_on_high_surface(basket, on);
    let inside: Vec<Idx> = s.sources(Relation::Inside, basket).collect();
    for y in inside {
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
