//! Reading task files and folders in either format, with errors that name the file,
//! the JSON path and the value.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::error::{Error, Result};
use crate::files::{self, Limit, MIB};
use crate::task::Task;

/// The most a task file may hold: the released files of the paper are under 400 KiB, and
/// a scene hundreds of times larger would be beyond the planner anyway.
pub const TASK_FILE_LIMIT: Limit = Limit {
    bytes: 64 * MIB,
    what: "a task file",
    raise: None,
};

/// Every task found at `path` (a file of either format, or a folder searched for
/// `*.json` files, recursively, in name order). The outer result fails when a file
/// cannot be read or is not JSON; each inner result is one task, so that a malformed
/// task is reported without hiding the rest.
pub fn read_tasks(path: &Path) -> Result<Vec<Result<Task>>> {
    let mut out = Vec::new();
    for file in task_files(path)? {
        out.extend(read_file(&file)?);
    }
    Ok(out)
}

/// Every task at `path`, or the first error; a file or folder with no task at all (an
/// empty list) is an error too.
pub fn load_tasks(path: &Path) -> Result<Vec<Task>> {
    let tasks: Vec<Task> = read_tasks(path)?.into_iter().collect::<Result<_>>()?;
    if tasks.is_empty() {
        return Err(Error::Malformed {
            file: path.display().to_string(),
            path: crate::JsonPath::root(),
            message: "no tasks: the list of tasks is empty".to_owned(),
        });
    }
    Ok(tasks)
}

/// The JSON files at `path`: the file itself, or a folder's `*.json` files, recursively.
/// A `*.json` entry of a folder that is not a regular file (a pipe, a device, a link to
/// one) is refused: reading it could block or never end.
pub fn task_files(path: &Path) -> Result<Vec<PathBuf>> {
    let meta = std::fs::metadata(path).map_err(|e| io_error(path, &e))?;
    if !meta.is_dir() {
        return Ok(vec![path.to_owned()]);
    }
    let mut files = Vec::new();
    let mut stack = vec![path.to_owned()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).map_err(|e| io_error(&dir, &e))? {
            let entry = entry.map_err(|e| io_error(&dir, &e))?;
            let p = entry.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|e| e == "json") {
                let meta = std::fs::metadata(&p).map_err(|e| io_error(&p, &e))?;
                if !meta.is_file() {
                    return Err(Error::Io {
                        file: p.display().to_string(),
                        message: "not a regular file (a pipe, a device?): a task file must be one"
                            .to_owned(),
                    });
                }
                files.push(p);
            }
        }
    }
    files.sort();
    if files.is_empty() {
        return Err(Error::Io {
            file: path.display().to_string(),
            message: "folder holds no .json task files".to_owned(),
        });
    }
    Ok(files)
}

/// The tasks of one file: a list (original format) or an object (native format); a
/// file of more than [`TASK_FILE_LIMIT`] is refused.
pub fn read_file(path: &Path) -> Result<Vec<Result<Task>>> {
    let file = path.display().to_string();
    let bytes = files::read(path, &TASK_FILE_LIMIT)?;
    let value = crate::json::parse(&file, &bytes)?;
    let scene = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    read_value(&file, &scene, &value)
}

/// The tasks of an already parsed JSON document; `scene` names the scene of an
/// original-format list (its file stem).
pub fn read_value(file: &str, scene: &str, value: &Value) -> Result<Vec<Result<Task>>> {
    match value {
        Value::Array(_) => crate::original::read(file, scene, value),
        Value::Object(map) if map.contains_key("format") => {
            Ok(vec![crate::native::read(file, value)])
        }
        other => Err(Error::Malformed {
            file: file.to_owned(),
            path: crate::JsonPath::root(),
            message: format!(
                "expected a list of tasks (original format) or an object with \"format\": \"{}\", found {}",
                crate::native::FORMAT,
                crate::json::describe(other)
            ),
        }),
    }
}

fn io_error(path: &Path, e: &std::io::Error) -> Error {
    Error::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    }
}
