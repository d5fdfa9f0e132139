//! Import is lossless: for every task of the four released files,
//! original -> Task -> native JSON -> Task and original -> Task -> original JSON -> Task
//! give back the same Task.

use coherent_core::{Task, load, native, original};
use serde_json::{Value, json};

mod common;

struct Scene {
    /// The file name as given to the loader (and kept in the tasks' source).
    file: String,
    scene: String,
    /// The file's JSON list as released.
    list: Vec<Value>,
    /// Each element of the list, read.
    tasks: Vec<coherent_core::Result<Task>>,
}

fn scenes() -> Vec<Scene> {
    (0..4)
        .map(|n| {
            let path = common::data_dir().join(format!("env{n}.json"));
            let file = path.display().to_string();
            let list = common::original_list(n);
            let tasks = load::read_tasks(&path).expect("benchmark file loads");
            assert_eq!(tasks.len(), list.len());
            Scene {
                file,
                scene: format!("env{n}"),
                list,
                tasks,
            }
        })
        .collect()
}

/// The only known malformed task: env3, index 18 (duplicate node id 24).
fn expect_well_formed(scene: &Scene, i: usize, t: &coherent_core::Result<Task>) -> bool {
    match t {
        Ok(_) => {
            assert!(
                !(scene.scene == "env3" && i == 18),
                "env3[18] should be malformed"
            );
            true
        }
        Err(e) => {
            assert!(
                scene.scene == "env3" && i == 18,
                "{}[{i}] is malformed: {e}",
                scene.scene
            );
            false
        }
    }
}

#[test]
fn all_tasks_load_except_env3_18() {
    let scenes = scenes();
    let loaded: usize = scenes
        .iter()
        .map(|s| s.tasks.iter().filter(|t| t.is_ok()).count())
        .sum();
    let total: usize = scenes.iter().map(|s| s.tasks.len()).sum();
    assert_eq!(total, 82);
    assert_eq!(loaded, 81);
    for s in &scenes {
        for (i, t) in s.tasks.iter().enumerate() {
            if expect_well_formed(s, i, t) {
                let t = t.as_ref().expect("checked");
                assert_eq!(t.meta.scene, s.scene);
                let source = t
                    .meta
                    .source
                    .as_ref()
                    .expect("imported tasks keep their source");
                assert_eq!(source.index, i);
                assert_eq!(source.file, format!("{}.json", s.scene));
                assert_eq!(source.format, original::FORMAT);
                assert_eq!(Some(t.meta.task_id), s.list[i]["task_id"].as_i64());
            }
        }
    }
}

