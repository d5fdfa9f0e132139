//! Building the world from its layout: the ground, each room's floor and walls (cut
//! where doors open and flights arrive, raised beside a stairwell), door panels, flights
//! of stairs, furniture and objects (boxes, open containers, lids), and the three robot
//! models with their arms.

use std::collections::HashMap;
use std::f32::consts::{FRAC_PI_2, PI};
use std::sync::Arc;

use coherent_core::{Idx, NodeId, PropSet, RobotKind, Task};
use rapier3d::control::{CharacterLength, KinematicCharacterController};
use rapier3d::prelude::*;

use super::arm::ARM_HOME;
use super::{
    Arm, Dog, FailureKind, G_DOG, G_OBJECT, G_QUAD, G_STATIC, Hinge, PhysicsError, Quad,
    Tolerances, Volume, World, fail, groups, hinge_pose, v3,
};
use crate::layout::{
    self, ASIDE, DoorGeom, Flight, ItemGeom, Layout, Lid, RobotGeom, RobotSpecs, RoomGeom, WALL,
    wall_of,
};

/// A wall of the lower room closer than this to a side of a flight rises with the
/// stairwell (the robots need no gap that narrow).
const STAIRWELL_GAP: f32 = 0.35;

// What the world is built of, beyond the layout's sizes: lengths in metres.

/// Half extents of the ground slab under the things set aside off the plan (`ASIDE`, its
/// corner), whose middle lies this far in from that corner.
const ASIDE_GROUND_HALF: f32 = 8.0;
const ASIDE_GROUND_INSET: f32 = 4.0;
/// Half thickness of the ground and of each room's floor slab (below its level).
const SLAB_HALF: f32 = 0.05;
/// A door's panel: the gap it leaves at each side of its opening and above the floor,
/// its half thickness, and its handle's distance from its free edge and height.
const DOOR_SIDE_GAP: f32 = 0.02;
const DOOR_FLOOR_GAP: f32 = 0.01;
const DOOR_HALF_THICKNESS: f32 = 0.025;
const DOOR_HANDLE_IN: f32 = 0.12;
const DOOR_HANDLE_HEIGHT: f32 = 0.9;
/// Friction of a flight's surface: the legged robot does not slip on it.
const FLIGHT_FRICTION: f32 = 0.9;
/// Friction of furniture and things, damping of loose things' motion and turning, and
/// the densities (kg/m³) of loose things and of fixed furniture.
const ITEM_FRICTION: f32 = 0.8;
const ITEM_LINEAR_DAMPING: f32 = 0.1;
const ITEM_ANGULAR_DAMPING: f32 = 0.5;
const ITEM_DENSITY: f32 = 100.0;
const FURNITURE_DENSITY: f32 = 1000.0;
/// Where a hand takes a top lid (in from its front edge) and a front door (in from its
/// free edge).
const LID_HANDLE_IN: f32 = 0.03;
const FRONT_DOOR_HANDLE_IN: f32 = 0.05;
/// The angle (rad) lids and front doors open to: past upright, so that they stay open.
const LID_OPEN_ANGLE: f32 = -1.9;
/// The quadrotor: its damping in the air (linear, angular), its basket's wall thickness
/// and height, the part of its mass in each of its ten parts (the basket's five, four
/// rotors and the hub), its rotors (in from the frame's corners, their height, radius
/// and half height), its hub (half extents and height), and the half height of the
/// basket's inside.
const QUAD_LINEAR_DAMPING: f32 = 0.3;
const QUAD_ANGULAR_DAMPING: f32 = 1.0;
const BASKET_WALL: f32 = 0.02;
const BASKET_WALL_HEIGHT: f32 = 0.14;
const BASKET_FRICTION: f32 = 0.9;
const QUAD_PART_MASS: f32 = 0.1;
const ROTOR_INSET: f32 = 0.08;
const ROTOR_HEIGHT: f32 = 0.24;
const ROTOR_RADIUS: f32 = 0.08;
const ROTOR_HALF_HEIGHT: f32 = 0.01;
const HUB_HALF: [f32; 3] = [0.06, 0.03, 0.06];
const HUB_HEIGHT: f32 = 0.25;
const BASKET_INSIDE_HALF: f32 = 0.06;
/// A fixed arm's base: its radius.
const ARM_BASE_RADIUS: f32 = 0.08;
/// An arm's links: capsules of this radius and density, no shorter than the yaw link's
/// half length; the hand's half length.
const LINK_RADIUS: f32 = 0.03;
const LINK_DENSITY: f32 = 500.0;
const YAW_LINK_HALF: f32 = 0.01;
const HAND_HALF: f32 = 0.02;
/// An arm's joint limits (rad): yaw, shoulder, elbow (the wrist follows them).
const ARM_LIMITS: [(f32, f32); 3] = [(-PI, PI), (-1.6, 1.6), (0.0, 2.6)];

