//! The driver's side of a benchmark run, whatever executes the episodes: the results
//! file read back and repaired, the episodes still to run, and each result written as
//! it comes, once. Only the driver writes the results file; executors hand it results.

use std::collections::{BTreeMap, HashSet};
use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_core::Task;

use coherent_core::Execution;

use crate::error::Error;
use crate::harness::results::{
    EpisodeKey, ResultLine, mark_orphans, read_results_within, repair, transcripts_dir,
};
use crate::harness::run_settings::{RunSettings, method_text};
use crate::records::lock;
use crate::records::transcript::Status;
use crate::run::settings::MethodSpec;
use crate::setting::{Difference, Setting};

/// What came of one episode, as an executor hands it to the driver.
#[derive(Debug)]
pub enum EpisodeResult {
    /// It ran (to any end): its results line, its transcript written.
    Line(Box<ResultLine>),
    /// Cancelled before it started.
    NotStarted,
    /// Its task cannot run, and why (no ground truth and no plan to size a budget, or no
    /// recording to replay).
    TaskSkipped(String),
}

/// Every episode of `methods` x `executions` x `tasks` x seed indices `0..seeds`, task by
/// task, seed by seed, execution by execution, method by method: the order a run starts
/// them in.
pub fn episode_keys(
    tasks: &[Arc<Task>],
    methods: &[MethodSpec],
    executions: &[Execution],
    seeds: u32,
) -> Vec<EpisodeKey> {
    let mut keys = Vec::new();
    for task in tasks {
        for seed in 0..seeds {
            for &execution in executions {
                for method in methods {
                    keys.push(EpisodeKey {
                        method: method.name().to_owned(),
                        scene: task.meta.scene.clone(),
                        task_id: task.meta.task_id,
                        seed,
                        execution,
                    });
                }
            }
        }
    }
    keys
}

/// What a run did.
#[derive(Debug, Default)]
pub struct BenchOutcome {
    /// Episodes in the plan (methods x tasks x seeds).
    pub total: usize,
    /// Already finished in the results file before this run.
    pub skipped: usize,
    /// Lines written by this run (any status).
    pub written: usize,
    /// Episodes this run finished for good (success or budget spent): `total` is
    /// `skipped + finished + unfinished`.
    pub finished: usize,
    /// Episodes this run did not finish for good: interrupted, backend errors, the
    /// method's errors, tasks that cannot run, or never started because of Ctrl-C.
    pub unfinished: usize,
    /// Those of them that ended in the method's own error (status `error`).
    pub method_errors: usize,
    /// Those of them never started (Ctrl-C) or whose task cannot run.
    pub not_started: usize,
    /// Whether Ctrl-C (the `cancel` handle) stopped the run.
    pub interrupted: bool,
    /// Tasks that could not be run and why (no ground truth and no plan to size a budget).
    pub skipped_tasks: Vec<String>,
    /// Lines dropped from a cut-off last line.
    pub repaired_bytes: u64,
    /// Transcripts that no results line points to (episodes killed mid-run), renamed to
    /// `*.jsonl.unfinished` before this run; their episodes run again.
    pub orphaned: Vec<PathBuf>,
}

/// A run's results file, open for appending, and the lock that makes the run its only
/// writer (and the only one to rename transcripts in its folder).
#[derive(Debug)]
pub struct Ledger {
    out: PathBuf,
    /// Held while the ledger lives ([`crate::records::lock`]).
    _lock: File,
    /// The most the results file may hold when read back.
    max_bytes: u64,
    file: File,
    /// Episodes with a final line: in the file before the run, or written by it.
    done: HashSet<EpisodeKey>,
    /// Episodes this run has written a line for (of any status).
    written: HashSet<EpisodeKey>,
    /// The run's settings by method, recorded in each line written.
    settings: BTreeMap<String, RunSettings>,
    outcome: BenchOutcome,
}

