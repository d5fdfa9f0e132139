//! `coherent run` with several endpoints of one model: `--base-url` repeated, or
//! `OPENAI_BASE_URL` as a comma-separated list. One endpoint refuses connections; the
//! run goes on at the other, the backend line names both, and every call of the
//! transcript names the endpoint that answered it.

use std::io::{BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::thread;

use serde_json::{Value, json};

mod common;

use common::{answer, demo, read_request};

/// A server on a loopback port answering every request with the first robot, or its
/// first action.
fn serve() -> String {
    let listener = TcpListener::bind("127.0.0.1:0").expect("bind loopback");
    let url = format!("http://{}/v1", listener.local_addr().expect("address"));
    thread::spawn(move || {
        for socket in listener.incoming().flatten() {
            thread::spawn(move || connection(socket));
        }
    });
    url
}

fn connection(socket: TcpStream) {
    let mut reader = BufReader::new(socket.try_clone().expect("clone the socket"));
    let mut out = socket;
    while let Some(request) = read_request(&mut reader) {
        let body = json!({
            "choices": [{"message": {"role": "assistant", "content": answer(&request)}, "finish_reason": "stop"}],
            "usage": {"prompt_tokens": 10, "completion_tokens": 5},
        })
        .to_string();
        let response = format!(
            "HTTP/1.1 200 OK\r\ncontent-type: application/json\r\ncontent-length: {}\r\n\r\n{body}",
            body.len()
        );
        if out.write_all(response.as_bytes()).is_err() {
            return;
        }
    }
}

/// A loopback URL nobody listens on.
fn refused() -> String {
    let listener = TcpListener::bind("127.0.0.1:0").expect("bind loopback");
    format!("http://{}/v1", listener.local_addr().expect("address"))
}

/// `coherent run` on the demo task for two steps with `args`, into a fresh folder.
fn run(name: &str, args: &[&str], env: Option<&str>) -> (Output, PathBuf) {
    let out = std::env::temp_dir().join(format!(
        "coherent-cli-endpoints-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&out);
    let demo = demo();
    let mut command = Command::new(env!("CARGO_BIN_EXE_coherent"));
    command
        .arg("run")
        .arg(&demo)
        .args(["--model", "stub", "--max-steps", "2", "--max-retries", "1"])
        .arg("--out")
        .arg(&out)
        .args(args)
        .env_remove("OPENAI_BASE_URL")
        .env_remove("OPENAI_API_KEY");
    if let Some(list) = env {
        command.env("OPENAI_BASE_URL", list);
    }
    (command.output().expect("coherent runs"), out)
}

/// The endpoint each call of the run's transcript names.
fn endpoints(out: &Path) -> Vec<String> {
    let transcript = std::fs::read_dir(out)
        .expect("the transcript folder")
        .map(|e| e.expect("an entry").path())
        .find(|p| p.extension().is_some_and(|x| x == "jsonl"))
        .expect("a transcript");
    let text = std::fs::read_to_string(transcript).expect("reads");
    text.lines()
        .map(|l| serde_json::from_str::<Value>(l).expect("a JSON line"))
        .filter(|r| r["type"] == "round")
        .flat_map(|r| r["calls"].as_array().cloned().unwrap_or_default())
        .map(|c| c["endpoint"].as_str().unwrap_or("(none)").to_owned())
        .collect()
}

#[test]
fn base_url_repeated_gives_several_endpoints_and_the_transcript_names_each() {
    let (dead, live) = (refused(), serve());
    let (output, out) = run("flags", &["--base-url", &dead, "--base-url", &live], None);
    let stdout = String::from_utf8_lossy(&output.stdout);
    // Exit status 1: the two steps spent the budget, no server failed.
    assert_eq!(
        output.status.code(),
        Some(1),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(stdout.contains(&format!("{dead},{live}")), "{stdout}");
    let named = endpoints(&out);
    assert_eq!(named.len(), 4, "two steps of two calls");
    assert!(named.iter().all(|e| *e == live), "{named:?}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn openai_base_url_takes_a_comma_separated_list() {
    let (dead, live) = (refused(), serve());
    let (output, out) = run("env", &[], Some(&format!("{dead}, {live}")));
    assert_eq!(
        output.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let named = endpoints(&out);
    assert_eq!(named.len(), 4);
    assert!(named.iter().all(|e| *e == live), "{named:?}");
    let _ = std::fs::remove_dir_all(&out);
}
