//! Parallel episodes (joint steps): with the built-in backend, PEFA, CMRS, DMRS and the
//! optimal method solve every solvable released task in the makespan the search gives;
//! transcripts of parallel episodes (the simulated backend's mistakes included) replay
//! round for round; a parallel PEFA round asks its executors at once, over real sockets;
//! the tree searches refuse to run in parallel; old transcripts' rounds read as before.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use coherent_agents::episode::{Budget, PlannedMakespan};
use coherent_agents::llm::{Backend, Role};
use coherent_agents::transcript::{self, RoundOutcome, Status};
use coherent_agents::{Builtin, Settings};
use coherent_agents::{BuiltinBackend, Cancel, ErrorRates, OpenAiClient, OpenAiConfig};
use coherent_core::Execution;
use coherent_core::makespan;
use coherent_core::planner::Limits;
use coherent_core::{SymbolicEnv, Task};
use serde_json::{Value, json};
use tokio::io::AsyncWriteExt;
use tokio::net::TcpListener;

mod common;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coherent-parallel-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

fn parallel(method: Builtin) -> Settings {
    Settings {
        execution: Execution::Parallel,
        ..Settings::new(method)
    }
}

/// Runs `settings` on `task` with `backend` within `budget` (the episode's own when
/// `None`); the episode and its transcript.
async fn run(
    task: &Arc<Task>,
    backend: &dyn Backend,
    settings: &Settings,
    budget: Option<Budget>,
    out: &Path,
) -> (coherent_agents::Episode, PathBuf) {
    let budget = budget.unwrap_or_else(|| {
        Budget::searched(task, settings.execution, None, &Limits::default()).expect("a budget")
    });
    let mut env = SymbolicEnv::new(Arc::clone(task));
    let (e, path) = common::run(
        task,
        &mut env,
        backend,
        settings,
        budget,
        out,
        &Cancel::default(),
    )
    .await
    .expect("the episode runs");
    (e, path)
}

