//! An action in progress: the stages one robot's motion goes through (a flight, a
//! walk, an arm move, a wait), advanced one simulation step at a time, so that several
//! robots' motions can share the steps of one world. Each stage keeps what its loop
//! would keep between steps; the code that advances it lives with its robot's job
//! (`quadrotor.rs`, `legged.rs`, `arm.rs`, `manipulation.rs`, `step.rs`), and this file
//! only says what a stage holds and which code runs it.
//!
//! A step of a motion is [`World::prepare`] (instant stages run, and a stepping stage
//! sets its controls for the next simulation step), the world's step, then
//! [`World::after_step`] (what the stage checks once the step is done). One motion run
//! alone this way does exactly what one blocking loop per stage did, in the same order.

use std::collections::VecDeque;

use coherent_core::{Action, Idx};
use rapier3d::prelude::*;

use super::{Hinge, PhysicsError, World};
use crate::layout::Flight;

/// One robot's action in progress: the stages still to run, the current one first.
#[derive(Debug)]
pub(super) struct Motion {
    pub(super) robot: Idx,
    pub(super) action: Action,
    stages: VecDeque<Stage>,
}

impl Motion {
    pub(super) fn new(robot: Idx, action: Action, stages: Vec<Stage>) -> Motion {
        Motion {
            robot,
            action,
            stages: stages.into(),
        }
    }
}

/// What a stage asks for before the next simulation step.
pub(super) enum Tick {
    /// Its controls are set: step the world, then call its `after` hook.
    Step,
    /// It is over.
    Done,
    /// It is over and these stages come next, in order.
    Then(Vec<Stage>),
}

/// A part of a motion. Stepping stages take simulation steps; the others happen between
/// two steps.
#[derive(Debug)]
pub(super) enum Stage {
    /// The quadrotor's set point moving along waypoints at flight speed.
    Fly(Fly),
    /// The quadrotor holding the end of a flight until it is still there.
    Hover(Hover),
    /// The quadrotor sinking onto a surface until it touches it.
    Descend(Descend),
    /// The quadrotor's motors on (the controller's integral cleared) or off.
    Motors(bool),
    /// The quadrotor, motors off, must rest on this surface.
    Landed(Idx),
    /// The legged robot walking through waypoints on a storey or along a flight.
    Walk(Walk),
    /// The legged robot, off the flight, must stand on the floor (body origin given).
    OffStairs(Flight, Vector),
    /// The legged robot turning on the spot to face a point.
    Turn(Turn),
    /// An arm's joints moving to angles at a bounded joint speed.
    Arm(ArmMove),
    /// The hand of `robot` must be at `target` now (`what` is there).
    HandAt {
        robot: Idx,
        target: Vector,
        what: String,
    },
    /// The hand of `robot` takes hold of `object` and what rides on it.
    Fasten { robot: Idx, object: Idx },
    /// The hand of `robot` lets go of `object`.
    Unfasten { robot: Idx, object: Idx },
    /// A door or lid turning about its hinge.
    Hinge(HingeTurn),
    /// Waiting until loose things rest.
    Settle(Settle),
}

/// A flight's set point: the waypoints (body origin), the next one, and where the set
/// point is (from the craft's position when the flight starts).
#[derive(Debug)]
pub(super) struct Fly {
    pub(super) waypoints: Vec<Vector>,
    pub(super) next: usize,
    /// The set point, and the offset of the centre of mass from the body origin.
    pub(super) at: Option<(Vector, Vector)>,
}

impl Fly {
    pub(super) fn stage(waypoints: Vec<Vector>) -> Stage {
        Stage::Fly(Fly {
            waypoints,
            next: 0,
            at: None,
        })
    }
}

/// Hovering at `end` (body origin); `steps` taken so far.
#[derive(Debug)]
pub(super) struct Hover {
    pub(super) end: Vector,
    pub(super) com_off: Vector,
    pub(super) steps: usize,
    pub(super) still: bool,
}

/// Sinking onto `surface` over `spot`: the set point's height, the steps taken, whether
/// it touches.
#[derive(Debug)]
pub(super) struct Descend {
    pub(super) surface: Idx,
    pub(super) spot: Vector,
    /// The set point's height and the centre of mass's offset, from when it starts.
    pub(super) at: Option<(f32, Vector)>,
    pub(super) steps: usize,
    pub(super) touches: bool,
}

/// The legged robot walking `waypoints` (on a flight's slope when `on_flight`).
#[derive(Debug)]
pub(super) struct Walk {
    pub(super) dog: Idx,
    pub(super) body: RigidBodyHandle,
    pub(super) waypoints: Vec<Vector>,
    pub(super) on_flight: bool,
    pub(super) next: usize,
    /// Steps allowed towards the next waypoint (set when it is started) and taken.
    pub(super) budget: Option<usize>,
    pub(super) taken: usize,
    /// Steps in a row that moved it less than a fifth of the way it wanted to go.
    pub(super) stuck: usize,
    /// What the character controller touched last on this walk, and where.
    pub(super) last_hit: Option<(ColliderHandle, Vector)>,
    /// The last step's start, what it moved and what it wanted to move.
    pub(super) last_move: (Vector, Vector, Vector),
}

