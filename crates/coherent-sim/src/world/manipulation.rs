//! What the arms do to things: grasping (what rides on the thing comes along), putting
//! down on a free spot within reach, and opening and closing doors and lids by their
//! handles.

use std::f32::consts::FRAC_PI_2;

use coherent_core::{Idx, NodeKind};
use rapier3d::prelude::*;

use super::motion::{HingeTurn, Settle, Stage, Tick};
use super::{
    FailureKind, G_OBJECT, Grasp, PhysicsError, Placement, World, fail, groups, hinge_pose, solid,
};

/// The size (m) taken for a thing the layout does not size: a small thing's.
const UNKNOWN_SIZE: [f32; 3] = [0.12; 3];

impl World {
    /// The size the layout gives `h` (a small thing's when it gives none).
    pub(super) fn item_size(&self, h: Idx) -> [f32; 3] {
        self.layout
            .item(self.task.id(h))
            .map(|it| it.size)
            .unwrap_or(UNKNOWN_SIZE)
    }

    /// The spots where `h` could rest on surface `holder` (in container `holder`,
    /// `inside`), as bottom centres in world coordinates on a grid over the top or the
    /// inside, in the order they are tried; an error when `h` does not fit at all.
    pub(super) fn spot_grid(
        &self,
        h: Idx,
        holder: Idx,
        inside: bool,
    ) -> Result<Vec<Vector>, PhysicsError> {
        let size = self.item_size(h);
        let (body, centre, half) = if inside {
            let Some(v) = self.volume[holder.get()] else {
                return fail(
                    FailureKind::Blocked,
                    format!("{} has no inside", self.label(holder)),
                );
            };
            let bottom = v.local.translation - Vector::new(0.0, v.half.y, 0.0);
            (v.body, bottom, [v.half.x, v.half.z])
        } else {
            let Some(t) = self.top[holder.get()] else {
                return fail(
                    FailureKind::Blocked,
                    format!("{} has no top", self.label(holder)),
                );
            };
            t
        };
        let t = &self.tol;
        let hx = half[0] - size[0] / 2.0 - t.put_edge_margin;
        let hz = half[1] - size[2] / 2.0 - t.put_edge_margin;
        if hx < -t.put_fit_tolerance || hz < -t.put_fit_tolerance {
            return fail(
                FailureKind::Blocked,
                format!(
                    "{} ({:.2} m wide) does not fit {} {}",
                    self.label(h),
                    size[0],
                    if inside { "in" } else { "on" },
                    self.label(holder)
                ),
            );
        }
        let pose = *self.pw.bodies[body].position();
        let step = t.put_grid;
        let (nx, nz) = (
            (hx.max(0.0) / step).floor() as i32,
            (hz.max(0.0) / step).floor() as i32,
        );
        let mut spots = Vec::new();
        for i in -nx..=nx {
            for k in -nz..=nz {
                let local = centre + Vector::new(i as f32 * step, t.put_lift, k as f32 * step);
                spots.push(pose.transform_point(local));
            }
        }
        Ok(spots)
    }

    /// What fills spot `p` (a bottom centre from [`World::spot_grid`]) for `h` on or in
    /// `holder`, leaving out the bodies `moving` (they go with `h`): `None` when it is
    /// free, else the named thing in the way (`Some(None)`: an unnamed body, a robot).
    pub(super) fn spot_blocker(
        &self,
        h: Idx,
        p: Vector,
        holder: Idx,
        inside: bool,
        moving: &[RigidBodyHandle],
    ) -> Option<Option<Idx>> {
        let size = self.item_size(h);
        let t = &self.tol;
        let shape = Cuboid::new(Vector::new(
            size[0] / 2.0 - t.put_probe_shrink,
            size[1] / 2.0 - t.put_probe_shrink,
            size[2] / 2.0 - t.put_probe_shrink,
        ));
        let lift = size[1] / 2.0 + t.put_probe_lift;
        let probe = Pose::from_translation(p + Vector::new(0.0, lift, 0.0));
        let not_moving =
            |_: ColliderHandle, c: &Collider| c.parent().is_none_or(|b| !moving.contains(&b));
        let filter = solid().predicate(&not_moving);
        let qp = self.pw.query_pipeline_with_filter(filter);
        qp.intersect_shape(probe, &shape).find_map(|(ch, col)| {
            let owner = self.owner.get(&ch).copied();
            (col.collision_groups().memberships != Group::NONE
                && (inside || owner != Some(holder))
                && self.task.node(owner.unwrap_or(holder)).kind != NodeKind::Door)
                .then_some(owner)
        })
    }

