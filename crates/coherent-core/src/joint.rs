//! Joint steps: several robots acting in one step, at most one action each
//! (docs/semantics.md, "Parallel steps").
//!
//! A joint step is valid when every action is offered in the state before the step and
//! no two of them interfere: their [`Footprint`]s do not meet (one writes nothing the
//! other reads or writes). Such a step is a forall-step: its actions can be applied in
//! every order, each offered at its turn, and every order ends in the same state, which
//! [`apply`] computes. A step that is not valid is refused as a whole, with a
//! [`Refusal`] that names the actions at fault and, for two that interfere, what they
//! share.

use std::fmt;

use crate::action::Action;
use crate::feasibility::{self, Infeasible, Reason};
use crate::footprint::{self, AtomKind, Conflict, Footprint, Read};
use crate::graph::{Idx, NodeKind, State};
use crate::rules::{self, Contents, View};
use crate::task::{Robot, Task};
use crate::vocab::{PropSet, Relation};

/// One robot's part of a joint step.
pub type Part = (Robot, Action);

/// Two actions of one step that interfere.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Interference {
    /// Positions of the two actions in the step, `first < second`.
    pub first: usize,
    pub second: usize,
    /// What they share: a node of the scene (the robot itself, given two actions).
    pub shared: Idx,
    /// The two actions and what they share, in words.
    pub message: String,
}

/// Why a joint step was refused. Nothing of a refused step is carried out.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// Actions that are not offered to their robots now, by position, with the reason.
    Infeasible(Vec<(usize, Infeasible)>),
    /// Two actions interfere.
    Interference(Interference),
}

impl Refusal {
    /// What part `i` of the refused step tells its robot: its own reason when the fault
    /// is its action, otherwise that the step it was part of was refused.
    pub fn part(&self, i: usize) -> Infeasible {
        match self {
            Refusal::Infeasible(parts) => {
                if let Some((_, why)) = parts.iter().find(|(j, _)| *j == i) {
                    return why.clone();
                }
            }
            Refusal::Interference(x) if x.first == i || x.second == i => {
                return Infeasible {
                    reason: Reason::Interference,
                    message: x.message.clone(),
                };
            }
            Refusal::Interference(_) => {}
        }
        Infeasible {
            reason: Reason::StepRefused,
            message: format!("not carried out: the joint step was refused ({self})"),
        }
    }
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refusal::Infeasible(parts) => {
                let whys: Vec<&str> = parts.iter().map(|(_, why)| why.message.as_str()).collect();
                f.write_str(&whys.join("; "))
            }
            Refusal::Interference(x) => f.write_str(&x.message),
        }
    }
}

/// Checks a joint step in state `s`: `Ok` when every action is offered to its robot and
/// no two interfere; otherwise why not.
pub fn check(task: &Task, s: &State, step: &[Part]) -> Result<(), Refusal> {
    let contents = Contents::new(task, s);
    let views: Vec<View<'_>> = step
        .iter()
        .map(|&(robot, _)| View::with(task, s, robot, &contents))
        .collect();
    let infeasible: Vec<(usize, Infeasible)> = step
        .iter()
        .zip(&views)
        .enumerate()
        .filter(|(_, ((_, a), view))| !view.actions().contains(a))
        .map(|(i, ((robot, a), _))| {
            let why = feasibility::check(task, s, *robot, &a.render(task))
                .err()
                .unwrap_or_else(|| Infeasible {
                    reason: Reason::NotOffered,
                    message: format!("{} is not offered now", a.render(task)),
                });
            (i, why)
        })
        .collect();
    if !infeasible.is_empty() {
        return Err(Refusal::Infeasible(infeasible));
    }
    let prints: Vec<Footprint> = step
        .iter()
        .zip(&views)
        .map(|(&(_, a), view)| footprint::in_view(view, a))
        .collect();
    match interference(task, step, &prints) {
        Some(x) => Err(Refusal::Interference(x)),
        None => Ok(()),
    }
}

/// The first two actions of a step (each offered, with its footprint) that interfere:
/// one robot given two actions, or two footprints that meet.
pub fn interference(task: &Task, step: &[Part], prints: &[Footprint]) -> Option<Interference> {
    for j in 0..step.len() {
        for i in 0..j {
            if step[i].0.node == step[j].0.node {
                let robot = step[i].0.node;
                return Some(Interference {
                    first: i,
                    second: j,
                    shared: robot,
                    message: format!(
                        "{} and {} interfere over the robot {}: it is given two actions in one step",
                        describe(task, step[i]),
                        describe(task, step[j]),
                        task.node(robot).label()
                    ),
                });
            }
            if let Some(c) = prints[i].conflict(&prints[j]) {
                return Some(explain(task, step, i, j, c));
            }
        }
    }
    None
}

