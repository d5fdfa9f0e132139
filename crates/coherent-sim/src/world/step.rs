//! One simulation step and what runs in it: the quadrotor's flight controller (a
//! position PID and an attitude loop mixed into four rotor thrusts, with the basket's
//! load fed forward) and the arms' kinematic chains following their roots; settling
//! until loose things rest.

use coherent_core::NodeId;
use rapier3d::prelude::*;

use super::World;
use super::motion::{Settle, Tick};

impl World {
    pub(super) fn step(&mut self) {
        for i in 0..self.quads.len() {
            self.control_quad(i);
        }
        // A multibody writes its root link's pose into the root body during the step, so
        // the root link is put where a kinematic root (the walking dog) is going first;
        // otherwise the root's kinematic target is overwritten and it never moves.
        for i in 0..self.arms.len() {
            let (j, r) = (self.arms[i].joints[0], self.arms[i].root);
            let rb = &self.pw.bodies[r];
            let next = if rb.is_kinematic() {
                *rb.next_position()
            } else {
                *rb.position()
            };
            self.sync_arm_to(j, next);
        }
        self.pw.step();
        // Kinematic arm joints follow their root (the moving dog) after each step.
        for i in 0..self.arms.len() {
            let (j, r) = (self.arms[i].joints[0], self.arms[i].root);
            self.sync_arm(j, r);
        }
        self.sim_time += f64::from(self.tol.dt);
    }

    /// Steps until loose things rest (or `max_s` simulated seconds).
    pub(super) fn settle(&mut self, max_s: f32) {
        let mut s = Settle::new(max_s, self.tol.dt);
        while let Tick::Step = self.settle_tick(&mut s) {
            self.step();
            self.settle_after(&mut s);
        }
    }

    pub(super) fn settle_tick(&mut self, s: &mut Settle) -> Tick {
        if s.resting || s.taken >= s.steps {
            Tick::Done
        } else {
            Tick::Step
        }
    }

    /// Loose things count as resting only after the first `settle_min_steps` steps.
    pub(super) fn settle_after(&mut self, s: &mut Settle) {
        if s.taken >= self.tol.settle_min_steps && self.resting() {
            s.resting = true;
        }
        s.taken += 1;
    }

    fn resting(&self) -> bool {
        self.layout.items.iter().filter(|it| it.dynamic).all(|it| {
            self.task
                .idx(NodeId(it.id))
                .and_then(|n| self.body[n.get()])
                .is_none_or(|b| {
                    let rb = &self.pw.bodies[b];
                    rb.linvel().length() < self.tol.rest_speed
                        && rb.angvel().length() < self.tol.rest_spin
                })
        })
    }

