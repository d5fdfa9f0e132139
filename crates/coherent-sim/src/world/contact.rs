//! Robots moving at once must keep apart: after every simulation step of a joint step,
//! what each moving robot brings (its body, its arm's links, what its hand holds, and
//! the thing its action handles: the object it grabs, the door or lid it turns) must
//! not touch what another moving robot brings. The arms' links and held things collide
//! with nothing in the simulation (the arms have no motion planning around obstacles),
//! so the test is geometric; where the simulation has a contact of its own between
//! the two (a walking robot's body against the quadrotor), its impulse is reported too.
//! A robot that is not moving (not in the step, its action over, or waiting for its way
//! to clear) stands still, as between sequential steps, and is not watched.
//!
//! Before that comes to pass, robots give way by their order in the step: one that comes
//! within [`CLEARANCE`] of a robot earlier in the step holds where it is (see
//! `World::hold`) until that one has moved away or its action is over. The first robot
//! never holds, so robots never wait on each other in a circle; a robot that runs into
//! one holding still fails the step.

use coherent_core::{Idx, Verb};
use rapier3d::parry::query;
use rapier3d::prelude::*;

use super::motion::Motion;
use super::{FailureKind, PhysicsError, World, fail};

/// How close (m) what a robot brings may come to what a robot earlier in the step brings
/// before it holds.
pub(super) const CLEARANCE: f32 = 0.1;

/// What one moving robot brings into the step now: each collider with its bounding
/// box, and the box around them all.
pub(super) struct Brought<'m> {
    motion: &'m Motion,
    parts: Vec<(ColliderHandle, Aabb)>,
    aabb: Option<Aabb>,
}

impl World {
    /// What the robot of `m` brings into the step now.
    pub(super) fn brought<'m>(&self, m: &'m Motion) -> Brought<'m> {
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
        let parts: Vec<(ColliderHandle, Aabb)> = unique
            .iter()
            .flat_map(|&b| self.pw.bodies[b].colliders().iter().copied())
            .map(|c| (c, self.pw.colliders[c].compute_aabb()))
            .collect();
        let aabb = parts.iter().map(|(_, a)| *a).reduce(|a, b| a.merged(&b));
        Brought {
            motion: m,
            parts,
            aabb,
        }
    }

    /// Whether what `a` and `b` bring are within [`CLEARANCE`] of each other.
    pub(super) fn near(&self, a: &Brought<'_>, b: &Brought<'_>) -> bool {
        let close = |x: &Aabb, y: &Aabb| x.loosened(CLEARANCE).intersects(y);
        let (Some(ba), Some(bb)) = (&a.aabb, &b.aabb) else {
            return false;
        };
        close(ba, bb)
            && a.parts.iter().any(|(x, xa)| {
                b.parts.iter().any(|(y, ya)| {
                    let (cx, cy) = (&self.pw.colliders[*x], &self.pw.colliders[*y]);
                    x != y
                        && close(xa, ya)
                        && query::distance(cx.position(), cx.shape(), cy.position(), cy.shape())
                            .is_ok_and(|d| d.distance <= CLEARANCE)
                })
            })
    }

    /// What collider `c`, brought by `robot`, is, for a message.
    fn part_name(&self, robot: Idx, c: ColliderHandle) -> String {
        match self.owner.get(&c) {
            Some(&n) => self.label(n),
            None => format!("the arm of {}", self.label(robot)),
        }
    }

    /// No two of the moving robots touch (see the file's note); `t0` is when the joint
    /// step started.
    pub(super) fn check_contacts(
        &self,
        moving: &[Brought<'_>],
        t0: f64,
    ) -> Result<(), PhysicsError> {
        for (i, a) in moving.iter().enumerate() {
            for b in &moving[i + 1..] {
                let (Some(ba), Some(bb)) = (&a.aabb, &b.aabb) else {
                    continue;
                };
                if !ba.intersects(bb) {
                    continue;
                }
                for (x, xa) in &a.parts {
                    for (y, ya) in &b.parts {
                        if x == y || !xa.intersects(ya) {
                            continue;
                        }
                        if let Some(touch) = self.touch(*x, *y) {
                            let (ma, mb) = (a.motion, b.motion);
                            return fail(
                                FailureKind::Collision,
                                format!(
                                    "{} {} and {} {} collided {:.2} s into the joint step ({:.2} s simulated): {} touched {} {touch}",
                                    self.label(ma.robot),
                                    ma.action.render(&self.task),
                                    self.label(mb.robot),
                                    mb.action.render(&self.task),
                                    self.sim_time - t0,
                                    self.sim_time,
                                    self.part_name(ma.robot, *x),
                                    self.part_name(mb.robot, *y),
                                ),
                            );
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Where and how deep colliders `a` and `b` (whose boxes meet) touch, with the
    /// simulation's contact impulse between them when it has one, or `None`.
    fn touch(&self, a: ColliderHandle, b: ColliderHandle) -> Option<String> {
        let (ca, cb) = (&self.pw.colliders[a], &self.pw.colliders[b]);
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