/// Applies a valid joint step (see [`check`]): its actions one after the other, which
/// for a valid step gives the state every order gives.
pub fn apply(task: &Task, s: &mut State, step: &[Part]) {
    for &(robot, a) in step {
        rules::apply(task, s, robot, a);
    }
}

/// `<robot dog>(13)'s [grab] <apple>(3)`.
fn describe(task: &Task, (robot, a): Part) -> String {
    format!("{}'s {}", task.node(robot.node).label(), a.render(task))
}

/// The refusal of two actions whose footprints meet in `c`, in words.
fn explain(task: &Task, step: &[Part], i: usize, j: usize, c: Conflict) -> Interference {
    let (writer, other) = if c.swapped { (j, i) } else { (i, j) };
    let robots = [step[i].0.node, step[j].0.node];
    let shared = shared_node(task, c, &robots);
    let label = |n: Idx| task.node(n).label();
    let who = |k: usize| label(step[k].0.node);
    let change = aspect(task, c, shared);
    let consequence = match c.read {
        None => format!("{} changes it the other way", who(other)),
        Some(_) => format!("{}'s action depends on it", who(other)),
    };
    Interference {
        first: i,
        second: j,
        shared,
        message: format!(
            "{} and {} interfere over {}: {} changes {change}, and {consequence}, so the order they ran in would matter",
            describe(task, step[i]),
            describe(task, step[j]),
            what(task, shared),
            who(writer),
        ),
    }
}

/// The node two conflicting actions share: the one the atom and the read have in
/// common, or for an edge both write, its end that is not one of the two robots.
fn shared_node(task: &Task, c: Conflict, robots: &[Idx; 2]) -> Idx {
    match c.atom.kind() {
        AtomKind::States(n) | AtomKind::High(n) => n,
        AtomKind::Edge(e) => {
            let end = match c.read {
                Some(Read::In(n, _)) => n,
                Some(Read::Out(n, _)) => n,
                _ => e.from(),
            };
            let robot =
                |n: Idx| robots.contains(&n) || matches!(task.node(n).kind, NodeKind::Robot(_));
            if robot(end) && !robot(e.to()) {
                e.to()
            } else if robot(end) && !robot(e.from()) {
                e.from()
            } else {
                end
            }
        }
    }
}

/// `the same object <apple>(3)`, `the basket <basket>(12) of <quadrotor>(11)`, ...
fn what(task: &Task, n: Idx) -> String {
    let node = task.node(n);
    let label = node.label();
    match node.kind {
        NodeKind::Door => format!("the door {label}"),
        NodeKind::Room => format!("the room {label}"),
        NodeKind::Floor => format!("the floor {label}"),
        NodeKind::Robot(_) => format!("the robot {label}"),
        NodeKind::Tool => match task
            .robots
            .iter()
            .find(|r| task.basket_of(r.node) == Some(n))
        {
            Some(q) => format!("the basket {label} of {}", task.node(q.node).label()),
            None => format!("the tool {label}"),
        },
        NodeKind::Object if node.properties.contains(PropSet::CONTAINERS) => {
            format!("the same container {label}")
        }
        NodeKind::Object if node.properties.contains(PropSet::SURFACES) => {
            format!("the same surface {label}")
        }
        NodeKind::Object => format!("the same object {label}"),
    }
}

/// What the writer changes about the shared node `n`, in words.
fn aspect(task: &Task, c: Conflict, n: Idx) -> String {
    let label = |n: Idx| task.node(n).label();
    match c.atom.kind() {
        AtomKind::States(x) => match task.node(x).kind {
            NodeKind::Robot(_) => format!("whether {} flies", label(x)),
            _ => format!("whether {} is open", label(x)),
        },
        AtomKind::High(x) => format!("whether {} is on a high surface", label(x)),
        AtomKind::Edge(e) => {
            let (x, t) = (label(e.from()), label(e.to()));
            match e.rel() {
                Relation::On | Relation::Inside if n == e.to() && n != e.from() => {
                    let prep = if e.rel() == Relation::On { "on" } else { "in" };
                    format!("what is {prep} {t}")
                }
                Relation::On | Relation::Inside => format!("where {x} is"),
                Relation::Close => format!("whether {x} is close to {t}"),
                Relation::Hold => format!("whether {x} holds {t}"),
                Relation::Above => format!("where {x} hovers"),
                Relation::LeadingTo | Relation::With => format!("the edge {x} {} {t}", e.rel()),
            }
        }
    }
}
