//! Two storeys: a hall and a kitchen on the ground floor, a bedroom 3 m up, joined by a
//! flight of stairs in the hall. The legged robot carries a book up the stairs and
//! down again, the quadrotor flies a cup up the stairwell, a scene without usable
//! stairs is refused, and two runs give bit-identical final poses.

use std::sync::Arc;

use coherent_core::planner::{self, Limits};
use coherent_core::{Task, native};
use coherent_sim::{PlanReport, execute_plan, layout, render};
use serde_json::{Value, json};

fn node(id: i64, category: &str, class: &str, properties: &[&str], states: &[&str]) -> Value {
    json!({
        "id": id,
        "category": category,
        "class_name": class,
        "prefab_name": class.replace(' ', "_"),
        "properties": properties,
        "states": states,
    })
}

fn edge(from: i64, rel: &str, to: i64) -> Value {
    json!({"from_id": from, "to_id": to, "relation_type": rel})
}

/// A piece of furniture of the layout: it stays where it is put.
fn fixed(id: i64, pos: [f32; 3], size: [f32; 3]) -> Value {
    json!({"id": id, "pos": pos, "size": size, "container": false, "lid": "none", "dynamic": false})
}

/// An object of the layout that physics moves (a rigid body robots carry).
fn loose(id: i64, pos: [f32; 3], size: [f32; 3]) -> Value {
    json!({"id": id, "pos": pos, "size": size, "container": false, "lid": "none", "dynamic": true})
}

/// The two-storey scene as a native task file with `goal`, under the geometric rules.
fn house(goal: Value) -> Value {
    let nodes = vec![
        node(0, "Rooms", "hall", &[], &[]),
        node(1, "Floor", "hall floor", &["SURFACES", "LANDABLE"], &[]),
        node(2, "Rooms", "kitchen", &[], &[]),
        node(3, "Floor", "kitchen floor", &["SURFACES", "LANDABLE"], &[]),
        node(4, "Rooms", "bedroom", &[], &[]),
        node(5, "Floor", "bedroom floor", &["SURFACES", "LANDABLE"], &[]),
        node(6, "Doors", "door", &["CAN_OPEN"], &["OPEN"]),
        node(7, "Doors", "stairs", &[], &["OPEN"]),
        node(8, "Furniture", "hall table", &["SURFACES"], &[]),
        node(9, "Furniture", "kitchen table", &["SURFACES"], &[]),
        node(10, "Furniture", "bedside table", &["SURFACES"], &[]),
        node(11, "Furniture", "dresser", &["SURFACES", "LANDABLE"], &[]),
        node(12, "Books", "book", &["GRABABLE", "MOVABLE"], &[]),
        node(13, "Tableware", "cup", &["GRABABLE", "MOVABLE"], &[]),
        node(
            14,
            "Agents",
            "quadrotor",
            &["MOVABLE", "FLYABLE", "HAVE_A_BASKET"],
            &["LAND"],
        ),
        node(
            15,
            "AgentTool",
            "basket",
            &["MOVABLE", "CONTAINERS", "WITH_QUADROTOR"],
            &["OPEN_FOREVER"],
        ),
        node(16, "Agents", "robot dog", &["MOVABLE"], &[]),
        node(17, "Agents", "robot arm", &[], &[]),
    ];
    let edges = vec![
        edge(1, "INSIDE", 0),
        edge(3, "INSIDE", 2),
        edge(5, "INSIDE", 4),
        edge(6, "LEADING TO", 0),
        edge(6, "LEADING TO", 2),
        edge(7, "LEADING TO", 0),
        edge(7, "LEADING TO", 4),
        edge(8, "ON", 1),
        edge(9, "ON", 3),
        edge(10, "ON", 5),
        edge(11, "ON", 5),
        edge(12, "ON", 8),
        edge(13, "ON", 9),
        edge(14, "ON", 9),
        edge(14, "INSIDE", 2),
        edge(14, "WITH", 15),
        edge(15, "ON", 9),
        edge(16, "ON", 1),
        edge(16, "INSIDE", 0),
        edge(17, "ON", 9),
        edge(17, "INSIDE", 2),
    ];
    // The bedroom lies over the north part of the hall; the flight runs north along
    // the hall's west wall and arrives through the bedroom's south wall.
    let geometry = json!({
        "rooms": [
            {"id": 0, "min": [0.0, 0.0], "max": [5.0, 9.2]},
            {"id": 2, "min": [5.0, 0.0], "max": [10.0, 6.0]},
            {"id": 4, "min": [0.0, 0.0], "max": [5.0, 3.6], "level": 3.0},
        ],
        "doors": [
            {"id": 6, "rooms": [0, 2], "center": [5.0, 4.5], "along_x": false, "width": 1.1, "height": 2.3},
        ],
        "stairs": [
            {"id": 7, "rooms": [0, 4], "foot": [0.65, 7.8], "head": [0.65, 3.6], "width": 1.1},
        ],
        "items": [
            fixed(8, [3.0, 0.0, 7.0], [1.2, 0.45, 0.6]),
            fixed(9, [7.5, 0.0, 3.0], [1.4, 0.75, 1.0]),
            fixed(10, [3.6, 3.0, 0.9], [1.2, 0.5, 0.6]),
            fixed(11, [1.6, 3.0, 0.9], [1.2, 0.8, 1.1]),
            loose(12, [3.0, 0.452, 7.0], [0.2, 0.05, 0.15]),
            loose(13, [7.1, 0.752, 2.8], [0.08, 0.1, 0.08]),
        ],
        "robots": [
            {"id": 14, "pos": [7.88, 0.75, 2.9]},
            {"id": 16, "pos": [2.5, 0.0, 5.0]},
            {"id": 17, "pos": [7.344, 0.75, 3.35]},
        ],
    });
    json!({
        "format": "coherent-task",
        "version": 1,
        "scene": "two-storey-house",
        "task_id": 0,
        "name": "levels",
        "rules": "geometric",
        "instruction": "",
        "goal": goal,
        "robots": [
            {"id": 14, "type": "quadrotor"},
            {"id": 16, "type": "robot dog"},
            {"id": 17, "type": "robot arm"},
        ],
        "graph": {"nodes": nodes, "edges": edges},
        "geometry": geometry,
    })
}

