//! Prompt files at run time and cost, through the `coherent` binary: `prompts export`,
//! an edited template that reaches the model (a stub OpenAI-compatible server on a
//! loopback socket records what it is sent), the transcript header's record of the set,
//! replays of it, a template with an unknown placeholder refused with exit 2 before any
//! request, and `--prices` turning the server's token counts into `cost_usd`.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::process::Output;
use std::sync::{Arc, Mutex};

use serde_json::{Value, json};

mod common;

use common::{answer, coherent, demo, scratch, show, utf8};

/// What the stub server answers every call with, in tokens.
const PROMPT_TOKENS: u64 = 1000;
const CACHED_TOKENS: u64 = 400;
const COMPLETION_TOKENS: u64 = 50;

/// A chat-completions server on 127.0.0.1 that records every request body and answers
/// each role with a valid choice: the first robot, the first action of the list.
struct Stub {
    url: String,
    seen: Arc<Mutex<Vec<Value>>>,
}

impl Stub {
    fn start() -> Stub {
        let listener = TcpListener::bind("127.0.0.1:0").expect("bind loopback");
        let url = format!("http://{}/v1", listener.local_addr().expect("address"));
        let seen = Arc::new(Mutex::new(Vec::new()));
        let log = Arc::clone(&seen);
        std::thread::spawn(move || {
            for socket in listener.incoming().flatten() {
                let log = Arc::clone(&log);
                std::thread::spawn(move || serve(socket, &log));
            }
        });
        Stub { url, seen }
    }

    fn requests(&self) -> Vec<Value> {
        self.seen.lock().expect("log").clone()
    }
}

/// Answers the requests of one connection (HTTP/1.1 keep-alive) until it closes.
fn serve(socket: TcpStream, log: &Mutex<Vec<Value>>) {
    let mut reader = BufReader::new(socket.try_clone().expect("a second handle"));
    let mut writer = socket;
    loop {
        let mut length = None;
        loop {
            let mut line = String::new();
            if reader.read_line(&mut line).unwrap_or(0) == 0 {
                return;
            }
            if line == "\r\n" {
                break;
            }
            if let Some((name, value)) = line.split_once(':')
                && name.eq_ignore_ascii_case("content-length")
            {
                length = value.trim().parse::<usize>().ok();
            }
        }
        let mut body = vec![0; length.unwrap_or(0)];
        if reader.read_exact(&mut body).is_err() {
            return;
        }
        let request: Value = serde_json::from_slice(&body).unwrap_or(Value::Null);
        let answer = answer(&request);
        log.lock().expect("log").push(request);
        let reply = json!({
            "choices": [{"index": 0, "message": {"role": "assistant", "content": answer}, "finish_reason": "stop"}],
            "usage": {
                "prompt_tokens": PROMPT_TOKENS,
                "completion_tokens": COMPLETION_TOKENS,
                "prompt_tokens_details": {"cached_tokens": CACHED_TOKENS},
            },
        })
        .to_string();
        let head = format!(
            "HTTP/1.1 200 OK\r\ncontent-type: application/json\r\ncontent-length: {}\r\n\r\n",
            reply.len()
        );
        if writer
            .write_all(head.as_bytes())
            .and_then(|()| writer.write_all(reply.as_bytes()))
            .is_err()
        {
            return;
        }
    }
}

/// The transcript a `--json` run names.
fn transcript(out: &Output) -> (Value, Vec<Value>) {
    let summary: Value = serde_json::from_slice(&out.stdout).expect("a JSON summary");
    let path = summary["transcript"].as_str().expect("a transcript path");
    let text = std::fs::read_to_string(path).expect("the transcript reads");
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON lines"))
        .collect();
    (summary, lines)
}

#[test]
fn export_writes_every_template_and_does_not_overwrite_unasked() {
    let dir = scratch("export").join("d");
    let d = utf8(&dir);
    let out = coherent(&["prompts", "export", d]);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .expect("the folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "assigner_parallel_system.txt",
            "assigner_parallel_user.txt",
            "assigner_system.txt",
            "assigner_user.txt",
            "central.txt",
            "central_parallel.txt",
            "dmrs_speaker.txt",
            "dmrs_speaker_parallel.txt",
            "executor_quadrotor.txt",
            "executor_robot_arm.txt",
            "executor_robot_dog.txt",
            "executor_user.txt",
            "goal.txt"
        ]
    );
    let again = coherent(&["prompts", "export", d]);
    assert_eq!(again.status.code(), Some(2), "{}", show(&again));
    assert!(String::from_utf8_lossy(&again.stderr).contains("--force"));
    let forced = coherent(&["prompts", "export", d, "--force"]);
    assert_eq!(forced.status.code(), Some(0), "{}", show(&forced));
}

