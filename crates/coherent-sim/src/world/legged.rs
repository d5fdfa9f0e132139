//! The legged robot: its way between two points (a route on each storey's occupancy
//! grid, [`crate::path`], joined by flights of stairs), walking it with the character
//! controller, and where it stands to work on a thing or to enter a room.

use std::f32::consts::TAU;

use coherent_core::{Idx, NodeKind};
use rapier3d::prelude::*;

use super::motion::{Stage, Tick, Turn, Walk};
use super::{FailureKind, PhysicsError, Placement, World, fail, solid, v3};
use crate::layout::{self, Flight};
use crate::path;

/// A stretch of the legged robot's way: waypoints on one storey (the first is where
/// it starts), or a flight walked from the approach at one end to the approach at the
/// other (given).
#[derive(Clone, Debug)]
enum Leg {
    Floor(Vec<Vector>),
    Flight(Flight, Vector),
}

impl World {
    /// One occupancy grid per storey, for the legged robot.
    fn grids(&self, dog: RigidBodyHandle) -> Vec<(f32, path::Grid)> {
        layout::levels(&self.layout)
            .into_iter()
            .map(|level| {
                let grid = path::Grid::new(
                    &self.layout,
                    &self.flights,
                    &self.pw.colliders,
                    dog,
                    level,
                    &self.tol,
                );
                (level, grid)
            })
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
        let (approach, gap) = (self.tol.dog_flight_approach, self.tol.dog_floor_gap);
        let mut legs = Vec::new();
        let mut at = start;
        for (f, up) in flights {
            let (foot, head) = (
                f.at(-approach, f.lower + gap),
                f.at(f.run + approach, f.upper + gap),
            );
            let (here, there) = if up { (foot, head) } else { (head, foot) };
            let (here, there) = (v3(here), v3(there));
            legs.push(Leg::Floor(grid(self.level_at(at))?.route(at, here)?));
            legs.push(Leg::Flight(f, there));
            at = there;
        }
        legs.push(Leg::Floor(grid(to)?.route(at, goal)?));
        Some(legs)
    }

    /// The way of the legged robot `robot` to `goal` (body origin, on the storey its
    /// height says), as walks along the floor and the flights, then a turn to face
    /// `face`.
    pub(super) fn walk(
        &self,
        robot: Idx,
        goal: Vector,
        face: Vector,
    ) -> Result<Vec<Stage>, PhysicsError> {
        let dog = self.dog_of(robot)?.clone();
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
        let mut stages = Vec::new();
        for leg in legs {
            match leg {
                Leg::Floor(route) => {
                    stages.push(Walk::stage(dog.robot, dog.body, route[1..].to_vec(), false));
                }
                Leg::Flight(f, there) => {
                    stages.push(Walk::stage(dog.robot, dog.body, vec![there], true));
                    stages.push(Stage::OffStairs(f, there));
                }
            }
        }
        stages.push(Stage::Turn(Turn {
            face,
            steps: 0,
            yaw: 0.0,
        }));
        Ok(stages)
    }

    /// Off a flight, the dog stands on the floor at the far end.
    pub(super) fn check_off_stairs(
        &self,
        robot: Idx,
        f: &Flight,
        there: Vector,
    ) -> Result<(), PhysicsError> {
        let dog = self.dog_of(robot)?;
        let y = self.pw.bodies[dog.body].translation().y;
        if (y - there.y).abs() > self.tol.dog_off_stairs_tolerance {
            return fail(
                FailureKind::Blocked,
                format!(
                    "the legged robot on stairs {} stopped at height {y:.2} m, not on the floor at {:.2} m",
                    f.id,
                    there.y - self.tol.dog_floor_gap
                ),
            );
        }
        Ok(())
    }

