//! Robots moving at once must keep apart: after every simulation step of a joint step,
//! what each moving robot brings (its body, its arm's links, what its hand holds, and
//! the thing its action handles: the object it grabs, the door or lid it turns) must
//! not touch what another moving robot brings. The arms' links and held things collide
//! with nothing in the simulation (the arms have no motion planning around obstacles),
//! so the test is geometric; where the simulation has a contact of its own between
//! the two (a walking robot's body against the quadrotor), its impulse is reported too.
//! A robot that is not moving (not in the step, its action over, or waiting for its way
//! to clear) stands still, as between sequential steps, and is not watched.

use coherent_core::{Idx, Verb};
use rapier3d::parry::query;
use rapier3d::prelude::*;

use super::motion::Motion;
use super::{FailureKind, PhysicsError, World, fail};

impl World {
    /// The colliders of what the robot of `m` brings into the step now.
    fn parts(&self, m: &Motion) -> Vec<ColliderHandle> {
        let r = m.robot;
        let mut bodies: Vec<RigidBodyHandle> = self.body[r.get()].into_iter().collect();
        for a in self.arms.iter().filter(|a| a.robot == r) {
            bodies.extend(a.links);
        }
        for g in self.grasps.iter().filter(|g| g.robot == r) {
            bodies.extend(&g.carried);
        }
        let x = m.action.object;
        match m.action.verb {
            Verb::Grab => bodies.extend(self.body[x.get()]),
            Verb::Open | Verb::Close => {
                bodies.extend(self.hinges.iter().filter(|h| h.node == x).map(|h| h.body));
            }
            _ => {}
        }
        // A grabbed thing is handled and, once held, carried: count it once.
        let mut unique: Vec<RigidBodyHandle> = Vec::new();
        for b in bodies {
            if !unique.contains(&b) {
                unique.push(b);
            }
        }
        unique
            .iter()
            .flat_map(|&b| self.pw.bodies[b].colliders().iter().copied())
            .collect()
    }

    /// What collider `c`, brought by `robot`, is, for a message.
    fn part_name(&self, robot: Idx, c: ColliderHandle) -> String {
        match self.owner.get(&c) {
            Some(&n) => self.label(n),
            None => format!("the arm of {}", self.label(robot)),
        }
    }

    /// No two of `motions`' robots touch (see the file's note); `t0` is when the joint
    /// step started.
    pub(super) fn check_contacts(&self, motions: &[&Motion], t0: f64) -> Result<(), PhysicsError> {
        let parts: Vec<Vec<ColliderHandle>> = motions.iter().map(|m| self.parts(m)).collect();
        for i in 0..motions.len() {
            for j in i + 1..motions.len() {
                for &a in &parts[i] {
                    for &b in &parts[j] {
                        if a == b {
                            continue;
                        }
                        if let Some(touch) = self.touch(a, b) {
                            let (mi, mj) = (motions[i], motions[j]);
                            return fail(
                                FailureKind::Collision,
                                format!(
                                    "{} {} and {} {} collided {:.2} s into the joint step ({:.2} s simulated): {} touched {} {touch}",
                                    self.label(mi.robot),
                                    mi.action.render(&self.task),
                                    self.label(mj.robot),
                                    mj.action.render(&self.task),
                                    self.sim_time - t0,
                                    self.sim_time,
                                    self.part_name(mi.robot, a),
                                    self.part_name(mj.robot, b),
                                ),
                            );
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Where and how deep colliders `a` and `b` touch (with the simulation's contact
    /// impulse between them, when it has one), or `None`.
    fn touch(&self, a: ColliderHandle, b: ColliderHandle) -> Option<String> {
        let (ca, cb) = (&self.pw.colliders[a], &self.pw.colliders[b]);
        if !ca.compute_aabb().intersects(&cb.compute_aabb()) {
            return None;
        }
        let pair = self
            .pw
            .narrow_phase
            .contact_pair(a, b)
            .filter(|p| p.has_any_active_contact());
        let contact = query::contact(ca.position(), ca.shape(), cb.position(), cb.shape(), 0.0)
            .ok()
            .flatten()
            .filter(|c| c.dist <= 0.0);
        if pair.is_none() && contact.is_none() {
            return None;
        }
        let (at, depth) =
            contact.map_or_else(|| (ca.position().translation, 0.0), |c| (c.point1, -c.dist));
        let impulse = pair.map_or(String::new(), |p| {
            format!(", contact impulse {:.3} N s", p.total_impulse_magnitude())
        });
        Some(format!(
            "at ({:.2}, {:.2}, {:.2}) m, {depth:.3} m deep{impulse}",
            at.x, at.y, at.z
        ))
    }
}
