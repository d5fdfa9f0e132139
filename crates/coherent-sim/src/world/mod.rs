//! The physical world of one task: Rapier bodies built from a [`Layout`], the three
//! robot models, physical execution of one action or of several robots' actions at
//! once, and the relations read back from the bodies. This file holds the [`World`] itself, what its robot models and panels keep
//! beside the bodies, the errors, and the lookups every job shares; the jobs are one
//! file each, each using only this one and those above it in this list:
//! - `motion.rs`: an action in progress, as stages advanced one simulation step at a
//!   time (what each stage keeps; the files below advance them);
//! - `step.rs`: one simulation step and the controllers it runs (the quadrotor's
//!   thrust controller, the arm chains following their roots);
//! - `arm.rs`: inverse kinematics and arm motion;
//! - `relations.rs`: where things are, read back from the bodies;
//! - `build.rs`: the bodies from the layout (rooms, walls, doors, stairs, furniture,
//!   objects, the robots and their arms);
//! - `quadrotor.rs`: take-off, flights between rooms and storeys, landing;
//! - `legged.rs`: the legged robot's routes and walking;
//! - `manipulation.rs`: grasping, putting down, opening and closing;
//! - `contact.rs`: robots acting at once that touch each other or what another handles;
//! - `execute.rs`: one action, or a joint step's actions at once, dispatched to the
//!   jobs above.
//! - `events.rs`: what an event mid-task does to the bodies (a thing moved by someone
//!   outside the team), with the free spots and the riders of `manipulation.rs`.
//!
//! Every step, tolerance, margin, speed and limit they work to is a field of the
//! world's [`Tolerances`] (`tolerances.rs`, which uses nothing of the others).

mod arm;
mod build;
mod contact;
mod events;
mod execute;
mod legged;
mod manipulation;
mod motion;
mod quadrotor;
mod relations;
mod step;
mod tolerances;

use std::collections::HashMap;
use std::sync::Arc;

use coherent_core::{Idx, NodeId, Task};
use rapier3d::control::KinematicCharacterController;
use rapier3d::prelude::*;

use crate::layout::{self, Flight, Layout};

pub use self::tolerances::Tolerances;

/// A physical failure, with numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct PhysicsError {
    pub kind: FailureKind,
    pub message: String,
}

/// What kind of physical failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FailureKind {
    /// Beyond an arm's reach (distance or height).
    Reach,
    /// A motion was blocked (closed door, no path, no free spot).
    Blocked,
    /// A motion did not settle in time.
    Timeout,
    /// The relations read back disagree with the symbolic state.
    Disagreement,
    /// The world could not be built.
    Layout,
    /// Robots acting at once touched each other, or what another of them handles.
    Collision,
}

impl std::fmt::Display for PhysicsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for PhysicsError {}

pub(crate) fn fail<T>(kind: FailureKind, message: String) -> Result<T, PhysicsError> {
    Err(PhysicsError { kind, message })
}

/// What a node physically rests on or in, or who holds it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    On(Idx),
    Inside(Idx),
    Held(Idx),
    /// Not resting on anything the graph names (falling, or on an unnamed thing).
    Loose,
}

/// The physical world of one task.
pub struct World {
    pub task: Arc<Task>,
    pub layout: Layout,
    pw: PhysicsWorld,
    body: Vec<Option<RigidBodyHandle>>,
    owner: HashMap<ColliderHandle, Idx>,
    volume: Vec<Option<Volume>>,
    /// Top surface: body, centre of the top in the body frame, half extents (x, z).
    top: Vec<Option<(RigidBodyHandle, Vector, [f32; 2])>>,
    hinges: Vec<Hinge>,
    arms: Vec<Arm>,
    /// The quadrotors and the legged robots, in the layout's order: a team may have
    /// several of each.
    quads: Vec<Quad>,
    dogs: Vec<Dog>,
    grasps: Vec<Grasp>,
    kcc: KinematicCharacterController,
    /// The legged robot on a flight: climbs slopes up to 45 degrees and keeps to the
    /// surface going down.
    stairs_kcc: KinematicCharacterController,
    flights: Vec<Flight>,
    flight_colliders: Vec<ColliderHandle>,
    pub sim_time: f64,
    /// Each mobile robot's track, `[x, y, z]` of its body, sampled every 20 cm on the
    /// floor plan and where it changes storey.
    pub paths: Vec<(NodeId, Vec<[f32; 3]>)>,
    /// What every job of the world works to.
    tol: Tolerances,
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("task", &self.task.meta.name)
            .field("sim_time", &self.sim_time)
            .finish()
    }
}

/// A hinged panel (door or lid), driven kinematically about its hinge.
#[derive(Clone, Debug)]
struct Hinge {
    node: Idx,
    body: RigidBodyHandle,
    /// World pose of the panel when closed.
    closed: Pose,
    pivot: Vector,
    axis: Vector,
    /// Signed angle that opens it (doors pick the side away from the robot).
    open_angle: f32,
    /// Where a hand pushes or pulls it, in the panel's frame.
    handle: Vector,
}

/// The pose of a hinged panel turned `angle` about its hinge from closed.
fn hinge_pose(h: &Hinge, angle: f32) -> Pose {
    let r = Rotation::from_axis_angle(h.axis, angle);
    let t = h.pivot + r * (h.closed.translation - h.pivot);
    Pose::from_parts(t, r * h.closed.rotation)
}