    /// A free spot for `h` on surface `holder` or in container `holder`, nearest to the
    /// robot's shoulder and within its reach; returns the bottom centre for `h`.
    fn put_spot(
        &self,
        robot: Idx,
        h: Idx,
        holder: Idx,
        inside: bool,
    ) -> Result<Vector, PhysicsError> {
        let spots = self.spot_grid(h, holder, inside)?;
        let Some(ai) = self.arm_index(robot) else {
            return fail(
                FailureKind::Reach,
                format!("{} has no arm", self.label(robot)),
            );
        };
        let t = &self.tol;
        let size = self.item_size(h);
        let shoulder = self.shoulder(&self.arms[ai]);
        let reach = self.arms[ai].reach;
        let min_reach = self.arms[ai].min_reach + t.put_min_reach_margin;
        let moving: Vec<RigidBodyHandle> = self.body[h.get()].into_iter().collect();
        let mut best: Option<(f32, Vector)> = None;
        let mut nearest_any = f32::INFINITY;
        // What filled the last spot tried within reach (None: an unnamed body).
        let mut in_the_way: Option<Option<Idx>> = None;
        for p in spots {
            let grip = p + Vector::new(0.0, size[1], 0.0);
            let d = (grip - shoulder).length();
            nearest_any = nearest_any.min(d);
            if d > reach - t.put_reach_margin || d < min_reach {
                continue;
            }
            if let Some(owner) = self.spot_blocker(h, p, holder, inside, &moving) {
                in_the_way = Some(owner);
                continue;
            }
            if best.is_none_or(|(d0, _)| d < d0) {
                best = Some((d, p));
            }
        }
        match best {
            Some((_, p)) => Ok(p),
            None if nearest_any > reach - t.put_reach_margin => fail(
                FailureKind::Reach,
                format!(
                    "every spot {} {} is beyond the reach of {}: the nearest is {:.2} m from its shoulder, its reach is {:.2} m",
                    if inside { "in" } else { "on" },
                    self.label(holder),
                    self.label(robot),
                    nearest_any,
                    reach
                ),
            ),
            None => fail(
                FailureKind::Blocked,
                format!(
                    "no free spot for {} {} {} within reach of {}{}",
                    self.label(h),
                    if inside { "in" } else { "on" },
                    self.label(holder),
                    self.label(robot),
                    match in_the_way {
                        Some(Some(n)) => format!(" ({} is in the way)", self.label(n)),
                        Some(None) => " (a robot is in the way)".to_owned(),
                        None => String::new(),
                    }
                ),
            ),
        }
    }

    /// Reaching the middle of the top of `x`, taking hold of it, folding back.
    pub(super) fn grasp(&self, robot: Idx, x: Idx) -> Result<Vec<Stage>, PhysicsError> {
        let Some(xb) = self.body[x.get()] else {
            return fail(
                FailureKind::Layout,
                format!("{} has no body", self.label(x)),
            );
        };
        let size = self.item_size(x);
        // The middle of its top as it lies now (it may have tipped over).
        let top = match self.node_aabb(x) {
            Some(a) => Vector::new(a.center().x, a.maxs.y, a.center().z),
            None => self.pw.bodies[xb]
                .position()
                .transform_point(Vector::new(0.0, size[1], 0.0)),
        };
        let above = Vector::new(0.0, self.tol.grasp_above, 0.0);
        let mut stages = self.reach(robot, top + above, &self.label(x))?;
        stages.push(Stage::Fasten { robot, object: x });
        stages.extend(self.arm_home(robot));
        Ok(stages)
    }

