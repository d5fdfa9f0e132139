//! Rapier execution, the relations read back and compared with the rules after every
//! step:
//! - `physics/plan/<scene>`: a whole optimal plan, one task per scene, the one whose
//!   plan moves the most robots (the pictures of `docs/render/`);
//! - `physics/plan/<robot type>`: a whole optimal plan of a mono task of that type;
//! - `physics/action/<robot type>/<verb>`: one action of each kind that optimal plans
//!   use, timed alone: each iteration builds the world and plays the plan up to that
//!   action outside the measurement. (No optimal plan closes anything; a dog closing
//!   the fridge it just opened fails in physics, the handle out of reach.)
//!
//! - `physics/joint/four_robots`: one joint step of env0 task 9, its four robots at once
//!   (both arms grab, the quadrotor takes off, the dog walks to the fridge), and
//!   `physics/joint/four_robots_in_turn`, the same four actions one after the other;
//!   each iteration builds the world outside the measurement.
//!
//! Each bench prints the simulated seconds it covers, for the ratio to wall time.

use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

use coherent_core::planner::{self, Limits, Step};
use coherent_core::{NodeId, NodeKind, RobotKind, Task, Verb};
use coherent_sim::PhysicalEnv;
use criterion::{
    BatchSize, BenchmarkGroup, Criterion, SamplingMode, criterion_group, criterion_main,
};

mod common;

fn shortest_plan(task: &Task) -> Vec<Step> {
    planner::search(task, &task.robots, &task.goal, &Limits::default())
        .plan
        .expect("the task is solvable")
}

/// `robot dog`, say, as an id segment: `robot_dog`.
fn type_id(kind: RobotKind) -> String {
    kind.class_name().replace(' ', "_")
}

fn bench_plan(
    group: &mut BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: &str,
    task: Task,
) {
    let task = Arc::new(task);
    let plan = shortest_plan(&task);
    let report = coherent_sim::execute_plan(&task, &plan);
    assert!(report.physics_ok, "{:?}", report.physics_error);
    eprintln!(
        "physics/{id}: {} task {}, {} steps, {:.1} s simulated",
        task.meta.scene,
        task.meta.task_id,
        plan.len(),
        report.sim_seconds
    );
    group.bench_function(id, |b| {
        b.iter(|| black_box(coherent_sim::execute_plan(&task, black_box(&plan))))
    });
}

fn plans(c: &mut Criterion) {
    let mut group = c.benchmark_group("physics");
    group.sample_size(10);
    for (n, id) in [(0, 14), (1, 15), (2, 13), (3, 13)] {
        bench_plan(&mut group, &format!("plan/env{n}"), common::task(n, id));
    }
    // Mono tasks whose shortest plan is the longest for their type.
    for (kind, n, id) in [
        (RobotKind::Quadrotor, 0, 0),
        (RobotKind::RobotDog, 2, 2),
        (RobotKind::RobotArm, 2, 3),
    ] {
        let task = common::task(n, id);
        let plan = shortest_plan(&task);
        assert!(
            plan.iter()
                .all(|s| task.robot(s.robot).map(|r| r.kind) == Some(kind)),
            "env{n} task {id} is not a {kind} task"
        );
        bench_plan(&mut group, &format!("plan/{}", type_id(kind)), task);
    }
    group.finish();
}

/// A world with `prefix` played, and the step to time after it.
struct Scenario {
    task: Arc<Task>,
    prefix: Vec<Step>,
    step: Step,
}

impl Scenario {
    /// The first step of the shortest plan of env`n` task `id` that `kind` takes with
    /// `verb` (towards a room or not), and the plan before it.
    fn find(n: usize, id: i64, kind: RobotKind, verb: Verb, room: bool) -> Scenario {
        let task = Arc::new(common::task(n, id));
        let plan = shortest_plan(&task);
        let at = plan
            .iter()
            .position(|s| {
                task.robot(s.robot).map(|r| r.kind) == Some(kind)
                    && s.action.verb == verb
                    && (task.node(s.action.object).kind == NodeKind::Room) == room
            })
            .unwrap_or_else(|| panic!("env{n} task {id}: no {kind} {} step", verb.name()));
        Scenario {
            prefix: plan[..at].to_vec(),
            step: plan[at],
            task,
        }
    }

    fn prepared(&self) -> PhysicalEnv {
        let mut env = PhysicalEnv::new(self.task.clone()).expect("the world builds");
        for s in &self.prefix {
            play(&mut env, &self.task, s).expect("the prefix plays");
        }
        env
    }
}

