//! Joint steps in Rapier: several robots' actions at once in the one world. Hand-picked
//! steps on the demo task and env0 agree with the rules after every step and take as
//! long as their slowest action, not the sum; robots of one step that run into each
//! other fail with the numbers; a robot gives way to one earlier in the step, and waits
//! for a way another still blocks; refused steps move nothing; two runs are
//! bit-identical.

use std::sync::Arc;

use coherent_core::joint::Refusal;
use coherent_core::{Environment, NodeId, Reason, SymbolicEnv, Task};
use coherent_sim::{FailureKind, JointReport, PhysicalEnv, execute_joint_plan};

mod common;

/// A joint step as `(robot id, action)` pairs.
type Joint = &'static [(i64, &'static str)];

/// The demo's goal (mug and apple onto the coffee table) in 13 joint steps, the robots
/// working side by side: the arm hands the mug to the quadrotor while the dog fetches
/// the apple from the fridge.
const DEMO: &[Joint] = &[
    &[
        (6, "[grab] <mug>(7)"),
        (11, "[takeoff_from] <living room floor>(3)"),
        (13, "[movetowards] <door>(4)"),
    ],
    &[(13, "[open] <door>(4)")],
    &[
        (13, "[movetowards] <fridge>(8)"),
        (11, "[movetowards] <kitchen>(0)"),
    ],
    &[
        (13, "[open] <fridge>(8)"),
        (11, "[movetowards] <kitchen counter>(5)"),
    ],
    &[
        (13, "[movetowards] <apple>(9)"),
        (11, "[land_on] <kitchen counter>(5)"),
    ],
    &[
        (13, "[grab] <apple>(9)"),
        (6, "[putinto] <mug>(7) into <basket>(12)"),
    ],
    &[
        (13, "[movetowards] <living room>(2)"),
        (11, "[takeoff_from] <kitchen counter>(5)"),
    ],
    &[
        (13, "[movetowards] <coffee table>(10)"),
        (11, "[movetowards] <living room>(2)"),
    ],
    &[
        (13, "[puton] <apple>(9) on <coffee table>(10)"),
        (11, "[land_on] <living room floor>(3)"),
    ],
    &[(13, "[movetowards] <mug>(7)")],
    &[(13, "[grab] <mug>(7)")],
    &[(13, "[movetowards] <coffee table>(10)")],
    &[(13, "[puton] <mug>(7) on <coffee table>(10)")],
];

fn refs<'a>(step: &[(i64, &'a str)]) -> Vec<(NodeId, &'a str)> {
    step.iter().map(|&(r, a)| (NodeId(r), a)).collect()
}

/// Plays `steps` as joint steps, checking each against the rules' own joint step: the
/// same state after it, and the step as long as its slowest action.
fn play(
    env: &mut PhysicalEnv,
    rules: &mut SymbolicEnv,
    steps: &[&[(i64, &str)]],
) -> Vec<JointReport> {
    let mut reports = Vec::new();
    for (i, &step) in steps.iter().enumerate() {
        let report = match env.step_joint_physical(&refs(step)) {
            Ok(Ok(report)) => report,
            Ok(Err(refused)) => panic!("joint step {i} refused: {refused}"),
            Err(e) => panic!("joint step {i}: {e}"),
        };
        let symbolic = rules.step_joint(&refs(step)).expect("robots exist");
        assert!(
            symbolic.refused.is_none(),
            "step {i}: {:?}",
            symbolic.refused
        );
        assert_eq!(env.state(), rules.state(), "joint step {i}");
        assert_eq!(report.done, symbolic.done, "joint step {i}");
        let slowest = report.action_seconds.iter().copied().fold(0.0, f64::max);
        assert_eq!(report.sim_seconds, slowest, "joint step {i}");
        reports.push(report);
    }
    reports
}

/// Simulated seconds of `steps`' actions one at a time, in the order given, from the
/// world's building on.
fn sequential(task: &Arc<Task>, steps: &[Joint]) -> f64 {
    let mut env = PhysicalEnv::new(task.clone()).expect("the world builds");
    for &(robot, text) in steps.iter().flat_map(|s| s.iter()) {
        match env.step_physical(NodeId(robot), text) {
            Ok(Ok(_)) => {}
            other => panic!("{text}: {other:?}"),
        }
    }
    env.sim_seconds().expect("physics keeps time")
}