fn on(subject: i64, target: i64) -> Value {
    json!({"relation": "ON", "subject": subject, "target": target, "count": 1})
}

fn read(file: &Value) -> coherent_core::Result<Task> {
    native::read("two-storey-house.json", file)
}

/// Where node `id` ended up: the position part of its final pose.
fn position(report: &PlanReport, id: i64) -> [f32; 3] {
    let pose = report
        .final_poses
        .iter()
        .find(|(n, _)| n.0 == id)
        .unwrap_or_else(|| panic!("node {id} has a final pose"))
        .1;
    [pose[0], pose[1], pose[2]]
}

/// The task's optimal plan carried out in physics.
fn run(file: &Value) -> (Arc<Task>, Vec<String>, PlanReport) {
    let task = Arc::new(read(file).expect("the two-storey task reads"));
    let plan = planner::analyse(&task, &Limits::default())
        .plan
        .expect("the task is solvable");
    let text = plan
        .iter()
        .map(|s| format!("{} {}", task.node(s.robot).label(), s.action.render(&task)))
        .collect();
    let report = execute_plan(&task, &plan);
    // A picture of the scene with the robots' tracks, on request.
    if let Ok(dir) = std::env::var("COHERENT_LEVELS_SVG_DIR") {
        let layout = layout::for_task(&task).expect("the geometry reads");
        let svg = render::svg(&task, &layout, &task.init, Some(&report.paths));
        let subjects: Vec<String> = task
            .goal
            .iter()
            .map(|g| task.id(g.subject).0.to_string())
            .collect();
        let name = format!("levels-{}.svg", subjects.join("-"));
        std::fs::write(std::path::Path::new(&dir).join(name), svg).expect("the picture is written");
    }
    (task, text, report)
}

