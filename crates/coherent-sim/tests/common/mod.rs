//! The released benchmark tasks and their optimal plans, shared by the physics tests.
#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::Arc;

use coherent_core::planner::{self, Limits, Step};
use coherent_core::{Task, load_tasks, read_tasks};

/// The original benchmark files, from `COHERENT_ORIGINAL_ENV` (`.cargo/config.toml`:
/// beside the checkout).
pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("COHERENT_ORIGINAL_ENV"))
}

/// Every well-formed task of the four files (env3 index 18 is malformed by design).
pub fn released_tasks() -> Vec<Arc<Task>> {
    let mut out = Vec::new();
    for n in 0..4 {
        let path = data_dir().join(format!("env{n}.json"));
        for (i, t) in read_tasks(&path)
            .expect("benchmark file loads")
            .into_iter()
            .enumerate()
        {
            match t {
                Ok(t) => out.push(Arc::new(t)),
                Err(e) => assert!(n == 3 && i == 18, "env{n}[{i}] is malformed: {e}"),
            }
        }
    }
    assert_eq!(out.len(), 81);
    out
}

pub fn task(scene: &str, id: i64) -> Arc<Task> {
    released_tasks()
        .into_iter()
        .find(|t| t.meta.scene == scene && t.meta.task_id == id)
        .expect("task exists")
}

pub fn optimal_plan(task: &Task) -> Option<Vec<Step>> {
    planner::analyse(task, &Limits::default()).plan
}

pub fn name(t: &Task) -> String {
    format!("{} task {}", t.meta.scene, t.meta.task_id)
}

/// The bundled demo task (examples/tasks/demo.json).
pub fn demo() -> Task {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/tasks/demo.json");
    load_tasks(&path).expect("the demo task loads").remove(0)
}

/// Task `id` of scene `scene` of our own benchmark (compiled in).
pub fn native_task(scene: &str, id: i64) -> Arc<Task> {
    coherent_core::benchmark::tasks()
        .expect("the benchmark loads")
        .into_iter()
        .find(|t| t.meta.scene == scene && t.meta.task_id == id)
        .map(Arc::new)
        .expect("task exists")
}
