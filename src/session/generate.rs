//! Generated task sets (`coherent generate`, `coherent.generate`): a request, the set
//! made by `coherent-generate`, and the folder it is written to: a native task file per
//! task under `<scene>/`, `manifest.jsonl` and the datasheet `README.md`. Every file is
//! written under a temporary name and renamed when whole, so that Ctrl-C (or a full
//! disk) leaves whole files only; the manifest and the datasheet are written last, of
//! the tasks written.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::Cancel;
use coherent_core::Task;
use coherent_generate::sheet::Tally;
use coherent_generate::{About, Entry, Generated};

use crate::session::Error;

use coherent_generate::request::{parse_split, parse_types};
use coherent_generate::{KnobError, Ratio, Span, TeamSpec};

use crate::session::engine::Limits;

pub use coherent_generate::{Progress, Request};

/// What a front end asks for: the set, where it goes (`None`: nowhere, the tasks are
/// only handed back), and the command that asks, for the datasheet.
#[derive(Clone, Debug)]
pub struct GenerateRequest {
    pub request: Request,
    pub out: Option<PathBuf>,
    pub command: String,
}

/// The knobs of a set as the command line and Python give them, the spans and lists as
/// typed (`"2-6"`, `"quadrotor=2,legged=0-3"`, `"mono,trio"`); [`Knobs::request`] reads
/// them, an error naming the knob as the command line does (`--rooms`). The defaults are
/// the command line's.
#[derive(Clone, Debug)]
pub struct Knobs {
    pub tasks: usize,
    pub seed: u64,
    /// `None`: one per 25 tasks, at least 3 (so that each split has a scene).
    pub scenes: Option<usize>,
    pub rooms: String,
    pub upstairs: f64,
    pub closed: f64,
    pub team: Option<String>,
    pub robots: Option<String>,
    pub predicates: String,
    pub types: Option<String>,
    pub needed: Option<String>,
    pub steps: Option<String>,
    pub ratio: Option<String>,
    pub proven: bool,
    pub physics: bool,
    pub max_states: usize,
    /// MiB.
    pub max_memory: usize,
    pub max_draws: Option<usize>,
    pub split: String,
    /// `None`: one per core.
    pub jobs: Option<usize>,
}

impl Default for Knobs {
    fn default() -> Knobs {
        Knobs {
            tasks: 100,
            seed: 0,
            scenes: None,
            rooms: "2-6".to_owned(),
            upstairs: 0.25,
            closed: 0.35,
            team: None,
            robots: None,
            predicates: "1-3".to_owned(),
            types: None,
            needed: None,
            steps: None,
            ratio: None,
            proven: false,
            physics: false,
            max_states: Limits::DEFAULT_MAX_STATES,
            max_memory: Limits::DEFAULT_MAX_MEMORY >> 20,
            max_draws: None,
            split: "0.8,0.1,0.1".to_owned(),
            jobs: None,
        }
    }
}

impl Knobs {
    /// The request these knobs make, written to `out` (or nowhere).
    pub fn request(&self, out: Option<PathBuf>) -> Result<GenerateRequest, Error> {
        let span = |name: &'static str, text: &str| Span::parse(name, text).map_err(knob);
        let optional_span = |name: &'static str, text: &Option<String>| {
            text.as_deref().map(|t| span(name, t)).transpose()
        };
        let jobs = self.jobs.unwrap_or_else(|| {
            std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
        });
        let request = Request {
            tasks: self.tasks,
            seed: self.seed,
            scenes: self.scenes.unwrap_or_else(|| (self.tasks / 25).max(3)),
            rooms: span("--rooms", &self.rooms)?,
            upstairs: self.upstairs,
            closed: self.closed,
            team: TeamSpec::parse(self.team.as_deref(), self.robots.as_deref()).map_err(knob)?,
            predicates: span("--predicates", &self.predicates)?,
            types: match self.types.as_deref() {
                Some(t) => parse_types(t).map_err(knob)?,
                None => Vec::new(),
            },
            needed: optional_span("--needed", &self.needed)?,
            steps: optional_span("--steps", &self.steps)?,
            ratio: self
                .ratio
                .as_deref()
                .map(|t| Ratio::parse("--ratio", t))
                .transpose()
                .map_err(knob)?,
            proven_only: self.proven,
            physics: self.physics,
            limits: Limits {
                max_memory: self.max_memory.saturating_mul(1 << 20),
                ..Limits::max_states(self.max_states)
            },
            max_draws: self.max_draws,
            split: parse_split(&self.split).map_err(knob)?,
            jobs,
        };
        Ok(GenerateRequest {
            command: request.command(),
            request,
            out,
        })
    }
}

