//! The command line on seeded mutations of real files (the mutations of
//! `crates/coherent-core/tests/mutate/mod.rs`, which `fuzz_inputs.rs` there runs in
//! process by the hundred): task files through `coherent validate`, whose exit status is
//! 0, 1 or 2 and whose every error names the file and a JSON path (and the byte offset
//! of text that is not UTF-8); and the other files a run reads: prompt folders
//! (`--prompts`), price tables (`--prices`), results files (`bench --report` and a
//! resumed `bench --out`) and transcripts (`run --replay`). None may panic, and every
//! error names the file it is about.
//!
//! `COHERENT_FUZZ_CASES` (default 24 task files, and half as many of each other kind)
//! and `COHERENT_FUZZ_SEED` (default 1) run more or other cases.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

#[path = "../crates/coherent-core/tests/mutate/mod.rs"]
mod mutate;

mod common;

use common::{coherent, demo, scratch, show, utf8};

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

/// Runs `coherent ARGS` for fuzz case `case`: the exit status must be one of `codes`,
/// nothing may panic, and every error line must name `file`. Returns the status.
fn fuzzed(case: &str, args: &[&str], codes: &[i32], file: &str) -> i32 {
    let out = coherent(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let seen = format!("{case}: {args:?}\n{}", show(&out));
    let code = out
        .status
        .code()
        .unwrap_or_else(|| panic!("killed by a signal: {seen}"));
    assert!(
        codes.contains(&code) && !stderr.contains("panicked"),
        "{seen}"
    );
    for e in stderr.lines().filter(|l| l.starts_with("error: ")) {
        assert!(e.contains(file), "the error does not name {file}: {seen}");
    }
    code
}

fn cases() -> u64 {
    number("COHERENT_FUZZ_CASES", 24).div_ceil(2)
}

fn rng(salt: u64) -> mutate::Rng {
    mutate::Rng::new(number("COHERENT_FUZZ_SEED", 1).wrapping_add(salt))
}

#[test]
fn runs_with_mutated_prompt_templates_go_on_or_exit_2_naming_the_template() {
    let dir = scratch("fuzz-prompts");
    let prompts = dir.join("prompts");
    let exported = coherent(&["prompts", "export", utf8(&prompts)]);
    assert_eq!(exported.status.code(), Some(0), "{}", show(&exported));
    let demo = demo();
    let runs = dir.join("runs");
    let names: Vec<String> = std::fs::read_dir(&prompts)
        .expect("the templates")
        .map(|e| {
            e.expect("an entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    let mut rng = rng(11);
    let mut codes = Vec::new();
    for i in 0..cases() {
        let name = rng.pick(&names).clone();
        let file = prompts.join(&name);
        let builtin = std::fs::read_to_string(&file).expect("a template");
        let (bytes, what) = mutate::mutate_text(&mut rng, &builtin);
        std::fs::write(&file, &bytes).expect("written");
        let case = format!("case {i} ({name}: {what})");
        let args = [
            "run",
            utf8(&demo),
            "--prompts",
            utf8(&prompts),
            "--out",
            utf8(&runs),
        ];
        codes.push(fuzzed(&case, &args, &[0, 1, 2], &name));
        std::fs::write(&file, builtin).expect("put back");
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(codes.contains(&2), "exit statuses {codes:?}");
}

#[test]
fn mutated_price_tables_price_or_exit_2_naming_the_file() {
    let dir = scratch("fuzz-prices");
    let seed = serde_json::json!({
        "gpt-4o": {"input": 2.5, "cached_input": 1.25, "output": 10.0,
                   "date": "2026-11-01", "source": "https://openai.com/api/pricing/"},
        "smollm2": {"input": 0.01, "output": 0.02},
    });
    let seed = serde_json::to_string_pretty(&seed).expect("JSON");
    let empty = dir.join("results.jsonl");
    std::fs::write(&empty, "").expect("an empty results file");
    let mut rng = rng(12);
    let mut codes = Vec::new();
    for i in 0..cases() {
        let (bytes, what) = mutate::mutate(&mut rng, &seed);
        let file = dir.join(format!("prices-{i}.json"));
        std::fs::write(&file, &bytes).expect("written");
        let case = format!("case {i} ({what})");
        let args = ["bench", "--report", utf8(&empty), "--prices", utf8(&file)];
        codes.push(fuzzed(&case, &args, &[0, 2], utf8(&file)));
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(codes.contains(&2), "exit statuses {codes:?}");
}

#[test]
fn mutated_results_files_report_and_resume_or_exit_2_naming_the_file() {
    let dir = scratch("fuzz-results");
    let demo = demo();
    let seed = dir.join("seed.jsonl");
    let bench = |out: &Path| {
        coherent(&[
            "bench",
            "--tasks",
            utf8(&demo),
            "--methods",
            "optimal,pefa",
            "--seeds",
            "2",
            "--out",
            utf8(out),
        ])
    };
    let ran = bench(&seed);
    assert_eq!(ran.status.code(), Some(0), "{}", show(&ran));
    let text = std::fs::read_to_string(&seed).expect("the results");
    let mut rng = rng(13);
    let mut codes = Vec::new();
    for i in 0..cases() {
        let (bytes, what) = mutate::mutate_lines(&mut rng, &text);
        let file = dir.join(format!("results-{i}.jsonl"));
        std::fs::write(&file, &bytes).expect("written");
        let case = format!("case {i} ({what})");
        let shown = utf8(&file);
        codes.push(fuzzed(&case, &["bench", "--report", shown], &[0, 2], shown));
        let resumed = bench(&file);
        let code = resumed.status.code().unwrap_or(-1);
        let err = String::from_utf8_lossy(&resumed.stderr);
        assert!(
            [0, 2].contains(&code) && !err.contains("panicked"),
            "{case}: resumed\n{}",
            show(&resumed)
        );
        for e in err.lines().filter(|l| l.starts_with("error: ")) {
            assert!(e.contains(shown), "{case}: resumed\n{}", show(&resumed));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        codes.contains(&2) && codes.contains(&0),
        "exit statuses {codes:?}"
    );
}

#[test]
fn mutated_transcripts_replay_or_exit_with_a_status_naming_the_file() {
    let dir = scratch("fuzz-transcripts");
    let demo = demo();
    let recorded = dir.join("recorded");
    let ran = coherent(&["run", utf8(&demo), "--out", utf8(&recorded)]);
    assert_eq!(ran.status.code(), Some(0), "{}", show(&ran));
    let path = std::fs::read_dir(&recorded)
        .expect("the transcript's folder")
        .next()
        .expect("a transcript")
        .expect("an entry")
        .path();
    let text = std::fs::read_to_string(&path).expect("the transcript");
    let runs = dir.join("runs");
    let mut rng = rng(14);
    let mut codes = Vec::new();
    for i in 0..cases() {
        let (bytes, what) = mutate::mutate_lines(&mut rng, &text);
        let file = dir.join(format!("transcript-{i}.jsonl"));
        std::fs::write(&file, &bytes).expect("written");
        let case = format!("case {i} ({what})");
        let shown = utf8(&file);
        let args = ["run", "--replay", shown, "--out", utf8(&runs)];
        codes.push(fuzzed(&case, &args, &[0, 1, 2, 3], shown));
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(codes.contains(&2), "exit statuses {codes:?}");
}
