//! `--method random`, the floor: seeded and reproducible, every action it takes one the
//! rules offer (so it runs), every joint step it takes valid, and its episodes replay.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::episode::Budget;
use coherent_agents::transcript::{self, RoundOutcome, Status};
use coherent_agents::{Builtin, BuiltinBackend, Cancel, Episode, Replay, Settings};
use coherent_core::planner::Limits;
use coherent_core::{Execution, SymbolicEnv, Task};

mod common;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("coherent-random-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

async fn random(
    task: &Arc<Task>,
    execution: Execution,
    seed: u64,
    out: &Path,
) -> (Episode, PathBuf) {
    let settings = Settings {
        execution,
        seed: Some(seed),
        ..Settings::new(Builtin::Random)
    };
    let mut env = SymbolicEnv::new(Arc::clone(task));
    let backend = BuiltinBackend::new(Limits::default());
    common::run(
        task,
        &mut env,
        &backend,
        &settings,
        Budget::Given(30),
        out,
        &Cancel::default(),
    )
    .await
    .expect("the episode runs")
}

/// The robot and action of each round, or of each part of a joint step.
fn taken(e: &Episode) -> Vec<Vec<(Option<i64>, Option<String>)>> {
    e.rounds
        .iter()
        .map(|r| {
            if r.parts.is_empty() {
                let (robot, action) = r.chosen();
                vec![(robot.map(|id| id.0), action.map(str::to_owned))]
            } else {
                r.parts
                    .iter()
                    .map(|p| (Some(p.robot.0), p.action().map(str::to_owned)))
                    .collect()
            }
        })
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_same_seed_gives_the_same_episode_and_other_seeds_others() {
    let out = scratch("seeds");
    let task = common::task("env1", 16);
    for execution in Execution::ALL {
        let (a, _) = random(&task, execution, 7, &out).await;
        let (b, _) = random(&task, execution, 7, &out).await;
        assert_eq!(taken(&a), taken(&b), "{execution}");
        let mut differ = false;
        for seed in 8..12 {
            differ |= taken(&random(&task, execution, seed, &out).await.0) != taken(&a);
        }
        assert!(differ, "{execution}: the seed decides");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_action_it_takes_runs_and_every_joint_step_is_valid() {
    let out = scratch("valid");
    for task in common::released_tasks().into_iter().step_by(9) {
        let task = Arc::new(task);
        let name = format!("{} task {}", task.meta.scene, task.meta.task_id);
        let (e, _) = random(&task, Execution::Sequential, 1, &out).await;
        assert!(!e.rounds.is_empty(), "{name}");
        for r in &e.rounds {
            assert_eq!(r.outcome, RoundOutcome::Executed, "{name} round {}", r.step);
            let d = r.decision.as_ref().expect("a decision");
            let robot = d.robot.expect("its robot");
            let line = coherent_agents::prompts::fill::action_line(
                &task,
                robot,
                d.action.as_deref().unwrap_or_default(),
            );
            assert!(
                r.actions.contains(&line),
                "{name}: one of the team's actions"
            );
            assert_eq!(r.calls.len(), 0, "no model");
        }
        let (e, _) = random(&task, Execution::Parallel, 1, &out).await;
        for r in &e.rounds {
            assert_eq!(r.outcome, RoundOutcome::Executed, "{name} round {}", r.step);
            assert!(!r.parts.is_empty(), "{name}: some robot can always act");
            assert!(r.parts.iter().all(|p| p.outcome == RoundOutcome::Executed));
        }
        assert_ne!(e.summary.status, Status::Error, "{name}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_random_episode_replays_exactly() {
    let out = scratch("replay");
    let task = common::task("env0", 2);
    for execution in Execution::ALL {
        let (_, path) = random(&task, execution, 3, &out).await;
        let recorded = transcript::read(&path).expect("reads back");
        assert_eq!(recorded.header.method, "random");
        let replay = Replay::prepare(&recorded, &path).expect("a replay");
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
        assert_eq!(replay.difference(&replayed), None, "{execution}");
    }
    let _ = std::fs::remove_dir_all(&out);
}