impl Ledger {
    /// Opens the results file `out` (and its folder) for appending: a last line cut off
    /// mid-write is dropped, transcripts no line points to are marked unfinished, and the
    /// episodes with a final line are known to be done. A results file of more than
    /// `max_bytes` is refused. Another run on the same results file, or on one whose
    /// transcripts share the folder, is refused naming its process. A file whose lines
    /// were run with other settings than `now` (each method's, by name) is refused before
    /// anything is changed ([`Error::SettingsDiffer`]); the file is read once, under the
    /// lock, for both.
    pub fn open(
        out: &Path,
        max_bytes: u64,
        now: &BTreeMap<String, RunSettings>,
    ) -> Result<Ledger, Error> {
        refuse_other_than_a_file(out)?;
        let lock = take_lock(out)?;
        let mut outcome = BenchOutcome::default();
        let mut done = HashSet::new();
        if out.exists() {
            let file = read_results_within(out, max_bytes)?;
            let differences = mismatch(&file.lines, now);
            if !differences.is_empty() {
                return Err(Error::SettingsDiffer {
                    file: out.display().to_string(),
                    differences,
                });
            }
            outcome.repaired_bytes = file.truncated_bytes;
            repair(out, &file)?;
            done.extend(
                file.lines
                    .iter()
                    .filter(|l| l.is_final())
                    .map(ResultLine::key),
            );
            outcome.orphaned = mark_orphans(out, &file.lines)?;
        } else if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, &e))?;
        }
        let file = OpenOptions::new()
            .create(true)
            .append(true)
            .open(out)
            .map_err(|e| Error::io(out, &e))?;
        Ok(Ledger {
            out: out.to_owned(),
            _lock: lock,
            max_bytes,
            file,
            done,
            written: HashSet::new(),
            settings: now.clone(),
            outcome,
        })
    }

    /// The episodes of `methods` x `executions` x `tasks` x seed indices `0..seeds` that
    /// have no final line yet, in the order they are to start ([`episode_keys`]); the
    /// others count as skipped.
    pub fn plan(
        &mut self,
        tasks: &[Arc<Task>],
        methods: &[MethodSpec],
        executions: &[Execution],
        seeds: u32,
    ) -> Vec<EpisodeKey> {
        let all = episode_keys(tasks, methods, executions, seeds);
        self.outcome.total += all.len();
        let pending: Vec<EpisodeKey> = all.into_iter().filter(|k| !self.done.contains(k)).collect();
        self.outcome.skipped = self.outcome.total - pending.len();
        pending
    }

    /// Records what came of one episode: a line with the run's settings is appended and
    /// flushed, unless this run already wrote that episode's line (a result delivered
    /// twice is written once). Returns the line written, if one was.
    pub fn record(&mut self, result: EpisodeResult) -> Result<Option<ResultLine>, Error> {
        let line = match result {
            EpisodeResult::Line(line) => ResultLine {
                settings: self.settings.get(&line.method).cloned(),
                ..*line
            },
            EpisodeResult::NotStarted => {
                self.outcome.unfinished += 1;
                self.outcome.not_started += 1;
                return Ok(None);
            }
            EpisodeResult::TaskSkipped(why) => {
                self.outcome.unfinished += 1;
                self.outcome.not_started += 1;
                if !self.outcome.skipped_tasks.contains(&why) {
                    self.outcome.skipped_tasks.push(why);
                }
                return Ok(None);
            }
        };
        if !self.written.insert(line.key()) {
            return Ok(None);
        }
        let mut text = serde_json::to_string(&line).map_err(|e| Error::Io {
            file: self.out.display().to_string(),
            message: format!("cannot encode a results line: {e}"),
        })?;
        text.push('\n');
        self.file
            .write_all(text.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| Error::io(&self.out, &e))?;
        self.outcome.written += 1;
        if line.is_final() {
            self.done.insert(line.key());
            self.outcome.finished += 1;
        } else {
            self.outcome.unfinished += 1;
            self.outcome.method_errors += usize::from(line.status == Status::Error);
        }
        Ok(Some(line))
    }

    /// Renames to `*.jsonl.unfinished` the transcripts no line of the results file
    /// points to, as resuming does: a worker that died mid-episode left them, and its
    /// episodes ran again elsewhere. They are added to the outcome's `orphaned`.
    pub fn mark_orphans(&mut self) -> Result<(), Error> {
        let lines = read_results_within(&self.out, self.max_bytes)?.lines;
        let marked = mark_orphans(&self.out, &lines)?;
        self.outcome.orphaned.extend(marked);
        Ok(())
    }

    /// The file whose lock makes a run the only one on `out` (in its transcripts
    /// folder, which two results files of the same stem share).
    pub fn lock_path(out: &Path) -> PathBuf {
        transcripts_dir(out).join(".lock")
    }

    /// What the run did so far.
    pub fn outcome(&self) -> &BenchOutcome {
        &self.outcome
    }

    /// What the run did; `interrupted` when it was stopped from outside.
    pub fn finish(mut self, interrupted: bool) -> BenchOutcome {
        self.outcome.interrupted = interrupted;
        self.outcome
    }
}

