//! Events mid-task (docs/dynamic.md): for each kind, the built-in backend (the optimal
//! planner, replanning at each event) finishes in exactly the reference steps, in PEFA,
//! CMRS and the optimal method, sequential and parallel (the optimum after an event
//! against a breadth-first search: tests/events.rs); an event that puts the goal out
//! of reach for good ends the episode as right, with the reason; the prompts after an
//! event say what happened; and a transcript with events replays round for round.

use std::path::PathBuf;
use std::sync::Arc;

use coherent_agents::episode::Budget;
use coherent_agents::transcript::{self, Status};
use coherent_agents::{Builtin, BuiltinBackend, Cancel, Settings};
use coherent_core::planner::Limits;
use coherent_core::{Execution, JsonPath, SymbolicEnv, Task, events};
use serde_json::{Value, json};

mod common;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coherent-events-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// The demo task (examples/tasks/demo.json): an arm on the kitchen counter, a quadrotor
/// in the living room, a dog in the kitchen; the mug and the apple to the coffee table.
fn demo() -> Task {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/tasks/demo.json");
    coherent_core::load_tasks(&path)
        .expect("the demo")
        .remove(0)
}

fn with_events(events: Value) -> Arc<Task> {
    let mut task = demo();
    task.events = events::read(&task, &events, "test", JsonPath::root()).expect("events read");
    Arc::new(task)
}

/// One event of each kind on the demo task (and two that end a span), failing actions
/// twice.
fn kinds() -> Vec<(&'static str, Value)> {
    vec![
        (
            "robot_down",
            // The arm, once the mug it grabs from the high counter is in the basket.
            json!([{"when": {"relation": "INSIDE", "subject": 7, "target": 12},
                    "kind": "robot_down", "robot": 6}]),
        ),
        (
            "robot_up",
            json!([{"step": 6, "kind": "robot_up", "robot": 13, "room": 0}]),
        ),
        (
            "object_moved",
            json!([{"when": {"held": 7}, "kind": "object_moved", "thing": 9,
                    "relation": "ON", "target": 14}]),
        ),
        (
            "goal_changed",
            json!([{"step": 5, "kind": "goal_changed",
                    "remove": [{"relation": "ON", "subject": 9, "target": 10}],
                    "add": [{"relation": "ON", "subject": 9, "target": 14}],
                    "instruction": "The mug to the coffee table, the apple to the sofa."}]),
        ),
        (
            "blocked",
            json!([{"step": 2, "kind": "blocked", "door": 4, "steps": 3}]),
        ),
        (
            "action_fails",
            json!([{"step": 2, "kind": "action_fails", "probability": 0.3}]),
        ),
        (
            // Half the actions: in a parallel episode, joint steps in which several
            // actions fail, each one joint step lost.
            "action_fails",
            json!([{"step": 2, "kind": "action_fails", "probability": 0.5}]),
        ),
    ]
}

async fn episode(
    task: &Arc<Task>,
    method: Builtin,
    execution: Execution,
    out: &std::path::Path,
) -> (coherent_agents::Episode, PathBuf) {
    let mut settings = Settings::new(method);
    settings.execution = execution;
    settings.seed = Some(3);
    let mut env = SymbolicEnv::new(Arc::clone(task));
    common::run(
        task,
        &mut env,
        &BuiltinBackend::new(Limits::default()),
        &settings,
        Budget::Given(80),
        out,
        &Cancel::default(),
    )
    .await
    .expect("the episode runs")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_builtin_backend_finishes_in_exactly_the_reference_steps_for_every_kind() {
    let out = scratch("reference");
    for (kind, list) in kinds() {
        let task = with_events(list);
        for execution in [Execution::Sequential, Execution::Parallel] {
            for method in [Builtin::Pefa, Builtin::Cmrs, Builtin::Optimal] {
                let name = format!("{kind} {} {execution:?}", method.name());
                let (e, path) = episode(&task, method, execution, &out).await;
                let s = &e.summary;
                let reference = s.reference.as_ref().expect("a reference with events");
                assert_eq!(s.status, Status::Success, "{name}");
                assert_eq!(Some(s.steps), reference.steps, "{name}: {reference:?}");
                let happened: usize = e.rounds.iter().map(|r| r.events.len()).sum();
                assert!(happened >= 1, "{name}: the event happened");
                // Replayed round for round, events and all.
                let recorded = transcript::read(&path).expect("the transcript");
                let again = common::replay(&recorded, &path, &out).await;
                assert_eq!(again, None, "{name}: the replay differs");
            }
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn without_the_lost_robot_the_goal_is_out_of_reach_and_saying_so_is_right() {
    let out = scratch("conceded");
    // The quadrotor is the only way the mug leaves the high counter.
    let task = with_events(json!([{"step": 4, "kind": "robot_down", "robot": 11}]));
    for method in [Builtin::Pefa, Builtin::Optimal] {
        let (e, _) = episode(&task, method, Execution::Sequential, &out).await;
        let s = &e.summary;
        assert_eq!(s.status, Status::Conceded, "{}", method.name());
        assert!(s.success, "conceding an unreachable goal is right");
        assert_eq!(
            s.steps, 4,
            "the team stops at the first round after the event"
        );
        let reference = s.reference.as_ref().expect("a reference");
        assert_eq!(reference.steps, None);
        let why = reference.unreachable.as_deref().expect("the reason");
        assert!(why.contains("reaches the goal"), "{why}");
    }
    // A robot that joins later brings the goal back: out of reach at the start is not
    // out of reach for good, and nobody concedes.
    let task = with_events(json!([{"step": 6, "kind": "robot_up", "robot": 13, "room": 0}]));
    let (e, _) = episode(&task, Builtin::Pefa, Execution::Sequential, &out).await;
    let reference = e.summary.reference.as_ref().expect("a reference");
    assert!(reference.start.unreachable.is_some(), "{reference:?}");
    assert_eq!(e.summary.status, Status::Success);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_role_is_told_what_happened_in_its_next_prompt() {
    let out = scratch("told");
    let task = with_events(json!([{"step": 3, "kind": "object_moved", "thing": 9,
                                    "relation": "ON", "target": 14}]));
    for method in [
        Builtin::Pefa,
        Builtin::Cmrs,
        Builtin::Dmrs2d,
        Builtin::LlmPddl,
    ] {
        let (e, _) = episode(&task, method, Execution::Sequential, &out).await;
        let told = "Someone outside the team moved <apple>(9) onto <sofa>(14).";
        let round = &e.rounds[2];
        assert_eq!(round.events.len(), 1, "{}", method.name());
        assert!(!round.calls.is_empty(), "{}", method.name());
        for call in &round.calls {
            let text: String = call.messages.iter().map(|m| m.content.as_str()).collect();
            assert!(text.contains(told), "{}: {text}", method.name());
        }
        for call in &e.rounds[1].calls {
            let text: String = call.messages.iter().map(|m| m.content.as_str()).collect();
            assert!(!text.contains("What just happened"), "{}", method.name());
        }
    }
}
