//! `coherent generate` (docs/generate.md), checked on the sets it makes:
//! - the same command writes the same bytes, whatever the number of threads;
//! - every generated task is clean under `coherent validate`; `coherent plan --parallel`
//!   finds the manifest's optimal steps, type and makespan; every joint step of the
//!   makespan plan applies in every order through the sequential rules, each action
//!   offered at its turn, all orders ending in one state, the last reaching the goal;
//! - at least 5% of each set (every tenth task) has its optimal plan carried out in
//!   Rapier with `physics_ok`;
//! - on every task of the sets (one of them of many rooms and closed doors), the makespan
//!   search's bound never overestimates along the plan and no joint step lowers it by
//!   more than one; on the short ones, the makespan and its fewest actions are a
//!   breadth-first search's;
//! - `coherent export --format original` reads back through `coherent import` to the
//!   same tasks;
//! - a knob out of range, or a request the draws cannot meet, exits 2 with a message
//!   naming the knob and the value.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use coherent_core::makespan;
use coherent_core::planner::Limits;
use coherent_core::{Robot, State, Task, feasibility, load_tasks, rules};
use serde_json::Value;

mod common;
#[path = "../crates/coherent-core/tests/common/oracle.rs"]
mod oracle;

use common::{coherent, scratch, show, utf8};

/// The sets of the tests: a name, and the knobs after `--out DIR`.
/// Both keep only tasks whose optimal plan runs in Rapier (`--physics`): without it, a
/// third of the tasks of the first set fail there (docs/generate.md, "Physics").
const MIXED: (&str, &[&str]) = ("mixed", &["--tasks", "20", "--seed", "7", "--physics"]);
const LARGE: (&str, &[&str]) = (
    "large",
    &[
        "--tasks",
        "6",
        "--seed",
        "11",
        "--team",
        "quadrotor=1-2,legged=1-2,arm=1-2",
        "--robots",
        "4-5",
        "--predicates",
        "1-2",
        "--upstairs",
        "0.5",
        "--rooms",
        "4-8",
        "--physics",
    ],
);

/// Scenes of many rooms and closed doors, teams with several robot dogs: the chain
/// bound's walks across rooms are the longest here. Short tasks, for the breadth-first
/// search that checks their makespans.
const ROOMS: (&str, &[&str]) = (
    "rooms",
    &[
        "--tasks",
        "20",
        "--seed",
        "5",
        "--rooms",
        "3-8",
        "--closed",
        "0.5",
        "--team",
        "quadrotor=0-1,legged=1-3,arm=0-1",
        "--robots",
        "2-3",
        "--predicates",
        "1-2",
        "--steps",
        "2-4",
        "--max-states",
        "50000",
        "--max-memory",
        "128",
    ],
);

/// Writes the set `knobs` describes to `dir` with `coherent generate`.
fn generate(dir: &Path, knobs: &[&str]) {
    let mut args = vec!["generate", "--out", utf8(dir)];
    args.extend_from_slice(knobs);
    let out = coherent(&args);
    assert!(out.status.success(), "{}", show(&out));
}

/// The set `(name, knobs)`, made once for all the tests of this file.
fn set(which: (&str, &[&str])) -> &'static Path {
    static MIXED_SET: OnceLock<PathBuf> = OnceLock::new();
    static LARGE_SET: OnceLock<PathBuf> = OnceLock::new();
    static ROOMS_SET: OnceLock<PathBuf> = OnceLock::new();
    let cell = match which.0 {
        "mixed" => &MIXED_SET,
        "large" => &LARGE_SET,
        _ => &ROOMS_SET,
    };
    cell.get_or_init(|| {
        let dir = scratch(&format!("generate-{}", which.0)).join("set");
        generate(&dir, which.1);
        dir
    })
}

/// Every file under `dir`, by its path relative to `dir`, with its bytes.
fn files(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    walk(dir)
        .into_iter()
        .map(|path| {
            let bytes = std::fs::read(&path).expect("a file of the set");
            let rel = path.strip_prefix(dir).expect("under the set").to_path_buf();
            (rel, bytes)
        })
        .collect()
}

/// Every file under `dir`.
fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let path = entry.path();
        if path.is_dir() {
            found.extend(walk(&path));
        } else {
            found.push(path);
        }
    }
    found
}

