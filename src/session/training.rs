//! Training data for the methods' models (`coherent export sft`, `coherent.training`;
//! `docs/training.md`): episodes of one method on the tasks given, one with the
//! built-in planner's answers and others with the simulated backend's mistakes, every
//! question labelled with the optimal planner's answer from the state it was asked in
//! (`coherent_agents::training`), written as chat examples in three splits by scene,
//! with a datasheet.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::bench::{Subset, select};
use coherent_agents::digest::fnv128;
use coherent_agents::prompts::fill::robot_label;
use coherent_agents::training::{self, Lesson, Teacher};
use coherent_agents::{Builtin, BuiltinBackend, Cancel, ErrorRates, Settings};
use coherent_core::files::{self, Limit, MIB};
use coherent_core::planner::Limits;
use coherent_core::{Execution, Task};
use coherent_generate::Split;
use serde_json::{Value, json};

use crate::session::error::Error;
use crate::session::prompts::PromptSource;
use crate::session::tasks;

/// What a front end asks for.
#[derive(Clone, Debug)]
pub struct SftRequest {
    /// Task files or folders (a generated set's folder brings its splits).
    pub files: Vec<PathBuf>,
    pub method: Builtin,
    /// The executions to play (the method's, both by default).
    pub executions: Vec<Execution>,
    /// The roles to keep; empty: every role of the method.
    pub roles: Vec<String>,
    /// The simulated backend's mistakes in the episodes that leave the optimal plans.
    pub errors: ErrorRates,
    /// Episodes with mistakes per task and execution (seeds 1 to `seeds`), besides the
    /// one with the planner's answers.
    pub seeds: u64,
    /// The history window of the prompts.
    pub history: usize,
    pub prompts: PromptSource,
    /// Shares of the scenes of tasks from no generated set in train, validation and
    /// test.
    pub split: [f64; 3],
    /// Keep the evaluation subsets' tasks (paper40, native40), left out by default.
    pub include_eval: bool,
    /// Most states one search may visit.
    pub max_states: usize,
    pub out: PathBuf,
    /// The command that asks, for the datasheet.
    pub command: String,
}

impl SftRequest {
    /// The defaults: both executions (where the method runs them), every role, two
    /// episodes with the simulated backend's mistakes at `all=0.1` per task and
    /// execution, the history window, the built-in prompts, scenes split 0.8 / 0.1 /
    /// 0.1, the evaluation subsets left out.
    pub fn new(files: Vec<PathBuf>, method: Builtin, out: PathBuf) -> SftRequest {
        SftRequest {
            files,
            method,
            executions: training::executions(method),
            roles: Vec::new(),
            errors: ErrorRates::all(0.1),
            seeds: 2,
            history: coherent_agents::HISTORY_WINDOW,
            prompts: PromptSource::default(),
            split: [0.8, 0.1, 0.1],
            include_eval: false,
            max_states: Limits::DEFAULT_MAX_STATES,
            out,
            command: String::new(),
        }
    }
}

/// The shares of `--split TRAIN,VAL,TEST` (`0.8,0.1,0.1`); an error names the flag.
pub fn split_shares(text: &str) -> Result<[f64; 3], Error> {
    coherent_generate::request::parse_split(text).map_err(Error::Knob)
}

/// What was written.
#[derive(Clone, Debug, Default)]
pub struct Written {
    /// Examples by split, in the order train, validation, test.
    pub examples: BTreeMap<Split, usize>,
    /// Examples by role.
    pub by_role: BTreeMap<String, usize>,
    /// The files: a JSONL file per split, the datasheet.
    pub files: Vec<PathBuf>,
    /// Tasks played, tasks of the evaluation subsets left out, and why each malformed
    /// task was.
    pub tasks: usize,
    pub left_out_eval: usize,
    pub malformed: Vec<String>,
    /// Questions left out: no optimal answer from there, the same prompt as an earlier
    /// example, the same prompt with another answer.
    pub no_answer: usize,
    pub duplicates: usize,
    pub conflicts: usize,
    /// Answers the method's parser could not read (a fault of the planner's answers:
    /// none is expected).
    pub unreadable: usize,
}

