//! The benchmark harness: methods x tasks x seeds, run concurrently, one JSON line per
//! finished episode appended to a results file (flushed as each ends), resumable after a
//! crash or Ctrl-C. [`crate::report`] turns the lines into the paper's tables.

use std::collections::{HashMap, HashSet};
use std::fs::{File, OpenOptions};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use coherent_core::planner::{self, Limits};
use coherent_core::{SymbolicEnv, Task};
use serde::{Deserialize, Serialize};
use tokio::sync::{OnceCell, Semaphore};
use tokio::task::JoinSet;

use crate::builtin::{BuiltinBackend, ErrorRates};
use crate::episode::{self, Budget, Method, Settings};
use crate::llm::{Backend, BackendInfo};
use crate::openai::OpenAiClient;
use crate::pefa::Cancel;
use crate::replay::ReplayBackend;
use crate::transcript::{self, Status};

/// The paper's 40-task subset (SEMANTICS.md section 6): 8 tasks per scene, by the scene's
/// file name and the task id.
pub const PAPER40: [(&str, [i64; 8]); 5] = [
    ("env0", [2, 4, 9, 10, 11, 15, 16, 20]),
    ("env1", [1, 3, 7, 8, 10, 11, 16, 20]),
    ("env2", [3, 5, 6, 7, 10, 11, 16, 17]),
    ("env3", [2, 4, 6, 7, 10, 16, 17, 19]),
    ("env4", [0, 1, 7, 10, 12, 17, 18, 19]),
];

/// Which tasks of those read to run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Subset {
    /// Every well-formed task.
    All,
    /// [`PAPER40`].
    Paper40,
    /// `scene task_id` pairs from a file, one per line, `#` starting a comment.
    Listed(Vec<(String, i64)>),
}

impl Subset {
    /// The subset a name stands for: `all`, `paper40` (the paper's subset of its released
    /// tasks) or `native40` (the 40-task subset of the project's own benchmark, listed by
    /// `coherent_core::benchmark::subset40`); None for any other name.
    pub fn named(name: &str) -> Option<Subset> {
        match name {
            "all" => Some(Subset::All),
            "paper40" => Some(Subset::Paper40),
            "native40" => Some(Subset::Listed(coherent_core::benchmark::subset40())),
            _ => None,
        }
    }

    /// Reads a subset file; errors name the file and the line.
    pub fn read_file(path: &Path) -> Result<Subset, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut pairs = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let at = || format!("{}: line {}", path.display(), i + 1);
            let mut words = line.split_whitespace();
            let (Some(scene), Some(id), None) = (words.next(), words.next(), words.next()) else {
                return Err(format!(
                    "{}: expected `scene task_id`, found {line:?}",
                    at()
                ));
            };
            let id: i64 = id
                .parse()
                .map_err(|_| format!("{}: task id {id:?} is not an integer", at()))?;
            pairs.push((scene.to_owned(), id));
        }
        Ok(Subset::Listed(pairs))
    }

    fn wanted(&self) -> Option<Vec<(String, i64)>> {
        match self {
            Subset::All => None,
            Subset::Paper40 => Some(
                PAPER40
                    .iter()
                    .flat_map(|(scene, ids)| ids.iter().map(|id| ((*scene).to_owned(), *id)))
                    .collect(),
            ),
            Subset::Listed(pairs) => Some(pairs.clone()),
        }
    }
}

/// The tasks a subset picks, and the (scene, task_id) pairs it names that were not read.
#[derive(Debug)]
pub struct Selection {
    pub tasks: Vec<Arc<Task>>,
    pub missing: Vec<(String, i64)>,
}