/// The manifest's lines.
fn manifest(dir: &Path) -> Vec<Value> {
    std::fs::read_to_string(dir.join("manifest.jsonl"))
        .expect("the manifest")
        .lines()
        .map(|l| serde_json::from_str(l).expect("a manifest line is JSON"))
        .collect()
}

/// `coherent plan ARGS --json`'s lines, by scene and task id.
fn plan_lines(args: &[&str]) -> BTreeMap<(String, i64), Value> {
    let mut all = vec!["plan", "--json"];
    all.extend_from_slice(args);
    let out = coherent(&all);
    assert!(out.status.success(), "{}", show(&out));
    String::from_utf8(out.stdout)
        .expect("UTF-8")
        .lines()
        .map(|l| {
            let v: Value = serde_json::from_str(l).expect("a plan line is JSON");
            let key = (
                v["scene"].as_str().expect("a scene").to_owned(),
                v["task_id"].as_i64().expect("a task id"),
            );
            (key, v)
        })
        .collect()
}

#[test]
fn the_same_command_writes_the_same_bytes_whatever_the_threads() {
    let first = set(MIXED);
    let again = scratch("generate-again");
    for (name, jobs) in [("one", "1"), ("three", "3")] {
        let dir = again.join(name);
        let mut knobs = MIXED.1.to_vec();
        knobs.extend(["--jobs", jobs]);
        generate(&dir, &knobs);
        let (a, b) = (files(first), files(&dir));
        assert_eq!(
            a.keys().collect::<Vec<_>>(),
            b.keys().collect::<Vec<_>>(),
            "the same files (--jobs {jobs})"
        );
        for (path, bytes) in &a {
            assert!(
                b[path] == *bytes,
                "{} differs between two runs (--jobs {jobs})",
                path.display()
            );
        }
    }
    // 20 tasks, their manifest and the datasheet.
    assert_eq!(files(first).len(), 22);
    let sheet = String::from_utf8(files(first)[Path::new("README.md")].clone()).expect("UTF-8");
    assert!(
        sheet.contains("coherent generate --tasks 20 --seed 7 "),
        "{sheet}"
    );
}

/// Every order of `0..n`.
fn orders(n: usize) -> Vec<Vec<usize>> {
    if n == 0 {
        return vec![Vec::new()];
    }
    let mut out = Vec::new();
    for rest in orders(n - 1) {
        for at in 0..=rest.len() {
            let mut o = rest.clone();
            o.insert(at, n - 1);
            out.push(o);
        }
    }
    out
}

/// The robot whose node id is `id`.
fn robot(task: &Task, id: i64) -> Robot {
    *task
        .robots
        .iter()
        .find(|r| task.id(r.node).0 == id)
        .expect("a robot of the team")
}

/// Plays `parallel_plan` (`[[{"robot", "action"}]]`) from the start, each joint step in
/// every order through the sequential rules; the state at the end. At most 6 parts a
/// step are permuted in full (720 orders), beyond that every rotation and its reverse.
fn play(task: &Task, name: &str, plan: &[Value]) -> State {
    let mut s = task.init.clone();
    for (k, step) in plan.iter().enumerate() {
        let parts: Vec<(Robot, &str)> = step
            .as_array()
            .expect("a joint step is a list")
            .iter()
            .map(|p| {
                (
                    robot(task, p["robot"].as_i64().expect("a robot id")),
                    p["action"].as_str().expect("an action"),
                )
            })
            .collect();
        assert!(!parts.is_empty(), "{name}: joint step {k} is empty");
        let n = parts.len();
        let tried: Vec<Vec<usize>> = if n <= 6 {
            orders(n)
        } else {
            (0..n)
                .flat_map(|r| {
                    let fwd: Vec<usize> = (0..n).map(|i| (i + r) % n).collect();
                    let back: Vec<usize> = fwd.iter().rev().copied().collect();
                    [fwd, back]
                })
                .collect()
        };
        let mut ends: Vec<State> = Vec::new();
        for order in tried {
            let mut t = s.clone();
            for &i in &order {
                let (r, text) = parts[i];
                let a = feasibility::check(task, &t, r, text).unwrap_or_else(|e| {
                    panic!(
                        "{name}: joint step {k}, order {order:?}: {text}: {}",
                        e.message
                    )
                });
                rules::apply(task, &mut t, r, a);
            }
            ends.push(t);
        }
        assert!(
            ends.iter().all(|e| *e == ends[0]),
            "{name}: joint step {k} ends differently by order"
        );
        s = ends.swap_remove(0);
    }
    s
}

