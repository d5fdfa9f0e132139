//! Transcripts of version 1 (before decisions named their robot) still read, as version 2
//! records the same rounds, and still replay: each transcript below is written now,
//! turned back into version 1 the way version 1 wrote it (the robot of a decision without
//! a proposal in front of its action, `<robot label>: <action>`; no `robot` fields), and
//! read again.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::episode::Budget;
use coherent_agents::prompts::fill::robot_label;
use coherent_agents::transcript::{self, Transcript};
use coherent_agents::{Builtin, BuiltinBackend, Cancel, ErrorRates, Replay, Settings};
use coherent_core::planner::Limits;
use coherent_core::{Execution, NodeId, SymbolicEnv, Task};
use serde_json::Value;

mod common;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coherent-v1-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// A decision as version 1 wrote it: no robot; without a proposal, the robot's label in
/// front of the action.
fn decision_v1(task: &Task, decision: &mut Value, prefix: bool) {
    let Some(d) = decision.as_object_mut() else {
        return;
    };
    let robot = d.remove("robot").and_then(|r| r.as_i64());
    if let (true, Some(robot), Some(Value::String(action))) = (prefix, robot, d.get_mut("action")) {
        *action = format!("{}: {action}", robot_label(task, NodeId(robot)));
    }
}

/// The transcript at `path` rewritten as version 1, at `to`.
fn as_version_1(task: &Task, path: &Path, to: &Path) {
    let text = std::fs::read_to_string(path).expect("reads");
    let mut lines = Vec::new();
    for line in text.lines() {
        let mut record: Value = serde_json::from_str(line).expect("JSON");
        match record["type"].as_str() {
            Some("header") => record["version"] = 1.into(),
            Some("round") => {
                let prefix = record["proposal"].is_null();
                decision_v1(task, &mut record["decision"], prefix);
                let parts = record.get_mut("parts").and_then(Value::as_array_mut);
                for part in parts.into_iter().flatten() {
                    decision_v1(task, &mut part["decision"], false);
                }
            }
            _ => {}
        }
        lines.push(serde_json::to_string(&record).expect("JSON"));
    }
    std::fs::write(to, lines.join("\n") + "\n").expect("writes");
}

async fn recorded(task: &Arc<Task>, settings: &Settings, out: &Path) -> (Transcript, PathBuf) {
    let mut env = SymbolicEnv::new(Arc::clone(task));
    let rates = ErrorRates::all(0.3);
    let backend = BuiltinBackend::simulated(Limits::default(), rates, 5);
    let budget = Budget::Given(12);
    let (_, path) = common::run(
        task,
        &mut env,
        &backend,
        settings,
        budget,
        out,
        &Cancel::default(),
    )
    .await
    .expect("the episode runs");
    (transcript::read(&path).expect("reads back"), path)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_version_1_transcript_reads_as_version_2_and_replays() {
    let out = scratch("read");
    let task = common::task("env0", 2);
    let methods = [
        Builtin::Pefa,
        Builtin::Cmrs,
        Builtin::Dmrs1d,
        Builtin::Mcts,
        Builtin::Optimal,
    ];
    for method in methods {
        for execution in Execution::ALL {
            let settings = Settings {
                execution,
                ..Settings::new(method)
            };
            if settings.method.check_runs(execution).is_err() {
                continue;
            }
            let name = format!("{} {execution}", method.name());
            let (now, path) = recorded(&task, &settings, &out).await;
            assert_eq!(now.header.version, transcript::VERSION);
            let old = path.with_extension("v1.jsonl");
            as_version_1(&task, &path, &old);
            let read = transcript::read(&old).expect("a version 1 transcript reads");
            assert_eq!(read.header.version, 1);
            assert_eq!(read.rounds, now.rounds, "{name}: the same rounds");
            let replay = Replay::prepare(&read, &old).expect("a replay");
            let mut env = SymbolicEnv::new(Arc::clone(&replay.task));
            let (replayed, _) = common::run(
                &replay.task,
                &mut env,
                replay.backend.as_ref(),
                &replay.settings,
                replay.budget,
                &out,
                &Cancel::default(),
            )
            .await
            .expect("the replay runs");
            assert_eq!(replay.difference(&replayed), None, "{name}");
        }
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_version_the_reader_does_not_know_is_refused_with_the_versions_it_reads() {
    let out = scratch("future");
    let task = common::task("env0", 2);
    let (_, path) = recorded(&task, &Settings::new(Builtin::Cmrs), &out).await;
    let text = std::fs::read_to_string(&path).expect("reads");
    let later = format!("\"version\":{}", transcript::VERSION + 1);
    let now = format!("\"version\":{}", transcript::VERSION);
    std::fs::write(&path, text.replacen(&now, &later, 1)).expect("writes");
    let err = transcript::read(&path).expect_err("refused");
    assert!(err.to_string().contains("line 1"), "{err}");
    assert!(err.to_string().contains("versions 1 to 2"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}
