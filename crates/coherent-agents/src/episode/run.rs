//! Running one episode's method end to end: the transcript file (header, rounds,
//! summary) and the method the settings name, within the step budget. The session's
//! episode runner, under every front end and the benchmark alike, goes through here.

use std::fs::OpenOptions;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use coherent_core::planner::Limits;
use coherent_core::text::file_name_part;
use coherent_core::{Environment, Task, native};

use crate::backends::llm::{Backend, BackendInfo};
use crate::episode::budget::Budget;
use crate::episode::cancel::Cancel;
use crate::episode::rounds::Episode;
use crate::episode::settings::{Execution, Method, MethodSpec, Settings};
use crate::error::Error;
use crate::methods::cmrs::{self, CmrsConfig};
use crate::methods::dmrs::{self, DmrsConfig};
use crate::methods::external;
use crate::methods::mcts::{self, MctsConfig};
use crate::methods::optimal;
use crate::methods::pefa::{self, PefaConfig};
use crate::methods::pefa_parallel;
use crate::records::transcript::{self, Header, Record, Round, Writer};

/// The most bytes of a scene's or a method's name that a transcript's file name holds
/// (the whole name stays well under the 255 bytes file systems allow).
const NAME_PART_BYTES: usize = 64;

/// `<out>/<scene>-task<id>-<method>-<UTC time>.jsonl`, with a counter when that exists;
/// `method` is the method's name. The scene and the method are written in safe
/// characters only and shortened, with a hash when either had to change
/// ([`file_name_part`]). The file is made here, empty, so that the name is this
/// episode's alone: two episodes starting in the same second (a benchmark's sequential
/// and parallel runs of one task, two runs into one folder) would otherwise both find it
/// free and write one file. Where it cannot be made (its folder cannot be), the name is
/// given as it is, and making the transcript says why.
pub fn transcript_path(out: &Path, task: &Task, method: &str) -> PathBuf {
    let secs = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let stem = format!(
        "{}-task{}-{}-{}",
        file_name_part(&task.meta.scene, NAME_PART_BYTES),
        task.meta.task_id,
        file_name_part(method, NAME_PART_BYTES),
        utc_stamp(secs)
    );
    let _ = std::fs::create_dir_all(out);
    let mut path = out.join(format!("{stem}.jsonl"));
    let mut n = 2;
    loop {
        match OpenOptions::new().write(true).create_new(true).open(&path) {
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {
                path = out.join(format!("{stem}-{n}.jsonl"));
                n += 1;
            }
            _ => return path,
        }
    }
}

/// `YYYYmmddTHHMMSSZ` for Unix seconds (the civil calendar from days, after H. Hinnant's
/// public-domain date algorithms).
fn utc_stamp(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}{month:02}{day:02}T{:02}{:02}{:02}Z",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