/// Picks `subset` from `tasks`, in the subset's order (the read order for `All`). Two
/// tasks with the same scene and id are an error: results are keyed by them.
pub fn select(tasks: Vec<Task>, subset: &Subset) -> Result<Selection, String> {
    let mut by_key: HashMap<(String, i64), Arc<Task>> = HashMap::new();
    let mut order = Vec::new();
    for t in tasks {
        let key = (t.meta.scene.clone(), t.meta.task_id);
        if by_key.contains_key(&key) {
            return Err(format!(
                "two tasks with scene {:?} and task_id {}: results could not tell them apart",
                key.0, key.1
            ));
        }
        order.push(key.clone());
        by_key.insert(key, Arc::new(t));
    }
    let Some(wanted) = subset.wanted() else {
        let tasks = order.iter().map(|k| Arc::clone(&by_key[k])).collect();
        return Ok(Selection {
            tasks,
            missing: Vec::new(),
        });
    };
    let mut seen = HashSet::new();
    let mut selection = Selection {
        tasks: Vec::new(),
        missing: Vec::new(),
    };
    for key in wanted {
        if !seen.insert(key.clone()) {
            continue;
        }
        match by_key.get(&key) {
            Some(t) => selection.tasks.push(Arc::clone(t)),
            None => selection.missing.push(key),
        }
    }
    Ok(selection)
}

/// Which backend answers the model-using methods.
#[derive(Clone, Debug)]
pub enum BackendChoice {
    /// The optimal planner in every role.
    Builtin,
    /// The planner with seeded mistakes; each episode gets its own seed.
    Simulated(ErrorRates),
    /// One client shared by every episode (its own concurrency limit holds across them).
    OpenAi(Arc<OpenAiClient>),
    /// The transcripts of an earlier run: each episode answers from the recording with
    /// its method, task and seed, with the recorded settings, and must come out the same.
    Replay(Arc<Recorded>),
}

/// An earlier run's finished episodes, by key: the transcripts a replay answers from.
#[derive(Debug)]
pub struct Recorded {
    /// The earlier results file.
    pub results: PathBuf,
    pub transcripts: HashMap<EpisodeKey, PathBuf>,
    /// The backend of the recordings (the first one's, when they differ).
    pub backend: BackendInfo,
}

impl Recorded {
    /// The final episodes of the results file `results`.
    pub fn read(results: &Path) -> Result<Recorded, String> {
        let file = read_results(results)?;
        let mut backend = None;
        let mut transcripts = HashMap::new();
        for line in file.lines.iter().filter(|l| l.is_final()) {
            if line.uses_model {
                backend.get_or_insert_with(|| line.backend.clone());
            }
            transcripts.insert(line.key(), PathBuf::from(&line.transcript));
        }
        if transcripts.is_empty() {
            return Err(format!(
                "{}: no finished episodes to replay",
                results.display()
            ));
        }
        Ok(Recorded {
            results: results.to_owned(),
            transcripts,
            backend: backend.unwrap_or(BackendInfo {
                kind: "none".into(),
                model: String::new(),
                base_url: None,
            }),
        })
    }
}

impl BackendChoice {
    pub fn info(&self) -> BackendInfo {
        match self {
            BackendChoice::Builtin => BuiltinBackend::new(Limits::default()).info(),
            BackendChoice::Simulated(rates) => {
                BuiltinBackend::simulated(Limits::default(), *rates, 0).info()
            }
            BackendChoice::OpenAi(client) => client.info(),
            BackendChoice::Replay(recorded) => BackendInfo {
                kind: "replay".into(),
                model: recorded.backend.model.clone(),
                base_url: None,
            },
        }
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    pub methods: Vec<Method>,
    /// Seed indices `0..seeds`.
    pub seeds: u32,
    /// Episodes at once.
    pub concurrency: usize,
    pub backend: BackendChoice,
    /// Rounds of history (see [`Settings::history`]).
    pub history: usize,
    /// Recorded in the episodes' settings for an HTTP backend.
    pub temperature: Option<f32>,
    /// Most states one planner search may visit.
    pub max_states: usize,
    /// The results file; transcripts go to [`transcripts_dir`] of it.
    pub out: PathBuf,
}

/// One finished episode: a line of the results file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResultLine {
    pub method: String,
    pub scene: String,
    pub task_id: i64,
    /// `mono`, `dual` or `trio`; null when the planner finds no plan.
    pub task_type: Option<String>,
    /// The seed index (0-based).
    pub seed: u32,
    /// The seed the episode actually ran with, derived from the index, method and task.
    #[serde(default)]
    pub episode_seed: u64,
    pub success: bool,
    pub status: Status,
    pub steps: u32,
    pub gt_steps: Option<u32>,
    #[serde(default)]
    pub optimal_steps: Option<u32>,
    pub max_steps: u32,
    pub llm_calls: u32,
    pub prompt_tokens: u64,
    pub completion_tokens: u64,
    pub wall_ms: f64,
    /// The run's backend (even for a method that asks no model; see `uses_model`).
    pub backend: BackendInfo,
    #[serde(default = "yes")]
    pub uses_model: bool,
    #[serde(default)]
    pub error: Option<String>,
    pub transcript: String,
}

