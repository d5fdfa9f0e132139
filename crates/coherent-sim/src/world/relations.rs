//! The relations read back from the bodies: where a movable thing is (held, inside,
//! on), what touches what, hinge angles, the quadrotor landed or above a surface, the
//! legged robot's distance to things, robots' rooms, and poses.

use coherent_core::{Idx, NodeId, NodeKind};
use rapier3d::prelude::*;

use super::{Placement, World, solid};

impl World {
    /// Where a movable thing physically is: held, inside a container's volume, or on
    /// the surface under it that it touches.
    pub fn placement(&self, x: Idx) -> Placement {
        if let Some(g) = self.grasps.iter().find(|g| g.object == x) {
            return Placement::Held(g.robot);
        }
        let Some(xb) = self.body[x.get()] else {
            return Placement::Loose;
        };
        // The basket rides with its quadrotor: on what the quadrotor has landed on.
        if self.task.node(x).kind == NodeKind::Tool {
            let landed = self
                .quads
                .iter()
                .any(|q| self.task.basket_of(q.robot) == Some(x) && !q.motors_on);
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

    /// The middle of body `b`'s underside (`underside_lift` up) in the frame `frame`, not
    /// above the middle of its extent there.
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
        let low = aabb.mins.y + self.tol.underside_lift;
        Some(Vector::new(c.x, low.min(c.y), c.z))
    }

    /// A point `underside_lift` above the lowest point of a body's colliders, below its
    /// centre of mass.
    fn underside(&self, b: RigidBodyHandle) -> Option<Vector> {
        let rb = &self.pw.bodies[b];
        let com = rb.center_of_mass();
        let low = rb
            .colliders()
            .iter()
            .map(|c| self.pw.colliders[*c].compute_aabb().mins.y)
            .reduce(f32::min)?;
        let low = low + self.tol.underside_lift;
        Some(Vector::new(com.x, low.min(com.y), com.z))
    }

    /// The named thing under body `xb` that it touches.
    fn support_of(&self, xb: RigidBodyHandle, x: Idx) -> Option<Idx> {
        // From just above its underside: a ray from the centre would start inside what
        // rests in it (a tall apple in a shallow plate).
        let origin = self.underside(xb)?;
        let mut filter = solid().exclude_rigid_body(xb);
        // The quadrotor rests on furniture or a floor, never on what is in its basket.
        if self.quads.iter().any(|q| q.body == xb) {
            filter.flags |= QueryFilterFlags::EXCLUDE_DYNAMIC;
        }
        let qp = self.pw.query_pipeline_with_filter(filter);
        let ray = Ray::new(origin, -Vector::Y);
        let (hit, _) = qp.cast_ray(&ray, self.tol.support_ray, true)?;
        let s = *self.owner.get(&hit)?;
        if s == x {
            return None;
        }
        // Contact, not just something below.
        self.body_touches(xb, s).then_some(s)
    }

    pub(super) fn body_touches(&self, body: RigidBodyHandle, s: Idx) -> bool {
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

    /// World AABB of all of a node's colliders.
    pub(super) fn node_aabb(&self, n: Idx) -> Option<Aabb> {
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

    /// Current hinge angle of a door or lid, read from its panel's pose.
    pub fn hinge_angle(&self, n: Idx) -> Option<f32> {
        let h = self.hinges.iter().find(|h| h.node == n)?;
        let rot = *self.pw.bodies[h.body].rotation();
        let rel = rot * h.closed.rotation.inverse();
        let (axis, angle) = rel.to_axis_angle();
        Some(angle * axis.dot(h.axis).signum())
    }

    /// Distance from the shoulder of the legged robot `dog` to the nearest point of `x`.
    pub fn dog_distance(&self, dog: Idx, x: Idx) -> Option<f32> {
        let ai = self.arm_index(self.dog_of(dog).ok()?.robot)?;
        let s = self.shoulder(&self.arms[ai]);
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

    /// How far the arm of the legged robot `dog` reaches.
    pub fn dog_reach(&self, dog: Idx) -> f32 {
        self.dog_of(dog)
            .ok()
            .and_then(|d| self.arm_index(d.robot))
            .map_or(0.0, |ai| self.arms[ai].reach)
    }

    /// The room each mobile robot's footprint is in.
    pub fn robot_room(&self, robot: Idx) -> Option<Idx> {
        let b = self.body[robot.get()]?;
        self.room_at(self.pw.bodies[b].translation())
    }

    /// Whether the quadrotor `robot` has landed, and on what (`None`: no such
    /// quadrotor).
    pub fn quad_landed_on(&self, robot: Idx) -> Option<(bool, Option<Idx>)> {
        let q = self.quad_of(robot).ok()?;
        if q.motors_on {
            return Some((false, None));
        }
        let rb = &self.pw.bodies[q.body];
        let on = self.support_of(q.body, q.robot);
        let resting = rb.linvel().length() < self.tol.quad_landed_speed;
        Some((resting && on.is_some(), on))
    }

    /// Whether the flying quadrotor `robot` is over `s`'s top (a floor: its room).
    pub fn quad_above(&self, robot: Idx, s: Idx) -> bool {
        let Some(p) = self.quad_pos(robot) else {
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
}
