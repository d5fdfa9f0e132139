//! What one action reads and writes: the pairwise test behind joint steps
//! (docs/semantics.md, "Parallel steps").
//!
//! A state is made of atoms: each node's state word, each node's `ON_HIGH_SURFACE` bit,
//! and each possible edge (present or absent). A [`Footprint`] lists the atoms an action
//! assigns and the values it leaves them with ([`Footprint::writes`], and
//! [`Footprint::clears`] for a relation it empties whatever is in it), and the parts of
//! the state it depends on ([`Footprint::reads`]: single atoms, or every edge of one
//! relation out of or into a node). It is built so that one property holds, the
//! *locality* of an action `a` offered in `s`: in any state that agrees with `s` on the
//! reads, `a` is still offered, has the same footprint, and assigns the same atoms the
//! same values, leaving every other atom as it was. Two footprints *meet* when one
//! changes an atom the other reads, or when they leave an atom with different values.
//! Actions whose footprints do not meet commute: whichever runs first leaves the
//! other's reads alone, and they agree on what they both assign. So a set of actions
//! that pairwise do not meet is a forall-step (Rintanen, Heljanko and Niemelä 2006):
//! every order applies each action at its turn and ends in one state.
//!
//! The reads mirror the action lists of `rules.rs` one condition at a time: what makes
//! the action offered (its robot's room, hand, state; the visibility of every node it
//! names, through one witness: the chain of `ON`/`INSIDE` edges that puts a node in
//! sight, or the door of the room) and what its transition looks at (what stands on a
//! surface the dog walks up to, what is in a basket that takes off). Where a read covers
//! a whole relation the test could refuse two actions whose orders happen to agree; the
//! tests find no such pair on the states they visit (`tests/joint_steps.rs`).

use smallvec::SmallVec;

use crate::action::{Action, Verb};
use crate::graph::{Edge, Idx, NodeKind, NodeSet, RobotKind, State};
use crate::rules::{Contents, View};
use crate::task::{Robot, RuleSet, Task};
use crate::vocab::{PropSet, Relation, StateSet};

/// One atom of a state: an edge (present or absent), a node's state word, or a node's
/// `ON_HIGH_SURFACE` bit. Packed as an [`Edge`] is; node atoms use the relation bits
/// no relation has (7) and tell the two apart by the low bits.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Atom(u32);

const NODE_ATOM: u32 = 7;

/// What an [`Atom`] is, unpacked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AtomKind {
    Edge(Edge),
    States(Idx),
    High(Idx),
}

impl Atom {
    pub fn edge(e: Edge) -> Atom {
        Atom((e.from().0 as u32) << 17 | (e.rel() as u32) << 14 | e.to().0 as u32)
    }
    pub fn states(n: Idx) -> Atom {
        Atom((n.0 as u32) << 17 | NODE_ATOM << 14)
    }
    pub fn high(n: Idx) -> Atom {
        Atom((n.0 as u32) << 17 | NODE_ATOM << 14 | 1)
    }
    fn node(self) -> Idx {
        Idx((self.0 >> 17) as u16)
    }
    pub fn kind(self) -> AtomKind {
        let n = self.node();
        match self.0 >> 14 & 0b111 {
            NODE_ATOM if self.0 & 1 == 0 => AtomKind::States(n),
            NODE_ATOM => AtomKind::High(n),
            rel => AtomKind::Edge(Edge::new(
                n,
                Relation::ALL[rel as usize],
                Idx((self.0 & 0x3fff) as u16),
            )),
        }
    }
    /// The bit of each node the atom is about, in a 64-bit summary (node index mod 64).
    fn mask(self) -> u64 {
        match self.kind() {
            AtomKind::Edge(e) => bit(e.from()) | bit(e.to()),
            AtomKind::States(n) | AtomKind::High(n) => bit(n),
        }
    }
}

impl std::fmt::Debug for Atom {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.kind() {
            AtomKind::Edge(e) => write!(f, "{e:?}"),
            AtomKind::States(n) => write!(f, "states({})", n.0),
            AtomKind::High(n) => write!(f, "high({})", n.0),
        }
    }
}