fn play(env: &mut PhysicalEnv, task: &Task, s: &Step) -> Result<f64, String> {
    let text = s.action.render(task);
    match env.step_physical(task.id(s.robot), &text) {
        Ok(Ok(report)) => Ok(report.sim_seconds),
        Ok(Err(why)) => Err(format!("{text}: {}", why.message)),
        Err(e) => Err(format!("{text}: {e}")),
    }
}

fn actions(c: &mut Criterion) {
    let mut group = c.benchmark_group("physics");
    // Every iteration replays a prefix outside the measurement: few, flat samples.
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    use RobotKind::{Quadrotor, RobotArm, RobotDog};
    let cases = [
        (Quadrotor, Verb::TakeoffFrom, false, 0, 0, "takeoff_from"),
        (Quadrotor, Verb::MoveTowards, true, 0, 0, "movetowards_room"),
        (Quadrotor, Verb::MoveTowards, false, 2, 9, "movetowards"),
        (Quadrotor, Verb::LandOn, false, 2, 9, "land_on"),
        (RobotDog, Verb::MoveTowards, false, 0, 5, "movetowards"),
        (RobotDog, Verb::MoveTowards, true, 0, 4, "movetowards_room"),
        (RobotDog, Verb::Open, false, 0, 5, "open"),
        (RobotDog, Verb::Grab, false, 0, 8, "grab"),
        (RobotDog, Verb::PutInto, false, 0, 18, "putinto"),
        (RobotDog, Verb::PutOn, false, 2, 0, "puton"),
        (RobotArm, Verb::Open, false, 0, 2, "open"),
        (RobotArm, Verb::Grab, false, 0, 3, "grab"),
        (RobotArm, Verb::PutInto, false, 0, 3, "putinto"),
        (RobotArm, Verb::PutOn, false, 3, 1, "puton"),
    ];
    for (kind, verb, room, n, id, name) in cases {
        let sc = Scenario::find(n, id, kind, verb, room);
        let sim = play(&mut sc.prepared(), &sc.task, &sc.step).expect("the step plays");
        let bench = format!("action/{}/{name}", type_id(kind));
        eprintln!(
            "physics/{bench}: env{n} task {id}, step {} ({}), {sim:.2} s simulated",
            sc.prefix.len(),
            sc.step.action.render(&sc.task)
        );
        group.bench_function(bench, |b| {
            b.iter_batched(
                || sc.prepared(),
                |mut env| {
                    let out = play(&mut env, &sc.task, &sc.step);
                    (env, out)
                },
                BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

/// env0 task 9's robots, each with its first action.
const FOUR_ROBOTS: [(i64, &str); 4] = [
    (24, "[grab] <plate>(51)"),
    (50, "[grab] <battery>(39)"),
    (22, "[takeoff_from] <livingroom floor>(5)"),
    (23, "[movetowards] <fridge>(14)"),
];

/// Plays actions on a world; their simulated seconds.
type Play = fn(&mut PhysicalEnv) -> Result<f64, String>;

/// The four actions as one joint step; its simulated seconds.
fn at_once(env: &mut PhysicalEnv) -> Result<f64, String> {
    let step: Vec<(NodeId, &str)> = FOUR_ROBOTS.iter().map(|&(r, a)| (NodeId(r), a)).collect();
    match env.step_joint_physical(&step) {
        Ok(Ok(report)) => Ok(report.sim_seconds),
        Ok(Err(refused)) => Err(refused.to_string()),
        Err(e) => Err(e.to_string()),
    }
}

/// The four actions one after the other; their simulated seconds.
fn in_turn(env: &mut PhysicalEnv) -> Result<f64, String> {
    let mut total = 0.0;
    for (r, a) in FOUR_ROBOTS {
        match env.step_physical(NodeId(r), a) {
            Ok(Ok(report)) => total += report.sim_seconds,
            Ok(Err(why)) => return Err(why.to_string()),
            Err(e) => return Err(e.to_string()),
        }
    }
    Ok(total)
}

fn joint(c: &mut Criterion) {
    let mut group = c.benchmark_group("physics");
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    let task = Arc::new(common::task(0, 9));
    let fresh = || PhysicalEnv::new(task.clone()).expect("the world builds");
    let cases: [(&str, Play); 2] = [("four_robots", at_once), ("four_robots_in_turn", in_turn)];
    for (name, run) in cases {
        let sim = run(&mut fresh()).expect("the actions play");
        eprintln!("physics/joint/{name}: env0 task 9, {sim:.2} s simulated");
        group.bench_function(format!("joint/{name}"), |b| {
            b.iter_batched(
                fresh,
                |mut env| {
                    let out = run(&mut env);
                    (env, out)
                },
                BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, plans, actions, joint);
criterion_main!(benches);
