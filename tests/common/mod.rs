//! What the command-line tests share: the `coherent` binary run with no endpoint from
//! the environment, its output shown in a failure message, scratch folders, the bundled
//! and the released tasks, the data of a `coherent view` page, and the server side of a
//! stub model server (one blocking thread per connection).

#![allow(dead_code)]

pub mod netns;

use std::io::{BufRead, BufReader, Read};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::{Value, json};

/// One event of each kind on the demo task (an arm on the kitchen counter, a quadrotor in
/// the living room, a legged robot in the kitchen; the mug and the apple to the coffee
/// table): the robot that joins where the task placed it, a thing moved from a table and
/// one taken out of a hand, a door locked for a span.
pub const DEMO_KINDS: [(&str, &str); 7] = [
    (
        "robot_down",
        r#"[{"when": {"relation": "INSIDE", "subject": 7, "target": 12}, "kind": "robot_down", "robot": 6}]"#,
    ),
    (
        "robot_up",
        r#"[{"step": 4, "kind": "robot_up", "robot": 13}]"#,
    ),
    (
        "object_moved",
        r#"[{"when": {"held": 7}, "kind": "object_moved", "thing": 9, "relation": "ON", "target": 14}]"#,
    ),
    (
        "object_moved",
        r#"[{"when": {"held": 7}, "kind": "object_moved", "thing": 7, "relation": "ON", "target": 14}]"#,
    ),
    (
        "goal_changed",
        r#"[{"step": 5, "kind": "goal_changed", "remove": [{"relation": "ON", "subject": 9, "target": 10}], "add": [{"relation": "ON", "subject": 9, "target": 14}], "instruction": "The mug to the coffee table, the apple to the sofa."}]"#,
    ),
    (
        "blocked",
        r#"[{"step": 2, "kind": "blocked", "door": 4, "steps": 3}]"#,
    ),
    (
        "action_fails",
        r#"[{"step": 2, "kind": "action_fails", "probability": 0.3}]"#,
    ),
];

/// Runs `coherent ARGS` to its end. No endpoint from the environment may change the
/// backend: `OPENAI_BASE_URL`, `OPENAI_API_KEY` and `COHERENT_MODEL` are removed.
pub fn coherent(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_coherent"))
        .args(args)
        .env_remove("OPENAI_BASE_URL")
        .env_remove("OPENAI_API_KEY")
        .env_remove("COHERENT_MODEL")
        .output()
        .expect("the coherent binary runs")
}

/// Every line of the JSON-lines file at `path`.
pub fn json_lines(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .expect("the file is written")
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect()
}

/// A run's status, the last 40 lines of its stdout and its stderr, for a failure message.
pub fn show(out: &Output) -> String {
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    let tail = lines[lines.len().saturating_sub(40)..].join("\n");
    format!(
        "status {:?}\n--- stdout (last 40 lines)\n{tail}\n--- stderr\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    )
}

/// An empty folder of its own for the test `name` (emptied if a crashed run left it).
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coherent-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

pub fn utf8(path: &Path) -> &str {
    path.to_str().expect("a UTF-8 path")
}

/// The data a page of `coherent view` embeds, as its script reads it.
pub fn embedded(page: &Path) -> Value {
    let html = std::fs::read_to_string(page).expect("the page");
    let marker = r#"<script type="application/json" id="data">"#;
    let start = html.find(marker).expect("the data element") + marker.len();
    let end = start + html[start..].find("</script>").expect("its end");
    serde_json::from_str(&html[start..end]).expect("the data is JSON")
}

/// The bundled demo task.
pub fn demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/tasks/demo.json")
}

/// The released benchmark's folder (`COHERENT_ORIGINAL_ENV`, set in
/// `.cargo/config.toml`).
pub fn released() -> PathBuf {
    PathBuf::from(env!("COHERENT_ORIGINAL_ENV"))
}

/// The released env0 tasks.
pub fn env0() -> PathBuf {
    released().join("env0.json")
}

/// Task `id` of the released scene `scene` (`env0`..`env3`).
pub fn released_task(scene: &str, id: i64) -> std::sync::Arc<coherent::session::engine::Task> {
    let path = released().join(format!("{scene}.json"));
    let task = coherent::session::tasks::pick_task(&path, Some(id)).expect("the task is there");
    std::sync::Arc::new(task)
}

/// One HTTP/1.1 request as a server sees it.
pub struct Request {
    /// `POST /v1/chat/completions HTTP/1.1`.
    pub line: String,
    /// Each header's name (lower case) and value, in order.
    pub headers: Vec<(String, String)>,
    pub body: Value,
}

impl Request {
    /// The values of the header `name` (lower case).
    pub fn header(&self, name: &str) -> Vec<&str> {
        self.headers
            .iter()
            .filter(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
            .collect()
    }
}

/// One HTTP/1.1 request: the request line, the headers up to the blank line, then
/// `Content-Length` bytes of JSON. `None` when the client closed the connection or sent
/// something else.
pub fn read_whole_request(reader: &mut BufReader<TcpStream>) -> Option<Request> {
    let mut line = String::new();
    if reader.read_line(&mut line).ok()? == 0 {
        return None;
    }
    let mut headers = Vec::new();
    let mut length = 0;
    loop {
        let mut header = String::new();
        if reader.read_line(&mut header).ok()? == 0 {
            return None;
        }
        let header = header.trim_end();
        if header.is_empty() {
            break;
        }
        if let Some((name, value)) = header.split_once(':') {
            let (name, value) = (name.trim().to_ascii_lowercase(), value.trim().to_owned());
            if name == "content-length" {
                length = value.parse().ok()?;
            }
            headers.push((name, value));
        }
    }
    let mut body = vec![0; length];
    reader.read_exact(&mut body).ok()?;
    Some(Request {
        line: line.trim_end().to_owned(),
        headers,
        body: serde_json::from_slice(&body).ok()?,
    })
}

/// One HTTP/1.1 request's JSON body ([`read_whole_request`]).
pub fn read_request(reader: &mut BufReader<TcpStream>) -> Option<Value> {
    read_whole_request(reader).map(|r| r.body)
}

/// A valid answer to whichever role asks, from the schema it sent: the first robot, or
/// the first action of the list.
pub fn answer(request: &Value) -> String {
    let format = &request["response_format"]["json_schema"];
    let properties = &format["schema"]["properties"];
    match format["name"].as_str() {
        Some("proposal") => json!({
            "reasoning": "go",
            "robot": properties["robot"]["enum"][0],
            "subtask": "do the first thing you can",
        }),
        _ => json!({
            "action": properties["action"]["enum"][0],
            "subtask_complete": false,
            "note": "",
        }),
    }
    .to_string()
}

/// A model server on loopback that reads requests and never answers, for runs that must
/// stay busy until they are stopped: its URL, and a channel that hears of each request.
pub fn silent_server() -> (String, std::sync::mpsc::Receiver<()>) {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").expect("bind loopback");
    let url = format!("http://{}/v1", listener.local_addr().expect("address"));
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for socket in listener.incoming().flatten() {
            let tx = tx.clone();
            std::thread::spawn(move || {
                let mut reader = BufReader::new(socket.try_clone().expect("a second handle"));
                while read_request(&mut reader).is_some() {
                    let _ = tx.send(());
                }
                drop(socket);
            });
        }
    });
    (url, rx)
}