/// The book from the hall table to the bedside table upstairs: the legged robot
/// carries it up the flight.
#[test]
fn the_legged_robot_carries_a_book_upstairs() {
    let (task, plan, report) = run(&house(json!([on(12, 10)])));
    assert!(
        plan.iter()
            .any(|s| s.contains("robot dog") && s.contains("bedroom")),
        "{plan:?}"
    );
    assert!(report.physics_ok, "{plan:?}: {:?}", report.physics_error);
    let book = position(&report, 12);
    // On the bedside table, whose top is 3.5 m up.
    assert!((book[1] - 3.5).abs() < 0.03, "the book is at {book:?}");
    // The dog's track climbs from the ground floor to the bedroom's.
    let dog = &report
        .paths
        .iter()
        .find(|(id, _)| id.0 == 16)
        .expect("the dog has a track")
        .1;
    assert!(dog.first().is_some_and(|p| p[1] < 0.1), "{dog:?}");
    assert!(
        dog.last().is_some_and(|p| (p[1] - 3.02).abs() < 0.03),
        "{dog:?}"
    );
    let layout = layout::for_task(&task).expect("the geometry reads");
    let svg = render::svg(&task, &layout, &task.init, Some(&report.paths));
    for text in ["level 0.00 m", "level 3.00 m", "stairs 7 up to 3.00 m"] {
        assert!(svg.contains(text), "no {text:?} in the picture");
    }
    // The dog's track is drawn in both panels, the arrow on the upper one.
    assert_eq!(svg.matches("data-robot=\"16\"").count(), 2);
}

/// The same book brought down: it starts on the bedside table with the legged robot in
/// the bedroom, and goes to the hall table.
#[test]
fn the_legged_robot_carries_a_book_downstairs() {
    let mut file = house(json!([on(12, 8)]));
    for e in file["graph"]["edges"].as_array_mut().expect("edges") {
        match (e["from_id"].as_i64(), e["relation_type"].as_str()) {
            (Some(12), Some("ON")) => e["to_id"] = json!(10),
            (Some(16), Some("ON")) => e["to_id"] = json!(5),
            (Some(16), Some("INSIDE")) => e["to_id"] = json!(4),
            _ => {}
        }
    }
    file["geometry"]["items"][4]["pos"] = json!([3.6, 3.502, 0.9]);
    file["geometry"]["robots"][1]["pos"] = json!([2.5, 3.0, 2.6]);
    let (_, plan, report) = run(&file);
    assert!(report.physics_ok, "{plan:?}: {:?}", report.physics_error);
    let book = position(&report, 12);
    assert!((book[1] - 0.45).abs() < 0.03, "the book is at {book:?}");
}

/// The cup from the kitchen table into the basket and the quadrotor onto the dresser
/// upstairs: it flies up the stairwell and lands on the upper storey.
#[test]
fn the_quadrotor_flies_a_cup_up_the_stairwell() {
    let goal = json!([
        {"relation": "INSIDE", "subject": 13, "target": 15, "count": 1},
        on(15, 11),
    ]);
    let (_, plan, report) = run(&house(goal));
    assert!(
        plan.iter()
            .any(|s| s.contains("quadrotor") && s.contains("bedroom")),
        "{plan:?}"
    );
    assert!(report.physics_ok, "{plan:?}: {:?}", report.physics_error);
    let cup = position(&report, 13);
    // In the basket on the dresser, whose top is 3.8 m up.
    assert!(cup[1] > 3.8 && cup[1] < 4.0, "the cup is at {cup:?}");
}

/// Without its stairs the file is refused; with a flight too steep to climb the world
/// is not built, and the message says why.
#[test]
fn a_scene_without_usable_stairs_is_refused() {
    let mut file = house(json!([on(12, 10)]));
    file["geometry"]["stairs"] = json!([]);
    let e = read(&file).expect_err("refused").to_string();
    assert!(
        e.contains("$.geometry: no entry in doors or stairs for <stairs>(7)"),
        "{e}"
    );

    let mut file = house(json!([on(12, 10)]));
    file["geometry"]["stairs"][0]["foot"] = json!([0.65, 6.6]);
    let (_, _, report) = run(&file);
    assert!(!report.physics_ok);
    let e = report.physics_error.unwrap_or_default();
    assert!(
        e.contains("stairs 7: it rises 3.00 m over a run of 3.00 m; the steepest flight rises 0.75 m per metre"),
        "{e}"
    );
}

#[test]
fn two_runs_up_the_stairs_give_bit_identical_final_poses() {
    let file = house(json!([on(12, 10)]));
    let (_, _, a) = run(&file);
    let (_, _, b) = run(&file);
    assert!(a.physics_ok, "{:?}", a.physics_error);
    assert_eq!(a.final_poses.len(), b.final_poses.len());
    for ((ia, pa), (ib, pb)) in a.final_poses.iter().zip(&b.final_poses) {
        assert_eq!(ia, ib);
        let bits = |p: &[f32; 7]| p.map(f32::to_bits);
        assert_eq!(bits(pa), bits(pb), "{ia:?}");
    }
}