impl World {
    pub fn new(task: Arc<Task>, layout: Layout) -> Result<World, PhysicsError> {
        let n = task.nodes.len();
        let flights = layout::flights(&layout).map_err(|e| PhysicsError {
            kind: FailureKind::Layout,
            message: e.0,
        })?;
        let tol = Tolerances::default();
        let mut pw = PhysicsWorld::new();
        pw.integration_parameters.dt = tol.dt;
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
            quads: Vec::new(),
            dogs: Vec::new(),
            grasps: Vec::new(),
            kcc: KinematicCharacterController::default(),
            stairs_kcc: KinematicCharacterController {
                // The robot's bottom stays as far above what it walks on as on a floor.
                offset: CharacterLength::Absolute(tol.dog_floor_gap),
                max_slope_climb_angle: tol.dog_stairs_max_slope,
                min_slope_slide_angle: tol.dog_stairs_max_slope,
                snap_to_ground: Some(CharacterLength::Absolute(tol.dog_stairs_snap)),
                autostep: None,
                ..KinematicCharacterController::default()
            },
            flights,
            flight_colliders: Vec::new(),
            sim_time: 0.0,
            paths: Vec::new(),
            tol,
        };
        w.kcc.offset = CharacterLength::Absolute(tol.dog_skin);
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
        w.settle(tol.initial_settle);
        Ok(w)
    }

    fn node_of(&self, id: i64) -> Result<Idx, PhysicsError> {
        self.task.idx(NodeId(id)).ok_or_else(|| PhysicsError {
            kind: FailureKind::Layout,
            message: format!("geometry names node {id}, which is not in the task"),
        })
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

    /// The ground, each room's floor and walls, the flights of stairs and the door
    /// panels (each door open or closed as the task starts is set by [`World::new`]).
    fn build_rooms(&mut self) -> Result<(), PhysicsError> {
        let ground = self.pw.insert_body(RigidBodyBuilder::fixed());
        self.add_collider(
            ColliderBuilder::cuboid(ASIDE_GROUND_HALF, SLAB_HALF, ASIDE_GROUND_HALF)
                .translation(Vector::new(
                    ASIDE[0] - ASIDE_GROUND_INSET,
                    -SLAB_HALF,
                    ASIDE[1] - ASIDE_GROUND_INSET,
                ))
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
                ColliderBuilder::cuboid(hx, SLAB_HALF, hz)
                    .translation(Vector::new(cx, r.level - SLAB_HALF, cz))
                    .collision_groups(groups(G_STATIC)),
                ground,
                floor,
            );
            if let Some(f) = floor {
                self.top[f.get()] = Some((ground, Vector::new(cx, r.level, cz), [hx, hz]));
            }
            self.build_walls(ground, &r);
        }
        for f in self.flights.clone() {
            self.build_flight(ground, &f)?;
        }
        for d in self.layout.doors.clone() {
            self.build_door(&d)?;
        }
        Ok(())
    }

    /// A room's four walls, cut where a door opens in them or a flight arrives, and
    /// raised beside a flight that leaves the room.
    fn build_walls(&mut self, ground: RigidBodyHandle, r: &RoomGeom) {
        let wh = self.layout.wall_height;
        let sides = [
            (true, r.min[1], r.min[0], r.max[0]),
            (true, r.max[1], r.min[0], r.max[0]),
            (false, r.min[0], r.min[1], r.max[1]),
            (false, r.max[0], r.min[1], r.max[1]),
        ];
        let mut raised = Vec::new();
        for (along_x, at, a0, a1) in sides {
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
            for (c0, c1, h) in self.wall_cuts(r, along_x, at) {
                pieces.push((start, c0, 0.0, wh));
                pieces.push((c0, c1, h, wh)); // lintel
                start = c1;
            }
            pieces.push((start, a1, 0.0, wh));
            let eps = self.tol.geometry_epsilon;
            for (p0, p1, y0, y1) in pieces {
                if p1 - p0 < eps || y1 - y0 < eps {
                    continue;
                }
                self.wall_box(ground, r.level, (along_x, at), (p0, p1), (y0, y1));
            }
        }
        for (along_x, at, p0, p1, top) in raised {
            self.wall_box(ground, r.level, (along_x, at), (p0, p1), (wh, top));
        }
    }

    /// The openings in the wall of room `r` that runs along x (`along_x`) or z at `at`:
    /// `(from, to, height)` along the wall, in order; a door is as high as it is, a
    /// flight arriving through the wall leaves it open to the wall's full height.
    fn wall_cuts(&self, r: &RoomGeom, along_x: bool, at: f32) -> Vec<(f32, f32, f32)> {
        let eps = self.tol.geometry_epsilon;
        let mut cuts: Vec<(f32, f32, f32)> = self
            .layout
            .doors
            .iter()
            .filter(|d| {
                d.along_x == along_x
                    && layout::door_level(&self.layout, d) == r.level
                    && (if along_x { d.center[1] } else { d.center[0] } - at).abs() < eps
            })
            .map(|d| {
                let c = if along_x { d.center[0] } else { d.center[1] };
                (c - d.width / 2.0, c + d.width / 2.0, d.height)
            })
            .collect();
        cuts.extend(
            self.flights
                .iter()
                .filter(|f| {
                    f.rooms[1] == r.id
                        && f.along_x() != along_x
                        && (if along_x { f.head[1] } else { f.head[0] } - at).abs() < eps
                })
                .map(|f| {
                    let c = if along_x { f.head[0] } else { f.head[1] };
                    (
                        c - f.width / 2.0,
                        c + f.width / 2.0,
                        self.layout.wall_height,
                    )
                }),
        );
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
        cuts
    }

    /// A piece of wall on the storey at `level`, on the line `(along_x, at)`, from `p0`
    /// to `p1` along it and from `y0` to `y1` above the floor.
    fn wall_box(
        &mut self,
        ground: RigidBodyHandle,
        level: f32,
        (along_x, at): (bool, f32),
        (p0, p1): (f32, f32),
        (y0, y1): (f32, f32),
    ) {
        let (m, half) = ((p0 + p1) / 2.0, (p1 - p0) / 2.0);
        let (t, hx, hz) = if along_x {
            (Vector::new(m, level + (y0 + y1) / 2.0, at), half, WALL)
        } else {
            (Vector::new(at, level + (y0 + y1) / 2.0, m), WALL, half)
        };
        self.add_collider(
            ColliderBuilder::cuboid(hx, (y1 - y0) / 2.0, hz)
                .translation(t)
                .collision_groups(groups(G_STATIC)),
            ground,
            None,
        );
    }

    /// A door's panel, hinged on the low end of its opening.
    fn build_door(&mut self, d: &DoorGeom) -> Result<(), PhysicsError> {
        let door = self.node_of(d.id)?;
        let level = layout::door_level(&self.layout, d);
        let (w2, h2) = (
            d.width / 2.0 - DOOR_SIDE_GAP,
            d.height / 2.0 - DOOR_FLOOR_GAP,
        );
        let centre = Vector::new(d.center[0], level + h2 + DOOR_FLOOR_GAP, d.center[1]);
        let (pivot, shape) = if d.along_x {
            (
                Vector::new(
                    d.center[0] - d.width / 2.0 + DOOR_SIDE_GAP,
                    level,
                    d.center[1],
                ),
                ColliderBuilder::cuboid(w2, h2, DOOR_HALF_THICKNESS),
            )
        } else {
            (
                Vector::new(
                    d.center[0],
                    level,
                    d.center[1] - d.width / 2.0 + DOOR_SIDE_GAP,
                ),
                ColliderBuilder::cuboid(DOOR_HALF_THICKNESS, h2, w2),
            )
        };
        let closed = Pose::from_translation(centre);
        let body = self
            .pw
            .insert_body(RigidBodyBuilder::kinematic_position_based().pose(closed));
        self.add_collider(shape.collision_groups(groups(G_STATIC)), body, Some(door));
        self.body[door.get()] = Some(body);
        let handle_world = if d.along_x {
            Vector::new(
                d.center[0] + d.width / 2.0 - DOOR_HANDLE_IN,
                level + DOOR_HANDLE_HEIGHT,
                d.center[1],
            )
        } else {
            Vector::new(
                d.center[0],
                level + DOOR_HANDLE_HEIGHT,
                d.center[1] + d.width / 2.0 - DOOR_HANDLE_IN,
            )
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
            wedge
                .friction(FLIGHT_FRICTION)
                .collision_groups(groups(G_STATIC)),
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
                    .angular_damping(ITEM_ANGULAR_DAMPING)
                    .linear_damping(ITEM_LINEAR_DAMPING)
            } else {
                RigidBodyBuilder::fixed().translation(base)
            };
            let body = self.pw.insert_body(builder);
            self.body[n.get()] = Some(body);
            let gr = groups(if it.dynamic { G_OBJECT } else { G_STATIC });
            let density = if it.dynamic {
                ITEM_DENSITY
            } else {
                FURNITURE_DENSITY
            };
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
                            .friction(ITEM_FRICTION)
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
                        .friction(ITEM_FRICTION)
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
                Vector::new(0.0, t / 2.0, -d / 2.0 + LID_HANDLE_IN),
            ),
            _ => (
                Pose::from_translation(base + Vector::new(0.0, h / 2.0, -d / 2.0 + t / 2.0)),
                base + Vector::new(-w / 2.0, 0.0, -d / 2.0),
                Vector::Y,
                ColliderBuilder::cuboid(w / 2.0, h / 2.0, t / 2.0),
                Vector::new(w / 2.0 - FRONT_DOOR_HANDLE_IN, 0.0, -t / 2.0),
            ),
        };
        let body = self
            .pw
            .insert_body(RigidBodyBuilder::kinematic_position_based().pose(closed));
        let gr = groups(if it.dynamic { G_OBJECT } else { G_STATIC });
        self.add_collider(shape.collision_groups(gr), body, Some(n));
        // Top lids open upwards (about +x with the pivot at the back: negative angle lifts
        // the front); front doors swing out to the left.
        self.hinges.push(Hinge {
            node: n,
            body,
            closed,
            pivot,
            axis,
            open_angle: LID_OPEN_ANGLE,
            handle,
        });
        Ok(())
    }

    /// Each robot of the layout, as its kind is built.
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
                RobotKind::Quadrotor => self.build_quadrotor(r, &rg, rot, &specs),
                RobotKind::RobotDog => self.build_dog(r, &rg, rot, &specs)?,
                RobotKind::RobotArm => self.build_fixed_arm(r, &rg, rot, &specs)?,
            }
        }
        Ok(())
    }

    /// The quadrotor: a dynamic body whose basket (floor and walls) carries most of its
    /// mass, four rotors and a hub; the basket's inside is a volume of the basket node.
    fn build_quadrotor(&mut self, r: Idx, rg: &RobotGeom, rot: Rotation, specs: &RobotSpecs) {
        let lift = Vector::new(0.0, self.tol.quad_start_lift, 0.0);
        let pose = Pose::from_parts(v3(rg.pos) + lift, rot);
        let body = self.pw.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(pose)
                .linear_damping(QUAD_LINEAR_DAMPING)
                .angular_damping(QUAD_ANGULAR_DAMPING)
                .can_sleep(false),
        );
        let basket = self.task.basket_of(r);
        let b = specs.basket_half;
        let q = specs.quad_half;
        let t = BASKET_WALL;
        let wall_h = BASKET_WALL_HEIGHT;
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
                    .mass(total * QUAD_PART_MASS)
                    .friction(BASKET_FRICTION)
                    .collision_groups(gr),
                body,
                owner,
            );
        }
        let (i, h) = (ROTOR_INSET, ROTOR_HEIGHT);
        let rotors = [
            Vector::new(q - i, h, q - i),
            Vector::new(-q + i, h, q - i),
            Vector::new(-q + i, h, -q + i),
            Vector::new(q - i, h, -q + i),
        ];
        for p in rotors {
            self.add_collider(
                ColliderBuilder::cylinder(ROTOR_HALF_HEIGHT, ROTOR_RADIUS)
                    .translation(p)
                    .mass(total * QUAD_PART_MASS)
                    .collision_groups(gr),
                body,
                Some(r),
            );
        }
        self.add_collider(
            ColliderBuilder::cuboid(HUB_HALF[0], HUB_HALF[1], HUB_HALF[2])
                .translation(Vector::new(0.0, HUB_HEIGHT, 0.0))
                .mass(total * QUAD_PART_MASS)
                .collision_groups(gr),
            body,
            Some(r),
        );
        self.body[r.get()] = Some(body);
        if let Some(bk) = basket {
            self.body[bk.get()] = Some(body);
            self.volume[bk.get()] = Some(Volume {
                body,
                local: Pose::from_translation(Vector::new(0.0, t + BASKET_INSIDE_HALF, 0.0)),
                half: Vector::new(b - t, BASKET_INSIDE_HALF, b - t),
            });
        }
        self.quads.push(Quad {
            robot: r,
            body,
            motors_on: false,
            integral: Vector::ZERO,
            rotors,
            target: (Vector::ZERO, Vector::ZERO),
        });
        self.paths.push((self.task.id(r), vec![rg.pos]));
    }

    /// The legged robot: a kinematic cylinder walked by the character controller, and
    /// its arm.
    fn build_dog(
        &mut self,
        r: Idx,
        rg: &RobotGeom,
        rot: Rotation,
        specs: &RobotSpecs,
    ) -> Result<(), PhysicsError> {
        let h = specs.dog_half;
        let lift = Vector::new(0.0, self.tol.dog_floor_gap, 0.0);
        let pose = Pose::from_parts(v3(rg.pos) + lift, rot);
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
        self.dogs.push(Dog {
            robot: r,
            body,
            yaw: rg.yaw,
        });
        let shoulder = v3(specs.dog_shoulder);
        self.build_arm(r, body, shoulder, specs.dog_links)?;
        self.paths.push((self.task.id(r), vec![rg.pos]));
        Ok(())
    }

    /// A fixed arm: a fixed base on its surface (it touches nothing) and the arm on it.
    fn build_fixed_arm(
        &mut self,
        r: Idx,
        rg: &RobotGeom,
        rot: Rotation,
        specs: &RobotSpecs,
    ) -> Result<(), PhysicsError> {
        let pose = Pose::from_parts(v3(rg.pos), rot);
        let body = self.pw.insert_body(RigidBodyBuilder::fixed().pose(pose));
        self.add_collider(
            ColliderBuilder::cylinder(specs.arm_shoulder / 2.0, ARM_BASE_RADIUS)
                .translation(Vector::new(0.0, specs.arm_shoulder / 2.0, 0.0))
                .collision_groups(InteractionGroups::none()),
            body,
            Some(r),
        );
        self.body[r.get()] = Some(body);
        let shoulder = Vector::new(0.0, specs.arm_shoulder, 0.0);
        self.build_arm(r, body, shoulder, specs.arm_links)
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
                ColliderBuilder::capsule_z(half_len.max(YAW_LINK_HALF), LINK_RADIUS)
                    .translation(Vector::new(0.0, 0.0, -half_len))
                    .density(LINK_DENSITY)
                    .collision_groups(InteractionGroups::none()),
                b,
                &mut pw.bodies,
            );
            b
        };
        let yaw = link(&mut self.pw, YAW_LINK_HALF);
        let upper = link(&mut self.pw, links[0] / 2.0);
        let fore = link(&mut self.pw, links[1] / 2.0);
        let hand = link(&mut self.pw, HAND_HALF);
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
            limits: ARM_LIMITS,
            reach: links[0] + links[1],
            min_reach: {
                // The elbow at its limit.
                let c = ARM_LIMITS[2].1.cos();
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
}
