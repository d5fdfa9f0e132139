//! A task's events along one episode (docs/dynamic.md): before each step, [`Schedule`]
//! says which are due and puts the world in the state they leave it in: a variant of the
//! task (its team, goal, instruction and passable doors, `Task::vary`) and an edited
//! state. Failing actions are a chance the schedule names
//! ([`Schedule::failure_chance`]); the draw is the episode's.

use crate::graph::{Edge, Idx, NodeKind, NodeSet, RobotKind, State};
use crate::task::{GoalPredicate, Happening, Robot, Task, Trigger, predicate_holds};
use crate::vocab::{PropSet, Relation, StateSet};

/// What the schedule did before a step: an event that happened (its index in the task's
/// list), or the end of one's span (a door unlocked, failures over).
#[derive(Clone, Debug, PartialEq)]
pub struct Change {
    /// The event's index in the task's `events`.
    pub event: usize,
    /// Whether this is the end of the event's span rather than the event itself.
    pub ended: bool,
    /// What the team is told, in a sentence; empty when nothing is told (failing
    /// actions are noticed when they fail).
    pub told: String,
    /// Why the event changed nothing, when it could not happen as written (a thing
    /// moved into something standing on it).
    pub void: Option<String>,
}

/// A task's events along one episode: which have happened, which spans run, and the
/// world they leave.
#[derive(Clone, Debug)]
pub struct Schedule {
    base: std::sync::Arc<Task>,
    fired: Vec<bool>,
    /// Robots out of the team: not joined yet, or down.
    out: NodeSet,
    goal: Vec<GoalPredicate>,
    instruction: String,
    /// Locked doors, each with the step its lock ends before (`None`: for good) and
    /// the event that locked it.
    locked: Vec<(Idx, Option<u32>, usize)>,
    /// Failing actions: chance, robot, end step, event.
    failing: Vec<(f64, Option<Idx>, Option<u32>, usize)>,
}

impl Schedule {
    /// The schedule at the start: the robots that join later are out of the team.
    pub fn new(base: std::sync::Arc<Task>) -> Schedule {
        let mut out = NodeSet::new(base.nodes.len());
        for e in &base.events {
            if let Happening::RobotUp { robot, .. } = e.happening {
                out.insert(robot);
            }
        }
        Schedule {
            fired: vec![false; base.events.len()],
            goal: base.goal.clone(),
            instruction: base.meta.instruction.clone(),
            out,
            locked: Vec::new(),
            failing: Vec::new(),
            base,
        }
    }

    /// The task as the events have left it: its team, goal, instruction and doors.
    /// The task itself when nothing has changed it.
    pub fn world(&self) -> std::sync::Arc<Task> {
        let unchanged = self.out.iter().next().is_none()
            && self.locked.is_empty()
            && self.goal == self.base.goal
            && self.instruction == self.base.meta.instruction;
        if unchanged {
            return std::sync::Arc::clone(&self.base);
        }
        let team: Vec<Robot> = self
            .base
            .robots
            .iter()
            .filter(|r| !self.out.contains(r.node))
            .copied()
            .collect();
        let locked: Vec<Idx> = self.locked.iter().map(|&(d, ..)| d).collect();
        std::sync::Arc::new(
            self.base
                .vary(team, self.goal.clone(), &self.instruction, &locked),
        )
    }

    /// The events due before step `step` in state `s` (and the spans that end there),
    /// carried out on `s`; in the order of the task's list, spans' ends first. An event
    /// happens once.
    pub fn before_step(&mut self, step: u32, s: &mut State) -> Vec<Change> {
        let mut changes = Vec::new();
        self.end_spans(step, &mut changes);
        for i in 0..self.base.events.len() {
            if self.fired[i] {
                continue;
            }
            let due = match &self.base.events[i].trigger {
                Trigger::Step(n) => *n == step,
                Trigger::Held(x) => s.sources(Relation::Hold, *x).next().is_some(),
                Trigger::Holds(p) => predicate_holds(s, p),
            };
            if due {
                self.fired[i] = true;
                changes.push(self.happen(i, step, s));
            }
        }
        changes
    }

