//! The project's own benchmark (`benchmark/`), checked from the planner's and the
//! physics' output rather than from anything the files say about themselves: one hundred
//! valid, solvable tasks of the wanted types and sizes, every optimal plan carried out in
//! Rapier, no task repeated, the 40-task subset in the paper's proportions, and the
//! compiled-in copy equal to the files.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde_json::Value;

mod common;

use common::{coherent, show};

const SCENES: [&str; 5] = [
    "s1-apartment",
    "s2-apartment",
    "s3-grocery",
    "s4-restaurant",
    "s5-house",
];

fn benchmark_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("benchmark")
}

/// `coherent plan <what> --json [extra]`: one object per task, keyed by (scene, id).
fn plan_json(what: &str, extra: &[&str]) -> BTreeMap<(String, i64), Value> {
    let mut args = vec!["plan", what, "--json"];
    args.extend_from_slice(extra);
    let out = coherent(&args);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| {
            let v: Value = serde_json::from_str(l).expect("plan --json prints JSON lines");
            let key = (
                v["scene"].as_str().expect("scene").to_owned(),
                v["task_id"].as_i64().expect("task_id"),
            );
            (key, v)
        })
        .collect()
}

/// Every task file of the benchmark, parsed.
fn task_files() -> Vec<(PathBuf, Value)> {
    let mut out = Vec::new();
    for scene in SCENES {
        let dir = benchmark_dir().join("tasks").join(scene);
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.expect("a directory entry").path())
            .filter(|p| p.extension().is_some_and(|x| x == "json"))
            .collect();
        files.sort();
        for f in files {
            let text = std::fs::read_to_string(&f).expect("a readable task file");
            out.push((f, serde_json::from_str(&text).expect("a JSON task file")));
        }
    }
    out
}

#[test]
fn validate_accepts_the_whole_benchmark() {
    let dir = benchmark_dir();
    let out = coherent(&["validate", dir.to_str().expect("a UTF-8 path")]);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("100 tasks read: 100 clean"),
        "{}",
        show(&out)
    );
}

#[test]
fn the_planner_finds_one_hundred_tasks_of_the_wanted_types_and_sizes() {
    let dir = benchmark_dir();
    let plans = plan_json(dir.to_str().expect("a UTF-8 path"), &[]);
    assert_eq!(plans.len(), 100);
    let mut types: BTreeMap<String, usize> = BTreeMap::new();
    let mut per_scene: BTreeMap<String, usize> = BTreeMap::new();
    for ((scene, id), v) in &plans {
        assert_eq!(v["solvable"], true, "{scene} {id}: {}", v["reason"]);
        let ty = v["task_type"]
            .as_str()
            .unwrap_or_else(|| panic!("{scene} {id}: no task type (the goal holds at the start?)"));
        let optimal = v["optimal_steps"].as_u64().expect("optimal_steps");
        let (lo, hi) = match ty {
            "mono" => (4, 8),
            "dual" => (8, 12),
            "trio" => (10, 16),
            other => panic!("{scene} {id}: unknown type {other}"),
        };
        assert!(
            (lo..=hi).contains(&optimal),
            "{scene} {id}: {ty} with {optimal} optimal steps, outside {lo}-{hi}"
        );
        assert_eq!(
            v["gt_steps"].as_u64(),
            Some(optimal),
            "{scene} {id}: the file's ground truth is not the optimum"
        );
        *types.entry(ty.to_owned()).or_default() += 1;
        *per_scene.entry(scene.clone()).or_default() += 1;
    }
    let want: BTreeMap<String, usize> = [("mono", 32), ("dual", 30), ("trio", 38)]
        .map(|(t, n)| (t.to_owned(), n))
        .into();
    assert_eq!(types, want);
    assert_eq!(
        per_scene,
        SCENES.map(|s| (s.to_owned(), 20)).into_iter().collect()
    );
}

#[test]
fn every_optimal_plan_runs_in_physics() {
    let dir = benchmark_dir();
    let plans = plan_json(dir.to_str().expect("a UTF-8 path"), &["--physics"]);
    assert_eq!(plans.len(), 100);
    let failed: Vec<String> = plans
        .iter()
        .filter(|(_, v)| v["physics_ok"] != true)
        .map(|((scene, id), v)| format!("{scene} {id}: {}", v["physics_error"]))
        .collect();
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
fn no_two_tasks_share_a_goal_and_a_start() {
    let mut seen: BTreeMap<String, String> = BTreeMap::new();
    let mut goals_per_scene: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (file, task) in task_files() {
        let scene = task["scene"].as_str().expect("scene").to_owned();
        let mut goal: Vec<String> = task["goal"]
            .as_array()
            .expect("goal")
            .iter()
            .map(|p| format!("{} {} {}", p["subject"], p["relation"], p["target"]))
            .collect();
        goal.sort();
        // The start: where each robot is, in the graph and in metres.
        let robots: BTreeSet<i64> = task["robots"]
            .as_array()
            .expect("robots")
            .iter()
            .map(|r| r["id"].as_i64().expect("robot id"))
            .collect();
        let mut start: Vec<String> = task["graph"]["edges"]
            .as_array()
            .expect("edges")
            .iter()
            .filter(|e| robots.contains(&e["from_id"].as_i64().expect("from_id")))
            .map(|e| e.to_string())
            .collect();
        start.extend(
            task["geometry"]["robots"]
                .as_array()
                .expect("geometry robots")
                .iter()
                .map(|r| r.to_string()),
        );
        start.sort();
        let key = format!("{scene} | {} | {}", goal.join(", "), start.join(", "));
        if let Some(other) = seen.insert(key, file.display().to_string()) {
            panic!(
                "{} and {other} are the same goal from the same start",
                file.display()
            );
        }
        // Stronger than asked: no goal twice in one scene, whatever the start.
        assert!(
            goals_per_scene
                .entry(scene)
                .or_default()
                .insert(goal.join(", ")),
            "{}: its goal is another task's in the same scene",
            file.display()
        );
    }
    assert_eq!(seen.len(), 100);
}

#[test]
fn the_compiled_in_benchmark_and_its_40_subset_match_the_files() {
    let on_disk = plan_json(benchmark_dir().to_str().expect("a UTF-8 path"), &[]);
    let native = plan_json("native", &[]);
    assert_eq!(
        on_disk.keys().collect::<Vec<_>>(),
        native.keys().collect::<Vec<_>>()
    );
    for (key, v) in &on_disk {
        assert_eq!(v["plan"], native[key]["plan"], "{key:?}");
    }
    // The subset: per scene 2 mono, 3 dual and 3 trio tasks, as the planner types them.
    let text = std::fs::read_to_string(benchmark_dir().join("subset-40.txt"))
        .expect("benchmark/subset-40.txt");
    let mut counts: BTreeMap<(String, String), usize> = BTreeMap::new();
    let mut listed = 0;
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty())
    {
        let (scene, id) = line.split_once(' ').expect("a `scene task_id` line");
        let key = (scene.to_owned(), id.parse::<i64>().expect("a task id"));
        let ty = on_disk[&key]["task_type"]
            .as_str()
            .expect("a type")
            .to_owned();
        *counts.entry((key.0, ty)).or_default() += 1;
        listed += 1;
    }
    assert_eq!(listed, 40);
    for scene in SCENES {
        for (ty, n) in [("mono", 2), ("dual", 3), ("trio", 3)] {
            assert_eq!(
                counts.get(&(scene.to_owned(), ty.to_owned())),
                Some(&n),
                "{scene}: {ty} tasks in the subset"
            );
        }
    }
}
