//! Actions physically: the robot's kind and the verb pick the motion; one action runs
//! alone, or several robots' actions (a joint step) run in the same simulation steps,
//! watched for robots that touch each other.

use coherent_core::{Action, Idx, NodeKind, RobotKind, Verb};
use rapier3d::prelude::*;

use super::contact::Brought;
use super::motion::{Motion, Stage};
use super::{FailureKind, PhysicsError, World, fail};

/// Why a run of actions stopped: the action that failed (by index), or robots that
/// touched each other.
enum Stop {
    Motion(usize, PhysicsError),
    Contact(PhysicsError),
}

/// An action of a joint step: waiting for its way or spot to clear (why it cannot start
/// yet), moving, or over (its simulated seconds from the step's start).
enum Slot {
    Waiting(PhysicsError),
    Moving(Motion),
    Over(f64),
}

/// The motion of a moving action.
fn moving(s: &Slot) -> Option<&Motion> {
    match s {
        Slot::Moving(m) => Some(m),
        _ => None,
    }
}

impl World {
    /// Executes `a` by `robot` physically, without asking the rules.
    pub fn execute(&mut self, robot: Idx, a: Action) -> Result<(), PhysicsError> {
        match self.run(&[(robot, a)]) {
            Ok(_) => Ok(()),
            Err(Stop::Motion(_, e) | Stop::Contact(e)) => Err(e),
        }
    }

    /// Executes the actions of a joint step (at most one per robot) physically, without
    /// asking the rules, all at once: each simulation step advances every robot's motion
    /// that is not over, until all are. Each motion plans its way from where everything
    /// is when it starts; one whose way or spot another robot of the step still blocks
    /// waits, planning again every half second, until it can start (and fails if
    /// nothing moves any more). A moving robot that comes close to one earlier in the
    /// step that moves too holds where it is until that one has moved away or is done
    /// (`contact.rs`). Robots of the step that touch each other, or what another of them
    /// handles, fail it. Every failure names the robot and action
    /// (both, for a contact) and when it happened. Returns each action's simulated
    /// seconds from the step's start, in the order given; the step took the longest of
    /// them.
    pub fn execute_joint(&mut self, actions: &[(Idx, Action)]) -> Result<Vec<f64>, PhysicsError> {
        for (i, &(r, _)) in actions.iter().enumerate() {
            if actions[..i].iter().any(|&(other, _)| other == r) {
                return fail(
                    FailureKind::Layout,
                    format!("{} has two actions in one joint step", self.label(r)),
                );
            }
        }
        let t0 = self.sim_time;
        match self.run(actions) {
            Ok(seconds) => Ok(seconds),
            Err(Stop::Contact(e)) => Err(e),
            Err(Stop::Motion(i, e)) => {
                let (r, a) = actions[i];
                Err(self.blame(r, a, t0, e))
            }
        }
    }

    /// `e` with the robot, its action and when it happened in front.
    fn blame(&self, robot: Idx, a: Action, t0: f64, e: PhysicsError) -> PhysicsError {
        PhysicsError {
            kind: e.kind,
            message: format!(
                "{} {}, {:.2} s into the joint step ({:.2} s simulated): {}",
                self.label(robot),
                a.render(&self.task),
                self.sim_time - t0,
                self.sim_time,
                e.message
            ),
        }
    }

    /// Runs `actions` together until all are over; each one's simulated seconds. One
    /// action alone is its motion, step by step, and nothing else.
    fn run(&mut self, actions: &[(Idx, Action)]) -> Result<Vec<f64>, Stop> {
        let t0 = self.sim_time;
        let mut slots = Vec::with_capacity(actions.len());
        for (i, &(r, a)) in actions.iter().enumerate() {
            slots.push(match self.start(r, a) {
                Ok(m) => Slot::Moving(m),
                // Another robot of the step may be in the way, and about to leave.
                Err(e) if e.kind == FailureKind::Blocked && actions.len() > 1 => Slot::Waiting(e),
                Err(e) => return Err(Stop::Motion(i, e)),
            });
        }
        let mut taken = 0usize;
        loop {
            let holding = if slots.iter().filter_map(moving).count() > 1 {
                self.holding(&slots)
            } else {
                vec![false; slots.len()]
            };
            let mut stepping = false;
            for (i, slot) in slots.iter_mut().enumerate() {
                if let Slot::Moving(m) = slot {
                    if holding[i] {
                        self.hold(m);
                        stepping = true;
                    } else if self.prepare(m).map_err(|e| Stop::Motion(i, e))? {
                        stepping = true;
                    } else {
                        *slot = Slot::Over(self.sim_time - t0);
                    }
                }
            }
            for (i, slot) in slots.iter_mut().enumerate() {
                let retry = taken > 0 && (!stepping || taken.is_multiple_of(self.tol.retry_steps));
                if !(retry && matches!(slot, Slot::Waiting(_))) {
                    continue;
                }
                let (r, a) = actions[i];
                *slot = match self.start(r, a) {
                    Ok(mut m) => {
                        if self.prepare(&mut m).map_err(|e| Stop::Motion(i, e))? {
                            stepping = true;
                            Slot::Moving(m)
                        } else {
                            Slot::Over(self.sim_time - t0)
                        }
                    }
                    Err(e) if e.kind == FailureKind::Blocked => Slot::Waiting(e),
                    Err(e) => return Err(Stop::Motion(i, e)),
                };
            }
            if !stepping {
                // Nothing moves any more: an action still waiting will never start.
                return slots
                    .into_iter()
                    .enumerate()
                    .map(|(i, slot)| match slot {
                        Slot::Waiting(e) => Err(Stop::Motion(i, e)),
                        Slot::Over(t) => Ok(t),
                        Slot::Moving(_) => Ok(self.sim_time - t0),
                    })
                    .collect();
            }
            self.step();
            taken += 1;
            for (i, slot) in slots.iter_mut().enumerate() {
                if let Slot::Moving(m) = slot
                    && !holding[i]
                {
                    self.after_step(m).map_err(|e| Stop::Motion(i, e))?;
                }
            }
            if actions.len() > 1 {
                let brought: Vec<Brought> =
                    actions.iter().map(|&(r, a)| self.brought(r, a)).collect();
                self.check_contacts(&brought, t0).map_err(Stop::Contact)?;
            }
        }
    }

