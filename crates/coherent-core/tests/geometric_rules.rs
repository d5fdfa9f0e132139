//! The geometric rule set: height labels come from geometry and robot specs (tall
//! furniture is judged by the place it offers), hand-set labels are refused with their
//! JSON path, and a fixed arm's put-down is high only where the place is.

use coherent_core::{NodeId, PropSet, Task, native, rules};
use serde_json::{Value, json};

/// A kitchen: a 1.10 m counter with an arm and a mug, a 0.75 m table, a 0.30 m tall
/// bottle on the table, a legged robot. The tallest movable thing is the bottle, so the
/// counter (1.10 + 0.30 > 1.34 m, the legged robot's hand) is high and the table
/// (0.75 + 0.30) is low.
fn kitchen() -> Value {
    json!({
        "format": "coherent-task", "version": 1, "scene": "kitchen", "task_id": 0,
        "rules": "geometric",
        "instruction": "Put the mug on the table.",
        "goal": [{"relation": "ON", "subject": 4, "target": 3}],
        "robots": [{"id": 5, "type": "robot arm"}, {"id": 7, "type": "robot dog"}],
        "graph": {
            "nodes": [
                {"id": 0, "category": "Rooms", "class_name": "kitchen"},
                {"id": 1, "category": "Floor", "class_name": "kitchen floor",
                 "properties": ["SURFACES", "LANDABLE"]},
                {"id": 2, "category": "Furniture", "class_name": "counter",
                 "properties": ["SURFACES"]},
                {"id": 3, "category": "Furniture", "class_name": "table",
                 "properties": ["SURFACES"]},
                {"id": 4, "category": "Tableware", "class_name": "mug",
                 "properties": ["GRABABLE", "MOVABLE"]},
                {"id": 5, "category": "Agents", "class_name": "robot arm"},
                {"id": 6, "category": "Drinks", "class_name": "bottle",
                 "properties": ["GRABABLE", "MOVABLE"]},
                {"id": 7, "category": "Agents", "class_name": "robot dog",
                 "properties": ["MOVABLE"]}
            ],
            "edges": [
                {"from_id": 1, "to_id": 0, "relation_type": "INSIDE"},
                {"from_id": 2, "to_id": 1, "relation_type": "ON"},
                {"from_id": 3, "to_id": 1, "relation_type": "ON"},
                {"from_id": 4, "to_id": 2, "relation_type": "ON"},
                {"from_id": 5, "to_id": 2, "relation_type": "ON"},
                {"from_id": 5, "to_id": 0, "relation_type": "INSIDE"},
                {"from_id": 6, "to_id": 3, "relation_type": "ON"},
                {"from_id": 7, "to_id": 1, "relation_type": "ON"},
                {"from_id": 7, "to_id": 0, "relation_type": "INSIDE"}
            ]
        },
        "geometry": {
            "rooms": [{"id": 0, "min": [0, 0], "max": [5, 4]}],
            "doors": [],
            "items": [
                {"id": 2, "pos": [1.5, 0, 0.6], "size": [1.7, 1.1, 1.0],
                 "container": false, "lid": "none", "dynamic": false},
                {"id": 3, "pos": [2.1, 0, 1.6], "size": [1.2, 0.75, 0.6],
                 "container": false, "lid": "none", "dynamic": false},
                {"id": 4, "pos": [1.2, 1.1, 0.4], "size": [0.09, 0.1, 0.09],
                 "container": false, "lid": "none", "dynamic": true},
                {"id": 6, "pos": [1.8, 0.75, 1.6], "size": [0.08, 0.3, 0.08],
                 "container": false, "lid": "none", "dynamic": true}
            ],
            "robots": [
                {"id": 5, "pos": [1.5, 1.1, 0.95]},
                {"id": 7, "pos": [3.5, 0, 3.0]}
            ]
        }
    })
}

fn read(value: &Value) -> coherent_core::Result<Task> {
    native::read("kitchen.json", value)
}

fn idx(task: &Task, id: i64) -> coherent_core::Idx {
    task.idx(NodeId(id)).expect("the node exists")
}

#[test]
fn heights_come_from_geometry_and_specs() {
    let task = read(&kitchen()).expect("the kitchen reads");
    let props = |id| task.node(idx(&task, id)).properties;
    assert!(
        props(2).contains(PropSet::HIGH_HEIGHT),
        "the counter is high"
    );
    assert!(props(3).contains(PropSet::LOW_HEIGHT), "the table is low");
    assert!(props(1).contains(PropSet::LOW_HEIGHT), "the floor is low");
    assert!(
        task.init.on_high_surface(idx(&task, 4)),
        "the mug is on the counter"
    );
    assert!(
        !task.init.on_high_surface(idx(&task, 6)),
        "the bottle is on the table"
    );

    // Raise the table to 1.05 m: with the 0.30 m bottle it is out of reach now.
    let mut high_table = kitchen();
    high_table["geometry"]["items"][1]["size"][1] = json!(1.05);
    high_table["geometry"]["items"][3]["pos"][1] = json!(1.05);
    let task = read(&high_table).expect("it reads");
    assert!(
        task.node(idx(&task, 3))
            .properties
            .contains(PropSet::HIGH_HEIGHT)
    );
    assert!(task.init.on_high_surface(idx(&task, 6)));

    // A longer arm on the legged robot brings it back in reach.
    high_table["geometry"]["specs"] = json!({"dog_links": [0.5, 0.5]});
    let task = read(&high_table).expect("it reads");
    assert!(
        task.node(idx(&task, 3))
            .properties
            .contains(PropSet::LOW_HEIGHT)
    );
}

