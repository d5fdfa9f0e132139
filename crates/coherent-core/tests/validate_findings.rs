//! Semantic problems `validate::findings` must name: each test breaks one thing in a
//! real task (env0 task 0) and checks the message, and the untouched task is clean.

use coherent_core::planner::{self, Limits};
use coherent_core::{Task, load, validate};
use serde_json::{Value, json};

mod common;

fn findings(task: Value) -> Vec<String> {
    let task: Task = load::read_value("test.json", "env0", &Value::Array(vec![task]))
        .expect("a list of tasks")
        .pop()
        .expect("one task")
        .expect("well-formed");
    let analysis = planner::analyse(&task, &Limits::max_states(200_000));
    validate::findings(&task, &analysis)
}

fn node_mut(task: &mut Value, id: i64) -> &mut Value {
    task["init_graph"]["nodes"]
        .as_array_mut()
        .expect("nodes")
        .iter_mut()
        .find(|n| n["id"] == id)
        .expect("node exists")
}

fn edges_mut(task: &mut Value) -> &mut Vec<Value> {
    task["init_graph"]["edges"].as_array_mut().expect("edges")
}

fn assert_names(found: &[String], expected: &str) {
    assert!(
        found.iter().any(|f| f.contains(expected)),
        "expected {expected:?} among {found:#?}"
    );
}

#[test]
fn the_released_task_is_clean() {
    assert_eq!(
        findings(common::original_list(0).swap_remove(0)),
        Vec::<String>::new()
    );
}

#[test]
fn a_grabable_door() {
    let mut t = common::original_list(0).swap_remove(0);
    node_mut(&mut t, 8)["properties"]
        .as_array_mut()
        .expect("list")
        .push(json!("GRABABLE"));
    assert_names(&findings(t), "<door>(8): a room or door that is GRABABLE");
}

#[test]
fn a_floor_that_is_no_surface() {
    let mut t = common::original_list(0).swap_remove(0);
    node_mut(&mut t, 7)["properties"] = json!(["LANDABLE", "LOW_HEIGHT"]);
    assert_names(
        &findings(t),
        "<kitchen floor>(7): a floor that is not a surface (no SURFACES)",
    );
}

#[test]
fn a_robot_in_no_room() {
    let mut t = common::original_list(0).swap_remove(0);
    edges_mut(&mut t).retain(|e| !(e["from_id"] == 23 && e["relation_type"] == "INSIDE"));
    assert_names(
        &findings(t),
        "<robot dog>(23): a robot must be INSIDE exactly one room, this one is in 0",
    );
}

#[test]
fn a_quadrotor_without_basket_or_flight_state() {
    let mut t = common::original_list(0).swap_remove(0);
    edges_mut(&mut t).retain(|e| e["relation_type"] != "WITH");
    node_mut(&mut t, 22)["states"] = json!([]);
    let found = findings(t);
    assert_names(
        &found,
        "<quadrotor>(22): a quadrotor without a basket (no WITH edge)",
    );
    assert_names(
        &found,
        "<quadrotor>(22): a quadrotor that is neither LAND nor FLYING can never act",
    );
}

#[test]
fn an_arm_on_nothing() {
    let mut t = common::original_list(0).swap_remove(0);
    edges_mut(&mut t).retain(|e| !(e["from_id"] == 24 && e["relation_type"] == "ON"));
    assert_names(
        &findings(t),
        "<robot arm>(24): a robot arm that stands ON no surface reaches nothing",
    );
}

#[test]
fn a_closed_basket() {
    let mut t = common::original_list(0).swap_remove(0);
    node_mut(&mut t, 25)["states"] = json!(["CLOSED"]);
    assert_names(
        &findings(t),
        "<basket>(25): a basket must be an open container (CONTAINERS, OPEN_FOREVER)",
    );
}

#[test]
fn an_object_in_two_places() {
    let mut t = common::original_list(0).swap_remove(0);
    edges_mut(&mut t).push(json!({"from_id": 29, "to_id": 12, "relation_type": "ON"}));
    assert_names(&findings(t), "<socks>(29): an object in 2 places at once");
}

#[test]
fn high_and_low_at_once() {
    let mut t = common::original_list(0).swap_remove(0);
    node_mut(&mut t, 13)["properties"]
        .as_array_mut()
        .expect("list")
        .push(json!("LOW_HEIGHT"));
    assert_names(
        &findings(t),
        "<dining table>(13): both HIGH_HEIGHT and LOW_HEIGHT",
    );
}

#[test]
fn openable_without_an_open_or_closed_state() {
    let mut t = common::original_list(0).swap_remove(0);
    node_mut(&mut t, 14)["states"] = json!([]);
    assert_names(
        &findings(t),
        "<fridge>(14): CAN_OPEN, but neither OPEN, CLOSED nor OPEN_FOREVER",
    );
}

#[test]
fn a_door_to_one_room_and_a_room_without_floor() {
    let mut t = common::original_list(0).swap_remove(0);
    edges_mut(&mut t).retain(|e| !(e["from_id"] == 8 && e["to_id"] == 0));
    edges_mut(&mut t).retain(|e| !(e["from_id"] == 1 && e["relation_type"] == "INSIDE"));
    let found = findings(t);
    assert_names(
        &found,
        "<door>(8): a door must lead to 2 rooms, this one leads to 1",
    );
    assert_names(&found, "<bedroom>(0): a room with no floor");
}

#[test]
fn an_edge_listed_twice() {
    let mut t = common::original_list(0).swap_remove(0);
    let first = edges_mut(&mut t)[0].clone();
    edges_mut(&mut t).push(first);
    assert_names(&findings(t), "1 edges are listed more than once");
}

#[test]
fn a_goal_that_holds_at_the_start_and_a_count_that_never_can() {
    let mut t = common::original_list(0).swap_remove(0);
    t["task_goal"] = json!({"on_<socks>(29)_<sofa>(11)": [1, []]});
    assert_names(
        &findings(t.clone()),
        "the goal already holds at the start: on_<socks>(29)_<sofa>(11)",
    );
    t["task_goal"] = json!({"on_<socks>(29)_<bed>(27)": [2, []]});
    assert_names(&findings(t), "asks for 2 such edges, but edges form a set");
}

/// A ground truth no task can need is flagged with the limit; 2 x 2147483648 and
/// 2 x 4294967295 wrap around in 32 bits (to 0 and 4294967294), so no budget is sized
/// from them.
#[test]
fn a_ground_truth_beyond_any_task() {
    for gt in [2_147_483_648_u64, 4_294_967_295, 10_001] {
        let mut t = common::original_list(0).swap_remove(0);
        t["ground_truth_step_num"] = json!([gt]);
        let found = findings(t.clone());
        assert_names(&found, &format!("ground truth says {gt} steps"));
        assert_names(&found, "at most 10000");
        let task = load::read_value("test.json", "env0", &Value::Array(vec![t]))
            .expect("a list of tasks")
            .pop()
            .expect("one task")
            .expect("well-formed");
        let budget = task.meta.twice_ground_truth().expect("a ground truth");
        assert!(budget.is_err(), "{gt}: {budget:?}");
    }
    let mut t = common::original_list(0).swap_remove(0);
    t["ground_truth_step_num"] = json!([10_000]);
    assert_eq!(findings(t), Vec::<String>::new());
}