    /// Turning on the spot: the pose set, two steps, and its heading kept.
    pub(super) fn turn_tick(&mut self, robot: Idx, t: &mut Turn) -> Tick {
        let Ok(body) = self.dog_of(robot).map(|d| d.body) else {
            return Tick::Done;
        };
        t.steps += 1;
        match t.steps {
            1 => {
                let pos = self.pw.bodies[body].translation();
                t.yaw = (t.face.x - pos.x).atan2(t.face.z - pos.z);
                self.pw.bodies[body].set_next_kinematic_position(Pose::from_parts(
                    pos,
                    Rotation::from_rotation_y(t.yaw),
                ));
                Tick::Step
            }
            2 => Tick::Step,
            _ => {
                if let Some(d) = self.dogs.iter_mut().find(|d| d.robot == robot) {
                    d.yaw = t.yaw;
                }
                Tick::Done
            }
        }
    }

    /// The next step of a walk through waypoints on the floor plan with the character
    /// controller: at its height on a floor, or (`on_flight`) climbing and descending
    /// the flight's slope with the controller's vertical motion. Each waypoint gets
    /// `dog_walk_budget_factor` times the steps its straight distance takes, and
    /// `dog_walk_budget_steps` more; it must end within `dog_waypoint_tolerance` of it.
    pub(super) fn walk_tick(&mut self, w: &mut Walk) -> Result<Tick, PhysicsError> {
        let speed = self.layout.specs.dog_speed;
        let t = self.tol;
        let h = self.layout.specs.dog_half;
        // A cylinder: turning the robot never makes it collide.
        let shape = Cylinder::new(h[1], h[0].max(h[2]));
        let shape_off = Vector::new(0.0, h[1], 0.0);
        let kcc = if w.on_flight {
            self.stairs_kcc
        } else {
            self.kcc
        };
        while let Some(&wp) = w.waypoints.get(w.next) {
            let budget = *w.budget.get_or_insert_with(|| {
                let from = self.pw.bodies[w.body].translation();
                ((wp - from).length() / (speed * t.dt) * t.dog_walk_budget_factor) as usize
                    + t.dog_walk_budget_steps
            });
            let pos = self.pw.bodies[w.body].translation();
            let d = Vector::new(wp.x - pos.x, 0.0, wp.z - pos.z);
            if w.taken < budget && d.length() >= t.dog_waypoint_reached {
                let want = d.normalize_or_zero() * (speed * t.dt).min(d.length());
                let yaw = d.x.atan2(d.z);
                let last_hit = &mut w.last_hit;
                let moved = {
                    let filter = solid().exclude_rigid_body(w.body);
                    let qp = self.pw.query_pipeline_with_filter(filter);
                    let cpose = Pose::from_translation(pos + shape_off);
                    kcc.move_shape(t.dt, &qp, &shape, &cpose, want, |c| {
                        *last_hit = Some((c.handle, c.hit.witness1));
                    })
                    .translation
                };
                let rise = if w.on_flight { moved.y } else { 0.0 };
                self.pw.bodies[w.body].set_next_kinematic_position(Pose::from_parts(
                    pos + Vector::new(moved.x, rise, moved.z),
                    Rotation::from_rotation_y(yaw),
                ));
                w.taken += 1;
                w.last_move = (pos, moved, want);
                return Ok(Tick::Step);
            }
            let off = d.length();
            if off > t.dog_waypoint_tolerance {
                return fail(
                    FailureKind::Blocked,
                    format!(
                        "the legged robot slid along an obstacle and stopped {off:.2} m short of ({:.2}, {:.2}) at ({:.2}, {:.2}){}",
                        wp.x,
                        wp.z,
                        pos.x,
                        pos.z,
                        self.hit_name(w.last_hit)
                    ),
                );
            }
            w.next += 1;
            w.budget = None;
            w.taken = 0;
            w.stuck = 0;
        }
        Ok(Tick::Done)
    }