impl Walk {
    pub(super) fn stage(
        dog: Idx,
        body: RigidBodyHandle,
        waypoints: Vec<Vector>,
        on_flight: bool,
    ) -> Stage {
        Stage::Walk(Walk {
            dog,
            body,
            waypoints,
            on_flight,
            next: 0,
            budget: None,
            taken: 0,
            stuck: 0,
            last_hit: None,
            last_move: (Vector::ZERO, Vector::ZERO, Vector::ZERO),
        })
    }
}

/// The legged robot turning to face `face`: the steps taken, and the yaw it turns to.
#[derive(Debug)]
pub(super) struct Turn {
    pub(super) face: Vector,
    pub(super) steps: usize,
    pub(super) yaw: f32,
}

/// An arm (by index) moving to joint angles `to`: from where it was when the move
/// starts, in `steps` steps, `taken` so far.
#[derive(Debug)]
pub(super) struct ArmMove {
    pub(super) arm: usize,
    pub(super) to: [f32; 3],
    /// The angles it starts from, the change, and the steps the move takes.
    pub(super) plan: Option<([f32; 3], [f32; 3], usize)>,
    pub(super) taken: usize,
}

impl ArmMove {
    pub(super) fn stage(arm: usize, to: [f32; 3]) -> Stage {
        Stage::Arm(ArmMove {
            arm,
            to,
            plan: None,
            taken: 0,
        })
    }
}

/// A hinged panel turning to `to` radians from the angle it has when it starts.
#[derive(Debug)]
pub(super) struct HingeTurn {
    pub(super) hinge: Hinge,
    pub(super) to: f32,
    pub(super) from: Option<f32>,
    pub(super) taken: usize,
}

/// Waiting at most `steps` steps for loose things to rest.
#[derive(Debug)]
pub(super) struct Settle {
    pub(super) steps: usize,
    pub(super) taken: usize,
    pub(super) resting: bool,
}

impl Settle {
    /// At most `max_s` simulated seconds, of steps of `dt` seconds.
    pub(super) fn new(max_s: f32, dt: f32) -> Settle {
        Settle {
            steps: (max_s / dt) as usize,
            taken: 0,
            resting: false,
        }
    }
}

impl World {
    /// Runs `m` up to its next simulation step: instant stages happen, finished ones
    /// are dropped, and the current stepping stage sets its controls. `false` once the
    /// motion is over.
    pub(super) fn prepare(&mut self, m: &mut Motion) -> Result<bool, PhysicsError> {
        while let Some(stage) = m.stages.front_mut() {
            let tick = match stage {
                Stage::Fly(f) => self.fly_tick(m.robot, f)?,
                Stage::Hover(h) => self.hover_tick(m.robot, h)?,
                Stage::Descend(d) => self.descend_tick(m.robot, d)?,
                Stage::Motors(on) => {
                    self.set_motors(m.robot, *on);
                    Tick::Done
                }
                Stage::Landed(s) => {
                    self.check_landed(m.robot, *s)?;
                    Tick::Done
                }
                Stage::Walk(w) => self.walk_tick(w)?,
                Stage::OffStairs(f, there) => {
                    self.check_off_stairs(m.robot, f, *there)?;
                    Tick::Done
                }
                Stage::Turn(t) => self.turn_tick(m.robot, t),
                Stage::Arm(a) => self.arm_tick(a),
                Stage::HandAt {
                    robot,
                    target,
                    what,
                } => {
                    self.check_hand_at(*robot, *target, what)?;
                    Tick::Done
                }
                Stage::Fasten { robot, object } => {
                    self.fasten(*robot, *object);
                    Tick::Done
                }
                Stage::Unfasten { robot, object } => {
                    self.unfasten(*robot, *object)?;
                    Tick::Done
                }
                Stage::Hinge(h) => self.hinge_tick(h),
                Stage::Settle(s) => self.settle_tick(s),
            };
            match tick {
                Tick::Step => return Ok(true),
                Tick::Done => {
                    m.stages.pop_front();
                }
                Tick::Then(next) => {
                    m.stages.pop_front();
                    for s in next.into_iter().rev() {
                        m.stages.push_front(s);
                    }
                }
            }
        }
        Ok(false)
    }

    /// Keeps `m`'s robot where it is for the next simulation step instead of advancing
    /// its motion: the quadrotor holds its set point (at rest), the others stay as they
    /// are (kinematic bodies and arm joints stay where they were last put).
    pub(super) fn hold(&mut self, m: &Motion) {
        if let Some(Stage::Fly(_) | Stage::Hover(_) | Stage::Descend(_)) = m.stages.front()
            && let Some(i) = self.quad_index(m.robot)
        {
            self.quads[i].target.1 = Vector::ZERO;
        }
    }

    /// What `m`'s current stage checks once the simulation step it asked for is done.
    pub(super) fn after_step(&mut self, m: &mut Motion) -> Result<(), PhysicsError> {
        let robot = m.robot;
        match m.stages.front_mut() {
            Some(Stage::Fly(_)) => self.fly_after(robot),
            Some(Stage::Hover(h)) => self.hover_after(robot, h),
            Some(Stage::Descend(d)) => {
                d.steps += 1;
                d.touches = self.quad_touches(robot, d.surface);
                Ok(())
            }
            Some(Stage::Walk(w)) => self.walk_after(w),
            Some(Stage::Settle(s)) => {
                self.settle_after(s);
                Ok(())
            }
            _ => Ok(()),
        }
    }
}
