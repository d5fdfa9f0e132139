//! The HTTP backend against servers that misbehave, over real loopback sockets: a
//! scripted server answers each request with the next fault of its script, then with
//! well-formed chat completions. Each fault must leave a complete transcript (header,
//! every round, summary), a clear outcome, no panic, and no trace of the API key in
//! any file written.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use coherent_agents::episode::Budget;
use coherent_agents::llm::{Finish, LlmErrorKind, OutputMode};
use coherent_agents::retry::Backoff;
use coherent_agents::transcript::{self, RoundOutcome, Status};
use coherent_agents::{ApiKey, Cancel, Episode, OpenAiClient, OpenAiConfig};
use coherent_agents::{Builtin, Settings};
use coherent_core::{SymbolicEnv, Task, load_tasks};
use serde_json::json;
use tokio::io::AsyncWriteExt;
use tokio::net::{TcpListener, TcpStream};

mod common;

use common::http::{Request, answer, completion, read_request};

const KEY: &str = "sk-test-0123456789-SECRET";

/// What the server does with one request.
#[derive(Clone, Debug)]
enum Fault {
    /// A status line, extra headers and a body.
    Reply(u16, Vec<(&'static str, String)>, String),
    /// Never answer (until the client gives up).
    Hang,
    /// Close the connection without a response.
    Close,
    /// A chat completion with this content and finish reason.
    Content(String, &'static str),
}

struct Server {
    url: String,
    seen: Arc<Mutex<Vec<Request>>>,
}

/// Serves `script`, one fault per request in order, then good answers.
async fn serve(script: Vec<Fault>) -> Server {
    let listener = TcpListener::bind("127.0.0.1:0")
        .await
        .expect("bind loopback");
    let url = format!("http://{}/v1", listener.local_addr().expect("address"));
    let seen = Arc::new(Mutex::new(Vec::new()));
    let script = Arc::new(Mutex::new(script.into_iter()));
    let log = Arc::clone(&seen);
    tokio::spawn(async move {
        while let Ok((socket, _)) = listener.accept().await {
            let script = Arc::clone(&script);
            let log = Arc::clone(&log);
            tokio::spawn(connection(socket, script, log));
        }
    });
    Server { url, seen }
}

type Script = Arc<Mutex<std::vec::IntoIter<Fault>>>;

async fn connection(mut socket: TcpStream, script: Script, log: Arc<Mutex<Vec<Request>>>) {
    loop {
        let Some(seen) = read_request(&mut socket).await else {
            return;
        };
        let fault = script.lock().expect("script lock").next();
        let body = seen.body.clone();
        log.lock().expect("log lock").push(seen);
        let response = match fault {
            Some(Fault::Hang) => {
                tokio::time::sleep(Duration::from_secs(3600)).await;
                return;
            }
            Some(Fault::Close) => return,
            Some(Fault::Reply(status, headers, body)) => http(status, &headers, &body),
            Some(Fault::Content(content, finish)) => http(200, &[], &completion(&content, finish)),
            None => http(200, &[], &completion(&answer(&body), "stop")),
        };
        if socket.write_all(response.as_bytes()).await.is_err() {
            return;
        }
    }
}

fn http(status: u16, headers: &[(&str, String)], body: &str) -> String {
    let mut out = format!(
        "HTTP/1.1 {status} X\r\ncontent-type: application/json\r\ncontent-length: {}\r\n",
        body.len()
    );
    for (k, v) in headers {
        out.push_str(&format!("{k}: {v}\r\n"));
    }
    out.push_str("\r\n");
    out.push_str(body);
    out
}

fn demo() -> Arc<Task> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/tasks/demo.json");
    Arc::new(load_tasks(&path).expect("the demo task loads").remove(0))
}

fn config(url: &str) -> OpenAiConfig {
    OpenAiConfig {
        api_key: Some(ApiKey::new(KEY)),
        read_timeout: Duration::from_millis(400),
        total_timeout: Duration::from_secs(2),
        backoff: Backoff {
            max_retries: 2,
            base: Duration::from_millis(20),
            cap: Duration::from_secs(5),
        },
        ..OpenAiConfig::new(url, "test-model")
    }
}

struct Run {
    episode: Episode,
    transcript: transcript::Transcript,
    out: PathBuf,
}

/// Runs a `steps`-step episode of the demo task against `server`.
async fn run(name: &str, server: &Server, steps: u32) -> Run {
    let out = std::env::temp_dir().join(format!("coherent-faults-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let task = demo();
    let client = OpenAiClient::new(config(&server.url)).expect("a client");
    let mut env = SymbolicEnv::new(Arc::clone(&task));
    let (episode, path) = common::run(
        &task,
        &mut env,
        &client,
        &Settings::new(Builtin::Pefa),
        Budget::Given(steps),
        &out,
        &Cancel::default(),
    )
    .await
    .expect("the episode runs");
    let transcript = transcript::read(&path).expect("the transcript reads back");
    assert!(
        transcript.rounds == episode.rounds,
        "{name}: every round recorded"
    );
    assert_eq!(
        transcript.summary.as_ref(),
        Some(&episode.summary),
        "{name}"
    );
    assert_no_key(&out);
    assert!(
        server
            .seen
            .lock()
            .expect("log")
            .iter()
            .all(|s| s.authorization.as_deref() == Some(&format!("Bearer {KEY}"))),
        "{name}: the key is sent to the server"
    );
    Run {
        episode,
        transcript,
        out,
    }
}

fn assert_no_key(dir: &Path) {
    for entry in std::fs::read_dir(dir).expect("out folder") {
        let path = entry.expect("entry").path();
        let text = std::fs::read_to_string(&path).expect("readable");
        assert!(!text.contains(KEY), "{} holds the API key", path.display());
    }
}

#[tokio::test]
async fn too_many_requests_waits_for_retry_after_then_succeeds() {
    let server = serve(vec![Fault::Reply(
        429,
        vec![("retry-after", "1".into())],
        "{\"error\": \"slow down\"}".into(),
    )])
    .await;
    let r = run("429", &server, 1).await;
    let call = &r.episode.rounds[0].calls[0];
    let answer = call.answer.as_ref().expect("answered after the wait");
    assert_eq!(answer.attempts, 2);
    assert!(
        answer.latency_ms >= 1000.0,
        "waited {} ms",
        answer.latency_ms
    );
    assert_eq!(r.episode.rounds[0].outcome, RoundOutcome::Executed);
    assert_eq!(r.episode.summary.prompt_tokens, 200);
    assert_eq!(r.episode.summary.completion_tokens, 20);
}

/// One fault, then a good answer: the first call succeeds on its second attempt and
/// the action is carried out.
async fn recovers_after_one(fault: Fault, name: &str) {
    let server = serve(vec![fault]).await;
    let r = run(name, &server, 1).await;
    assert_eq!(
        r.episode.rounds[0].calls[0]
            .answer
            .as_ref()
            .map(|a| a.attempts),
        Some(2),
        "{name}"
    );
    assert_eq!(
        r.episode.rounds[0].outcome,
        RoundOutcome::Executed,
        "{name}"
    );
}

#[tokio::test]
async fn a_server_error_is_retried() {
    recovers_after_one(Fault::Reply(500, vec![], "oops".into()), "500").await;
}

#[tokio::test]
async fn a_hang_times_out_and_is_retried() {
    let server = serve(vec![Fault::Hang]).await;
    let r = run("hang-once", &server, 1).await;
    let answer = r.episode.rounds[0].calls[0]
        .answer
        .as_ref()
        .expect("answered");
    assert_eq!(answer.attempts, 2);
    assert!(answer.latency_ms >= 400.0);
}

#[tokio::test]
async fn a_server_that_always_hangs_ends_the_episode_in_bounded_time() {
    let server = serve(vec![Fault::Hang, Fault::Hang, Fault::Hang, Fault::Hang]).await;
    let start = Instant::now();
    let r = run("hang-always", &server, 3).await;
    // 3 attempts of 0.4 s each plus two short pauses.
    assert!(
        start.elapsed() < Duration::from_secs(10),
        "{:?}",
        start.elapsed()
    );
    assert_eq!(r.episode.summary.status, Status::BackendError);
    assert_eq!(r.episode.rounds.len(), 1);
    let error = r.episode.rounds[0].calls[0]
        .error
        .as_ref()
        .expect("an error");
    assert_eq!(error.kind, LlmErrorKind::Timeout);
    assert_eq!(error.attempts, 3);
    assert!(matches!(
        r.episode.rounds[0].outcome,
        RoundOutcome::BackendError { .. }
    ));
    assert!(r.transcript.summary.expect("summary").error.is_some());
}

#[tokio::test]
async fn a_closed_connection_is_retried() {
    recovers_after_one(Fault::Close, "close").await;
}

#[tokio::test]
async fn malformed_json_costs_the_round_and_the_episode_goes_on() {
    let server = serve(vec![Fault::Reply(
        200,
        vec![],
        "{\"choices\": [{\"mess".into(),
    )])
    .await;
    let r = run("malformed", &server, 2).await;
    let first = &r.episode.rounds[0];
    assert_eq!(
        first.calls[0].error.as_ref().map(|e| e.kind),
        Some(LlmErrorKind::Malformed)
    );
    assert!(
        matches!(&first.outcome, RoundOutcome::NoProposal { why } if why.contains("malformed"))
    );
    assert!(first.feedback.contains("could not be used"));
    assert_eq!(r.episode.rounds[1].outcome, RoundOutcome::Executed);
    assert_eq!(r.episode.summary.status, Status::Failure);
    assert_eq!(r.episode.summary.steps, 2);
}

#[tokio::test]
async fn truncated_refused_and_empty_answers_are_outcomes_not_panics() {
    let server = serve(vec![
        Fault::Content("{\"reasoning\": \"first I will think about".into(), "length"),
        Fault::Content(String::new(), "stop"),
        Fault::Reply(
            200,
            vec![],
            json!({"choices": [{"message": {"content": null, "refusal": "I will not"}, "finish_reason": "stop"}]})
                .to_string(),
        ),
    ])
    .await;
    let r = run("truncated", &server, 4).await;
    let whys: Vec<String> = r.episode.rounds[..3]
        .iter()
        .map(|round| match &round.outcome {
            RoundOutcome::NoProposal { why } => why.clone(),
            other => panic!("expected no proposal, got {other:?}"),
        })
        .collect();
    assert!(whys[0].contains("cut off"), "{}", whys[0]);
    assert!(whys[1].contains("empty"), "{}", whys[1]);
    assert!(whys[2].contains("refused"), "{}", whys[2]);
    let first = r.episode.rounds[0].calls[0]
        .answer
        .as_ref()
        .expect("an answer");
    assert_eq!(first.finish, Finish::Length);
    assert_eq!(r.episode.rounds[3].outcome, RoundOutcome::Executed);
}

#[tokio::test]
async fn a_server_without_json_schema_gets_json_object_then_text() {
    let refuse = |what: &str| {
        Fault::Reply(
            400,
            vec![],
            format!("{{\"error\": \"response_format type {what} is not supported\"}}"),
        )
    };
    let server = serve(vec![
        refuse("json_schema"),
        refuse("json_object"),
        Fault::Content("Robot: <robot arm>(6): grab the mug\n".into(), "stop"),
        Fault::Content("I will do [grab] <mug>(7).".into(), "stop"),
    ])
    .await;
    let r = run("downgrade", &server, 1).await;
    let round = &r.episode.rounds[0];
    let modes: Vec<OutputMode> = round
        .calls
        .iter()
        .filter_map(|c| c.answer.as_ref().map(|a| a.mode))
        .collect();
    assert_eq!(modes, [OutputMode::Text, OutputMode::Text]);
    assert_eq!(round.proposal.as_ref().map(|p| p.robot.0), Some(6));
    assert_eq!(round.outcome, RoundOutcome::Executed);
    let seen = server.seen.lock().expect("log");
    assert_eq!(seen[0].body["response_format"]["type"], "json_schema");
    assert_eq!(seen[1].body["response_format"]["type"], "json_object");
    assert!(seen[2].body.get("response_format").is_none());
}

#[tokio::test]
async fn an_unauthorised_key_ends_at_once_and_is_scrubbed_from_the_echo() {
    let server = serve(vec![Fault::Reply(
        401,
        vec![],
        format!("{{\"error\": \"invalid key {KEY}\"}}"),
    )])
    .await;
    let r = run("401", &server, 3).await;
    assert_eq!(r.episode.summary.status, Status::BackendError);
    let error = r.episode.rounds[0].calls[0]
        .error
        .as_ref()
        .expect("an error");
    assert_eq!(error.kind, LlmErrorKind::Status(401));
    assert_eq!(error.attempts, 1);
    assert!(error.message.contains("[api key]"), "{}", error.message);
    let _ = std::fs::remove_dir_all(&r.out);
}

#[tokio::test]
async fn a_truncated_answer_counts_when_the_action_came_before_the_cut() {
    let server = serve(vec![
        Fault::Content(
            json!({"reasoning": "", "robot": "<robot arm>(6)", "subtask": "grab the mug"})
                .to_string(),
            "stop",
        ),
        // Padding up to the token limit after a complete action, as small models do
        // under a grammar.
        Fault::Content("{\"action\": \"[grab] <mug>(7)\"\n\n\n\n".into(), "length"),
    ])
    .await;
    let r = run("salvage", &server, 1).await;
    let round = &r.episode.rounds[0];
    assert_eq!(
        round.calls[1].answer.as_ref().map(|a| a.finish.clone()),
        Some(Finish::Length)
    );
    assert_eq!(
        round.decision.as_ref().and_then(|d| d.action.as_deref()),
        Some("[grab] <mug>(7)")
    );
    assert_eq!(round.outcome, RoundOutcome::Executed);
}