    /// After a step of a walk: the track recorded; blocked after more than
    /// `dog_stuck_steps` in a row that moved it less than `dog_stuck_fraction` of the way
    /// it wanted to go.
    pub(super) fn walk_after(&mut self, w: &mut Walk) -> Result<(), PhysicsError> {
        self.record_path(w.dog);
        let (pos, moved, want) = w.last_move;
        let horizontal = Vector::new(moved.x, 0.0, moved.z).length();
        if horizontal >= self.tol.dog_stuck_fraction * want.length() {
            w.stuck = 0;
            return Ok(());
        }
        w.stuck += 1;
        if w.stuck > self.tol.dog_stuck_steps {
            let wp = w.waypoints[w.next];
            return fail(
                FailureKind::Blocked,
                format!(
                    "the legged robot is blocked at ({:.2}, {:.2}, {:.2}) on its way to ({:.2}, {:.2}){}",
                    pos.x,
                    pos.y,
                    pos.z,
                    wp.x,
                    wp.z,
                    self.hit_name(w.last_hit)
                ),
            );
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
        for _ in 0..self.tol.anchor_depth {
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

    /// Where the legged robot `robot` stands to work on `x`: beside what `x` stands on,
    /// nearest to `x`.
    pub(super) fn service_point(
        &self,
        robot: Idx,
        x: Idx,
    ) -> Result<(Vector, Vector), PhysicsError> {
        let dog = self.dog_of(robot)?;
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
        let t = &self.tol;
        let gap = h[0].max(h[2]) + t.dog_service_gap;
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
        // A spot in the thing's own room: the far side of a wall is not beside it. A
        // door has two rooms; the rules keep the robot in its own as it walks up to the
        // door, so the spot is on its side (the far side, when the two were as near,
        // was taken first, and reached the long way round through other doors).
        let home = if self.task.node(a).kind == NodeKind::Door {
            self.room_at(self.pw.bodies[dog.body].translation())
        } else {
            self.room_at(Vector::new(c.x, aabb.mins.y + t.room_probe_lift, c.z))
        };
        let mut cands = Vec::new();
        for (nx, nz) in [(0.0, -1.0), (0.0, 1.0), (-1.0, 0.0), (1.0, 0.0)] {
            let lateral = if nx == 0.0 {
                Vector::X * he.x
            } else {
                Vector::Z * he.z
            };
            for f in t.dog_service_offsets {
                // Nearest free cell straight out from that side (a wall beside a door
                // or the grid's cells can block the first one).
                let free = t.dog_service_steps_out.into_iter().find_map(|extra| {
                    let p = Vector::new(
                        c.x + nx * (he.x + gap + extra),
                        level + t.dog_floor_gap,
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

    pub(super) fn dog_to_room(&self, robot: Idx, room: Idx) -> Result<Vec<Stage>, PhysicsError> {
        let dog = self.dog_of(robot)?.clone();
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
        let t = &self.tol;
        // The robot's height on the room's floor.
        let y = if level == self.level_at(p) {
            p.y
        } else {
            level + t.dog_floor_gap
        };
        // A free spot inside the room, just past the door or the flight when there is one.
        let mid = Vector::new((lo[0] + hi[0]) / 2.0, y, (lo[1] + hi[1]) / 2.0);
        let seed = match (&door, flight) {
            (Some(d), _) => {
                let c = Vector::new(d.center[0], y, d.center[1]);
                c + (mid - c).normalize_or_zero() * t.dog_room_entry
            }
            (None, Some(f)) if f.rooms[1] == rid => v3(f.at(f.run + t.dog_room_entry, y)),
            (None, Some(f)) => v3(f.at(-t.dog_room_entry, y)),
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
        let directions = t.dog_room_search_directions;
        'search: for r in 0..t.dog_room_search_rings {
            for k in 0..directions {
                let a = k as f32 * TAU / directions as f32;
                let ring = r as f32 * t.dog_room_search_spacing;
                let q = seed + Vector::new(a.cos(), 0.0, a.sin()) * ring;
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
        self.walk(robot, goal, goal + (goal - p))
    }
}
