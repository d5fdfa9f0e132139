//! Explicit geometry: a native task file's `geometry` object is the layout the world is
//! built from, instead of the generated one, and a bad one is refused with its JSON path.

use std::sync::Arc;

use coherent_core::planner::{self, Limits};
use coherent_core::{Task, native};
use coherent_sim::{PhysicalEnv, execute_plan, layout};
use serde_json::Value;

mod common;
use common::demo;

/// `task` with `geometry` in its native file, read back.
fn with_geometry(task: &Task, geometry: Value) -> coherent_core::Result<Task> {
    let mut value = native::to_value(task);
    value["geometry"] = geometry;
    native::read("demo-with-geometry.json", &value)
}

#[test]
fn explicit_geometry_is_the_layout_and_the_plan_runs_on_it() {
    let task = demo();
    let mut layout = layout::generate(&task).expect("a generated layout");
    // Move the coffee table (10) a metre along x: the world must follow the file.
    let table = layout
        .items
        .iter_mut()
        .find(|i| i.id == 10)
        .expect("the coffee table has geometry");
    table.pos[0] += 1.0;
    let geometry = serde_json::to_value(&layout).expect("a layout serializes");
    let task = Arc::new(with_geometry(&task, geometry).expect("the native file reads back"));
    assert_eq!(layout::for_task(&task).expect("the geometry reads"), layout);
    let env = PhysicalEnv::new(Arc::clone(&task)).expect("the world builds");
    assert_eq!(env.layout(), &layout);
    let plan = planner::analyse(&task, &Limits::default())
        .plan
        .expect("the demo is solvable");
    let report = execute_plan(&task, &plan);
    assert!(report.physics_ok, "{:?}", report.physics_error);
}

#[test]
fn bad_geometry_names_its_json_path() {
    let task = demo();
    let mut geometry = serde_json::to_value(layout::generate(&task).expect("a layout"))
        .expect("a layout serializes");
    geometry["items"][0]["size"] = Value::String("big".into());
    let e = with_geometry(&task, geometry)
        .expect_err("refused")
        .to_string();
    assert!(
        e.starts_with("demo-with-geometry.json: $.geometry.items[0].size:"),
        "{e}"
    );

    // Geometry that leaves out a robot is incomplete.
    let mut geometry = serde_json::to_value(layout::generate(&task).expect("a layout"))
        .expect("a layout serializes");
    geometry["robots"] = Value::Array(Vec::new());
    let e = with_geometry(&task, geometry)
        .expect_err("refused")
        .to_string();
    assert!(
        e.starts_with("demo-with-geometry.json: $.geometry: no entry in robots for"),
        "{e}"
    );
}
