//! Fuzzing the readers and the validator with seeded mutations of real task files
//! (`mutate/mod.rs`): single tasks of the four released files and a native task of the
//! project's own benchmark. Whatever the mutation, reading never panics, every error
//! names the file and a JSON path (a byte offset too where the text is not UTF-8) and
//! stays short, and a task that reads is planned and validated without a panic.
//!
//! `COHERENT_FUZZ_CASES` (default 400) and `COHERENT_FUZZ_SEED` (default 1) run more or
//! other cases.

use std::path::Path;

use coherent_core::planner::{self, Limits};
use coherent_core::{Error, json, load, validate};
use serde_json::Value;

mod common;
mod mutate;

/// The seed files: one task of each released file, and the first native benchmark task.
fn seeds() -> Vec<(String, String)> {
    let mut out = Vec::new();
    for n in 0..4 {
        let task = common::original_list(n).swap_remove(n);
        let text = serde_json::to_string_pretty(&Value::Array(vec![task])).expect("JSON");
        out.push((format!("env{n}.json"), text));
    }
    let native = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../benchmark/tasks/s1-apartment/task-00.json");
    let text = std::fs::read_to_string(&native).expect("a benchmark task");
    out.push(("task-00.json".to_owned(), text));
    out
}

fn number(var: &str, default: u64) -> u64 {
    std::env::var(var)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Checks one error of reading `file`; `case` says how to replay it.
fn check_error(e: &Error, file: &str, case: &str) {
    let line = e.to_string();
    let Error::Malformed { file: f, path, .. } = e else {
        panic!("{case}: not a Malformed error: {line}");
    };
    assert_eq!(f, file, "{case}: {line}");
    assert!(
        line.starts_with(&format!("{file}: {path}: ")) && path.to_string().starts_with('$'),
        "{case}: {line}"
    );
    if line.contains("UTF-8") {
        assert!(line.contains("byte offset"), "{case}: {line}");
    }
    assert!(
        line.len() < 1_500,
        "{case}: a message of {} bytes: {}",
        line.len(),
        &line[..300]
    );
}

#[test]
fn mutated_task_files_read_and_validate_without_panics() {
    let cases = number("COHERENT_FUZZ_CASES", 400);
    let mut rng = mutate::Rng::new(number("COHERENT_FUZZ_SEED", 1));
    let seeds = seeds();
    let limits = Limits {
        max_memory: 8 << 20,
        ..Limits::max_states(2_000)
    };
    let (mut refused, mut read, mut flagged) = (0, 0, 0);
    for i in 0..cases {
        let (file, text) = rng.pick(&seeds).clone();
        let (bytes, what) = mutate::mutate(&mut rng, &text);
        let case = format!("case {i} ({file}: {what})");
        let scene = file.trim_end_matches(".json");
        let tasks =
            match json::parse(&file, &bytes).and_then(|v| load::read_value(&file, scene, &v)) {
                Ok(tasks) => tasks,
                Err(e) => {
                    check_error(&e, &file, &case);
                    refused += 1;
                    continue;
                }
            };
        for task in tasks {
            match task {
                Err(e) => {
                    check_error(&e, &file, &case);
                    refused += 1;
                }
                Ok(task) => {
                    read += 1;
                    let analysis = planner::analyse(&task, &limits);
                    if !validate::findings(&task, &analysis).is_empty() {
                        flagged += 1;
                    }
                }
            }
        }
    }
    // The mutations reach every stage: some files are refused, some read and flagged.
    assert!(
        refused > cases / 4 && read > cases / 10 && flagged > 0,
        "{refused} refused, {read} read, {flagged} with findings of {cases} cases"
    );
}