/// Every check of the module's second line on the set `which`; the tasks checked.
fn check_set(which: (&str, &[&str])) -> usize {
    let dir = set(which);
    let lines = manifest(dir);
    assert!(!lines.is_empty());
    let out = coherent(&["validate", utf8(dir)]);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    let planned = plan_lines(&[utf8(dir), "--parallel"]);
    assert_eq!(planned.len(), lines.len(), "a plan line per task");
    let mut sample = Vec::new();
    for (k, m) in lines.iter().enumerate() {
        let id = m["id"].as_str().expect("an id");
        let key = (
            m["scene"].as_str().expect("a scene").to_owned(),
            m["task_id"].as_i64().expect("a task id"),
        );
        let p = &planned[&key];
        assert_eq!(p["optimal_steps"], m["optimal_steps"], "{id}: {p}");
        assert_eq!(
            p["gt_steps"], m["optimal_steps"],
            "{id}: the file's ground truth"
        );
        assert_eq!(p["task_type"], m["type"], "{id}");
        assert_eq!(p["makespan_proven"], m["proven"], "{id}");
        if m["proven"] == Value::Bool(true) {
            assert_eq!(p["makespan"], m["makespan"], "{id}");
        }
        assert_eq!(
            m["bounds"]["makespan"][0], p["makespan_lower"],
            "{id}: the lower bound"
        );
        let file = dir.join(m["file"].as_str().expect("a file"));
        let task = load_tasks(&file).expect("the task reads").remove(0);
        assert_eq!(
            m["team_size"].as_u64(),
            Some(task.robots.len() as u64),
            "{id}"
        );
        let end = play(
            &task,
            id,
            p["parallel_plan"].as_array().expect("a parallel plan"),
        );
        assert!(
            task.goal_satisfied(&end),
            "{id}: the makespan plan reaches the goal"
        );
        if k % 10 == 0 {
            sample.push(file);
        }
    }
    // Every tenth task's optimal plan in Rapier, again (the generator ran them all).
    assert!(sample.len() * 20 >= lines.len(), "at least 5% in physics");
    let physical = scratch(&format!("generate-physics-{}", which.0));
    for file in &sample {
        let rel = file.strip_prefix(dir).expect("under the set");
        let to = physical.join(rel);
        std::fs::create_dir_all(to.parent().expect("a scene folder")).expect("a folder");
        std::fs::copy(file, &to).expect("a copy");
    }
    let ran = plan_lines(&[utf8(&physical), "--physics"]);
    assert_eq!(ran.len(), sample.len());
    for (key, p) in &ran {
        assert_eq!(p["physics_ok"], Value::Bool(true), "{key:?}: {p}");
    }
    lines.len()
}

#[test]
fn every_task_of_a_mixed_set_is_clean_planned_to_its_optimum_and_runs_in_physics() {
    assert_eq!(check_set(MIXED), 20);
}

#[test]
fn every_task_of_a_set_of_large_teams_is_clean_planned_to_its_optimum_and_runs_in_physics() {
    assert_eq!(check_set(LARGE), 6);
    for m in manifest(set(LARGE)) {
        let size = m["team_size"].as_u64().expect("a team size");
        assert!((4..=5).contains(&size), "{m}");
    }
}

