//! Fixtures shared by the benches: the paper's released tasks, read from
//! `COHERENT_ORIGINAL_ENV` (`.cargo/config.toml`: beside the checkout).

use std::path::PathBuf;

use coherent_core::{Task, load};

pub fn env_dir() -> PathBuf {
    PathBuf::from(env!("COHERENT_ORIGINAL_ENV"))
}

/// The well-formed tasks of scene `envN` (a malformed one, env3's index 18, is skipped).
pub fn scene(n: usize) -> Vec<Task> {
    let path = env_dir().join(format!("env{n}.json"));
    load::read_tasks(&path)
        .unwrap_or_else(|e| panic!("{e}"))
        .into_iter()
        .filter_map(Result::ok)
        .collect()
}

/// Task `id` of scene `envN`.
pub fn task(n: usize, id: i64) -> Task {
    scene(n)
        .into_iter()
        .find(|t| t.meta.task_id == id)
        .unwrap_or_else(|| panic!("env{n} has no task {id}"))
}
