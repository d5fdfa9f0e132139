//! PEFA's feedback explains a declined subtask: when an executor answers `none`, or an
//! answer that cannot be used, the assigner hears, for each thing the subtask names that
//! the robot cannot act on now, the engine's reason and which robots of the team could
//! get at it. A scripted model server on a loopback socket gives the answers (no real
//! model declines on demand); the rules, the loop and the client are the real ones.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use coherent_agents::episode::Budget;
use coherent_agents::transcript::{Round, RoundOutcome};
use coherent_agents::{Builtin, Settings};
use coherent_agents::{Cancel, OpenAiClient, OpenAiConfig};
use coherent_core::SymbolicEnv;
use serde_json::{Value, json};
use tokio::io::AsyncWriteExt;
use tokio::net::TcpListener;

mod common;

use common::http::{completion, read_request};

/// A server that answers the assigner and the executors from their own queues of texts,
/// in order, and keeps every request.
struct Scripted {
    url: String,
    seen: Arc<Mutex<Vec<Value>>>,
}

async fn scripted(assigner: Vec<String>, executor: Vec<String>) -> Scripted {
    let listener = TcpListener::bind("127.0.0.1:0")
        .await
        .expect("bind loopback");
    let url = format!("http://{}/v1", listener.local_addr().expect("address"));
    let queues = Arc::new(Mutex::new((
        VecDeque::from(assigner),
        VecDeque::from(executor),
    )));
    let seen = Arc::new(Mutex::new(Vec::new()));
    let log = Arc::clone(&seen);
    tokio::spawn(async move {
        while let Ok((mut socket, _)) = listener.accept().await {
            let queues = Arc::clone(&queues);
            let log = Arc::clone(&log);
            tokio::spawn(async move {
                while let Some(request) = read_request(&mut socket).await {
                    let role = request.body["response_format"]["json_schema"]["name"].clone();
                    let text = {
                        let mut q = queues.lock().expect("queues");
                        match role.as_str() {
                            Some("proposal") => q.0.pop_front(),
                            _ => q.1.pop_front(),
                        }
                    }
                    .expect("an answer scripted for every call");
                    log.lock().expect("log").push(request.body);
                    let body = completion(&text, "stop");
                    let reply = format!(
                        "HTTP/1.1 200 OK\r\ncontent-type: application/json\r\ncontent-length: {}\r\n\r\n{body}",
                        body.len()
                    );
                    if socket.write_all(reply.as_bytes()).await.is_err() {
                        return;
                    }
                }
            });
        }
    });
    Scripted { url, seen }
}

fn proposal(robot: &str, subtask: &str) -> String {
    json!({"reasoning": "", "robot": robot, "subtask": subtask}).to_string()
}

/// Two PEFA rounds of task `id` of env0 against the scripted server: the rounds, and the
/// user prompt of the second round's assigner call.
async fn two_rounds(id: i64, assigner: Vec<String>, executor: Vec<String>) -> (Vec<Round>, String) {
    let task = common::task("env0", id);
    let server = scripted(assigner, executor).await;
    let client = OpenAiClient::new(OpenAiConfig::new(&server.url, "scripted")).expect("a client");
    let out: PathBuf =
        std::env::temp_dir().join(format!("coherent-feedback-{id}-{}", std::process::id()));
    let mut env = SymbolicEnv::new(Arc::clone(&task));
    let (episode, _) = common::run(
        &task,
        &mut env,
        &client,
        &Settings::new(Builtin::Pefa),
        Budget::Given(2),
        &out,
        &Cancel::default(),
    )
    .await
    .expect("the episode runs");
    let _ = std::fs::remove_dir_all(&out);
    let seen = server.seen.lock().expect("log").clone();
    let second = seen
        .iter()
        .filter(|r| r["response_format"]["json_schema"]["name"] == "proposal")
        .nth(1)
        .expect("a second assigner call");
    let user = second["messages"][1]["content"]
        .as_str()
        .expect("a user message")
        .to_owned();
    (episode.rounds, user)
}

