//! The physical world: Rapier bodies built from a [`Layout`], the three robot models,
//! physical execution of one action, and the relations read back from the bodies.

use std::collections::HashMap;
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
use std::sync::Arc;

use coherent_core::{Action, Idx, NodeId, NodeKind, PropSet, Relation, RobotKind, Task, Verb};
use rapier3d::control::{CharacterLength, KinematicCharacterController};
use rapier3d::na::DVector;
use rapier3d::prelude::*;

use crate::layout::{self, ASIDE, Flight, ItemGeom, Layout, Lid, WALL, wall_of};
use crate::path;

pub const DT: f32 = 1.0 / 60.0;
/// A wall of the lower room closer than this to a side of a flight rises with the
/// stairwell (the robots need no gap that narrow).
const STAIRWELL_GAP: f32 = 0.35;

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

const G_STATIC: Group = Group::GROUP_1;
const G_OBJECT: Group = Group::GROUP_2;
const G_QUAD: Group = Group::GROUP_3;
const G_DOG: Group = Group::GROUP_4;

fn groups(member: Group) -> InteractionGroups {
    InteractionGroups::new(member, Group::ALL, InteractionTestMode::And)
}

/// Queries see only colliders that collide (not arm links, not held things).
pub(crate) fn solid() -> QueryFilter<'static> {
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

const ARM_HOME: [f32; 3] = [0.0, -1.3, 2.4];

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
}

#[derive(Clone, Debug)]
struct Dog {
    robot: Idx,
    body: RigidBodyHandle,
    yaw: f32,
}

/// A stretch of the legged robot's way: waypoints on one storey (the first is where
/// it starts), or a flight walked from the approach at one end to the approach at the
/// other (given).
#[derive(Clone, Debug)]
enum Leg {
    Floor(Vec<Vector>),
    Flight(Flight, Vector),
}

/// How far before the foot and past the head the legged robot lines up with a flight.
const FLIGHT_APPROACH: f32 = 0.55;

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

/// The physical world of one task.
pub struct World {
    pub task: Arc<Task>,
    pub layout: Layout,
    pub(crate) pw: PhysicsWorld,
    body: Vec<Option<RigidBodyHandle>>,
    owner: HashMap<ColliderHandle, Idx>,
    volume: Vec<Option<Volume>>,
    /// Top surface: body, centre of the top in the body frame, half extents (x, z).
    top: Vec<Option<(RigidBodyHandle, Vector, [f32; 2])>>,
    hinges: Vec<Hinge>,
    arms: Vec<Arm>,
    quad: Option<Quad>,
    dog: Option<Dog>,
    grasps: Vec<Grasp>,
    kcc: KinematicCharacterController,
    /// The legged robot on a flight: climbs slopes up to 45 degrees and keeps to the
    /// surface going down.
    stairs_kcc: KinematicCharacterController,
    pub(crate) flights: Vec<Flight>,
    flight_colliders: Vec<ColliderHandle>,
    pub sim_time: f64,
    /// Each mobile robot's track, `[x, y, z]` of its body, sampled every 20 cm on the
    /// floor plan and where it changes storey.
    pub paths: Vec<(NodeId, Vec<[f32; 3]>)>,
    quad_target: (Vector, Vector),
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("task", &self.task.meta.name)
            .field("sim_time", &self.sim_time)
            .finish()
    }
}

impl World {
    pub fn new(task: Arc<Task>, layout: Layout) -> Result<World, PhysicsError> {
        let n = task.nodes.len();
        let flights = layout::flights(&layout).map_err(|e| PhysicsError {
            kind: FailureKind::Layout,
            message: e.0,
        })?;
        let mut pw = PhysicsWorld::new();
        pw.integration_parameters.dt = DT;
        let mut w = World {
            task: task.clone(),
            layout,
            pw,
            body: vec![None; n],
            owner: HashMap::new(),
            volume: vec![None; n],
            top: vec![None; n],
            hinges: Vec::new(),
            arms: Vec::new(),
            quad: None,
            dog: None,
            grasps: Vec::new(),
            kcc: KinematicCharacterController::default(),
            stairs_kcc: KinematicCharacterController {
                // The robot's bottom stays 2 cm above what it walks on, as on a floor.
                offset: CharacterLength::Absolute(0.02),
                max_slope_climb_angle: FRAC_PI_4,
                min_slope_slide_angle: FRAC_PI_4,
                snap_to_ground: Some(CharacterLength::Absolute(0.2)),
                autostep: None,
                ..KinematicCharacterController::default()
            },
            flights,
            flight_colliders: Vec::new(),
            sim_time: 0.0,
            paths: Vec::new(),
            quad_target: (Vector::ZERO, Vector::ZERO),
        };
        w.kcc.offset = CharacterLength::Absolute(0.01);
        w.kcc.snap_to_ground = None;
        w.kcc.autostep = None;
        w.build_rooms()?;
        w.build_items()?;
        w.build_robots()?;
        for h in w.hinges.clone() {
            let open = task.init.states(h.node).is_open();
            let angle = if open { h.open_angle } else { 0.0 };
            let pose = hinge_pose(&h, angle);
            if let Some(b) = w.pw.bodies.get_mut(h.body) {
                b.set_position(pose, true);
            }
        }
        w.settle(1.0);
        Ok(w)
    }

    fn node_of(&self, id: i64) -> Result<Idx, PhysicsError> {
        self.task.idx(NodeId(id)).ok_or_else(|| PhysicsError {
            kind: FailureKind::Layout,
            message: format!("geometry names node {id}, which is not in the task"),
        })
    }

    fn label(&self, n: Idx) -> String {
        self.task.node(n).label()
    }

    fn add_collider(&mut self, c: ColliderBuilder, body: RigidBodyHandle, owner: Option<Idx>) {
        let h = self
            .pw
            .colliders
            .insert_with_parent(c, body, &mut self.pw.bodies);
        if let Some(o) = owner {
            self.owner.insert(h, o);
        }
    }

    fn build_rooms(&mut self) -> Result<(), PhysicsError> {
        let ground = self.pw.insert_body(RigidBodyBuilder::fixed());
        let wh = self.layout.wall_height;
        self.add_collider(
            ColliderBuilder::cuboid(8.0, 0.05, 8.0)
                .translation(Vector::new(ASIDE[0] - 4.0, -0.05, ASIDE[1] - 4.0))
                .collision_groups(groups(G_STATIC)),
            ground,
            None,
        );
        for r in self.layout.rooms.clone() {
            let room = self.node_of(r.id)?;
            let floor = self.task.floor_of(room);
            let (cx, cz) = ((r.min[0] + r.max[0]) / 2.0, (r.min[1] + r.max[1]) / 2.0);
            let (hx, hz) = ((r.max[0] - r.min[0]) / 2.0, (r.max[1] - r.min[1]) / 2.0);
            self.add_collider(
                ColliderBuilder::cuboid(hx, 0.05, hz)
                    .translation(Vector::new(cx, r.level - 0.05, cz))
                    .collision_groups(groups(G_STATIC)),
                ground,
                floor,
            );
            if let Some(f) = floor {
                self.top[f.get()] = Some((ground, Vector::new(cx, r.level, cz), [hx, hz]));
            }
            // Four walls, cut where a door opens in them.
            let sides = [
                (true, r.min[1], r.min[0], r.max[0]),
                (true, r.max[1], r.min[0], r.max[0]),
                (false, r.min[0], r.min[1], r.max[1]),
                (false, r.max[0], r.min[1], r.max[1]),
            ];
            let mut raised = Vec::new();
            for (along_x, at, a0, a1) in sides {
                let mut cuts: Vec<(f32, f32, f32)> = self
                    .layout
                    .doors
                    .iter()
                    .filter(|d| {
                        d.along_x == along_x
                            && layout::door_level(&self.layout, d) == r.level
                            && (if along_x { d.center[1] } else { d.center[0] } - at).abs() < 1e-3
                    })
                    .map(|d| {
                        let c = if along_x { d.center[0] } else { d.center[1] };
                        (c - d.width / 2.0, c + d.width / 2.0, d.height)
                    })
                    .collect();
                // Where a flight arrives: an opening the flight's width, the wall's full
                // height.
                cuts.extend(
                    self.flights
                        .iter()
                        .filter(|f| {
                            f.rooms[1] == r.id
                                && f.along_x() != along_x
                                && (if along_x { f.head[1] } else { f.head[0] } - at).abs() < 1e-3
                        })
                        .map(|f| {
                            let c = if along_x { f.head[0] } else { f.head[1] };
                            (c - f.width / 2.0, c + f.width / 2.0, wh)
                        }),
                );
                cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
                // Beside a flight of this room, the wall rises to the top of the upper
                // storey's walls: the stairwell is walled up to there.
                for f in self
                    .flights
                    .iter()
                    .filter(|f| f.rooms[0] == r.id && f.along_x() == along_x)
                {
                    let rect = f.rect();
                    let (e0, e1, s0, s1) = if along_x {
                        (rect[1], rect[3], rect[0], rect[2])
                    } else {
                        (rect[0], rect[2], rect[1], rect[3])
                    };
                    if (e0 - at).abs() < STAIRWELL_GAP || (e1 - at).abs() < STAIRWELL_GAP {
                        raised.push((along_x, at, s0.max(a0), s1.min(a1), f.upper - r.level + wh));
                    }
                }
                let mut start = a0;
                let mut pieces = Vec::new();
                for (c0, c1, h) in cuts {
                    pieces.push((start, c0, 0.0, wh));
                    pieces.push((c0, c1, h, wh)); // lintel
                    start = c1;
                }
                pieces.push((start, a1, 0.0, wh));
                for (p0, p1, y0, y1) in pieces {
                    if p1 - p0 < 1e-3 || y1 - y0 < 1e-3 {
                        continue;
                    }
                    let (m, half) = ((p0 + p1) / 2.0, (p1 - p0) / 2.0);
                    let (t, hx, hz) = if along_x {
                        (Vector::new(m, r.level + (y0 + y1) / 2.0, at), half, WALL)
                    } else {
                        (Vector::new(at, r.level + (y0 + y1) / 2.0, m), WALL, half)
                    };
                    self.add_collider(
                        ColliderBuilder::cuboid(hx, (y1 - y0) / 2.0, hz)
                            .translation(t)
                            .collision_groups(groups(G_STATIC)),
                        ground,
                        None,
                    );
                }
            }
            for (along_x, at, p0, p1, top) in raised {
                let (m, half, y) = ((p0 + p1) / 2.0, (p1 - p0) / 2.0, (wh + top) / 2.0);
                let (t, hx, hz) = if along_x {
                    (Vector::new(m, r.level + y, at), half, WALL)
                } else {
                    (Vector::new(at, r.level + y, m), WALL, half)
                };
                self.add_collider(
                    ColliderBuilder::cuboid(hx, (top - wh) / 2.0, hz)
                        .translation(t)
                        .collision_groups(groups(G_STATIC)),
                    ground,
                    None,
                );
            }
        }
        for f in self.flights.clone() {
            self.build_flight(ground, &f)?;
        }
        for d in self.layout.doors.clone() {
            let door = self.node_of(d.id)?;
            let level = layout::door_level(&self.layout, &d);
            let (w2, h2) = (d.width / 2.0 - 0.02, d.height / 2.0 - 0.01);
            // Hinge on the low end of the opening.
            let (pivot, centre, shape) = if d.along_x {
                (
                    Vector::new(d.center[0] - d.width / 2.0 + 0.02, level, d.center[1]),
                    Vector::new(d.center[0], level + h2 + 0.01, d.center[1]),
                    ColliderBuilder::cuboid(w2, h2, 0.025),
                )
            } else {
                (
                    Vector::new(d.center[0], level, d.center[1] - d.width / 2.0 + 0.02),
                    Vector::new(d.center[0], level + h2 + 0.01, d.center[1]),
                    ColliderBuilder::cuboid(0.025, h2, w2),
                )
            };
            let closed = Pose::from_translation(centre);
            let body = self
                .pw
                .insert_body(RigidBodyBuilder::kinematic_position_based().pose(closed));
            self.add_collider(shape.collision_groups(groups(G_STATIC)), body, Some(door));
            self.body[door.get()] = Some(body);
            let handle_world = if d.along_x {
                Vector::new(d.center[0] + d.width / 2.0 - 0.12, level + 0.9, d.center[1])
            } else {
                Vector::new(d.center[0], level + 0.9, d.center[1] + d.width / 2.0 - 0.12)
            };
            self.hinges.push(Hinge {
                node: door,
                body,
                closed,
                pivot,
                axis: Vector::Y,
                open_angle: FRAC_PI_2,
                handle: closed.inverse_transform_point(handle_world),
            });
        }
        Ok(())
    }

