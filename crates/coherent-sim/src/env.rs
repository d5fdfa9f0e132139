//! [`PhysicalEnv`]: the rules decide what may be done, Rapier does it, and the relations
//! read back from the bodies must agree with the symbolic state after every step.

use std::sync::Arc;
use std::time::Instant;

use coherent_core::env;
use coherent_core::feasibility::{self, Infeasible, Reason};
use coherent_core::joint::{self, Refusal};
use coherent_core::planner::Step;
use coherent_core::rules;
use coherent_core::{
    Action, Edge, Environment, Idx, JointOutcome, NodeId, NodeKind, Outcome, PartOutcome, PropSet,
    Relation, Robot, RobotKind, State, StateSet, Task,
};

use crate::layout::{self, Layout};
use crate::world::{FailureKind, PhysicsError, Placement, World, fail};

/// A symbolic environment whose every action is also carried out in Rapier.
#[derive(Debug)]
pub struct PhysicalEnv {
    /// The task as given; `task` is the task as events have left it (docs/dynamic.md).
    base: Arc<Task>,
    task: Arc<Task>,
    layout: Layout,
    state: State,
    world: World,
    last_error: Option<PhysicsError>,
}

/// What one physically executed step did.
#[derive(Clone, Debug, PartialEq)]
pub struct StepReport {
    pub action: String,
    pub sim_seconds: f64,
    pub done: bool,
}

/// What one physically executed joint step did.
#[derive(Clone, Debug, PartialEq)]
pub struct JointReport {
    /// Each robot's action as the rules print it, in the order given.
    pub actions: Vec<(NodeId, String)>,
    /// Each action's simulated seconds from the step's start, in the same order.
    pub action_seconds: Vec<f64>,
    /// The step's simulated seconds: its slowest action's.
    pub sim_seconds: f64,
    pub done: bool,
}

impl PhysicalEnv {
    /// The task's layout (its geometry, or a generated one) in Rapier.
    pub fn new(task: Arc<Task>) -> Result<PhysicalEnv, PhysicsError> {
        let layout = layout::for_task(&task).map_err(|e| PhysicsError {
            kind: FailureKind::Layout,
            message: e.0,
        })?;
        PhysicalEnv::with_layout(task, layout)
    }

    pub fn with_layout(task: Arc<Task>, layout: Layout) -> Result<PhysicalEnv, PhysicsError> {
        let world = World::new(task.clone(), layout.clone())?;
        let env = PhysicalEnv {
            state: task.init.clone(),
            base: Arc::clone(&task),
            task,
            layout,
            world,
            last_error: None,
        };
        env.compare().map_err(|e| PhysicsError {
            kind: e.kind,
            message: format!("the initial scene: {}", e.message),
        })?;
        Ok(env)
    }

    pub fn world(&self) -> &World {
        &self.world
    }

    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The physical failure of the last step, if it had one.
    pub fn last_physics_error(&self) -> Option<&PhysicsError> {
        self.last_error.as_ref()
    }

    /// Checks `text` with the rules, executes it physically, applies it symbolically and
    /// compares the two. A rules refusal is `Ok(Err(infeasible))`; a physical failure or
    /// a disagreement is `Err`.
    pub fn step_physical(
        &mut self,
        robot: NodeId,
        text: &str,
    ) -> Result<Result<StepReport, Infeasible>, PhysicsError> {
        self.consistent()?;
        let r = self.robot(robot)?;
        let a = match feasibility::check(&self.task, &self.state, r, text) {
            Ok(a) => a,
            Err(why) => return Ok(Err(why)),
        };
        let t0 = self.world.sim_time;
        match self.execute_and_compare(r.node, a) {
            Ok(()) => Ok(Ok(StepReport {
                action: a.render(&self.task),
                sim_seconds: self.world.sim_time - t0,
                done: self.task.goal_satisfied(&self.state),
            })),
            Err(e) => {
                let e = PhysicsError {
                    kind: e.kind,
                    message: format!(
                        "{} {}: {}",
                        self.task.node(r.node).label(),
                        a.render(&self.task),
                        e.message
                    ),
                };
                self.last_error = Some(e.clone());
                Err(e)
            }
        }
    }

