//! The quadrotor's flights: take-off, routes at cruise altitude through the door between
//! two rooms or up and down the stairwell between storeys, hovering, landing spots and
//! landing, and the crash check against walls and door panels. The thrust controller
//! that follows the set points runs in every step (`step.rs`).

use coherent_core::{Idx, NodeKind, Relation};
use rapier3d::prelude::*;

use super::motion::{Descend, Fly, Hover, Settle, Stage, Tick};
use super::{FailureKind, PhysicsError, World, fail, solid, v3};

impl World {
    /// The next step of a flight: the set point moves towards the next waypoint at
    /// flight speed; at the last one the craft hovers there.
    pub(super) fn fly_tick(&mut self, robot: Idx, f: &mut Fly) -> Result<Tick, PhysicsError> {
        let (i, body) = self.quad_and_body(robot)?;
        let (mut setpoint, com_off) = *f.at.get_or_insert_with(|| {
            let rb = &self.pw.bodies[body];
            (rb.translation(), rb.center_of_mass() - rb.translation())
        });
        let speed = self.layout.specs.flight_speed;
        let dt = self.tol.dt;
        while let Some(&wp) = f.waypoints.get(f.next) {
            if (wp - setpoint).length() > self.tol.quad_waypoint_epsilon {
                let d = wp - setpoint;
                let stepv = d.normalize_or_zero() * (speed * dt).min(d.length());
                setpoint += stepv;
                f.at = Some((setpoint, com_off));
                self.quads[i].target = (setpoint + com_off, stepv / dt);
                return Ok(Tick::Step);
            }
            f.next += 1;
        }
        Ok(Tick::Then(vec![Stage::Hover(Hover {
            end: setpoint,
            com_off,
            steps: 0,
            still: false,
        })]))
    }

    /// After a step of a flight: no crash, and the track recorded.
    pub(super) fn fly_after(&mut self, robot: Idx) -> Result<(), PhysicsError> {
        self.check_quad_hits(robot)?;
        self.record_path(robot);
        Ok(())
    }

    /// Holding the end of a flight, for at most `quad_hover_max_steps`.
    pub(super) fn hover_tick(&mut self, robot: Idx, h: &mut Hover) -> Result<Tick, PhysicsError> {
        let (i, _) = self.quad_and_body(robot)?;
        if h.still {
            return Ok(Tick::Done);
        }
        if h.steps >= self.tol.quad_hover_max_steps {
            let at = self.quad_pos(robot).unwrap_or(h.end);
            let end = h.end;
            return fail(
                FailureKind::Timeout,
                format!(
                    "the quadrotor did not settle at ({:.2}, {:.2}, {:.2}); it is {:.2} m away",
                    end.x,
                    end.y,
                    end.z,
                    (at - end).length()
                ),
            );
        }
        self.quads[i].target = (h.end + h.com_off, Vector::ZERO);
        Ok(Tick::Step)
    }

    /// After a step of hovering: no crash; still once it is within `quad_hover_radius`
    /// of the end and slower than `quad_hover_speed` (after `quad_hover_min_steps`).
    pub(super) fn hover_after(&mut self, robot: Idx, h: &mut Hover) -> Result<(), PhysicsError> {
        self.check_quad_hits(robot)?;
        if let Ok(q) = self.quad_of(robot) {
            let rb = &self.pw.bodies[q.body];
            if h.steps > self.tol.quad_hover_min_steps
                && (rb.translation() - h.end).length() < self.tol.quad_hover_radius
                && rb.linvel().length() < self.tol.quad_hover_speed
            {
                h.still = true;
            }
        }
        h.steps += 1;
        Ok(())
    }