    /// A flight of stairs: a solid wedge under the run whose sloped top passes through
    /// the nosings of its steps, from the lower floor at the foot to the upper floor at
    /// the head.
    fn build_flight(&mut self, ground: RigidBodyHandle, f: &Flight) -> Result<(), PhysicsError> {
        let side = Vector::new(f.dir[1].abs(), 0.0, f.dir[0].abs()) * (f.width / 2.0);
        let foot = Vector::new(f.foot[0], f.lower, f.foot[1]);
        let head = Vector::new(f.head[0], f.lower, f.head[1]);
        let top = Vector::new(f.head[0], f.upper, f.head[1]);
        let points = [
            foot - side,
            foot + side,
            head - side,
            head + side,
            top - side,
            top + side,
        ];
        let Some(wedge) = ColliderBuilder::convex_hull(&points) else {
            return fail(
                FailureKind::Layout,
                format!("stairs {}: the flight has no volume", f.id),
            );
        };
        let h = self.pw.colliders.insert_with_parent(
            wedge.friction(0.9).collision_groups(groups(G_STATIC)),
            ground,
            &mut self.pw.bodies,
        );
        self.flight_colliders.push(h);
        Ok(())
    }

    fn build_items(&mut self) -> Result<(), PhysicsError> {
        for it in self.layout.items.clone() {
            let n = self.node_of(it.id)?;
            let [w, h, d] = it.size;
            let base = v3(it.pos);
            let builder = if it.dynamic {
                RigidBodyBuilder::dynamic()
                    .translation(base)
                    .angular_damping(0.5)
                    .linear_damping(0.1)
            } else {
                RigidBodyBuilder::fixed().translation(base)
            };
            let body = self.pw.insert_body(builder);
            self.body[n.get()] = Some(body);
            let gr = groups(if it.dynamic { G_OBJECT } else { G_STATIC });
            let density = if it.dynamic { 100.0 } else { 1000.0 };
            if it.container {
                let t = wall_of(h);
                // Floor and four walls: an open box.
                let parts = [
                    (Vector::new(0.0, t / 2.0, 0.0), [w / 2.0, t / 2.0, d / 2.0]),
                    (
                        Vector::new(-w / 2.0 + t / 2.0, h / 2.0, 0.0),
                        [t / 2.0, h / 2.0, d / 2.0],
                    ),
                    (
                        Vector::new(w / 2.0 - t / 2.0, h / 2.0, 0.0),
                        [t / 2.0, h / 2.0, d / 2.0],
                    ),
                    (
                        Vector::new(0.0, h / 2.0, d / 2.0 - t / 2.0),
                        [w / 2.0, h / 2.0, t / 2.0],
                    ),
                ];
                for (c, e) in parts {
                    self.add_collider(
                        ColliderBuilder::cuboid(e[0], e[1], e[2])
                            .translation(c)
                            .density(density)
                            .friction(0.8)
                            .collision_groups(gr),
                        body,
                        Some(n),
                    );
                }
                // The front wall is the door of a front-opening container.
                if it.lid != Lid::Front {
                    self.add_collider(
                        ColliderBuilder::cuboid(w / 2.0, h / 2.0, t / 2.0)
                            .translation(Vector::new(0.0, h / 2.0, -d / 2.0 + t / 2.0))
                            .density(density)
                            .collision_groups(gr),
                        body,
                        Some(n),
                    );
                } else {
                    // Its top is a surface.
                    self.add_collider(
                        ColliderBuilder::cuboid(w / 2.0, t / 2.0, d / 2.0)
                            .translation(Vector::new(0.0, h - t / 2.0, 0.0))
                            .collision_groups(gr),
                        body,
                        Some(n),
                    );
                }
                let inner_h = if it.lid == Lid::Front {
                    h - 2.0 * t
                } else {
                    h - t
                };
                self.volume[n.get()] = Some(Volume {
                    body,
                    local: Pose::from_translation(Vector::new(0.0, t + inner_h / 2.0, 0.0)),
                    half: Vector::new(w / 2.0 - t, inner_h / 2.0, d / 2.0 - t),
                });
                if it.lid != Lid::None {
                    self.build_lid(n, &it, t)?;
                }
            } else {
                self.add_collider(
                    ColliderBuilder::cuboid(w / 2.0, h / 2.0, d / 2.0)
                        .translation(Vector::new(0.0, h / 2.0, 0.0))
                        .density(density)
                        .friction(0.8)
                        .collision_groups(gr),
                    body,
                    Some(n),
                );
            }
            if self.task.node(n).properties.contains(PropSet::SURFACES) {
                self.top[n.get()] = Some((body, Vector::new(0.0, h, 0.0), [w / 2.0, d / 2.0]));
            }
        }
        Ok(())
    }

    fn build_lid(&mut self, n: Idx, it: &ItemGeom, t: f32) -> Result<(), PhysicsError> {
        let [w, h, d] = it.size;
        let base = v3(it.pos);
        let (closed, pivot, axis, shape, handle) = match it.lid {
            Lid::Top => (
                Pose::from_translation(base + Vector::new(0.0, h + t / 2.0, 0.0)),
                base + Vector::new(0.0, h, d / 2.0),
                Vector::X,
                ColliderBuilder::cuboid(w / 2.0, t / 2.0, d / 2.0),
                Vector::new(0.0, t / 2.0, -d / 2.0 + 0.03),
            ),
            _ => (
                Pose::from_translation(base + Vector::new(0.0, h / 2.0, -d / 2.0 + t / 2.0)),
                base + Vector::new(-w / 2.0, 0.0, -d / 2.0),
                Vector::Y,
                ColliderBuilder::cuboid(w / 2.0, h / 2.0, t / 2.0),
                Vector::new(w / 2.0 - 0.05, 0.0, -t / 2.0),
            ),
        };
        let body = self
            .pw
            .insert_body(RigidBodyBuilder::kinematic_position_based().pose(closed));
        let gr = groups(if it.dynamic { G_OBJECT } else { G_STATIC });
        self.add_collider(shape.collision_groups(gr), body, Some(n));
        // Top lids open upwards (about +x with the pivot at the back: negative angle lifts
        // the front); front doors swing out to the left.
        let open_angle = -1.9;
        self.hinges.push(Hinge {
            node: n,
            body,
            closed,
            pivot,
            axis,
            open_angle,
            handle,
        });
        Ok(())
    }

    fn build_robots(&mut self) -> Result<(), PhysicsError> {
        let specs = self.layout.specs.clone();
        for rg in self.layout.robots.clone() {
            let r = self.node_of(rg.id)?;
            let Some(robot) = self.task.robot(r).copied() else {
                return fail(
                    FailureKind::Layout,
                    format!("{} is not a robot", self.label(r)),
                );
            };
            let rot = Rotation::from_rotation_y(rg.yaw);
            match robot.kind {
                RobotKind::Quadrotor => {
                    let pose = Pose::from_parts(v3(rg.pos) + Vector::new(0.0, 0.003, 0.0), rot);
                    let body = self.pw.insert_body(
                        RigidBodyBuilder::dynamic()
                            .pose(pose)
                            .linear_damping(0.3)
                            .angular_damping(1.0)
                            .can_sleep(false),
                    );
                    let basket = self.task.basket_of(r);
                    let b = specs.basket_half;
                    let q = specs.quad_half;
                    let t = 0.02;
                    let wall_h = 0.14;
                    let gr = groups(G_QUAD);
                    let owner = basket.or(Some(r));
                    // Basket: floor and walls. Its mass is most of the craft's.
                    let total = specs.quad_mass;
                    let parts = [
                        (Vector::new(0.0, t / 2.0, 0.0), [b, t / 2.0, b]),
                        (
                            Vector::new(-b + t / 2.0, wall_h / 2.0, 0.0),
                            [t / 2.0, wall_h / 2.0, b],
                        ),
                        (
                            Vector::new(b - t / 2.0, wall_h / 2.0, 0.0),
                            [t / 2.0, wall_h / 2.0, b],
                        ),
                        (
                            Vector::new(0.0, wall_h / 2.0, b - t / 2.0),
                            [b, wall_h / 2.0, t / 2.0],
                        ),
                        (
                            Vector::new(0.0, wall_h / 2.0, -b + t / 2.0),
                            [b, wall_h / 2.0, t / 2.0],
                        ),
                    ];
                    for (c, e) in parts {
                        self.add_collider(
                            ColliderBuilder::cuboid(e[0], e[1], e[2])
                                .translation(c)
                                .mass(total * 0.1)
                                .friction(0.9)
                                .collision_groups(gr),
                            body,
                            owner,
                        );
                    }
                    let rotors = [
                        Vector::new(q - 0.08, 0.24, q - 0.08),
                        Vector::new(-q + 0.08, 0.24, q - 0.08),
                        Vector::new(-q + 0.08, 0.24, -q + 0.08),
                        Vector::new(q - 0.08, 0.24, -q + 0.08),
                    ];
                    for p in rotors {
                        self.add_collider(
                            ColliderBuilder::cylinder(0.01, 0.08)
                                .translation(p)
                                .mass(total * 0.1)
                                .collision_groups(gr),
                            body,
                            Some(r),
                        );
                    }
                    self.add_collider(
                        ColliderBuilder::cuboid(0.06, 0.03, 0.06)
                            .translation(Vector::new(0.0, 0.25, 0.0))
                            .mass(total * 0.1)
                            .collision_groups(gr),
                        body,
                        Some(r),
                    );
                    self.body[r.get()] = Some(body);
                    if let Some(bk) = basket {
                        self.body[bk.get()] = Some(body);
                        self.volume[bk.get()] = Some(Volume {
                            body,
                            local: Pose::from_translation(Vector::new(0.0, t + 0.06, 0.0)),
                            half: Vector::new(b - t, 0.06, b - t),
                        });
                    }
                    self.quad = Some(Quad {
                        robot: r,
                        body,
                        motors_on: false,
                        integral: Vector::ZERO,
                        rotors,
                    });
                    self.paths.push((self.task.id(r), vec![rg.pos]));
                }
                RobotKind::RobotDog => {
                    let h = specs.dog_half;
                    let pose = Pose::from_parts(v3(rg.pos) + Vector::new(0.0, 0.02, 0.0), rot);
                    let body = self
                        .pw
                        .insert_body(RigidBodyBuilder::kinematic_position_based().pose(pose));
                    let collider = self.pw.colliders.insert_with_parent(
                        ColliderBuilder::cylinder(h[1], h[0].max(h[2]))
                            .translation(Vector::new(0.0, h[1], 0.0))
                            .collision_groups(groups(G_DOG)),
                        body,
                        &mut self.pw.bodies,
                    );
                    self.owner.insert(collider, r);
                    self.body[r.get()] = Some(body);
                    self.dog = Some(Dog {
                        robot: r,
                        body,
                        yaw: rg.yaw,
                    });
                    let shoulder = v3(specs.dog_shoulder);
                    self.build_arm(r, body, shoulder, specs.dog_links)?;
                    self.paths.push((self.task.id(r), vec![rg.pos]));
                }
                RobotKind::RobotArm => {
                    let pose = Pose::from_parts(v3(rg.pos), rot);
                    let body = self.pw.insert_body(RigidBodyBuilder::fixed().pose(pose));
                    self.add_collider(
                        ColliderBuilder::cylinder(specs.arm_shoulder / 2.0, 0.08)
                            .translation(Vector::new(0.0, specs.arm_shoulder / 2.0, 0.0))
                            .collision_groups(InteractionGroups::none()),
                        body,
                        Some(r),
                    );
                    self.body[r.get()] = Some(body);
                    let shoulder = Vector::new(0.0, specs.arm_shoulder, 0.0);
                    self.build_arm(r, body, shoulder, specs.arm_links)?;
                }
            }
        }
        Ok(())
    }

