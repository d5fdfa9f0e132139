//! Running one episode end to end: the methods by name and the settings a transcript
//! records ([`settings`]: each method built into a [`Method`] in one place), the
//! transcript file (header, rounds, summary) and the method under the one loop, within
//! the step budget ([`run()`]); and the replay of a recorded episode ([`replay`]). The
//! session's episode runner, under every front end and the benchmark alike, goes through
//! here.

pub mod replay;
pub mod settings;

use std::fs::{File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use coherent_core::text::file_name_part;
use coherent_core::{Environment, Task, native};

use crate::episode::budget::Budget;
use crate::episode::cancel::Cancel;
use crate::episode::method::Method;
use crate::episode::play::{Course, Episode, play};
use crate::error::Error;
use crate::llm::{Backend, BackendInfo};
use crate::records::transcript::{self, Header, Record, Round, Writer};
use crate::run::settings::Settings;

/// The most bytes of a scene's or a method's name that a transcript's file name holds
/// (the whole name stays well under the 255 bytes file systems allow).
const NAME_PART_BYTES: usize = 64;

/// An episode's transcript file, made for it alone.
#[derive(Debug)]
pub struct TranscriptFile {
    path: PathBuf,
    file: File,
}

impl TranscriptFile {
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// Makes `<out>/<scene>-task<id>-<method>-<UTC time>.jsonl` (and `out` when it is not
/// there), with a counter when that exists; `method` is the method's name. The scene and
/// the method are written in safe characters only and shortened, with a hash when either
/// had to change ([`file_name_part`]). The name is taken by making the file, so that it
/// is this episode's alone: two episodes starting in the same second (a benchmark's
/// sequential and parallel runs of one task, two runs into one folder) would otherwise
/// both find it free and write one file. An error when the folder or the file cannot
/// be made: nothing of the episode has run.
pub fn new_transcript(out: &Path, task: &Task, method: &str) -> Result<TranscriptFile, Error> {
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
    let mut path = out.join(format!("{stem}.jsonl"));
    // Named by the transcript it would have been (a benchmark's results line keeps it).
    std::fs::create_dir_all(out).map_err(|e| Error::NoTranscript {
        file: path.display().to_string(),
        message: if out.exists() && !out.is_dir() {
            "the folder it goes in is a file".to_owned()
        } else {
            format!("its folder cannot be made: {e}")
        },
    })?;
    let mut n = 2;
    loop {
        match OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(file) => return Ok(TranscriptFile { path, file }),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {
                path = out.join(format!("{stem}-{n}.jsonl"));
                n += 1;
            }
            Err(e) => {
                return Err(Error::NoTranscript {
                    file: path.display().to_string(),
                    message: e.to_string(),
                });
            }
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

/// Runs `method` (built by `settings`: [`Settings::build`]) on `env` with `backend`
/// under the one loop, writing the transcript into `transcript` (header first, then each
/// round as it ends, then the summary). `progress` sees each round. Returns the episode
/// and the transcript's header, so that a caller holds the whole transcript without
/// reading it back.
#[allow(clippy::too_many_arguments)]
pub async fn run(
    task: &Arc<Task>,
    env: &mut (dyn Environment + Send + Sync),
    backend: &dyn Backend,
    method: &mut dyn Method,
    settings: &Settings,
    budget: Budget,
    transcript: TranscriptFile,
    cancel: &Cancel,
    progress: &mut (dyn FnMut(&Round) + Send),
) -> Result<(Episode, Header), Error> {
    let backend_info = if settings.method.asks_backend() {
        backend.info()
    } else {
        BackendInfo::none()
    };
    let header = Header {
        format: transcript::FORMAT.into(),
        version: transcript::VERSION,
        coherent: crate::records::VERSION.into(),
        task: native::to_value(task),
        task_name: task.meta.name.clone(),
        method: settings.method.name().into(),
        execution: settings.execution,
        history: settings.history_window(),
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
        external: settings.method.builtin().is_none(),
        max_states: (!task.events.is_empty()).then_some(settings.max_states),
    };
    let TranscriptFile { path, file } = transcript;
    let io = |e: io::Error| Error::io(&path, &e);
    let mut writer = Writer::new(file, header.clone()).map_err(|e| Error::NoTranscript {
        file: path.display().to_string(),
        message: e.to_string(),
    })?;
    let mut on_round = |r: &Round| {
        progress(r);
        writer.write(&Record::Round(Box::new(r.clone())))
    };
    let course = Course {
        execution: settings.execution,
        max_steps: budget.steps(),
        history: header.history,
        max_states: settings.max_states,
        seed: settings.seed.unwrap_or(0),
    };
    let episode = play(env, task, method, backend, course, cancel, &mut on_round)
        .await
        .map_err(io)?;
    writer
        .write(&Record::Summary(episode.summary.clone()))
        .map_err(io)?;
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
        let task = crate::prompts::fill::demo_task();
        let start = std::sync::Barrier::new(8);
        let paths: Vec<PathBuf> = std::thread::scope(|s| {
            let each: Vec<_> = (0..8)
                .map(|_| {
                    s.spawn(|| {
                        start.wait();
                        new_transcript(&out, &task, "pefa").map(|t| t.path)
                    })
                })
                .collect();
            each.into_iter()
                .map(|t| t.join().expect("named").expect("made"))
                .collect()
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