/// The most a generated set's manifest may hold.
const MANIFEST_LIMIT: Limit = Limit {
    bytes: 256 * MIB,
    what: "a generated set's manifest",
    raise: None,
};

/// The splits a generated set's manifest gives its tasks, when `path` is the folder of
/// one.
fn manifest_splits(path: &Path) -> Result<HashMap<(String, i64), Split>, Error> {
    let manifest = path.join("manifest.jsonl");
    let mut out = HashMap::new();
    if !path.is_dir() || !manifest.is_file() {
        return Ok(out);
    }
    let text = String::from_utf8_lossy(&files::read(&manifest, &MANIFEST_LIMIT)?).into_owned();
    for (i, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let bad = |what: &str| Error::File {
            file: manifest.display().to_string(),
            line: Some(i + 1),
            message: what.to_owned(),
        };
        let v: Value = serde_json::from_str(line).map_err(|e| bad(&e.to_string()))?;
        let scene = v["scene"].as_str().ok_or_else(|| bad("no \"scene\""))?;
        let id = v["task_id"].as_i64().ok_or_else(|| bad("no \"task_id\""))?;
        let split = Split::ALL
            .into_iter()
            .find(|s| Some(s.name()) == v["split"].as_str())
            .ok_or_else(|| bad("\"split\" is none of train, validation, test"))?;
        out.insert((scene.to_owned(), id), split);
    }
    Ok(out)
}

/// The well-formed tasks of `req`, each with its split; the malformed ones are in
/// `written.malformed` (the data says how many were left out), and so is the count of
/// the evaluation subsets' tasks left out.
fn tasks_with_splits(
    req: &SftRequest,
    written: &mut Written,
) -> Result<Vec<(Arc<Task>, Split)>, Error> {
    let mut given: HashMap<(String, i64), Split> = HashMap::new();
    let mut all = Vec::new();
    for path in &req.files {
        given.extend(manifest_splits(path)?);
        for t in tasks::read_tasks(path)? {
            match t {
                Ok(t) => all.push(t),
                Err(e) => written.malformed.push(e.to_string()),
            }
        }
    }
    let eval: HashSet<(String, i64)> = ["paper40", "native40"]
        .iter()
        .filter_map(|name| Subset::named(name).and_then(|s| s.pairs()))
        .flatten()
        .collect();
    let key = |t: &Task| (t.meta.scene.clone(), t.meta.task_id);
    let before = all.len();
    if !req.include_eval {
        all.retain(|t| !eval.contains(&key(t)));
    }
    written.left_out_eval = before - all.len();
    // Two tasks of one scene and id are refused, as a benchmark refuses them.
    let all = select(all, &Subset::All)?.tasks;
    let mut scenes: Vec<String> = all
        .iter()
        .filter(|t| !given.contains_key(&key(t)))
        .map(|t| t.meta.scene.clone())
        .collect();
    scenes.sort();
    scenes.dedup();
    let of_scene: HashMap<String, Split> = scenes
        .iter()
        .cloned()
        .zip(coherent_generate::splits(scenes.len(), req.split, 0))
        .collect();
    let tasks = all
        .into_iter()
        .map(|t| {
            let split = given
                .get(&key(&t))
                .copied()
                .unwrap_or_else(|| of_scene[&t.meta.scene]);
            (t, split)
        })
        .collect();
    Ok(tasks)
}

/// One split's file, written under a temporary name and renamed when whole.
struct SplitFile {
    tmp: PathBuf,
    path: PathBuf,
    out: BufWriter<File>,
}

/// The example files of the three splits.
struct Files(BTreeMap<Split, SplitFile>);