    fn build_arm(
        &mut self,
        robot: Idx,
        root: RigidBodyHandle,
        shoulder: Vector,
        links: [f32; 2],
    ) -> Result<(), PhysicsError> {
        let root_pose = *self.pw.bodies[root].position();
        let start = root_pose.transform_point(shoulder);
        // Links touch nothing: the arms have no motion planning around obstacles.
        let link = |pw: &mut PhysicsWorld, half_len: f32| {
            let b = pw.insert_body(
                RigidBodyBuilder::dynamic()
                    .translation(start)
                    .gravity_scale(0.0)
                    .can_sleep(false),
            );
            pw.colliders.insert_with_parent(
                ColliderBuilder::capsule_z(half_len.max(0.01), 0.03)
                    .translation(Vector::new(0.0, 0.0, -half_len))
                    .density(500.0)
                    .collision_groups(InteractionGroups::none()),
                b,
                &mut pw.bodies,
            );
            b
        };
        let yaw = link(&mut self.pw, 0.01);
        let upper = link(&mut self.pw, links[0] / 2.0);
        let fore = link(&mut self.pw, links[1] / 2.0);
        let hand = link(&mut self.pw, 0.02);
        let j = [
            RevoluteJointBuilder::new(Vector::Y)
                .local_anchor1(shoulder)
                .local_anchor2(Vector::ZERO),
            RevoluteJointBuilder::new(Vector::X)
                .local_anchor1(Vector::ZERO)
                .local_anchor2(Vector::ZERO),
            RevoluteJointBuilder::new(Vector::X)
                .local_anchor1(Vector::new(0.0, 0.0, links[0]))
                .local_anchor2(Vector::new(0.0, 0.0, -links[1])),
            RevoluteJointBuilder::new(Vector::X)
                .local_anchor1(Vector::ZERO)
                .local_anchor2(Vector::ZERO),
        ];
        let chain = [root, yaw, upper, fore, hand];
        let mut handles = Vec::new();
        for (i, jb) in j.into_iter().enumerate() {
            let h = self
                .pw
                .multibody_joints
                .insert_kinematic(chain[i], chain[i + 1], jb, true)
                .ok_or_else(|| PhysicsError {
                    kind: FailureKind::Layout,
                    message: format!("cannot build the arm of {}", self.label(robot)),
                })?;
            handles.push(h);
        }
        let joints = [handles[0], handles[1], handles[2], handles[3]];
        let mut arm = Arm {
            robot,
            root,
            joints,
            hand,
            q: [0.0; 4],
            limits: [(-PI, PI), (-1.6, 1.6), (0.0, 2.6)],
            reach: links[0] + links[1],
            min_reach: {
                let c = 2.6f32.cos();
                (links[0] * links[0] + links[1] * links[1] + 2.0 * links[0] * links[1] * c)
                    .max(0.0)
                    .sqrt()
            },
            shoulder_local: shoulder,
        };
        let home = [ARM_HOME[0], ARM_HOME[1], ARM_HOME[2]];
        self.set_arm(&mut arm, home);
        self.arms.push(arm);
        Ok(())
    }

    /// Sets an arm's joints (the wrist keeps the hand level) and updates its links.
    fn set_arm(&mut self, arm: &mut Arm, q: [f32; 3]) {
        let target = [q[0], q[1], q[2], -(q[1] + q[2])];
        let Some((mb, _)) = self.pw.multibody_joints.get_mut(arm.joints[0]) else {
            return;
        };
        let mut disp = vec![0.0; mb.ndofs()];
        for (k, jh) in arm.joints.iter().enumerate() {
            let _ = jh;
            let link_id = k + 1;
            if let Some(link) = mb.link(link_id) {
                let a = link.assembly_id();
                if a < disp.len() {
                    disp[a] = target[k] - arm.q[k];
                }
            }
        }
        mb.apply_displacements(&disp);
        arm.q = target;
        self.sync_arm(arm.joints[0], arm.root);
    }

    /// Puts an arm's chain where its root body is now: Rapier reads a non-dynamic root's
    /// pose only when the root's type changes, so the pose is copied in here.
    fn sync_arm(&mut self, joint: MultibodyJointHandle, root: RigidBodyHandle) {
        let root_pose = *self.pw.bodies[root].position();
        self.sync_arm_to(joint, root_pose);
    }

    /// Puts an arm's chain on a root at `root_pose`.
    fn sync_arm_to(&mut self, joint: MultibodyJointHandle, root_pose: Pose) {
        if let Some((mb, _)) = self.pw.multibody_joints.get_mut(joint) {
            // `true`: on the first call the root turns from dynamic to fixed and takes
            // the body's pose rather than the identity.
            mb.forward_kinematics(&self.pw.bodies, true);
            mb.root_mut().joint.data.local_frame1 = root_pose;
            mb.forward_kinematics(&self.pw.bodies, false);
            mb.update_rigid_bodies(&mut self.pw.bodies, false);
        }
    }

    fn arm_index(&self, robot: Idx) -> Option<usize> {
        self.arms.iter().position(|a| a.robot == robot)
    }

    /// World position of an arm's shoulder.
    fn shoulder(&self, arm: &Arm) -> Vector {
        self.pw.bodies[arm.root]
            .position()
            .transform_point(arm.shoulder_local)
    }

    fn hand_pos(&self, arm: &Arm) -> Vector {
        self.pw.bodies[arm.hand].translation()
    }

    /// Joint angles that put the hand at `target`, within the limits; error with the
    /// numbers when the clamped solution misses by more than 2 cm.
    fn solve_ik(&self, arm: &Arm, target: Vector, what: &str) -> Result<[f32; 3], PhysicsError> {
        let shoulder = self.shoulder(arm);
        let dist = (target - shoulder).length();
        let me = self.label(arm.robot);
        let Some((mb, _)) = self.pw.multibody_joints.get(arm.joints[0]) else {
            return fail(FailureKind::Layout, format!("{me} has no arm"));
        };
        let fore_link = 3;
        let options = InverseKinematicsOption {
            damping: 0.05,
            max_iters: 80,
            constrained_axes: JointAxesMask::LIN_AXES,
            epsilon_linear: 1e-3,
            epsilon_angular: 1.0,
        };
        let pose = Pose::from_translation(target);
        // The yaw towards the target as a seed avoids the solver's local minima.
        let local = self.pw.bodies[arm.root]
            .position()
            .inverse_transform_point(target)
            - arm.shoulder_local;
        let yaw = local.x.atan2(local.z);
        let mut best: Option<([f32; 3], f32)> = None;
        for seed in [
            [yaw, -0.6, 1.4],
            [yaw, 0.2, 0.6],
            [arm.q[0], arm.q[1], arm.q[2]],
        ] {
            let mut disp = DVector::zeros(mb.ndofs());
            let assembly = |k: usize| mb.link(k + 1).map(|l| l.assembly_id());
            for k in 0..4 {
                let want = if k < 3 { seed[k] } else { -(seed[1] + seed[2]) };
                if let Some(a) = assembly(k) {
                    disp[a] = want - arm.q[k];
                }
            }
            mb.inverse_kinematics(
                &self.pw.bodies,
                fore_link,
                &options,
                &pose,
                |l| l.link_id() <= 3,
                &mut disp,
            );
            let mut q = [0.0f32; 3];
            for (k, qk) in q.iter_mut().enumerate() {
                let raw = assembly(k).map_or(0.0, |a| disp[a]) + arm.q[k];
                let wrapped = if k == 0 { wrap(raw) } else { raw };
                *qk = wrapped.clamp(arm.limits[k].0, arm.limits[k].1);
            }
            // Forward kinematics of the clamped solution: the residual that counts.
            let mut check = DVector::zeros(mb.ndofs());
            for (k, qk) in q.iter().enumerate() {
                if let Some(a) = assembly(k) {
                    check[a] = qk - arm.q[k];
                }
            }
            let reached = mb.forward_kinematics_single_link(
                &self.pw.bodies,
                fore_link,
                Some(check.as_slice()),
                None,
            );
            let residual = (reached.translation - target).length();
            if best.is_none_or(|(_, r)| residual < r) {
                best = Some((q, residual));
            }
        }
        let (q, residual) = best.unwrap_or(([0.0; 3], f32::INFINITY));
        if residual > 0.02 {
            return fail(
                FailureKind::Reach,
                format!(
                    "{what} at ({:.2}, {:.2}, {:.2}) m is {dist:.2} m from the shoulder of {me} at height {:.2} m; its reach is {:.2} m (best joint solution within limits misses by {residual:.2} m)",
                    target.x, target.y, target.z, shoulder.y, arm.reach
                ),
            );
        }
        Ok(q)
    }

    /// Moves an arm to `q` at a bounded joint speed, simulating as it goes.
    fn move_arm(&mut self, ai: usize, q: [f32; 3]) {
        let mut arm = self.arms[ai].clone();
        let from = [arm.q[0], arm.q[1], arm.q[2]];
        let mut dq = [0.0; 3];
        for k in 0..3 {
            dq[k] = q[k] - from[k];
            if k == 0 {
                dq[k] = wrap(dq[k]);
            }
        }
        let biggest = dq.iter().fold(0.0f32, |m, d| m.max(d.abs()));
        let steps = ((biggest / 1.5 / DT).ceil() as usize).max(10);
        for s in 1..=steps {
            let f = s as f32 / steps as f32;
            let qs = [
                from[0] + dq[0] * f,
                from[1] + dq[1] * f,
                from[2] + dq[2] * f,
            ];
            self.set_arm(&mut arm, qs);
            self.arms[ai] = arm.clone();
            self.step();
        }
    }