    /// The body `xb` of `x` and the bodies of the loose things that rest on or in it,
    /// and on or in those, ...: what goes where `x` goes.
    pub(super) fn riders(&self, x: Idx, xb: RigidBodyHandle) -> Vec<RigidBodyHandle> {
        let mut carried = vec![xb];
        let mut riders = vec![x];
        let mut i = 0;
        while i < riders.len() {
            let host = riders[i];
            for n in self.task.indices() {
                if riders.contains(&n) || self.body[n.get()].is_none() {
                    continue;
                }
                let dynamic = self
                    .layout
                    .item(self.task.id(n))
                    .is_some_and(|it| it.dynamic);
                if dynamic
                    && matches!(self.placement(n), Placement::On(s) | Placement::Inside(s) if s == host)
                {
                    riders.push(n);
                    if let Some(b) = self.body[n.get()] {
                        carried.push(b);
                    }
                }
            }
            i += 1;
        }
        carried
    }

    /// The hand of `robot` holds `x`: fixed joints to the hand hold it and what rides on
    /// or in it (fastened: no sloshing in transport), none of them colliding meanwhile.
    pub(super) fn fasten(&mut self, robot: Idx, x: Idx) {
        let (Some(ai), Some(xb)) = (self.arm_index(robot), self.body[x.get()]) else {
            return;
        };
        let hand = self.arms[ai].hand;
        let carried = self.riders(x, xb);
        let hand_pose = *self.pw.bodies[hand].position();
        let mut joints = Vec::new();
        for &b in &carried {
            let obj_pose = *self.pw.bodies[b].position();
            let frame2 = obj_pose.inverse() * hand_pose;
            let j = FixedJointBuilder::new()
                .local_frame1(Pose::IDENTITY)
                .local_frame2(frame2)
                .contacts_enabled(false);
            joints.push(self.pw.impulse_joints.insert(hand, b, j, true));
            self.set_body_groups(b, InteractionGroups::none());
        }
        self.grasps.push(Grasp {
            robot,
            object: x,
            joints,
            carried,
        });
    }

    pub(super) fn set_body_groups(&mut self, b: RigidBodyHandle, g: InteractionGroups) {
        let cs: Vec<ColliderHandle> = self.pw.bodies[b].colliders().to_vec();
        for c in cs {
            if let Some(col) = self.pw.colliders.get_mut(c) {
                col.set_collision_groups(g);
            }
        }
    }

    /// Putting `h` on `holder` (into it when `inside`): over a free spot within reach,
    /// letting go, a wait for it to rest, folding back, a wait again.
    pub(super) fn release(
        &self,
        robot: Idx,
        h: Idx,
        holder: Idx,
        inside: bool,
    ) -> Result<Vec<Stage>, PhysicsError> {
        if !self
            .grasps
            .iter()
            .any(|g| g.robot == robot && g.object == h)
        {
            return self.not_held(robot, h);
        }
        if inside {
            self.check_open(holder)?;
        }
        let spot = self.put_spot(robot, h, holder, inside)?;
        let size = self.item_size(h);
        let Some(ai) = self.arm_index(robot) else {
            return Ok(Vec::new());
        };
        // Hand target: where the middle of the object's underside is `put_drop` above the
        // spot (its lowest point, whichever way up it is held).
        let offset = match self.node_aabb(h) {
            Some(a) => {
                self.hand_pos(&self.arms[ai]) - Vector::new(a.center().x, a.mins.y, a.center().z)
            }
            None => Vector::new(0.0, size[1], 0.0),
        };
        let target = spot + Vector::new(0.0, self.tol.put_drop, 0.0) + offset;
        let what = format!(
            "the spot {} {}",
            if inside { "in" } else { "on" },
            self.label(holder)
        );
        let mut stages = self.reach(robot, target, &what)?;
        stages.push(Stage::Unfasten { robot, object: h });
        let dt = self.tol.dt;
        stages.push(Stage::Settle(Settle::new(self.tol.release_settle, dt)));
        stages.extend(self.arm_home(robot));
        stages.push(Stage::Settle(Settle::new(self.tol.home_settle, dt)));
        Ok(stages)
    }