fn bit(n: Idx) -> u64 {
    1 << (n.0 % 64)
}

/// A part of the state an action depends on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Read {
    Atom(Atom),
    /// Every edge `(n, rel, _)`, present or not.
    Out(Idx, Relation),
    /// Every edge `(_, rel, n)`, present or not.
    In(Idx, Relation),
    /// The whole state: an action whose dependence the rules below do not pin down
    /// (a robot with two `ON` or `ABOVE` edges, which no released or native task has).
    All,
}

impl Read {
    fn covers(self, w: Atom) -> bool {
        match self {
            Read::Atom(a) => a == w,
            Read::All => true,
            Read::Out(n, rel) => {
                matches!(w.kind(), AtomKind::Edge(e) if e.from() == n && e.rel() == rel)
            }
            Read::In(n, rel) => {
                matches!(w.kind(), AtomKind::Edge(e) if e.to() == n && e.rel() == rel)
            }
        }
    }

    fn mask(self) -> u64 {
        match self {
            Read::Atom(a) => a.mask(),
            Read::Out(n, _) | Read::In(n, _) => bit(n),
            Read::All => u64::MAX,
        }
    }
}

/// One atom an action assigns, and the value it gives it: 0 or 1 for an edge (absent,
/// present) and for `ON_HIGH_SURFACE`, the state word for a node's states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Write {
    pub atom: Atom,
    pub value: u32,
    /// Whether the value differs from the atom's value in the state the footprint was
    /// taken in. An assignment that changes nothing cannot disturb a reader.
    pub changes: bool,
}

/// What one action of one robot reads and writes in one state.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Footprint {
    pub reads: SmallVec<[Read; 16]>,
    /// The atoms it assigns, each once, with the value it leaves.
    pub writes: SmallVec<[Write; 12]>,
    /// Relations out of or into a node it empties ([`Read::Out`], [`Read::In`]): every
    /// edge there not among `writes` ends absent, whatever was there (the dog's `CLOSE`
    /// edges when it walks, the `CLOSE` edges to a basket that takes off). The edges
    /// there were are among `writes` too.
    pub clears: SmallVec<[Read; 4]>,
    /// Summaries of the nodes the reads and the writes are about: two footprints whose
    /// summaries do not meet cannot conflict, which settles most pairs at once.
    read_mask: u64,
    write_mask: u64,
}

/// Where two footprints meet: the atom the first (or, when `swapped`, the second)
/// writes, and whether the other writes it too or reads it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Conflict {
    pub atom: Atom,
    /// How the other footprint reaches `atom`: `None` when it assigns it another value.
    pub read: Option<Read>,
    /// Whether the second footprint is the one that writes `atom`.
    pub swapped: bool,
}

/// Reads a footprint looks through for a repeat before it keeps one more. An action
/// reads a few dozen atoms at most, except one that names a thing deep in containers,
/// which reads every edge up to the room (thousands, and a look through them each time
/// would make the footprint quadratic in the depth): past this many, reads are kept as
/// they come and the list is sorted and rid of repeats once, when it is done.
const LISTED_READS: usize = 32;

impl Footprint {
    fn read(&mut self, r: Read) {
        self.read_mask |= r.mask();
        if self.reads.len() >= LISTED_READS || !self.reads.contains(&r) {
            self.reads.push(r);
        }
    }

    /// The footprint built: its reads a set again when they were too many to look
    /// through (see [`LISTED_READS`]).
    fn done(mut self) -> Footprint {
        if self.reads.len() > LISTED_READS {
            self.reads.sort_unstable();
            self.reads.dedup();
        }
        self
    }

    /// Assigns `value` to `atom`, which had `before`; a later assignment of the same
    /// atom by the same action replaces an earlier one, as in the transition.
    fn write(&mut self, atom: Atom, value: u32, before: u32) {
        self.write_mask |= atom.mask();
        let w = Write {
            atom,
            value,
            changes: value != before,
        };
        match self.writes.iter_mut().find(|w| w.atom == atom) {
            Some(old) => *old = w,
            None => self.writes.push(w),
        }
    }

