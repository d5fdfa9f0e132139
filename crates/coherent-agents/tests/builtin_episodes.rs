//! The built-in backend (the optimal planner in both roles) through the whole PEFA loop:
//! every solvable released task is solved in exactly the optimal number of steps, two
//! calls per round, and the transcript replays round for round.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::episode::Budget;
use coherent_agents::llm::Role;
use coherent_agents::transcript::{self, RoundOutcome, Status};
use coherent_agents::{Builtin, Settings};
use coherent_agents::{BuiltinBackend, Cancel, Replay};
use coherent_core::Execution;
use coherent_core::planner::{self, Limits};
use coherent_core::{SymbolicEnv, Task};

mod common;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coherent-agents-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

async fn run_builtin(task: &Arc<Task>, out: &Path) -> (Budget, coherent_agents::Episode, PathBuf) {
    let budget =
        Budget::searched(task, Execution::Sequential, None, &Limits::default()).expect("a budget");
    let mut env = SymbolicEnv::new(Arc::clone(task));
    let (e, path) = common::run(
        task,
        &mut env,
        &BuiltinBackend::new(Limits::default()),
        &Settings::new(Builtin::Pefa),
        budget,
        out,
        &Cancel::default(),
    )
    .await
    .expect("the episode runs");
    (budget, e, path)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn builtin_solves_every_solvable_task_in_the_optimal_number_of_steps() {
    let out = scratch("builtin");
    let mut solved = 0;
    for task in common::released_tasks() {
        let name = format!("{} task {}", task.meta.scene, task.meta.task_id);
        let optimum = planner::analyse(&task, &Limits::default())
            .plan
            .map(|p| p.len() as u32);
        let task = Arc::new(task);
        let (budget, e, path) = run_builtin(&task, &out).await;
        let s = &e.summary;
        match optimum {
            Some(optimum) => {
                assert_eq!(s.llm_calls, 2 * s.steps, "{name}: two calls per round");
                assert_eq!(s.status, Status::Success, "{name}");
                assert_eq!(s.steps, optimum, "{name}: steps against the optimum");
                assert!(
                    e.rounds.iter().all(|r| r.outcome == RoundOutcome::Executed),
                    "{name}"
                );
                solved += 1;
            }
            None => {
                // env3 task 0: the planner refuses each round until the budget is spent.
                assert_eq!(s.status, Status::Failure, "{name}");
                assert_eq!(s.steps, budget.steps(), "{name}");
                assert_eq!(
                    s.llm_calls, s.steps,
                    "{name}: the assigner's refusal ends each round"
                );
                assert!(
                    e.rounds
                        .iter()
                        .all(|r| matches!(&r.outcome, RoundOutcome::NoProposal { why } if why.contains("CONTAINERS"))),
                    "{name}: the refusal says why"
                );
            }
        }
        let t = transcript::read(&path).expect("the transcript reads back");
        assert!(
            t.rounds == e.rounds,
            "{name}: every round is in the transcript"
        );
        assert_eq!(t.summary.as_ref(), Some(&e.summary), "{name}");
    }
    assert_eq!(solved, 80);
}

#[tokio::test]
async fn a_transcript_replays_round_for_round_and_a_changed_one_is_caught() {
    let out = scratch("replay");
    let task = common::released_tasks()
        .into_iter()
        .find(|t| t.meta.scene == "env0" && t.meta.task_id == 16)
        .expect("env0 task 16");
    let task = Arc::new(task);
    let (_, recorded_episode, path) = run_builtin(&task, &out).await;
    let recorded = transcript::read(&path).expect("reads back");
    assert!(
        recorded_episode.rounds[0]
            .calls
            .iter()
            .any(|c| c.role == Role::Executor)
    );

    let replay = |t: &transcript::Transcript| {
        let replay = Replay::prepare(t, Path::new("recorded")).expect("task and settings");
        let out = out.clone();
        async move {
            let task = &replay.task;
            let mut env = SymbolicEnv::new(Arc::clone(task));
            let (episode, _) = common::run(
                task,
                &mut env,
                replay.backend.as_ref(),
                &replay.settings,
                replay.budget,
                &out,
                &Cancel::default(),
            )
            .await
            .expect("the replay runs");
            (replay, episode)
        }
    };
    let (setup, replayed) = replay(&recorded).await;
    assert_eq!(setup.difference(&replayed), None, "same rounds");

    // A prompt that differs from the recording stops the replay with the round named.
    let mut changed = recorded.clone();
    changed.rounds[2].calls[0].messages[1]
        .content
        .push_str(" (edited)");
    let (_, diverged) = replay(&changed).await;
    assert_eq!(diverged.summary.status, Status::BackendError);
    let error = diverged.summary.error.clone().unwrap_or_default();
    assert!(
        error.contains("round 3") && error.contains("prompt"),
        "{error}"
    );
    assert!(setup.difference(&diverged).is_some());

    // A transcript of a method this version does not know cannot be replayed.
    let mut unknown = recorded.clone();
    unknown.header.method = "nope".into();
    let error = Replay::prepare(&unknown, Path::new("recorded"))
        .expect_err("no such method")
        .to_string();
    assert!(error.contains("unknown method \"nope\""), "{error}");
}
