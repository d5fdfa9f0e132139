//! `coherent validate` on seeded mutations of real task files (the mutations of
//! `crates/coherent-core/tests/mutate/mod.rs`, which `fuzz_inputs.rs` there runs in
//! process by the hundred): the exit status is 0, 1 or 2, never a panic, and every error
//! names the file and a JSON path (and the byte offset of text that is not UTF-8).
//!
//! `COHERENT_FUZZ_CASES` (default 24) and `COHERENT_FUZZ_SEED` (default 1) run more or
//! other cases.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

#[path = "../crates/coherent-core/tests/mutate/mod.rs"]
mod mutate;

fn number(var: &str, default: u64) -> u64 {
    std::env::var(var)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// One task of each released file, and a native task of the project's own benchmark.
fn seeds() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    for n in 0..4 {
        let path = Path::new(env!("COHERENT_ORIGINAL_ENV")).join(format!("env{n}.json"));
        let list: Value =
            serde_json::from_str(&std::fs::read_to_string(&path).expect("a released file"))
                .expect("JSON");
        let task = list[n].clone();
        let text = serde_json::to_string_pretty(&Value::Array(vec![task])).expect("JSON");
        out.push((format!("env{n}.json"), text));
    }
    let native = root.join("benchmark/tasks/s2-apartment/task-03.json");
    let text = std::fs::read_to_string(&native).expect("a benchmark task");
    out.push(("task-03.json".to_owned(), text));
    out
}

#[test]
fn validate_on_mutated_files_exits_0_1_or_2_and_names_the_place() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("coherent-cli-fuzz-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let cases = number("COHERENT_FUZZ_CASES", 24);
    let mut rng = mutate::Rng::new(number("COHERENT_FUZZ_SEED", 1));
    let seeds = seeds();
    let mut codes = [0; 3];
    for i in 0..cases {
        let (name, text) = rng.pick(&seeds).clone();
        let (bytes, what) = mutate::mutate(&mut rng, &text);
        let case_dir = dir.join(format!("case-{i}"));
        std::fs::create_dir_all(&case_dir).expect("a scratch folder");
        let file = case_dir.join(&name);
        std::fs::write(&file, &bytes).expect("the mutated file is written");
        let out = Command::new(env!("CARGO_BIN_EXE_coherent"))
            .args(["validate", "--max-states", "2000", "--max-memory", "16"])
            .arg(&file)
            .output()
            .expect("the coherent binary runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        let case = format!(
            "case {i} ({name}: {what}), status {:?}:\n{}{stderr}",
            out.status,
            String::from_utf8_lossy(&out.stdout)
        );
        let code = out.status.code().expect("an exit status, not a signal");
        assert!(
            (0..=2).contains(&code) && !stderr.contains("panicked"),
            "{case}"
        );
        codes[code as usize] += 1;
        let errors: Vec<&str> = stderr
            .lines()
            .filter(|l| l.starts_with("error: "))
            .collect();
        assert_eq!(code == 2, !errors.is_empty(), "{case}");
        let shown = file.display().to_string();
        for e in errors {
            assert!(e.starts_with(&format!("error: {shown}: $")), "{case}");
            if e.contains("UTF-8") {
                assert!(e.contains("byte offset"), "{case}");
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        codes[2] > 0 && codes[0] + codes[1] > 0,
        "exit statuses {codes:?}"
    );
}
