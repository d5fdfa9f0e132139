//! The arms (the fixed arm's, the legged robot's): joint angles set within their
//! limits, inverse kinematics with the numbers when a target is out of reach, and
//! motion at a bounded joint speed.

use std::f32::consts::PI;

use coherent_core::{Idx, RobotKind};
use rapier3d::na::DVector;
use rapier3d::prelude::*;

use super::motion::{ArmMove, Stage, Tick};
use super::{Arm, FailureKind, PhysicsError, World, fail};

/// The joint angles (yaw, shoulder, elbow) an arm rests at, folded up.
pub(super) const ARM_HOME: [f32; 3] = [0.0, -1.3, 2.4];

/// `a` brought into `[-pi, pi]`.
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

impl World {
    /// Sets an arm's joints (the wrist keeps the hand level) and updates its links.
    pub(super) fn set_arm(&mut self, arm: &mut Arm, q: [f32; 3]) {
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

    pub(super) fn arm_index(&self, robot: Idx) -> Option<usize> {
        self.arms.iter().position(|a| a.robot == robot)
    }

    /// World position of an arm's shoulder.
    pub(super) fn shoulder(&self, arm: &Arm) -> Vector {
        self.pw.bodies[arm.root]
            .position()
            .transform_point(arm.shoulder_local)
    }

    pub(super) fn hand_pos(&self, arm: &Arm) -> Vector {
        self.pw.bodies[arm.hand].translation()
    }

    /// Joint angles that put the hand at `target`, within the limits; error with the
    /// numbers when the clamped solution misses by more than `ik_miss`.
    fn solve_ik(&self, arm: &Arm, target: Vector, what: &str) -> Result<[f32; 3], PhysicsError> {
        let shoulder = self.shoulder(arm);
        let dist = (target - shoulder).length();
        let me = self.label(arm.robot);
        let Some((mb, _)) = self.pw.multibody_joints.get(arm.joints[0]) else {
            return fail(FailureKind::Layout, format!("{me} has no arm"));
        };
        let fore_link = 3;
        let t = &self.tol;
        let options = InverseKinematicsOption {
            damping: t.ik_damping,
            max_iters: t.ik_max_iters,
            constrained_axes: JointAxesMask::LIN_AXES,
            epsilon_linear: t.ik_epsilon_linear,
            epsilon_angular: t.ik_epsilon_angular,
        };
        let pose = Pose::from_translation(target);
        // The yaw towards the target as a seed avoids the solver's local minima.
        let local = self.pw.bodies[arm.root]
            .position()
            .inverse_transform_point(target)
            - arm.shoulder_local;
        let yaw = local.x.atan2(local.z);
        let mut best: Option<([f32; 3], f32)> = None;
        let [[s1, e1], [s2, e2]] = t.ik_seeds;
        for seed in [[yaw, s1, e1], [yaw, s2, e2], [arm.q[0], arm.q[1], arm.q[2]]] {
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
        if residual > t.ik_miss {
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

    /// The next step of an arm's move: every joint at most `arm_joint_speed`, in at least
    /// `arm_min_steps`.
    pub(super) fn arm_tick(&mut self, m: &mut ArmMove) -> Tick {
        let (ai, q) = (m.arm, m.to);
        let t = self.tol;
        let (from, dq, steps) = *m.plan.get_or_insert_with(|| {
            let a = &self.arms[ai];
            let from = [a.q[0], a.q[1], a.q[2]];
            let mut dq = [0.0; 3];
            for k in 0..3 {
                dq[k] = q[k] - from[k];
                if k == 0 {
                    dq[k] = wrap(dq[k]);
                }
            }
            let biggest = dq.iter().fold(0.0f32, |m, d| m.max(d.abs()));
            let steps = ((biggest / t.arm_joint_speed / t.dt).ceil() as usize).max(t.arm_min_steps);
            (from, dq, steps)
        });
        if m.taken >= steps {
            return Tick::Done;
        }
        m.taken += 1;
        let f = m.taken as f32 / steps as f32;
        let qs = [
            from[0] + dq[0] * f,
            from[1] + dq[1] * f,
            from[2] + dq[2] * f,
        ];
        let mut arm = self.arms[ai].clone();
        self.set_arm(&mut arm, qs);
        self.arms[ai] = arm;
        Tick::Step
    }

    /// Moving the hand of `robot` to `target`: the joint angles that put it there now,
    /// then the move, then the hand must be within `hand_tolerance` of it. An error says
    /// why it cannot.
    pub(super) fn reach(
        &self,
        robot: Idx,
        target: Vector,
        what: &str,
    ) -> Result<Vec<Stage>, PhysicsError> {
        let Some(ai) = self.arm_index(robot) else {
            return fail(
                FailureKind::Reach,
                format!("{} has no arm", self.label(robot)),
            );
        };
        let arm = &self.arms[ai];
        if self.task.robot(robot).map(|r| r.kind) == Some(RobotKind::RobotDog) {
            // Relative to the floor the robot stands on (its body walks above it).
            let stand = self.pw.bodies[arm.root].translation().y - self.tol.dog_floor_gap;
            let top = stand + self.layout.specs.dog_max_height();
            let shoulder = self.shoulder(arm);
            let top_here = shoulder.y + arm.reach;
            if target.y > top_here.max(top) + self.tol.dog_height_margin {
                return fail(
                    FailureKind::Reach,
                    format!(
                        "{what} at {:.2} m is above the legged robot's reach of {:.2} m (shoulder at {:.2} m + arm {:.2} m)",
                        target.y, top_here, shoulder.y, arm.reach
                    ),
                );
            }
        }
        let q = self.solve_ik(arm, target, what)?;
        Ok(vec![
            ArmMove::stage(ai, q),
            Stage::HandAt {
                robot,
                target,
                what: what.to_owned(),
            },
        ])
    }

    /// The hand of `robot` is within `hand_tolerance` of `target`.
    pub(super) fn check_hand_at(
        &self,
        robot: Idx,
        target: Vector,
        what: &str,
    ) -> Result<(), PhysicsError> {
        let Some(ai) = self.arm_index(robot) else {
            return Ok(());
        };
        let miss = (self.hand_pos(&self.arms[ai]) - target).length();
        if miss > self.tol.hand_tolerance {
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

    /// Folding the arm of `robot` back to its rest angles.
    pub(super) fn arm_home(&self, robot: Idx) -> Option<Stage> {
        self.arm_index(robot).map(|ai| ArmMove::stage(ai, ARM_HOME))
    }
}
