//! `coherent bench` as a separate process: an end-to-end run on the paper40 tasks of
//! env0, resume, `--report` in every format, our own benchmark's native40 subset, the
//! exit status of bad input, and a second run refused while one holds its results file.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::Duration;

mod common;

use common::{coherent, demo, env0, scratch, show, silent_server, utf8};

/// Asserts that `out` exited 0 and that its stdout says each of `texts`.
fn says(out: &Output, texts: &[&str]) {
    assert_eq!(out.status.code(), Some(0), "{}", show(out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    for text in texts {
        assert!(stdout.contains(text), "no {text:?} in:\n{}", show(out));
    }
}

#[test]
fn bench_runs_paper40_of_env0_end_to_end_then_resumes_without_rerunning() {
    let dir = scratch("e2e");
    let out = dir.join("results.jsonl");
    let tasks = env0();
    let args = [
        "bench",
        "--tasks",
        tasks.to_str().expect("UTF-8 path"),
        "--subset",
        "paper40",
        "--methods",
        "pefa,mcts",
        "--backend",
        "builtin",
        "--out",
        out.to_str().expect("UTF-8 path"),
    ];
    let first = coherent(&args);
    says(
        &first,
        &[
            "tasks: 8 of subset paper40 present",
            "missing: 32 of 40",
            "16 episodes: 0 already finished, 16 finished now, 0 unfinished;",
            "### Table I",
            // The built-in backend is the optimal planner: PEFA solves all 8.
            "| pefa | 1.000 / ",
            "| Ground truth |",
            "Backend: builtin: optimal-planner",
        ],
    );
    let lines = std::fs::read_to_string(&out).expect("results file");
    assert_eq!(lines.lines().count(), 16);
    let first_line: serde_json::Value =
        serde_json::from_str(lines.lines().next().expect("a line")).expect("JSON");
    for field in [
        "method",
        "scene",
        "task_id",
        "task_type",
        "seed",
        "success",
        "status",
        "steps",
        "gt_steps",
        "max_steps",
        "llm_calls",
        "prompt_tokens",
        "completion_tokens",
        "wall_ms",
        "backend",
        "transcript",
    ] {
        assert!(
            first_line.get(field).is_some(),
            "{field} missing: {first_line}"
        );
    }
    let transcript = first_line["transcript"].as_str().expect("a path");
    assert!(Path::new(transcript).starts_with(dir.join("results.transcripts")));
    assert!(Path::new(transcript).exists());

    let second = coherent(&args);
    says(
        &second,
        &["16 episodes: 16 already finished, 0 finished now, 0 unfinished;"],
    );
    let lines = std::fs::read_to_string(&out).expect("results file");
    assert_eq!(lines.lines().count(), 16, "nothing ran twice");

    let out_s = out.to_str().expect("UTF-8 path");
    let md = coherent(&["bench", "--report", out_s]);
    assert_eq!(md.status.code(), Some(0), "{}", show(&md));
    assert!(String::from_utf8_lossy(&md.stdout).contains("### Table II"));
    let csv = coherent(&["bench", "--report", out_s, "--format", "csv"]);
    assert_eq!(csv.status.code(), Some(0), "{}", show(&csv));
    let csv = String::from_utf8_lossy(&csv.stdout);
    assert!(csv.starts_with("table,method,column,"), "{csv}");
    assert!(csv.contains("\nI,mcts,Avg,8,8,0.000000,"), "{csv}");
    let json = coherent(&["bench", "--report", out_s, "--format", "json"]);
    let value: serde_json::Value = serde_json::from_slice(&json.stdout).expect("JSON report");
    assert_eq!(value["table1"]["rows"][0]["method"], "pefa");
    assert_eq!(value["table1"]["rows"][0]["cells"][3]["sr"]["mean"], 1.0);
}

/// Our own benchmark, compiled in: its 40-task subset by name, with no files at hand.
#[test]
fn bench_runs_the_native40_subset_of_our_benchmark() {
    let dir = scratch("native");
    let out = dir.join("results.jsonl");
    let run = coherent(&[
        "bench",
        "--tasks",
        "native",
        "--subset",
        "native40",
        "--methods",
        "pefa",
        "--backend",
        "builtin",
        "--out",
        out.to_str().expect("UTF-8 path"),
    ]);
    says(
        &run,
        &[
            "tasks: 40 of subset native40 (40 listed) present",
            "40 episodes: 0 already finished, 40 finished now, 0 unfinished;",
            "| pefa | 1.000 / 7.2 | 1.000 / 10.5 | 1.000 / 14.5 | 1.000 / 11.2 |",
            "s5-house (n=8)",
        ],
    );
}

#[test]
fn an_unknown_method_exits_2_and_lists_the_methods() {
    let dir = scratch("unknown");
    let tasks = env0();
    let out = coherent(&[
        "bench",
        "--tasks",
        tasks.to_str().expect("UTF-8 path"),
        "--methods",
        "pefa,telepathy",
        "--out",
        dir.join("r.jsonl").to_str().expect("UTF-8 path"),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("telepathy"), "{err}");
    for m in ["pefa", "pefa-no-history", "mcts", "llm-mcts"] {
        assert!(err.contains(m), "{m} not listed: {err}");
    }
}

#[test]
fn bad_input_exits_2_naming_the_file_and_line() {
    let dir = scratch("bad");
    let results = dir.join("r.jsonl");
    std::fs::write(&results, "{\"method\": 1}\n{}\n").expect("write");
    let out = coherent(&["bench", "--report", results.to_str().expect("UTF-8 path")]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("r.jsonl: line 1"), "{err}");

    let tasks = env0();
    let out = coherent(&[
        "bench",
        "--tasks",
        tasks.to_str().expect("UTF-8 path"),
        "--methods",
        "pefa",
        "--sim-errors",
        "hallucinate=2",
        "--out",
        dir.join("s.jsonl").to_str().expect("UTF-8 path"),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--sim-errors"));
    let missing = dir.join("no-such-subset.txt");
    let out = coherent(&[
        "bench",
        "--tasks",
        tasks.to_str().expect("UTF-8 path"),
        "--methods",
        "pefa",
        "--subset",
        missing.to_str().expect("UTF-8 path"),
        "--out",
        dir.join("t.jsonl").to_str().expect("UTF-8 path"),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no-such-subset.txt"));
}

#[test]
fn backend_replay_reruns_an_earlier_results_file_from_its_transcripts() {
    let dir = scratch("replay");
    let (recorded, replayed) = (dir.join("recorded.jsonl"), dir.join("replayed.jsonl"));
    let tasks = env0();
    let tasks = tasks.to_str().expect("UTF-8 path");
    let run = |out: &Path, backend: &[&str]| {
        let mut args = vec![
            "bench",
            "--tasks",
            tasks,
            "--subset",
            "paper40",
            "--methods",
            "pefa,cmrs",
        ];
        args.extend_from_slice(backend);
        args.extend_from_slice(&[
            "--out",
            out.to_str().expect("UTF-8 path"),
            "--format",
            "csv",
        ]);
        coherent(&args)
    };
    let first = run(
        &recorded,
        &["--backend", "simulated", "--sim-errors", "all=0.2"],
    );
    assert_eq!(first.status.code(), Some(0), "{}", show(&first));
    let from = recorded.to_str().expect("UTF-8 path");
    let again = run(&replayed, &["--backend", "replay", "--replay-from", from]);
    assert_eq!(again.status.code(), Some(0), "{}", show(&again));
    let stdout = String::from_utf8_lossy(&again.stdout);
    assert!(stdout.contains("backend: replay"), "{}", show(&again));
    // The same episodes, the same tables: only the backend's label differs.
    let table = |out: &Output| -> Vec<String> {
        let text = String::from_utf8_lossy(&out.stdout);
        let csv = &text[text.find("table,method").expect("the CSV tables")..];
        // The backend is the last field, quoted (it holds commas).
        csv.lines()
            .map(|l| l.split(",\"").next().unwrap_or(l).to_owned())
            .collect()
    };
    assert_eq!(table(&first), table(&again));
    let lines = std::fs::read_to_string(&replayed).expect("results");
    assert_eq!(lines.lines().count(), 16);
    assert!(!lines.contains("replay mismatch"), "{lines}");

    let bad = run(&dir.join("x.jsonl"), &["--backend", "replay"]);
    assert_eq!(bad.status.code(), Some(2), "{}", show(&bad));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--replay-from FILE"));
}

#[test]
fn a_second_bench_on_the_same_results_file_is_refused_and_touches_nothing() {
    let dir = scratch("two-runs");
    let (url, requests) = silent_server();
    let demo = demo();
    let out = dir.join("results.jsonl");
    // `--timeout`: the first run waits on the silent server until it is killed; a second
    // one, were it let run, would give up at once.
    let args = |out: &Path, timeout: &str| -> Vec<String> {
        let mut args: Vec<String> = ["bench", "--tasks", utf8(&demo), "--methods", "pefa,cmrs"]
            .map(str::to_owned)
            .to_vec();
        for (flag, value) in [
            ("--base-url", url.as_str()),
            ("--model", "m"),
            ("--max-retries", "0"),
            ("--timeout", timeout),
            ("--out", utf8(out)),
        ] {
            args.extend([flag.to_owned(), value.to_owned()]);
        }
        args
    };
    let mut first = Command::new(env!("CARGO_BIN_EXE_coherent"))
        .args(args(&out, "600"))
        .env_remove("OPENAI_API_KEY")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("coherent starts");
    // Both episodes are in flight, their transcripts open.
    for _ in 0..2 {
        requests
            .recv_timeout(Duration::from_secs(60))
            .expect("a model request");
    }
    let transcripts = || -> Vec<String> {
        let seed0 = dir.join("results.transcripts/seed0");
        let mut names: Vec<String> = std::fs::read_dir(seed0)
            .expect("the transcripts")
            .map(|e| {
                e.expect("an entry")
                    .file_name()
                    .to_string_lossy()
                    .into_owned()
            })
            .collect();
        names.sort();
        names
    };
    let before = transcripts();
    assert_eq!(before.len(), 2, "{before:?}");
    // The same file, and another whose transcripts share the folder.
    for other in [out.clone(), dir.join("results.json")] {
        let second_args = args(&other, "1");
        let second_args: Vec<&str> = second_args.iter().map(String::as_str).collect();
        let second = coherent(&second_args);
        let err = String::from_utf8_lossy(&second.stderr);
        assert_eq!(second.status.code(), Some(2), "{}", show(&second));
        let holder = format!(
            "another benchmark run is using it (process {} holds",
            first.id()
        );
        assert!(err.contains(&holder), "{err}");
        assert_eq!(transcripts(), before, "nothing renamed");
    }
    assert_eq!(std::fs::read_to_string(&out).unwrap_or_default(), "");
    assert!(!dir.join("results.json").exists());
    let _ = first.kill();
    let _ = first.wait();
    let _ = std::fs::remove_dir_all(&dir);
}

/// `bench --physics` carries every episode's actions out in Rapier too: the demo's
/// optimal plan succeeds in its 22 steps, and its transcript says it ran in physics.
#[test]
fn bench_physics_runs_each_episode_in_rapier_too() {
    let dir = scratch("bench-physics");
    let out = dir.join("results.jsonl");
    let demo = common::demo();
    let args = [
        "bench",
        "--tasks",
        common::utf8(&demo),
        "--methods",
        "optimal",
        "--physics",
        "--out",
        common::utf8(&out),
    ];
    let ran = coherent(&args);
    assert_eq!(ran.status.code(), Some(0), "{}", show(&ran));
    let text = std::fs::read_to_string(&out).expect("results file");
    let line: serde_json::Value = serde_json::from_str(text.trim()).expect("one line");
    assert_eq!(
        (line["success"].clone(), line["steps"].clone()),
        (true.into(), 22.into())
    );
    let transcript = std::fs::read_to_string(line["transcript"].as_str().expect("a path"))
        .expect("the transcript");
    let header: serde_json::Value =
        serde_json::from_str(transcript.lines().next().expect("a header")).expect("JSON");
    assert_eq!(header["physics"], true);
    assert_eq!(header["robots"], serde_json::json!({"kind": "local"}));
}
