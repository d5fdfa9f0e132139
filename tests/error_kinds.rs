//! The command line's exit status for each kind of error the session reports and each
//! way an episode ends (`coherent::session::Error`, `session::episode::Ending`;
//! README.md, "Exit status"). Robots over ROS 2 that cannot be reached (2) or stop
//! answering (5) are in `tests/ros.rs`, which makes the network namespaces DDS needs; a
//! method written in Python that raises (4) is in the Python tests, which have the
//! console script that loads one. Python's exception class for each kind:
//! `python/tests/test_errors.py`.

use std::io::{BufReader, Write};
use std::net::TcpListener;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

mod common;

use common::{coherent, demo, read_request, scratch, show, utf8};

fn status(args: &[&str]) -> i32 {
    let out = coherent(args);
    out.status
        .code()
        .unwrap_or_else(|| panic!("killed by a signal: {}", show(&out)))
}

/// The demo task with its door leading to one room only: a graph the rules take, and a
/// scene no layout can be drawn for, so no physical world can be built.
fn one_sided_door(dir: &Path) -> String {
    let mut task: Value =
        serde_json::from_str(&std::fs::read_to_string(demo()).expect("the demo")).expect("JSON");
    let edges = task["graph"]["edges"].as_array_mut().expect("edges");
    edges.retain(|e| !(e["from_id"] == 4 && e["to_id"] == 2 && e["relation_type"] == "LEADING TO"));
    let path = dir.join("one-sided-door.json");
    std::fs::write(&path, task.to_string()).expect("write");
    path.display().to_string()
}

/// A folder with one template that uses a placeholder no method fills.
fn bad_prompts(dir: &Path) -> String {
    let prompts = dir.join("prompts");
    std::fs::create_dir_all(&prompts).expect("a folder");
    std::fs::write(prompts.join("central.txt"), "{{no_such_placeholder}}\n").expect("write");
    prompts.display().to_string()
}

#[test]
fn each_kind_of_error_exits_2_and_nothing_runs() {
    let dir = scratch("error-kinds");
    let d = utf8(&dir).to_owned();
    let demo = demo().display().to_string();
    let out = format!("{d}/runs");
    let results = format!("{d}/results.jsonl");
    let garbage = format!("{d}/garbage.jsonl");
    std::fs::write(&garbage, "not a transcript\n").expect("write");
    let prompts = bad_prompts(&dir);
    let door = one_sided_door(&dir);
    // Each kind, the command that meets it and what the message says.
    let cases: [(&str, Vec<&str>, &str); 8] = [
        // An argument that cannot be used.
        (
            "invalid",
            vec!["run", &demo, "--sim-errors", "bogus", "--out", &out],
            "--sim-errors: \"bogus\"",
        ),
        // The backend's settings do not fit together.
        (
            "backend",
            vec![
                "bench",
                "--tasks",
                &demo,
                "--methods",
                "pefa",
                "--out",
                &results,
                "--backend",
                "replay",
            ],
            "--backend replay and --replay-from FILE go together",
        ),
        // A task file.
        (
            "task",
            vec!["run", "no-such-task.json", "--out", &out],
            "no-such-task.json: ",
        ),
        // A prompt template.
        (
            "prompt",
            vec!["run", &demo, "--prompts", &prompts, "--out", &out],
            "unknown placeholder {{no_such_placeholder}}",
        ),
        // A file of coherent's other formats (a transcript).
        (
            "file",
            vec!["run", "--replay", &garbage, "--out", &out],
            "garbage.jsonl: line 1: ",
        ),
        // A transcript that cannot be created: its folder would be a regular file.
        (
            "no transcript",
            vec!["run", &demo, "--out", &garbage],
            "garbage.jsonl/demo-apartment-task0-pefa-",
        ),
        // An endpoint that cannot be set up.
        (
            "endpoint",
            vec![
                "run",
                &demo,
                "--base-url",
                "not a url",
                "--model",
                "m",
                "--out",
                &out,
            ],
            "is not a URL",
        ),
        // A physical world that cannot be built.
        (
            "physics",
            vec!["run", &door, "--physics", "--out", &out],
            "physics: layout: <door>(4) leads to 1 rooms",
        ),
    ];
    for (kind, args, says) in &cases {
        let run = coherent(args);
        assert_eq!(run.status.code(), Some(2), "{kind}: {}", show(&run));
        let said = String::from_utf8_lossy(&run.stderr);
        assert!(
            said.starts_with("error: ") && said.contains(says),
            "{kind}: {said}"
        );
    }
    assert!(
        !Path::new(&out).exists(),
        "no episode started, so no transcript was written"
    );
}

