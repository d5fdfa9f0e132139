//! Observations as text for prompts: what a robot sees, one fact per line, in the
//! world's own vocabulary (`ON(<apple>(3), <table>(5))`), so that a model reads the same
//! relations the rules act on.

use std::fmt::Write;

use crate::graph::{Idx, NodeKind, State};
use crate::rules::Observation;
use crate::task::Task;
use crate::vocab::{PropSet, Relation};

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
    let mut nodes: Vec<Idx> = observations
        .iter()
        .flat_map(|o| o.nodes.iter().copied())
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let mut edges: Vec<_> = observations
        .iter()
        .flat_map(|o| o.edges.iter().copied())
        .filter(|e| e.rel() != Relation::LeadingTo)
        .collect();
    edges.sort_unstable();
    edges.dedup();

    let mut out = String::new();
    let rooms: Vec<String> = task.rooms().iter().map(|&r| task.node(r).label()).collect();
    let _ = writeln!(out, "Rooms: {}", rooms.join(", "));
    for &door in nodes
        .iter()
        .filter(|&&n| task.node(n).kind == NodeKind::Door)
    {
        let joins: Vec<String> = task
            .doors()
            .iter()
            .filter(|&&(d, _)| d == door)
            .map(|&(_, r)| task.node(r).label())
            .collect();
        let states = task.vocab.state_names(s.states(door)).join(", ");
        let _ = writeln!(
            out,
            "Door {} joins {} ({states})",
            task.node(door).label(),
            joins.join(" and ")
        );
    }
    out.push_str("Things seen:\n");
    for &n in &nodes {
        let node = task.node(n);
        if matches!(node.kind, NodeKind::Room | NodeKind::Door) {
            continue;
        }
        let mut words = task
            .vocab
            .property_names(PropSet(task.properties(s, n).0 & USEFUL.0));
        words.extend(task.vocab.state_names(s.states(n)));
        if words.is_empty() {
            let _ = writeln!(out, "- {}", node.label());
        } else {
            let _ = writeln!(out, "- {}: {}", node.label(), words.join(", "));
        }
    }
    out.push_str("Relations:\n");
    for e in edges {
        let _ = writeln!(
            out,
            "- {}({}, {})",
            e.rel().name(),
            task.node(e.from()).label(),
            task.node(e.to()).label()
        );
    }
    out
}