#[test]
fn an_edited_template_reaches_the_model_and_the_transcript_records_the_set() {
    let root = scratch("edited");
    let dir = root.join("d");
    let export = coherent(&["prompts", "export", utf8(&dir)]);
    assert_eq!(export.status.code(), Some(0), "{}", show(&export));
    let user = dir.join("assigner_user.txt");
    let text = std::fs::read_to_string(&user).expect("exported");
    let edited = text.replace(
        "Give one robot one subtask.",
        "EDITED-7f3a: one robot, one subtask.",
    );
    assert_ne!(edited, text, "the line to edit is in the built-in template");
    std::fs::write(&user, &edited).expect("edited");
    let prices = root.join("prices.toml");
    std::fs::write(
        &prices,
        "[\"stub-model\"]\ninput = 2.0\ncached_input = 0.5\noutput = 8.0\n",
    )
    .expect("a price file");

    let stub = Stub::start();
    let runs = root.join("runs");
    let demo = demo();
    let args = [
        "run",
        utf8(&demo),
        "--prompts",
        utf8(&dir),
        "--prices",
        utf8(&prices),
        "--base-url",
        &stub.url,
        "--model",
        "stub-model",
        "--max-steps",
        "2",
        "--out",
        utf8(&runs),
        "--json",
    ];
    let out = coherent(&args);
    assert_eq!(out.status.code(), Some(1), "budget spent: {}", show(&out));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("prompts: assigner_user.txt in place of the built-in templates"),
        "{}",
        show(&out)
    );

    // The edited text went to the server, in every assigner request, and nothing of the
    // replaced line did.
    let requests = stub.requests();
    assert_eq!(requests.len(), 4, "two rounds of two calls");
    let assigner: Vec<&Value> = requests
        .iter()
        .filter(|r| r["response_format"]["json_schema"]["name"] == "proposal")
        .collect();
    assert_eq!(assigner.len(), 2);
    for r in &assigner {
        let sent = r["messages"].to_string();
        assert!(
            sent.contains("EDITED-7f3a: one robot, one subtask."),
            "{sent}"
        );
        assert!(!sent.contains("Give one robot one subtask."), "{sent}");
    }

    // The transcript shows it, and its header records the set.
    let (summary, lines) = transcript(&out);
    let header = &lines[0];
    let record = &header["prompts"];
    assert_eq!(
        record["replaced"]["assigner_user.txt"].as_str(),
        Some(edited.as_str())
    );
    assert_eq!(record["replaced"].as_object().map(|m| m.len()), Some(1));
    let hash = record["hash"].as_str().expect("a hash");
    assert_eq!(hash.len(), 32);
    let first_call = &lines[1]["calls"][0]["messages"];
    assert!(
        first_call.to_string().contains("EDITED-7f3a"),
        "{first_call}"
    );

    // The cost: 4 calls of 600 fresh + 400 cached prompt tokens and 50 completion tokens.
    let per_call = (600.0 * 2.0 + 400.0 * 0.5 + 50.0 * 8.0) / 1e6;
    let cost = summary["cost_usd"].as_f64().expect("a priced model");
    assert!((cost - 4.0 * per_call).abs() < 1e-12, "{summary}");
    assert_eq!(summary["cached_tokens"], 4 * CACHED_TOKENS);

    // The built-in set hashes differently, so the two runs can be told apart.
    let plain = coherent(&[
        "run",
        utf8(&demo),
        "--base-url",
        &stub.url,
        "--model",
        "stub-model",
        "--max-steps",
        "1",
        "--out",
        utf8(&runs),
        "--json",
    ]);
    let asked = stub.requests().len();
    assert_eq!(asked, 6, "{}", show(&plain));
    let (plain_summary, plain_lines) = transcript(&plain);
    let plain_record = &plain_lines[0]["prompts"];
    assert_ne!(plain_record["hash"].as_str(), Some(hash));
    assert_eq!(plain_record["replaced"], json!({}));
    assert_eq!(
        plain_summary["cost_usd"],
        Value::Null,
        "stub-model has no built-in price"
    );

    // A replay renders the recorded set, without the folder; --prompts with it is refused.
    let recorded = summary["transcript"].as_str().expect("a path");
    let replay = coherent(&["run", "--replay", recorded, "--out", utf8(&runs)]);
    assert_eq!(replay.status.code(), Some(1), "{}", show(&replay));
    assert!(
        String::from_utf8_lossy(&replay.stdout).contains("replay: all 2 rounds match"),
        "{}",
        show(&replay)
    );
    let both = coherent(&[
        "run",
        "--replay",
        recorded,
        "--prompts",
        utf8(&dir),
        "--out",
        utf8(&runs),
    ]);
    assert_eq!(both.status.code(), Some(2), "{}", show(&both));
    assert_eq!(stub.requests().len(), asked, "replays ask no model");
}