fn yes() -> bool {
    true
}

impl ResultLine {
    /// Whether the episode ended in a way that counts: success or budget spent.
    pub fn is_final(&self) -> bool {
        matches!(self.status, Status::Success | Status::Failure)
    }

    pub fn key(&self) -> EpisodeKey {
        EpisodeKey {
            method: self.method.clone(),
            scene: self.scene.clone(),
            task_id: self.task_id,
            seed: self.seed,
        }
    }
}

/// What identifies an episode across runs.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EpisodeKey {
    pub method: String,
    pub scene: String,
    pub task_id: i64,
    pub seed: u32,
}

/// A results file as read.
#[derive(Debug, Default)]
pub struct ResultsFile {
    pub lines: Vec<ResultLine>,
    /// Bytes of a last line cut off mid-write (0 when none); [`repair`] drops them.
    pub truncated_bytes: u64,
    /// Length of the well-formed part.
    pub good_len: u64,
}

/// Reads a results file. A last line without its newline that does not parse is a write
/// cut short (reported in `truncated_bytes`); any other bad line is an error naming the
/// file, the line and the JSON path.
pub fn read_results(path: &Path) -> Result<ResultsFile, String> {
    let mut text = Vec::new();
    File::open(path)
        .and_then(|mut f| f.read_to_end(&mut text))
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let mut out = ResultsFile::default();
    let mut start = 0;
    let mut number = 0;
    while start < text.len() {
        number += 1;
        let (end, complete) = match text[start..].iter().position(|&b| b == b'\n') {
            Some(i) => (start + i + 1, true),
            None => (text.len(), false),
        };
        let raw = &text[start..end];
        let parsed = std::str::from_utf8(raw)
            .map_err(|e| e.to_string())
            .and_then(|s| {
                if s.trim().is_empty() {
                    return Ok(None);
                }
                let de = &mut serde_json::Deserializer::from_str(s);
                parse_line(de).map(Some)
            });
        match parsed {
            Ok(line) => {
                out.lines.extend(line);
                // A complete record missing only its newline is kept; repair adds it.
                out.good_len = end as u64;
            }
            Err(_) if !complete => {
                out.truncated_bytes = (end - start) as u64;
            }
            Err(e) => {
                return Err(format!("{}: line {number}: {e}", path.display()));
            }
        }
        start = end;
    }
    Ok(out)
}

fn parse_line(
    de: &mut serde_json::Deserializer<serde_json::de::StrRead<'_>>,
) -> Result<ResultLine, String> {
    // A key twice in one object is refused: serde_json alone would keep the last one.
    let value = coherent_core::json::value(&mut *de).map_err(|e| format!("invalid JSON: {e}"))?;
    de.end().map_err(|e| format!("invalid JSON: {e}"))?;
    serde_json::from_value::<ResultLine>(value.clone()).map_err(|e| {
        // Name the field: serde_json's messages say what, not where.
        let field = missing_or_bad_field(&value);
        format!("{e}{field}")
    })
}

/// ` (at $.field)` for the first field of a results line that is absent or has the
/// wrong JSON type, to point at the culprit.
fn missing_or_bad_field(value: &serde_json::Value) -> String {
    use serde_json::Value as V;
    let Some(map) = value.as_object() else {
        return " (at $: expected an object)".into();
    };
    type Check = fn(&V) -> bool;
    let expect: [(&str, Check); 14] = [
        ("method", V::is_string),
        ("scene", V::is_string),
        ("task_id", V::is_i64),
        ("seed", V::is_u64),
        ("success", V::is_boolean),
        ("status", V::is_string),
        ("steps", V::is_u64),
        ("max_steps", V::is_u64),
        ("llm_calls", V::is_u64),
        ("prompt_tokens", V::is_u64),
        ("completion_tokens", V::is_u64),
        ("wall_ms", V::is_number),
        ("backend", V::is_object),
        ("transcript", V::is_string),
    ];
    for (name, ok) in expect {
        match map.get(name) {
            None => return format!(" (at $.{name}: missing)"),
            Some(v) if !ok(v) => return format!(" (at $.{name}: found {v})"),
            Some(_) => {}
        }
    }
    String::new()
}