impl Files {
    fn create(dir: &Path) -> Result<Files, Error> {
        fs::create_dir_all(dir).map_err(|e| file_error(dir, &e.to_string()))?;
        let mut files = BTreeMap::new();
        for split in Split::ALL {
            let path = dir.join(format!("{}.jsonl", split.name()));
            let tmp = dir.join(format!(".{}.jsonl.tmp", split.name()));
            let file = File::create(&tmp).map_err(|e| file_error(&tmp, &e.to_string()))?;
            files.insert(
                split,
                SplitFile {
                    tmp,
                    path,
                    out: BufWriter::new(file),
                },
            );
        }
        Ok(Files(files))
    }

    fn write(&mut self, split: Split, line: &Value) -> Result<(), Error> {
        let f = self.0.get_mut(&split).expect("a file per split");
        writeln!(f.out, "{line}").map_err(|e| file_error(&f.tmp, &e.to_string()))
    }

    /// Every file renamed into place: the paths.
    fn finish(self) -> Result<Vec<PathBuf>, Error> {
        let mut paths = Vec::new();
        for (_, f) in self.0 {
            let SplitFile { tmp, path, out } = f;
            out.into_inner()
                .map_err(|e| file_error(&tmp, &e.to_string()))
                .and_then(|file| {
                    file.sync_all()
                        .map_err(|e| file_error(&tmp, &e.to_string()))
                })?;
            fs::rename(&tmp, &path).map_err(|e| file_error(&path, &e.to_string()))?;
            paths.push(path);
        }
        Ok(paths)
    }

    /// Removes the unfinished files (a run stopped or failed).
    fn discard(self) {
        for f in self.0.into_values() {
            let _ = fs::remove_file(&f.tmp);
        }
    }
}

fn file_error(path: &Path, message: &str) -> Error {
    Error::File {
        file: path.display().to_string(),
        line: None,
        message: message.to_owned(),
    }
}

/// The episodes of one task and execution: the planner's, then one per seed with
/// mistakes; each with its name in the data.
fn episodes(req: &SftRequest) -> Vec<(String, Option<u64>)> {
    let mut out = vec![("planner".to_owned(), None)];
    out.extend((1..=req.seeds).map(|seed| (format!("mistakes seed {seed}"), Some(seed))));
    out
}

/// Checks what `req` asks before any episode runs: a method that asks a model, roles of
/// it, executions it runs.
fn check(req: &SftRequest) -> Result<(), Error> {
    let roles = training::roles(req.method);
    if roles.is_empty() {
        return Err(Error::Invalid(format!(
            "{} asks no model, so there is nothing to teach one: choose a method that does \
             (pefa, pefa-no-history, cmrs, dmrs-1d, dmrs-2d, llm-mcts, llm-pddl)",
            req.method.name()
        )));
    }
    if let Some(bad) = req.roles.iter().find(|r| !roles.contains(&r.as_str())) {
        return Err(Error::Invalid(format!(
            "role {bad:?} is not one of {}'s: {}",
            req.method.name(),
            roles.join(", ")
        )));
    }
    if req.executions.is_empty() {
        return Err(Error::Invalid("no execution to play".into()));
    }
    for &e in &req.executions {
        coherent_agents::MethodSpec::Builtin(req.method).check_runs(e)?;
    }
    Ok(())
}

