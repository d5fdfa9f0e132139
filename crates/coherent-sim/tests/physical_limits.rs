//! Actions the rules would refuse, executed physically anyway: each fails with numbers.

use coherent_core::{Action, NodeId, Verb};
use coherent_sim::{FailureKind, PhysicalEnv};

mod common;

/// env0: the robot dog (23) in the living room, the dining table (13) is HIGH_HEIGHT
/// with sunglasses (55) on it.
#[test]
fn legged_robot_cannot_grab_from_a_high_table() {
    let task = common::task("env0", 1);
    let mut env = PhysicalEnv::new(task.clone()).expect("world builds");
    let idx = |id| task.idx(NodeId(id)).expect("node exists");
    let err = env
        .execute_unchecked(NodeId(23), Action::new(Verb::Grab, idx(55)))
        .expect_err("out of reach");
    eprintln!("{err}");
    assert_eq!(err.kind, FailureKind::Reach, "{err}");
    assert!(
        err.message.contains("above the legged robot's reach"),
        "{err}"
    );
    assert!(err.message.contains(" m"), "{err}");
}

/// env0: the arm on the dining table (24) asked for something on the high table (33)
/// in the bedroom.
#[test]
fn arm_cannot_reach_an_object_on_another_table() {
    let task = common::task("env0", 3);
    let mut env = PhysicalEnv::new(task.clone()).expect("world builds");
    let on_33 = task
        .indices()
        .find(|&n| {
            task.init.has(coherent_core::Edge::new(
                n,
                coherent_core::Relation::On,
                task.idx(NodeId(33)).expect("high table"),
            )) && task
                .node(n)
                .properties
                .contains(coherent_core::PropSet::GRABABLE)
        })
        .expect("something grabable on the high table");
    let err = env
        .execute_unchecked(NodeId(24), Action::new(Verb::Grab, on_33))
        .expect_err("out of reach");
    eprintln!("{err}");
    assert_eq!(err.kind, FailureKind::Reach, "{err}");
    assert!(err.message.contains("its reach is 1.25 m"), "{err}");
}

/// env0: door 8 (bedroom - living room) is CLOSED; the quadrotor takes off in the child
/// room and is sent to the bedroom, whose only door is 8.
#[test]
fn quadrotor_cannot_fly_through_a_closed_door() {
    let task = common::task("env0", 1);
    let mut env = PhysicalEnv::new(task.clone()).expect("world builds");
    let idx = |id| task.idx(NodeId(id)).expect("node exists");
    let quad = NodeId(22);
    let start = task
        .init
        .target(idx(22), coherent_core::Relation::On)
        .expect("on something");
    env.execute_unchecked(quad, Action::new(Verb::TakeoffFrom, start))
        .expect("takes off");
    env.execute_unchecked(quad, Action::new(Verb::MoveTowards, idx(4)))
        .expect("flies to the living room");
    let err = env
        .execute_unchecked(quad, Action::new(Verb::MoveTowards, idx(0)))
        .expect_err("the closed door blocks");
    eprintln!("{err}");
    assert_eq!(err.kind, FailureKind::Blocked, "{err}");
    assert!(err.message.contains("<door>(8)"), "{err}");
}
