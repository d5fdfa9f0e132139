//! The server side of HTTP/1.1 for the stub model servers of the integration tests.

use serde_json::{Value, json};
use tokio::io::AsyncReadExt;
use tokio::net::TcpStream;

/// A request as a stub server saw it.
#[derive(Clone, Debug)]
pub struct Request {
    pub authorization: Option<String>,
    pub body: Value,
}

/// Reads one HTTP/1.1 request (headers, then `Content-Length` bytes of a JSON body);
/// `None` when the client closed the connection or sent something else.
pub async fn read_request(socket: &mut TcpStream) -> Option<Request> {
    let mut buf = Vec::new();
    let mut chunk = [0u8; 8192];
    let head_end = loop {
        if let Some(i) = buf.windows(4).position(|w| w == b"\r\n\r\n") {
            break i + 4;
        }
        let n = socket.read(&mut chunk).await.ok()?;
        if n == 0 {
            return None;
        }
        buf.extend_from_slice(&chunk[..n]);
    };
    let head = String::from_utf8_lossy(&buf[..head_end]).into_owned();
    let header = |name: &str| {
        head.lines().find_map(|line| {
            let (k, v) = line.split_once(':')?;
            k.trim()
                .eq_ignore_ascii_case(name)
                .then(|| v.trim().to_owned())
        })
    };
    let length: usize = header("content-length")?.parse().ok()?;
    while buf.len() < head_end + length {
        let n = socket.read(&mut chunk).await.ok()?;
        if n == 0 {
            return None;
        }
        buf.extend_from_slice(&chunk[..n]);
    }
    Some(Request {
        authorization: header("authorization"),
        body: serde_json::from_slice(&buf[head_end..head_end + length]).ok()?,
    })
}

/// A chat completion body with `content` and `finish` as its finish reason, and 100
/// prompt and 10 completion tokens.
pub fn completion(content: &str, finish: &str) -> String {
    json!({
        "choices": [{"index": 0, "message": {"role": "assistant", "content": content}, "finish_reason": finish}],
        "usage": {"prompt_tokens": 100, "completion_tokens": 10},
    })
    .to_string()
}

/// A valid answer to whichever role asks, from the schema it sent: the first robot, or
/// the first action of the list.
pub fn answer(request: &Value) -> String {
    let schema = &request["response_format"]["json_schema"]["schema"]["properties"];
    match request["response_format"]["json_schema"]["name"].as_str() {
        Some("proposal") => json!({
            "reasoning": "go",
            "robot": schema["robot"]["enum"][0],
            "subtask": "do the first thing you can",
        }),
        _ => json!({"action": schema["action"]["enum"][0], "subtask_complete": false, "note": ""}),
    }
    .to_string()
}
