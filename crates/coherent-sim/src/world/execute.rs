//! One action physically: the robot's kind and the verb pick the motion.

use coherent_core::{Action, Idx, NodeKind, RobotKind, Verb};
use rapier3d::prelude::*;

use super::{FailureKind, PhysicsError, World, fail};

impl World {
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
}