/// Refuses a results file that exists and is no regular file (a device, a pipe, a
/// folder), before anything is made beside it: the lock's folder would otherwise be made
/// next to `/dev/zero`, say, for a run that cannot start.
fn refuse_other_than_a_file(out: &Path) -> Result<(), Error> {
    match std::fs::metadata(out) {
        Ok(meta) if !meta.is_file() => Err(Error::Io {
            file: out.display().to_string(),
            message: "not a regular file (a device, a pipe, a folder?): a results file must \
                      be one"
                .into(),
        }),
        _ => Ok(()),
    }
}

/// Locks the run's lock file of `out` ([`Ledger::lock_path`]) and writes this process's
/// id into it; when another run holds it, an error names that run's process.
fn take_lock(out: &Path) -> Result<File, Error> {
    let path = Ledger::lock_path(out);
    let io = |e: std::io::Error| Error::io(&path, &e);
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    let mut file = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(io)?;
    if !lock::try_exclusive(&file).map_err(io)? {
        // A process id is a few digits: read no more than that could be, whatever the
        // file has become (a link to a device, say).
        let mut holder = String::new();
        let _ = (&mut file).take(64).read_to_string(&mut holder);
        let holder = holder.trim();
        let holder = if holder.is_empty() || holder.len() > 20 {
            "another process".to_owned()
        } else {
            format!("process {holder}")
        };
        return Err(Error::Io {
            file: out.display().to_string(),
            message: format!(
                "another benchmark run is using it ({holder} holds {}): wait for it to end, \
                 or give this run another --out",
                path.display()
            ),
        });
    }
    file.set_len(0)
        .and_then(|()| writeln!(file, "{}", std::process::id()))
        .and_then(|()| file.flush())
        .map_err(io)?;
    Ok(file)
}

/// Why the lines already in a results file cannot be resumed by a run whose methods have
/// the settings `now` (by method name): each setting that differs, once, with its value
/// in the file and now. Empty when every line has this run's settings (a line of a
/// method this run does not have is held to the run-wide settings alone).
pub fn mismatch(lines: &[ResultLine], now: &BTreeMap<String, RunSettings>) -> Vec<Difference> {
    let Some(any) = now.values().next() else {
        return Vec::new();
    };
    let mut found: Vec<Difference> = Vec::new();
    let mut seen: Vec<(&str, &RunSettings)> = Vec::new();
    let add = |d: Difference, found: &mut Vec<Difference>| {
        if !found
            .iter()
            .any(|f| f.setting == d.setting && f.method == d.method)
        {
            found.push(d);
        }
    };
    for line in lines {
        let Some(settings) = &line.settings else {
            let d = Difference {
                setting: Setting::Unrecorded,
                method: None,
                file: "not recorded (the file was written by a version that did not keep them)"
                    .to_owned(),
                now: "recorded".to_owned(),
            };
            add(d, &mut found);
            continue;
        };
        // A file holds few distinct settings: compare each once.
        if seen
            .iter()
            .any(|(m, s)| *m == line.method && *s == settings)
        {
            continue;
        }
        seen.push((&line.method, settings));
        for d in settings.differences(any) {
            add(d, &mut found);
        }
        if let Some(mine) = now.get(&line.method)
            && mine.method != settings.method
        {
            let d = Difference {
                setting: Setting::Method,
                method: Some(line.method.clone()),
                file: method_text(&settings.method),
                now: method_text(&mine.method),
            };
            add(d, &mut found);
        }
    }
    found.sort_by(|a, b| (a.setting, &a.method).cmp(&(b.setting, &b.method)));
    found
}