    fn end_spans(&mut self, step: u32, changes: &mut Vec<Change>) {
        let task = std::sync::Arc::clone(&self.base);
        let mut ended: Vec<usize> = Vec::new();
        self.locked.retain(|&(_, until, i)| {
            let over = until == Some(step);
            if over && !ended.contains(&i) {
                ended.push(i);
            }
            !over
        });
        for &i in &ended {
            let Happening::Blocked { what, .. } = task.events[i].happening else {
                continue;
            };
            changes.push(Change {
                event: i,
                ended: true,
                told: format!("{} can be passed again.", task.node(what).label()),
                void: None,
            });
        }
        self.failing.retain(|&(_, _, until, i)| {
            let over = until == Some(step);
            if over {
                changes.push(Change {
                    event: i,
                    ended: true,
                    told: String::new(),
                    void: None,
                });
            }
            !over
        });
    }

    /// Carries out event `i` before step `step`.
    fn happen(&mut self, i: usize, step: u32, s: &mut State) -> Change {
        let task = std::sync::Arc::clone(&self.base);
        let label = |n: Idx| task.node(n).label();
        let mut void = None;
        let told = match &task.events[i].happening {
            Happening::RobotDown { robot } => {
                self.out.insert(*robot);
                let held = s.target(*robot, Relation::Hold);
                let holding = held.map_or(String::new(), |h| format!(", holding {}", label(h)));
                format!(
                    "{} broke down: it stays where it is for good{holding}, and can do nothing more.",
                    label(*robot)
                )
            }
            Happening::RobotUp { robot, room } => {
                self.out.remove(*robot);
                if let Some(room) = room {
                    join_in(&task, s, *robot, *room);
                }
                let at = crate::rules::room_of(&task, s, *robot)
                    .map_or(String::new(), |r| format!(" in {}", label(r)));
                format!("{} joined the team{at}.", label(*robot))
            }
            Happening::ObjectMoved {
                thing,
                relation,
                target,
            } => match move_thing(&task, s, *thing, *relation, *target) {
                Ok(()) => format!(
                    "Someone outside the team moved {} {} {}.",
                    label(*thing),
                    if *relation == Relation::On {
                        "onto"
                    } else {
                        "into"
                    },
                    label(*target)
                ),
                Err(why) => {
                    void = Some(why);
                    String::new()
                }
            },
            Happening::GoalChanged {
                add,
                remove,
                instruction,
            } => {
                let key = |p: &GoalPredicate| (p.relation, p.subject, p.target);
                self.goal
                    .retain(|q| !remove.iter().any(|p| key(p) == key(q)));
                for p in add {
                    if !self.goal.iter().any(|q| key(q) == key(p)) {
                        self.goal.push(*p);
                    }
                }
                self.instruction.clone_from(instruction);
                format!("The task has changed. The new task: {instruction}")
            }
            Happening::Blocked { what, doors, steps } => {
                let until = steps.map(|n| step + n);
                for &d in doors {
                    self.locked.push((d, until, i));
                }
                let span = steps.map_or("for good".to_owned(), |n| {
                    format!("for {n} step{}", if n == 1 { "" } else { "s" })
                });
                match task.node(*what).kind {
                    NodeKind::Door => {
                        format!("{} is locked {span}: no robot can pass it.", label(*what))
                    }
                    _ => format!(
                        "{} is closed {span}: no robot can go in or out of it.",
                        label(*what)
                    ),
                }
            }
            Happening::ActionFails {
                probability,
                robot,
                steps,
            } => {
                self.failing
                    .push((*probability, *robot, steps.map(|n| step + n), i));
                String::new()
            }
        };
        Change {
            event: i,
            ended: false,
            told,
            void,
        }
    }