    /// Which actions hold this step: those whose robot is near one moving earlier in the
    /// step.
    fn holding(&self, slots: &[Slot]) -> Vec<bool> {
        let brought: Vec<Option<Brought>> = slots
            .iter()
            .map(|s| moving(s).map(|m| self.brought(m.robot, m.action)))
            .collect();
        (0..slots.len())
            .map(|i| {
                brought[i].as_ref().is_some_and(|b| {
                    brought[..i]
                        .iter()
                        .flatten()
                        .any(|earlier| self.near(earlier, b))
                })
            })
            .collect()
    }

    /// The motion of `a` by `robot`, its way planned from where everything is now.
    fn start(&mut self, robot: Idx, a: Action) -> Result<Motion, PhysicsError> {
        let Some(kind) = self.task.robot(robot).map(|r| r.kind) else {
            return fail(
                FailureKind::Layout,
                format!("{} is not a robot", self.label(robot)),
            );
        };
        let x = a.object;
        let stages = match (kind, a.verb) {
            (RobotKind::Quadrotor, Verb::TakeoffFrom) => self.quad_takeoff(robot)?,
            (RobotKind::Quadrotor, Verb::LandOn) => self.quad_land(robot, x)?,
            (RobotKind::Quadrotor, Verb::MoveTowards) => self.quad_towards(robot, x)?,
            (RobotKind::RobotDog, Verb::MoveTowards) => {
                if self.task.node(x).kind == NodeKind::Room {
                    self.dog_to_room(robot, x)?
                } else {
                    let (p, face) = self.service_point(robot, x)?;
                    self.walk(robot, p, face)?
                }
            }
            (_, Verb::Open) => self.drive_hinge(robot, x, true)?,
            (_, Verb::Close) => self.drive_hinge(robot, x, false)?,
            (_, Verb::Grab) => self.grasp(robot, x)?,
            (_, Verb::PutOn) | (_, Verb::PutInto) => {
                let Some(t) = a.target else {
                    return fail(FailureKind::Layout, "put without a target".into());
                };
                self.release(robot, x, t, a.verb == Verb::PutInto)?
            }
            (k, v) => return fail(FailureKind::Layout, format!("a {k} cannot [{v}]")),
        };
        Ok(Motion::new(robot, a, stages))
    }

    /// The quadrotor `robot`'s flight to a room (over the middle of its floor, or a free
    /// spot there, at cruise altitude) or to hover `quad_hover_height` over a free spot
    /// on a surface.
    fn quad_towards(&self, robot: Idx, x: Idx) -> Result<Vec<Stage>, PhysicsError> {
        if self.task.node(x).kind == NodeKind::Room {
            let Some((lo, hi)) = self.room_rect(x) else {
                return fail(
                    FailureKind::Layout,
                    format!("{} has no footprint", self.label(x)),
                );
            };
            let floor = self.task.floor_of(x);
            let level = self.room_level(x);
            let mid = Vector::new((lo[0] + hi[0]) / 2.0, level, (lo[1] + hi[1]) / 2.0);
            let spot = match floor {
                Some(f) => self.landing_spot(robot, f, mid).unwrap_or(mid),
                None => mid,
            };
            let cruise = self.layout.specs.cruise_altitude;
            self.quad_fly_to(robot, spot, level + cruise)
        } else {
            let p = self.quad_pos(robot).unwrap_or(Vector::ZERO);
            let spot = self.landing_spot(robot, x, p)?;
            let y = self.top_height(x) + self.tol.quad_hover_height;
            self.quad_fly_to(robot, spot, y)
        }
    }
}