    /// Checks a joint step (at most one action per robot) with the rules
    /// ([`coherent_core::joint::check`]), executes its actions physically at once,
    /// applies them symbolically and compares the two. A refusal by the rules is
    /// `Ok(Err(refusal))`; a physical failure (robots of the step touching each other
    /// among them) or a disagreement is `Err`, with the numbers.
    pub fn step_joint_physical(
        &mut self,
        actions: &[(NodeId, &str)],
    ) -> Result<Result<JointReport, Refusal>, PhysicsError> {
        self.consistent()?;
        let step = match env::resolve_joint(&self.task, &self.state, actions) {
            Ok(Ok(step)) => step,
            Ok(Err(refused)) => return Ok(Err(refused)),
            Err(e) => return fail(FailureKind::Layout, e.to_string()),
        };
        let pairs: Vec<(Idx, Action)> = step.iter().map(|&(r, a)| (r.node, a)).collect();
        let outcome = self.world.execute_joint(&pairs).and_then(|seconds| {
            joint::apply(&self.task, &mut self.state, &step);
            self.compare().map_err(|e| PhysicsError {
                kind: e.kind,
                message: format!(
                    "after the joint step [{}]: {}",
                    pairs
                        .iter()
                        .map(|&(r, a)| format!(
                            "{} {}",
                            self.task.node(r).label(),
                            a.render(&self.task)
                        ))
                        .collect::<Vec<_>>()
                        .join(", "),
                    e.message
                ),
            })?;
            Ok(seconds)
        });
        match outcome {
            Ok(action_seconds) => Ok(Ok(JointReport {
                actions: pairs
                    .iter()
                    .map(|&(r, a)| (self.task.id(r), a.render(&self.task)))
                    .collect(),
                sim_seconds: action_seconds.iter().copied().fold(0.0, f64::max),
                action_seconds,
                done: self.task.goal_satisfied(&self.state),
            })),
            Err(e) => {
                self.last_error = Some(e.clone());
                Err(e)
            }
        }
    }

    /// No earlier failure left the world inconsistent.
    fn consistent(&self) -> Result<(), PhysicsError> {
        match &self.last_error {
            Some(e) => Err(PhysicsError {
                kind: e.kind,
                message: format!(
                    "the world is inconsistent after an earlier failure ({e}); reset it"
                ),
            }),
            None => Ok(()),
        }
    }

    fn robot(&self, robot: NodeId) -> Result<Robot, PhysicsError> {
        self.task.robot_by_id(robot).map_err(|e| PhysicsError {
            kind: FailureKind::Layout,
            message: e.to_string(),
        })
    }

    /// Executes `a` physically without asking the rules (for tests of physical limits);
    /// the symbolic state is left as it is.
    pub fn execute_unchecked(&mut self, robot: NodeId, a: Action) -> Result<(), PhysicsError> {
        let r = self.robot(robot)?;
        let out = self.world.execute(r.node, a);
        if let Err(e) = &out {
            self.last_error = Some(e.clone());
        }
        out
    }

    fn execute_and_compare(&mut self, robot: Idx, a: Action) -> Result<(), PhysicsError> {
        self.world.execute(robot, a)?;
        let robot = *self.task.robot(robot).ok_or_else(|| PhysicsError {
            kind: FailureKind::Layout,
            message: "not a robot".into(),
        })?;
        rules::apply(&self.task, &mut self.state, robot, a);
        self.compare()
    }

    /// Sets down each movable thing whose place differs between the current state and
    /// `next` (a state an event left) where `next` has it.
    fn move_things(&mut self, task: &Task, next: &State) -> Result<(), PhysicsError> {
        for x in task.indices() {
            let node = task.node(x);
            if !(node.properties.contains(PropSet::GRABABLE) || node.kind == NodeKind::Tool) {
                continue;
            }
            let place = |s: &State| {
                s.out(x)
                    .iter()
                    .filter(|e| e.rel().is_location())
                    .map(|e| (e.rel(), e.to()))
                    .collect::<Vec<_>>()
            };
            let now = place(next);
            let held = |s: &State| {
                task.indices()
                    .any(|r| s.has(Edge::new(r, Relation::Hold, x)))
            };
            if place(&self.state) == now && held(&self.state) == held(next) {
                continue;
            }
            let [(relation, holder)] = now[..] else {
                return fail(
                    FailureKind::Disagreement,
                    format!("{} was moved to no single place", node.label()),
                );
            };
            let near: Vec<Idx> = next
                .sources(Relation::Close, x)
                .filter(|&r| task.robot(r).is_some_and(|r| r.kind == RobotKind::RobotDog))
                .collect();
            self.world
                .move_thing(x, holder, relation == Relation::Inside, &near)?;
        }
        Ok(())
    }