#[test]
fn demo_joint_steps_agree_with_the_rules_and_take_the_slowest_actions_time() {
    let task = Arc::new(common::demo());
    let mut env = PhysicalEnv::new(task.clone()).expect("the world builds");
    let mut rules = SymbolicEnv::new(task.clone());
    let start = env.sim_seconds().expect("physics keeps time");
    let reports = play(&mut env, &mut rules, DEMO);
    assert!(reports.last().is_some_and(|r| r.done), "the goal holds");
    let parallel = env.sim_seconds().expect("physics keeps time") - start;
    let stepped: f64 = reports.iter().map(|r| r.sim_seconds).sum();
    assert!((parallel - stepped).abs() < 1e-6, "{parallel} vs {stepped}");
    // The same 22 actions one at a time take longer: the sum, not the longest, of each
    // step's actions.
    let sequential = sequential(&task, DEMO) - start;
    eprintln!("demo: {parallel:.2} s in 13 joint steps, {sequential:.2} s in 22 steps");
    assert!(parallel < 0.85 * sequential, "{parallel} vs {sequential}");
}

/// env0 task 9: both fixed arms (on the dining table in the living room and on the high
/// table in the bedroom), the quadrotor and the dog, all four at once.
const ENV0_FOUR: &[Joint] = &[
    &[
        (24, "[grab] <plate>(51)"),
        (50, "[grab] <battery>(39)"),
        (22, "[takeoff_from] <livingroom floor>(5)"),
        (23, "[movetowards] <fridge>(14)"),
    ],
    &[
        (50, "[putinto] <battery>(39) into <box>(52)"),
        (24, "[puton] <plate>(51) on <dining table>(13)"),
        (22, "[movetowards] <kitchen>(6)"),
        (23, "[open] <fridge>(14)"),
    ],
];

#[test]
fn env0_four_robots_at_once_take_their_slowest_actions_time_not_the_sum() {
    let task = common::task("env0", 9);
    let mut env = PhysicalEnv::new(task.clone()).expect("the world builds");
    let mut rules = SymbolicEnv::new(task.clone());
    let reports = play(&mut env, &mut rules, ENV0_FOUR);
    // Each action of the last step alone, from the same state: the joint step takes
    // about as long as the slowest of them, each action about as long as alone (a
    // robot's wait for loose things to rest may last while another's things still move).
    let last = ENV0_FOUR.len() - 1;
    let mut alone = Vec::new();
    for &(robot, text) in ENV0_FOUR[last] {
        let mut env = PhysicalEnv::new(task.clone()).expect("the world builds");
        let mut rules = SymbolicEnv::new(task.clone());
        play(&mut env, &mut rules, &ENV0_FOUR[..last]);
        match env.step_physical(NodeId(robot), text) {
            Ok(Ok(report)) => alone.push(report.sim_seconds),
            other => panic!("{text} alone: {other:?}"),
        }
    }
    let joint = &reports[last];
    eprintln!(
        "env0 task 9: joint {:.2} s {:?}, alone {alone:?}",
        joint.sim_seconds, joint.action_seconds
    );
    for (j, a) in joint.action_seconds.iter().zip(&alone) {
        assert!((j - a).abs() < 0.5, "{j} s at once, {a} s alone");
    }
    let slowest = alone.iter().copied().fold(0.0, f64::max);
    let sum: f64 = alone.iter().sum();
    assert!((joint.sim_seconds - slowest).abs() < 0.5, "{joint:?}");
    assert!(joint.sim_seconds < sum - 5.0, "{joint:?} vs {sum}");
}

/// The demo with the quadrotor hovering in the kitchen and the dog in the living room.
const BEFORE_COLLISION: &[Joint] = &[
    &[
        (11, "[takeoff_from] <living room floor>(3)"),
        (13, "[movetowards] <door>(4)"),
    ],
    &[(13, "[open] <door>(4)")],
    &[
        (11, "[movetowards] <kitchen>(0)"),
        (13, "[movetowards] <living room>(2)"),
    ],
];

/// The quadrotor lands on the kitchen floor just inside the door while the dog walks
/// back into the kitchen to the spot just inside the door. The rules see no conflict
/// (neither reads what the other changes); physics does.
const COLLIDING: Joint = &[
    (11, "[land_on] <kitchen floor>(1)"),
    (13, "[movetowards] <kitchen>(0)"),
];

