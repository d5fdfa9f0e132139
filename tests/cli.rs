//! The `coherent` command line, run as a separate process: exit codes, messages and
//! the JSON that `plan --json` prints.

use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::{Value, json};

mod common;

use common::{coherent, demo, show};

fn env_dir() -> PathBuf {
    PathBuf::from(env!("COHERENT_ORIGINAL_ENV"))
}

fn env_file(n: usize) -> PathBuf {
    env_dir().join(format!("env{n}.json"))
}

fn code(out: &Output) -> i32 {
    out.status
        .code()
        .expect("exited with a status, not a signal")
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A temporary folder, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(test: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("coherent-cli-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temporary folder can be created");
        TempDir(dir)
    }

    fn path(&self) -> &Path {
        &self.0
    }

    fn write_json(&self, name: &str, value: &Value) -> PathBuf {
        let path = self.0.join(name);
        let text = serde_json::to_string_pretty(value).expect("JSON serializes");
        std::fs::write(&path, text).expect("temporary file can be written");
        path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The released tasks of `env<n>.json`.
fn original_list(n: usize) -> Vec<Value> {
    let text = std::fs::read_to_string(env_file(n)).expect("benchmark file is readable");
    match serde_json::from_str(&text).expect("benchmark file is JSON") {
        Value::Array(items) => items,
        other => panic!("not a list: {other}"),
    }
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

/// `validate` over the four files reads all 82 tasks. env3's task 18 is malformed, so
/// the exit status is 2 and stderr names the file and the JSON path; the semantic
/// problems of the released files are named on stdout with their reasons.
#[test]
fn validate_four_files_names_every_problem_of_the_released_benchmark() {
    let files: Vec<PathBuf> = (0..4).map(env_file).collect();
    let mut args = vec!["validate"];
    args.extend(files.iter().map(|f| arg(f)));
    let out = coherent(&args);
    assert_eq!(code(&out), 2, "{}", show(&out));
    let err = stderr(&out);
    let env3 = env_file(3).display().to_string();
    assert!(
        err.contains(&format!(
            "{env3}: $[18].init_graph.nodes[25].id: duplicate node id 24"
        )),
        "{}",
        show(&out)
    );
    assert_eq!(
        err.lines().filter(|l| l.starts_with("error:")).count(),
        1,
        "{}",
        show(&out)
    );
    let text = stdout(&out);
    assert!(
        text.contains(
            "env3 task 0 (env3.json): the goal cannot be reached: \
             inside_<paper cup>(23)_<trash can>(25): <trash can>(25) has no CONTAINERS property"
        ),
        "{}",
        show(&out)
    );
    assert!(
        text.contains(
            "env1 task 6 (env1.json): ground truth says 7 steps, but the shortest plan takes 8"
        ),
        "{}",
        show(&out)
    );
    assert!(
        text.contains("82 tasks read: 79 clean, 2 with semantic problems, 1 malformed"),
        "{}",
        show(&out)
    );
}

#[test]
fn validate_malformed_env3_alone_exits_2() {
    let out = coherent(&["validate", "--max-states", "2000", arg(&env_file(3))]);
    assert_eq!(code(&out), 2, "{}", show(&out));
    assert!(
        stderr(&out).contains("$[18].init_graph.nodes[25].id"),
        "{}",
        show(&out)
    );
    assert!(stdout(&out).contains("20 tasks read:"), "{}", show(&out));
}

#[test]
fn validate_clean_single_task_exits_0() {
    let dir = TempDir::new("clean");
    let task = original_list(0).swap_remove(0);
    let file = dir.write_json("env0.json", &json!([task]));
    let out = coherent(&["validate", arg(&file)]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    assert!(
        stdout(&out).contains("1 tasks read: 1 clean, 0 with semantic problems, 0 malformed"),
        "{}",
        show(&out)
    );
    assert!(stderr(&out).is_empty(), "{}", show(&out));
}

#[test]
fn validate_goal_already_holding_exits_1() {
    let dir = TempDir::new("holds");
    let mut task = original_list(0).swap_remove(0);
    // The quadrotor starts ON the childroom floor (edge 22 -ON-> 3).
    let starts_there = task["init_graph"]["edges"]
        .as_array()
        .expect("edges")
        .iter()
        .any(|e| *e == json!({"from_id": 22, "to_id": 3, "relation_type": "ON"}));
    assert!(starts_there);
    task["task_goal"] = json!({"on_<quadrotor>(22)_<childroom floor>(3)": [1, []]});
    let file = dir.write_json("env0.json", &json!([task]));
    let out = coherent(&["validate", arg(&file)]);
    assert_eq!(code(&out), 1, "{}", show(&out));
    let text = stdout(&out);
    assert!(text.contains("already holds"), "{}", show(&out));
    assert!(
        text.contains("on_<quadrotor>(22)_<childroom floor>(3)"),
        "{}",
        show(&out)
    );
    assert!(text.contains("1 with semantic problems"), "{}", show(&out));
}

#[test]
fn validate_unsolvable_task_exits_1_and_says_why() {
    // env3 task 0: the goal container (trash can) is no container.
    let dir = TempDir::new("unsolvable");
    let task = original_list(3).swap_remove(0);
    let file = dir.write_json("env3.json", &json!([task]));
    let out = coherent(&["validate", arg(&file)]);
    assert_eq!(code(&out), 1, "{}", show(&out));
    assert!(stdout(&out).contains("CONTAINERS"), "{}", show(&out));
}

/// A flight of stairs narrower than the legged robot needs: the task is solvable, but
/// `validate` reports the broken scene rule with the numbers (exit 1).
#[test]
fn validate_reports_stairs_that_break_the_scene_rules() {
    let dir = TempDir::new("stairs");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("benchmark/tasks/s5-house/task-00.json");
    let mut task: Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("a benchmark task"))
            .expect("JSON");
    task["geometry"]["stairs"][0]["width"] = json!(0.6);
    let file = dir.write_json("narrow-stairs.json", &task);
    let out = coherent(&["validate", arg(&file)]);
    assert_eq!(code(&out), 1, "{}", show(&out));
    assert!(
        stdout(&out).contains("geometry: stairs 17: 0.60 m wide; a flight is at least 1 m wide"),
        "{}",
        show(&out)
    );
}

/// Drops `elapsed_ms`, the one field that differs from run to run.
fn without_elapsed(line: &str) -> Value {
    let mut v: Value =
        serde_json::from_str(line).unwrap_or_else(|e| panic!("not JSON ({e}): {line}"));
    let obj = v.as_object_mut().expect("each line is an object");
    assert!(
        obj.remove("elapsed_ms").is_some_and(|t| t.is_number()),
        "{line}"
    );
    v
}

/// `import` writes one native file per task; `plan` over the folder of native files
/// prints the same JSON lines as over the original file (the whole of env0).
#[test]
fn import_then_plan_native_folder_equals_plan_original() {
    let dir = TempDir::new("import");
    let tasks: Vec<Value> = original_list(0);
    let ids: Vec<i64> = tasks
        .iter()
        .map(|t| t["task_id"].as_i64().expect("task_id"))
        .collect();
    let file = dir.write_json("env0.json", &Value::Array(tasks));
    let out_dir = dir.path().join("native");

    let out = coherent(&["import", arg(&file), "-o", arg(&out_dir)]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    assert!(
        stdout(&out).contains("wrote 21 native task files"),
        "{}",
        show(&out)
    );
    let mut written: Vec<PathBuf> = std::fs::read_dir(out_dir.join("env0"))
        .expect("import made <out>/env0")
        .map(|e| e.expect("a folder entry").path())
        .collect();
    written.sort();
    let expected: Vec<PathBuf> = ids
        .iter()
        .map(|id| out_dir.join("env0").join(format!("task-{id:03}.json")))
        .collect();
    assert_eq!(written, expected);
    for path in &written {
        let v: Value = serde_json::from_str(&std::fs::read_to_string(path).expect("readable"))
            .expect("native files are JSON");
        assert_eq!(v["format"], "coherent-task", "{}", path.display());
        assert_eq!(v["scene"], "env0", "{}", path.display());
    }

    // The native files validate like the original.
    let out = coherent(&["validate", arg(&out_dir)]);
    assert_eq!(code(&out), 0, "{}", show(&out));

    let from_original = coherent(&["plan", arg(&file), "--json"]);
    assert_eq!(code(&from_original), 0, "{}", show(&from_original));
    let from_native = coherent(&["plan", arg(&out_dir), "--json"]);
    assert_eq!(code(&from_native), 0, "{}", show(&from_native));
    let a: Vec<Value> = stdout(&from_original)
        .lines()
        .map(without_elapsed)
        .collect();
    let b: Vec<Value> = stdout(&from_native).lines().map(without_elapsed).collect();
    assert_eq!(a.len(), 21);
    assert_eq!(a, b);
    // And the lines themselves, byte for byte, once elapsed_ms is gone.
    let text = |v: &[Value]| v.iter().map(Value::to_string).collect::<Vec<_>>();
    assert_eq!(text(&a), text(&b));
}

#[test]
fn plan_one_task_prints_one_json_object_with_the_documented_keys() {
    let out = coherent(&["plan", arg(&env_file(0)), "--task", "0", "--json"]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    let text = stdout(&out);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1, "{}", show(&out));
    let v: Value = serde_json::from_str(lines[0]).expect("one JSON object");
    let obj = v.as_object().expect("an object");
    let mut keys: Vec<&str> = obj.keys().map(String::as_str).collect();
    keys.sort_unstable();
    let mut want = [
        "scene",
        "task_id",
        "gt_steps",
        "optimal_steps",
        "solvable",
        "reason",
        "task_type",
        "plan",
        "states_expanded",
        "elapsed_ms",
    ];
    want.sort_unstable();
    assert_eq!(keys, want);
    assert_eq!(v["scene"], "env0");
    assert_eq!(v["task_id"], 0);
    assert_eq!(v["gt_steps"], 5);
    assert_eq!(v["optimal_steps"], 5);
    assert_eq!(v["solvable"], true);
    assert_eq!(v["reason"], Value::Null);
    assert_eq!(v["task_type"], "mono");
    let plan = v["plan"].as_array().expect("plan is a list");
    assert_eq!(plan.len(), 5);
    for step in plan {
        let step = step.as_object().expect("a step is an object");
        assert_eq!(step.len(), 2);
        assert!(step["robot"].is_i64());
        assert!(step["action"].as_str().is_some_and(|a| a.starts_with('[')));
    }
    // The goal is the quadrotor ON the high kitchen table: it ends by landing there.
    assert_eq!(plan[4]["action"], "[land_on] <high kitchen table>(35)");
    assert!(v["states_expanded"].as_u64().is_some_and(|n| n > 0));
    assert!(v["elapsed_ms"].as_f64().is_some_and(|ms| ms >= 0.0));
    // The file's malformed neighbours do not matter here: env0 is clean.
    assert!(stderr(&out).is_empty(), "{}", show(&out));
}

#[test]
fn plan_unknown_task_id_exits_2() {
    let out = coherent(&["plan", arg(&env_file(0)), "--task", "999", "--json"]);
    assert_eq!(code(&out), 2, "{}", show(&out));
    assert!(
        stderr(&out).contains("no task with task_id 999"),
        "{}",
        show(&out)
    );
}

#[test]
fn missing_file_exits_2_and_names_it() {
    let dir = TempDir::new("missing");
    let missing = dir.path().join("nope.json");
    for cmd in ["validate", "plan"] {
        let out = coherent(&[cmd, arg(&missing)]);
        assert_eq!(code(&out), 2, "{cmd}: {}", show(&out));
        assert!(
            stderr(&out).contains(arg(&missing)),
            "{cmd}: {}",
            show(&out)
        );
    }
}

#[test]
fn bad_json_exits_2_and_names_root() {
    let dir = TempDir::new("bad-json");
    let file = dir.path().join("env0.json");
    std::fs::write(&file, "[{\"task_id\": }]").expect("writable");
    let out = coherent(&["validate", arg(&file)]);
    assert_eq!(code(&out), 2, "{}", show(&out));
    assert!(
        stderr(&out).contains(&format!("{}: $: invalid JSON", arg(&file))),
        "{}",
        show(&out)
    );
}

#[test]
fn usage_errors_exit_2() {
    let env0 = env_file(0);
    let env0 = arg(&env0);
    for args in [
        &[][..],
        &["frobnicate"],
        &["validate"],
        &["import", env0],
        &["import", "-o", "/tmp/x"],
        &["plan"],
        &["plan", env0, "--task", "zero"],
        &["plan", env0, "--max-states", "-5"],
        &["plan", env0, "--bogus"],
        &["validate", env0, "--max-states"],
    ] {
        let out = coherent(args);
        assert_eq!(code(&out), 2, "{args:?}: {}", show(&out));
        assert!(
            stdout(&out).is_empty(),
            "{args:?}: usage errors go to stderr: {}",
            show(&out)
        );
        assert!(!stderr(&out).is_empty(), "{args:?}: {}", show(&out));
    }
}

#[test]
fn help_and_version_exit_0() {
    for args in [&["--help"][..], &["--version"], &["plan", "--help"]] {
        let out = coherent(args);
        assert_eq!(code(&out), 0, "{args:?}: {}", show(&out));
        assert!(!stdout(&out).is_empty(), "{args:?}");
    }
}

/// `plan --parallel` adds the fewest joint steps: env0 task 9 takes 9 steps one robot
/// at a time and 8 when the arm grabs the plate while the quadrotor takes off. Stopped
/// at a limit, it keeps the sequential optimum scheduled (8 steps) and a lower bound.
#[test]
fn plan_parallel_prints_the_fewest_joint_steps_and_bounds_at_a_limit() {
    let env0 = env_file(0);
    let out = coherent(&["plan", arg(&env0), "--task", "9", "--parallel", "--json"]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    let v: Value = serde_json::from_str(stdout(&out).trim()).expect("one JSON line");
    assert_eq!(v["optimal_steps"], 9);
    assert_eq!(
        (&v["makespan"], &v["makespan_proven"], &v["makespan_lower"]),
        (&json!(8), &json!(true), &json!(8))
    );
    assert_eq!(v["makespan_stop"], Value::Null);
    assert!(
        v["makespan_states_expanded"]
            .as_u64()
            .is_some_and(|n| n > 0)
    );
    assert!(v["makespan_ms"].as_f64().is_some_and(|ms| ms >= 0.0));
    let steps = v["parallel_plan"]
        .as_array()
        .expect("a list of joint steps");
    assert_eq!(steps.len(), 8);
    assert_eq!(
        steps[0],
        json!([
            {"robot": 22, "action": "[takeoff_from] <livingroom floor>(5)"},
            {"robot": 24, "action": "[grab] <plate>(51)"},
        ])
    );
    let actions: usize = steps.iter().map(|s| s.as_array().map_or(0, Vec::len)).sum();
    assert_eq!(actions, 9, "the same actions as the sequential plan");

    let out = coherent(&["plan", arg(&env0), "--task", "9", "--parallel"]);
    let text = stdout(&out);
    assert!(
        text.contains("parallel: 8 joint steps (the fewest)")
            && text.contains(
                "     1  22 [takeoff_from] <livingroom floor>(5)  |  24 [grab] <plate>(51)\n"
            ),
        "{}",
        show(&out)
    );

    let limited = [
        "plan",
        arg(&env0),
        "--task",
        "9",
        "--parallel",
        "--max-states",
        "500",
    ];
    let out = coherent(&[&limited[..], &["--json"]].concat());
    assert_eq!(code(&out), 0, "{}", show(&out));
    let v: Value = serde_json::from_str(stdout(&out).trim()).expect("one JSON line");
    assert_eq!(
        v["optimal_steps"], 9,
        "the sequential search stays within 500 states"
    );
    assert_eq!(
        (&v["makespan"], &v["makespan_proven"], &v["makespan_stop"]),
        (&json!(8), &json!(false), &json!("states"))
    );
    let lower = v["makespan_lower"].as_u64().expect("a lower bound");
    assert!((1..8).contains(&lower), "{v}");
    let text = stdout(&coherent(&limited));
    assert!(
        text.contains(&format!(
            "parallel: 8 joint steps (not proven the fewest: at least {lower}; the search stopped at the limit of 500 states)"
        )),
        "{text}"
    );
}

/// `plan --physics` carries the optimal plan out in Rapier and adds the four documented
/// keys to the JSON line.
#[test]
fn plan_physics_adds_the_physical_outcome_to_each_line() {
    let out = coherent(&["plan", arg(&demo()), "--physics", "--json"]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    let line: Value = serde_json::from_str(stdout(&out).trim()).expect("one JSON line");
    assert_eq!(line["physics_ok"], json!(true), "{line}");
    assert_eq!(line["physics_error"], Value::Null);
    assert!(line["sim_seconds"].as_f64().is_some_and(|s| s > 0.0));
    assert!(line["physics_wall_ms"].as_f64().is_some_and(|s| s > 0.0));
}

/// `plan --parallel --physics` carries out the makespan plan as well, each joint step's
/// robots moving at once: the demo's 13 joint steps take less simulated time than its 22
/// actions in turn, and the sequential plan's keys stay what `--physics` alone gives.
#[test]
fn plan_parallel_physics_runs_the_makespan_plan_in_rapier() {
    let demo = demo();
    let out = coherent(&["plan", arg(&demo), "--physics", "--json"]);
    let alone: Value = serde_json::from_str(stdout(&out).trim()).expect("one JSON line");
    let out = coherent(&["plan", arg(&demo), "--parallel", "--physics", "--json"]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    let line: Value = serde_json::from_str(stdout(&out).trim()).expect("one JSON line");
    assert_eq!(line["physics_ok"], json!(true), "{line}");
    assert_eq!(line["sim_seconds"], alone["sim_seconds"]);
    assert_eq!(line["makespan_physics_ok"], json!(true), "{line}");
    assert_eq!(line["makespan_physics_error"], Value::Null);
    assert!(
        line["makespan_physics_wall_ms"]
            .as_f64()
            .is_some_and(|ms| ms > 0.0)
    );
    let (actions, joint) = (&line["optimal_steps"], &line["makespan"]);
    assert!(joint.as_u64() < actions.as_u64(), "{actions} {joint}");
    let (seconds, parallel) = (
        line["sim_seconds"].as_f64().expect("seconds in turn"),
        line["makespan_sim_seconds"]
            .as_f64()
            .expect("seconds at once"),
    );
    assert!(
        parallel > 1.0 && parallel < seconds,
        "{parallel} s at once against {seconds} s in turn"
    );

    let out = coherent(&["plan", arg(&demo), "--parallel", "--physics"]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    let text = stdout(&out);
    assert!(
        text.contains(&format!("\n  physics: ok, {seconds:.1} s simulated in "))
            && text.contains(&format!(
                "\n  parallel physics: ok, {parallel:.1} s simulated in "
            )),
        "{text}"
    );
}

/// `run --physics` and `run --method mcts` go through the same loop and transcript.
#[test]
fn run_with_physics_and_with_mcts() {
    let dir = TempDir::new("run-physics");
    let out = coherent(&[
        "run",
        arg(&demo()),
        "--physics",
        "--json",
        "--out",
        arg(dir.path()),
    ]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    let summary: Value = serde_json::from_str(stdout(&out).trim()).expect("a JSON summary");
    assert_eq!(
        (summary["success"].clone(), summary["steps"].clone()),
        (json!(true), json!(22))
    );
    let transcript = std::fs::read_to_string(summary["transcript"].as_str().expect("a path"))
        .expect("the transcript is written");
    let header: Value =
        serde_json::from_str(transcript.lines().next().expect("a header")).expect("JSON");
    assert_eq!(header["physics"], json!(true));

    let out = coherent(&[
        "run",
        arg(&env_file(0)),
        "--task",
        "0",
        "--method",
        "mcts",
        "--out",
        arg(dir.path()),
    ]);
    assert!(matches!(code(&out), 0 | 1), "{}", show(&out));
    assert!(
        stdout(&out).starts_with("backend: none (mcts asks no model)"),
        "{}",
        show(&out)
    );
}

/// `render --plan` writes an SVG naming every room and robot, with the robots' paths.
#[test]
fn render_writes_a_picture_with_paths() {
    let dir = TempDir::new("render");
    let svg = dir.path().join("demo.svg");
    let out = coherent(&["render", arg(&demo()), "--plan", "-o", arg(&svg)]);
    assert_eq!(code(&out), 0, "{}", show(&out));
    let text = std::fs::read_to_string(&svg).expect("the SVG is written");
    assert!(
        text.starts_with("<svg") || text.starts_with("<?xml"),
        "{}",
        &text[..80]
    );
    for name in [
        "kitchen",
        "living room",
        "quadrotor",
        "robot dog",
        "robot arm",
    ] {
        assert!(text.contains(name), "{name} is not in the picture");
    }
    assert!(text.contains("<polyline class=\"path\""), "no path drawn");
    let out = coherent(&["render", arg(&env_file(0)), "-o", arg(&svg)]);
    assert_eq!(code(&out), 2, "{}", show(&out));
    assert!(stderr(&out).contains("choose one with --task ID"));
}

/// A ground truth no task can need (2 x 2147483648 is 0 in 32 bits, 2 x 4294967295 is
/// 4294967294): `validate` flags it with the limit, and `run` sizes no budget from it.
#[test]
fn a_ground_truth_beyond_any_task_is_flagged_and_sizes_no_budget() {
    let dir = TempDir::new("huge-gt");
    for gt in [2_147_483_648_u64, 4_294_967_295] {
        let mut task = original_list(0).swap_remove(0);
        task["ground_truth_step_num"] = json!([gt]);
        let file = dir.write_json("env0.json", &json!([task]));
        let out = coherent(&["validate", arg(&file)]);
        assert_eq!(code(&out), 1, "{}", show(&out));
        assert!(
            stdout(&out).contains(&format!(
                "ground truth says {gt} steps, more than any task needs (at most 10000"
            )),
            "{}",
            show(&out)
        );
        let out = coherent(&["run", arg(&file), "--task", "0", "--out", arg(dir.path())]);
        assert_eq!(code(&out), 2, "{}", show(&out));
        assert!(!stdout(&out).contains("budget"), "{}", show(&out));
        assert!(
            stderr(&out).contains(&format!("the ground truth of {gt} steps")),
            "{}",
            show(&out)
        );
    }
}

/// An empty list is no tasks: a warning, and exit 1 (not "0 tasks read" and 0).
#[test]
fn an_empty_task_list_is_a_warning_and_exits_1() {
    let dir = TempDir::new("empty-list");
    let file = dir.write_json("env0.json", &json!([]));
    for cmd in ["validate", "plan"] {
        let out = coherent(&[cmd, arg(&file)]);
        assert_eq!(code(&out), 1, "{cmd}: {}", show(&out));
        assert!(
            stderr(&out).contains(&format!(
                "warning: {}: no tasks (an empty list)",
                arg(&file)
            )),
            "{cmd}: {}",
            show(&out)
        );
    }
}

/// A key twice in one object is malformed input, named with its path.
#[test]
fn a_key_twice_exits_2_naming_its_path() {
    let dir = TempDir::new("key-twice");
    let text = serde_json::to_string(&json!([original_list(0).swap_remove(0)])).expect("JSON");
    let file = dir.path().join("env0.json");
    std::fs::write(&file, text.replacen("[{", "[{\"task_id\": 7, ", 1)).expect("writable");
    let out = coherent(&["validate", arg(&file)]);
    assert_eq!(code(&out), 2, "{}", show(&out));
    assert!(
        stderr(&out).contains(&format!(
            "error: {}: $[0].task_id: duplicate key \"task_id\"",
            arg(&file)
        )),
        "{}",
        show(&out)
    );
}

/// env1 task 2 with the sink moved off the kitchen table (its edge now the robot arm's,
/// twice): the plate can no longer go into it, and proving so takes more states than
/// any bound here. `validate` stops at the memory bound and says the goal was not
/// decided (by default it stops at 1 GiB instead of 5,000,000 states and 1.8 GB).
#[test]
fn validate_stops_at_the_memory_bound_and_says_the_goal_was_not_decided() {
    let dir = TempDir::new("memory-bound");
    let mut task = original_list(1).swap_remove(2);
    assert_eq!(
        task["init_graph"]["edges"][7],
        json!({"from_id": 8, "to_id": 11, "relation_type": "ON"})
    );
    task["init_graph"]["edges"][7]["from_id"] = json!(20);
    let file = dir.write_json("env1.json", &json!([task]));
    let out = coherent(&["validate", "--max-memory", "16", arg(&file)]);
    assert_eq!(code(&out), 1, "{}", show(&out));
    assert!(
        stdout(&out).contains(
            "env1 task 2 (env1.json): the goal could not be decided within the search limits: \
             search stopped at the memory limit of 16 MiB ("
        ),
        "{}",
        show(&out)
    );
}

#[test]
fn a_method_written_in_python_needs_the_python_package() {
    let dir = TempDir::new("python-method");
    let out_dir = dir.path().to_str().expect("UTF-8 path");
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/tasks/demo.json");
    let demo = demo.to_str().expect("UTF-8 path");
    let run = coherent(&["run", demo, "--method", "greedy:Greedy", "--out", out_dir]);
    assert_eq!(code(&run), 2, "{}", show(&run));
    assert!(
        stderr(&run)
            .contains("method greedy:Greedy: a method written in Python needs the Python package"),
        "{}",
        show(&run)
    );
    let results = dir.path().join("r.jsonl");
    let bench = coherent(&[
        "bench",
        "--tasks",
        demo,
        "--methods",
        "optimal,examples/methods/greedy.py:Greedy",
        "--out",
        results.to_str().expect("UTF-8 path"),
    ]);
    assert_eq!(code(&bench), 2, "{}", show(&bench));
    assert!(
        stderr(&bench).contains("needs the Python package"),
        "{}",
        show(&bench)
    );
    assert!(!results.exists(), "nothing ran");
    // A name that is neither a method nor MODULE:CLASS is a usage error that lists them.
    let typo = coherent(&["run", demo, "--method", "greddy", "--out", out_dir]);
    assert_eq!(code(&typo), 2, "{}", show(&typo));
    assert!(stderr(&typo).contains("or MODULE:CLASS"), "{}", show(&typo));
}
