//! Events: what happens to the world mid-task that the team did not do (docs/dynamic.md).
//! A task's `events` list each one with when it happens (at a step, or when a condition
//! first holds) and what it does: a robot breaks down or joins the team, a thing is
//! moved by someone outside the team, the goal changes, a door is locked, actions fail.
//! This module reads them from a task file (or a file of their own) and writes them
//! back; `crate::schedule` runs them along an episode.

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{Result, Site, ensure, quoted};
use crate::graph::{Idx, NodeId, NodeKind, RobotKind};
pub use crate::task::{Event, Happening, Trigger};
use crate::task::{GoalPredicate, Task};
use crate::vocab::{PropSet, Relation};

/// The kinds of event, as task files name them.
pub const KINDS: [&str; 6] = [
    "robot_down",
    "robot_up",
    "object_moved",
    "goal_changed",
    "blocked",
    "action_fails",
];

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawEvent {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    step: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    when: Option<RawCondition>,
    kind: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    robot: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    room: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    door: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    thing: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    relation: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    target: Option<i64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    add: Vec<RawPredicate>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    remove: Vec<RawPredicate>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    instruction: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    steps: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    probability: Option<f64>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawCondition {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    held: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    relation: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    subject: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    target: Option<i64>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawPredicate {
    relation: String,
    subject: i64,
    target: i64,
}

/// Reads an `events` list (`value`, read at `site`) against `task`: every robot, thing,
/// door and room named must be the task's and of the right kind, every predicate over
/// its nodes. The step budget is checked when an episode's is known
/// ([`last_step`]).
pub fn read(task: &Task, value: &Value, file: &str, path: crate::JsonPath) -> Result<Vec<Event>> {
    let site = Site::new(file, path);
    let raw: Vec<RawEvent> = crate::json::from_value(value, &site)?;
    let mut events = Vec::with_capacity(raw.len());
    for (i, r) in raw.iter().enumerate() {
        events.push(read_one(task, r, &site.index(i))?);
    }
    check_robots_once(task, &events, &site)?;
    check_removals(task, &events, &site)?;
    Ok(events)
}

/// The node of id `id`, read at `at`, when `ok` says it is of the right kind (`what`).
fn node_of(
    task: &Task,
    id: Option<i64>,
    at: &Site<'_>,
    what: &str,
    ok: impl Fn(&Task, Idx) -> bool,
) -> Result<Idx> {
    let Some(id) = id else {
        return Err(at.error(format!("missing: the event needs {what}")));
    };
    let n = task
        .idx(NodeId(id))
        .ok_or_else(|| at.error(format!("unknown node id {id}: the task has no such node")))?;
    ensure!(
        ok(task, n),
        at,
        "node {id} ({}) is not {what}",
        task.node(n).shown_label()
    );
    Ok(n)
}

fn is_robot(task: &Task, n: Idx) -> bool {
    matches!(task.node(n).kind, NodeKind::Robot(_))
}

fn relation(name: &str, at: &Site<'_>) -> Result<Relation> {
    match name {
        "ON" => Ok(Relation::On),
        "INSIDE" => Ok(Relation::Inside),
        other => Err(at.error(format!(
            "relation {}: expected \"ON\" or \"INSIDE\"",
            quoted(other)
        ))),
    }
}

fn predicate(task: &Task, p: &RawPredicate, at: &Site<'_>) -> Result<GoalPredicate> {
    let any = |_: &Task, _: Idx| true;
    Ok(GoalPredicate {
        relation: relation(&p.relation, &at.key("relation"))?,
        subject: node_of(task, Some(p.subject), &at.key("subject"), "a node", any)?,
        target: node_of(task, Some(p.target), &at.key("target"), "a node", any)?,
        count: 1,
    })
}

fn read_one(task: &Task, r: &RawEvent, at: &Site<'_>) -> Result<Event> {
    let trigger = match (r.step, &r.when) {
        (Some(0), _) => return Err(at.key("step").error("step 0: steps count from 1")),
        (Some(n), None) => Trigger::Step(n),
        (None, Some(c)) => condition(task, c, &at.key("when"))?,
        (Some(_), Some(_)) => {
            return Err(at.error("both `step` and `when`: an event has one of them"));
        }
        (None, None) => return Err(at.error("neither `step` nor `when`: when does it happen?")),
    };
    let known = [
        ("robot", r.robot.is_some()),
        ("room", r.room.is_some()),
        ("door", r.door.is_some()),
        ("thing", r.thing.is_some()),
        ("relation", r.relation.is_some()),
        ("target", r.target.is_some()),
        ("add", !r.add.is_empty()),
        ("remove", !r.remove.is_empty()),
        ("instruction", r.instruction.is_some()),
        ("steps", r.steps.is_some()),
        ("probability", r.probability.is_some()),
    ];
    let allowed: &[&str] = match r.kind.as_str() {
        "robot_down" => &["robot"],
        "robot_up" => &["robot", "room"],
        "object_moved" => &["thing", "relation", "target"],
        "goal_changed" => &["add", "remove", "instruction"],
        "blocked" => &["door", "room", "steps"],
        "action_fails" => &["probability", "robot", "steps"],
        other => {
            return Err(at.key("kind").error(format!(
                "unknown event kind {}: known kinds are {}",
                quoted(other),
                KINDS.join(", ")
            )));
        }
    };
    if let Some((field, _)) = known.iter().find(|(f, set)| *set && !allowed.contains(f)) {
        return Err(at.key(field).error(format!(
            "a {} event has no `{field}` (its fields: {})",
            r.kind,
            allowed.join(", ")
        )));
    }
    if r.steps == Some(0) {
        return Err(at
            .key("steps")
            .error("steps 0: a span lasts at least one step (leave it out for good)"));
    }
    let happening = happening(task, r, at)?;
    Ok(Event { trigger, happening })
}

/// What event `r` (read at `at`, its kind and fields checked) does.
fn happening(task: &Task, r: &RawEvent, at: &Site<'_>) -> Result<Happening> {
    let robot = |what| node_of(task, r.robot, &at.key("robot"), what, is_robot);
    Ok(match r.kind.as_str() {
        "robot_down" => Happening::RobotDown {
            robot: robot("a robot")?,
        },
        "robot_up" => {
            let robot = robot("a robot")?;
            let room = match r.room {
                None => None,
                Some(_) => {
                    ensure!(
                        task.node(robot).kind != NodeKind::Robot(RobotKind::RobotArm),
                        at.key("room"),
                        "robot {} is an arm, fixed where the task mounts it: it joins there",
                        task.id(robot)
                    );
                    Some(node_of(task, r.room, &at.key("room"), "a room", |t, n| {
                        t.node(n).kind == NodeKind::Room
                    })?)
                }
            };
            Happening::RobotUp { robot, room }
        }
        "object_moved" => {
            let thing = node_of(
                task,
                r.thing,
                &at.key("thing"),
                "a thing to grab",
                |t, n| {
                    t.node(n).kind == NodeKind::Object
                        && t.node(n).properties.contains(PropSet::GRABABLE)
                },
            )?;
            let Some(name) = &r.relation else {
                return Err(at.key("relation").error("missing: \"ON\" or \"INSIDE\""));
            };
            let relation = relation(name, &at.key("relation"))?;
            let (prop, what) = match relation {
                Relation::On => (PropSet::SURFACES, "a surface (SURFACES)"),
                _ => (PropSet::CONTAINERS, "a container (CONTAINERS)"),
            };
            let target = node_of(task, r.target, &at.key("target"), what, |t, n| {
                t.node(n).properties.contains(prop) && n != thing
            })?;
            Happening::ObjectMoved {
                thing,
                relation,
                target,
            }
        }
        "goal_changed" => {
            let preds = |list: &[RawPredicate], key| {
                list.iter()
                    .enumerate()
                    .map(|(i, p)| predicate(task, p, &at.key(key).index(i)))
                    .collect::<Result<Vec<_>>>()
            };
            let instruction = r.instruction.clone().unwrap_or_default();
            ensure!(
                !instruction.trim().is_empty(),
                at.key("instruction"),
                "missing: a changed goal comes with the instruction's new wording"
            );
            let (add, remove) = (preds(&r.add, "add")?, preds(&r.remove, "remove")?);
            ensure!(
                !add.is_empty() || !remove.is_empty(),
                at,
                "a goal_changed event adds or removes at least one predicate"
            );
            Happening::GoalChanged {
                add,
                remove,
                instruction,
            }
        }
        "blocked" => {
            let (what, doors) = match (r.door, r.room) {
                (Some(_), None) => {
                    let door = node_of(task, r.door, &at.key("door"), "a door", |t, n| {
                        t.node(n).kind == NodeKind::Door
                    })?;
                    (door, vec![door])
                }
                (None, Some(_)) => {
                    let room = node_of(task, r.room, &at.key("room"), "a room", |t, n| {
                        t.node(n).kind == NodeKind::Room
                    })?;
                    let doors: Vec<Idx> = task
                        .doors()
                        .iter()
                        .filter(|&&(_, to)| to == room)
                        .map(|&(d, _)| d)
                        .collect();
                    ensure!(
                        !doors.is_empty(),
                        at.key("room"),
                        "room {} has no door to lock",
                        task.id(room)
                    );
                    (room, doors)
                }
                _ => return Err(at.error("a blocked event names one `door` or one `room`")),
            };
            Happening::Blocked {
                what,
                doors,
                steps: r.steps,
            }
        }
        _ => {
            let p = r.probability.unwrap_or(f64::NAN);
            ensure!(
                p > 0.0 && p <= 1.0,
                at.key("probability"),
                "probability {}: a chance above 0 and at most 1",
                r.probability
                    .map_or("missing".to_owned(), |p| p.to_string())
            );
            let robot = r.robot.map(|_| robot("a robot")).transpose()?;
            Happening::ActionFails {
                probability: p,
                robot,
                steps: r.steps,
            }
        }
    })
}

fn condition(task: &Task, c: &RawCondition, at: &Site<'_>) -> Result<Trigger> {
    match (c.held, &c.relation) {
        (Some(_), None) if c.subject.is_none() && c.target.is_none() => {
            let thing = node_of(task, c.held, &at.key("held"), "a thing to grab", |t, n| {
                t.node(n).properties.contains(PropSet::GRABABLE)
            })?;
            Ok(Trigger::Held(thing))
        }
        (None, Some(rel)) => {
            let p = RawPredicate {
                relation: rel.clone(),
                subject: c
                    .subject
                    .ok_or_else(|| at.key("subject").error("missing"))?,
                target: c.target.ok_or_else(|| at.key("target").error("missing"))?,
            };
            Ok(Trigger::Holds(predicate(task, &p, at)?))
        }
        _ => Err(at.error(
            "a condition is {\"held\": ID} or {\"relation\": ..., \"subject\": ID, \"target\": ID}",
        )),
    }
}

/// A robot goes down at most once and joins at most once, and not both: a robot that
/// joins was out of the team, and one that goes down is gone for good.
fn check_robots_once(task: &Task, events: &[Event], site: &Site<'_>) -> Result<()> {
    let mut seen: Vec<(Idx, usize)> = Vec::new();
    for (i, e) in events.iter().enumerate() {
        let (Happening::RobotDown { robot } | Happening::RobotUp { robot, .. }) = e.happening
        else {
            continue;
        };
        if let Some(&(_, first)) = seen.iter().find(|(r, _)| *r == robot) {
            return Err(site.index(i).key("robot").error(format!(
                "robot {} already goes down or joins at events[{first}]: a robot that joins \
                 was out of the team, one that goes down is gone for good",
                task.id(robot)
            )));
        }
        seen.push((robot, i));
    }
    Ok(())
}

/// A predicate removed from the goal must be in it: in the task's goal, or added by an
/// event.
fn check_removals(task: &Task, events: &[Event], site: &Site<'_>) -> Result<()> {
    let added: Vec<&GoalPredicate> = events
        .iter()
        .filter_map(|e| match &e.happening {
            Happening::GoalChanged { add, .. } => Some(add),
            _ => None,
        })
        .flatten()
        .collect();
    for (i, e) in events.iter().enumerate() {
        let Happening::GoalChanged { remove, .. } = &e.happening else {
            continue;
        };
        for (j, p) in remove.iter().enumerate() {
            let same = |q: &&GoalPredicate| {
                (q.relation, q.subject, q.target) == (p.relation, p.subject, p.target)
            };
            ensure!(
                task.goal.iter().any(|q| same(&q)) || added.iter().any(same),
                site.index(i).key("remove").index(j),
                "{} is not in the goal, nor added by an event",
                task.predicate_label(p)
            );
        }
    }
    Ok(())
}

/// The events of a task as its file writes them.
pub fn to_value(task: &Task) -> Value {
    let id = |n: Idx| task.id(n).0;
    let pred = |p: &GoalPredicate| RawPredicate {
        relation: p.relation.name().to_owned(),
        subject: id(p.subject),
        target: id(p.target),
    };
    let raw: Vec<RawEvent> = task
        .events
        .iter()
        .map(|e| {
            let mut r = RawEvent {
                step: None,
                when: None,
                kind: e.happening.kind().to_owned(),
                robot: None,
                room: None,
                door: None,
                thing: None,
                relation: None,
                target: None,
                add: Vec::new(),
                remove: Vec::new(),
                instruction: None,
                steps: None,
                probability: None,
            };
            match &e.trigger {
                Trigger::Step(n) => r.step = Some(*n),
                Trigger::Held(x) => {
                    r.when = Some(RawCondition {
                        held: Some(id(*x)),
                        relation: None,
                        subject: None,
                        target: None,
                    });
                }
                Trigger::Holds(p) => {
                    r.when = Some(RawCondition {
                        held: None,
                        relation: Some(p.relation.name().to_owned()),
                        subject: Some(id(p.subject)),
                        target: Some(id(p.target)),
                    });
                }
            }
            match &e.happening {
                Happening::RobotDown { robot } => r.robot = Some(id(*robot)),
                Happening::RobotUp { robot, room } => {
                    r.robot = Some(id(*robot));
                    r.room = room.map(id);
                }
                Happening::ObjectMoved {
                    thing,
                    relation,
                    target,
                } => {
                    r.thing = Some(id(*thing));
                    r.relation = Some(relation.name().to_owned());
                    r.target = Some(id(*target));
                }
                Happening::GoalChanged {
                    add,
                    remove,
                    instruction,
                } => {
                    r.add = add.iter().map(pred).collect();
                    r.remove = remove.iter().map(pred).collect();
                    r.instruction = Some(instruction.clone());
                }
                Happening::Blocked { what, steps, .. } => {
                    if task.node(*what).kind == NodeKind::Door {
                        r.door = Some(id(*what));
                    } else {
                        r.room = Some(id(*what));
                    }
                    r.steps = *steps;
                }
                Happening::ActionFails {
                    probability,
                    robot,
                    steps,
                } => {
                    r.probability = Some(*probability);
                    r.robot = robot.map(id);
                    r.steps = *steps;
                }
            }
            r
        })
        .collect();
    serde_json::to_value(raw).expect("plain data always serializes")
}

/// The latest step an event names (its `step`, and the end of its span), so that a
/// budget can be checked against it: `(index of the event, step)`.
pub fn last_step(events: &[Event]) -> Option<(usize, u32)> {
    events
        .iter()
        .enumerate()
        .filter_map(|(i, e)| match e.trigger {
            Trigger::Step(n) => Some((i, n)),
            _ => None,
        })
        .max_by_key(|&(_, n)| n)
}