#[test]
fn original_to_native_to_task_is_identity() {
    let mut checked = 0;
    for s in scenes() {
        for (i, t) in s.tasks.iter().enumerate() {
            if !expect_well_formed(&s, i, t) {
                continue;
            }
            let task = t.as_ref().expect("checked");
            let value = native::to_value(task);
            assert_eq!(value["format"], native::FORMAT);

            // Through the format-detecting reader.
            let name = format!("{}/task-{:03}.json", s.scene, task.meta.task_id);
            let mut back =
                load::read_value(&name, "ignored-for-native", &value).unwrap_or_else(|e| {
                    panic!("{}[{i}]: native JSON does not read back: {e}", s.scene)
                });
            assert_eq!(back.len(), 1);
            let back = back
                .remove(0)
                .unwrap_or_else(|e| panic!("{}[{i}]: native JSON is malformed: {e}", s.scene));
            assert_eq!(
                &back, task,
                "{}[{i}]: native round trip changed the task",
                s.scene
            );

            // Directly, and through text (what `coherent import` writes).
            let text = serde_json::to_string_pretty(&value).expect("JSON serializes");
            let reparsed: Value = serde_json::from_str(&text).expect("written JSON parses");
            let direct = native::read(&name, &reparsed).unwrap_or_else(|e| {
                panic!("{}[{i}]: native text does not read back: {e}", s.scene)
            });
            assert_eq!(
                &direct, task,
                "{}[{i}]: native text round trip changed the task",
                s.scene
            );

            // Exporting again gives the same JSON.
            assert_eq!(
                native::to_value(&direct),
                value,
                "{}[{i}]: native export is stable",
                s.scene
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 81);
}

#[test]
fn original_to_original_to_task_is_identity() {
    let mut checked = 0;
    for s in scenes() {
        // Re-export every well-formed task in place, so that each keeps its index in the
        // list (part of its source); the malformed one stays as released.
        let mut list = s.list.clone();
        for (i, t) in s.tasks.iter().enumerate() {
            if let Ok(task) = t {
                list[i] = original::to_value(task);
            }
        }
        let exported = Value::Array(list);
        // Through text, as a file would be written.
        let text = serde_json::to_string(&exported).expect("JSON serializes");
        let reparsed: Value = serde_json::from_str(&text).expect("written JSON parses");
        let back = load::read_value(&s.file, &s.scene, &reparsed)
            .unwrap_or_else(|e| panic!("{}: exported list does not read back: {e}", s.scene));
        assert_eq!(back.len(), s.tasks.len());
        for (i, (t, b)) in s.tasks.iter().zip(&back).enumerate() {
            if !expect_well_formed(&s, i, t) {
                assert!(b.is_err(), "{}[{i}] stays malformed", s.scene);
                continue;
            }
            let task = t.as_ref().expect("checked");
            let b = b
                .as_ref()
                .unwrap_or_else(|e| panic!("{}[{i}]: exported task is malformed: {e}", s.scene));
            assert_eq!(
                b, task,
                "{}[{i}]: original round trip changed the task",
                s.scene
            );
            // And exporting again is stable.
            assert_eq!(original::to_value(b), original::to_value(task));
            checked += 1;
        }
    }
    assert_eq!(checked, 81);
}

/// Sorts the `properties` and `states` lists of every node, the only place where the
/// export may reorder what the file says.
fn normalise(task: &Value) -> Value {
    let mut t = task.clone();
    if let Some(nodes) = t["init_graph"]["nodes"].as_array_mut() {
        for n in nodes {
            for key in ["properties", "states"] {
                if let Some(list) = n[key].as_array_mut() {
                    list.sort_by_key(|v| v.to_string());
                }
            }
        }
    }
    t
}

/// The original export gives back the released JSON itself, up to the order of each
/// node's properties and states (sets, written in a fixed order).
#[test]
fn original_export_matches_released_json() {
    let mut verbatim = 0;
    let mut checked = 0;
    for s in scenes() {
        for (i, t) in s.tasks.iter().enumerate() {
            if !expect_well_formed(&s, i, t) {
                continue;
            }
            let task = t.as_ref().expect("checked");
            let exported = original::to_value(task);
            let released = &s.list[i];
            for key in [
                "task_id",
                "task_name",
                "env_id",
                "task_goal",
                "ground_truth_step_num",
                "goal_instruction",
            ] {
                assert_eq!(exported[key], released[key], "{}[{i}].{key}", s.scene);
            }
            assert_eq!(
                normalise(&exported),
                normalise(released),
                "{}[{i}]: export differs from the released task",
                s.scene
            );
            if &exported == released {
                verbatim += 1;
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 81);
    eprintln!(
        "{verbatim} of {checked} tasks export verbatim (the others reorder properties or states)"
    );
}

#[test]
fn native_json_of_env0_task0_by_value() {
    let s = scenes().swap_remove(0);
    let task = s.tasks[0].as_ref().expect("env0[0] loads");
    let released = &s.list[0];
    let v = native::to_value(task);
    let keys: Vec<&str> = v
        .as_object()
        .expect("an object")
        .keys()
        .map(String::as_str)
        .collect();
    assert_eq!(
        keys,
        [
            "format",
            "version",
            "scene",
            "task_id",
            "name",
            "rules",
            "instruction",
            "goal",
            "ground_truth",
            "robots",
            "graph",
            "source"
        ]
    );
    assert_eq!(v["format"], json!("coherent-task"));
    assert_eq!(v["version"], json!(1));
    assert_eq!(v["scene"], json!("env0"));
    assert_eq!(v["task_id"], json!(0));
    assert_eq!(v["name"], released["task_name"]);
    assert_eq!(v["rules"], json!("compatible"));
    assert_eq!(v["instruction"], released["goal_instruction"][0]);
    assert_eq!(
        v["goal"],
        json!([{"relation": "ON", "subject": 22, "target": 35, "count": 1}])
    );
    assert_eq!(v["ground_truth"], json!({"steps": 5}));
    assert_eq!(
        v["robots"],
        json!([
            {"id": 22, "type": "quadrotor"},
            {"id": 23, "type": "robot dog"},
            {"id": 24, "type": "robot arm"},
            {"id": 50, "type": "robot arm"}
        ])
    );
    assert_eq!(
        v["source"],
        json!({"format": "coherent-original", "file": "env0.json", "index": 0, "env_id": released["env_id"]})
    );
    assert!(
        v.get("geometry").is_none(),
        "no geometry is written when there is none"
    );
    // The graph is the released one: same nodes (up to property order), same edges in
    // the same order.
    let graph = &v["graph"];
    assert_eq!(graph["edges"], released["init_graph"]["edges"]);
    assert_eq!(
        graph["nodes"].as_array().map(Vec::len),
        released["init_graph"]["nodes"].as_array().map(Vec::len)
    );
    let wrapped = |g: &Value| normalise(&json!({"init_graph": g}));
    assert_eq!(wrapped(graph), wrapped(&released["init_graph"]));
    assert_eq!(
        graph["nodes"][0],
        json!({
            "id": 0, "category": "Rooms", "class_name": "bedroom", "prefab_name": "bedroom_0",
            "properties": [], "states": []
        })
    );
    assert_eq!(
        graph["edges"][0],
        json!({"from_id": 1, "to_id": 0, "relation_type": "INSIDE"})
    );
}