    /// A flying quadrotor touching a door panel or a wall has crashed.
    fn check_quad_hits(&self, robot: Idx) -> Result<(), PhysicsError> {
        let q = self.quad_of(robot)?;
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
                let is_wall = owner.is_none()
                    && self
                        .pw
                        .colliders
                        .get(other)
                        .is_some_and(|c| c.parent().is_some_and(|p| self.pw.bodies[p].is_fixed()))
                    && self.pw.colliders[other].compute_aabb().maxs.y > self.tol.quad_wall_min_top;
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

    /// A free spot for the quadrotor `robot` on `s` (body origin), preferring one next
    /// to a fixed arm on `s`, else the one nearest `near`.
    pub(super) fn landing_spot(
        &self,
        robot: Idx,
        s: Idx,
        near: Vector,
    ) -> Result<Vector, PhysicsError> {
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
        let t = &self.tol;
        // A margin around the craft: it must not brush a wall or the arm on arrival.
        let shape = Cuboid::new(Vector::new(
            qh + t.quad_landing_margin,
            t.quad_landing_probe_half_height,
            qh + t.quad_landing_margin,
        ));
        let qbody = self.quad_of(robot).ok().map(|q| q.body);
        let mut best: Option<(f32, Vector)> = None;
        let step = t.quad_landing_grid;
        // A floor is walled: keep the craft's overshoot on arrival off the walls.
        let wall_gap = if self.task.node(s).kind == NodeKind::Floor {
            t.quad_floor_wall_gap
        } else {
            0.0
        };
        let nx = ((half[0] - qh - wall_gap) / step).floor() as i32;
        let nz = ((half[1] - qh - wall_gap) / step).floor() as i32;
        for i in -nx..=nx {
            for k in -nz..=nz {
                let local = c + Vector::new(i as f32 * step, t.quad_landing_lift, k as f32 * step);
                let p = pose.transform_point(local);
                let probe =
                    Pose::from_translation(p + Vector::new(0.0, t.quad_landing_probe_lift, 0.0));
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
                    Some(a) => ((p - a).length() - t.quad_arm_distance).abs(),
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

    pub(super) fn top_height(&self, s: Idx) -> f32 {
        self.top[s.get()]
            .map(|(b, c, _)| self.pw.bodies[b].position().transform_point(c).y)
            .unwrap_or(0.0)
    }

    /// Flies to hover at `hover_y` over `dest` (a point on the destination's surface) at
    /// the cruise altitude above each storey's floor: through the door between two rooms
    /// of a storey, or up or down the stairwell between storeys (over the flight's first
    /// `quad_stairs_climb_at`, where nothing is above it, then along the run through the
    /// opening in the upper room's wall).
    pub(super) fn quad_fly_to(
        &self,
        robot: Idx,
        dest: Vector,
        hover_y: f32,
    ) -> Result<Vec<Stage>, PhysicsError> {
        let p = self.pw.bodies[self.quad_of(robot)?.body].translation();
        let cruise = self.layout.specs.cruise_altitude;
        let t = &self.tol;
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
                let clear = (d.width + self.layout.specs.quad_half + t.quad_door_clearance)
                    .max(t.quad_door_min_clear);
                // Points kept `quad_room_margin` inside `room` (its middle line when it is
                // narrower): a narrow room, a hallway, is crossed, not flown out of.
                let margin = t.quad_room_margin;
                let fit = |v: f32, lo: f32, hi: f32| {
                    if hi - lo > 2.0 * margin {
                        v.clamp(lo + margin, hi - margin)
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
                let (climb, past) = (t.quad_stairs_climb_at, t.quad_stairs_past_head);
                let mut legs = [
                    f.at(climb, low),
                    f.at(climb, high),
                    f.at(f.run + past, high),
                ];
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
        Ok(vec![Fly::stage(wps)])
    }

    /// Motors on, then straight up `quad_takeoff_height`.
    pub(super) fn quad_takeoff(&self, robot: Idx) -> Result<Vec<Stage>, PhysicsError> {
        let p = self.pw.bodies[self.quad_of(robot)?.body].translation();
        let up = Vector::new(0.0, self.tol.quad_takeoff_height, 0.0);
        Ok(vec![Stage::Motors(true), Fly::stage(vec![p + up])])
    }

    /// Over a free spot on `s`, down to `quad_descent_start` above it, then slowly down
    /// until the basket touches it; the motors cut, it must rest there.
    pub(super) fn quad_land(&self, robot: Idx, s: Idx) -> Result<Vec<Stage>, PhysicsError> {
        let p = self.pw.bodies[self.quad_of(robot)?.body].translation();
        let spot = self.landing_spot(robot, s, p)?;
        let t = &self.tol;
        Ok(vec![
            Fly::stage(vec![
                Vector::new(spot.x, p.y.max(spot.y + t.quad_approach_height), spot.z),
                spot + Vector::new(0.0, t.quad_descent_start, 0.0),
            ]),
            Stage::Descend(Descend {
                surface: s,
                spot,
                at: None,
                steps: 0,
                touches: false,
            }),
        ])
    }

    /// The next step of the descent (at `quad_descent_speed`, for at most
    /// `quad_descent_max_steps`); once the craft touches, the motors are cut and it
    /// settles.
    pub(super) fn descend_tick(
        &mut self,
        robot: Idx,
        d: &mut Descend,
    ) -> Result<Tick, PhysicsError> {
        let (i, body) = self.quad_and_body(robot)?;
        let t = self.tol;
        let (y, com_off) = d.at.get_or_insert_with(|| {
            let rb = &self.pw.bodies[body];
            let start = d.spot.y + t.quad_descent_start;
            (start, rb.center_of_mass() - rb.translation())
        });
        if d.touches || d.steps >= t.quad_descent_max_steps {
            return Ok(Tick::Then(vec![
                Stage::Motors(false),
                Stage::Settle(Settle::new(t.quad_landing_settle, t.dt)),
                Stage::Landed(d.surface),
            ]));
        }
        *y -= t.quad_descent_speed * t.dt;
        self.quads[i].target = (
            Vector::new(d.spot.x, *y, d.spot.z) + *com_off,
            Vector::new(0.0, -t.quad_descent_speed, 0.0),
        );
        Ok(Tick::Step)
    }

    /// Motors on (the position controller starts afresh) or off.
    pub(super) fn set_motors(&mut self, robot: Idx, on: bool) {
        if let Some(q) = self.quads.iter_mut().find(|q| q.robot == robot) {
            q.motors_on = on;
            if on {
                q.integral = Vector::ZERO;
            }
        }
    }

    /// The landed quadrotor rests on `s`.
    pub(super) fn check_landed(&self, robot: Idx, s: Idx) -> Result<(), PhysicsError> {
        if !self.quad_touches(robot, s) {
            return fail(
                FailureKind::Blocked,
                format!("the quadrotor did not come to rest on {}", self.label(s)),
            );
        }
        Ok(())
    }

    /// Whether a collider of the quadrotor `robot` is in contact with one of `s`.
    pub(super) fn quad_touches(&self, robot: Idx, s: Idx) -> bool {
        self.quad_of(robot)
            .is_ok_and(|q| self.body_touches(q.body, s))
    }

    /// The quadrotor `robot`'s index in `quads` and its body.
    fn quad_and_body(&self, robot: Idx) -> Result<(usize, RigidBodyHandle), PhysicsError> {
        let body = self.quad_of(robot)?.body;
        Ok((self.quad_index(robot).unwrap_or(0), body))
    }
}
