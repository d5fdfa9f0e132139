//! Robots moving at once must keep apart: after every simulation step of a joint step,
//! what each moving robot brings (its body, and the thing its action handles: the
//! object it grabs, the door or lid it turns) must not touch what another moving robot
//! brings. Only what the simulation makes solid counts: the arms' links and held things
//! collide with nothing in it (the arms have no motion planning around obstacles), and a
//! sequential step has always let an arm pass through a quadrotor landed beside it, so a
//! joint step does too. Where the simulation has a contact of its own between the two
//! (the quadrotor against the walking dog), its impulse is reported with where and how
//! deep. The robots of the step are watched until the step is over, also once their own
//! action is over or while they wait for their way to clear; robots that are not in the
//! step stand still, as between sequential steps, and are not watched.
//!
//! Before that comes to pass, robots give way by their order in the step: a moving one
//! that comes within the clearance ([`Tolerances::contact_clearance`]) of a robot earlier
//! in the step that is moving too holds where it is (see `World::hold`) until that one
//! has moved away or its action is over. The first robot never holds, so robots never
//! wait on each other in a circle; a robot that runs into one holding still fails the
//! step.
//!
//! [`Tolerances::contact_clearance`]: super::Tolerances::contact_clearance

use coherent_core::{Action, Idx, Verb};
use rapier3d::parry::query;
use rapier3d::prelude::*;

use super::{FailureKind, PhysicsError, World, fail};

/// What one moving robot brings into the step now: each solid collider with its
/// bounding box, and the box around them all.
pub(super) struct Brought {
    robot: Idx,
    action: Action,
    parts: Vec<(ColliderHandle, Aabb)>,
    aabb: Option<Aabb>,
}

impl World {
    /// What the robot of `m` brings into the step now.
    pub(super) fn brought(&self, robot: Idx, action: Action) -> Brought {
        let mut bodies: Vec<RigidBodyHandle> = self.body[robot.get()].into_iter().collect();
        let x = action.object;
        match action.verb {
            Verb::Grab => bodies.extend(self.body[x.get()]),
            Verb::Open | Verb::Close => {
                bodies.extend(self.hinges.iter().filter(|h| h.node == x).map(|h| h.body));
            }
            _ => {}
        }
        // Solid: a grabbed thing once held, a fixed arm's base and the arms' links are not.
        let parts: Vec<(ColliderHandle, Aabb)> = bodies
            .iter()
            .flat_map(|&b| self.pw.bodies[b].colliders().iter().copied())
            .filter(|&c| self.pw.colliders[c].collision_groups().memberships != Group::NONE)
            .map(|c| (c, self.pw.colliders[c].compute_aabb()))
            .collect();
        let aabb = parts.iter().map(|(_, a)| *a).reduce(|a, b| a.merged(&b));
        Brought {
            robot,
            action,
            parts,
            aabb,
        }
    }

    /// Whether what `a` and `b` bring are within the clearance of each other.
    pub(super) fn near(&self, a: &Brought, b: &Brought) -> bool {
        let clearance = self.tol.contact_clearance;
        let close = |x: &Aabb, y: &Aabb| x.loosened(clearance).intersects(y);
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
                            .is_ok_and(|d| d.distance <= clearance)
                })
            })
    }

    /// What collider `c`, brought by `robot`, belongs to, for a message.
    fn part_name(&self, robot: Idx, c: ColliderHandle) -> String {
        self.label(self.owner.get(&c).copied().unwrap_or(robot))
    }

    /// No two of the step's robots touch (see the file's note); `t0` is when the joint
    /// step started.
    pub(super) fn check_contacts(&self, step: &[Brought], t0: f64) -> Result<(), PhysicsError> {
        for (i, a) in step.iter().enumerate() {
            for b in &step[i + 1..] {
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
                            return fail(
                                FailureKind::Collision,
                                format!(
                                    "{} {} and {} {} collided {:.2} s into the joint step ({:.2} s simulated): {} touched {} {touch}",
                                    self.label(a.robot),
                                    a.action.render(&self.task),
                                    self.label(b.robot),
                                    b.action.render(&self.task),
                                    self.sim_time - t0,
                                    self.sim_time,
                                    self.part_name(a.robot, *x),
                                    self.part_name(b.robot, *y),
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