    /// Relations read back from the bodies against the symbolic state; every difference
    /// is listed with both views.
    pub fn compare(&self) -> Result<(), PhysicsError> {
        let diffs = disagreements(&self.task, &self.state, &self.world);
        if diffs.is_empty() {
            Ok(())
        } else {
            fail(FailureKind::Disagreement, diffs.join("; "))
        }
    }
}

/// Every difference between the physical relations and the symbolic state `s`.
pub fn disagreements(task: &Task, s: &State, w: &World) -> Vec<String> {
    let tol = w.tolerances();
    let mut out = Vec::new();
    let label = |n: Idx| task.node(n).label();
    for x in task.indices() {
        let node = task.node(x);
        let movable = node.properties.contains(PropSet::GRABABLE) || node.kind == NodeKind::Tool;
        if movable {
            let mut symbolic: Vec<Placement> = Vec::new();
            for e in s.out(x) {
                match e.rel() {
                    Relation::On => symbolic.push(Placement::On(e.to())),
                    Relation::Inside => symbolic.push(Placement::Inside(e.to())),
                    _ => {}
                }
            }
            for r in &task.robots {
                if s.has(Edge::new(r.node, Relation::Hold, x)) {
                    symbolic.push(Placement::Held(r.node));
                }
            }
            let physical = w.placement(x);
            let agree = match (symbolic.as_slice(), physical) {
                ([], Placement::Loose) => true,
                ([one], p) => *one == p,
                _ => false,
            };
            if !agree {
                let show = |p: &Placement| match *p {
                    Placement::On(t) => format!("ON {}", label(t)),
                    Placement::Inside(t) => format!("INSIDE {}", label(t)),
                    Placement::Held(r) => format!("held by {}", label(r)),
                    Placement::Loose => "on nothing named".to_owned(),
                };
                let sym: Vec<String> = symbolic.iter().map(show).collect();
                let pos = w.position(x).map_or(String::new(), |p| {
                    format!(" at ({:.2}, {:.2}, {:.2})", p.x, p.y, p.z)
                });
                out.push(format!(
                    "{}: symbolic [{}], physical {}{pos}",
                    label(x),
                    sym.join(", "),
                    show(&physical)
                ));
            }
        }
        let states = s.states(x);
        if states.intersects(StateSet::OPEN | StateSet::CLOSED | StateSet::OPEN_FOREVER)
            && let Some(angle) = w.hinge_angle(x)
        {
            let deg = angle.abs().to_degrees();
            let open = states.is_open();
            if (open && deg < tol.open_min_degrees) || (!open && deg > tol.closed_max_degrees) {
                out.push(format!(
                    "{}: symbolic {}, physical hinge at {deg:.1} degrees",
                    label(x),
                    if open { "OPEN" } else { "CLOSED" }
                ));
            }
        }
    }
    for r in &task.robots {
        let me = label(r.node);
        if r.kind != RobotKind::RobotArm {
            let sym = rules::room_of(task, s, r.node);
            let phys = w.robot_room(r.node);
            if sym != phys {
                out.push(format!(
                    "{me}: symbolic room {}, physical room {}",
                    sym.map_or("none".into(), label),
                    phys.map_or("none".into(), label)
                ));
            }
        }
        match r.kind {
            RobotKind::Quadrotor => {
                let flying = s.states(r.node).contains(StateSet::FLYING);
                let Some((landed, on)) = w.quad_landed_on(r.node) else {
                    continue;
                };
                let sym_on = s.target(r.node, Relation::On);
                if flying == landed {
                    out.push(format!(
                        "{me}: symbolic {}, physical {}",
                        if flying { "FLYING" } else { "LAND" },
                        if landed { "landed" } else { "in the air" }
                    ));
                } else if landed && sym_on != on {
                    out.push(format!(
                        "{me}: symbolic ON {}, physical on {}",
                        sym_on.map_or("nothing".into(), label),
                        on.map_or("nothing".into(), label)
                    ));
                }
                if flying
                    && let Some(a) = s.target(r.node, Relation::Above)
                    && !w.quad_above(r.node, a)
                {
                    out.push(format!(
                        "{me}: symbolic ABOVE {}, physically not over it",
                        label(a)
                    ));
                }
            }
            RobotKind::RobotDog => {
                let reach = w.dog_reach(r.node);
                for x in s.targets(r.node, Relation::Close) {
                    match w.dog_distance(r.node, x) {
                        Some(d) if d <= reach + tol.close_margin => {}
                        Some(d) => out.push(format!(
                            "{me}: symbolic CLOSE {}, physically {d:.2} m from its shoulder (reach {reach:.2} m)",
                            label(x)
                        )),
                        None => {}
                    }
                }
            }
            RobotKind::RobotArm => {}
        }
    }
    out
}

