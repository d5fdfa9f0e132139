//! What a robot can get at: whether an action of its list names a thing now, whether it
//! could after moves of its own (walking, flying, taking off, landing, opening a door),
//! and, when it cannot, the feasibility reason that stops it. PEFA's feedback explains
//! a declined subtask with these: for each thing the subtask names, why its robot cannot
//! act on it and which robot of the team could.

use std::collections::{HashSet, VecDeque};

use crate::action::{self, Action, Verb};
use crate::feasibility::{Infeasible, Reason, diagnose, hand_reach};
use crate::graph::{Edge, Idx, NodeKind, RobotKind, State};
use crate::rules::{self, Contents, View};
use crate::task::{Robot, Task};
use crate::vocab::{PropSet, Relation};

/// The most moves of its own a robot is given to get at a thing: enough to cross the
/// released scenes (take off, fly through two rooms, move towards a surface, land).
pub const MAX_MOVES: u32 = 8;

/// The most states one search visits; a robot's own moves reach a few dozen.
const MAX_STATES: usize = 4096;

/// Whether a robot can get at a thing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reach {
    /// An action of its list names the thing now (or would, for a surface or a container
    /// within reach, once it holds something to put there).
    Now,
    /// After this many moves of its own (a robot whose hand is full counts one to put
    /// down what it holds).
    After(u32),
    /// Not by its own moves, within [`MAX_MOVES`].
    Never,
}

/// The things a text names as `<name>(id)` (a subtask, say): each node of `task` whose
/// id and name both match, in the order written, robots left out.
pub fn things_named(task: &Task, text: &str) -> Vec<Idx> {
    action::mentions(text)
        .into_iter()
        .filter_map(|m| {
            let n = task.idx(m.id)?;
            let node = task.node(n);
            (node.class_name == m.name && !matches!(node.kind, NodeKind::Robot(_))).then_some(n)
        })
        .collect()
}

/// Whether `robot` can get at `x` from state `s`: act on it, or, for a quadrotor, on the
/// surface a thing that can be grabbed stands on (a quadrotor cannot grab; it gets at
/// such a thing by landing where it is, to carry it in its basket), or carry it in its
/// basket already.
pub fn reach(task: &Task, s: &State, robot: Robot, x: Idx) -> Reach {
    let mut targets = vec![x];
    if let Some(basket) = task.basket_of(robot.node) {
        if s.has(Edge::new(x, Relation::Inside, basket)) {
            return Reach::Now;
        }
        if task.node(x).properties.contains(PropSet::GRABABLE) {
            targets.extend(s.targets(x, Relation::On));
        }
    }
    search(task, s, robot, &targets).found
}

/// Why `robot` cannot act on `x` in state `s`, or `None` when an action of its list names
/// it: the engine's reason for one of its verbs with `x` (as the object, or as where to
/// put what it holds). When its own moves would get it there, the reason is one of now
/// (it must first move, land, open a door...); when they would not, the reason that
/// stops it wherever it goes (too high, out of reach, not something it can land on...).
pub fn why_not(task: &Task, s: &State, robot: Robot, x: Idx) -> Option<Infeasible> {
    let found = search(task, s, robot, &[x]);
    match found.found {
        Reach::Now => None,
        Reach::After(_) => best(found.now, |r| Class::of(r).when_reachable()),
        Reach::Never => best(found.anywhere, |r| Class::of(r).when_out_of_reach()),
    }
}

/// What a search over a robot's own moves found.
struct Found {
    found: Reach,
    /// The reasons of its verbs on the thing in the state it started from.
    now: Vec<Infeasible>,
    /// The same, in every state it visited, nearest first.
    anywhere: Vec<Infeasible>,
}

/// Breadth first over `robot`'s own moves from `s`, until an action of its list names one
/// of `targets` (or only its full hand stops it), [`MAX_MOVES`] moves or [`MAX_STATES`]
/// states.
fn search(task: &Task, s: &State, robot: Robot, targets: &[Idx]) -> Found {
    let mut seen: HashSet<State> = HashSet::from([s.clone()]);
    let mut queue: VecDeque<(State, u32)> = VecDeque::from([(s.clone(), 0)]);
    let mut now = Vec::new();
    let mut anywhere = Vec::new();
    while let Some((state, depth)) = queue.pop_front() {
        let contents = Contents::new(task, &state);
        let view = View::with(task, &state, robot, &contents);
        let offered = view.actions();
        let named = |x: Idx| offered.iter().any(|a| a.object == x || a.target == Some(x));
        if targets
            .iter()
            .any(|&x| named(x) || hand_only(task, &view, x))
        {
            let found = if depth == 0 {
                Reach::Now
            } else {
                Reach::After(depth)
            };
            return Found {
                found,
                now,
                anywhere,
            };
        }
        let reasons: Vec<Infeasible> = targets
            .iter()
            .flat_map(|&x| {
                let tried = candidates(task, &view, x)
                    .into_iter()
                    .filter(|a| !offered.contains(a))
                    .map(|a| diagnose(&view, a));
                tried.chain(hand_reach(&view, x))
            })
            .collect();
        if depth == 0 {
            now.clone_from(&reasons);
        }
        if reasons.iter().any(|r| r.reason == Reason::HandFull) {
            return Found {
                found: Reach::After(depth + 1),
                now,
                anywhere,
            };
        }
        anywhere.extend(reasons);
        if depth < MAX_MOVES {
            for a in offered.into_iter().filter(|a| own_move(task, a)) {
                let mut next = state.clone();
                rules::apply(task, &mut next, robot, a);
                if seen.len() < MAX_STATES && seen.insert(next.clone()) {
                    queue.push_back((next, depth + 1));
                }
            }
        }
    }
    Found {
        found: Reach::Never,
        now,
        anywhere,
    }
}