    /// The bytes the footprint holds beyond its own size: its lists, once they outgrow
    /// the room they have inline.
    pub(crate) fn heap_bytes(&self) -> usize {
        let spilled = |spilled: bool, capacity: usize, each: usize| {
            if spilled { capacity * each } else { 0 }
        };
        spilled(
            self.reads.spilled(),
            self.reads.capacity(),
            size_of::<Read>(),
        ) + spilled(
            self.writes.spilled(),
            self.writes.capacity(),
            size_of::<Write>(),
        ) + spilled(
            self.clears.spilled(),
            self.clears.capacity(),
            size_of::<Read>(),
        )
    }

    /// The value this footprint leaves `atom` with, when it assigns it.
    fn assigns(&self, atom: Atom) -> Option<u32> {
        if let Some(w) = self.writes.iter().find(|w| w.atom == atom) {
            return Some(w.value);
        }
        self.clears.iter().any(|c| c.covers(atom)).then_some(0)
    }

    /// Where `self` and `other` meet, if they do: an atom they leave with different
    /// values, or one that one changes and the other reads. `None` means the two
    /// actions commute.
    pub fn conflict(&self, other: &Footprint) -> Option<Conflict> {
        if self.write_mask & (other.write_mask | other.read_mask) == 0
            && other.write_mask & self.read_mask == 0
        {
            return None;
        }
        let meet = |a: &Footprint, b: &Footprint, swapped| {
            a.writes.iter().find_map(|w| {
                if b.assigns(w.atom).is_some_and(|v| v != w.value) {
                    return Some(Conflict {
                        atom: w.atom,
                        read: None,
                        swapped,
                    });
                }
                let r = b.reads.iter().find(|r| w.changes && r.covers(w.atom))?;
                Some(Conflict {
                    atom: w.atom,
                    read: Some(*r),
                    swapped,
                })
            })
        };
        meet(self, other, false).or_else(|| meet(other, self, true))
    }
}

impl Footprint {
    /// The footprint of `a`, an action offered to `robot` in `s`.
    pub fn of(task: &Task, s: &State, robot: Robot, a: Action) -> Footprint {
        let contents = Contents::new(task, s);
        in_view(&View::with(task, s, robot, &contents), a)
    }
}

/// The footprint of `a`, offered to the view's robot in the view's state.
pub(crate) fn in_view(v: &View<'_>, a: Action) -> Footprint {
    let mut t = Trace {
        v,
        f: Footprint::default(),
    };
    let me = v.robot.node;
    // The room decides what the robot sees, so every action depends on it.
    t.f.read(Read::Out(me, Relation::Inside));
    match v.robot.kind {
        RobotKind::Quadrotor => t.quadrotor(a),
        RobotKind::RobotDog => t.dog(a),
        RobotKind::RobotArm => t.arm(a),
    }
    t.f.done()
}

/// Builds one footprint, reading the state through the view.
struct Trace<'v, 'a> {
    v: &'v View<'a>,
    f: Footprint,
}

impl Trace<'_, '_> {
    fn task(&self) -> &Task {
        self.v.task
    }
    fn s(&self) -> &State {
        self.v.s
    }
    fn me(&self) -> Idx {
        self.v.robot.node
    }

    /// Reads one edge atom; whether the edge is there.
    fn edge(&mut self, e: Edge) -> bool {
        self.f.read(Read::Atom(Atom::edge(e)));
        self.s().has(e)
    }

    /// Adds edge `e` (`present`) or removes it.
    fn set_edge(&mut self, e: Edge, present: bool) {
        let before = self.s().has(e);
        self.f
            .write(Atom::edge(e), u32::from(present), u32::from(before));
    }

    fn set_states(&mut self, n: Idx, value: StateSet) {
        let before = self.s().states(n);
        self.f.write(Atom::states(n), value.0, before.0);
    }

