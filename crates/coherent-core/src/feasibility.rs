//! Feasibility, the "why not": for any action string a robot is asked to do, either the
//! resolved action (it is in the robot's action list) or a specific, human-readable
//! reason. PEFA's executor feedback is built on these reasons.

use std::fmt;

use crate::action::{self, Action, Mention, Verb};
use crate::graph::{Idx, NodeKind, RobotKind, State};
use crate::rules::{Contents, View};
use crate::task::{Robot, Task};
use crate::vocab::{PropSet, Relation, StateSet};

/// Why an action cannot be executed now, as a category for statistics.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Reason {
    /// The text does not follow the action grammar.
    Unparsable,
    /// No node has the id, or the name does not match the node with that id.
    NoSuchNode,
    /// This robot type does not have the verb.
    WrongRobotType,
    /// The node is not in the robot's observation.
    NotInView,
    /// The robot dog must move close first.
    NotClose,
    /// The fixed arm cannot reach it from its surface.
    OutOfReach,
    /// A high surface, or a thing on one, which the robot dog cannot reach.
    TooHigh,
    HandFull,
    HandEmpty,
    /// Holding something other than the object named.
    NotHolding,
    NotGrabable,
    NotContainer,
    NotSurface,
    /// Neither a container nor (for the dog) a door, or it has no open/closed state.
    NotOpenable,
    AlreadyOpen,
    AlreadyClosed,
    /// `OPEN_FOREVER`: it can never be closed.
    AlwaysOpen,
    ContainerClosed,
    DoorClosed,
    /// No door connects the robot's room and the room named.
    NoDoor,
    /// Already where the action would take it.
    AlreadyThere,
    /// Rooms, floors and robots are not things to move next to.
    NotATarget,
    NotLandable,
    /// The quadrotor is on a surface and must take off first.
    NotFlying,
    /// The quadrotor is flying and must land first.
    NotLanded,
    /// The quadrotor is not hovering above that surface.
    NotAbove,
    /// The quadrotor is not on that surface.
    NotOnSurface,
    /// The robot is in no room, or its arm is on no surface.
    Misplaced,
    /// Not offered, and no rule above explains why; tests pin that this never happens.
    NotOffered,
    /// Allowed by the rules, but the physical world could not carry it out (a reach, a
    /// collision, a landing spot); the message has the numbers. Only physical
    /// environments give it.
    Physics,
    /// Allowed by the rules, but the robot it was sent to reports that it could not
    /// carry it out; the message is the robot's. This and the four below come only from
    /// environments that send actions to robots outside the process (`coherent-ros`).
    Robot,
    /// The robot's server refused the action.
    Rejected,
    /// The robot did not answer in time: what it did is unknown.
    Timeout,
    /// Cancelled while the robot was carrying it out (Ctrl-C).
    Cancelled,
    /// The robot reports success, but the relations it observes afterwards disagree with
    /// the rules' state.
    Disagreement,
    /// Another robot's action of the same joint step interferes with this one: the order
    /// they ran in would matter (docs/semantics.md, "Parallel steps").
    Interference,
    /// The joint step this action was part of was refused for another action's sake.
    StepRefused,
}