#[test]
fn robots_sent_to_the_same_spot_at_once_fail_with_who_where_and_when() {
    let task = Arc::new(common::demo());
    let mut env = PhysicalEnv::new(task.clone()).expect("the world builds");
    let mut rules = SymbolicEnv::new(task.clone());
    play(&mut env, &mut rules, BEFORE_COLLISION);
    let before = env.sim_seconds().expect("physics keeps time");
    let err = env
        .step_joint_physical(&refs(COLLIDING))
        .expect_err("the rules allow the step, and the robots collide");
    eprintln!("{err}");
    assert_eq!(err.kind, FailureKind::Collision, "{err}");
    let m = &err.message;
    for part in [
        "<quadrotor>(11) [land_on] <kitchen floor>(1)",
        "<robot dog>(13) [movetowards] <kitchen>(0)",
        "collided",
        "s into the joint step",
        "s simulated",
        "touched",
        " m deep",
    ] {
        assert!(m.contains(part), "{part:?} missing: {m}");
    }
    let into: f64 = m
        .split(" collided ")
        .nth(1)
        .and_then(|r| r.split(" s into").next())
        .and_then(|t| t.parse().ok())
        .expect("when, in seconds");
    let after = env.sim_seconds().expect("physics keeps time");
    assert!(into > 0.0 && (after - before - into).abs() < 0.01, "{m}");
    // The world is not trusted after a failure, through the Environment trait too.
    let next = env
        .step_joint(&[(NodeId(13), "[movetowards] <fridge>(8)")])
        .expect("robots exist");
    let why = next.parts[0].infeasible.as_ref().expect("not carried out");
    assert_eq!(why.reason, Reason::Physics, "{why:?}");
    assert!(why.message.contains("inconsistent"), "{why:?}");

    // One after the other, the dog first, the same two actions succeed: the collision
    // is the robots' acting at once. (The other way round, the landed quadrotor blocks
    // the dog's way in.)
    let mut env = PhysicalEnv::new(task.clone()).expect("the world builds");
    let mut rules = SymbolicEnv::new(task.clone());
    play(&mut env, &mut rules, BEFORE_COLLISION);
    play(&mut env, &mut rules, &[&COLLIDING[1..], &COLLIDING[..1]]);
}

/// Simulated seconds of each action of `step`, played after `before` (one action at a
/// time when `step` has one).
fn seconds(task: &Arc<Task>, before: &[Joint], step: &[(i64, &str)]) -> Vec<f64> {
    let mut env = PhysicalEnv::new(task.clone()).expect("the world builds");
    let mut rules = SymbolicEnv::new(task.clone());
    play(&mut env, &mut rules, before);
    play(&mut env, &mut rules, &[step]).remove(0).action_seconds
}

/// env0 task 18: the dog has just put the napkin into the basket of the quadrotor landed
/// beside it.
const BESIDE_THE_BASKET: &[Joint] = &[
    &[(23, "[movetowards] <dinner napkin>(41)")],
    &[(23, "[grab] <dinner napkin>(41)")],
    &[(23, "[movetowards] <basket>(25)")],
    &[(23, "[putinto] <dinner napkin>(41) into <basket>(25)")],
];

#[test]
fn a_robot_close_to_one_earlier_in_the_step_holds_until_the_way_is_clear() {
    let task = common::task("env0", 18);
    let walk = (23, "[movetowards] <toy car>(46)");
    let takeoff = (22, "[takeoff_from] <childroom floor>(3)");
    let alone_walk = seconds(&task, BESIDE_THE_BASKET, &[walk])[0];
    let alone_takeoff = seconds(&task, BESIDE_THE_BASKET, &[takeoff])[0];
    // The dog first: it walks off as alone while the quadrotor holds until the dog is
    // clear of its basket; the other way round, the dog holds for the quadrotor.
    let dog_first = seconds(&task, BESIDE_THE_BASKET, &[walk, takeoff]);
    let quad_first = seconds(&task, BESIDE_THE_BASKET, &[takeoff, walk]);
    eprintln!(
        "alone: walk {alone_walk:.2} s, take-off {alone_takeoff:.2} s; dog first {dog_first:?}, quadrotor first {quad_first:?}"
    );
    assert_eq!(dog_first[0], alone_walk);
    assert!(dog_first[1] > alone_takeoff + 0.05, "{dog_first:?}");
    assert_eq!(quad_first[0], alone_takeoff);
    assert!(quad_first[1] > alone_walk + 0.05, "{quad_first:?}");
}