/// A wardrobe 1.90 m tall is taller than the legged robot's hand, but what it offers is
/// its inner floor: it is low, not out of reach, and the robot may walk to it and open
/// it. A movable thing is judged by its own top.
#[test]
fn tall_furniture_is_not_out_of_reach_for_being_tall() {
    let mut v = kitchen();
    v["graph"]["nodes"]
        .as_array_mut()
        .expect("nodes")
        .push(json!(
            {"id": 8, "category": "Furniture", "class_name": "wardrobe",
             "properties": ["CONTAINERS", "CAN_OPEN"], "states": ["CLOSED"]}
        ));
    v["graph"]["edges"]
        .as_array_mut()
        .expect("edges")
        .push(json!(
            {"from_id": 8, "to_id": 1, "relation_type": "ON"}
        ));
    v["geometry"]["items"]
        .as_array_mut()
        .expect("items")
        .push(json!(
            {"id": 8, "pos": [4.4, 0, 0.4], "size": [1.0, 1.9, 0.6],
             "container": true, "lid": "front", "dynamic": false}
        ));
    let task = read(&v).expect("the kitchen with a wardrobe reads");
    let wardrobe = idx(&task, 8);
    assert!(task.node(wardrobe).properties.contains(PropSet::LOW_HEIGHT));
    assert!(!task.init.on_high_surface(wardrobe));
    let dog = *task
        .robots
        .iter()
        .find(|r| r.node == idx(&task, 7))
        .expect("the dog is a robot");
    let moves: Vec<String> = rules::actions(&task, &task.init, dog)
        .iter()
        .map(|a| a.render(&task))
        .collect();
    assert!(
        moves.contains(&"[movetowards] <wardrobe>(8)".to_owned()),
        "{moves:?}"
    );

    // A movable thing standing on the floor (always low) whose own top is above the
    // hand is out of reach: a bottle 1.5 m tall.
    let mut tall_bottle = kitchen();
    tall_bottle["graph"]["edges"][6]["to_id"] = json!(1);
    tall_bottle["geometry"]["items"][3]["pos"][1] = json!(0.0);
    tall_bottle["geometry"]["items"][3]["size"][1] = json!(1.5);
    let task = read(&tall_bottle).expect("it reads");
    assert!(task.init.on_high_surface(idx(&task, 6)));
}

#[test]
fn hand_set_height_labels_are_refused_with_their_path() {
    let mut v = kitchen();
    v["graph"]["nodes"][2]["properties"] = json!(["SURFACES", "HIGH_HEIGHT"]);
    let e = read(&v).expect_err("refused").to_string();
    assert!(
        e.starts_with("kitchen.json: $.graph.nodes[2].properties: <counter>(2): HIGH_HEIGHT comes from the geometry"),
        "{e}"
    );

    let mut v = kitchen();
    v.as_object_mut().expect("an object").remove("geometry");
    let e = read(&v).expect_err("refused").to_string();
    assert!(
        e.starts_with("kitchen.json: $.rules: the geometric rule set"),
        "{e}"
    );

    // An arm that cannot reach what starts on its table.
    let mut v = kitchen();
    v["geometry"]["items"][2]["pos"] = json!([0.0, 1.1, -1.5]);
    let e = read(&v).expect_err("refused").to_string();
    assert!(
        e.starts_with("kitchen.json: $.geometry.items[2].pos: <mug>(4)"),
        "{e}"
    );
}

#[test]
fn written_files_leave_the_derived_labels_out_and_read_back_equal() {
    let task = read(&kitchen()).expect("the kitchen reads");
    let written = native::to_value(&task);
    let text = written["graph"].to_string();
    assert!(
        !text.contains("HIGH_HEIGHT") && !text.contains("LOW_HEIGHT"),
        "{text}"
    );
    assert_eq!(read(&written).expect("it reads back"), task);
}

#[test]
fn what_the_arm_puts_on_a_low_table_is_within_the_legged_robots_reach() {
    let mut v = kitchen();
    // The arm's counter lowered to 0.75 m: low, so the legged robot reaches what is on it.
    v["geometry"]["items"][0]["size"][1] = json!(0.75);
    v["geometry"]["items"][2]["pos"][1] = json!(0.75);
    v["geometry"]["robots"][0]["pos"][1] = json!(0.75);
    let task = read(&v).expect("it reads");
    let (arm, dog) = (task.robots[0], task.robots[1]);
    let mug = idx(&task, 4);
    let counter = idx(&task, 2);
    let mut s = task.init.clone();
    let approach = |s: &coherent_core::State| {
        rules::actions(&task, s, dog)
            .iter()
            .any(|a| a.object == mug && a.verb == coherent_core::Verb::MoveTowards)
    };
    assert!(
        approach(&s),
        "the mug starts within the legged robot's reach"
    );
    let grab = *rules::actions(&task, &s, arm)
        .iter()
        .find(|a| a.object == mug)
        .expect("the arm may grab the mug");
    rules::apply(&task, &mut s, arm, grab);
    let put = *rules::actions(&task, &s, arm)
        .iter()
        .find(|a| a.target == Some(counter))
        .expect("the arm may put the mug back on its counter");
    rules::apply(&task, &mut s, arm, put);
    assert!(
        !s.on_high_surface(mug),
        "compatible rules would mark it high"
    );
    assert!(approach(&s), "and it is still within reach");
}
