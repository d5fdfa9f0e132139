//! Observations as text for prompts: what a robot sees, one fact per line, in the
//! world's own vocabulary (`ON(<apple>(3), <table>(5))`), so that a model reads the same
//! relations the rules act on.
//!
//! Two layouts of the same facts: [`facts`] writes them as one block (the paper's
//! layout), [`layered`] in two, the scene's facts that no action changes first and
//! what actions change after, so that a prompt's beginning stays the same from one
//! round to the next and a server's prompt cache can skip it.

use std::fmt::{self, Write};

use crate::graph::{Edge, Idx, NodeKind, RobotKind, State};
use crate::rules::Observation;
use crate::task::Task;
use crate::vocab::{PropSet, Relation, StateSet};

/// Properties that tell a model what it can do with a thing; the others (`MOVABLE`,
/// `HEATABLE`, a task's own names...) only lengthen the prompt.
const USEFUL: PropSet = PropSet(
    PropSet::SURFACES.0
        | PropSet::CONTAINERS.0
        | PropSet::CAN_OPEN.0
        | PropSet::GRABABLE.0
        | PropSet::LANDABLE.0
        | PropSet::HIGH_HEIGHT.0
        | PropSet::LOW_HEIGHT.0
        | PropSet::ON_HIGH_SURFACE.0,
);

/// `observations` merged and written as text: first every thing seen with its useful
/// properties and its states, then every relation between things seen, each once, in a
/// stable order. Rooms come first, and each door seen with the rooms it joins.
pub fn facts(task: &Task, s: &State, observations: &[&Observation]) -> String {
    let (nodes, edges) = merged(observations);
    let mut out = rooms_line(task);
    for &door in nodes
        .iter()
        .filter(|&&n| task.node(n).kind == NodeKind::Door)
    {
        let states = task.vocab.state_names(s.states(door)).join(", ");
        let _ = writeln!(out, "Door {} ({states})", joins(task, door));
    }
    out.push_str("Things seen:\n");
    for &n in &nodes {
        let node = task.node(n);
        if matches!(node.kind, NodeKind::Room | NodeKind::Door) {
            continue;
        }
        let properties = task
            .vocab
            .property_names(PropSet(task.properties(s, n).0 & USEFUL.0));
        let states = task.vocab.state_names(s.states(n));
        item(
            &mut out,
            node.shown_label(),
            properties.into_iter().chain(states),
        );
    }
    out.push_str("Relations:\n");
    for e in edges {
        relation(&mut out, task, e);
    }
    out
}

/// The nodes and the relations (all but `LEADING TO`) of `observations`, each once, in
/// a stable order.
fn merged(observations: &[&Observation]) -> (Vec<Idx>, Vec<Edge>) {
    let mut nodes: Vec<Idx> = observations
        .iter()
        .flat_map(|o| o.nodes.iter().copied())
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let mut edges: Vec<Edge> = observations
        .iter()
        .flat_map(|o| o.edges.iter().copied())
        .filter(|e| e.rel() != Relation::LeadingTo)
        .collect();
    edges.sort_unstable();
    edges.dedup();
    (nodes, edges)
}

/// Every room of the task, seen or not (a robot knows the rooms of its home).
fn rooms_line(task: &Task) -> String {
    let rooms: Vec<String> = task.rooms().iter().map(|&r| task.node(r).label()).collect();
    format!("Rooms: {}\n", rooms.join(", "))
}

/// An observation in two parts: what no action can change, and what actions change.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Layers {
    /// The rooms, the doors seen and the rooms each joins, the things seen that stay in
    /// place with their properties (and the states no action changes), and the
    /// relations between such things.
    pub scene: String,
    /// What actions change: first the things' (the states of doors and containers that
    /// open and close, the things seen that move with their properties and states, and
    /// their relations), then each robot's, in team order (its states, and the
    /// relations of the robot and of its basket), as robots change most often.
    pub state: String,
}