    fn set_high(&mut self, n: Idx, on: bool) {
        let before = self.s().on_high_surface(n);
        self.f
            .write(Atom::high(n), u32::from(on), u32::from(before));
    }

    /// Removes every `(n, rel, _)` edge: whatever was there, none is left.
    fn clear_out(&mut self, n: Idx, rel: Relation) {
        self.clear(Read::Out(n, rel));
        let targets: SmallVec<[Idx; 8]> = self.s().targets(n, rel).collect();
        for t in targets {
            self.set_edge(Edge::new(n, rel, t), false);
        }
    }

    /// Removes every `(_, rel, n)` edge.
    fn clear_in(&mut self, rel: Relation, n: Idx) {
        self.clear(Read::In(n, rel));
        let sources: SmallVec<[Idx; 8]> = self.s().sources(rel, n).collect();
        for d in sources {
            self.set_edge(Edge::new(d, rel, n), false);
        }
    }

    fn clear(&mut self, family: Read) {
        self.f.write_mask |= family.mask();
        if !self.f.clears.contains(&family) {
            self.f.clears.push(family);
        }
    }

    /// Sources of the `rel` edges into `n`, read as a whole.
    fn sources(&mut self, rel: Relation, n: Idx) -> SmallVec<[Idx; 8]> {
        self.f.read(Read::In(n, rel));
        self.s().sources(rel, n).collect()
    }

    fn props(&self, n: Idx, p: PropSet) -> bool {
        self.task().node(n).properties.contains(p)
    }

    /// The robot's `rel` target the rules use (`View::own`: its first visible one).
    fn own(&mut self, rel: Relation) {
        let me = self.me();
        self.f.read(Read::Out(me, rel));
        let targets: SmallVec<[Idx; 2]> = self.s().targets(me, rel).collect();
        match targets[..] {
            [] => {}
            [t] => self.seen(t),
            // Which one counts would depend on what else is in view.
            _ => self.f.read(Read::All),
        }
    }

    /// Why the robot sees `n`: one witness of docs/semantics.md, "Observations".
    fn seen(&mut self, n: Idx) {
        let (me, task) = (self.me(), self.v.task);
        let kind = task.node(n).kind;
        if n == me || kind == NodeKind::Room {
            return;
        }
        if self.s().has(Edge::new(me, Relation::Hold, n)) {
            self.edge(Edge::new(me, Relation::Hold, n));
            return;
        }
        let Some(room) = self.v.room else {
            // In no room a robot sees the rooms, itself and what it holds only.
            return self.f.read(Read::All);
        };
        if kind == NodeKind::Door && task.doors().contains(&(n, room)) {
            return;
        }
        if matches!(kind, NodeKind::Robot(_)) && self.edge(Edge::new(n, Relation::Inside, room)) {
            return;
        }
        // A quadrotor in the room shows its basket and what is in the basket.
        for r in &task.robots {
            if let Some(basket) = task.basket_of(r.node) {
                let shows = n == basket || self.s().has(Edge::new(n, Relation::Inside, basket));
                if shows && self.s().has(Edge::new(r.node, Relation::Inside, room)) {
                    self.edge(Edge::new(r.node, Relation::Inside, room));
                    if n != basket {
                        self.edge(Edge::new(n, Relation::Inside, basket));
                    }
                    return;
                }
            }
        }
        match self.chain_to(n, room) {
            Some(chain) => {
                for e in chain {
                    self.edge(e);
                }
                // Not hidden: each container `n` is INSIDE, other than a room, is open.
                self.f.read(Read::Out(n, Relation::Inside));
                let holders: SmallVec<[Idx; 4]> = self.s().targets(n, Relation::Inside).collect();
                for c in holders {
                    if task.node(c).kind != NodeKind::Room {
                        self.f.read(Read::Atom(Atom::states(c)));
                    }
                }
            }
            None => self.f.read(Read::All),
        }
    }