    /// Moves the hand of `robot` to `target`, or says why it cannot.
    fn reach(&mut self, robot: Idx, target: Vector, what: &str) -> Result<(), PhysicsError> {
        let Some(ai) = self.arm_index(robot) else {
            return fail(
                FailureKind::Reach,
                format!("{} has no arm", self.label(robot)),
            );
        };
        let arm = self.arms[ai].clone();
        if self.task.robot(robot).map(|r| r.kind) == Some(RobotKind::RobotDog) {
            // Relative to the floor the robot stands on (its body walks 2 cm above it).
            let stand = self.pw.bodies[arm.root].translation().y - 0.02;
            let top = stand + self.layout.specs.dog_max_height();
            let shoulder = self.shoulder(&arm);
            let top_here = shoulder.y + arm.reach;
            if target.y > top_here.max(top) + 0.01 {
                return fail(
                    FailureKind::Reach,
                    format!(
                        "{what} at {:.2} m is above the legged robot's reach of {:.2} m (shoulder at {:.2} m + arm {:.2} m)",
                        target.y, top_here, shoulder.y, arm.reach
                    ),
                );
            }
        }
        let q = self.solve_ik(&arm, target, what)?;
        self.move_arm(ai, q);
        let hand = self.hand_pos(&self.arms[ai]);
        let miss = (hand - target).length();
        if miss > 0.03 {
            return fail(
                FailureKind::Reach,
                format!(
                    "the hand of {} stopped {miss:.3} m from {what}",
                    self.label(robot)
                ),
            );
        }
        Ok(())
    }

    fn arm_home(&mut self, robot: Idx) {
        if let Some(ai) = self.arm_index(robot) {
            self.move_arm(ai, ARM_HOME);
        }
    }

    pub(crate) fn step(&mut self) {
        self.control_quad();
        // A multibody writes its root link's pose into the root body during the step, so
        // the root link is put where a kinematic root (the walking dog) is going first;
        // otherwise the root's kinematic target is overwritten and it never moves.
        for i in 0..self.arms.len() {
            let (j, r) = (self.arms[i].joints[0], self.arms[i].root);
            let rb = &self.pw.bodies[r];
            let next = if rb.is_kinematic() {
                *rb.next_position()
            } else {
                *rb.position()
            };
            self.sync_arm_to(j, next);
        }
        self.pw.step();
        // Kinematic arm joints follow their root (the moving dog) after each step.
        for i in 0..self.arms.len() {
            let (j, r) = (self.arms[i].joints[0], self.arms[i].root);
            self.sync_arm(j, r);
        }
        self.sim_time += f64::from(DT);
    }

    /// Steps until loose things rest (or `max_s` simulated seconds).
    pub(crate) fn settle(&mut self, max_s: f32) {
        let steps = (max_s / DT) as usize;
        for i in 0..steps {
            self.step();
            if i >= 10 && self.resting() {
                break;
            }
        }
    }

    fn resting(&self) -> bool {
        self.layout.items.iter().filter(|it| it.dynamic).all(|it| {
            self.task
                .idx(NodeId(it.id))
                .and_then(|n| self.body[n.get()])
                .is_none_or(|b| {
                    let rb = &self.pw.bodies[b];
                    rb.linvel().length() < 0.01 && rb.angvel().length() < 0.05
                })
        })
    }

    // ---------------------------------------------------------------- quadrotor

    fn control_quad(&mut self) {
        let Some(q) = self.quad.clone() else { return };
        let target = self.quad_target;
        let (payload, load_at) = if q.motors_on {
            self.basket_load()
        } else {
            (0.0, Vector::ZERO)
        };
        let rb = &mut self.pw.bodies[q.body];
        rb.reset_forces(false);
        rb.reset_torques(false);
        if !q.motors_on {
            return;
        }
        let craft = rb.mass();
        // Feed-forward: what rides in the basket weighs on it too.
        let m = craft + payload;
        let p = rb.center_of_mass();
        let v = rb.linvel();
        let w = rb.angvel();
        let rot = *rb.rotation();
        // Position loop (PID): desired acceleration, tilt limited.
        let (tp, tv) = target;
        // Horizontally only while hovering: it would wind up on the tracking lag of a
        // long flight and overshoot at the end of it.
        let err = tp - p;
        let err = if tv.length() < 1e-3 {
            err
        } else {
            Vector::new(0.0, err.y, 0.0)
        };
        let mut integral = q.integral + err * DT;
        if integral.length() > 0.5 {
            integral = integral.normalize() * 0.5;
        }
        if let Some(qm) = self.quad.as_mut() {
            qm.integral = integral;
        }
        let rb = &mut self.pw.bodies[q.body];
        let mut acc = (tp - p) * 3.0 + (tv - v) * 3.5 + integral * 1.5;
        let horiz = Vector::new(acc.x, 0.0, acc.z);
        let limit = 2.5;
        if horiz.length() > limit {
            let s = limit / horiz.length();
            acc.x *= s;
            acc.z *= s;
        }
        acc.y = acc.y.clamp(-4.0, 4.0);
        let f = (acc + Vector::new(0.0, 9.81, 0.0)) * m;
        let up = rot * Vector::Y;
        let thrust = f.dot(up).max(0.0);
        // Attitude loop: align body up with the force direction, hold yaw at zero.
        let want_up = f.normalize_or(Vector::Y);
        let err_tilt = up.cross(want_up);
        let fwd = rot * Vector::Z;
        let err_yaw = Vector::new(0.0, -fwd.x.atan2(fwd.z), 0.0);
        let inertia = 0.08;
        // Feed-forward: cancel the load's weight torque about the centre of mass.
        let load_torque = if payload > 0.0 {
            (load_at - p).cross(Vector::new(0.0, -9.81 * payload, 0.0))
        } else {
            Vector::ZERO
        };
        let torque_world = (err_tilt * 60.0 + err_yaw * 4.0 - w * 12.0) * inertia - load_torque;
        let torque = rot.inverse() * torque_world;
        // Mixer: four rotor thrusts along body up give the thrust and the roll/pitch
        // torques; yaw comes from rotor drag, applied as a torque.
        let l = q.rotors[0].x.abs();
        let mut fr = [0.0f32; 4];
        for (i, r) in q.rotors.iter().enumerate() {
            // A force f along +y at (x, y, z) gives the torque (-z f, 0, x f).
            fr[i] = thrust / 4.0 - torque.x * r.z.signum() / (4.0 * l)
                + torque.z * r.x.signum() / (4.0 * l);
            fr[i] = fr[i].clamp(0.0, craft * 9.81);
        }
        let pose = *rb.position();
        for (i, r) in q.rotors.iter().enumerate() {
            let at = pose.transform_point(*r);
            rb.add_force_at_point(up * fr[i], at, true);
        }
        rb.add_torque(rot * Vector::new(0.0, torque.y, 0.0), true);
    }
}

impl World {
    /// Mass of the loose things resting in the quadrotor's basket (their centres within
    /// the basket's footprint, up to 0.4 m above its floor).
    /// Returns the mass and its centre.
    fn basket_load(&self) -> (f32, Vector) {
        let none = (0.0, Vector::ZERO);
        let Some(q) = &self.quad else { return none };
        let Some(v) = self
            .task
            .basket_of(q.robot)
            .and_then(|b| self.volume[b.get()])
        else {
            return none;
        };
        let mut moment = Vector::ZERO;
        let frame = *self.pw.bodies[v.body].position() * v.local;
        let mut load = 0.0;
        for it in self.layout.items.iter().filter(|it| it.dynamic) {
            let Some(b) = self
                .task
                .idx(NodeId(it.id))
                .and_then(|n| self.body[n.get()])
            else {
                continue;
            };
            if b == q.body {
                continue;
            }
            let rb = &self.pw.bodies[b];
            let l = frame.inverse_transform_point(rb.translation());
            if l.x.abs() <= v.half.x
                && l.z.abs() <= v.half.z
                && l.y >= -v.half.y - 0.02
                && l.y <= 0.4
            {
                load += rb.mass();
                moment += rb.center_of_mass() * rb.mass();
            }
        }
        if load > 0.0 {
            (load, moment / load)
        } else {
            none
        }
    }
}

fn wrap(a: f32) -> f32 {
    let mut a = a;
    while a > PI {
        a -= 2.0 * PI;
    }
    while a < -PI {
        a += 2.0 * PI;
    }
    a
}

