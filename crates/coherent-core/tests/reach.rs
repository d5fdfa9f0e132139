//! What a robot can get at (`coherent_core::reach`), on the released env0 tasks: the
//! feasibility reason that stops a robot, and which robots of the team could instead,
//! as PEFA's feedback on a declined subtask tells them.

use coherent_core::reach::{self, Reach};
use coherent_core::{Idx, NodeId, Reason, Robot, State, Task};

mod common;

fn task(scene: &str, id: i64) -> Task {
    common::released_tasks()
        .into_iter()
        .find(|t| t.meta.scene == scene && t.meta.task_id == id)
        .expect("a released task")
}

fn robot(task: &Task, id: i64) -> Robot {
    task.robot_by_id(NodeId(id)).expect("a robot of the team")
}

fn node(task: &Task, id: i64) -> Idx {
    task.idx(NodeId(id)).expect("a node of the task")
}

/// The reason `robot` cannot act on `thing`, by name, and its message.
fn why(task: &Task, s: &State, robot_id: i64, thing: i64) -> (Reason, String) {
    let why = reach::why_not(task, s, robot(task, robot_id), node(task, thing)).expect("a reason");
    (why.reason, why.message)
}

#[test]
fn a_thing_on_a_high_surface_is_too_high_for_the_dog_and_the_others_get_at_it() {
    // env0 task 1: the sunglasses (55) lie on the dining table (13), a high surface in the
    // living room, where robot arm 24 stands; the dog (23) is in the living room, the
    // quadrotor (22) landed in the child room next door.
    let t = task("env0", 1);
    let s = &t.init;
    let (reason, message) = why(&t, s, 23, 55);
    assert_eq!(reason, Reason::TooHigh);
    assert_eq!(
        message,
        "<sunglasses>(55) is on a high surface (ON_HIGH_SURFACE), out of the robot dog's reach"
    );
    let sunglasses = node(&t, 55);
    assert_eq!(reach::reach(&t, s, robot(&t, 23), sunglasses), Reach::Never);
    assert_eq!(reach::reach(&t, s, robot(&t, 24), sunglasses), Reach::Now);
    // Take off, fly into the living room: then it can fly towards the table under them.
    assert_eq!(
        reach::reach(&t, s, robot(&t, 22), sunglasses),
        Reach::After(2)
    );
    // The table itself is a high surface: too high for the dog as well.
    let (reason, message) = why(&t, s, 23, 13);
    assert_eq!(reason, Reason::TooHigh);
    assert!(message.contains("(HIGH_HEIGHT)"), "{message}");
}

#[test]
fn an_arm_is_told_what_it_reaches_when_the_thing_is_elsewhere() {
    // env0 task 2: robot arm 24 on the dining table (13) in the living room; the textbook
    // (44) lies on a bed in the child room.
    let t = task("env0", 2);
    let (reason, message) = why(&t, &t.init, 24, 44);
    assert_eq!(reason, Reason::OutOfReach);
    assert_eq!(
        message,
        "<textbook>(44) is out of reach of <robot arm>(24), which only reaches what is on <dining table>(13)"
    );
    assert_eq!(
        reach::reach(&t, &t.init, robot(&t, 24), node(&t, 44)),
        Reach::Never
    );
    // Its own table, on which it puts what it holds, and the microwave there it opens.
    for thing in [13, 15] {
        assert!(reach::why_not(&t, &t.init, robot(&t, 24), node(&t, thing)).is_none());
    }
}

#[test]
fn a_robot_that_could_get_there_is_told_its_first_step() {
    // env0 task 2: the door (8) between the living room and the bedroom is closed; the
    // dog could open it and walk through; the quadrotor, landed in the bedroom, cannot
    // open doors.
    let t = task("env0", 2);
    let s = &t.init;
    let (reason, message) = why(&t, s, 23, 0);
    assert_eq!(reason, Reason::DoorClosed);
    assert!(message.starts_with("<door>(8) between"), "{message}");
    assert_eq!(
        reach::reach(&t, s, robot(&t, 23), node(&t, 0)),
        Reach::After(2)
    );
    let (reason, _) = why(&t, s, 22, 13);
    assert_eq!(reason, Reason::DoorClosed);
    assert_eq!(
        reach::reach(&t, s, robot(&t, 22), node(&t, 13)),
        Reach::Never
    );
    // The fridge in the kitchen: not in view from the living room, one walk away.
    let (reason, _) = why(&t, s, 23, 14);
    assert_eq!(reason, Reason::NotInView);
    assert_eq!(
        reach::reach(&t, s, robot(&t, 23), node(&t, 14)),
        Reach::After(1)
    );
}

#[test]
fn a_quadrotor_is_told_it_cannot_land_on_what_is_no_surface() {
    // env0 task 1: the quadrotor (22) can fly to the living room, but the sunglasses are
    // nothing to land on; the reason it gives is that one, not "take off first".
    let t = task("env0", 1);
    let why = reach::why_not(&t, &t.init, robot(&t, 22), node(&t, 55)).expect("a reason");
    assert_eq!(why.reason, Reason::NotLandable, "{}", why.message);
}

#[test]
fn things_named_are_the_task_s_nodes_written_as_labels() {
    let t = task("env0", 1);
    let named = reach::things_named(
        &t,
        "grab the <sunglasses>(55) from the <dining table>(13), then the <sunglasses>(55) \
         again; <robot arm>(24) helps; <ghost>(13) and <sunglasses>(999) are nothing",
    );
    assert_eq!(named, vec![node(&t, 55), node(&t, 13)]);
}

/// On every released task's initial state, for every robot and node: no reason exactly
/// when the robot can act on it now, and every reason one of the rules' own.
#[test]
fn a_reason_is_given_exactly_when_the_robot_cannot_act_now() {
    for t in common::released_tasks() {
        for &r in &t.robots {
            for i in 0..t.nodes.len() {
                let x = Idx(i as u16);
                if t.robot_by_id(t.id(x)).is_ok() {
                    continue;
                }
                let why = reach::why_not(&t, &t.init, r, x);
                let now = reach::reach(&t, &t.init, r, x) == Reach::Now;
                let grabable = t
                    .node(x)
                    .properties
                    .contains(coherent_core::PropSet::GRABABLE);
                // A quadrotor gets at a grabable thing through the surface under it.
                if !(r.kind == coherent_core::RobotKind::Quadrotor && grabable) {
                    assert_eq!(
                        why.is_none(),
                        now,
                        "{} robot {} node {}: {why:?}",
                        common::name(&t),
                        t.id(r.node),
                        t.id(x)
                    );
                }
                if let Some(why) = why {
                    assert!(
                        Reason::ALL[..28].contains(&why.reason),
                        "{}: {:?}",
                        common::name(&t),
                        why.reason
                    );
                }
            }
        }
    }
}