/// A task the set kept, as a front end sees it.
#[derive(Clone, Debug)]
pub struct Kept {
    pub task: Task,
    /// Its manifest line.
    pub manifest: serde_json::Value,
}

/// How a run ended.
#[derive(Clone, Debug)]
pub struct Made {
    pub tally: Tally,
    pub scenes: usize,
    /// Ctrl-C stopped it before the set was complete.
    pub interrupted: bool,
}

/// The version every datasheet names.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

impl GenerateRequest {
    /// Makes the set: each kept task to `kept` (and to its file), the progress to
    /// `progress`. A request that cannot be met is `Error::Invalid` naming the knob; an
    /// output folder that cannot be written `Error::File`.
    pub fn run(
        &self,
        cancel: &Cancel,
        kept: &mut dyn FnMut(Kept),
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Made, Error> {
        self.request.check().map_err(knob)?;
        let mut folder = match &self.out {
            Some(dir) => Some(Folder::create(dir)?),
            None => None,
        };
        let flag: Arc<std::sync::atomic::AtomicBool> = cancel.flag();
        let mut write_error = None;
        let outcome = {
            let mut keep = |g: Generated| -> std::io::Result<()> {
                if let Some(f) = folder.as_mut()
                    && let Err(e) = f.task(&g)
                {
                    write_error = Some(e);
                    return Err(std::io::Error::other("the task could not be written"));
                }
                kept(Kept {
                    manifest: g.entry.to_json(),
                    task: g.task,
                });
                Ok(())
            };
            coherent_generate::generate(&self.request, &flag, &mut keep, progress).map_err(knob)?
        };
        if let Some(e) = write_error {
            return Err(e);
        }
        let outcome = outcome.map_err(|e| Error::Internal(e.to_string()))?;
        let about = About {
            command: &self.command,
            version: VERSION,
            seed: self.request.seed,
            scenes: outcome.scenes.len(),
            interrupted: outcome.interrupted,
        };
        if let Some(f) = folder {
            f.finish(&outcome.tally.datasheet(&about))?;
        }
        Ok(Made {
            scenes: outcome.scenes.len(),
            interrupted: outcome.interrupted,
            tally: outcome.tally,
        })
    }
}

/// A request the knobs cannot meet, as the session's error.
fn knob(e: KnobError) -> Error {
    Error::Knob(e)
}

/// The output folder being written.
struct Folder {
    dir: PathBuf,
    manifest: BufWriter<File>,
}

const MANIFEST: &str = "manifest.jsonl";
const DATASHEET: &str = "README.md";

impl Folder {
    /// The folder, made if it does not exist; one that holds anything is refused, so
    /// that no old task is mistaken for one of this set.
    fn create(dir: &Path) -> Result<Folder, Error> {
        let io = |e: std::io::Error| file_error(dir, &e.to_string());
        if dir.exists() {
            if !dir.is_dir() {
                return Err(file_error(dir, "exists and is no folder"));
            }
            if fs::read_dir(dir).map_err(io)?.next().is_some() {
                return Err(file_error(
                    dir,
                    "the folder is not empty: a generated set is written to a new or empty folder",
                ));
            }
        }
        fs::create_dir_all(dir).map_err(io)?;
        let tmp = dir.join(temporary(MANIFEST));
        let manifest =
            BufWriter::new(File::create(&tmp).map_err(|e| file_error(&tmp, &e.to_string()))?);
        Ok(Folder {
            dir: dir.to_path_buf(),
            manifest,
        })
    }

    /// A kept task: its file, whole, then its manifest line.
    fn task(&mut self, g: &Generated) -> Result<(), Error> {
        let path = self.dir.join(format!("{}.json", g.entry.id));
        write_whole(&path, g.text.as_bytes())?;
        self.line(&g.entry)
    }