/// An executor that declines.
fn none() -> String {
    json!({"action": "none", "subtask_complete": false, "note": ""}).to_string()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_dog_declining_a_thing_on_a_high_surface_hears_the_height_and_who_could() {
    // env0 task 1: the sunglasses (55) lie on the dining table, a high surface where robot
    // arm 24 stands; the quadrotor (22) is landed next door.
    let ask = proposal("<robot dog>(23)", "grab the <sunglasses>(55)");
    let (rounds, next_prompt) = two_rounds(1, vec![ask.clone(), ask], vec![none(), none()]).await;
    assert_eq!(rounds[0].outcome, RoundOutcome::Declined);
    let feedback = &rounds[0].feedback;
    let lines: Vec<&str> = feedback.lines().collect();
    assert_eq!(lines.len(), 2, "{feedback}");
    assert!(
        lines[0].starts_with("<robot dog>(23) cannot do this subtask now (no reason given)."),
        "{feedback}"
    );
    // Robot arm 50, on the high table in the bedroom, could not: it is left out.
    assert_eq!(
        lines[1],
        "- <sunglasses>(55): <sunglasses>(55) is on a high surface (ON_HIGH_SURFACE), out \
         of the robot dog's reach (too_high). <quadrotor>(22) (quadrotor) could after 2 \
         moves of its own; <robot arm>(24) (robot arm) can get at it now."
    );
    // The assigner reads it in its history the next round.
    assert!(next_prompt.contains(feedback.as_str()), "{next_prompt}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_arm_asked_to_fetch_from_another_room_hears_what_it_reaches() {
    // env0 task 2: robot arm 24 stands on the dining table in the living room; the
    // textbook (44) lies on a bed in the child room.
    let ask = proposal(
        "<robot arm>(24)",
        "fetch the <textbook>(44) from the <childroom>(2)",
    );
    let (rounds, _) = two_rounds(2, vec![ask.clone(), ask], vec![none(), none()]).await;
    let feedback = &rounds[0].feedback;
    let lines: Vec<&str> = feedback.lines().collect();
    assert_eq!(lines.len(), 3, "{feedback}");
    assert_eq!(
        lines[1],
        "- <textbook>(44): <textbook>(44) is out of reach of <robot arm>(24), which only \
         reaches what is on <dining table>(13) (out_of_reach). <robot dog>(23) (robot dog) \
         could after 1 move of its own."
    );
    assert!(
        lines[2].starts_with("- <childroom>(2): <childroom>(2) is out of reach of <robot arm>(24)"),
        "{feedback}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_answer_that_cannot_be_used_is_explained_too() {
    let ask = proposal("<robot dog>(23)", "grab the <sunglasses>(55)");
    let garbage = "I am not sure what to do here.".to_owned();
    let (rounds, _) = two_rounds(1, vec![ask.clone(), ask], vec![garbage.clone(), garbage]).await;
    assert!(
        matches!(rounds[0].outcome, RoundOutcome::NoDecision { .. }),
        "{:?}",
        rounds[0].outcome
    );
    let feedback = &rounds[0].feedback;
    assert!(
        feedback.starts_with("<robot dog>(23) gave no usable answer"),
        "{feedback}"
    );
    assert!(
        feedback.contains(
            "\n- <sunglasses>(55): <sunglasses>(55) is on a high surface (ON_HIGH_SURFACE), \
             out of the robot dog's reach (too_high)."
        ),
        "{feedback}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_subtask_the_robot_can_start_adds_no_line() {
    // The dog can walk to the kitchen (6) now; it declines anyway: nothing to explain.
    let ask = proposal("<robot dog>(23)", "walk into the <kitchen>(6)");
    let (rounds, _) = two_rounds(2, vec![ask.clone(), ask], vec![none(), none()]).await;
    assert_eq!(
        rounds[0].feedback.lines().count(),
        1,
        "{}",
        rounds[0].feedback
    );
}