/// Cuts a results file back to its well-formed part and ends it with a newline, so
/// that appended lines start on their own line.
pub fn repair(path: &Path, file: &ResultsFile) -> Result<(), String> {
    let io = |e: io::Error| format!("{}: {e}", path.display());
    let mut f = OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .map_err(io)?;
    f.set_len(file.good_len).map_err(io)?;
    if file.good_len > 0 {
        f.seek(SeekFrom::Start(file.good_len - 1)).map_err(io)?;
        let mut last = [0u8];
        f.read_exact(&mut last).map_err(io)?;
        if last[0] != b'\n' {
            f.seek(SeekFrom::End(0)).map_err(io)?;
            f.write_all(b"\n").map_err(io)?;
        }
    }
    f.flush().map_err(io)
}

/// `results.jsonl` -> `results.transcripts/`, next to it.
pub fn transcripts_dir(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map_or_else(|| "results".into(), |s| s.to_string_lossy().into_owned());
    out.with_file_name(format!("{stem}.transcripts"))
}

/// The seed of one episode: a hash of the seed index, the method and the task, so that
/// results do not depend on the order episodes run in (FNV-1a, then SplitMix64's mixer).
pub fn episode_seed(seed: u32, method: &str, scene: &str, task_id: i64) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        // A separator, so that ("ab", "c") and ("a", "bc") differ.
        h ^= 0xff;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    };
    eat(&seed.to_le_bytes());
    eat(method.as_bytes());
    eat(scene.as_bytes());
    eat(&task_id.to_le_bytes());
    let mut z = h.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// What the planner says about a task, once per task.
#[derive(Clone, Debug)]
struct TaskInfo {
    task_type: Option<String>,
    optimal: Option<u32>,
    budget: Result<Budget, String>,
}

/// One episode to run.
#[derive(Clone, Debug)]
struct Job {
    method: Method,
    task: Arc<Task>,
    info: Arc<OnceCell<TaskInfo>>,
    seed: u32,
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
    /// Episodes this run did not finish for good: interrupted, backend errors, or never
    /// started because of Ctrl-C.
    pub unfinished: usize,
    /// Whether Ctrl-C (the `cancel` handle) stopped the run.
    pub interrupted: bool,
    /// Tasks that could not be run and why (no ground truth and no plan to size a budget).
    pub skipped_tasks: Vec<String>,
    /// Lines dropped from a cut-off last line.
    pub repaired_bytes: u64,
}

/// What the harness reports as it goes.
#[derive(Debug)]
pub enum Event<'a> {
    /// Before the first episode: how many to run, how many were already done.
    Start { to_run: usize, skipped: usize },
    /// An episode ended and its line is on disk.
    Finished(&'a ResultLine),
}