impl Reason {
    /// A stable snake_case name, as written in transcripts and results.
    pub fn name(self) -> &'static str {
        match self {
            Reason::Unparsable => "unparsable",
            Reason::NoSuchNode => "no_such_node",
            Reason::WrongRobotType => "wrong_robot_type",
            Reason::NotInView => "not_in_view",
            Reason::NotClose => "not_close",
            Reason::OutOfReach => "out_of_reach",
            Reason::TooHigh => "too_high",
            Reason::HandFull => "hand_full",
            Reason::HandEmpty => "hand_empty",
            Reason::NotHolding => "not_holding",
            Reason::NotGrabable => "not_grabable",
            Reason::NotContainer => "not_container",
            Reason::NotSurface => "not_surface",
            Reason::NotOpenable => "not_openable",
            Reason::AlreadyOpen => "already_open",
            Reason::AlreadyClosed => "already_closed",
            Reason::AlwaysOpen => "always_open",
            Reason::ContainerClosed => "container_closed",
            Reason::DoorClosed => "door_closed",
            Reason::NoDoor => "no_door",
            Reason::AlreadyThere => "already_there",
            Reason::NotATarget => "not_a_target",
            Reason::NotLandable => "not_landable",
            Reason::NotFlying => "not_flying",
            Reason::NotLanded => "not_landed",
            Reason::NotAbove => "not_above",
            Reason::NotOnSurface => "not_on_surface",
            Reason::Misplaced => "misplaced",
            Reason::NotOffered => "not_offered",
            Reason::Physics => "physics",
            Reason::Robot => "robot",
            Reason::Rejected => "rejected",
            Reason::Timeout => "timeout",
            Reason::Cancelled => "cancelled",
            Reason::Disagreement => "disagreement",
            Reason::Interference => "interference",
            Reason::StepRefused => "step_refused",
        }
    }

    /// Every reason, in declaration order.
    pub const ALL: [Reason; 37] = [
        Reason::Unparsable,
        Reason::NoSuchNode,
        Reason::WrongRobotType,
        Reason::NotInView,
        Reason::NotClose,
        Reason::OutOfReach,
        Reason::TooHigh,
        Reason::HandFull,
        Reason::HandEmpty,
        Reason::NotHolding,
        Reason::NotGrabable,
        Reason::NotContainer,
        Reason::NotSurface,
        Reason::NotOpenable,
        Reason::AlreadyOpen,
        Reason::AlreadyClosed,
        Reason::AlwaysOpen,
        Reason::ContainerClosed,
        Reason::DoorClosed,
        Reason::NoDoor,
        Reason::AlreadyThere,
        Reason::NotATarget,
        Reason::NotLandable,
        Reason::NotFlying,
        Reason::NotLanded,
        Reason::NotAbove,
        Reason::NotOnSurface,
        Reason::Misplaced,
        Reason::NotOffered,
        Reason::Physics,
        Reason::Robot,
        Reason::Rejected,
        Reason::Timeout,
        Reason::Cancelled,
        Reason::Disagreement,
        Reason::Interference,
        Reason::StepRefused,
    ];

    /// The reason whose [`Reason::name`] is `name`.
    pub fn from_name(name: &str) -> Option<Reason> {
        Reason::ALL.into_iter().find(|r| r.name() == name)
    }
}

/// An action that cannot be executed, with the reason in words.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Infeasible {
    pub reason: Reason,
    pub message: String,
}