    /// The chance that `robot`'s action at this step fails, and the event that makes it
    /// fail (the highest chance when several do); `None` when no failure runs.
    pub fn failure_chance(&self, robot: Idx) -> Option<(f64, usize)> {
        self.failing
            .iter()
            .filter(|&&(_, r, ..)| r.is_none_or(|r| r == robot))
            .map(|&(p, _, _, i)| (p, i))
            .max_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// Whether something yet to come may bring a goal out of reach back within it: an
    /// event not yet happened that adds a robot, moves a thing or changes the goal, or a
    /// lock that ends. Until none is left, a goal out of reach is out of reach for now.
    pub fn may_help_later(&self) -> bool {
        let pending = self.base.events.iter().zip(&self.fired).any(|(e, &fired)| {
            !fired
                && matches!(
                    e.happening,
                    Happening::RobotUp { .. }
                        | Happening::ObjectMoved { .. }
                        | Happening::GoalChanged { .. }
                )
        });
        pending || self.locked.iter().any(|&(_, until, _)| until.is_some())
    }

    /// The task as given, events and all.
    pub fn task(&self) -> &std::sync::Arc<Task> {
        &self.base
    }
}

/// Puts `robot` (a dog or a quadrotor) in `room`: a dog on its floor, a quadrotor flying
/// above it, its basket in the air with it.
fn join_in(task: &Task, s: &mut State, robot: Idx, room: Idx) {
    let NodeKind::Robot(kind) = task.node(robot).kind else {
        return;
    };
    let floor = task.floor_of(room);
    s.remove_out(robot, Relation::Close);
    s.remove_out(robot, Relation::On);
    s.remove_out(robot, Relation::Above);
    match kind {
        RobotKind::RobotDog => {
            if let Some(f) = floor {
                s.add(Edge::new(robot, Relation::On, f));
            }
        }
        RobotKind::Quadrotor => {
            s.set_states(robot, StateSet::FLYING);
            if let Some(f) = floor {
                s.add(Edge::new(robot, Relation::Above, f));
            }
            if let Some(b) = task.basket_of(robot) {
                s.remove_out(b, Relation::On);
                crate::rules::lift_basket(s, b);
            }
        }
        RobotKind::RobotArm => return,
    }
    crate::rules::move_to_room(task, s, robot, room);
}

/// Puts `thing` on or into `target`, taken from wherever it is (a robot's hand
/// included); robots next to it are no longer, robot dogs next to the target now are.
/// An error, changing nothing, when the target stands on or in the thing. The one way
/// an event moves a thing, whichever world carries it out.
pub fn move_thing(
    task: &Task,
    s: &mut State,
    thing: Idx,
    relation: Relation,
    target: Idx,
) -> std::result::Result<(), String> {
    let mut at = Some(target);
    let mut hops = 0;
    while let Some(n) = at {
        if n == thing {
            return Err(format!(
                "{} stands on or in {}: it cannot be put there",
                task.node(target).label(),
                task.node(thing).label()
            ));
        }
        hops += 1;
        if hops > task.nodes.len() {
            break;
        }
        at = s
            .out(n)
            .iter()
            .find(|e| e.rel().is_location())
            .map(|e| e.to());
    }
    s.retain(|e| {
        let holds = e.rel() == Relation::Hold && e.to() == thing;
        let placed = e.from() == thing && e.rel().is_location();
        let close = e.rel() == Relation::Close && e.to() == thing;
        !(holds || placed || close)
    });
    s.add(Edge::new(thing, relation, target));
    let high = task.has(s, target, PropSet::HIGH_HEIGHT) || s.on_high_surface(target);
    s.set_on_high_surface(thing, high);
    let seen_inside = relation == Relation::On || s.states(target).is_open();
    let dogs: Vec<Idx> = s
        .sources(Relation::Close, target)
        .filter(|&r| task.robot(r).is_some_and(|r| r.kind == RobotKind::RobotDog))
        .collect();
    if seen_inside {
        for d in dogs {
            s.add(Edge::new(d, Relation::Close, thing));
        }
    }
    Ok(())
}