/// Runs every method on every task for every seed, `config.concurrency` at once, skipping
/// those already finished in `config.out`, appending one flushed line per episode.
/// `cancel` stops the run: episodes in flight end as interrupted (and are written so),
/// those not started are not started.
pub async fn run(
    tasks: &[Arc<Task>],
    config: &BenchConfig,
    cancel: &Cancel,
    progress: &mut (dyn FnMut(Event<'_>) + Send),
) -> Result<BenchOutcome, String> {
    let out = &config.out;
    let mut outcome = BenchOutcome::default();
    let mut done: HashSet<EpisodeKey> = HashSet::new();
    if out.exists() {
        let file = read_results(out)?;
        if file.truncated_bytes > 0 {
            outcome.repaired_bytes = file.truncated_bytes;
        }
        repair(out, &file)?;
        done.extend(
            file.lines
                .iter()
                .filter(|l| l.is_final())
                .map(ResultLine::key),
        );
    } else if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let mut file = OpenOptions::new()
        .create(true)
        .append(true)
        .open(out)
        .map_err(|e| format!("{}: {e}", out.display()))?;

    let mut jobs = Vec::new();
    for task in tasks {
        let info = Arc::new(OnceCell::new());
        for seed in 0..config.seeds {
            for &method in &config.methods {
                outcome.total += 1;
                let key = EpisodeKey {
                    method: method.name().to_owned(),
                    scene: task.meta.scene.clone(),
                    task_id: task.meta.task_id,
                    seed,
                };
                if done.contains(&key) {
                    outcome.skipped += 1;
                    continue;
                }
                jobs.push(Job {
                    method,
                    task: Arc::clone(task),
                    info: Arc::clone(&info),
                    seed,
                });
            }
        }
    }
    progress(Event::Start {
        to_run: jobs.len(),
        skipped: outcome.skipped,
    });

    let shared = Arc::new(Shared {
        backend: config.backend.clone(),
        backend_info: config.backend.info(),
        history: config.history,
        temperature: config.temperature,
        max_states: config.max_states,
        transcripts: transcripts_dir(out),
        cancel: cancel.clone(),
        permits: Semaphore::new(config.concurrency.max(1)),
    });
    let mut set = JoinSet::new();
    for job in jobs {
        let shared = Arc::clone(&shared);
        set.spawn(async move { run_job(job, &shared).await });
    }
    let mut first_error = None;
    while let Some(joined) = set.join_next().await {
        let result = joined.map_err(|e| format!("an episode panicked: {e}"));
        match result.and_then(|r| r) {
            Ok(JobResult::Line(line)) => {
                let mut text = serde_json::to_string(&line)
                    .map_err(|e| format!("cannot encode a results line: {e}"))?;
                text.push('\n');
                if let Err(e) = file.write_all(text.as_bytes()).and_then(|()| file.flush()) {
                    first_error.get_or_insert(format!("{}: {e}", out.display()));
                    cancel.cancel();
                    continue;
                }
                outcome.written += 1;
                if !line.is_final() {
                    outcome.unfinished += 1;
                }
                progress(Event::Finished(&line));
            }
            Ok(JobResult::NotStarted) => outcome.unfinished += 1,
            Ok(JobResult::TaskSkipped(why)) => {
                outcome.unfinished += 1;
                if !outcome.skipped_tasks.contains(&why) {
                    outcome.skipped_tasks.push(why);
                }
            }
            Err(e) => {
                // A transcript that cannot be written would lose data: stop everything.
                first_error.get_or_insert(e);
                cancel.cancel();
            }
        }
    }
    outcome.interrupted = cancel.is_cancelled() && first_error.is_none();
    match first_error {
        Some(e) => Err(e),
        None => Ok(outcome),
    }
}

#[derive(Debug)]
struct Shared {
    backend: BackendChoice,
    backend_info: BackendInfo,
    history: usize,
    temperature: Option<f32>,
    max_states: usize,
    transcripts: PathBuf,
    cancel: Cancel,
    permits: Semaphore,
}

enum JobResult {
    Line(Box<ResultLine>),
    NotStarted,
    TaskSkipped(String),
}

async fn run_job(job: Job, shared: &Shared) -> Result<JobResult, String> {
    let permit = tokio::select! {
        p = shared.permits.acquire() => p.map_err(|e| e.to_string())?,
        () = shared.cancel.cancelled() => return Ok(JobResult::NotStarted),
    };
    if shared.cancel.is_cancelled() {
        return Ok(JobResult::NotStarted);
    }
    let limits = Limits {
        cancel: Some(shared.cancel.flag()),
        ..Limits::max_states(shared.max_states)
    };
    let task = &job.task;
    let info = job
        .info
        .get_or_try_init(|| async {
            let (task, limits) = (Arc::clone(task), limits.clone());
            tokio::task::spawn_blocking(move || task_info(&task, &limits))
                .await
                .map_err(|e| format!("the planner failed: {e}"))
        })
        .await?
        .clone();
    let name = format!("{} task {}", task.meta.scene, task.meta.task_id);
    let budget = match info.budget {
        Ok(b) => b,
        Err(why) => return Ok(JobResult::TaskSkipped(format!("{name}: {why}"))),
    };
    if shared.cancel.is_cancelled() {
        return Ok(JobResult::NotStarted);
    }
    let method = job.method;
    let seed = episode_seed(job.seed, method.name(), &task.meta.scene, task.meta.task_id);
    let mut settings = Settings {
        history: shared.history,
        temperature: shared.temperature,
        seed: Some(seed),
        ..Settings::new(method)
    };
    let mut budget = budget;
    let mut recording = None;
    let backend: Arc<dyn Backend> = match &shared.backend {
        BackendChoice::Builtin => Arc::new(BuiltinBackend::new(limits.clone())),
        BackendChoice::Simulated(rates) => {
            Arc::new(BuiltinBackend::simulated(limits.clone(), *rates, seed))
        }
        BackendChoice::OpenAi(client) => Arc::clone(client) as Arc<dyn Backend>,
        BackendChoice::Replay(recorded) => {
            let key = EpisodeKey {
                method: method.name().to_owned(),
                scene: task.meta.scene.clone(),
                task_id: task.meta.task_id,
                seed: job.seed,
            };
            let Some(path) = recorded.transcripts.get(&key) else {
                return Ok(JobResult::TaskSkipped(format!(
                    "{name}: {} seed {} has no finished episode in {}",
                    method.name(),
                    job.seed,
                    recorded.results.display()
                )));
            };
            let t = transcript::read(path)?;
            (settings, budget) = episode::recorded_settings(&t)?;
            let backend = Arc::new(ReplayBackend::new(&t));
            recording = Some(t);
            backend
        }
    };
    let dir = shared.transcripts.join(format!("seed{}", job.seed));
    let path = episode::transcript_path(&dir, task, method);
    // An episode's future holds `&dyn Environment` across awaits, so it is not `Send`:
    // each runs to completion on a blocking-pool thread of the same multi-thread runtime
    // (its model calls, timers and planner searches still use the runtime).
    let handle = tokio::runtime::Handle::current();
    let episode = {
        let (task, path, cancel) = (Arc::clone(task), path.clone(), shared.cancel.clone());
        tokio::task::spawn_blocking(move || {
            handle.block_on(async move {
                let mut env = SymbolicEnv::new(Arc::clone(&task));
                episode::run(
                    &task,
                    &mut env,
                    backend.as_ref(),
                    &settings,
                    budget,
                    &path,
                    &cancel,
                    &mut |_| {},
                )
                .await
            })
        })
        .await
        .map_err(|e| format!("an episode panicked: {e}"))??
    };
    drop(permit);
    // A replay that comes out differently says so in its line's error.
    let mismatch = recording
        .as_ref()
        .and_then(|t| episode::check_replay(t, &episode).err())
        .map(|why| format!("replay mismatch: {why}"));
    let s = episode.summary;
    Ok(JobResult::Line(Box::new(ResultLine {
        method: method.name().to_owned(),
        scene: task.meta.scene.clone(),
        task_id: task.meta.task_id,
        task_type: info.task_type,
        seed: job.seed,
        episode_seed: seed,
        success: s.success,
        status: s.status,
        steps: s.steps,
        gt_steps: s.gt_steps,
        optimal_steps: info.optimal,
        max_steps: s.max_steps,
        llm_calls: s.llm_calls,
        prompt_tokens: s.prompt_tokens,
        completion_tokens: s.completion_tokens,
        wall_ms: (s.wall_ms * 1e3).round() / 1e3,
        backend: shared.backend_info.clone(),
        uses_model: method.uses_model(),
        error: mismatch.or(s.error),
        transcript: path.display().to_string(),
    })))
}

fn task_info(task: &Task, limits: &Limits) -> TaskInfo {
    let analysis = planner::analyse(task, limits);
    let optimal = analysis.plan.as_ref().map(|p| p.len() as u32);
    let budget = match (task.meta.twice_ground_truth(), optimal) {
        (Some(budget), _) => budget.map(Budget::TwiceGroundTruth),
        (None, Some(n)) => Ok(Budget::TwiceOptimum(n.max(1).saturating_mul(2))),
        (None, None) => Err(format!(
            "no ground truth, and the planner finds no plan to size a budget from ({})",
            analysis.reason.as_deref().unwrap_or("search stopped")
        )),
    };
    TaskInfo {
        task_type: analysis.task_type.map(|t| t.name().to_owned()),
        optimal,
        budget,
    }
}

/// Progress lines: on a terminal one line redrawn in place, otherwise one line per
/// finished episode.
#[derive(Debug)]
pub struct Progress {
    terminal: bool,
    start: Instant,
    to_run: usize,
    done: usize,
    successes: usize,
    counted: usize,
}

impl Progress {
    pub fn new(terminal: bool) -> Progress {
        Progress {
            terminal,
            start: Instant::now(),
            to_run: 0,
            done: 0,
            successes: 0,
            counted: 0,
        }
    }

    /// The text to print for `event` (for a terminal, with a carriage return and no
    /// newline), or `None`.
    pub fn line(&mut self, event: &Event<'_>) -> Option<String> {
        match event {
            Event::Start { to_run, skipped } => {
                self.to_run = *to_run;
                self.start = Instant::now();
                Some(format!(
                    "{to_run} episodes to run, {skipped} already finished in the results file\n"
                ))
            }
            Event::Finished(line) => {
                self.done += 1;
                if line.is_final() {
                    self.counted += 1;
                    self.successes += usize::from(line.success);
                }
                let sr = if self.counted == 0 {
                    "-".to_owned()
                } else {
                    format!("{:.3}", self.successes as f64 / self.counted as f64)
                };
                let elapsed = self.start.elapsed();
                let left = self.to_run.saturating_sub(self.done);
                let eta = elapsed.mul_f64(left as f64 / self.done as f64);
                let width = self.to_run.to_string().len();
                let head = format!(
                    "[{:>width$}/{}] SR {sr} | ETA {}",
                    self.done,
                    self.to_run,
                    clock(eta)
                );
                Some(if self.terminal {
                    format!(
                        "\r\x1b[2K{head} | last: {} {} task {} seed {} {}",
                        line.method,
                        line.scene,
                        line.task_id,
                        line.seed,
                        status_word(line.status)
                    )
                } else {
                    format!(
                        "{head} | {} {} task {} seed {}: {} in {} steps (GT {}), {} LLM calls, {:.1} s\n",
                        line.method,
                        line.scene,
                        line.task_id,
                        line.seed,
                        status_word(line.status),
                        line.steps,
                        line.gt_steps.map_or("-".to_owned(), |g| g.to_string()),
                        line.llm_calls,
                        line.wall_ms / 1e3
                    )
                })
            }
        }
    }
}

fn status_word(s: Status) -> &'static str {
    match s {
        Status::Success => "success",
        Status::Failure => "failure",
        Status::BackendError => "backend error",
        Status::Interrupted => "interrupted",
    }
}

/// `1h02m03s`, `2m03s`, `3s`.
fn clock(d: Duration) -> String {
    let s = d.as_secs();
    match (s / 3600, s / 60 % 60, s % 60) {
        (0, 0, sec) => format!("{sec}s"),
        (0, m, sec) => format!("{m}m{sec:02}s"),
        (h, m, sec) => format!("{h}h{m:02}m{sec:02}s"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_differ_by_every_part_and_are_stable() {
        let a = episode_seed(0, "pefa", "env0", 2);
        assert_eq!(a, episode_seed(0, "pefa", "env0", 2));
        assert_ne!(a, episode_seed(1, "pefa", "env0", 2));
        assert_ne!(a, episode_seed(0, "mcts", "env0", 2));
        assert_ne!(a, episode_seed(0, "pefa", "env1", 2));
        assert_ne!(a, episode_seed(0, "pefa", "env0", 3));
    }

    #[test]
    fn clock_text() {
        assert_eq!(clock(Duration::from_secs(3)), "3s");
        assert_eq!(clock(Duration::from_secs(123)), "2m03s");
        assert_eq!(clock(Duration::from_secs(3723)), "1h02m03s");
    }

    #[test]
    fn transcripts_sit_next_to_the_results() {
        assert_eq!(
            transcripts_dir(Path::new("out/results.jsonl")),
            Path::new("out/results.transcripts")
        );
    }
}