/// An arm as a multibody chain: yaw, shoulder pitch, elbow pitch, and a wrist that keeps
/// the hand level. Rapier ignores joint limits in IK: `limits` are enforced here.
#[derive(Clone, Debug)]
struct Arm {
    robot: Idx,
    root: RigidBodyHandle,
    joints: [MultibodyJointHandle; 4],
    hand: RigidBodyHandle,
    q: [f32; 4],
    limits: [(f32, f32); 3],
    reach: f32,
    /// Closest the hand gets to the shoulder with the elbow at its limit.
    min_reach: f32,
    shoulder_local: Vector,
}

#[derive(Clone, Debug)]
struct Quad {
    robot: Idx,
    body: RigidBodyHandle,
    motors_on: bool,
    /// Integral of the position error (m·s): removes the steady offset a payload or
    /// a tilted start leaves.
    integral: Vector,
    /// Rotor positions in the body frame.
    rotors: [Vector; 4],
    /// Where its controller steers the centre of mass, and at what velocity.
    target: (Vector, Vector),
}

#[derive(Clone, Debug)]
struct Dog {
    robot: Idx,
    body: RigidBodyHandle,
    yaw: f32,
}

/// A grasp: the joints that hold the object (and what rides on it) to the hand.
#[derive(Clone, Debug)]
struct Grasp {
    robot: Idx,
    object: Idx,
    joints: Vec<ImpulseJointHandle>,
    carried: Vec<RigidBodyHandle>,
}

/// Container inner volume: body, pose in the body, half extents.
#[derive(Clone, Copy, Debug)]
struct Volume {
    body: RigidBodyHandle,
    local: Pose,
    half: Vector,
}

const G_STATIC: Group = Group::GROUP_1;
const G_OBJECT: Group = Group::GROUP_2;
const G_QUAD: Group = Group::GROUP_3;
const G_DOG: Group = Group::GROUP_4;

fn groups(member: Group) -> InteractionGroups {
    InteractionGroups::new(member, Group::ALL, InteractionTestMode::And)
}

/// Queries see only colliders that collide (not arm links, not held things).
fn solid() -> QueryFilter<'static> {
    QueryFilter::default()
        .exclude_sensors()
        .groups(InteractionGroups::new(
            Group::ALL,
            Group::ALL,
            InteractionTestMode::And,
        ))
}

fn v3(a: [f32; 3]) -> Vector {
    Vector::new(a[0], a[1], a[2])
}

impl World {
    /// The step, tolerances, margins, speeds and limits the world works to.
    pub fn tolerances(&self) -> &Tolerances {
        &self.tol
    }

    fn label(&self, n: Idx) -> String {
        self.task.node(n).label()
    }

    /// The quadrotor `robot`'s index in `quads`.
    fn quad_index(&self, robot: Idx) -> Option<usize> {
        self.quads.iter().position(|q| q.robot == robot)
    }

    /// The quadrotor `robot`, or a layout failure naming it.
    fn quad_of(&self, robot: Idx) -> Result<&Quad, PhysicsError> {
        self.quads
            .iter()
            .find(|q| q.robot == robot)
            .ok_or_else(|| PhysicsError {
                kind: FailureKind::Layout,
                message: format!("{} is no quadrotor of the world", self.label(robot)),
            })
    }

    /// The legged robot `robot`, or a layout failure naming it.
    fn dog_of(&self, robot: Idx) -> Result<&Dog, PhysicsError> {
        self.dogs
            .iter()
            .find(|d| d.robot == robot)
            .ok_or_else(|| PhysicsError {
                kind: FailureKind::Layout,
                message: format!("{} is no legged robot of the world", self.label(robot)),
            })
    }

    fn quad_pos(&self, robot: Idx) -> Option<Vector> {
        let q = self.quads.iter().find(|q| q.robot == robot)?;
        Some(self.pw.bodies[q.body].translation())
    }

    fn record_path(&mut self, robot: Idx) {
        let Some(b) = self.body[robot.get()] else {
            return;
        };
        let t = self.pw.bodies[b].translation();
        let id = self.task.id(robot);
        let level = self.level_at(t);
        let Some((_, p)) = self.paths.iter().find(|(i, _)| *i == id) else {
            return;
        };
        let last = p.last().copied().unwrap_or([f32::NAN; 3]);
        // Every `track_spacing` on the floor plan, and where the robot changes storey.
        let moved = (last[0] - t.x).hypot(last[2] - t.z) > self.tol.track_spacing;
        let changed = self.level_at(Vector::new(last[0], last[1], last[2])) != level;
        if (moved || changed)
            && let Some((_, p)) = self.paths.iter_mut().find(|(i, _)| *i == id)
        {
            p.push([t.x, t.y, t.z]);
        }
    }

    fn room_rect(&self, room: Idx) -> Option<([f32; 2], [f32; 2])> {
        self.layout.room(self.task.id(room)).map(|r| (r.min, r.max))
    }

    /// The room `p` is in: its footprint holds `p` on the storey `p` is on
    /// ([`layout::room_at`]).
    pub fn room_at(&self, p: Vector) -> Option<Idx> {
        layout::room_at(&self.layout, [p.x, p.y, p.z]).and_then(|r| self.task.idx(NodeId(r.id)))
    }

    /// Floor height of the storey `p` is on (the lowest storey outside every room).
    fn level_at(&self, p: Vector) -> f32 {
        layout::room_at(&self.layout, [p.x, p.y, p.z]).map_or_else(
            || layout::levels(&self.layout).first().copied().unwrap_or(0.0),
            |r| r.level,
        )
    }

    fn room_level(&self, room: Idx) -> f32 {
        self.layout
            .room(self.task.id(room))
            .map_or(0.0, |r| r.level)
    }
}