#[test]
fn on_generated_tasks_the_makespan_bound_never_overestimates_and_breadth_first_agrees() {
    let (mut checked, mut compared) = (0, 0);
    for which in [MIXED, LARGE, ROOMS] {
        let dir = set(which);
        for m in manifest(dir) {
            let id = m["id"].as_str().expect("an id");
            let file = dir.join(m["file"].as_str().expect("a file"));
            let task = load_tasks(&file).expect("the task reads").remove(0);
            let found = makespan::search(&task, &task.robots, &task.goal, &Limits::default());
            let plan = found.plan.expect("a generated task has a plan");
            checked += oracle::bound_along(&task, &plan, id);
            // Breadth-first over every joint step stays small for short tasks of small
            // teams only.
            if !found.proven || m["optimal_steps"].as_u64() > Some(5) || task.robots.len() > 3 {
                continue;
            }
            if let Some(bfs) = oracle::breadth_first(&task, 30_000) {
                assert_eq!(
                    (plan.len(), oracle::actions(&plan)),
                    bfs,
                    "{id}: (joint steps, actions)"
                );
                compared += 1;
            }
        }
    }
    assert!(checked > 5_000, "only {checked} joint steps checked");
    assert!(compared >= 10, "only {compared} tasks small enough");
}

#[test]
fn export_to_the_original_format_reads_back_to_the_same_tasks() {
    let dir = set(MIXED);
    let work = scratch("generate-export");
    let (original, back) = (work.join("original"), work.join("back"));
    let out = coherent(&[
        "export",
        "--format",
        "original",
        utf8(dir),
        "-o",
        utf8(&original),
    ]);
    assert!(out.status.success(), "{}", show(&out));
    let out = coherent(&["import", utf8(&original), "-o", utf8(&back)]);
    assert!(out.status.success(), "{}", show(&out));
    let key = |t: &Task| (t.meta.scene.clone(), t.meta.task_id);
    let mut made = load_tasks(dir).expect("the set reads");
    let mut read = load_tasks(&back).expect("the imported tasks read");
    made.sort_by_key(key);
    read.sort_by_key(key);
    assert_eq!(made.len(), read.len());
    for (a, b) in made.iter().zip(&read) {
        let name = format!("{} task {}", a.meta.scene, a.meta.task_id);
        assert_eq!(key(a), key(b));
        assert_eq!(
            coherent_core::original::to_value(a),
            coherent_core::original::to_value(b),
            "{name}"
        );
        assert_eq!(a.goal, b.goal, "{name}");
        assert_eq!(a.robots, b.robots, "{name}");
        assert_eq!(
            a.init, b.init,
            "{name}: the same start, every height a label"
        );
        assert_eq!(a.meta.instruction, b.meta.instruction, "{name}");
        assert_eq!(a.meta.gt_steps, b.meta.gt_steps, "{name}");
    }
    // The same optima, read back.
    let (x, y) = (plan_lines(&[utf8(dir)]), plan_lines(&[utf8(&back)]));
    for (k, p) in &x {
        assert_eq!(p["optimal_steps"], y[k]["optimal_steps"], "{k:?}");
        assert_eq!(p["task_type"], y[k]["task_type"], "{k:?}");
    }
}