/// Whether only an empty hand keeps the robot from `x`: a surface or a container within
/// its hand's reach, to put something on or into once it holds something (which counts
/// as acting on it).
fn hand_only(task: &Task, view: &View<'_>, x: Idx) -> bool {
    view.holding.is_none()
        && view.robot.kind != RobotKind::Quadrotor
        && (task.has(view.s, x, PropSet::SURFACES) || task.has(view.s, x, PropSet::CONTAINERS))
        && hand_reach(view, x).is_none()
}

/// A move of the robot's own: it goes somewhere (walks, flies, takes off, lands) or opens
/// a door on its way. Grabbing and putting change the world, not where the robot is.
fn own_move(task: &Task, a: &Action) -> bool {
    match a.verb {
        Verb::MoveTowards | Verb::TakeoffFrom | Verb::LandOn => true,
        Verb::Open => task.node(a.object).kind == NodeKind::Door,
        _ => false,
    }
}

/// The robot's verbs with `x`, moving towards it first: `x` as the object of each, `x` as
/// where to put what it holds, and, when `x` is in another room than the robot, moving
/// into each room next to it (a closed door on the way says why it cannot go).
fn candidates(task: &Task, view: &View<'_>, x: Idx) -> Vec<Action> {
    let verbs = Verb::of(view.robot.kind);
    let mut out: Vec<Action> = verbs
        .iter()
        .filter(|&&v| v == Verb::MoveTowards)
        .chain(verbs.iter().filter(|&&v| v != Verb::MoveTowards))
        .filter_map(|&verb| match verb {
            Verb::PutInto | Verb::PutOn => view
                .holding
                .filter(|&h| h != x)
                .map(|h| Action::with_target(verb, h, x)),
            _ => Some(Action::new(verb, x)),
        })
        .collect();
    let room = room_around(task, view.s, x);
    if verbs.contains(&Verb::MoveTowards) && room.is_some() && room != view.room {
        out.extend(
            view.next_rooms()
                .map(|(next, _)| Action::new(Verb::MoveTowards, next)),
        );
    }
    out
}

/// The room `x` is in, through what it stands on or is in (a cup on a table on a floor
/// inside a kitchen); `x` itself when it is a room.
fn room_around(task: &Task, s: &State, x: Idx) -> Option<Idx> {
    let mut at = x;
    for _ in 0..task.nodes.len() {
        if task.node(at).kind == NodeKind::Room {
            return Some(at);
        }
        at = s
            .out(at)
            .iter()
            .find(|e| e.rel().is_location())
            .map(|e| e.to())?;
    }
    None
}

/// What a reason is about, which says how much it tells.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Class {
    /// The robot cannot get there: too high, out of a fixed arm's reach, no door.
    Reach,
    /// The thing is not one the verb applies to (not grabable, not landable...).
    Kind,
    /// The hand or the thing's state: full, empty, closed, open already.
    Hand,
    /// A closed door on the way.
    Way,
    /// Where the robot is: not in view, not close, not above.
    Place,
    Other,
}

impl Class {
    fn of(r: Reason) -> Class {
        match r {
            Reason::TooHigh | Reason::OutOfReach | Reason::NoDoor | Reason::Misplaced => {
                Class::Reach
            }
            Reason::NotGrabable
            | Reason::NotContainer
            | Reason::NotSurface
            | Reason::NotOpenable
            | Reason::NotLandable
            | Reason::NotATarget
            | Reason::AlwaysOpen
            | Reason::WrongRobotType => Class::Kind,
            Reason::HandFull
            | Reason::HandEmpty
            | Reason::NotHolding
            | Reason::ContainerClosed
            | Reason::AlreadyOpen
            | Reason::AlreadyClosed => Class::Hand,
            Reason::DoorClosed => Class::Way,
            Reason::NotInView
            | Reason::NotClose
            | Reason::NotAbove
            | Reason::NotFlying
            | Reason::NotLanded
            | Reason::NotOnSurface
            | Reason::AlreadyThere => Class::Place,
            _ => Class::Other,
        }
    }

    /// The order when the robot's own moves get it there: what it must do first (move,
    /// land, open) tells most, what the verb applies to least.
    fn when_reachable(self) -> u8 {
        match self {
            Class::Place | Class::Way => 0,
            Class::Hand => 1,
            Class::Reach => 2,
            Class::Kind => 3,
            Class::Other => 4,
        }
    }

    /// The order when they do not: what no move of its own changes (too high, out of
    /// reach), then what the verb applies to, then a closed door it cannot pass.
    fn when_out_of_reach(self) -> u8 {
        match self {
            Class::Reach => 0,
            Class::Kind => 1,
            Class::Way => 2,
            Class::Hand => 3,
            Class::Place => 4,
            Class::Other => 5,
        }
    }
}

/// The first reason of the lowest rank.
fn best(reasons: Vec<Infeasible>, rank: impl Fn(Reason) -> u8) -> Option<Infeasible> {
    reasons
        .into_iter()
        .enumerate()
        .min_by_key(|(i, r)| (rank(r.reason), *i))
        .map(|(_, r)| r)
}
