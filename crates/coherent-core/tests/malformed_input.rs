//! One test per class of malformed input: the error must be `Error::Malformed`, name
//! the file, the exact JSON path and the offending value. Malformed files are made by
//! corrupting a real task of env0.json and written into a temporary folder.

use std::path::{Path, PathBuf};

use coherent_core::{Error, Task, load, native};
use serde_json::{Value, json};

mod common;

/// Task 0 of env0.json as a JSON value, ready to corrupt.
fn env0_task0() -> Value {
    common::original_list(0).swap_remove(0)
}

/// A temporary folder, removed when dropped.
struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Writes `text` to `<temp>/coherent-malformed-<pid>-<test>/<name>`; the folder goes
/// away with the returned guard.
fn write(test: &str, name: &str, text: &str) -> (TempDir, PathBuf) {
    let dir =
        std::env::temp_dir().join(format!("coherent-malformed-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temporary folder can be created");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("temporary file can be written");
    (TempDir(dir), path)
}

fn write_json(test: &str, name: &str, value: &Value) -> (TempDir, PathBuf) {
    write(
        test,
        name,
        &serde_json::to_string_pretty(value).expect("JSON serializes"),
    )
}

/// The only task of a one-task file, which must be malformed.
fn single_task_error(path: &Path) -> Error {
    let mut tasks = load::read_tasks(path).expect("the file itself is readable JSON");
    assert_eq!(tasks.len(), 1, "one task in {}", path.display());
    match tasks.remove(0) {
        Ok(t) => panic!(
            "task {} of {} loaded, but it is malformed",
            t.meta.task_id,
            path.display()
        ),
        Err(e) => e,
    }
}

/// Asserts that `err` is `Malformed` at `path` in file `file`, and that its message
/// contains every string of `values`. Returns the message.
fn assert_malformed(err: &Error, file: &Path, path: &str, values: &[&str]) -> String {
    let Error::Malformed {
        file: f,
        path: p,
        message,
    } = err
    else {
        panic!("expected Error::Malformed, got {err:?}");
    };
    assert_eq!(
        f,
        &file.display().to_string(),
        "the error names the file: {err}"
    );
    assert_eq!(
        p.to_string(),
        path,
        "the error names the exact JSON path: {err}"
    );
    for v in values {
        assert!(
            message.contains(v),
            "the message names the offending value {v:?}: {err}"
        );
    }
    // The one-line form carries all three.
    let line = err.to_string();
    assert!(
        line.contains(&file.display().to_string()) && line.contains(path),
        "{line}"
    );
    message.clone()
}

/// Index of the first edge of `task` (original format) satisfying `pred`.
fn edge_index(task: &Value, pred: impl Fn(&Value) -> bool) -> usize {
    task["init_graph"]["edges"]
        .as_array()
        .expect("edges is a list")
        .iter()
        .position(pred)
        .expect("such an edge exists")
}

#[test]
fn bad_json_syntax_names_root_and_line_and_column() {
    let (_dir, path) = write(
        "syntax",
        "env0.json",
        "[\n  {\"task_id\": 0,\n   \"task_name\": ,\n  }\n]\n",
    );
    let err = load::read_tasks(&path).expect_err("bad JSON is an error for the whole file");
    let message = assert_malformed(&err, &path, "$", &["line 3", "column"]);
    assert!(message.contains("line 3 column 17"), "{message}");
    // The same through load_tasks.
    assert_eq!(load::load_tasks(&path).expect_err("bad JSON"), err);
}

#[test]
fn truncated_json_is_malformed_at_root() {
    let full = serde_json::to_string(&vec![env0_task0()]).expect("JSON serializes");
    let (_dir, path) = write("truncated", "env0.json", &full[..full.len() / 2]);
    let err = load::read_tasks(&path).expect_err("truncated JSON");
    assert_malformed(&err, &path, "$", &["line 1 column"]);
}

#[test]
fn unknown_node_id_in_edge() {
    let mut task = env0_task0();
    let k = 7;
    task["init_graph"]["edges"][k]["to_id"] = json!(9999);
    let (_dir, path) = write_json("edge-id", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    assert_malformed(
        &err,
        &path,
        &format!("$[0].init_graph.edges[{k}].to_id"),
        &["9999"],
    );

    let mut task = env0_task0();
    task["init_graph"]["edges"][3]["from_id"] = json!(-12);
    let (_dir, path) = write_json("edge-from-id", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$[0].init_graph.edges[3].from_id", &["-12"]);
}

#[test]
fn unknown_relation() {
    let mut task = env0_task0();
    let k = edge_index(&task, |e| e["relation_type"] == "ON");
    task["init_graph"]["edges"][k]["relation_type"] = json!("NEAR BY");
    let (_dir, path) = write_json("relation", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    assert_malformed(
        &err,
        &path,
        &format!("$[0].init_graph.edges[{k}].relation_type"),
        &["\"NEAR BY\""],
    );
}

#[test]
fn duplicate_node_ids() {
    let mut task = env0_task0();
    let first = task["init_graph"]["nodes"][2]["id"].clone();
    task["init_graph"]["nodes"][6]["id"] = first.clone();
    let (_dir, path) = write_json("duplicate", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    let message = assert_malformed(
        &err,
        &path,
        "$[0].init_graph.nodes[6].id",
        &[&format!("duplicate node id {first}")],
    );
    assert!(
        message.contains("nodes[2]"),
        "names the first node with the id: {message}"
    );
}

#[test]
fn goal_naming_a_missing_node() {
    let mut task = env0_task0();
    let key = "on_<apple>(777)_<high kitchen table>(35)";
    task["task_goal"] = json!({ key: [1, []] });
    let (_dir, path) = write_json("goal-node", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    assert_malformed(&err, &path, &format!("$[0].task_goal.{key}"), &["777"]);

    // The target missing, the subject fine.
    let mut task = env0_task0();
    let key = "inside_<quadrotor>(22)_<box>(31337)";
    task["task_goal"] = json!({ key: [1, []] });
    let (_dir, path) = write_json("goal-target", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    assert_malformed(&err, &path, &format!("$[0].task_goal.{key}"), &["31337"]);
}

#[test]
fn unparsable_goal_key() {
    for (i, key) in [
        "near_<quadrotor>(22)_<high kitchen table>(35)",
        "on_<quadrotor>(22)<high kitchen table>(35)",
        "on_<quadrotor>(x)_<high kitchen table>(35)",
        "on_<quadrotor>(22)_<high kitchen table>(35)_",
        "on_",
    ]
    .into_iter()
    .enumerate()
    {
        let mut task = env0_task0();
        task["task_goal"] = json!({ key: [1, []] });
        let (_dir, path) = write_json(&format!("goal-key-{i}"), "env0.json", &json!([task]));
        let err = single_task_error(&path);
        assert_malformed(
            &err,
            &path,
            &format!("$[0].task_goal.{key}"),
            &[&format!("{key:?}")],
        );
    }
}

#[test]
fn bad_goal_count() {
    let mut task = env0_task0();
    let key = "on_<quadrotor>(22)_<high kitchen table>(35)";
    task["task_goal"] = json!({ key: "one" });
    let (_dir, path) = write_json("goal-count", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    assert_malformed(&err, &path, &format!("$[0].task_goal.{key}"), &["\"one\""]);
}

#[test]
fn wrong_field_type() {
    let mut task = env0_task0();
    task["task_id"] = json!("x");
    let (_dir, path) = write_json("field-type", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$[0].task_id", &["\"x\""]);

    // Deeper: a node's properties as a string instead of a list.
    let mut task = env0_task0();
    task["init_graph"]["nodes"][4]["properties"] = json!("SURFACES");
    let (_dir, path) = write_json("field-type-deep", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    assert_malformed(
        &err,
        &path,
        "$[0].init_graph.nodes[4].properties",
        &["\"SURFACES\""],
    );

    // An edge id that is not an integer.
    let mut task = env0_task0();
    task["init_graph"]["edges"][2]["from_id"] = json!(1.5);
    let (_dir, path) = write_json("field-type-edge", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$[0].init_graph.edges[2].from_id", &["1.5"]);
}

#[test]
fn missing_field() {
    let mut task = env0_task0();
    task.as_object_mut()
        .expect("a task is an object")
        .remove("init_graph");
    let (_dir, path) = write_json("missing-field", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$[0]", &["init_graph"]);
}

#[test]
fn one_malformed_task_does_not_hide_the_others() {
    let mut bad = env0_task0();
    bad["init_graph"]["edges"][0]["to_id"] = json!(4242);
    let list = common::original_list(0);
    let good_count = list.len();
    let mut all = list;
    all.insert(1, bad);
    let (_dir, path) = write_json("others", "env0.json", &Value::Array(all));
    let tasks = load::read_tasks(&path).expect("the file is JSON");
    assert_eq!(tasks.len(), good_count + 1);
    for (i, t) in tasks.iter().enumerate() {
        match (i, t) {
            (1, Err(e)) => {
                assert_malformed(e, &path, "$[1].init_graph.edges[0].to_id", &["4242"]);
            }
            (1, Ok(_)) => panic!("task 1 is malformed"),
            (_, Err(e)) => panic!("task {i} is fine but failed: {e}"),
            (_, Ok(_)) => {}
        }
    }
}

#[test]
fn top_level_not_a_list_or_task() {
    let (_dir, path) = write_json("top-level", "env0.json", &json!({"tasks": []}));
    let err = load::read_tasks(&path).expect_err("neither format");
    assert_malformed(&err, &path, "$", &["format"]);
}

/// Task 0 of env0 as a native JSON value, ready to corrupt.
fn native_from_env0() -> Value {
    let path = common::data_dir().join("env0.json");
    let tasks: Vec<Task> = load::read_tasks(&path)
        .expect("env0.json is readable")
        .into_iter()
        .map(|t| t.expect("env0 tasks are well formed"))
        .collect();
    native::to_value(&tasks[0])
}

#[test]
fn native_bad_version() {
    let mut task = native_from_env0();
    task["version"] = json!(2);
    let (_dir, path) = write_json("native-version", "task-000.json", &task);
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$.version", &["2"]);

    let mut task = native_from_env0();
    task["version"] = json!("1");
    let (_dir, path) = write_json("native-version-type", "task-000.json", &task);
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$.version", &["\"1\""]);
}

#[test]
fn native_bad_format_name() {
    let mut task = native_from_env0();
    task["format"] = json!("coherent-tusk");
    let (_dir, path) = write_json("native-format", "task-000.json", &task);
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$.format", &["\"coherent-tusk\""]);
}

#[test]
fn native_unknown_field() {
    let mut task = native_from_env0();
    task["colour"] = json!("red");
    let (_dir, path) = write_json("native-field", "task-000.json", &task);
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$.colour", &["colour"]);

    // Inside a nested object that denies unknown fields too.
    let mut task = native_from_env0();
    task["goal"][0]["weight"] = json!(3);
    let (_dir, path) = write_json("native-field-goal", "task-000.json", &task);
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$.goal[0].weight", &["weight"]);
}

#[test]
fn native_bad_goal_relation() {
    let mut task = native_from_env0();
    task["goal"][0]["relation"] = json!("UNDER");
    let (_dir, path) = write_json("native-goal-rel", "task-000.json", &task);
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$.goal[0].relation", &["\"UNDER\""]);
}

/// A native goal naming a missing node: the predicate is reported, with the id.
#[test]
fn native_goal_naming_a_missing_node() {
    let mut task = native_from_env0();
    task["goal"][0]["target"] = json!(5150);
    let (_dir, path) = write_json("native-goal-node", "task-000.json", &task);
    let err = single_task_error(&path);
    let Error::Malformed { path: p, .. } = &err else {
        panic!("expected Error::Malformed, got {err:?}");
    };
    assert!(p.to_string().starts_with("$.goal[0]"), "{err}");
    let message = assert_malformed(&err, &path, &p.to_string(), &["5150"]);
    assert!(
        message.contains("the goal names node 5150, which is not in the graph"),
        "{message}"
    );
}

/// The exact path of the field holding the missing id, as for edges
/// (`$.graph.edges[K].to_id`).
#[test]
fn native_goal_missing_node_names_the_field() {
    for field in ["subject", "target"] {
        let mut task = native_from_env0();
        task["goal"][0][field] = json!(5150);
        let (_dir, path) = write_json(&format!("native-goal-{field}"), "task-000.json", &task);
        let err = single_task_error(&path);
        assert_malformed(&err, &path, &format!("$.goal[0].{field}"), &["5150"]);
    }
}

#[test]
fn native_graph_errors_name_graph_path() {
    let mut task = native_from_env0();
    task["graph"]["edges"][5]["to_id"] = json!(8080);
    let (_dir, path) = write_json("native-edge", "task-000.json", &task);
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$.graph.edges[5].to_id", &["8080"]);
}

#[test]
fn native_robot_list_disagrees_with_graph() {
    let base = native_from_env0();
    let robots = base["robots"].as_array().expect("robots is a list").clone();
    assert_eq!(robots.len(), 4, "env0 task 0 has four robots: {robots:?}");

    // A robot of the graph missing from the list.
    let mut task = base.clone();
    let dropped = task["robots"].as_array_mut().expect("list").remove(1);
    let (_dir, path) = write_json("robots-missing", "task-000.json", &task);
    let err = single_task_error(&path);
    let id = dropped["id"].to_string();
    assert_malformed(
        &err,
        &path,
        "$.robots",
        &[&format!("robot {id}"), "missing"],
    );

    // The wrong type for a robot.
    let mut task = base.clone();
    assert_eq!(task["robots"][0]["type"], "quadrotor");
    task["robots"][0]["type"] = json!("robot dog");
    let (_dir, path) = write_json("robots-type", "task-000.json", &task);
    let err = single_task_error(&path);
    assert_malformed(
        &err,
        &path,
        "$.robots[0].type",
        &["\"robot dog\"", "\"quadrotor\""],
    );

    // A listed id that is not a robot of the graph (node 35, the high kitchen table).
    let mut task = base.clone();
    task["robots"][2]["id"] = json!(35);
    let (_dir, path) = write_json("robots-not-robot", "task-000.json", &task);
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$.robots[2].id", &["35", "not a robot"]);

    // A listed id that is no node at all.
    let mut task = base;
    task["robots"][3]["id"] = json!(123456);
    let (_dir, path) = write_json("robots-unknown", "task-000.json", &task);
    let err = single_task_error(&path);
    assert_malformed(&err, &path, "$.robots[3].id", &["123456"]);
}

#[test]
fn env3_task_18_duplicate_id_is_reported_and_others_load() {
    let path = common::data_dir().join("env3.json");
    let tasks = load::read_tasks(&path).expect("env3.json is JSON");
    assert_eq!(tasks.len(), 20);
    for (i, t) in tasks.iter().enumerate() {
        match t {
            Ok(task) => {
                assert_ne!(i, 18, "task index 18 has a duplicate node id");
                assert_eq!(task.meta.scene, "env3");
            }
            Err(e) => {
                assert_eq!(i, 18, "only task index 18 is malformed, not {i}: {e}");
                assert_malformed(
                    e,
                    &path,
                    "$[18].init_graph.nodes[25].id",
                    &["duplicate node id 24"],
                );
            }
        }
    }
    assert_eq!(tasks.iter().filter(|t| t.is_ok()).count(), 19);
    // load_tasks gives the first error.
    let err = load::load_tasks(&path).expect_err("env3 holds a malformed task");
    assert_malformed(&err, &path, "$[18].init_graph.nodes[25].id", &["24"]);
}

/// The schema: "one entry for each Agents node of the graph, no more and no fewer". A
/// robot listed twice is one entry too many.
#[test]
fn native_robot_listed_twice() {
    let mut task = native_from_env0();
    let first = task["robots"][0].clone();
    task["robots"].as_array_mut().expect("list").push(first);
    let (_dir, path) = write_json("robots-twice", "task-000.json", &task);
    let tasks = load::read_tasks(&path).expect("the file is JSON");
    match &tasks[0] {
        Ok(_) => panic!("a robot listed twice was accepted"),
        Err(Error::Malformed {
            file,
            path: p,
            message,
        }) => {
            assert_eq!(file, &path.display().to_string());
            assert!(p.to_string().starts_with("$.robots[4]"), "{p}: {message}");
            assert!(message.contains("22"), "{message}");
        }
        Err(other) => panic!("expected Error::Malformed, got {other:?}"),
    }
}

/// A key twice in one object is refused wherever it is (serde_json alone keeps the last
/// one: `"task_id": 7, "task_id": 0` would plan as task 0), with the path of the repeat.
#[test]
fn duplicate_keys_are_refused_with_their_path() {
    let text = serde_json::to_string(&json!([env0_task0()])).expect("JSON serializes");
    assert!(text.starts_with("[{\"task_id\":0,"), "{}", &text[..40]);
    // At the top of a task: the second "task_id" is the file's own.
    let twice = text.replacen("[{", "[{\"task_id\": 7, ", 1);
    let (_dir, path) = write("duplicate-key", "env0.json", &twice);
    let err = load::read_tasks(&path).expect_err("a repeated key");
    let message = assert_malformed(&err, &path, "$[0].task_id", &["duplicate key \"task_id\""]);
    assert!(message.contains("line 1 column"), "{message}");

    // Written with an escape, it is still the same key.
    let escaped = text.replacen("[{", "[{\"task\\u005fid\": 7, ", 1);
    let (_dir, path) = write("duplicate-key-escaped", "env0.json", &escaped);
    let err = load::read_tasks(&path).expect_err("a repeated key");
    assert_malformed(&err, &path, "$[0].task_id", &["duplicate key \"task_id\""]);

    // Deep inside: an edge with two `to_id`s.
    let edge = "{\"from_id\":";
    let at = text.find(edge).expect("an edge");
    let deep = format!(
        "{}{{\"to_id\": 1, \"from_id\":{}",
        &text[..at],
        &text[at + edge.len()..]
    );
    let deep = deep.replacen(
        "\"to_id\": 1, \"from_id\":",
        "\"to_id\": 1, \"to_id\": 2, \"from_id\":",
        1,
    );
    let (_dir, path) = write("duplicate-key-deep", "env0.json", &deep);
    let err = load::read_tasks(&path).expect_err("a repeated key");
    assert_malformed(
        &err,
        &path,
        "$[0].init_graph.edges[0].to_id",
        &["duplicate key \"to_id\""],
    );

    // In a native task file too.
    let native = serde_json::to_string_pretty(&native_from_env0()).expect("JSON serializes");
    let twice = native.replacen('{', "{\n  \"scene\": \"elsewhere\",", 1);
    let (_dir, path) = write("duplicate-key-native", "task-000.json", &twice);
    let err = load::read_tasks(&path).expect_err("a repeated key");
    assert_malformed(&err, &path, "$.scene", &["duplicate key \"scene\""]);
}

/// Bytes that are not UTF-8: the message gives the byte offset, line and column of the
/// first bad byte (not only "stream did not contain valid UTF-8").
#[test]
fn text_that_is_not_utf8_names_the_byte_offset() {
    let text = serde_json::to_string_pretty(&json!([env0_task0()])).expect("JSON serializes");
    let name = "\"task_name\": \"";
    let at = text.find(name).expect("a task name") + name.len();
    let mut bytes = text.into_bytes();
    bytes.insert(at, 0xff);
    let line = bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
    let (_dir, path) = write("not-utf8", "env0.json", "");
    std::fs::write(&path, &bytes).expect("temporary file can be written");
    let err = load::read_tasks(&path).expect_err("not UTF-8");
    let message = assert_malformed(
        &err,
        &path,
        "$",
        &[
            &format!("byte offset {at}"),
            &format!("line {line} column"),
            "0xff",
        ],
    );
    assert!(message.contains("UTF-8"), "{message}");
}

/// A value repeated in a message is cut to 80 characters, with an ellipsis and its full
/// length, wherever it comes from: a name core checks, a goal key (which is also part
/// of the path), a wrong type serde reports, an unknown field.
#[test]
fn long_values_are_cut_in_messages() {
    let long = "X".repeat(100_000);
    let short_enough = |err: &Error| {
        let line = err.to_string();
        assert!(
            line.len() < 1_000,
            "{} bytes: {}...",
            line.len(),
            &line[..200]
        );
        assert!(
            line.contains('…') && line.contains("(100000 chars)"),
            "{line}"
        );
    };

    let mut task = env0_task0();
    task["init_graph"]["edges"][0]["relation_type"] = json!(long);
    let (_dir, path) = write_json("long-relation", "env0.json", &json!([task]));
    short_enough(&single_task_error(&path));

    let mut task = env0_task0();
    task["task_goal"] = json!({ long.clone(): [1, []] });
    let (_dir, path) = write_json("long-goal", "env0.json", &json!([task]));
    short_enough(&single_task_error(&path));

    let mut task = env0_task0();
    task["task_id"] = json!(long);
    let (_dir, path) = write_json("long-type", "env0.json", &json!([task]));
    short_enough(&single_task_error(&path));

    let mut task = env0_task0();
    task["init_graph"]["nodes"][0]["category"] = json!("Agents");
    task["init_graph"]["nodes"][0]["class_name"] = json!(long);
    let (_dir, path) = write_json("long-robot", "env0.json", &json!([task]));
    short_enough(&single_task_error(&path));

    let mut task = native_from_env0();
    task[long.as_str()] = json!(1);
    let (_dir, path) = write_json("long-field", "task-000.json", &task);
    short_enough(&single_task_error(&path));

    let mut task = native_from_env0();
    task["format"] = json!(long);
    let (_dir, path) = write_json("long-format", "task-000.json", &task);
    short_enough(&single_task_error(&path));
}

/// An empty list holds no task: `read_tasks` says so by an empty result, `load_tasks`
/// (every task or an error) by an error naming the file.
#[test]
fn an_empty_list_is_no_tasks() {
    let (_dir, path) = write("empty", "env0.json", "[]");
    assert!(
        load::read_tasks(&path)
            .expect("the file is JSON")
            .is_empty()
    );
    let err = load::load_tasks(&path).expect_err("no tasks");
    assert_malformed(&err, &path, "$", &["no tasks"]);
}

/// A cycle of `ON` and `INSIDE` edges (a thing on or in itself, through others) is
/// refused where the file is read: the rules would carry it along inside what it holds,
/// and no layout can place it. The error is at the edge that closes the cycle and spells
/// the cycle out, each edge with its path; a long cycle is cut, a deep chain is no cycle.
#[test]
fn a_cycle_of_on_and_inside_edges_is_refused_with_each_edge_and_its_path() {
    // The socks (29) are on the sofa (11); put the sofa on the socks.
    let mut task = env0_task0();
    let socks_on_sofa = edge_index(&task, |e| e["from_id"] == 29 && e["to_id"] == 11);
    let edges = task["init_graph"]["edges"].as_array_mut().expect("a list");
    edges.push(json!({"from_id": 11, "to_id": 29, "relation_type": "ON"}));
    let sofa_on_socks = edges.len() - 1;
    let (_dir, path) = write_json("cycle", "env0.json", &json!([task]));
    let err = single_task_error(&path);
    let at = |i: usize| format!("$[0].init_graph.edges[{i}]");
    let message = assert_malformed(
        &err,
        &path,
        &at(socks_on_sofa),
        &[
            "a cycle of ON and INSIDE edges",
            "nothing can be on or in itself",
        ],
    );
    assert!(
        message.contains(&format!(
            "<sofa>(11) ON <socks>(29) ({}), <socks>(29) ON <sofa>(11) ({})",
            at(sofa_on_socks),
            at(socks_on_sofa)
        )),
        "{message}"
    );

    // Native: a thing inside itself, and the same path notation.
    let mut task = native_from_env0();
    let edges = task["graph"]["edges"].as_array_mut().expect("a list");
    edges.push(json!({"from_id": 29, "to_id": 29, "relation_type": "INSIDE"}));
    let itself = edges.len() - 1;
    let (_dir, path) = write_json("cycle-native", "task-000.json", &task);
    let err = single_task_error(&path);
    let message = assert_malformed(&err, &path, &format!("$.graph.edges[{itself}]"), &[]);
    assert!(
        message.contains(&format!(
            "<socks>(29) INSIDE <socks>(29) ($.graph.edges[{itself}]);"
        )),
        "{message}"
    );

    // 2,000 boxes, each inside the next and the last inside the first: 16 edges shown.
    // Without the last edge the chain is no cycle, however deep, and loads.
    let mut task = native_from_env0();
    let (nodes, edges) = (
        task["graph"]["nodes"].clone(),
        task["graph"]["edges"].clone(),
    );
    let (mut nodes, mut edges) = (
        nodes.as_array().expect("nodes").clone(),
        edges.as_array().expect("edges").clone(),
    );
    for i in 0..2000 {
        nodes.push(json!({"id": 1000 + i, "category": "Containers", "class_name": "box"}));
        let to = if i + 1 < 2000 { 1001 + i } else { 1000 };
        edges.push(json!({"from_id": 1000 + i, "to_id": to, "relation_type": "INSIDE"}));
    }
    task["graph"]["nodes"] = json!(nodes);
    task["graph"]["edges"] = json!(edges.clone());
    let (_dir, path) = write_json("ring", "task-000.json", &task);
    let message = assert_malformed(
        &single_task_error(&path),
        &path,
        &format!("$.graph.edges[{}]", edges.len() - 1),
        &["and 1984 more edges; "],
    );
    assert_eq!(message.matches(" INSIDE <box>").count(), 16, "{message}");
    edges.pop();
    task["graph"]["edges"] = json!(edges);
    let (_dir, path) = write_json("chain", "task-000.json", &task);
    assert!(load::load_tasks(&path).is_ok(), "a chain 2,000 deep loads");
}
