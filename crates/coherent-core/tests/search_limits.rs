//! The planner's bounds on a task built to explode: one room, a robot dog, a few tables
//! and eight objects it may shuffle between them (some 4^8 x the dog's places states),
//! with a goal no shuffle reaches (the first object on two tables at once). Every
//! search must stop at its bound, and `validate` must say the goal was not decided.

use coherent_core::planner::{self, Limits, Stop};
use coherent_core::{Task, load, validate};
use serde_json::{Value, json};

const TABLES: i64 = 3;
const OBJECTS: i64 = 8;

fn exploding_task() -> Task {
    let mut nodes = vec![
        json!({"id": 1, "category": "Rooms", "class_name": "hall", "properties": [], "states": []}),
        json!({"id": 2, "category": "Floor", "class_name": "hall floor",
               "properties": ["SURFACES", "LOW_HEIGHT"], "states": []}),
        json!({"id": 3, "category": "Agents", "class_name": "robot dog",
               "properties": ["MOVABLE"], "states": []}),
    ];
    let mut edges = vec![
        json!({"from_id": 2, "to_id": 1, "relation_type": "INSIDE"}),
        json!({"from_id": 3, "to_id": 2, "relation_type": "ON"}),
        json!({"from_id": 3, "to_id": 1, "relation_type": "INSIDE"}),
    ];
    for t in 0..TABLES {
        nodes.push(
            json!({"id": 10 + t, "category": "Furniture", "class_name": "table",
                          "properties": ["SURFACES", "LOW_HEIGHT"], "states": []}),
        );
        edges.push(json!({"from_id": 10 + t, "to_id": 2, "relation_type": "ON"}));
    }
    let mut goal = serde_json::Map::new();
    for o in 0..OBJECTS {
        nodes.push(
            json!({"id": 100 + o, "category": "Props", "class_name": "cup",
                          "properties": ["GRABABLE", "MOVABLE"], "states": []}),
        );
        edges.push(json!({"from_id": 100 + o, "to_id": 10, "relation_type": "ON"}));
        goal.insert(format!("on_<cup>({})_<table>(11)", 100 + o), json!([1, []]));
    }
    // The first cup on a second table too: an object stands on one thing at a time.
    goal.insert("on_<cup>(100)_<table>(12)".to_owned(), json!([1, []]));
    let task = json!({
        "task_id": 0,
        "task_name": "explode",
        "init_graph": {"nodes": nodes, "edges": edges},
        "task_goal": goal,
        "ground_truth_step_num": [40],
        "goal_instruction": ["Put every cup on the second table, and the first on the third too."],
    });
    load::read_value("explode.json", "explode", &Value::Array(vec![task]))
        .expect("a list of tasks")
        .pop()
        .expect("one task")
        .expect("well-formed")
}

/// At the state limit the search stops with exactly that many states, and `validate`
/// says the goal was not decided rather than that it cannot be reached.
#[test]
fn an_exploding_task_stops_at_the_state_limit() {
    let task = exploding_task();
    let limits = Limits::max_states(20_000);
    let found = planner::search(&task, &task.robots, &task.goal, &limits);
    assert!(found.plan.is_none() && found.truncated, "{found:?}");
    assert_eq!(found.stop, Some(Stop::States));
    assert_eq!(found.states_seen, 20_000);
    let analysis = planner::analyse(&task, &limits);
    let findings = validate::findings(&task, &analysis);
    assert!(
        findings.iter().any(|f| f.starts_with(
            "the goal could not be decided within the search limits: search stopped at the limit of 20000 states"
        )),
        "{findings:#?}"
    );
    assert!(
        !findings.iter().any(|f| f.contains("cannot be reached")),
        "{findings:#?}"
    );
}

/// Before its tables outgrow the memory limit the search stops, with its estimate of
/// them within the limit, and says so.
#[test]
fn an_exploding_task_stops_at_the_memory_limit() {
    let task = exploding_task();
    let limits = Limits {
        max_memory: 4 << 20,
        ..Limits::max_states(usize::MAX)
    };
    let found = planner::search(&task, &task.robots, &task.goal, &limits);
    assert!(found.plan.is_none(), "{found:?}");
    assert_eq!(found.stop, Some(Stop::Memory));
    assert!(found.memory <= 4 << 20, "{} bytes", found.memory);
    // The estimate counts at least each state's words.
    let words = task.init.edges().len() + task.nodes.len();
    assert!(
        found.memory >= found.states_seen * words * 4,
        "{} bytes for {} states of {words} words",
        found.memory,
        found.states_seen
    );
    assert!(found.states_seen > 1_000, "{found:?}");
    let analysis = planner::analyse(&task, &limits);
    assert_eq!(analysis.stop, Some(Stop::Memory));
    let reason = analysis.reason.as_deref().unwrap_or_default();
    assert!(
        reason.starts_with("search stopped at the memory limit of 4 MiB ("),
        "{reason}"
    );
    let findings = validate::findings(&task, &analysis);
    assert!(
        findings
            .iter()
            .any(|f| f.starts_with("the goal could not be decided within the search limits")),
        "{findings:#?}"
    );
}
