//! What the integration tests share: the released benchmark, from `COHERENT_ORIGINAL_ENV`
//! (`.cargo/config.toml`: `../shared/coherent-original/env` beside the checkout), and
//! [`http`], the stub model servers' side of HTTP.

#![allow(dead_code)]

pub mod http;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::episode::Budget;
use coherent_agents::llm::Backend;
use coherent_agents::run::new_transcript;
use coherent_agents::transcript::Transcript;
use coherent_agents::{Cancel, Episode, Error, Replay, Settings};
use coherent_core::{Environment, SymbolicEnv, Task, read_tasks};

pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("COHERENT_ORIGINAL_ENV"))
}

/// Every well-formed task of the released files `env<n>.json` for `scenes`.
pub fn scenes(scenes: &[usize]) -> Vec<Task> {
    let mut out = Vec::new();
    for n in scenes {
        let path = data_dir().join(format!("env{n}.json"));
        out.extend(
            read_tasks(&path)
                .expect("benchmark file loads")
                .into_iter()
                .flatten(),
        );
    }
    out
}

/// Every well-formed task of the four released files (env3's index 18 is malformed).
pub fn released_tasks() -> Vec<Task> {
    let out = scenes(&[0, 1, 2, 3]);
    assert_eq!(out.len(), 81, "81 well-formed released tasks");
    out
}

/// Task `id` of scene `scene` (`env0`..`env3`).
pub fn task(scene: &str, id: i64) -> Arc<Task> {
    let path = data_dir().join(format!("{scene}.json"));
    let task = read_tasks(&path)
        .expect("benchmark file loads")
        .into_iter()
        .flatten()
        .find(|t| t.meta.task_id == id)
        .expect("the task is in the file");
    Arc::new(task)
}

/// Runs the method `settings` name on `env` as the session does (built by its name, under
/// the one loop), into a transcript made in `out`: the episode and the transcript's path.
pub async fn run(
    task: &Arc<Task>,
    env: &mut (dyn Environment + Send + Sync),
    backend: &dyn Backend,
    settings: &Settings,
    budget: Budget,
    out: &Path,
    cancel: &Cancel,
) -> Result<(Episode, PathBuf), Error> {
    let file = new_transcript(out, task, settings.method.name())?;
    let path = file.path().to_owned();
    let mut method = settings.build(task, cancel)?;
    let mut progress = |_: &coherent_agents::transcript::Round| {};
    let run = coherent_agents::run(
        task,
        env,
        backend,
        method.as_mut(),
        settings,
        budget,
        file,
        cancel,
        &mut progress,
    );
    Ok((run.await?.0, path))
}

/// Replays `recorded`, the transcript read from `file`, by the rules (its new transcript
/// in `out`): where the replay first differs from the recording, if it does.
pub async fn replay(recorded: &Transcript, file: &Path, out: &Path) -> Option<String> {
    let replay = Replay::prepare(recorded, file).expect("a replay");
    let mut env = SymbolicEnv::new(Arc::clone(&replay.task));
    let (replayed, _) = run(
        &replay.task,
        &mut env,
        replay.backend.as_ref(),
        &replay.settings,
        replay.budget,
        out,
        &Cancel::default(),
    )
    .await
    .expect("the replay runs");
    replay.difference(&replayed)
}