/// Runs `method` on `env` with `backend`, writing the transcript to `transcript` (header
/// first, then each round as it ends, then the summary). `progress` sees each round.
/// Returns the episode and the transcript's header, so that a caller holds the whole
/// transcript without reading it back.
#[allow(clippy::too_many_arguments)]
pub async fn run(
    task: &Arc<Task>,
    env: &mut (dyn Environment + Send),
    backend: &dyn Backend,
    settings: &Settings,
    budget: Budget,
    transcript: &Path,
    cancel: &Cancel,
    progress: &mut (dyn FnMut(&Round) + Send),
) -> Result<(Episode, Header), Error> {
    let history = match settings.method {
        MethodSpec::Builtin(Method::PefaNoHistory) => 0,
        _ => settings.history,
    };
    let backend_info = if settings.method.asks_backend() {
        backend.info()
    } else {
        BackendInfo::none()
    };
    let header = Header {
        format: transcript::FORMAT.into(),
        version: transcript::VERSION,
        coherent: crate::VERSION.into(),
        task: native::to_value(task),
        task_name: task.meta.name.clone(),
        method: settings.method.name().into(),
        execution: settings.execution,
        history,
        max_steps: budget.steps(),
        gt_steps: task.meta.gt_steps,
        physics: settings.physics,
        robots: settings.robots.clone(),
        backend: backend_info,
        temperature: settings.temperature,
        seed: settings.seed,
        prompts: Some(settings.prompts.record(settings.execution)),
        started_ms: SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_millis() as u64),
        external: matches!(settings.method, MethodSpec::External(_)),
    };
    let io = |e: std::io::Error| Error::io(transcript, &e);
    let mut writer =
        Writer::create(transcript, header.clone()).map_err(|e| Error::NoTranscript {
            file: transcript.display().to_string(),
            message: e.to_string(),
        })?;
    let mut on_round = |r: &Round| {
        progress(r);
        writer.write(&Record::Round(Box::new(r.clone())))
    };
    let prompts = settings.prompts.clone();
    let mcts = MctsConfig {
        seed: settings.seed.unwrap_or(0),
        history,
        prompts: prompts.clone(),
        ..MctsConfig::default()
    };
    let steps = budget.steps();
    let execution = settings.execution;
    settings.method.check_runs(execution)?;
    let method = match &settings.method {
        MethodSpec::Builtin(method) => *method,
        MethodSpec::External(method) => {
            let made = method.make(task);
            let budget = (execution, steps);
            let limit = method.step_timeout();
            let episode =
                external::run(env, task, made, budget, limit, cancel, &mut on_round).await;
            return finish(episode.map_err(io)?, header, &mut writer, transcript);
        }
    };
    let parallel = execution == Execution::Parallel;
    let episode = match method {
        Method::Pefa | Method::PefaNoHistory => {
            let config = PefaConfig {
                history,
                prompts,
                ..PefaConfig::new(steps)
            };
            if parallel {
                pefa_parallel::run(env, task, backend, &config, cancel, &mut on_round).await
            } else {
                pefa::run(env, task, backend, &config, cancel, &mut on_round).await
            }
        }
        Method::Cmrs => {
            let config = CmrsConfig {
                history,
                prompts,
                execution,
            };
            cmrs::run(env, task, backend, &config, steps, cancel, &mut on_round).await
        }
        Method::Dmrs1d | Method::Dmrs2d => {
            let config = DmrsConfig {
                dialogue_rounds: if method == Method::Dmrs1d { 1 } else { 2 },
                history,
                seed: settings.seed.unwrap_or(0),
                prompts,
                execution,
            };
            dmrs::run(env, task, backend, &config, steps, cancel, &mut on_round).await
        }
        Method::Mcts => mcts::run(env, task, None, &mcts, steps, cancel, &mut on_round).await,
        Method::LlmMcts => {
            let model = Some(backend);
            mcts::run(env, task, model, &mcts, steps, cancel, &mut on_round).await
        }
        Method::Optimal => {
            let limits = Limits {
                cancel: Some(cancel.flag()),
                ..Limits::default()
            };
            optimal::run(env, task, &limits, execution, steps, cancel, &mut on_round).await
        }
    }
    .map_err(io)?;
    finish(episode, header, &mut writer, transcript)
}

/// Writes the summary line: the transcript is complete.
fn finish(
    episode: Episode,
    header: Header,
    writer: &mut Writer,
    transcript: &Path,
) -> Result<(Episode, Header), Error> {
    writer
        .write(&Record::Summary(episode.summary.clone()))
        .map_err(|e| Error::io(transcript, &e))?;
    Ok((episode, header))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_stamps() {
        assert_eq!(utc_stamp(0), "19700101T000000Z");
        assert_eq!(utc_stamp(951_782_400), "20000229T000000Z");
        assert_eq!(utc_stamp(1_795_323_508), "20261122T045828Z");
    }

    /// Episodes of one task and method that start at once (a benchmark's sequential and
    /// parallel runs, say) each get a transcript of their own, never one between them.
    #[test]
    fn episodes_starting_at_once_get_a_transcript_each() {
        let out = std::env::temp_dir().join(format!("coherent-names-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let task = crate::methods::prompt::demo_task();
        let start = std::sync::Barrier::new(8);
        let paths: Vec<PathBuf> = std::thread::scope(|s| {
            let each: Vec<_> = (0..8)
                .map(|_| {
                    s.spawn(|| {
                        start.wait();
                        transcript_path(&out, &task, "pefa")
                    })
                })
                .collect();
            each.into_iter().map(|t| t.join().expect("named")).collect()
        });
        let mut distinct = paths.clone();
        distinct.sort();
        distinct.dedup();
        assert_eq!(distinct.len(), 8, "{paths:?}");
        assert!(
            paths.iter().all(|p| p.is_file()),
            "each name is taken: {paths:?}"
        );
        let _ = std::fs::remove_dir_all(&out);
    }
}