fn hinge_pose(h: &Hinge, angle: f32) -> Pose {
    let r = Rotation::from_axis_angle(h.axis, angle);
    let t = h.pivot + r * (h.closed.translation - h.pivot);
    Pose::from_parts(t, r * h.closed.rotation)
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

impl World {
    // ------------------------------------------------------------ flight

    fn quad_pos(&self) -> Option<Vector> {
        let q = self.quad.as_ref()?;
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
        // Every 20 cm on the floor plan, and where the robot changes storey.
        let moved = (last[0] - t.x).hypot(last[2] - t.z) > 0.2;
        let changed = self.level_at(Vector::new(last[0], last[1], last[2])) != level;
        if (moved || changed)
            && let Some((_, p)) = self.paths.iter_mut().find(|(i, _)| *i == id)
        {
            p.push([t.x, t.y, t.z]);
        }
    }

    /// Flies the quadrotor along `waypoints` (body origin) and hovers at the last one.
    fn fly(&mut self, waypoints: &[Vector]) -> Result<(), PhysicsError> {
        let Some(q) = self.quad.clone() else {
            return fail(FailureKind::Layout, "no quadrotor".into());
        };
        let speed = self.layout.specs.flight_speed;
        let com_off = {
            let rb = &self.pw.bodies[q.body];
            rb.center_of_mass() - rb.translation()
        };
        let mut setpoint = self.pw.bodies[q.body].translation();
        for &wp in waypoints {
            while (wp - setpoint).length() > 1e-4 {
                let d = wp - setpoint;
                let stepv = d.normalize_or_zero() * (speed * DT).min(d.length());
                setpoint += stepv;
                self.quad_target = (setpoint + com_off, stepv / DT);
                self.step();
                self.check_quad_hits()?;
                self.record_path(q.robot);
            }
        }
        let end = setpoint;
        self.quad_target = (end + com_off, Vector::ZERO);
        for i in 0..600 {
            self.step();
            self.check_quad_hits()?;
            let rb = &self.pw.bodies[q.body];
            if i > 20 && (rb.translation() - end).length() < 0.05 && rb.linvel().length() < 0.08 {
                return Ok(());
            }
        }
        let at = self.pw.bodies[q.body].translation();
        fail(
            FailureKind::Timeout,
            format!(
                "the quadrotor did not settle at ({:.2}, {:.2}, {:.2}); it is {:.2} m away",
                end.x,
                end.y,
                end.z,
                (at - end).length()
            ),
        )
    }

    /// A flying quadrotor touching a door panel or a wall has crashed.
    fn check_quad_hits(&self) -> Result<(), PhysicsError> {
        let Some(q) = &self.quad else { return Ok(()) };
        for c in self.pw.bodies[q.body].colliders() {
            for pair in self.pw.narrow_phase.contact_pairs_with(*c) {
                if !pair.has_any_active_contact() {
                    continue;
                }
                let other = if pair.collider1 == *c {
                    pair.collider2
                } else {
                    pair.collider1
                };
                let owner = self.owner.get(&other).copied();
                let is_door = owner.is_some_and(|o| self.task.node(o).kind == NodeKind::Door);
                let is_wall =
                    owner.is_none()
                        && self.pw.colliders.get(other).is_some_and(|c| {
                            c.parent().is_some_and(|p| self.pw.bodies[p].is_fixed())
                        })
                        && self.pw.colliders[other].compute_aabb().maxs.y > 0.5;
                if is_door || is_wall {
                    let p = self.pw.bodies[q.body].translation();
                    let v = self.pw.bodies[q.body].linvel().length();
                    let what = match owner {
                        Some(o) => {
                            let angle = self.hinge_angle(o).unwrap_or(0.0).to_degrees();
                            format!("the panel of {} (open {angle:.0} degrees)", self.label(o))
                        }
                        None if self.flight_colliders.contains(&other) => {
                            "a flight of stairs".to_owned()
                        }
                        None => "a wall".to_owned(),
                    };
                    return fail(
                        FailureKind::Blocked,
                        format!(
                            "the quadrotor hit {what} at ({:.2}, {:.2}, {:.2}) m, flying at {v:.2} m/s",
                            p.x, p.y, p.z
                        ),
                    );
                }
            }
        }
        Ok(())
    }

    /// A free spot for the quadrotor on `s` (body origin), preferring one next to a
    /// fixed arm on `s`, else the one nearest `near`.
    fn landing_spot(&self, s: Idx, near: Vector) -> Result<Vector, PhysicsError> {
        let Some((b, c, half)) = self.top[s.get()] else {
            return fail(
                FailureKind::Blocked,
                format!("{} has no top to land on", self.label(s)),
            );
        };
        let pose = *self.pw.bodies[b].position();
        let qh = self.layout.specs.quad_half;
        let arm_at = self
            .arms
            .iter()
            .find(|a| {
                self.task
                    .init
                    .has(coherent_core::Edge::new(a.robot, Relation::On, s))
            })
            .map(|a| self.pw.bodies[a.root].translation());
        // A margin around the craft: it must not brush a wall or the arm on arrival.
        let shape = Cuboid::new(Vector::new(qh + 0.25, 0.13, qh + 0.25));
        let qbody = self.quad.as_ref().map(|q| q.body);
        let mut best: Option<(f32, Vector)> = None;
        let step = 0.1;
        // A floor is walled: keep the craft's overshoot on arrival off the walls.
        let wall_gap = if self.task.node(s).kind == NodeKind::Floor {
            0.45
        } else {
            0.0
        };
        let nx = ((half[0] - qh - wall_gap) / step).floor() as i32;
        let nz = ((half[1] - qh - wall_gap) / step).floor() as i32;
        for i in -nx..=nx {
            for k in -nz..=nz {
                let local = c + Vector::new(i as f32 * step, 0.005, k as f32 * step);
                let p = pose.transform_point(local);
                let probe = Pose::from_translation(p + Vector::new(0.0, 0.14, 0.0));
                let mut filter = solid();
                if let Some(qb) = qbody {
                    filter = filter.exclude_rigid_body(qb);
                }
                let qp = self.pw.query_pipeline_with_filter(filter);
                let blocked = qp.intersect_shape(probe, &shape).any(|(h, col)| {
                    col.collision_groups().memberships != Group::NONE
                        && self.owner.get(&h) != Some(&s)
                });
                if blocked {
                    continue;
                }
                let key = match arm_at {
                    // Close to the arm, but with room for its base.
                    Some(a) => ((p - a).length() - 0.55).abs(),
                    None => (p - near).length(),
                };
                if best.is_none_or(|(k0, _)| key < k0) {
                    best = Some((key, p));
                }
            }
        }
        best.map(|(_, p)| p).ok_or_else(|| PhysicsError {
            kind: FailureKind::Blocked,
            message: format!(
                "no free {:.1} m x {:.1} m spot for the quadrotor on {}",
                2.0 * qh,
                2.0 * qh,
                self.label(s)
            ),
        })
    }

    fn top_height(&self, s: Idx) -> f32 {
        self.top[s.get()]
            .map(|(b, c, _)| self.pw.bodies[b].position().transform_point(c).y)
            .unwrap_or(0.0)
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

    /// Flies to hover at `hover_y` over `dest` (a point on the destination's surface) at
    /// the cruise altitude above each storey's floor: through the door between two rooms
    /// of a storey, or up or down the stairwell between storeys (over the flight's first
    /// 0.6 m, where nothing is above it, then along the run through the opening in the
    /// upper room's wall).
    fn quad_fly_to(&mut self, dest: Vector, hover_y: f32) -> Result<(), PhysicsError> {
        let Some(p) = self.quad_pos() else {
            return fail(FailureKind::Layout, "no quadrotor".into());
        };
        let cruise = self.layout.specs.cruise_altitude;
        let here = self.level_at(p) + cruise;
        let mut wps = vec![Vector::new(p.x, here, p.z)];
        let from_room = self.room_at(p);
        let to_room = self.room_at(dest);
        if from_room != to_room
            && let (Some(a), Some(b)) = (from_room, to_room)
        {
            let (ia, ib) = (self.task.id(a).0, self.task.id(b).0);
            let door = self
                .layout
                .doors
                .iter()
                .find(|d| d.rooms.contains(&ia) && d.rooms.contains(&ib))
                .cloned();
            let flight = self
                .flights
                .iter()
                .find(|f| f.rooms.contains(&ia) && f.rooms.contains(&ib))
                .copied();
            if let Some(d) = door {
                let c = Vector::new(d.center[0], here, d.center[1]);
                let normal = if d.along_x { Vector::Z } else { Vector::X };
                let side = (Vector::new(p.x, here, p.z) - c).dot(normal).signum();
                // An open door's panel stands out from the wall as far as the door is
                // wide: leave the wall straight out to beyond it before turning to the
                // doorway, and come back to it the same way on the far side.
                let clear = (d.width + self.layout.specs.quad_half + 0.2).max(1.6);
                // Points kept 0.8 m inside `room` (its middle line when it is narrower):
                // a narrow room, a hallway, is crossed, not flown out of.
                let fit = |v: f32, lo: f32, hi: f32| {
                    if hi - lo > 1.6 {
                        v.clamp(lo + 0.8, hi - 0.8)
                    } else {
                        (lo + hi) / 2.0
                    }
                };
                let within = |mut o: Vector, room: Idx| {
                    if let Some((lo, hi)) = self.room_rect(room) {
                        o.x = fit(o.x, lo[0], hi[0]);
                        o.z = fit(o.z, lo[1], hi[1]);
                    }
                    o
                };
                let out = |q: Vector, s: f32, room: Idx| {
                    let short = clear - (q - c).dot(normal) * s;
                    if short <= 0.0 {
                        q
                    } else {
                        within(q + normal * s * short, room)
                    }
                };
                wps.push(out(Vector::new(p.x, here, p.z), side, a));
                wps.push(within(c + normal * side * clear, a));
                wps.push(c);
                wps.push(within(c - normal * side * clear, b));
                let there = self.room_level(b) + cruise;
                wps.push(out(Vector::new(dest.x, there, dest.z), -side, b));
            } else if let Some(f) = flight {
                let (low, high) = (f.lower + cruise, f.upper + cruise);
                let mut legs = [f.at(0.6, low), f.at(0.6, high), f.at(f.run + 1.6, high)];
                if f.rooms[0] != ia {
                    legs.reverse();
                }
                wps.extend(legs.map(v3));
            } else {
                return fail(
                    FailureKind::Blocked,
                    format!(
                        "no door or stairs between {} and {}",
                        self.label(a),
                        self.label(b)
                    ),
                );
            }
        }
        let there = to_room.map_or(here, |r| self.room_level(r) + cruise);
        wps.push(Vector::new(dest.x, there, dest.z));
        wps.push(Vector::new(dest.x, hover_y, dest.z));
        self.fly(&wps)
    }

    fn quad_takeoff(&mut self) -> Result<(), PhysicsError> {
        let Some(p) = self.quad_pos() else {
            return fail(FailureKind::Layout, "no quadrotor".into());
        };
        if let Some(q) = self.quad.as_mut() {
            q.motors_on = true;
            q.integral = Vector::ZERO;
        }
        self.fly(&[p + Vector::new(0.0, 0.7, 0.0)])
    }

    fn quad_land(&mut self, s: Idx) -> Result<(), PhysicsError> {
        let Some(p) = self.quad_pos() else {
            return fail(FailureKind::Layout, "no quadrotor".into());
        };
        let spot = self.landing_spot(s, p)?;
        self.fly(&[
            Vector::new(spot.x, p.y.max(spot.y + 0.5), spot.z),
            spot + Vector::new(0.0, 0.25, 0.0),
        ])?;
        // Descend slowly until the basket touches the surface, then cut the motors.
        let Some(q) = self.quad.clone() else {
            return Ok(());
        };
        let com_off = {
            let rb = &self.pw.bodies[q.body];
            rb.center_of_mass() - rb.translation()
        };
        let mut y = spot.y + 0.25;
        for _ in 0..600 {
            y -= 0.3 * DT;
            self.quad_target = (
                Vector::new(spot.x, y, spot.z) + com_off,
                Vector::new(0.0, -0.3, 0.0),
            );
            self.step();
            if self.quad_touches(s) {
                break;
            }
        }
        if let Some(q) = self.quad.as_mut() {
            q.motors_on = false;
        }
        self.settle(1.5);
        if !self.quad_touches(s) {
            return fail(
                FailureKind::Blocked,
                format!("the quadrotor did not come to rest on {}", self.label(s)),
            );
        }
        Ok(())
    }

    /// Whether a collider of the quadrotor is in contact with one of `s`.
    fn quad_touches(&self, s: Idx) -> bool {
        self.quad
            .as_ref()
            .is_some_and(|q| self.body_touches(q.body, s))
    }

    fn body_touches(&self, body: RigidBodyHandle, s: Idx) -> bool {
        self.pw.bodies[body].colliders().iter().any(|c| {
            self.pw.narrow_phase.contact_pairs_with(*c).any(|pair| {
                let other = if pair.collider1 == *c {
                    pair.collider2
                } else {
                    pair.collider1
                };
                pair.has_any_active_contact() && self.owner.get(&other) == Some(&s)
            })
        })
    }

    // ------------------------------------------------------------ legged robot

    fn dog_shoulder_world(&self) -> Option<Vector> {
        let d = self.dog.as_ref()?;
        let ai = self.arm_index(d.robot)?;
        Some(self.shoulder(&self.arms[ai]))
    }

    /// One occupancy grid per storey, for the legged robot.
    fn grids(&self, dog: RigidBodyHandle) -> Vec<(f32, path::Grid)> {
        layout::levels(&self.layout)
            .into_iter()
            .map(|level| (level, path::Grid::new(self, dog, level)))
            .collect()
    }

    /// The legged robot's way from `start` to `goal` (body origins; each on the storey
    /// its height says): a route on each storey, joined by the flights between them
    /// (fewest flights first). `None` when there is no way.
    fn dog_route(
        &self,
        grids: &[(f32, path::Grid)],
        start: Vector,
        goal: Vector,
    ) -> Option<Vec<Leg>> {
        let grid = |level: f32| grids.iter().find(|(l, _)| *l == level).map(|(_, g)| g);
        let (from, to) = (self.level_at(start), self.level_at(goal));
        // Breadth first over storeys, a flight being an edge either way.
        let mut reached: Vec<(f32, Option<(usize, bool)>)> = vec![(from, None)];
        let mut i = 0;
        while i < reached.len() && !reached.iter().any(|(l, _)| *l == to) {
            let level = reached[i].0;
            for (k, f) in self.flights.iter().enumerate() {
                for (up, a, b) in [(true, f.lower, f.upper), (false, f.upper, f.lower)] {
                    if a == level && !reached.iter().any(|(l, _)| *l == b) {
                        reached.push((b, Some((k, up))));
                    }
                }
            }
            i += 1;
        }
        let mut flights = Vec::new();
        let mut level = to;
        while let Some(&(_, Some((k, up)))) = reached.iter().find(|(l, _)| *l == level) {
            flights.push((self.flights[k], up));
            level = if up {
                self.flights[k].lower
            } else {
                self.flights[k].upper
            };
        }
        if level != from {
            return None;
        }
        flights.reverse();
        let mut legs = Vec::new();
        let mut at = start;
        for (f, up) in flights {
            let (here, there) = if up {
                (
                    f.at(-FLIGHT_APPROACH, f.lower + 0.02),
                    f.at(f.run + FLIGHT_APPROACH, f.upper + 0.02),
                )
            } else {
                (
                    f.at(f.run + FLIGHT_APPROACH, f.upper + 0.02),
                    f.at(-FLIGHT_APPROACH, f.lower + 0.02),
                )
            };
            let (here, there) = (v3(here), v3(there));
            legs.push(Leg::Floor(grid(self.level_at(at))?.route(at, here)?));
            legs.push(Leg::Flight(f, there));
            at = there;
        }
        legs.push(Leg::Floor(grid(to)?.route(at, goal)?));
        Some(legs)
    }

    /// Walks the dog to `goal` (body origin, on the storey its height says) along a
    /// planned way, then turns it to face `face`.
    fn walk(&mut self, goal: Vector, face: Vector) -> Result<(), PhysicsError> {
        let Some(dog) = self.dog.clone() else {
            return fail(FailureKind::Layout, "no legged robot".into());
        };
        let start = self.pw.bodies[dog.body].translation();
        let grids = self.grids(dog.body);
        let Some(legs) = self.dog_route(&grids, start, goal) else {
            return fail(
                FailureKind::Blocked,
                format!(
                    "no path for the legged robot from ({:.2}, {:.2}, {:.2}) to ({:.2}, {:.2}, {:.2}): closed doors, furniture or missing stairs block every way",
                    start.x, start.y, start.z, goal.x, goal.y, goal.z
                ),
            );
        };
        for leg in legs {
            match leg {
                Leg::Floor(route) => self.walk_along(&dog, &route[1..], false)?,
                Leg::Flight(f, there) => {
                    self.walk_along(&dog, &[there], true)?;
                    let y = self.pw.bodies[dog.body].translation().y;
                    if (y - there.y).abs() > 0.03 {
                        return fail(
                            FailureKind::Blocked,
                            format!(
                                "the legged robot on stairs {} stopped at height {y:.2} m, not on the floor at {:.2} m",
                                f.id,
                                there.y - 0.02
                            ),
                        );
                    }
                }
            }
        }
        let pos = self.pw.bodies[dog.body].translation();
        let yaw = (face.x - pos.x).atan2(face.z - pos.z);
        self.pw.bodies[dog.body]
            .set_next_kinematic_position(Pose::from_parts(pos, Rotation::from_rotation_y(yaw)));
        self.step();
        self.step();
        if let Some(d) = self.dog.as_mut() {
            d.yaw = yaw;
        }
        Ok(())
    }

    /// Moves the dog through `waypoints` on the floor plan with the character
    /// controller: at its height on a floor, or (`on_flight`) climbing and descending
    /// the flight's slope with the controller's vertical motion.
    fn walk_along(
        &mut self,
        dog: &Dog,
        waypoints: &[Vector],
        on_flight: bool,
    ) -> Result<(), PhysicsError> {
        let speed = self.layout.specs.dog_speed;
        let h = self.layout.specs.dog_half;
        // A cylinder: turning the robot never makes it collide.
        let shape = Cylinder::new(h[1], h[0].max(h[2]));
        let shape_off = Vector::new(0.0, h[1], 0.0);
        let kcc = if on_flight { self.stairs_kcc } else { self.kcc };
        let mut last_hit: Option<(ColliderHandle, Vector)> = None;
        for &wp in waypoints {
            let mut stuck = 0;
            let from = self.pw.bodies[dog.body].translation();
            let budget = ((wp - from).length() / (speed * DT) * 3.0) as usize + 120;
            for _ in 0..budget {
                let pos = self.pw.bodies[dog.body].translation();
                let d = Vector::new(wp.x - pos.x, 0.0, wp.z - pos.z);
                if d.length() < 0.01 {
                    break;
                }
                let want = d.normalize_or_zero() * (speed * DT).min(d.length());
                let yaw = d.x.atan2(d.z);
                let moved = {
                    let filter = solid().exclude_rigid_body(dog.body);
                    let qp = self.pw.query_pipeline_with_filter(filter);
                    let cpose = Pose::from_translation(pos + shape_off);
                    kcc.move_shape(DT, &qp, &shape, &cpose, want, |c| {
                        last_hit = Some((c.handle, c.hit.witness1));
                    })
                    .translation
                };
                let rise = if on_flight { moved.y } else { 0.0 };
                let rb = &mut self.pw.bodies[dog.body];
                rb.set_next_kinematic_position(Pose::from_parts(
                    pos + Vector::new(moved.x, rise, moved.z),
                    Rotation::from_rotation_y(yaw),
                ));
                self.step();
                self.record_path(dog.robot);
                let horizontal = Vector::new(moved.x, 0.0, moved.z).length();
                if horizontal < 0.2 * want.length() {
                    stuck += 1;
                    if stuck > 30 {
                        return fail(
                            FailureKind::Blocked,
                            format!(
                                "the legged robot is blocked at ({:.2}, {:.2}, {:.2}) on its way to ({:.2}, {:.2}){}",
                                pos.x,
                                pos.y,
                                pos.z,
                                wp.x,
                                wp.z,
                                self.hit_name(last_hit)
                            ),
                        );
                    }
                } else {
                    stuck = 0;
                }
            }
            let pos = self.pw.bodies[dog.body].translation();
            let off = Vector::new(wp.x - pos.x, 0.0, wp.z - pos.z).length();
            if off > 0.05 {
                return fail(
                    FailureKind::Blocked,
                    format!(
                        "the legged robot slid along an obstacle and stopped {off:.2} m short of ({:.2}, {:.2}) at ({:.2}, {:.2}){}",
                        wp.x,
                        wp.z,
                        pos.x,
                        pos.z,
                        self.hit_name(last_hit)
                    ),
                );
            }
        }
        Ok(())
    }

    /// Names what a character-controller contact touched, for failure messages.
    fn hit_name(&self, hit: Option<(ColliderHandle, Vector)>) -> String {
        let Some((h, p)) = hit else {
            return String::new();
        };
        let what = match self.owner.get(&h) {
            Some(n) => self.label(*n),
            None => "a wall".to_string(),
        };
        format!(
            " (last contact: {what} at ({:.2}, {:.2}, {:.2}))",
            p.x, p.y, p.z
        )
    }

    /// The fixed thing a node ultimately stands on or in (furniture), or itself.
    fn anchor(&self, x: Idx) -> Idx {
        let mut cur = x;
        for _ in 0..6 {
            match self.placement(cur) {
                Placement::On(s) | Placement::Inside(s) => {
                    let k = self.task.node(s).kind;
                    if k == NodeKind::Floor {
                        return cur;
                    }
                    if k == NodeKind::Tool {
                        return s;
                    }
                    cur = s;
                }
                _ => return cur,
            }
        }
        cur
    }

    /// World AABB of all of a node's colliders.
    fn node_aabb(&self, n: Idx) -> Option<Aabb> {
        let b = self.body[n.get()]?;
        let mut out: Option<Aabb> = None;
        for c in self.pw.bodies[b].colliders() {
            if self.owner.get(c) != Some(&n) && self.task.node(n).kind != NodeKind::Tool {
                continue;
            }
            let a = self.pw.colliders[*c].compute_aabb();
            out = Some(match out {
                Some(o) => o.merged(&a),
                None => a,
            });
        }
        out
    }

    /// Where the dog stands to work on `x`: beside what `x` stands on, nearest to `x`.
    fn service_point(&self, x: Idx) -> Result<(Vector, Vector), PhysicsError> {
        let Some(dog) = &self.dog else {
            return fail(FailureKind::Layout, "no legged robot".into());
        };
        let a = self.anchor(x);
        let aabb = self
            .node_aabb(a)
            .or_else(|| self.node_aabb(x))
            .ok_or_else(|| PhysicsError {
                kind: FailureKind::Layout,
                message: format!("{} has no body", self.label(x)),
            })?;
        // Aim at what the move brings within reach: the things on a surface (the dog is
        // to handle them next), else the thing itself.
        let on_top: Vec<Vector> = if self.top[x.get()].is_some() {
            self.task
                .indices()
                .filter(|&n| self.body[n.get()].is_some())
                .filter(|&n| matches!(self.placement(n), Placement::On(s) if s == x))
                .filter_map(|n| self.node_aabb(n).map(|b| b.center()))
                .collect()
        } else {
            Vec::new()
        };
        let target = if on_top.is_empty() {
            self.node_aabb(x)
                .map(|b| b.center())
                .unwrap_or(aabb.center())
        } else {
            on_top.iter().copied().sum::<Vector>() / on_top.len() as f32
        };
        let h = self.layout.specs.dog_half;
        let gap = h[0].max(h[2]) + 0.12;
        let c = aabb.center();
        let he = aabb.half_extents();
        // The storey of what the thing stands on.
        let level = self.level_at(Vector::new(c.x, aabb.mins.y, c.z));
        let grids = self.grids(dog.body);
        let Some((_, grid)) = grids.iter().find(|(l, _)| *l == level) else {
            return fail(
                FailureKind::Layout,
                format!("no storey at {level:.2} m for {}", self.label(a)),
            );
        };
        // A spot in the thing's own room: the far side of a wall is not beside it.
        let home = if self.task.node(a).kind == NodeKind::Door {
            None
        } else {
            self.room_at(Vector::new(c.x, aabb.mins.y + 0.05, c.z))
        };
        let mut cands = Vec::new();
        for (nx, nz) in [(0.0, -1.0), (0.0, 1.0), (-1.0, 0.0), (1.0, 0.0)] {
            let lateral = if nx == 0.0 {
                Vector::X * he.x
            } else {
                Vector::Z * he.z
            };
            for f in [0.0f32, -0.6, 0.6, -0.3, 0.3] {
                // Nearest free cell straight out from that side (a wall beside a door
                // or the grid's 10 cm cells can block the first one).
                let free = [0.0f32, 0.1, 0.2, 0.3].into_iter().find_map(|extra| {
                    let p = Vector::new(
                        c.x + nx * (he.x + gap + extra),
                        level + 0.02,
                        c.z + nz * (he.z + gap + extra),
                    ) + lateral * f;
                    (grid.free(p) && (home.is_none() || self.room_at(p) == home)).then_some(p)
                });
                cands.extend(free);
            }
        }
        let start = self.pw.bodies[dog.body].translation();
        let fwd = self.layout.specs.dog_shoulder[2];
        cands.sort_by(|p, q| {
            let sp =
                *p + (Vector::new(target.x - p.x, 0.0, target.z - p.z)).normalize_or_zero() * fwd;
            let sq =
                *q + (Vector::new(target.x - q.x, 0.0, target.z - q.z)).normalize_or_zero() * fwd;
            let dp = Vector::new(sp.x - target.x, 0.0, sp.z - target.z).length();
            let dq = Vector::new(sq.x - target.x, 0.0, sq.z - target.z).length();
            dp.total_cmp(&dq)
        });
        for p in cands {
            if self.dog_route(&grids, start, p).is_some() {
                return Ok((p, target));
            }
        }
        fail(
            FailureKind::Blocked,
            format!(
                "the legged robot can reach no free spot beside {} (closed doors or furniture in the way)",
                self.label(a)
            ),
        )
    }

    fn dog_to_room(&mut self, room: Idx) -> Result<(), PhysicsError> {
        let Some(dog) = self.dog.clone() else {
            return fail(FailureKind::Layout, "no legged robot".into());
        };
        let p = self.pw.bodies[dog.body].translation();
        let here = self.room_at(p).map(|h| self.task.id(h).0);
        let rid = self.task.id(room).0;
        let joins =
            |rooms: &[i64; 2]| rooms.contains(&rid) && here.is_some_and(|h| rooms.contains(&h));
        let door = self.layout.doors.iter().find(|d| joins(&d.rooms)).cloned();
        let flight = self.flights.iter().find(|f| joins(&f.rooms)).copied();
        let Some((lo, hi)) = self.room_rect(room) else {
            return fail(
                FailureKind::Layout,
                format!("{} has no footprint", self.label(room)),
            );
        };
        let level = self.room_level(room);
        // The robot's height on the room's floor.
        let y = if level == self.level_at(p) {
            p.y
        } else {
            level + 0.02
        };
        // A free spot inside the room, just past the door or the flight when there is one.
        let mid = Vector::new((lo[0] + hi[0]) / 2.0, y, (lo[1] + hi[1]) / 2.0);
        let seed = match (&door, flight) {
            (Some(d), _) => {
                let c = Vector::new(d.center[0], y, d.center[1]);
                c + (mid - c).normalize_or_zero() * 1.0
            }
            (None, Some(f)) if f.rooms[1] == rid => v3(f.at(f.run + 1.0, y)),
            (None, Some(f)) => v3(f.at(-1.0, y)),
            (None, None) => mid,
        };
        let grids = self.grids(dog.body);
        let Some((_, grid)) = grids.iter().find(|(l, _)| *l == level) else {
            return fail(
                FailureKind::Layout,
                format!("no storey at {level:.2} m for {}", self.label(room)),
            );
        };
        let mut goal = None;
        'search: for r in 0..20 {
            for k in 0..16 {
                let a = k as f32 * PI / 8.0;
                let q = seed + Vector::new(a.cos(), 0.0, a.sin()) * (r as f32 * 0.15);
                if self.room_at(q) == Some(room) && grid.free(q) {
                    goal = Some(q);
                    break 'search;
                }
                if r == 0 {
                    break;
                }
            }
        }
        let Some(goal) = goal else {
            return fail(
                FailureKind::Blocked,
                format!("no free floor in {}", self.label(room)),
            );
        };
        self.walk(goal, goal + (goal - p))
    }

    // ------------------------------------------------------------ hands

    /// A free spot for `h` on surface `s` or in container `c`, nearest to the robot's
    /// shoulder and within its reach; returns the bottom centre for `h`.
    fn put_spot(
        &self,
        robot: Idx,
        h: Idx,
        holder: Idx,
        inside: bool,
    ) -> Result<Vector, PhysicsError> {
        let size = self
            .layout
            .item(self.task.id(h))
            .map(|it| it.size)
            .unwrap_or([0.12; 3]);
        let (body, centre, half) = if inside {
            let Some(v) = self.volume[holder.get()] else {
                return fail(
                    FailureKind::Blocked,
                    format!("{} has no inside", self.label(holder)),
                );
            };
            let bottom = v.local.translation - Vector::new(0.0, v.half.y, 0.0);
            (v.body, bottom, [v.half.x, v.half.z])
        } else {
            let Some(t) = self.top[holder.get()] else {
                return fail(
                    FailureKind::Blocked,
                    format!("{} has no top", self.label(holder)),
                );
            };
            t
        };
        let Some(ai) = self.arm_index(robot) else {
            return fail(
                FailureKind::Reach,
                format!("{} has no arm", self.label(robot)),
            );
        };
        let shoulder = self.shoulder(&self.arms[ai]);
        let reach = self.arms[ai].reach;
        let min_reach = self.arms[ai].min_reach + 0.05;
        let pose = *self.pw.bodies[body].position();
        let shape = Cuboid::new(Vector::new(
            size[0] / 2.0 - 0.005,
            size[1] / 2.0 - 0.005,
            size[2] / 2.0 - 0.005,
        ));
        let hb = self.body[h.get()];
        let hx = half[0] - size[0] / 2.0 - 0.01;
        let hz = half[1] - size[2] / 2.0 - 0.01;
        if hx < -0.005 || hz < -0.005 {
            return fail(
                FailureKind::Blocked,
                format!(
                    "{} ({:.2} m wide) does not fit {} {}",
                    self.label(h),
                    size[0],
                    if inside { "in" } else { "on" },
                    self.label(holder)
                ),
            );
        }
        let step = 0.04;
        let (nx, nz) = (
            (hx.max(0.0) / step).floor() as i32,
            (hz.max(0.0) / step).floor() as i32,
        );
        let mut best: Option<(f32, Vector)> = None;
        let mut nearest_any = f32::INFINITY;
        // What filled the last spot tried within reach (None: an unnamed body).
        let mut in_the_way: Option<Option<Idx>> = None;
        for i in -nx..=nx {
            for k in -nz..=nz {
                let local = centre + Vector::new(i as f32 * step, 0.003, k as f32 * step);
                let p = pose.transform_point(local);
                let grip = p + Vector::new(0.0, size[1], 0.0);
                let d = (grip - shoulder).length();
                nearest_any = nearest_any.min(d);
                if d > reach - 0.03 || d < min_reach {
                    continue;
                }
                let probe =
                    Pose::from_translation(p + Vector::new(0.0, size[1] / 2.0 + 0.004, 0.0));
                let mut filter = solid();
                if let Some(b) = hb {
                    filter = filter.exclude_rigid_body(b);
                }
                let qp = self.pw.query_pipeline_with_filter(filter);
                let blocker = qp.intersect_shape(probe, &shape).find_map(|(ch, col)| {
                    let owner = self.owner.get(&ch).copied();
                    (col.collision_groups().memberships != Group::NONE
                        && (inside || owner != Some(holder))
                        && self.task.node(owner.unwrap_or(holder)).kind != NodeKind::Door)
                        .then_some(owner)
                });
                if let Some(owner) = blocker {
                    in_the_way = Some(owner);
                    continue;
                }
                if best.is_none_or(|(d0, _)| d < d0) {
                    best = Some((d, p));
                }
            }
        }
        match best {
            Some((_, p)) => Ok(p),
            None if nearest_any > reach - 0.03 => fail(
                FailureKind::Reach,
                format!(
                    "every spot {} {} is beyond the reach of {}: the nearest is {:.2} m from its shoulder, its reach is {:.2} m",
                    if inside { "in" } else { "on" },
                    self.label(holder),
                    self.label(robot),
                    nearest_any,
                    reach
                ),
            ),
            None => fail(
                FailureKind::Blocked,
                format!(
                    "no free spot for {} {} {} within reach of {}{}",
                    self.label(h),
                    if inside { "in" } else { "on" },
                    self.label(holder),
                    self.label(robot),
                    match in_the_way {
                        Some(Some(n)) => format!(" ({} is in the way)", self.label(n)),
                        Some(None) => " (a robot is in the way)".to_owned(),
                        None => String::new(),
                    }
                ),
            ),
        }
    }

    fn grasp(&mut self, robot: Idx, x: Idx) -> Result<(), PhysicsError> {
        let Some(xb) = self.body[x.get()] else {
            return fail(
                FailureKind::Layout,
                format!("{} has no body", self.label(x)),
            );
        };
        let size = self
            .layout
            .item(self.task.id(x))
            .map(|it| it.size)
            .unwrap_or([0.12; 3]);
        // The middle of its top as it lies now (it may have tipped over).
        let top = match self.node_aabb(x) {
            Some(a) => Vector::new(a.center().x, a.maxs.y, a.center().z),
            None => self.pw.bodies[xb]
                .position()
                .transform_point(Vector::new(0.0, size[1], 0.0)),
        };
        self.reach(robot, top + Vector::new(0.0, 0.01, 0.0), &self.label(x))?;
        let Some(ai) = self.arm_index(robot) else {
            return Ok(());
        };
        let hand = self.arms[ai].hand;
        // What rides on or in it comes along, fastened (no sloshing in transport).
        let mut carried = vec![xb];
        let mut riders = vec![x];
        let mut i = 0;
        while i < riders.len() {
            let host = riders[i];
            for n in self.task.indices() {
                if riders.contains(&n) || self.body[n.get()].is_none() {
                    continue;
                }
                let dynamic = self
                    .layout
                    .item(self.task.id(n))
                    .is_some_and(|it| it.dynamic);
                if dynamic
                    && matches!(self.placement(n), Placement::On(s) | Placement::Inside(s) if s == host)
                {
                    riders.push(n);
                    if let Some(b) = self.body[n.get()] {
                        carried.push(b);
                    }
                }
            }
            i += 1;
        }
        let hand_pose = *self.pw.bodies[hand].position();
        let mut joints = Vec::new();
        for &b in &carried {
            let obj_pose = *self.pw.bodies[b].position();
            let frame2 = obj_pose.inverse() * hand_pose;
            let j = FixedJointBuilder::new()
                .local_frame1(Pose::IDENTITY)
                .local_frame2(frame2)
                .contacts_enabled(false);
            joints.push(self.pw.impulse_joints.insert(hand, b, j, true));
            self.set_body_groups(b, InteractionGroups::none());
        }
        self.grasps.push(Grasp {
            robot,
            object: x,
            joints,
            carried,
        });
        self.arm_home(robot);
        Ok(())
    }

    fn set_body_groups(&mut self, b: RigidBodyHandle, g: InteractionGroups) {
        let cs: Vec<ColliderHandle> = self.pw.bodies[b].colliders().to_vec();
        for c in cs {
            if let Some(col) = self.pw.colliders.get_mut(c) {
                col.set_collision_groups(g);
            }
        }
    }

    fn release(
        &mut self,
        robot: Idx,
        h: Idx,
        holder: Idx,
        inside: bool,
    ) -> Result<(), PhysicsError> {
        let Some(gi) = self
            .grasps
            .iter()
            .position(|g| g.robot == robot && g.object == h)
        else {
            return fail(
                FailureKind::Disagreement,
                format!("{} does not hold {}", self.label(robot), self.label(h)),
            );
        };
        if inside {
            self.check_open(holder)?;
        }
        let spot = self.put_spot(robot, h, holder, inside)?;
        let size = self
            .layout
            .item(self.task.id(h))
            .map(|it| it.size)
            .unwrap_or([0.12; 3]);
        let Some(ai) = self.arm_index(robot) else {
            return Ok(());
        };
        // Hand target: where the middle of the object's underside is 1 cm above the
        // spot (its lowest point, whichever way up it is held).
        let offset = match self.node_aabb(h) {
            Some(a) => {
                self.hand_pos(&self.arms[ai]) - Vector::new(a.center().x, a.mins.y, a.center().z)
            }
            None => Vector::new(0.0, size[1], 0.0),
        };
        let target = spot + Vector::new(0.0, 0.01, 0.0) + offset;
        let what = format!(
            "the spot {} {}",
            if inside { "in" } else { "on" },
            self.label(holder)
        );
        self.reach(robot, target, &what)?;
        let g = self.grasps.remove(gi);
        for j in g.joints {
            self.pw.impulse_joints.remove(j, true);
        }
        for b in g.carried {
            self.set_body_groups(b, groups(G_OBJECT));
            let rb = &mut self.pw.bodies[b];
            rb.set_linvel(Vector::ZERO, true);
            rb.set_angvel(Vector::ZERO, true);
        }
        self.settle(0.5);
        self.arm_home(robot);
        self.settle(1.0);
        Ok(())
    }

    fn check_open(&self, c: Idx) -> Result<(), PhysicsError> {
        if let Some(angle) = self.hinge_angle(c)
            && angle.abs() < 1.0
        {
            return fail(
                FailureKind::Blocked,
                format!(
                    "the lid of {} is open only {:.0} degrees: the opening is blocked",
                    self.label(c),
                    angle.to_degrees()
                ),
            );
        }
        Ok(())
    }

    /// Current hinge angle of a door or lid, read from its panel's pose.
    pub fn hinge_angle(&self, n: Idx) -> Option<f32> {
        let h = self.hinges.iter().find(|h| h.node == n)?;
        let rot = *self.pw.bodies[h.body].rotation();
        let rel = rot * h.closed.rotation.inverse();
        let (axis, angle) = rel.to_axis_angle();
        Some(angle * axis.dot(h.axis).signum())
    }

    fn drive_hinge(&mut self, robot: Idx, n: Idx, open: bool) -> Result<(), PhysicsError> {
        let Some(hi) = self.hinges.iter().position(|h| h.node == n) else {
            return fail(
                FailureKind::Blocked,
                format!("{} has no door or lid", self.label(n)),
            );
        };
        // Doors swing away from the robot that opens them.
        if open
            && self.task.node(n).kind == NodeKind::Door
            && let Some(rb) = self.body[robot.get()]
        {
            let rp = self.pw.bodies[rb].translation();
            let h = &self.hinges[hi];
            let side_of = |angle: f32| {
                let tip = hinge_pose(h, angle).transform_point(Vector::new(0.0, 0.0, 0.0));
                (tip - rp).length()
            };
            let a = if side_of(FRAC_PI_2) >= side_of(-FRAC_PI_2) {
                FRAC_PI_2
            } else {
                -FRAC_PI_2
            };
            self.hinges[hi].open_angle = a;
        }
        let h = self.hinges[hi].clone();
        let handle_world = self.pw.bodies[h.body].position().transform_point(h.handle);
        self.reach(
            robot,
            handle_world,
            &format!("the handle of {}", self.label(n)),
        )?;
        let from = self.hinge_angle(n).unwrap_or(0.0);
        let to = if open { h.open_angle } else { 0.0 };
        let steps = 60;
        for s in 1..=steps {
            let a = from + (to - from) * s as f32 / steps as f32;
            self.pw.bodies[h.body].set_next_kinematic_position(hinge_pose(&h, a));
            self.step();
        }
        self.arm_home(robot);
        Ok(())
    }

    // ------------------------------------------------------------ one action

    /// Executes `a` by `robot` physically, without asking the rules.
    pub fn execute(&mut self, robot: Idx, a: Action) -> Result<(), PhysicsError> {
        let Some(kind) = self.task.robot(robot).map(|r| r.kind) else {
            return fail(
                FailureKind::Layout,
                format!("{} is not a robot", self.label(robot)),
            );
        };
        let x = a.object;
        match (kind, a.verb) {
            (RobotKind::Quadrotor, Verb::TakeoffFrom) => self.quad_takeoff(),
            (RobotKind::Quadrotor, Verb::LandOn) => self.quad_land(x),
            (RobotKind::Quadrotor, Verb::MoveTowards) => {
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
                        Some(f) => self.landing_spot(f, mid).unwrap_or(mid),
                        None => mid,
                    };
                    let cruise = self.layout.specs.cruise_altitude;
                    self.quad_fly_to(spot, level + cruise)
                } else {
                    let p = self.quad_pos().unwrap_or(Vector::ZERO);
                    let spot = self.landing_spot(x, p)?;
                    let y = self.top_height(x) + 0.7;
                    self.quad_fly_to(spot, y)
                }
            }
            (RobotKind::RobotDog, Verb::MoveTowards) => {
                if self.task.node(x).kind == NodeKind::Room {
                    self.dog_to_room(x)
                } else {
                    let (p, face) = self.service_point(x)?;
                    self.walk(p, face)
                }
            }
            (_, Verb::Open) => self.drive_hinge(robot, x, true),
            (_, Verb::Close) => self.drive_hinge(robot, x, false),
            (_, Verb::Grab) => self.grasp(robot, x),
            (_, Verb::PutOn) | (_, Verb::PutInto) => {
                let Some(t) = a.target else {
                    return fail(FailureKind::Layout, "put without a target".into());
                };
                self.release(robot, x, t, a.verb == Verb::PutInto)
            }
            (k, v) => fail(FailureKind::Layout, format!("a {k} cannot [{v}]")),
        }
    }

    // ------------------------------------------------------------ read back

    /// Where a movable thing physically is: held, inside a container's volume, or on
    /// the surface under it that it touches.
    pub fn placement(&self, x: Idx) -> Placement {
        if let Some(g) = self.grasps.iter().find(|g| g.object == x) {
            return Placement::Held(g.robot);
        }
        let Some(xb) = self.body[x.get()] else {
            return Placement::Loose;
        };
        // The basket rides with the quadrotor: on what the quadrotor has landed on.
        if self.task.node(x).kind == NodeKind::Tool {
            let landed = self.quad.as_ref().is_some_and(|q| !q.motors_on);
            if !landed {
                return Placement::Loose;
            }
            return self
                .support_of(xb, x)
                .map_or(Placement::Loose, Placement::On);
        }
        // Inside = resting within a container's interior: the middle of the thing's
        // underside lies in the interior volume (an apple in a shallow plate pokes out
        // above the rim, yet it is in the plate). Its underside is taken in the
        // container's frame, so that a plate in a basket tilted in flight is still in it.
        let mut best: Option<(f32, Idx)> = None;
        for n in self.task.indices() {
            if n == x {
                continue;
            }
            if let Some(v) = self.volume[n.get()] {
                if v.body == xb {
                    continue;
                }
                let pose = *self.pw.bodies[v.body].position() * v.local;
                let Some(low) = self.underside_in(xb, pose) else {
                    return Placement::Loose;
                };
                let shape = Cuboid::new(v.half);
                if shape.contains_local_point(low) {
                    let vol = v.half.x * v.half.y * v.half.z;
                    if best.is_none_or(|(b, _)| vol < b) {
                        best = Some((vol, n));
                    }
                }
            }
        }
        if let Some((_, c)) = best {
            return Placement::Inside(c);
        }
        self.support_of(xb, x)
            .map_or(Placement::Loose, Placement::On)
    }

    /// The middle of body `b`'s underside (1 cm up) in the frame `frame`, not above
    /// the middle of its extent there.
    fn underside_in(&self, b: RigidBodyHandle, frame: Pose) -> Option<Vector> {
        let inv = frame.inverse();
        let aabb = self.pw.bodies[b]
            .colliders()
            .iter()
            .map(|c| {
                let col = &self.pw.colliders[*c];
                col.shape().compute_aabb(&(inv * *col.position()))
            })
            .reduce(|a, b| a.merged(&b))?;
        let c = aabb.center();
        Some(Vector::new(c.x, (aabb.mins.y + 0.01).min(c.y), c.z))
    }

    /// A point 1 cm above the lowest point of a body's colliders, below its centre of
    /// mass.
    fn underside(&self, b: RigidBodyHandle) -> Option<Vector> {
        let rb = &self.pw.bodies[b];
        let com = rb.center_of_mass();
        let low = rb
            .colliders()
            .iter()
            .map(|c| self.pw.colliders[*c].compute_aabb().mins.y)
            .reduce(f32::min)?;
        Some(Vector::new(com.x, (low + 0.01).min(com.y), com.z))
    }

    /// The named thing under body `xb` that it touches.
    fn support_of(&self, xb: RigidBodyHandle, x: Idx) -> Option<Idx> {
        // From just above its underside: a ray from the centre would start inside what
        // rests in it (a tall apple in a shallow plate).
        let origin = self.underside(xb)?;
        let mut filter = solid().exclude_rigid_body(xb);
        // The quadrotor rests on furniture or a floor, never on what is in its basket.
        if self.quad.as_ref().is_some_and(|q| q.body == xb) {
            filter.flags |= QueryFilterFlags::EXCLUDE_DYNAMIC;
        }
        let qp = self.pw.query_pipeline_with_filter(filter);
        let ray = Ray::new(origin, -Vector::Y);
        let (hit, _) = qp.cast_ray(&ray, 3.0, true)?;
        let s = *self.owner.get(&hit)?;
        if s == x {
            return None;
        }
        // Contact, not just something below.
        self.body_touches(xb, s).then_some(s)
    }

    /// Distance from the dog's shoulder to the nearest point of `x`.
    pub fn dog_distance(&self, x: Idx) -> Option<f32> {
        let s = self.dog_shoulder_world()?;
        let b = self.body[x.get()]?;
        let mut best = f32::INFINITY;
        for c in self.pw.bodies[b].colliders() {
            if self.owner.get(c) != Some(&x) {
                continue;
            }
            let col = &self.pw.colliders[*c];
            let proj = col.shape().project_point(col.position(), s, true);
            best = best.min((proj.point - s).length());
        }
        best.is_finite().then_some(best)
    }

    pub fn dog_reach(&self) -> f32 {
        self.dog
            .as_ref()
            .and_then(|d| self.arm_index(d.robot))
            .map_or(0.0, |ai| self.arms[ai].reach)
    }

    /// The room each mobile robot's footprint is in.
    pub fn robot_room(&self, robot: Idx) -> Option<Idx> {
        let b = self.body[robot.get()]?;
        self.room_at(self.pw.bodies[b].translation())
    }

    /// `Some(true)` landed, `Some(false)` flying.
    pub fn quad_landed_on(&self) -> Option<(bool, Option<Idx>)> {
        let q = self.quad.as_ref()?;
        if q.motors_on {
            return Some((false, None));
        }
        let rb = &self.pw.bodies[q.body];
        let on = self.support_of(q.body, q.robot);
        Some((rb.linvel().length() < 0.05 && on.is_some(), on))
    }

    /// Whether the flying quadrotor is over `s`'s top (a floor: its room).
    pub fn quad_above(&self, s: Idx) -> bool {
        let Some(p) = self.quad_pos() else {
            return false;
        };
        if self.task.node(s).kind == NodeKind::Floor {
            return self
                .task
                .rooms()
                .iter()
                .find(|&&r| self.task.floor_of(r) == Some(s))
                .is_some_and(|&r| self.room_at(p) == Some(r));
        }
        let Some((b, c, half)) = self.top[s.get()] else {
            return false;
        };
        let local = self.pw.bodies[b].position().inverse_transform_point(p) - c;
        local.x.abs() <= half[0] && local.z.abs() <= half[1] && local.y > 0.0
    }

    /// Pose of every body of the task's nodes, as `(id, [x, y, z, qx, qy, qz, qw])`.
    pub fn poses(&self) -> Vec<(NodeId, [f32; 7])> {
        let mut out = Vec::new();
        for n in self.task.indices() {
            if let Some(b) = self.body[n.get()] {
                let p = self.pw.bodies[b].position();
                let (t, r) = (p.translation, p.rotation);
                out.push((self.task.id(n), [t.x, t.y, t.z, r.x, r.y, r.z, r.w]));
            }
        }
        out
    }

    /// Hand position of `robot`'s arm, if it has one.
    pub fn hand(&self, robot: Idx) -> Option<Vector> {
        self.arm_index(robot)
            .map(|ai| self.hand_pos(&self.arms[ai]))
    }

    /// Centre of `x`'s body.
    pub fn position(&self, x: Idx) -> Option<Vector> {
        self.body[x.get()].map(|b| self.pw.bodies[b].translation())
    }

    pub fn grasped_body_near_hand(&self, robot: Idx, x: Idx) -> Option<f32> {
        let hand = self.hand(robot)?;
        let b = self.body[x.get()]?;
        let aabb = self.node_aabb(x)?;
        let _ = b;
        Some(Vector::new(hand.x - aabb.center().x, 0.0, hand.z - aabb.center().z).length())
    }
}