impl Environment for PhysicalEnv {
    fn task(&self) -> &Task {
        &self.task
    }

    fn state(&self) -> &State {
        &self.state
    }

    /// A physical failure comes back as an infeasible outcome whose message has the
    /// numbers; [`PhysicalEnv::last_physics_error`] has it too.
    fn step(&mut self, robot: NodeId, action: &str) -> coherent_core::Result<Outcome> {
        self.task.robot_by_id(robot)?;
        let infeasible = match self.step_physical(robot, action) {
            Ok(Ok(_)) => None,
            Ok(Err(why)) => Some(why),
            Err(e) => Some(Infeasible {
                reason: Reason::Physics,
                message: format!("physics: {}", e.message),
            }),
        };
        Ok(Outcome {
            infeasible,
            done: self.goal_satisfied(),
            report: None,
        })
    }

    /// The robots of the step move at once; a physical failure (robots that touched each
    /// other among them) makes every part infeasible with the numbers, as
    /// [`Environment::step`] does for one action.
    fn step_joint(&mut self, actions: &[(NodeId, &str)]) -> coherent_core::Result<JointOutcome> {
        for &(robot, _) in actions {
            self.task.robot_by_id(robot)?;
        }
        let failed = match self.step_joint_physical(actions) {
            Ok(Ok(_)) => None,
            Ok(Err(refused)) => {
                return Ok(env::refused_outcome(
                    self.goal_satisfied(),
                    actions,
                    refused,
                ));
            }
            Err(e) => Some(Infeasible {
                reason: Reason::Physics,
                message: format!("physics: {}", e.message),
            }),
        };
        Ok(JointOutcome {
            parts: actions
                .iter()
                .map(|&(robot, _)| PartOutcome {
                    robot,
                    infeasible: failed.clone(),
                    report: None,
                })
                .collect(),
            refused: None,
            done: self.goal_satisfied(),
        })
    }

    /// Things an event moved are set down where the rules now have them
    /// ([`World::move_thing`]), and the bodies must then agree with the new state. A
    /// robot that goes down stays as an obstacle; a robot joins only where the task
    /// placed it (physics does not carry a robot elsewhere: `coherent run` refuses such
    /// an event first). A physical failure is an error, and the world stays
    /// inconsistent.
    fn befall(&mut self, task: Arc<Task>, state: State) -> coherent_core::Result<()> {
        let physics = |e: PhysicsError| coherent_core::Error::Unsupported(format!("physics: {e}"));
        self.consistent().map_err(physics)?;
        let stance = |t: &Task, s: &State, r: Idx| {
            let on = [Relation::On, Relation::Above].map(|rel| s.target(r, rel));
            (rules::room_of(t, s, r), s.states(r), on)
        };
        for r in &self.base.robots {
            if stance(&self.base, &self.state, r.node) != stance(&task, &state, r.node) {
                return Err(coherent_core::Error::Unsupported(format!(
                    "physics does not carry {} anywhere at an event: a robot joins where the \
                     task placed it",
                    task.node(r.node).label()
                )));
            }
        }
        let out = self.move_things(&task, &state).and_then(|()| {
            self.task = task;
            self.state = state;
            self.compare()
        });
        out.map_err(|e| {
            self.last_error = Some(e.clone());
            physics(e)
        })
    }

