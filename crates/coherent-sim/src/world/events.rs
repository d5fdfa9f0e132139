//! What an event mid-task (docs/dynamic.md) does to the bodies. A thing moved by someone
//! outside the team is taken from wherever it is (out of a hand too) and set down on a
//! free spot of its new surface, or inside its new container, with what rests on it; the
//! world then settles. The other kinds move no body: a robot that goes down stays where
//! it stands, an obstacle to the others; one that joins where the task placed it is
//! there already; goals, locks and failing actions are the rules' alone.

use coherent_core::{Idx, NodeKind};
use rapier3d::prelude::*;

use super::{FailureKind, G_OBJECT, PhysicsError, World, fail, groups};

impl World {
    /// Sets `x` down on surface `holder` (in container `holder`, `inside`), with what
    /// rests on it: at the free spot nearest to the shoulders of the legged robots
    /// `near` (those the rules put next to it there), else nearest to the middle of the
    /// top or the inside. Out of any hand first.
    pub fn move_thing(
        &mut self,
        x: Idx,
        holder: Idx,
        inside: bool,
        near: &[Idx],
    ) -> Result<(), PhysicsError> {
        let Some(xb) = self.body[x.get()] else {
            return fail(
                FailureKind::Layout,
                format!("{} has no body", self.label(x)),
            );
        };
        if self.task.node(x).kind == NodeKind::Tool {
            return fail(
                FailureKind::Blocked,
                format!("{} goes where its quadrotor goes", self.label(x)),
            );
        }
        let moving = self.riders(x, xb);
        self.let_go(x, &moving)?;
        let spots = self.spot_grid(x, holder, inside)?;
        let shoulders: Vec<Vector> = near
            .iter()
            .filter_map(|&d| self.arm_index(d))
            .map(|ai| self.shoulder(&self.arms[ai]))
            .collect();
        let middle = spots.iter().fold(Vector::ZERO, |a, &p| a + p) / spots.len().max(1) as f32;
        let lift = Vector::new(0.0, self.item_size(x)[1] / 2.0, 0.0);
        let cost = |p: Vector| -> f32 {
            if shoulders.is_empty() {
                (p - middle).length()
            } else {
                shoulders
                    .iter()
                    .map(|&s| (p + lift - s).length())
                    .fold(0.0, f32::max)
            }
        };
        let mut best: Option<(f32, Vector)> = None;
        let mut in_the_way = None;
        for p in spots {
            if let Some(owner) = self.spot_blocker(x, p, holder, inside, &moving) {
                in_the_way = Some(owner);
                continue;
            }
            let c = cost(p);
            if best.is_none_or(|(c0, _)| c < c0) {
                best = Some((c, p));
            }
        }
        let Some((_, spot)) = best else {
            return fail(
                FailureKind::Blocked,
                format!(
                    "no free spot for {} {} {}{}",
                    self.label(x),
                    if inside { "in" } else { "on" },
                    self.label(holder),
                    match in_the_way {
                        Some(Some(n)) => format!(" ({} is in the way)", self.label(n)),
                        Some(None) => " (a robot is in the way)".to_owned(),
                        None => String::new(),
                    }
                ),
            );
        };
        let Some(aabb) = self.node_aabb(x) else {
            return fail(
                FailureKind::Layout,
                format!("{} has no collider", self.label(x)),
            );
        };
        let bottom = Vector::new(aabb.center().x, aabb.mins.y, aabb.center().z);
        let shift = spot + Vector::new(0.0, self.tol.put_drop, 0.0) - bottom;
        for b in moving {
            let rb = &mut self.pw.bodies[b];
            let mut pose = *rb.position();
            pose.translation += shift;
            rb.set_position(pose, true);
            rb.set_linvel(Vector::ZERO, true);
            rb.set_angvel(Vector::ZERO, true);
        }
        self.settle(self.tol.release_settle);
        Ok(())
    }

    /// `x` out of the hand that holds it, and the bodies `moving` (what rests on it) out
    /// of any grasp they ride in: colliding again.
    fn let_go(&mut self, x: Idx, moving: &[RigidBodyHandle]) -> Result<(), PhysicsError> {
        if let Some(g) = self.grasps.iter().find(|g| g.object == x) {
            let robot = g.robot;
            return self.unfasten(robot, x);
        }
        for gi in 0..self.grasps.len() {
            let mut k = 0;
            while k < self.grasps[gi].carried.len() {
                let b = self.grasps[gi].carried[k];
                if !moving.contains(&b) {
                    k += 1;
                    continue;
                }
                let joint = self.grasps[gi].joints.remove(k);
                self.grasps[gi].carried.remove(k);
                self.pw.impulse_joints.remove(joint, true);
                self.set_body_groups(b, groups(G_OBJECT));
            }
        }
        Ok(())
    }
}