/// Plays the episodes and writes the data into `req.out`: `train.jsonl`,
/// `validation.jsonl`, `test.jsonl` and the datasheet `README.md`. `progress` hears the
/// tasks done and the examples written; `cancel` stops between episodes (nothing is
/// then left in the folder but what was there).
pub fn export(
    req: &SftRequest,
    cancel: &Cancel,
    progress: &mut dyn FnMut(usize, usize, usize),
) -> Result<Written, Error> {
    check(req)?;
    let prompts = req.prompts.clone().read()?;
    let mut written = Written::default();
    let tasks = tasks_with_splits(req, &mut written)?;
    if tasks.is_empty() {
        return Err(Error::Invalid(format!(
            "no tasks to make data from ({} of the evaluation subsets left out, --include-eval \
             keeps them; {} malformed{})",
            written.left_out_eval,
            written.malformed.len(),
            written
                .malformed
                .first()
                .map(|e| format!(": {e}"))
                .unwrap_or_default()
        )));
    }
    let limits = Limits {
        cancel: Some(cancel.flag()),
        ..Limits::max_states(req.max_states)
    };
    let mut files = Files::create(&req.out)?;
    written.tasks = tasks.len();
    let mut book = Book::default();
    let result = (|| {
        for (done, (task, split)) in tasks.iter().enumerate() {
            for &execution in &req.executions {
                for (name, seed) in episodes(req) {
                    if cancel.is_cancelled() {
                        return Err(Error::Interrupted);
                    }
                    let planner = Arc::new(BuiltinBackend::new(limits.clone()));
                    let acting = seed.map(|s| planner.with_errors(req.errors, s));
                    let teacher = Teacher::new(Arc::clone(&planner), acting);
                    let settings = Settings {
                        execution,
                        history: req.history,
                        seed,
                        prompts: prompts.clone(),
                        ..Settings::new(req.method)
                    };
                    let (episode, lessons) = crate::session::block_on(training::episode(
                        task, &settings, &teacher, &limits, cancel,
                    ))??;
                    let steps: Vec<u32> = episode
                        .rounds
                        .iter()
                        .flat_map(|r| r.calls.iter().map(move |_| r.step))
                        .collect();
                    for (i, lesson) in lessons.iter().enumerate() {
                        let Some(mut line) = book.example(
                            req,
                            &prompts,
                            &settings,
                            lesson,
                            *split,
                            &name,
                            &mut written,
                        ) else {
                            continue;
                        };
                        line["step"] = json!(steps.get(i));
                        files.write(*split, &line)?;
                    }
                }
            }
            progress(done + 1, tasks.len(), written.examples.values().sum());
        }
        Ok(())
    })();
    if let Err(e) = result {
        files.discard();
        return Err(e);
    }
    written.files = files.finish()?;
    let sheet = req.out.join("README.md");
    fs::write(&sheet, datasheet(req, &prompts, &tasks, &written))
        .map_err(|e| file_error(&sheet, &e.to_string()))?;
    written.files.push(sheet);
    Ok(written)
}

/// What the examples written so far are: their prompts' hashes (no prompt twice in a
/// split) and answers' hashes.
#[derive(Default)]
struct Book {
    seen: HashMap<(Split, String), String>,
}

impl Book {
    /// The example line of `lesson`, or `None` when it is left out (counted in
    /// `written`): no optimal answer, another role, a prompt written already.
    #[allow(clippy::too_many_arguments)]
    fn example(
        &mut self,
        req: &SftRequest,
        prompts: &coherent_agents::Prompts,
        settings: &Settings,
        lesson: &Lesson,
        split: Split,
        episode: &str,
        written: &mut Written,
    ) -> Option<Value> {
        let role = training::role(req.method, lesson.schema);
        if !req.roles.is_empty() && !req.roles.iter().any(|r| r == role) {
            return None;
        }
        let Ok(answer) = &lesson.answer else {
            written.no_answer += 1;
            return None;
        };
        if training::read_back(req.method, prompts, lesson, answer).is_err() {
            written.unreadable += 1;
            return None;
        }
        let prompt_hash = fnv128(
            lesson
                .messages
                .iter()
                .map(|m| (m.role.as_str(), m.content.as_str())),
        );
        let answer_hash = fnv128([("answer", answer.as_str())]);
        if let Some(earlier) = self.seen.get(&(split, prompt_hash.clone())) {
            if *earlier == answer_hash {
                written.duplicates += 1;
            } else {
                written.conflicts += 1;
            }
            return None;
        }
        self.seen.insert((split, prompt_hash.clone()), answer_hash);
        *written.examples.entry(split).or_default() += 1;
        *written.by_role.entry(role.to_owned()).or_default() += 1;
        let task = &lesson.situation.task;
        Some(json!({
            "prompt": lesson.messages,
            "completion": [{"role": "assistant", "content": answer}],
            "id": prompt_hash,
            "method": req.method.name(),
            "role": role,
            "execution": settings.execution.to_string(),
            "scene": task.meta.scene,
            "task_id": task.meta.task_id,
            "split": split.name(),
            "episode": episode,
            "robot": lesson.robot.map(|r| robot_label(task, r)),
        }))
    }
}