    fn not_held<T>(&self, robot: Idx, h: Idx) -> Result<T, PhysicsError> {
        fail(
            FailureKind::Disagreement,
            format!("{} does not hold {}", self.label(robot), self.label(h)),
        )
    }

    /// The hand of `robot` lets go of `h`: its joints removed, what it carried at rest
    /// and colliding again.
    pub(super) fn unfasten(&mut self, robot: Idx, h: Idx) -> Result<(), PhysicsError> {
        let Some(gi) = self
            .grasps
            .iter()
            .position(|g| g.robot == robot && g.object == h)
        else {
            return self.not_held(robot, h);
        };
        let g = self.grasps.remove(gi);
        for j in g.joints {
            self.pw.impulse_joints.remove(j, true);
        }
        for b in g.carried {
            self.set_body_groups(b, groups(G_OBJECT));
            let rb = &mut self.pw.bodies[b];
            rb.set_linvel(Vector::ZERO, true);
            rb.set_angvel(Vector::ZERO, true);
        }
        Ok(())
    }

    fn check_open(&self, c: Idx) -> Result<(), PhysicsError> {
        if let Some(angle) = self.hinge_angle(c)
            && angle.abs() < self.tol.lid_open_min
        {
            return fail(
                FailureKind::Blocked,
                format!(
                    "the lid of {} is open only {:.0} degrees: the opening is blocked",
                    self.label(c),
                    angle.to_degrees()
                ),
            );
        }
        Ok(())
    }

    /// Opening or closing `n` by its handle: the hand to the handle, the panel turned
    /// over `hinge_steps`, the arm folded back.
    pub(super) fn drive_hinge(
        &mut self,
        robot: Idx,
        n: Idx,
        open: bool,
    ) -> Result<Vec<Stage>, PhysicsError> {
        let Some(hi) = self.hinges.iter().position(|h| h.node == n) else {
            return fail(
                FailureKind::Blocked,
                format!("{} has no door or lid", self.label(n)),
            );
        };
        // Doors swing away from the robot that opens them.
        if open
            && self.task.node(n).kind == NodeKind::Door
            && let Some(rb) = self.body[robot.get()]
        {
            let rp = self.pw.bodies[rb].translation();
            let h = &self.hinges[hi];
            let side_of = |angle: f32| {
                let tip = hinge_pose(h, angle).transform_point(Vector::new(0.0, 0.0, 0.0));
                (tip - rp).length()
            };
            let a = if side_of(FRAC_PI_2) >= side_of(-FRAC_PI_2) {
                FRAC_PI_2
            } else {
                -FRAC_PI_2
            };
            self.hinges[hi].open_angle = a;
        }
        let h = self.hinges[hi].clone();
        let handle_world = self.pw.bodies[h.body].position().transform_point(h.handle);
        let mut stages = self.reach(
            robot,
            handle_world,
            &format!("the handle of {}", self.label(n)),
        )?;
        let to = if open { h.open_angle } else { 0.0 };
        stages.push(Stage::Hinge(HingeTurn {
            hinge: h,
            to,
            from: None,
            taken: 0,
        }));
        stages.extend(self.arm_home(robot));
        Ok(stages)
    }

    /// The next of the `hinge_steps` that turn a panel from the angle it had when it
    /// started.
    pub(super) fn hinge_tick(&mut self, t: &mut HingeTurn) -> Tick {
        let steps = self.tol.hinge_steps;
        let from = match t.from {
            Some(a) => a,
            None => *t.from.insert(self.hinge_angle(t.hinge.node).unwrap_or(0.0)),
        };
        if t.taken >= steps {
            return Tick::Done;
        }
        t.taken += 1;
        let a = from + (t.to - from) * t.taken as f32 / steps as f32;
        self.pw.bodies[t.hinge.body].set_next_kinematic_position(hinge_pose(&t.hinge, a));
        Tick::Step
    }
}