#[test]
fn each_way_an_episode_ends_has_its_exit_status() {
    let dir = scratch("endings");
    let out = format!("{}/runs", utf8(&dir));
    let demo = demo().display().to_string();
    assert_eq!(
        status(&["run", &demo, "--out", &out]),
        0,
        "the goal reached"
    );
    assert_eq!(
        status(&["run", &demo, "--max-steps", "1", "--out", &out]),
        1,
        "the budget spent"
    );
    // A replay that does not come out as recorded: a summary that says otherwise.
    let recorded = std::fs::read_dir(&out)
        .expect("transcripts")
        .map(|e| e.expect("an entry").path())
        .find(|p| std::fs::read_to_string(p).is_ok_and(|t| t.contains("\"status\":\"success\"")))
        .expect("the first run's transcript");
    let text = std::fs::read_to_string(&recorded).expect("read");
    let tampered = dir.join("tampered.jsonl");
    std::fs::write(&tampered, text.replace("\"steps\":22", "\"steps\":21")).expect("write");
    assert_eq!(
        status(&["run", "--replay", utf8(&tampered), "--out", &out]),
        3,
        "a replay that differs"
    );
    assert_eq!(
        status(&["run", "--replay", utf8(&recorded), "--out", &out]),
        0,
        "the untouched replay"
    );
}

/// A server that refuses the key for good ends the episode (3); Ctrl-C during a model
/// call interrupts it (130).
#[test]
fn a_server_gone_for_good_exits_3_and_ctrl_c_exits_130() {
    let dir = scratch("server-endings");
    let out = format!("{}/runs", utf8(&dir));
    let demo = demo().display().to_string();
    let refusing = TcpListener::bind("127.0.0.1:0").expect("a port");
    let url = format!("http://{}/v1", refusing.local_addr().expect("an address"));
    std::thread::spawn(move || {
        for stream in refusing.incoming().flatten() {
            let mut reader = BufReader::new(stream.try_clone().expect("a stream"));
            if read_request(&mut reader).is_some() {
                let body = "{\"error\": {\"message\": \"bad key\"}}";
                let _ = write!(
                    &stream,
                    "HTTP/1.1 401 Unauthorized\r\ncontent-type: application/json\r\n\
                     content-length: {}\r\n\r\n{body}",
                    body.len()
                );
            }
        }
    });
    let args = [
        "run",
        &demo,
        "--base-url",
        &url,
        "--model",
        "m",
        "--out",
        &out,
    ];
    assert_eq!(status(&args), 3, "the backend failed for good");

    // A server that never answers; Ctrl-C while the first call waits.
    let silent = TcpListener::bind("127.0.0.1:0").expect("a port");
    let url = format!("http://{}/v1", silent.local_addr().expect("an address"));
    let mut run = Command::new(env!("CARGO_BIN_EXE_coherent"))
        .args([
            "run",
            &demo,
            "--base-url",
            &url,
            "--model",
            "m",
            "--out",
            &out,
        ])
        .env_remove("OPENAI_BASE_URL")
        .env_remove("OPENAI_API_KEY")
        .env_remove("COHERENT_MODEL")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("coherent runs");
    let (held, _) = silent.accept().expect("the model call comes");
    let sent = Command::new("kill")
        .args(["-INT", &run.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    let start = Instant::now();
    let code = loop {
        if let Some(status) = run.try_wait().expect("waits") {
            break status.code();
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no end after Ctrl-C"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    drop(held);
    assert_eq!(code, Some(130), "interrupted");
}

/// Coherent's own failure (70): its async runtime takes file descriptors (epoll, an
/// eventfd, a socket pair for signals and a copy of one), so with `ulimit -n` just above
/// what the process needs to start and read its task, it cannot start. Every limit from
/// the lowest the dynamic loader takes up to one that runs the episode ends in the
/// runtime's error with the OS's words (70), a transcript that cannot be opened (2) or
/// the goal reached, never in a panic (tokio panics on the socket pair: 101 before).
#[test]
fn a_runtime_without_file_descriptors_exits_70_and_says_why_at_every_low_limit() {
    let dir = scratch("no-descriptors");
    let out = format!("{}/runs", utf8(&dir));
    let demo = demo().display().to_string();
    let mut runtime_failures = Vec::new();
    let mut ran = false;
    for limit in 3..=64 {
        let run = Command::new("prlimit")
            .arg(format!("--nofile={limit}:{limit}"))
            .arg(env!("CARGO_BIN_EXE_coherent"))
            .args(["run", &demo, "--out", &out])
            .env_remove("OPENAI_BASE_URL")
            .env_remove("OPENAI_API_KEY")
            .env_remove("COHERENT_MODEL")
            .output()
            .expect("prlimit (util-linux) runs");
        let said = String::from_utf8_lossy(&run.stderr);
        match run.status.code() {
            // Too few for the dynamic loader to open the binary's libraries.
            Some(127) if said.contains("error while loading shared libraries") => {}
            Some(70) => {
                assert!(
                    said.starts_with("error: cannot start the async runtime: ")
                        && said.contains("Too many open files")
                        && !said.contains("panicked"),
                    "limit {limit}: {said}"
                );
                runtime_failures.push(limit);
            }
            Some(2) => assert!(
                said.contains(".jsonl: Too many open files"),
                "limit {limit}: only the transcript may fail for want of descriptors: {}",
                show(&run)
            ),
            Some(0) => {
                ran = true;
                break;
            }
            _ => panic!("limit {limit}: {}", show(&run)),
        }
    }
    assert!(ran, "64 descriptors are enough to run the demo");
    // The lowest limit the loader takes leaves the process one descriptor after its
    // task is read; the runtime needs five, so at least four limits in a row fail.
    assert!(
        runtime_failures.len() >= 4,
        "the runtime fails at the lowest limits: {runtime_failures:?}"
    );
}