/// The datasheet: what the data is, how it was made, and its counts.
fn datasheet(
    req: &SftRequest,
    prompts: &coherent_agents::Prompts,
    tasks: &[(Arc<Task>, Split)],
    w: &Written,
) -> String {
    let mut s = format!(
        "# Training data: {}, from the optimal planner\n\n\
         Made by coherent {} with\n\n```sh\n{}\n```\n\n",
        req.method.name(),
        coherent_agents::VERSION,
        req.command
    );
    s.push_str(
        "Each line is one question a role of the method asked in an episode (`prompt`, the \
         messages exactly as the method sent them) and the optimal planner's answer from \
         the state it was asked in, in the method's own answer format (`completion`). The \
         episodes: one with the built-in planner's answers (states on an optimal plan), \
         and others with the simulated backend's mistakes (states off it, the answer then \
         the way back). Splits are by scene: no scene is in two. docs/training.md says more.\n\n",
    );
    let execs: Vec<String> = req.executions.iter().map(ToString::to_string).collect();
    let hashes: Vec<String> = req
        .executions
        .iter()
        .map(|&e| format!("{} ({e})", prompts.hash(e)))
        .collect();
    s.push_str(&format!(
        "| setting | value |\n|---|---|\n| method | {} |\n| roles | {} |\n| executions | {} |\n\
         | history window | {} |\n| prompt set | {} |\n| episodes per task and execution | 1 with the planner's answers, {} with mistakes at {} (seeds 1 to {}) |\n\
         | evaluation subsets (paper40, native40) | {} |\n\n",
        req.method.name(),
        if req.roles.is_empty() {
            training::roles(req.method).join(", ")
        } else {
            req.roles.join(", ")
        },
        execs.join(", "),
        req.history,
        hashes.join(", "),
        req.seeds,
        req.errors.label(),
        req.seeds,
        if req.include_eval {
            "kept".to_owned()
        } else {
            format!("left out ({} tasks)", w.left_out_eval)
        }
    ));
    s.push_str("| split | scenes | tasks | examples |\n|---|---|---|---|\n");
    for split in Split::ALL {
        let of: Vec<&Arc<Task>> = tasks
            .iter()
            .filter(|(_, s)| *s == split)
            .map(|(t, _)| t)
            .collect();
        let mut scenes: Vec<&str> = of.iter().map(|t| t.meta.scene.as_str()).collect();
        scenes.sort_unstable();
        scenes.dedup();
        s.push_str(&format!(
            "| {} | {} | {} | {} |\n",
            split.name(),
            scenes.len(),
            of.len(),
            w.examples.get(&split).copied().unwrap_or(0)
        ));
    }
    s.push_str("\n| role | examples |\n|---|---|\n");
    for (role, n) in &w.by_role {
        s.push_str(&format!("| {role} | {n} |\n"));
    }
    if !w.malformed.is_empty() {
        s.push_str(&format!(
            "\n{} malformed tasks were left out (`coherent validate` says why).\n",
            w.malformed.len()
        ));
    }
    s.push_str(&format!(
        "\nLeft out: {} questions with no optimal answer from their state (no plan \
         reaches the goal, or a search stopped at its limit), {} repeats of a prompt \
         already written with the same answer, {} with another answer (the first kept), \
         {} whose answer the method's parser could not read.\n",
        w.no_answer, w.duplicates, w.conflicts, w.unreadable
    ));
    s
}