#[test]
fn an_unknown_placeholder_exits_2_naming_file_line_and_placeholder_before_any_call() {
    let root = scratch("unknown");
    let dir = root.join("d");
    let export = coherent(&["prompts", "export", utf8(&dir)]);
    assert_eq!(export.status.code(), Some(0), "{}", show(&export));
    let user = dir.join("executor_user.txt");
    let text = std::fs::read_to_string(&user).expect("exported");
    std::fs::write(&user, format!("{text}\nAlso: {{{{no_such_thing}}}}\n")).expect("edited");
    let line = text.lines().count() + 2;
    let stub = Stub::start();
    let demo = demo();
    let results = root.join("r.jsonl");
    let runs = [
        vec!["run", utf8(&demo)],
        vec![
            "bench",
            "--tasks",
            utf8(&demo),
            "--methods",
            "pefa",
            "--out",
            utf8(&results),
        ],
    ];
    for mut args in runs {
        args.extend_from_slice(&[
            "--prompts",
            utf8(&dir),
            "--base-url",
            &stub.url,
            "--model",
            "stub-model",
        ]);
        let out = coherent(&args);
        assert_eq!(out.status.code(), Some(2), "{}", show(&out));
        let expected = format!(
            "{}:{line}: unknown placeholder {{{{no_such_thing}}}}; the placeholders of this \
             template: subtask, observation, scene, state, actions",
            user.display()
        );
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(&expected),
            "{expected}\n{}",
            show(&out)
        );
    }
    assert!(stub.requests().is_empty(), "no model call was made");
    assert!(!results.exists(), "the benchmark did not start");

    // A misspelt file name is refused too, rather than silently ignored.
    std::fs::write(&user, text).expect("repaired");
    std::fs::write(dir.join("asigner_user.txt"), "x").expect("a typo");
    let out = coherent(&["run", utf8(&demo), "--prompts", utf8(&dir)]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("asigner_user.txt: not a template"),
        "{}",
        show(&out)
    );
}

#[test]
fn bench_prices_every_line_and_its_tables_show_cost_per_task_and_per_success() {
    let root = scratch("bench");
    let prices = root.join("prices.json");
    std::fs::write(
        &prices,
        r#"{"stub-model": {"input": 1.0, "output": 4.0, "date": "2026-11-24", "source": "a test"}}"#,
    )
    .expect("a price file");
    let stub = Stub::start();
    let results = root.join("r.jsonl");
    let demo = demo();
    let out = coherent(&[
        "bench",
        "--tasks",
        utf8(&demo),
        "--methods",
        "pefa,optimal",
        "--prices",
        utf8(&prices),
        "--base-url",
        &stub.url,
        "--model",
        "stub-model",
        "--out",
        utf8(&results),
        "--format",
        "csv",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", show(&out));
    let text = std::fs::read_to_string(&results).expect("results");
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON"))
        .collect();
    assert_eq!(lines.len(), 2);
    for line in &lines {
        let calls = line["llm_calls"].as_u64().expect("calls");
        // No cached price given: cached tokens cost the input price.
        let expected =
            calls as f64 * (PROMPT_TOKENS as f64 * 1.0 + COMPLETION_TOKENS as f64 * 4.0) / 1e6;
        let cost = line["cost_usd"].as_f64().expect("priced");
        assert!((cost - expected).abs() < 1e-12, "{line}");
        if line["method"] == "optimal" {
            assert_eq!(cost, 0.0, "the optimal plan asks no model");
        }
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains(",cost_per_task,cost_per_success,"),
        "{stdout}"
    );
    let pefa = lines
        .iter()
        .find(|l| l["method"] == "pefa")
        .expect("a pefa line");
    let per_task = pefa["cost_usd"].as_f64().expect("priced").to_string();
    let row = stdout
        .lines()
        .find(|l| l.starts_with("costs,pefa,"))
        .expect("pefa's costs row");
    assert!(row.contains(&format!(",{per_task},")), "{row}");

    // --report re-prices with --prices: without it, the recorded costs.
    let recorded = coherent(&["bench", "--report", utf8(&results), "--format", "csv"]);
    assert_eq!(
        String::from_utf8_lossy(&recorded.stdout),
        stdout[stdout.find("table,method").expect("the tables")..]
    );
    std::fs::write(&prices, r#"{"stub-model": {"input": 0, "output": 0}}"#).expect("free");
    let free = coherent(&[
        "bench",
        "--report",
        utf8(&results),
        "--prices",
        utf8(&prices),
        "--format",
        "csv",
    ]);
    let free = String::from_utf8_lossy(&free.stdout);
    let row = free
        .lines()
        .find(|l| l.starts_with("costs,pefa,"))
        .expect("pefa's costs row");
    assert!(row.contains(",0,"), "{row}");
}
