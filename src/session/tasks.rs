//! Reading tasks: files and folders of either format, the project's own benchmark by
//! its name, and one task of a file.

use std::path::{Path, PathBuf};

use coherent_core::{Error, Task, benchmark, load};

/// The tasks at `path` ([`load::read_tasks`]: one result per task, so that one malformed
/// task does not hide the others), or, when `path` is `native` and no such file exists,
/// the project's own benchmark, compiled in.
pub fn read_tasks(path: &Path) -> coherent_core::Result<Vec<coherent_core::Result<Task>>> {
    if path.as_os_str() == benchmark::NAME && !path.exists() {
        return Ok(benchmark::tasks()?.into_iter().map(Ok).collect());
    }
    load::read_tasks(path)
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
pub fn pick_task(file: &Path, id: Option<i64>) -> Result<Task, String> {
    let results = read_tasks(file).map_err(|e| e.to_string())?;
    let name = file.display();
    match id {
        Some(id) => {
            let mut malformed = Vec::new();
            for r in results {
                match r {
                    Ok(t) if t.meta.task_id == id => return Ok(t),
                    Ok(_) => {}
                    Err(e) => malformed.push(e.to_string()),
                }
            }
            let mut message = format!("{name}: no well-formed task with task_id {id}");
            for e in malformed {
                message.push_str(&format!("\n  (malformed, and possibly that task: {e})"));
            }
            Err(message)
        }
        None => {
            let mut results = results;
            match results.len() {
                1 => results.pop().expect("one task").map_err(|e| e.to_string()),
                0 => Err(format!("{name}: no tasks")),
                n => Err(format!("{name}: {n} tasks; choose one with --task ID")),
            }
        }
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
