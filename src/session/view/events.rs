//! What an episode's page shows of the task's events (docs/dynamic.md): each event where
//! it happened, in words (what the task says it does, what the team was told, why it
//! changed nothing, the optimum proven after it), and the reference the episode is
//! measured against, with the team's recovery from each event.
//!
//! Every text here comes from the task file or the engine's words about it: it is
//! [`shown`] as on a terminal, as everything else of the page.

use coherent_agents::transcript::{Happened, Proof, Recovery, Reference, Round};
use coherent_core::text::{shown, shown_lines};
use coherent_core::{Event, GoalPredicate, Happening, Idx, NodeKind, Relation, Task, Trigger};
use serde::Serialize;

/// An event as it happened (or the end of its span), before a step.
#[derive(Debug, Serialize)]
pub struct EventView {
    /// Its index in the task's `events`.
    pub event: usize,
    pub kind: String,
    /// Whether this is the end of the event's span (a door unlocked, failures over).
    pub ended: bool,
    /// What the task says the event does and when, in words.
    pub what: String,
    /// What the team was told; empty when nothing was.
    pub told: String,
    /// Why the event changed nothing, when it could not happen as written.
    pub void: Option<String>,
    /// The optimum proven from the state it left.
    pub optimum: ProofView,
}

/// An optimum as the planner proved it.
#[derive(Debug, Serialize)]
pub struct ProofView {
    pub steps: Option<u32>,
    pub makespan: Option<u32>,
    pub unreachable: Option<String>,
    pub unknown: Option<String>,
}

/// The reference of an episode with events, and how the team recovered.
#[derive(Debug, Serialize)]
pub struct ReferenceView {
    pub kinds: Vec<String>,
    pub steps: Option<u32>,
    pub unreachable: Option<String>,
    pub start: ProofView,
    pub recoveries: Vec<RecoveryView>,
    /// Events after the last step (they left the goal holding), with no round to show
    /// them in.
    pub closing: Vec<EventView>,
}

/// How the team recovered from one event (or from the end of its span).
#[derive(Debug, Serialize)]
pub struct RecoveryView {
    pub event: usize,
    pub kind: String,
    /// Whether it is the end of the event's span that the team recovered from.
    pub ended: bool,
    pub step: u32,
    pub rounds: Option<u32>,
    pub wasted: u32,
    pub calls: u32,
}

/// What happened before a round, for the page.
pub fn happened(task: &Task, h: &Happened) -> EventView {
    EventView {
        event: h.event,
        kind: shown(&h.kind).into_owned(),
        ended: h.ended,
        what: task
            .events
            .get(h.event)
            .map_or_else(String::new, |e| described(task, e, h.ended)),
        told: shown_lines(&h.told),
        void: h.void.as_deref().map(shown_lines),
        optimum: proof(&h.optimum),
    }
}

/// The reference, for the page; `rounds` tell a recovery from the end of a span.
pub fn reference(task: &Task, r: &Reference, rounds: &[Round]) -> ReferenceView {
    ReferenceView {
        kinds: r.kinds.iter().map(|k| shown(k).into_owned()).collect(),
        steps: r.steps,
        unreachable: r.unreachable.as_deref().map(shown_lines),
        start: proof(&r.start),
        recoveries: r
            .recoveries
            .iter()
            .map(|c| recovery(r, c, rounds))
            .collect(),
        closing: r.closing.iter().map(|h| happened(task, h)).collect(),
    }
}

fn recovery(r: &Reference, c: &Recovery, rounds: &[Round]) -> RecoveryView {
    let ended = rounds
        .iter()
        .filter(|round| round.step == c.step)
        .flat_map(|round| &round.events)
        .any(|h| h.event == c.event && h.ended);
    RecoveryView {
        ended,
        event: c.event,
        kind: r
            .kinds
            .get(c.event)
            .map_or_else(String::new, |k| shown(k).into_owned()),
        step: c.step,
        rounds: c.rounds,
        wasted: c.wasted,
        calls: c.calls,
    }
}

fn proof(p: &Proof) -> ProofView {
    ProofView {
        steps: p.steps,
        makespan: p.makespan,
        unreachable: p.unreachable.as_deref().map(shown_lines),
        unknown: p.unknown.as_deref().map(shown_lines),
    }
}

/// The event `e` of `task` in words: what it does, and when; the end of its span when
/// `ended`.
fn described(task: &Task, e: &Event, ended: bool) -> String {
    let name = |n: Idx| shown(&task.node(n).label()).into_owned();
    let span = |steps: &Option<u32>| match steps {
        Some(1) => " for 1 step".to_owned(),
        Some(n) => format!(" for {n} steps"),
        None => " for good".to_owned(),
    };
    let what = match &e.happening {
        Happening::Blocked { what, .. } if ended => {
            format!("{} open again", doors(task, *what, &name))
        }
        Happening::ActionFails { .. } if ended => "actions no longer fail".to_owned(),
        Happening::RobotDown { robot } => format!("{} goes down", name(*robot)),
        Happening::RobotUp { robot, room } => match room {
            Some(room) => format!("{} joins the team in {}", name(*robot), name(*room)),
            None => format!("{} joins the team", name(*robot)),
        },
        Happening::ObjectMoved {
            thing,
            relation,
            target,
        } => {
            let onto = if *relation == Relation::Inside {
                "into"
            } else {
                "on"
            };
            format!("{} is put {onto} {}", name(*thing), name(*target))
        }
        Happening::GoalChanged { add, remove, .. } => {
            let listed = |ps: &[GoalPredicate]| {
                ps.iter()
                    .map(|p| shown(&task.predicate_label(p)).into_owned())
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let mut parts = Vec::new();
            if !remove.is_empty() {
                parts.push(format!("without {}", listed(remove.as_slice())));
            }
            if !add.is_empty() {
                parts.push(format!("with {}", listed(add.as_slice())));
            }
            format!("the goal changes: {}", parts.join("; "))
        }
        Happening::Blocked { what, steps, .. } => {
            format!("{} locked{}", doors(task, *what, &name), span(steps))
        }
        Happening::ActionFails {
            probability,
            robot,
            steps,
        } => {
            let whose = robot.map_or_else(
                || "each action".to_owned(),
                |r| format!("each action of {}", name(r)),
            );
            format!(
                "{whose} fails with probability {probability}{}",
                span(steps)
            )
        }
    };
    if ended {
        return what;
    }
    let when = match &e.trigger {
        Trigger::Step(n) => format!("before step {n}"),
        Trigger::Held(x) => format!("once a robot holds {}", name(*x)),
        Trigger::Holds(p) => format!("once {} holds", shown(&task.predicate_label(p))),
    };
    format!("{what} ({when})")
}

/// A lock's door, or a room's doors, in words, with the verb that agrees.
fn doors(task: &Task, what: Idx, name: &dyn Fn(Idx) -> String) -> String {
    if task.node(what).kind == NodeKind::Door {
        format!("{} is", name(what))
    } else {
        format!("the doors of {} are", name(what))
    }
}