/// `observations` merged, as [`facts`] has them, in two [`Layers`]: each fact of
/// [`facts`] is in one of them (a door's or a container's line is split in two: what it
/// joins or what it is in the scene, its state in the state), and no other.
pub fn layered(task: &Task, s: &State, observations: &[&Observation]) -> Layers {
    let (nodes, edges) = merged(observations);
    // The robot whose part of the state holds `n`'s changing facts: the robot itself,
    // or the quadrotor whose basket it is.
    let owner = |n: Idx| {
        task.robots
            .iter()
            .position(|r| r.node == n || task.basket_of(r.node) == Some(n))
    };
    let mut scene = rooms_line(task);
    let mut things = String::from("Things that move, and states that change:\n");
    let mut robots = vec![String::new(); task.robots.len()];
    scene.push_str("Doors:\n");
    for &door in nodes
        .iter()
        .filter(|&&n| task.node(n).kind == NodeKind::Door)
    {
        let _ = write!(scene, "- {}", joins(task, door));
        let states = task.vocab.state_names(s.states(door));
        if states_change(task, s, door) {
            item(&mut things, task.node(door).shown_label(), states);
            scene.push('\n');
        } else if states.is_empty() {
            scene.push('\n');
        } else {
            let _ = writeln!(scene, " ({})", states.join(", "));
        }
    }
    scene.push_str("Things that stay in place:\n");
    for &n in &nodes {
        let node = task.node(n);
        if matches!(node.kind, NodeKind::Room | NodeKind::Door) {
            continue;
        }
        let changing = match owner(n) {
            Some(r) => &mut robots[r],
            None => &mut things,
        };
        let properties = task
            .vocab
            .property_names(PropSet(task.properties(s, n).0 & USEFUL.0));
        let states = task.vocab.state_names(s.states(n));
        if moves(task, n) {
            item(
                changing,
                node.shown_label(),
                properties.into_iter().chain(states),
            );
        } else if states_change(task, s, n) {
            item(&mut scene, node.shown_label(), properties);
            if !states.is_empty() {
                item(changing, node.shown_label(), states);
            }
        } else {
            item(
                &mut scene,
                node.shown_label(),
                properties.into_iter().chain(states),
            );
        }
    }
    scene.push_str("Where they stand:\n");
    things.push_str("Their relations now:\n");
    for e in edges {
        if fixed(task, e) {
            relation(&mut scene, task, e);
        } else {
            match owner(e.from()) {
                Some(r) => relation(&mut robots[r], task, e),
                None => relation(&mut things, task, e),
            }
        }
    }
    things.push_str("The robots now:\n");
    things.extend(robots);
    Layers {
        scene,
        state: things,
    }
}

/// `<door>(8) joins <bedroom>(0) and <livingroom>(4)`.
fn joins(task: &Task, door: Idx) -> String {
    let rooms: Vec<String> = task
        .doors()
        .iter()
        .filter(|&&(d, _)| d == door)
        .map(|&(_, r)| task.node(r).label())
        .collect();
    format!("{} joins {}", task.node(door).label(), rooms.join(" and "))
}

/// `- ON(<apple>(3), <table>(5))`.
fn relation(out: &mut String, task: &Task, e: Edge) {
    let _ = writeln!(
        out,
        "- {}({}, {})",
        e.rel().name(),
        task.node(e.from()).shown_label(),
        task.node(e.to()).shown_label()
    );
}

/// `- <label>` or `- <label>: WORD, WORD`.
fn item(out: &mut String, label: impl fmt::Display, words: impl IntoIterator<Item = String>) {
    let _ = write!(out, "- {label}");
    let mut separator = ": ";
    for word in words {
        out.push_str(separator);
        out.push_str(&word);
        separator = ", ";
    }
    out.push('\n');
}

/// Whether an action can move `n` (change what it stands on or is in, or whether it is
/// on a high surface): the robots that walk or fly, a quadrotor's basket, and what can
/// be grabbed. Rooms, floors, doors, furniture and the arms fixed on it stay where the
/// task put them (docs/semantics.md, "Actions").
pub fn moves(task: &Task, n: Idx) -> bool {
    let node = task.node(n);
    match node.kind {
        NodeKind::Robot(RobotKind::Quadrotor | RobotKind::RobotDog) | NodeKind::Tool => true,
        NodeKind::Robot(RobotKind::RobotArm) | NodeKind::Room | NodeKind::Floor => false,
        NodeKind::Door => false,
        NodeKind::Object => node.properties.contains(PropSet::GRABABLE),
    }
}

/// Whether an action can change `n`'s states: a robot's (a quadrotor lands and takes
/// off), and those of a door or a container that is open or closed (opening and closing
/// set them); `OPEN_FOREVER` and the states of anything else stay as they are.
pub fn states_change(task: &Task, s: &State, n: Idx) -> bool {
    matches!(task.node(n).kind, NodeKind::Robot(_))
        || s.states(n).intersects(StateSet::OPEN | StateSet::CLOSED)
}

/// Whether no action can change relation `e`: a location (`ON`, `INSIDE`) or `WITH`
/// between two things that stay in place. Holding, being close and hovering above are
/// robots' and change as they act.
pub fn fixed(task: &Task, e: Edge) -> bool {
    matches!(e.rel(), Relation::On | Relation::Inside | Relation::With)
        && !moves(task, e.from())
        && !moves(task, e.to())
}