impl fmt::Display for Infeasible {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Infeasible {}

fn no(reason: Reason, message: String) -> Infeasible {
    Infeasible { reason, message }
}

/// Checks `text` for `robot` in state `s`: the action when it is in the robot's action
/// list, otherwise why not.
pub fn check(task: &Task, s: &State, robot: Robot, text: &str) -> Result<Action, Infeasible> {
    let parsed = action::parse(text).map_err(|e| match e {
        crate::Error::BadAction { reason, .. } => no(
            Reason::Unparsable,
            format!("cannot parse {text:?}: {reason}"),
        ),
        other => no(Reason::Unparsable, other.to_string()),
    })?;
    let me = task.node(robot.node).label();
    if !Verb::of(robot.kind).contains(&parsed.verb) {
        return Err(no(
            Reason::WrongRobotType,
            format!(
                "{me} is a {} and cannot [{}]; its verbs are {}",
                robot.kind,
                parsed.verb,
                Verb::of(robot.kind)
                    .iter()
                    .map(|v| format!("[{v}]"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    }
    let object = resolve(task, &parsed.object)?;
    let target = parsed
        .target
        .as_ref()
        .map(|t| resolve(task, t))
        .transpose()?;
    let action = Action {
        verb: parsed.verb,
        object,
        target,
    };
    // One view serves both the action list and, when the action is not in it, the why.
    let contents = Contents::new(task, s);
    let view = View::with(task, s, robot, &contents);
    if view.actions().contains(&action) {
        return Ok(action);
    }
    Err(diagnose(&view, action))
}

fn resolve(task: &Task, m: &Mention) -> Result<Idx, Infeasible> {
    let n = task.idx(m.id).ok_or_else(|| {
        no(
            Reason::NoSuchNode,
            format!("there is no node with id {} (in {m})", m.id),
        )
    })?;
    let node = task.node(n);
    if node.class_name != m.name {
        return Err(no(
            Reason::NoSuchNode,
            format!("node {} is {}, not {m}", m.id, node.label()),
        ));
    }
    Ok(n)
}

/// Why an action that is not in the robot's list cannot be done.
pub(crate) fn diagnose(v: &View<'_>, a: Action) -> Infeasible {
    let d = Diag { v };
    let found = match (v.robot.kind, a.verb) {
        (RobotKind::Quadrotor, Verb::LandOn) => d.land_on(a.object),
        (RobotKind::Quadrotor, Verb::TakeoffFrom) => d.takeoff_from(a.object),
        (RobotKind::Quadrotor, Verb::MoveTowards) => d.fly_towards(a.object),
        (RobotKind::RobotDog, Verb::MoveTowards) => d.walk_towards(a.object),
        (_, Verb::Open | Verb::Close) => d.open_close(a.verb, a.object),
        (_, Verb::Grab) => d.grab(a.object),
        (_, Verb::PutInto | Verb::PutOn) => d.put(a),
        // Verbs of another robot type were rejected before.
        _ => None,
    };
    found.unwrap_or_else(|| {
        no(
            Reason::NotOffered,
            format!(
                "{} is not among the actions of {} now",
                a.render(v.task),
                v.task.node(v.robot.node).label()
            ),
        )
    })
}

/// Why `v`'s robot cannot get its hand on `x` from where it is (the dog must be close and
/// `x` low enough, the arm reaches only its surface), or `None`; a quadrotor has no hand.
pub(crate) fn hand_reach(v: &View<'_>, x: Idx) -> Option<Infeasible> {
    match v.robot.kind {
        RobotKind::Quadrotor => None,
        // The arm always reaches the surface it stands on, to put things down.
        RobotKind::RobotArm if v.own(Relation::On) == Some(x) => None,
        RobotKind::RobotDog | RobotKind::RobotArm => Diag { v }.within_reach(x),
    }
}

struct Diag<'v, 'a> {
    v: &'v View<'a>,
}

impl Diag<'_, '_> {
    fn label(&self, n: Idx) -> String {
        self.v.task.node(n).label()
    }
    fn me(&self) -> String {
        self.label(self.v.robot.node)
    }
    fn room_label(&self) -> String {
        self.v
            .room
            .map(|r| self.label(r))
            .unwrap_or_else(|| "no room".to_owned())
    }

    fn in_view(&self, n: Idx) -> Option<Infeasible> {
        (!self.v.sees(n)).then(|| {
            no(
                Reason::NotInView,
                format!(
                    "{} is not in view of {} (in {})",
                    self.label(n),
                    self.me(),
                    self.room_label()
                ),
            )
        })
    }

    fn placed(&self) -> Option<Infeasible> {
        self.v
            .room
            .is_none()
            .then(|| no(Reason::Misplaced, format!("{} is in no room", self.me())))
    }

    /// Moving into a neighbouring room: a door must lead there and be open.
    fn to_room(&self, room: Idx) -> Option<Infeasible> {
        if let Some(p) = self.placed() {
            return Some(p);
        }
        if Some(room) == self.v.room {
            return Some(no(
                Reason::AlreadyThere,
                format!("{} is already in {}", self.me(), self.label(room)),
            ));
        }
        let doors: Vec<Idx> = self
            .v
            .next_rooms()
            .filter(|&(r, _)| r == room)
            .map(|(_, d)| d)
            .collect();
        if doors.is_empty() {
            return Some(no(
                Reason::NoDoor,
                format!(
                    "no door connects {} and {}",
                    self.room_label(),
                    self.label(room)
                ),
            ));
        }
        if doors.iter().all(|&d| !self.v.states(d).is_open()) {
            return Some(no(
                Reason::DoorClosed,
                format!(
                    "{} between {} and {} is closed; a robot dog must open it first",
                    self.label(doors[0]),
                    self.room_label(),
                    self.label(room)
                ),
            ));
        }
        None
    }

    fn land_on(&self, s: Idx) -> Option<Infeasible> {
        let v = self.v;
        if !v.states(v.robot.node).contains(StateSet::FLYING) {
            return Some(self.not_flying());
        }
        self.in_view(s)
            .or_else(|| self.landable(s))
            .or_else(|| (v.above() != Some(s)).then(|| self.not_above(s)))
    }

    fn not_flying(&self) -> Infeasible {
        let on = self
            .v
            .own(Relation::On)
            .map(|s| format!(" on {}", self.label(s)))
            .unwrap_or_default();
        no(
            Reason::NotFlying,
            format!("{} has landed{on}; it must take off first", self.me()),
        )
    }

    fn not_above(&self, s: Idx) -> Infeasible {
        let above = match self.v.own(Relation::Above) {
            Some(a) => format!("is above {}", self.label(a)),
            None => "is above no surface".to_owned(),
        };
        no(
            Reason::NotAbove,
            format!(
                "{} {above}, not above {}; it must move towards it first",
                self.me(),
                self.label(s)
            ),
        )
    }

    fn landable(&self, s: Idx) -> Option<Infeasible> {
        (!self.v.has(s, PropSet::LANDABLE)).then(|| {
            no(
                Reason::NotLandable,
                format!(
                    "{} is not LANDABLE: a quadrotor can only land on landable surfaces",
                    self.label(s)
                ),
            )
        })
    }

    fn takeoff_from(&self, s: Idx) -> Option<Infeasible> {
        let v = self.v;
        if !v.states(v.robot.node).contains(StateSet::LAND) {
            return Some(no(
                Reason::NotLanded,
                format!("{} is already flying", self.me()),
            ));
        }
        (v.own(Relation::On) != Some(s)).then(|| {
            let on = v
                .own(Relation::On)
                .map(|o| self.label(o))
                .unwrap_or_else(|| "nothing".to_owned());
            no(
                Reason::NotOnSurface,
                format!("{} is on {on}, not on {}", self.me(), self.label(s)),
            )
        })
    }

    fn fly_towards(&self, x: Idx) -> Option<Infeasible> {
        let v = self.v;
        if !v.states(v.robot.node).contains(StateSet::FLYING) {
            return Some(self.not_flying());
        }
        if v.kind(x) == NodeKind::Room {
            return self.to_room(x);
        }
        self.in_view(x)
            .or_else(|| self.landable(x))
            .or_else(|| match v.above() {
                None => Some(no(
                    Reason::NotAbove,
                    format!(
                        "{} is not above a landable surface, so it can only move to another room",
                        self.me()
                    ),
                )),
                Some(a) if a == x => Some(no(
                    Reason::AlreadyThere,
                    format!(
                        "{} is already above {}; it can land on it",
                        self.me(),
                        self.label(x)
                    ),
                )),
                Some(_) => None,
            })
    }

    fn walk_towards(&self, x: Idx) -> Option<Infeasible> {
        let v = self.v;
        if v.kind(x) == NodeKind::Room {
            return self.to_room(x);
        }
        if let Some(e) = self.in_view(x) {
            return Some(e);
        }
        if v.holding == Some(x) {
            return Some(no(
                Reason::AlreadyThere,
                format!("{} already holds {}", self.me(), self.label(x)),
            ));
        }
        if matches!(v.kind(x), NodeKind::Robot(_) | NodeKind::Floor) {
            return Some(no(
                Reason::NotATarget,
                format!(
                    "{} is a robot or a floor, not something to move next to; move towards an object, a surface or a room",
                    self.label(x)
                ),
            ));
        }
        if let Some(e) = self.too_high(x) {
            return Some(e);
        }
        v.close_to(x).then(|| {
            no(
                Reason::AlreadyThere,
                format!("{} is already close to {}", self.me(), self.label(x)),
            )
        })
    }

    /// The robot dog cannot reach high surfaces nor things on them.
    fn too_high(&self, x: Idx) -> Option<Infeasible> {
        let v = self.v;
        if v.has(x, PropSet::HIGH_HEIGHT) {
            return Some(no(
                Reason::TooHigh,
                format!(
                    "{} is a high surface (HIGH_HEIGHT), out of the robot dog's reach",
                    self.label(x)
                ),
            ));
        }
        v.has(x, PropSet::ON_HIGH_SURFACE).then(|| {
            no(
                Reason::TooHigh,
                format!(
                    "{} is on a high surface (ON_HIGH_SURFACE), out of the robot dog's reach",
                    self.label(x)
                ),
            )
        })
    }

    /// The object must be within reach: close for the dog, in reach for the arm.
    fn within_reach(&self, x: Idx) -> Option<Infeasible> {
        let v = self.v;
        match v.robot.kind {
            RobotKind::RobotArm => {
                let on_surface = v.own(Relation::On);
                if on_surface.is_none() {
                    return Some(no(
                        Reason::Misplaced,
                        format!("{} stands on no surface", self.me()),
                    ));
                }
                (!v.arm_reach().contains(&x)).then(|| {
                    let surface = on_surface.map(|s| self.label(s)).unwrap_or_default();
                    no(
                        Reason::OutOfReach,
                        format!(
                            "{} is out of reach of {}, which only reaches what is on {surface}",
                            self.label(x),
                            self.me()
                        ),
                    )
                })
            }
            _ => (!v.close_to(x)).then(|| {
                self.too_high(x).unwrap_or_else(|| {
                    no(
                        Reason::NotClose,
                        format!(
                            "{} is not close enough to {}; it must move towards it first",
                            self.me(),
                            self.label(x)
                        ),
                    )
                })
            }),
        }
    }

    fn hand_free(&self) -> Option<Infeasible> {
        self.v.holding.map(|h| {
            no(
                Reason::HandFull,
                format!(
                    "{} is holding {}; its hand must be empty",
                    self.me(),
                    self.label(h)
                ),
            )
        })
    }

    fn open_close(&self, verb: Verb, x: Idx) -> Option<Infeasible> {
        let v = self.v;
        if let Some(e) = self.in_view(x) {
            return Some(e);
        }
        let door = v.kind(x) == NodeKind::Door;
        let dog = v.robot.kind == RobotKind::RobotDog;
        if !v.has(x, PropSet::CONTAINERS) && (!door || !dog) {
            let what = match (door, dog) {
                (true, _) => "a robot arm cannot open or close doors".to_owned(),
                (false, true) => format!("{} is neither a container nor a door", self.label(x)),
                (false, false) => format!("{} is not a container", self.label(x)),
            };
            return Some(no(Reason::NotOpenable, what));
        }
        let states = v.states(x);
        let state_problem = match verb {
            Verb::Open if states.is_open() => Some(no(
                Reason::AlreadyOpen,
                format!("{} is already open", self.label(x)),
            )),
            Verb::Close if states.contains(StateSet::OPEN_FOREVER) => Some(no(
                Reason::AlwaysOpen,
                format!(
                    "{} is always open (OPEN_FOREVER) and cannot be closed",
                    self.label(x)
                ),
            )),
            Verb::Close if states.contains(StateSet::CLOSED) => Some(no(
                Reason::AlreadyClosed,
                format!("{} is already closed", self.label(x)),
            )),
            Verb::Open if !states.contains(StateSet::CLOSED) => Some(self.stateless(x)),
            Verb::Close if !states.contains(StateSet::OPEN) => Some(self.stateless(x)),
            _ => None,
        };
        state_problem
            .or_else(|| self.within_reach(x))
            .or_else(|| self.hand_free())
    }

    fn stateless(&self, x: Idx) -> Infeasible {
        no(
            Reason::NotOpenable,
            format!(
                "{} is neither OPEN nor CLOSED, so it cannot be opened or closed",
                self.label(x)
            ),
        )
    }

    fn grab(&self, x: Idx) -> Option<Infeasible> {
        let v = self.v;
        if v.holding == Some(x) {
            return Some(no(
                Reason::HandFull,
                format!("{} already holds {}", self.me(), self.label(x)),
            ));
        }
        self.in_view(x)
            .or_else(|| {
                (!v.has(x, PropSet::GRABABLE)).then(|| {
                    no(
                        Reason::NotGrabable,
                        format!("{} is not GRABABLE", self.label(x)),
                    )
                })
            })
            .or_else(|| self.within_reach(x))
            .or_else(|| self.hand_free())
    }

    fn put(&self, a: Action) -> Option<Infeasible> {
        let v = self.v;
        let x = a.object;
        let t = a.target?;
        match v.holding {
            None => {
                return Some(no(
                    Reason::HandEmpty,
                    format!(
                        "{} is not holding anything; it must grab {} first",
                        self.me(),
                        self.label(x)
                    ),
                ));
            }
            Some(h) if h != x => {
                return Some(no(
                    Reason::NotHolding,
                    format!(
                        "{} is holding {}, not {}",
                        self.me(),
                        self.label(h),
                        self.label(x)
                    ),
                ));
            }
            Some(_) => {}
        }
        if let Some(e) = self.in_view(t) {
            return Some(e);
        }
        let kind_problem = if a.verb == Verb::PutInto {
            if !v.has(t, PropSet::CONTAINERS) {
                Some(no(
                    Reason::NotContainer,
                    format!("{} is not a container", self.label(t)),
                ))
            } else if !v.states(t).is_open() {
                Some(no(
                    Reason::ContainerClosed,
                    format!("{} is closed; it must be opened first", self.label(t)),
                ))
            } else {
                None
            }
        } else {
            (!v.has(t, PropSet::SURFACES)).then(|| {
                no(
                    Reason::NotSurface,
                    format!("{} is not a surface", self.label(t)),
                )
            })
        };
        kind_problem.or_else(|| {
            // The arm may always put down on its own surface.
            let own_surface = v.robot.kind == RobotKind::RobotArm
                && a.verb == Verb::PutOn
                && v.own(Relation::On) == Some(t);
            if own_surface {
                None
            } else {
                self.within_reach(t)
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::Reason;

    #[test]
    fn every_reason_is_found_by_its_own_name_and_no_other() {
        for r in Reason::ALL {
            assert_eq!(Reason::from_name(r.name()), Some(r), "{r:?}");
        }
        let mut names: Vec<&str> = Reason::ALL.iter().map(|r| r.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), Reason::ALL.len());
        assert_eq!(Reason::from_name("no such reason"), None);
    }
}
