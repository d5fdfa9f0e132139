//! `coherent run` against model servers that misbehave on purpose, over real loopback
//! sockets: a body that never ends, a 20 MB answer, an answer dripped one byte a second,
//! answers full of terminal escapes, a `Retry-After` of days or centuries, redirects to
//! another server; and base URLs that carry a secret (a gateway's key in the query, a
//! user and password). Each run must end in bounded time and memory (the peak resident
//! memory of the `coherent` process, read from `/proc`, stays under [`MEMORY_BOUND`]),
//! leave a complete transcript, print nothing a terminal would act on, and write no
//! secret anywhere.

use std::io::{BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use serde_json::{Value, json};

mod common;

use common::{Request, read_whole_request};

/// The most resident memory a run against a hostile server may reach: the engine, the
/// physics-free world and a few MB of response buffers fit many times over.
const MEMORY_BOUND: u64 = 200 << 20;

/// What the server does with every request.
#[derive(Clone)]
enum Behaviour {
    /// Headers, then bytes forever (no length, no end).
    Endless,
    /// A well-formed chat completion whose content is `size` bytes of JSON.
    Huge(usize),
    /// A valid answer, sent one byte a second.
    Drip,
    /// Valid JSON answers whose fields are full of terminal escapes.
    Escapes,
    /// HTTP 429 with this `Retry-After`.
    RetryAfter(&'static str),
    /// A redirect: this status, to this URL.
    Redirect(u16, String),
    /// Valid answers; every request is kept.
    Record(Arc<Mutex<Vec<Request>>>),
}

/// A server on a loopback port that answers every request with `behaviour`, until the
/// returned flag is set.
fn serve(behaviour: Behaviour) -> (String, Arc<AtomicBool>) {
    let listener = TcpListener::bind("127.0.0.1:0").expect("bind loopback");
    let url = format!("http://{}/v1", listener.local_addr().expect("address"));
    let stop = Arc::new(AtomicBool::new(false));
    let done = Arc::clone(&stop);
    thread::spawn(move || {
        for socket in listener.incoming() {
            if done.load(Ordering::Relaxed) {
                return;
            }
            let Ok(socket) = socket else { continue };
            let (done, behaviour) = (Arc::clone(&done), behaviour.clone());
            thread::spawn(move || connection(socket, &behaviour, &done));
        }
    });
    (url, stop)
}

fn connection(socket: TcpStream, behaviour: &Behaviour, stop: &AtomicBool) {
    let mut reader = BufReader::new(socket.try_clone().expect("clone the socket"));
    let mut out = socket;
    while let Some(whole) = read_whole_request(&mut reader) {
        let request = &whole.body;
        let answered = match behaviour {
            Behaviour::Endless => endless(&mut out, stop),
            Behaviour::Huge(size) => {
                let content = format!("{{\"note\": \"{}\"}}", "x".repeat(*size));
                respond(&mut out, &completion(&content))
            }
            Behaviour::Drip => drip(&mut out, &completion(&answer(request, "")), stop),
            Behaviour::Escapes => {
                let evil = "\u{1b}[2J\rsuccess=true\n\u{202e}";
                respond(&mut out, &completion(&answer(request, evil)))
            }
            Behaviour::RetryAfter(wait) => {
                let body = r#"{"error": "slow down"}"#;
                write!(
                    out,
                    "HTTP/1.1 429 Too Many Requests\r\nretry-after: {wait}\r\n\
                     content-type: application/json\r\ncontent-length: {}\r\n\r\n{body}",
                    body.len()
                )
            }
            Behaviour::Redirect(status, to) => write!(
                out,
                "HTTP/1.1 {status} Elsewhere\r\nlocation: {to}\r\ncontent-length: 0\r\n\r\n"
            ),
            Behaviour::Record(log) => {
                let reply = respond(&mut out, &completion(&answer(request, "")));
                log.lock().expect("the log").push(whole);
                reply
            }
        };
        if answered.is_err() {
            return;
        }
    }
}

fn respond(out: &mut TcpStream, body: &str) -> std::io::Result<()> {
    write!(
        out,
        "HTTP/1.1 200 OK\r\ncontent-type: application/json\r\ncontent-length: {}\r\n\r\n{body}",
        body.len()
    )
}

fn endless(out: &mut TcpStream, stop: &AtomicBool) -> std::io::Result<()> {
    out.write_all(b"HTTP/1.1 200 OK\r\ncontent-type: application/json\r\n\r\n{\"choices\": [")?;
    let block = [b' '; 64 << 10];
    while !stop.load(Ordering::Relaxed) {
        out.write_all(&block)?;
    }
    Ok(())
}

fn drip(out: &mut TcpStream, body: &str, stop: &AtomicBool) -> std::io::Result<()> {
    write!(
        out,
        "HTTP/1.1 200 OK\r\ncontent-type: application/json\r\ncontent-length: {}\r\n\r\n",
        body.len()
    )?;
    for byte in body.bytes() {
        if stop.load(Ordering::Relaxed) {
            break;
        }
        out.write_all(&[byte])?;
        thread::sleep(Duration::from_secs(1));
    }
    Ok(())
}

fn completion(content: &str) -> String {
    json!({
        "choices": [{"index": 0, "message": {"role": "assistant", "content": content}, "finish_reason": "stop"}],
        "usage": {"prompt_tokens": 100, "completion_tokens": 10},
    })
    .to_string()
}

/// An answer to whichever role asks, with `evil` put into its free-text fields.
fn answer(request: &Value, evil: &str) -> String {
    let format = &request["response_format"]["json_schema"];
    let schema = &format["schema"]["properties"];
    match format["name"].as_str() {
        Some("proposal") => json!({
            "reasoning": evil,
            "robot": schema["robot"]["enum"][0],
            "subtask": format!("{evil}do the first thing"),
        }),
        _ => json!({
            "action": format!("{evil}{}", schema["action"]["enum"][0].as_str().unwrap_or("")),
            "subtask_complete": false,
            "note": evil,
        }),
    }
    .to_string()
}

/// What a run did: its exit status, its output, its peak resident memory, its time and
/// its transcript.
struct Ran {
    status: Option<i32>,
    stdout: String,
    stderr: String,
    peak_bytes: u64,
    elapsed: Duration,
    transcript: PathBuf,
}

/// `coherent run` on the demo task against `url`, with `flags`; the peak memory is the
/// largest `VmHWM` read while the process ran (every 10 ms).
fn run(name: &str, url: &str, flags: &[&str]) -> Ran {
    let out = std::env::temp_dir().join(format!("coherent-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/tasks/demo.json");
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_coherent"))
        .arg("run")
        .arg(&demo)
        .args([
            "--base-url",
            url,
            "--model",
            "hostile",
            "--api-key",
            "sk-hostile-0123456789",
        ])
        .arg("--out")
        .arg(&out)
        .args(flags)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("coherent starts");
    let status_file = format!("/proc/{}/status", child.id());
    let (mut stdout, mut stderr) = (child.stdout.take(), child.stderr.take());
    let readers = [
        thread::spawn(move || read_all(stdout.as_mut())),
        thread::spawn(move || read_all(stderr.as_mut())),
    ];
    let mut peak_bytes = 0;
    let status = loop {
        if let Ok(text) = std::fs::read_to_string(&status_file)
            && let Some(kb) = text
                .lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        {
            peak_bytes = peak_bytes.max(kb * 1024);
        }
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "{name}: still running after two minutes"
        );
        thread::sleep(Duration::from_millis(10));
    };
    let [stdout, stderr] = readers.map(|r| r.join().expect("reader"));
    let transcript = std::fs::read_dir(&out)
        .expect("the transcript folder")
        .map(|e| e.expect("an entry").path())
        .find(|p| p.extension().is_some_and(|x| x == "jsonl"))
        .expect("a transcript");
    Ran {
        status: status.code(),
        stdout,
        stderr,
        peak_bytes,
        elapsed: start.elapsed(),
        transcript,
    }
}

fn read_all(stream: Option<&mut impl Read>) -> String {
    let mut text = String::new();
    if let Some(s) = stream {
        let _ = s.read_to_string(&mut text);
    }
    text
}

/// The transcript's records; the last must be the summary.
fn records(ran: &Ran) -> Vec<Value> {
    let text = std::fs::read_to_string(&ran.transcript).expect("the transcript reads");
    assert!(!text.contains("sk-hostile-0123456789"), "the key leaked");
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    assert_eq!(lines.first().map(|l| &l["type"]), Some(&json!("header")));
    assert_eq!(lines.last().map(|l| &l["type"]), Some(&json!("summary")));
    lines
}

fn within_bounds(name: &str, ran: &Ran, seconds: u64) {
    eprintln!(
        "{name}: peak resident memory {:.1} MB, {:.2} s",
        ran.peak_bytes as f64 / f64::from(1 << 20),
        ran.elapsed.as_secs_f64()
    );
    assert!(
        ran.peak_bytes > 0 && ran.peak_bytes < MEMORY_BOUND,
        "{name}: peak memory {} MB (bound {} MB)\n{}",
        ran.peak_bytes >> 20,
        MEMORY_BOUND >> 20,
        ran.stderr
    );
    assert!(
        ran.elapsed < Duration::from_secs(seconds),
        "{name}: took {:?}",
        ran.elapsed
    );
}

#[test]
fn a_body_that_never_ends_stops_at_the_limit() {
    let (url, stop) = serve(Behaviour::Endless);
    let ran = run("endless", &url, &["--max-steps", "2", "--timeout", "30"]);
    stop.store(true, Ordering::Relaxed);
    within_bounds("endless", &ran, 60);
    let lines = records(&ran);
    let text = lines[1..].iter().map(Value::to_string).collect::<String>();
    assert!(
        text.contains("more than the limit of 4194304 bytes"),
        "{text}"
    );
    assert_eq!(ran.status, Some(1), "{}", ran.stdout);
}

#[test]
fn a_20_mb_answer_is_refused_or_cut_and_kept_small() {
    let (url, stop) = serve(Behaviour::Huge(20 << 20));
    // Over the body limit: every call fails, read no further than the limit.
    let refused = run("huge", &url, &["--max-steps", "2"]);
    within_bounds("huge", &refused, 60);
    records(&refused);
    let size = std::fs::metadata(&refused.transcript).expect("size").len();
    assert!(size < 1 << 20, "the transcript is {size} bytes");
    // Under a raised limit: the answer is cut before it is parsed, stored or fed back.
    let cut = run(
        "huge-cut",
        &url,
        &["--max-steps", "3", "--max-response-bytes", "67108864"],
    );
    stop.store(true, Ordering::Relaxed);
    within_bounds("huge-cut", &cut, 60);
    records(&cut);
    let size = std::fs::metadata(&cut.transcript).expect("size").len();
    assert!(size < 1 << 20, "the transcript is {size} bytes");
}

#[test]
fn an_answer_dripped_a_byte_a_second_times_out() {
    let (url, stop) = serve(Behaviour::Drip);
    let flags = [
        "--max-steps",
        "1",
        "--timeout",
        "3",
        "--read-timeout",
        "2",
        "--max-retries",
        "1",
    ];
    let ran = run("drip", &url, &flags);
    stop.store(true, Ordering::Relaxed);
    within_bounds("drip", &ran, 30);
    let lines = records(&ran);
    assert_eq!(
        lines.last().map(|l| &l["status"]),
        Some(&json!("backend_error"))
    );
    assert_eq!(ran.status, Some(3), "{}", ran.stdout);
}

#[test]
fn terminal_escapes_in_answers_are_shown_escaped_and_kept_raw() {
    let (url, stop) = serve(Behaviour::Escapes);
    let ran = run("escapes", &url, &["--max-steps", "2"]);
    stop.store(true, Ordering::Relaxed);
    within_bounds("escapes", &ran, 60);
    for (stream, text) in [("stdout", &ran.stdout), ("stderr", &ran.stderr)] {
        assert!(
            !text.contains(['\u{1b}', '\r', '\u{202e}']),
            "{stream} carries raw escapes: {text:?}"
        );
        assert!(
            !text.lines().any(|l| l.starts_with("success=true")),
            "{stream}: a forged line: {text}"
        );
    }
    assert!(
        ran.stdout.contains("\\u{1b}[2J\\rsuccess=true\\n\\u{202e}"),
        "{}",
        ran.stdout
    );
    let lines = records(&ran);
    let action = lines[1]["decision"]["action"].as_str().unwrap_or_default();
    assert!(
        action.starts_with("\u{1b}[2J\rsuccess=true\n\u{202e}"),
        "{action:?}"
    );
}

#[test]
fn a_retry_after_of_days_or_centuries_is_capped_said_and_ends_in_exit_3() {
    for wait in [
        "999999",
        "18446744073709551615",
        "Thu, 01 Jan 2099 00:00:00 GMT",
    ] {
        let (url, stop) = serve(Behaviour::RetryAfter(wait));
        let flags = ["--max-steps", "1", "--timeout", "2", "--max-retries", "2"];
        let ran = run("retry-after", &url, &flags);
        stop.store(true, Ordering::Relaxed);
        within_bounds("retry-after", &ran, 30);
        assert_eq!(ran.status, Some(3), "{wait}: {}", ran.stdout);
        let notes: Vec<&str> = ran
            .stderr
            .lines()
            .filter(|l| l.contains("answered HTTP 429 and asked to wait"))
            .collect();
        assert_eq!(notes.len(), 2, "one note per wait: {}", ran.stderr);
        assert!(
            notes[0].ends_with("waiting 2.0 s, retry 1 of 2"),
            "{}",
            ran.stderr
        );
        if wait == "999999" {
            assert!(
                notes[0].contains("asked to wait 999999 s"),
                "{}",
                ran.stderr
            );
        }
        let lines = records(&ran);
        assert_eq!(
            lines.last().map(|l| &l["status"]),
            Some(&json!("backend_error"))
        );
    }
}

/// `coherent bench` on the demo task with `pefa` against `url`, one step; the results
/// file's text.
fn bench_once(name: &str, url: &str) -> String {
    let out = std::env::temp_dir().join(format!("coherent-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let results = out.join("results.jsonl");
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/tasks/demo.json");
    let ran = Command::new(env!("CARGO_BIN_EXE_coherent"))
        .arg("bench")
        .arg("--tasks")
        .arg(&demo)
        .args(["--methods", "pefa", "--max-steps", "1", "--base-url", url])
        .args(["--model", "hostile", "--api-key", "sk-hostile-0123456789"])
        .arg("--out")
        .arg(&results)
        .output()
        .expect("coherent runs");
    assert_eq!(ran.status.code(), Some(0), "{ran:?}");
    std::fs::read_to_string(&results).expect("the results file")
}

#[test]
fn a_secret_in_the_base_url_stays_on_the_request_and_out_of_every_record() {
    let log = Arc::new(Mutex::new(Vec::new()));
    let (url, stop) = serve(Behaviour::Record(Arc::clone(&log)));
    let secret = "gw-secret-0123456789";
    let in_query = format!("{url}?api-key={secret}");
    let ran = run("query-key", &in_query, &["--max-steps", "2", "--json"]);
    let results = bench_once("query-key-bench", &in_query);
    // A user and password in the URL: basic auth alone, no bearer key beside it.
    let password = "gw-pass-0123456789";
    let with_user = url.replacen("http://", &format!("http://gw-user:{password}@"), 1);
    let user = run("user-password", &with_user, &["--max-steps", "1", "--json"]);
    stop.store(true, Ordering::Relaxed);
    let requests = log.lock().expect("the log");
    let (queried, basic): (Vec<&Request>, Vec<&Request>) =
        requests.iter().partition(|r| r.line.contains("api-key"));
    assert!(queried.len() >= 3 && !basic.is_empty());
    for r in &queried {
        assert_eq!(
            r.line,
            format!("POST /v1/chat/completions?api-key={secret} HTTP/1.1")
        );
        assert_eq!(r.header("authorization"), ["Bearer sk-hostile-0123456789"]);
    }
    for r in &basic {
        assert_eq!(r.line, "POST /v1/chat/completions HTTP/1.1");
        // base64 of "gw-user:gw-pass-0123456789".
        assert_eq!(
            r.header("authorization"),
            ["Basic Z3ctdXNlcjpndy1wYXNzLTAxMjM0NTY3ODk="]
        );
    }
    let transcript = std::fs::read_to_string(&ran.transcript).expect("the transcript");
    for (what, text) in [
        ("--json", &ran.stdout),
        ("stderr", &ran.stderr),
        ("the transcript", &transcript),
        ("the results line", &results),
    ] {
        assert!(!text.contains(secret), "{what} holds the secret: {text}");
        assert!(text.contains("/v1?api-key=[redacted]"), "{what}: {text}");
    }
    let transcript = std::fs::read_to_string(&user.transcript).expect("the transcript");
    for text in [&user.stdout, &user.stderr, &transcript] {
        assert!(
            !text.contains(password) && !text.contains("gw-user"),
            "{text}"
        );
    }
}

#[test]
fn a_redirect_is_the_servers_error_and_is_never_followed() {
    let log = Arc::new(Mutex::new(Vec::new()));
    let (elsewhere, stop_elsewhere) = serve(Behaviour::Record(Arc::clone(&log)));
    let to = format!("{elsewhere}/chat/completions");
    for status in [307, 302] {
        let (url, stop) = serve(Behaviour::Redirect(status, to.clone()));
        let ran = run("redirect", &url, &["--max-steps", "2"]);
        stop.store(true, Ordering::Relaxed);
        within_bounds("redirect", &ran, 30);
        assert_eq!(ran.status, Some(3), "{}", ran.stdout);
        let said = format!("HTTP {status}: redirect to {to}, not followed");
        assert!(ran.stdout.contains(&said), "{said}\n{}", ran.stdout);
        let lines = records(&ran);
        let call = &lines[1]["calls"][0];
        assert_eq!(call["endpoint"], json!(url), "the server that answered");
        assert_eq!(call["error"]["kind"], json!({"status": status}));
    }
    stop_elsewhere.store(true, Ordering::Relaxed);
    assert!(
        log.lock().expect("the log").is_empty(),
        "nothing sent elsewhere"
    );
}