    fn line(&mut self, e: &Entry) -> Result<(), Error> {
        let tmp = self.dir.join(temporary(MANIFEST));
        writeln!(self.manifest, "{}", e.to_json()).map_err(|err| file_error(&tmp, &err.to_string()))
    }

    /// The manifest renamed into place, and the datasheet.
    fn finish(mut self, datasheet: &str) -> Result<(), Error> {
        let tmp = self.dir.join(temporary(MANIFEST));
        self.manifest
            .flush()
            .and_then(|()| self.manifest.get_ref().sync_all())
            .map_err(|e| file_error(&tmp, &e.to_string()))?;
        let path = self.dir.join(MANIFEST);
        fs::rename(&tmp, &path).map_err(|e| file_error(&path, &e.to_string()))?;
        write_whole(&self.dir.join(DATASHEET), datasheet.as_bytes())
    }
}

/// The temporary name of `name` while it is written: hidden, and no `.json`, so that no
/// reader of task folders takes it for a task.
fn temporary(name: &str) -> String {
    format!(".{name}.partial")
}

/// Writes `bytes` to a temporary file beside `path`, then renames it to `path`.
fn write_whole(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let err = |e: std::io::Error| file_error(path, &e.to_string());
    let dir = path.parent().unwrap_or(Path::new("."));
    fs::create_dir_all(dir).map_err(err)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(temporary(&name));
    fs::write(&tmp, bytes).map_err(err)?;
    fs::rename(&tmp, path).map_err(err)
}

fn file_error(path: &Path, message: &str) -> Error {
    Error::File {
        file: path.display().to_string(),
        line: None,
        message: message.to_owned(),
    }
}

/// What [`write_variants`] wrote: the variants by kind, and the tasks without any.
#[derive(Clone, Debug, Default)]
pub struct VariantsWritten {
    pub tasks: usize,
    /// `(kind, variants)`, in the order of the kinds.
    pub by_kind: Vec<(&'static str, usize)>,
    /// Tasks with no variant (no optimal plan of two steps within the limit, or events
    /// of their own), by name.
    pub skipped: Vec<String>,
}

/// The dynamic variants of every well-formed task at `tasks` (a file, a folder or
/// `native`; docs/dynamic.md), one native task file per variant in `out`, named
/// `<scene>-task<id>-<kind>.json`, its scene `<scene>-<kind>` so that a benchmark tells
/// the variants apart, and a `manifest.jsonl` line each (file, scene, task, kind). Each
/// file is renamed into place when whole. Malformed tasks are left out, as in a
/// benchmark.
pub fn write_variants(tasks: &Path, out: &Path, limits: &Limits) -> Result<VariantsWritten, Error> {
    let read = crate::session::tasks::read_tasks(tasks)?;
    let mut written = VariantsWritten::default();
    let mut manifest = String::new();
    for task in read.into_iter().flatten() {
        written.tasks += 1;
        let variants = coherent_generate::variants::variants(&task, limits);
        if variants.is_empty() {
            written
                .skipped
                .push(format!("{} task {}", task.meta.scene, task.meta.task_id));
        }
        for v in variants {
            let mut t = v.task;
            let scene = format!("{}-{}", t.meta.scene, v.kind);
            let name = format!(
                "{}-task{}-{}.json",
                coherent_core::text::file_name_part(&t.meta.scene, 64),
                t.meta.task_id,
                v.kind
            );
            t.meta.scene.clone_from(&scene);
            let mut bytes = serde_json::to_vec_pretty(&coherent_core::native::to_value(&t))
                .map_err(|e| Error::Internal(e.to_string()))?;
            bytes.push(b'\n');
            write_whole(&out.join(&name), &bytes)?;
            let line = serde_json::json!({
                "file": name, "scene": scene, "task_id": t.meta.task_id, "kind": v.kind,
            });
            manifest.push_str(&line.to_string());
            manifest.push('\n');
            match written.by_kind.iter_mut().find(|(k, _)| *k == v.kind) {
                Some((_, n)) => *n += 1,
                None => written.by_kind.push((v.kind, 1)),
            }
        }
    }
    write_whole(&out.join("manifest.jsonl"), manifest.as_bytes())?;
    Ok(written)
}
