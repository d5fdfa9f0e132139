//! Reading tasks: files and folders of either format, the project's own benchmark by
//! its name, one task of a file, and where an episode's task comes from
//! ([`TaskSource`]).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::bench::{Subset, select};
use coherent_core::{Error, Task, benchmark, load};

/// Where an episode's task comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum TaskSource {
    /// The task `task_id` of a file (its only task when `None`).
    File { path: PathBuf, task_id: Option<i64> },
    /// A task already read.
    Given(Arc<Task>),
}

impl TaskSource {
    /// The file the task comes from, as errors name it (`the task given` for one read
    /// already).
    pub fn file_name(&self) -> String {
        match self {
            TaskSource::File { path, .. } => path.display().to_string(),
            TaskSource::Given(_) => "the task given".to_owned(),
        }
    }

    /// The task.
    pub fn task(self) -> Result<Arc<Task>, Error> {
        match self {
            TaskSource::File { path, task_id } => pick_task(&path, task_id).map(Arc::new),
            TaskSource::Given(task) => Ok(task),
        }
    }
}

/// The tasks at `path` ([`load::read_tasks`]: one result per task, so that one malformed
/// task does not hide the others), or, when `path` is `native` and no such file exists,
/// the project's own benchmark, compiled in.
pub fn read_tasks(path: &Path) -> coherent_core::Result<Vec<coherent_core::Result<Task>>> {
    if path.as_os_str() == benchmark::NAME && !path.exists() {
        return Ok(benchmark::tasks()?.into_iter().map(Ok).collect());
    }
    load::read_tasks(path)
}

/// The project's own benchmark, compiled in: the tasks `subset` picks of it.
pub fn benchmark(subset: &Subset) -> Result<Vec<Arc<Task>>, crate::session::Error> {
    Ok(select(benchmark::tasks()?, subset)?.tasks)
}

/// What [`read_all`] found.
#[derive(Debug, Default)]
pub struct Read {
    /// The well-formed tasks, in the order of the paths.
    pub tasks: Vec<Task>,
    /// An error for each malformed task or unreadable path.
    pub malformed: Vec<Error>,
    /// The paths that hold no task at all (an empty list, an empty folder).
    pub empty: Vec<PathBuf>,
}

/// The tasks of every path, the malformed ones, and the paths with none.
pub fn read_all(paths: &[PathBuf]) -> Read {
    let mut read = Read::default();
    for path in paths {
        match read_tasks(path) {
            Ok(results) => {
                if results.is_empty() {
                    read.empty.push(path.clone());
                }
                for r in results {
                    match r {
                        Ok(t) => read.tasks.push(t),
                        Err(e) => read.malformed.push(e),
                    }
                }
            }
            Err(e) => read.malformed.push(e),
        }
    }
    read
}

/// The task `id` of `file`, or its only task when `id` is `None`.
pub fn pick_task(file: &Path, id: Option<i64>) -> Result<Task, Error> {
    let results = read_tasks(file)?;
    let name = file.display().to_string();
    let no = |message: String| Error::Io {
        file: name.clone(),
        message,
    };
    let ids = |results: &[Result<Task, _>]| {
        id_list(
            results
                .iter()
                .filter_map(|r| r.as_ref().ok().map(|t| t.meta.task_id)),
        )
    };
    match id {
        Some(id) => {
            let known = ids(&results);
            let mut malformed = Vec::new();
            for r in results {
                match r {
                    Ok(t) if t.meta.task_id == id => return Ok(t),
                    Ok(_) => {}
                    Err(e) => malformed.push(e.to_string()),
                }
            }
            let mut message =
                format!("no well-formed task with task_id {id}; its task ids: {known}");
            for e in malformed {
                message.push_str(&format!("\n  (malformed, and possibly that task: {e})"));
            }
            Err(no(message))
        }
        None => {
            let mut results = results;
            match results.len() {
                1 => results.pop().expect("one task"),
                0 => Err(no("no tasks".into())),
                n => Err(no(format!(
                    "{n} tasks; choose one with --task ID (its task ids: {})",
                    ids(&results)
                ))),
            }
        }
    }
}

/// Task ids as a short list, runs of consecutive ids as ranges: `0-16`, `0-3, 5, 7-9`.
pub fn id_list(ids: impl IntoIterator<Item = i64>) -> String {
    let mut ids: Vec<i64> = ids.into_iter().collect();
    ids.sort_unstable();
    ids.dedup();
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < ids.len() {
        let start = ids[i];
        while i + 1 < ids.len() && ids[i + 1] == ids[i] + 1 {
            i += 1;
        }
        parts.push(if ids[i] == start {
            start.to_string()
        } else {
            format!("{start}-{}", ids[i])
        });
        i += 1;
    }
    if parts.is_empty() {
        "none".to_owned()
    } else {
        parts.join(", ")
    }
}

/// `scene task N (file)`, how reports name a task.
pub fn task_name(t: &Task) -> String {
    let file = t
        .meta
        .source
        .as_ref()
        .map(|s| format!(" ({})", s.file))
        .unwrap_or_default();
    format!("{} task {}{file}", t.meta.scene, t.meta.task_id)
}