/// Replays the transcript at `path` and asserts it comes out as recorded.
async fn replays(path: &Path, out: &Path) {
    let recorded = transcript::read(path).expect("the transcript reads back");
    let difference = common::replay(&recorded, path, out).await;
    assert_eq!(difference, None, "{}", path.display());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn builtin_methods_solve_every_released_task_in_the_makespan_of_the_search() {
    let out = scratch("makespan");
    let mut solved = 0;
    for task in common::released_tasks() {
        let name = format!("{} task {}", task.meta.scene, task.meta.task_id);
        let search = makespan::search(&task, &task.robots, &task.goal, &Limits::default());
        let Some(makespan) = search.makespan() else {
            continue;
        };
        let budget =
            Budget::parallel(&task, None, || PlannedMakespan::of(&search)).expect("a budget");
        let task = Arc::new(task);
        // One backend for the task's episodes: it plans once and follows the plan.
        let backend = BuiltinBackend::new(Limits::default());
        for method in [
            Builtin::Pefa,
            Builtin::Cmrs,
            Builtin::Dmrs1d,
            Builtin::Optimal,
        ] {
            let (e, path) = run(&task, &backend, &parallel(method), Some(budget), &out).await;
            let s = &e.summary;
            assert_eq!(s.status, Status::Success, "{name} {}", method.name());
            assert_eq!(
                s.steps as usize,
                makespan,
                "{name} {}: the makespan",
                method.name()
            );
            let actions = transcript::actions(&e.rounds) as usize;
            let sequential = search.plan.iter().flatten().map(Vec::len).sum::<usize>();
            assert_eq!(
                actions,
                sequential,
                "{name} {}: every action of the plan",
                method.name()
            );
            for r in &e.rounds {
                assert_eq!(
                    r.outcome,
                    RoundOutcome::Executed,
                    "{name} {}",
                    method.name()
                );
                assert!(r.parts.iter().all(|p| p.outcome == RoundOutcome::Executed));
            }
            if method == Builtin::Pefa {
                // The assigner once a round (every robot is idle again: the built-in
                // executor completes its one-action subtask), then one executor per part.
                let parts: usize = e.rounds.iter().map(|r| r.parts.len()).sum();
                assert_eq!(s.llm_calls as usize, e.rounds.len() + parts, "{name}");
                replays(&path, &out).await;
            }
        }
        solved += 1;
    }
    assert_eq!(solved, 80, "every solvable released task");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn parallel_episodes_with_mistakes_replay_round_for_round() {
    let out = scratch("replay");
    let rates = ErrorRates::all(0.15);
    for (scene, id) in [("env0", 2), ("env1", 16), ("env2", 13), ("env3", 19)] {
        let task = common::task(scene, id);
        for method in [
            Builtin::Pefa,
            Builtin::Cmrs,
            Builtin::Dmrs2d,
            Builtin::Optimal,
        ] {
            for seed in 0..3 {
                let backend = BuiltinBackend::simulated(Limits::default(), rates, seed);
                let settings = Settings {
                    seed: Some(seed),
                    ..parallel(method)
                };
                let (e, path) = run(&task, &backend, &settings, None, &out).await;
                assert!(!e.rounds.is_empty());
                replays(&path, &out).await;
            }
        }
    }
}

#[test]
fn the_tree_searches_are_sequential_only() {
    let task = common::task("env0", 2);
    for method in [Builtin::Mcts, Builtin::LlmMcts] {
        let e = parallel(method)
            .build(&task, &Cancel::default())
            .err()
            .expect("refused");
        assert!(e.to_string().contains("sequential only"), "{e}");
    }
}

#[test]
fn a_round_written_before_parallel_episodes_reads_as_a_sequential_one() {
    let line = json!({
        "type": "round", "step": 1, "calls": [], "proposal": null, "actions": ["a"],
        "decision": null, "outcome": {"kind": "declined"}, "feedback": "", "done": false,
        "wall_ms": 1.0,
    });
    let record: transcript::Record = serde_json::from_value(line).expect("reads");
    let transcript::Record::Round(round) = record else {
        panic!("a round")
    };
    assert!(round.parts.is_empty());
    assert_eq!(round.actions_executed(), 0);
    let written = serde_json::to_value(transcript::Record::Round(round)).expect("writes");
    assert!(
        written.get("parts").is_none(),
        "a sequential round writes no parts"
    );
}

/// A model server that gives every idle robot a subtask, and whose executors always
/// pick the first action of their list and never finish: each answer waits `delay`, and
/// the server counts the executor requests in flight at once.
struct SlowServer {
    url: String,
    most_at_once: Arc<AtomicUsize>,
    requests: Arc<Mutex<Vec<Value>>>,
}

async fn slow_server(delay: Duration) -> SlowServer {
    let listener = TcpListener::bind("127.0.0.1:0").await.expect("a port");
    let url = format!("http://{}/v1", listener.local_addr().expect("an address"));
    let most_at_once = Arc::new(AtomicUsize::new(0));
    let requests = Arc::new(Mutex::new(Vec::new()));
    let (most, log) = (Arc::clone(&most_at_once), Arc::clone(&requests));
    let now = Arc::new(AtomicUsize::new(0));
    tokio::spawn(async move {
        loop {
            let Ok((mut socket, _)) = listener.accept().await else {
                return;
            };
            let (most, log, now) = (Arc::clone(&most), Arc::clone(&log), Arc::clone(&now));
            tokio::spawn(async move {
                while let Some(request) = common::http::read_request(&mut socket).await {
                    let body = request.body;
                    let name = body["response_format"]["json_schema"]["name"].clone();
                    let schema = &body["response_format"]["json_schema"]["schema"]["properties"];
                    let text = if name == "proposals" {
                        let idle = schema["assignments"]["items"]["properties"]["robot"]["enum"]
                            .as_array()
                            .cloned()
                            .unwrap_or_default();
                        let given: Vec<Value> = idle
                            .iter()
                            .map(|r| json!({"robot": r, "subtask": "keep busy"}))
                            .collect();
                        json!({"reasoning": "all at once", "assignments": given}).to_string()
                    } else {
                        let at_once = now.fetch_add(1, Ordering::SeqCst) + 1;
                        most.fetch_max(at_once, Ordering::SeqCst);
                        tokio::time::sleep(delay).await;
                        now.fetch_sub(1, Ordering::SeqCst);
                        let first = schema["action"]["enum"][0].clone();
                        json!({"action": first, "subtask_complete": false, "note": "more"})
                            .to_string()
                    };
                    log.lock().expect("the log").push(body);
                    let reply = common::http::completion(&text, "stop");
                    let head = format!(
                        "HTTP/1.1 200 OK\r\ncontent-type: application/json\r\ncontent-length: {}\r\n\r\n",
                        reply.len()
                    );
                    if socket.write_all(head.as_bytes()).await.is_err()
                        || socket.write_all(reply.as_bytes()).await.is_err()
                    {
                        return;
                    }
                }
            });
        }
    });
    SlowServer {
        url,
        most_at_once,
        requests,
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_parallel_round_asks_its_executors_at_once_and_robots_keep_their_subtasks() {
    let server = slow_server(Duration::from_millis(300)).await;
    let config = OpenAiConfig {
        base_urls: vec![server.url.clone()],
        model: "stub".into(),
        ..OpenAiConfig::default()
    };
    let client = OpenAiClient::new(config).expect("a client");
    // env1 task 16: four robots.
    let task = common::task("env1", 16);
    let out = scratch("at-once");
    let mut env = SymbolicEnv::new(Arc::clone(&task));
    let (e, _) = common::run(
        &task,
        &mut env,
        &client,
        &parallel(Builtin::Pefa),
        Budget::Given(3),
        &out,
        &Cancel::default(),
    )
    .await
    .expect("the episode runs");
    assert_eq!(e.rounds.len(), 3);
    let robots = task.robots.len();
    assert!(robots >= 3, "a team of several robots");
    assert_eq!(
        server.most_at_once.load(Ordering::SeqCst),
        robots,
        "every robot's executor was asked at once"
    );
    let first = &e.rounds[0];
    assert_eq!(first.parts.len(), robots);
    assert_eq!(first.calls[0].role, Role::Assigner);
    let executors = &first.calls[1..];
    assert!(executors.iter().all(|c| c.role == Role::Executor));
    let latencies: f64 = executors
        .iter()
        .filter_map(|c| c.answer.as_ref().map(|a| a.latency_ms))
        .sum();
    assert!(
        first.wall_ms < latencies * 0.6,
        "the round took {} ms, its executors' calls {latencies} ms between them",
        first.wall_ms
    );
    // Nobody finished a subtask: the later rounds keep them and ask no assigner, unless
    // a robot failed (its action refused) and is idle again.
    for r in &e.rounds[1..] {
        let asked = r.calls.iter().any(|c| c.role == Role::Assigner);
        let kept = r.parts.iter().filter(|p| p.kept).count();
        assert_eq!(asked, kept < robots, "round {}", r.step);
        assert!(kept > 0, "round {}: subtasks kept", r.step);
    }
    let calls = server.requests.lock().expect("the log").len();
    assert_eq!(calls as u32, e.summary.llm_calls);
}