/// s1-apartment task 12 (our benchmark): the quadrotor hovers just after taking off in
/// the living room, in front of the door the dog is sent to.
const HOVERING_BY_THE_DOOR: &[Joint] = &[&[
    (25, "[grab] <bread>(28)"),
    (45, "[takeoff_from] <kitchen floor>(1)"),
    (47, "[movetowards] <kitchen>(0)"),
]];

#[test]
fn a_robot_whose_way_another_of_the_step_blocks_waits_until_it_is_clear() {
    let task = common::native_task("s1-apartment", 12);
    let to_the_door = (47, "[movetowards] <door>(10)");
    // Alone, the dog finds no free spot beside the door: the quadrotor is in the way.
    let mut env = PhysicalEnv::new(task.clone()).expect("the world builds");
    let mut rules = SymbolicEnv::new(task.clone());
    play(&mut env, &mut rules, HOVERING_BY_THE_DOOR);
    let err = env
        .step_physical(NodeId(to_the_door.0), to_the_door.1)
        .expect_err("blocked");
    assert_eq!(err.kind, FailureKind::Blocked, "{err}");
    assert!(err.message.contains("no free spot beside"), "{err}");
    // With the quadrotor flying off in the same step, the dog waits and then goes.
    let at_once = seconds(
        &task,
        HOVERING_BY_THE_DOOR,
        &[(45, "[movetowards] <kitchen island>(11)"), to_the_door],
    );
    eprintln!("at once: {at_once:?}");
    assert!(at_once[1] >= 0.5, "{at_once:?}");
}

#[test]
fn a_refused_joint_step_moves_nothing() {
    let task = Arc::new(common::demo());
    let mut env = PhysicalEnv::new(task.clone()).expect("the world builds");
    let mut rules = SymbolicEnv::new(task.clone());
    play(&mut env, &mut rules, &DEMO[..5]);
    let (time, poses) = (env.sim_seconds(), env.world().poses());
    // The arm puts the mug into the basket of the quadrotor that takes off.
    let step = [
        (NodeId(6), "[putinto] <mug>(7) into <basket>(12)"),
        (NodeId(11), "[takeoff_from] <kitchen counter>(5)"),
    ];
    match env.step_joint_physical(&step) {
        Ok(Err(Refusal::Interference(x))) => {
            assert!(x.message.contains("<basket>(12)"), "{}", x.message)
        }
        other => panic!("not refused for interference: {other:?}"),
    }
    let outcome = env.step_joint(&step).expect("robots exist");
    assert!(outcome.refused.is_some());
    for part in &outcome.parts {
        let why = part.infeasible.as_ref().expect("not carried out");
        assert_eq!(why.reason, Reason::Interference, "{why:?}");
    }
    assert_eq!(env.sim_seconds(), time);
    assert_eq!(env.world().poses(), poses);
    assert_eq!(env.state(), rules.state());
}

/// `steps` as a plan of joint steps, each action resolved in the state before its step.
fn joint_plan(task: &Task, steps: &[Joint]) -> Vec<Vec<coherent_core::planner::Step>> {
    let mut s = task.init.clone();
    let mut plan = Vec::new();
    for &step in steps {
        let parts = match coherent_core::env::resolve_joint(task, &s, &refs(step)) {
            Ok(Ok(parts)) => parts,
            other => panic!("{step:?}: {other:?}"),
        };
        coherent_core::joint::apply(task, &mut s, &parts);
        plan.push(
            parts
                .iter()
                .map(|&(r, action)| coherent_core::planner::Step {
                    robot: r.node,
                    action,
                })
                .collect(),
        );
    }
    plan
}

#[test]
fn a_plan_of_joint_steps_runs_bit_identically_twice() {
    let task = Arc::new(common::demo());
    let plan = joint_plan(&task, DEMO);
    let a = execute_joint_plan(&task, &plan);
    let b = execute_joint_plan(&task, &plan);
    assert!(a.physics_ok, "{:?}", a.physics_error);
    assert_eq!(a.steps_done, DEMO.len());
    let bits = |r: &coherent_sim::PlanReport| -> Vec<(i64, [u32; 7])> {
        r.final_poses
            .iter()
            .map(|(id, p)| (id.0, p.map(f32::to_bits)))
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a.sim_seconds.to_bits(), b.sim_seconds.to_bits());
    assert_eq!(a.paths, b.paths);
}