    /// A chain of `ON`/`INSIDE` edges from `n` up to `room`, the last one `INSIDE` it:
    /// what puts `n` among the things a robot in `room` sees.
    fn chain_to(&self, n: Idx, room: Idx) -> Option<SmallVec<[Edge; 8]>> {
        let s = self.s();
        // Breadth-first upwards; each node found with the edge that reached it and the
        // index of that edge's source. What was found is also kept as a set: a thing
        // thousands of containers deep would make a look through the list quadratic.
        type Found = (Idx, Option<(usize, Edge)>);
        let mut seen: SmallVec<[Found; 16]> = smallvec::smallvec![(n, None)];
        let mut found = NodeSet::new(self.v.task.nodes.len());
        found.insert(n);
        let mut i = 0;
        while i < seen.len() {
            let x = seen[i].0;
            for &e in s.out(x).iter().filter(|e| e.rel().is_location()) {
                if e.to() == room && e.rel() == Relation::Inside {
                    let mut chain: SmallVec<[Edge; 8]> = smallvec::smallvec![e];
                    let mut at = i;
                    while let (_, Some((prev, edge))) = seen[at] {
                        chain.push(edge);
                        at = prev;
                    }
                    return Some(chain);
                }
                if found.insert(e.to()) {
                    seen.push((e.to(), Some((i, e))));
                }
            }
            i += 1;
        }
        None
    }

    /// The robot's room changes to `room` (`rules::move_to_room`).
    fn enter(&mut self, room: Idx) {
        let task = self.v.task;
        let me = self.me();
        // Only the room edge goes (a robot is INSIDE nothing else): read them all.
        self.f.read(Read::Out(me, Relation::Inside));
        let rooms: SmallVec<[Idx; 2]> = self
            .s()
            .targets(me, Relation::Inside)
            .filter(|&t| task.node(t).kind == NodeKind::Room)
            .collect();
        for r in rooms {
            self.set_edge(Edge::new(me, Relation::Inside, r), false);
        }
        self.set_edge(Edge::new(me, Relation::Inside, room), true);
    }

    /// Offered `movetowards room`: an open, visible door of the robot's room leads
    /// there. Whether one does.
    fn door_to(&mut self, room: Idx) -> bool {
        let Some(door) = self
            .v
            .next_rooms()
            .find_map(|(r, door)| (r == room && self.v.states(door).is_open()).then_some(door))
        else {
            return false;
        };
        self.seen(door);
        self.f.read(Read::Atom(Atom::states(door)));
        true
    }

    /// `b` and what is in it get `ON_HIGH_SURFACE` set or cleared (`set_basket_high`).
    fn basket_high(&mut self, b: Idx, on: bool) {
        self.set_high(b, on);
        for y in self.sources(Relation::Inside, b) {
            self.set_high(y, on);
        }
    }

    fn quadrotor(&mut self, a: Action) {
        let (me, x) = (self.me(), a.object);
        let task = self.v.task;
        self.f.read(Read::Atom(Atom::states(me)));
        let basket = task.basket_of(me);
        match a.verb {
            Verb::LandOn => {
                self.own(Relation::Above);
                self.set_states(me, StateSet::LAND);
                self.set_edge(Edge::new(me, Relation::Above, x), false);
                self.set_edge(Edge::new(me, Relation::On, x), true);
                if let Some(b) = basket {
                    self.set_edge(Edge::new(b, Relation::On, x), true);
                    if self.props(x, PropSet::HIGH_HEIGHT) {
                        self.basket_high(b, true);
                    } else if self.props(x, PropSet::LOW_HEIGHT) {
                        self.f.read(Read::Atom(Atom::high(b)));
                        if self.s().on_high_surface(b) {
                            self.basket_high(b, false);
                        }
                    }
                }
            }
            Verb::TakeoffFrom => {
                self.own(Relation::On);
                self.set_states(me, StateSet::FLYING);
                self.set_edge(Edge::new(me, Relation::On, x), false);
                self.set_edge(Edge::new(me, Relation::Above, x), true);
                if let Some(b) = basket {
                    self.set_edge(Edge::new(b, Relation::On, x), false);
                    // Whoever is close to the basket or to what is in it is no more.
                    let mut near = self.sources(Relation::Inside, b);
                    near.push(b);
                    for y in near {
                        self.clear_in(Relation::Close, y);
                    }
                    self.basket_high(b, true);
                }
            }
            _ => {
                let room = task.node(x).kind == NodeKind::Room;
                if !(room && self.door_to(x)) {
                    self.own(Relation::Above);
                    self.seen(x);
                }
                self.clear_out(me, Relation::Above);
                if room {
                    if let Some(floor) = task.floor_of(x) {
                        self.set_edge(Edge::new(me, Relation::Above, floor), true);
                    }
                    self.enter(x);
                } else {
                    self.set_edge(Edge::new(me, Relation::Above, x), true);
                }
            }
        }
    }