    /// The controller of the quadrotor `quads[i]`.
    fn control_quad(&mut self, i: usize) {
        let q = self.quads[i].clone();
        let target = q.target;
        let (payload, load_at) = if q.motors_on {
            self.basket_load(&q)
        } else {
            (0.0, Vector::ZERO)
        };
        let t = self.tol;
        let rb = &mut self.pw.bodies[q.body];
        rb.reset_forces(false);
        rb.reset_torques(false);
        if !q.motors_on {
            return;
        }
        let craft = rb.mass();
        // Feed-forward: what rides in the basket weighs on it too.
        let m = craft + payload;
        let p = rb.center_of_mass();
        let v = rb.linvel();
        let w = rb.angvel();
        let rot = *rb.rotation();
        // Position loop (PID): desired acceleration, tilt limited.
        let (tp, tv) = target;
        // Horizontally only while hovering: it would wind up on the tracking lag of a
        // long flight and overshoot at the end of it.
        let err = tp - p;
        let err = if tv.length() < t.quad_hover_setpoint_speed {
            err
        } else {
            Vector::new(0.0, err.y, 0.0)
        };
        let mut integral = q.integral + err * t.dt;
        if integral.length() > t.quad_integral_limit {
            integral = integral.normalize() * t.quad_integral_limit;
        }
        self.quads[i].integral = integral;
        let rb = &mut self.pw.bodies[q.body];
        let mut acc = (tp - p) * t.quad_kp + (tv - v) * t.quad_kd + integral * t.quad_ki;
        let horiz = Vector::new(acc.x, 0.0, acc.z);
        let limit = t.quad_max_horizontal_accel;
        if horiz.length() > limit {
            let s = limit / horiz.length();
            acc.x *= s;
            acc.z *= s;
        }
        acc.y = acc
            .y
            .clamp(-t.quad_max_vertical_accel, t.quad_max_vertical_accel);
        let f = (acc + Vector::new(0.0, t.gravity, 0.0)) * m;
        let up = rot * Vector::Y;
        let thrust = f.dot(up).max(0.0);
        // Attitude loop: align body up with the force direction, hold yaw at zero.
        let want_up = f.normalize_or(Vector::Y);
        let err_tilt = up.cross(want_up);
        let fwd = rot * Vector::Z;
        let err_yaw = Vector::new(0.0, -fwd.x.atan2(fwd.z), 0.0);
        // Feed-forward: cancel the load's weight torque about the centre of mass.
        let load_torque = if payload > 0.0 {
            (load_at - p).cross(Vector::new(0.0, -t.gravity * payload, 0.0))
        } else {
            Vector::ZERO
        };
        let torque_world = (err_tilt * t.quad_tilt_gain + err_yaw * t.quad_yaw_gain
            - w * t.quad_rate_gain)
            * t.quad_inertia
            - load_torque;
        let torque = rot.inverse() * torque_world;
        // Mixer: four rotor thrusts along body up give the thrust and the roll/pitch
        // torques; yaw comes from rotor drag, applied as a torque.
        let l = q.rotors[0].x.abs();
        let n = q.rotors.len() as f32;
        let mut fr = [0.0f32; 4];
        for (i, r) in q.rotors.iter().enumerate() {
            // A force f along +y at (x, y, z) gives the torque (-z f, 0, x f).
            fr[i] =
                thrust / n - torque.x * r.z.signum() / (n * l) + torque.z * r.x.signum() / (n * l);
            // A rotor lifts at most the craft's weight.
            fr[i] = fr[i].clamp(0.0, craft * t.gravity);
        }
        let pose = *rb.position();
        for (i, r) in q.rotors.iter().enumerate() {
            let at = pose.transform_point(*r);
            rb.add_force_at_point(up * fr[i], at, true);
        }
        rb.add_torque(rot * Vector::new(0.0, torque.y, 0.0), true);
    }

    /// Mass of the loose things resting in the quadrotor's basket (their centres within
    /// the basket's footprint, from `basket_load_below` under its inner floor up to
    /// `basket_load_height` above its middle).
    /// Returns the mass and its centre.
    fn basket_load(&self, q: &super::Quad) -> (f32, Vector) {
        let none = (0.0, Vector::ZERO);
        let Some(v) = self
            .task
            .basket_of(q.robot)
            .and_then(|b| self.volume[b.get()])
        else {
            return none;
        };
        let mut moment = Vector::ZERO;
        let frame = *self.pw.bodies[v.body].position() * v.local;
        let mut load = 0.0;
        for it in self.layout.items.iter().filter(|it| it.dynamic) {
            let Some(b) = self
                .task
                .idx(NodeId(it.id))
                .and_then(|n| self.body[n.get()])
            else {
                continue;
            };
            if b == q.body {
                continue;
            }
            let rb = &self.pw.bodies[b];
            let l = frame.inverse_transform_point(rb.translation());
            if l.x.abs() <= v.half.x
                && l.z.abs() <= v.half.z
                && l.y >= -v.half.y - self.tol.basket_load_below
                && l.y <= self.tol.basket_load_height
            {
                load += rb.mass();
                moment += rb.center_of_mass() * rb.mass();
            }
        }
        if load > 0.0 {
            (load, moment / load)
        } else {
            none
        }
    }

    /// Puts an arm's chain where its root body is now: Rapier reads a non-dynamic root's
    /// pose only when the root's type changes, so the pose is copied in here.
    pub(super) fn sync_arm(&mut self, joint: MultibodyJointHandle, root: RigidBodyHandle) {
        let root_pose = *self.pw.bodies[root].position();
        self.sync_arm_to(joint, root_pose);
    }

    /// Puts an arm's chain on a root at `root_pose`.
    fn sync_arm_to(&mut self, joint: MultibodyJointHandle, root_pose: Pose) {
        if let Some((mb, _)) = self.pw.multibody_joints.get_mut(joint) {
            // `true`: on the first call the root turns from dynamic to fixed and takes
            // the body's pose rather than the identity.
            mb.forward_kinematics(&self.pw.bodies, true);
            mb.root_mut().joint.data.local_frame1 = root_pose;
            mb.forward_kinematics(&self.pw.bodies, false);
            mb.update_rigid_bodies(&mut self.pw.bodies, false);
        }
    }
}