/// `coherent generate KNOBS` into a fresh folder: its status and stderr.
fn refused(name: &str, knobs: &[&str]) -> (Option<i32>, String) {
    let dir = scratch(&format!("generate-refused-{name}")).join("set");
    let mut args = vec!["generate", "--out", utf8(&dir)];
    args.extend_from_slice(knobs);
    let out = coherent(&args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn knobs_out_of_range_and_requests_that_cannot_be_met_exit_2_naming_the_knob() {
    let cases: &[(&str, &[&str], &[&str])] = &[
        ("tasks", &["--tasks", "0"], &["--tasks", "0"]),
        ("scenes", &["--scenes", "0"], &["--scenes"]),
        ("rooms", &["--rooms", "1-40"], &["--rooms", "1-40"]),
        ("rooms-text", &["--rooms", "many"], &["--rooms", "many"]),
        ("predicates", &["--predicates", "0"], &["--predicates"]),
        ("closed", &["--closed", "1.5"], &["--closed", "1.5"]),
        ("team-kind", &["--team", "tank=2"], &["--team", "tank"]),
        ("team-empty", &["--team", "arm=0"], &["--team"]),
        (
            "type",
            &["--team", "arm=2", "--type", "trio"],
            &["--type", "trio"],
        ),
        ("split", &["--split", "0.5,x,0.1"], &["--split", "x"]),
        (
            "steps",
            &["--tasks", "2", "--steps", "200", "--max-draws", "8"],
            &["--steps", "after 8 draws"],
        ),
    ];
    for (name, knobs, said) in cases {
        let (code, stderr) = refused(name, knobs);
        assert_eq!(code, Some(2), "{name}: {stderr}");
        for s in *said {
            assert!(stderr.contains(s), "{name}: {s:?} not in {stderr}");
        }
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    }
}

#[test]
fn ctrl_c_leaves_the_tasks_written_so_far_whole_and_listed() {
    let dir = scratch("generate-interrupted").join("set");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_coherent"))
        .args([
            "generate",
            "--out",
            utf8(&dir),
            "--tasks",
            "2000",
            "--seed",
            "3",
            "--scenes",
            "4",
        ])
        .args([
            "--robots",
            "3-4",
            "--max-states",
            "20000",
            "--max-memory",
            "128",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("coherent generate starts");
    // Interrupted once some tasks are written, while threads are still searching.
    let start = std::time::Instant::now();
    while json_files(&dir).len() < 3 {
        if let Some(status) = child.try_wait().expect("the child's status") {
            panic!("coherent generate ended first: {status}");
        }
        assert!(
            start.elapsed() < std::time::Duration::from_secs(300),
            "no three tasks written in 5 min"
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let sent = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    let out = child.wait_with_output().expect("coherent generate ends");
    assert_eq!(out.status.code(), Some(130), "{}", show(&out));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("interrupted"),
        "{}",
        show(&out)
    );
    // Every task file is whole and in the manifest; nothing half written is left.
    let listed: Vec<PathBuf> = manifest(&dir)
        .iter()
        .map(|e| dir.join(e["file"].as_str().expect("a file")))
        .collect();
    assert!(!listed.is_empty());
    assert_eq!(json_files(&dir), listed.iter().cloned().collect());
    for file in &listed {
        assert_eq!(load_tasks(file).expect("a whole task").len(), 1);
    }
    let sheet = std::fs::read_to_string(dir.join("README.md")).expect("the datasheet");
    assert!(
        sheet.contains(&format!("{} tasks", listed.len())),
        "{sheet}"
    );
    let hidden = walk(&dir)
        .into_iter()
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        })
        .collect::<Vec<_>>();
    assert!(hidden.is_empty(), "left behind: {hidden:?}");
}

/// The task files written under `dir` so far.
fn json_files(dir: &Path) -> std::collections::BTreeSet<PathBuf> {
    walk(dir)
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect()
}

#[test]
fn a_benchmark_on_a_generated_set_breaks_its_results_down_by_team_size() {
    let dir = set(LARGE);
    let sizes: std::collections::BTreeSet<u64> = manifest(dir)
        .iter()
        .map(|m| m["team_size"].as_u64().expect("a team size"))
        .collect();
    assert!(
        sizes.len() >= 2,
        "the set has teams of several sizes: {sizes:?}"
    );
    let work = scratch("generate-bench");
    for (name, extra) in [
        ("builtin", &[][..]),
        ("simulated", &["--sim-errors", "all=0.1"][..]),
    ] {
        let results = work.join(format!("{name}.jsonl"));
        let mut args = vec![
            "bench",
            "--tasks",
            utf8(dir),
            "--methods",
            "pefa,optimal",
            "--out",
            utf8(&results),
        ];
        args.extend_from_slice(extra);
        let out = coherent(&args);
        assert!(out.status.success(), "{name}: {}", show(&out));
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains("Table III: success rate (SR) and average steps (AS) by team size"),
            "{name}: {text}"
        );
        for n in &sizes {
            assert!(
                text.contains(&format!("| {n} robots (n=")),
                "{name}: no column of {n} robots: {text}"
            );
        }
    }
}

#[test]
fn the_docs_picture_of_a_generated_scene_is_what_the_commands_write() {
    let task = set(MIXED).join("scene-001/task-0001.json");
    let out = scratch("generate-render").join("generated.svg");
    let run = coherent(&["render", utf8(&task), "--plan", "-o", utf8(&out)]);
    assert_eq!(run.status.code(), Some(0), "{}", show(&run));
    let kept = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/render/generated.svg");
    assert!(
        std::fs::read(&out).expect("the render") == std::fs::read(kept).expect("the docs' render"),
        "docs/render/generated.svg is not what docs/generate.md's commands write: regenerate it"
    );
}