    /// The dog has `r` within reach: it is close to it and sees it.
    fn dog_reaches(&mut self, r: Idx) {
        self.edge(Edge::new(self.me(), Relation::Close, r));
        self.seen(r);
    }

    fn dog(&mut self, a: Action) {
        let (me, x) = (self.me(), a.object);
        let task = self.v.task;
        self.f.read(Read::Out(me, Relation::Hold));
        match a.verb {
            Verb::MoveTowards if task.node(x).kind == NodeKind::Room => {
                if !self.door_to(x) {
                    self.f.read(Read::All);
                }
                self.clear_out(me, Relation::Close);
                self.clear_out(me, Relation::On);
                if let Some(floor) = task.floor_of(x) {
                    self.set_edge(Edge::new(me, Relation::On, floor), true);
                }
                self.enter(x);
            }
            Verb::MoveTowards => {
                // Offered while not close to `x`, which is not on a high surface.
                self.seen(x);
                self.edge(Edge::new(me, Relation::Close, x));
                self.f.read(Read::Atom(Atom::high(x)));
                self.clear_out(me, Relation::Close);
                self.approach(x);
            }
            Verb::PutInto | Verb::PutOn => {
                if let Some(t) = a.target {
                    self.dog_reaches(t);
                    self.put(a, t);
                }
                self.set_edge(Edge::new(me, Relation::Close, x), true);
            }
            _ => {
                self.dog_reaches(x);
                self.hand(a);
            }
        }
    }

    /// What the dog is close to after walking up to `x` (`rules::dog_approach`).
    fn approach(&mut self, x: Idx) {
        let me = self.me();
        let task = self.v.task;
        let mut close: SmallVec<[Idx; 16]> = smallvec::smallvec![x];
        if self.props(x, PropSet::CONTAINERS) {
            self.f.read(Read::Atom(Atom::states(x)));
            if self.s().states(x).is_open() {
                close.extend(self.sources(Relation::Inside, x));
            }
        }
        for rel in [Relation::On, Relation::Inside] {
            self.f.read(Read::Out(x, rel));
            close.extend(
                self.s()
                    .targets(x, rel)
                    .filter(|&t| task.node(t).kind != NodeKind::Floor),
            );
        }
        if self.props(x, PropSet::SURFACES) && task.node(x).kind != NodeKind::Floor {
            close.extend(self.sources(Relation::On, x));
        }
        for t in close {
            self.set_edge(Edge::new(me, Relation::Close, t), true);
        }
    }

    /// `open`, `close` or `grab` of `x`, with an empty hand.
    fn hand(&mut self, a: Action) {
        let (me, x) = (self.me(), a.object);
        match a.verb {
            Verb::Open | Verb::Close => {
                self.f.read(Read::Atom(Atom::states(x)));
                let value = if a.verb == Verb::Open {
                    StateSet::OPEN
                } else {
                    StateSet::CLOSED
                };
                self.set_states(x, value);
            }
            Verb::Grab => {
                self.set_edge(Edge::new(me, Relation::Close, x), false);
                self.set_edge(Edge::new(me, Relation::Hold, x), true);
                // The first ON/INSIDE edge of `x` goes.
                for rel in [Relation::On, Relation::Inside] {
                    self.f.read(Read::Out(x, rel));
                }
                let first = self
                    .s()
                    .out(x)
                    .iter()
                    .copied()
                    .filter(|e| e.rel().is_location())
                    .min_by_key(|e| {
                        self.task()
                            .init_edges
                            .iter()
                            .position(|i| i == e)
                            .unwrap_or(usize::MAX)
                    });
                if let Some(e) = first {
                    self.set_edge(e, false);
                }
            }
            _ => {}
        }
    }