    /// From the world's building on: it settles for up to a second before the first
    /// action.
    fn sim_seconds(&self) -> Option<f64> {
        Some(self.world.sim_time)
    }

    /// Rebuilds the world from the layout (deterministic: the same bodies in the same order).
    fn reset(&mut self) {
        self.task = Arc::clone(&self.base);
        self.state = self.task.init.clone();
        self.last_error = None;
        match World::new(self.task.clone(), self.layout.clone()) {
            Ok(w) => self.world = w,
            Err(e) => self.last_error = Some(e),
        }
    }
}

/// The result of executing a whole plan physically.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanReport {
    pub physics_ok: bool,
    pub physics_error: Option<String>,
    /// Steps executed before the end or the failure.
    pub steps_done: usize,
    pub sim_seconds: f64,
    pub wall_ms: f64,
    /// Final pose of every body, `(id, [x, y, z, qx, qy, qz, qw])`.
    pub final_poses: Vec<(NodeId, [f32; 7])>,
    /// Each mobile robot's track, `[x, y, z]` (see `World::paths`).
    pub paths: Vec<(NodeId, Vec<[f32; 3]>)>,
}

/// Executes `plan` (e.g. `planner::analyse(..).plan`) in Rapier with the task's layout,
/// checking the relations after every step.
pub fn execute_plan(task: &Arc<Task>, plan: &[Step]) -> PlanReport {
    run_plan(task, plan.len(), |env, i| {
        let text = plan[i].action.render(task);
        match env.step_physical(task.id(plan[i].robot), &text) {
            Ok(Ok(_)) => Ok(()),
            Ok(Err(why)) => Err(format!("step {i}: the rules refuse {text}: {why}")),
            Err(e) => Err(format!("step {i}: {e}")),
        }
    })
}

/// Executes a plan of joint steps (each the actions of several robots at once) in Rapier
/// with the task's layout, checking the relations after every joint step; its
/// `steps_done` counts joint steps.
pub fn execute_joint_plan(task: &Arc<Task>, plan: &[Vec<Step>]) -> PlanReport {
    run_plan(task, plan.len(), |env, i| {
        let texts: Vec<(NodeId, String)> = plan[i]
            .iter()
            .map(|s| (task.id(s.robot), s.action.render(task)))
            .collect();
        let step: Vec<(NodeId, &str)> = texts.iter().map(|(r, t)| (*r, t.as_str())).collect();
        match env.step_joint_physical(&step) {
            Ok(Ok(_)) => Ok(()),
            Ok(Err(refused)) => Err(format!("joint step {i}: the rules refuse it: {refused}")),
            Err(e) => Err(format!("joint step {i}: {e}")),
        }
    })
}

/// Builds the world, runs `steps` steps with `step` (its error says which and why) until
/// the end or the first failure, and reports.
fn run_plan(
    task: &Arc<Task>,
    steps: usize,
    mut step: impl FnMut(&mut PhysicalEnv, usize) -> Result<(), String>,
) -> PlanReport {
    let start = Instant::now();
    let mut report = PlanReport {
        physics_ok: false,
        physics_error: None,
        steps_done: 0,
        sim_seconds: 0.0,
        wall_ms: 0.0,
        final_poses: Vec::new(),
        paths: Vec::new(),
    };
    let mut env = match PhysicalEnv::new(task.clone()) {
        Ok(env) => env,
        Err(e) => {
            report.physics_error = Some(e.message);
            report.wall_ms = start.elapsed().as_secs_f64() * 1e3;
            return report;
        }
    };
    for i in 0..steps {
        if let Err(e) = step(&mut env, i) {
            report.physics_error = Some(e);
            break;
        }
        report.steps_done = i + 1;
    }
    report.physics_ok = report.physics_error.is_none();
    report.sim_seconds = env.world.sim_time;
    report.final_poses = env.world.poses();
    report.paths = env.world.paths.clone();
    report.wall_ms = start.elapsed().as_secs_f64() * 1e3;
    report
}