    /// `putinto`/`puton` of the held `a.object` into or on `t`.
    fn put(&mut self, a: Action, t: Idx) {
        let (me, x) = (self.me(), a.object);
        let rel = if a.verb == Verb::PutInto {
            self.f.read(Read::Atom(Atom::states(t)));
            Relation::Inside
        } else {
            Relation::On
        };
        self.set_edge(Edge::new(me, Relation::Hold, x), false);
        self.set_edge(Edge::new(x, rel, t), true);
    }

    fn arm(&mut self, a: Action) {
        let me = self.me();
        self.f.read(Read::Out(me, Relation::Hold));
        let surface = self.s().target(me, Relation::On);
        match (a.verb, a.target) {
            (Verb::PutInto | Verb::PutOn, Some(t)) => {
                // `puton` on the arm's own surface is offered whatever it reaches.
                if a.verb == Verb::PutOn && Some(t) == surface {
                    self.own(Relation::On);
                } else {
                    self.arm_reaches(t);
                }
                self.put(a, t);
                // The arm marks what it puts down (by the place's height, geometric).
                let high = if self.task().meta.rules == RuleSet::Geometric {
                    self.f.read(Read::Atom(Atom::high(t)));
                    self.props(t, PropSet::HIGH_HEIGHT) || self.s().on_high_surface(t)
                } else {
                    true
                };
                self.set_high(a.object, high);
            }
            _ => {
                self.arm_reaches(a.object);
                self.hand(a);
            }
        }
    }

    /// `o` is among what the arm reaches (`View::arm_reach`): a chain of visible
    /// things from `o` down to one standing ON the arm's surface, at most three levels
    /// below it, or four when the last holder is a surface or container.
    fn arm_reaches(&mut self, o: Idx) {
        self.own(Relation::On);
        let Some(surface) = self.v.own(Relation::On) else {
            return self.f.read(Read::All);
        };
        match self.arm_chain(o, surface) {
            Some(chain) => {
                for e in chain {
                    self.edge(e);
                    self.seen(e.from());
                }
            }
            None => self.f.read(Read::All),
        }
    }

    /// The chain of `arm_reaches`, edges from `o` upwards, or none.
    fn arm_chain(&self, o: Idx, surface: Idx) -> Option<SmallVec<[Edge; 8]>> {
        let v = self.v;
        let holder =
            |p: Idx| self.props(p, PropSet::SURFACES) || self.props(p, PropSet::CONTAINERS);
        // Depth-first upwards over visible things, at most five edges.
        let mut path: SmallVec<[Edge; 8]> = SmallVec::new();
        fn walk(
            v: &View<'_>,
            x: Idx,
            surface: Idx,
            path: &mut SmallVec<[Edge; 8]>,
            ok: &dyn Fn(&[Edge]) -> bool,
        ) -> bool {
            if !v.sees(x) || path.len() > 4 {
                return false;
            }
            for &e in v.s.out(x).iter().filter(|e| e.rel().is_location()) {
                path.push(e);
                let found = if e.to() == surface && e.rel() == Relation::On && x != v.robot.node {
                    ok(path)
                } else {
                    walk(v, e.to(), surface, path, ok)
                };
                if found {
                    return true;
                }
                path.pop();
            }
            false
        }
        // `path` ends with the edge onto the surface; `o` is at depth path.len() - 1.
        let ok = |path: &[Edge]| match path.len() {
            1..=4 => true,
            5 => holder(path[0].to()),
            _ => false,
        };
        walk(v, o, surface, &mut path, &ok).then_some(path)
    }
}
