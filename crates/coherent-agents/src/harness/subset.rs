//! Which tasks a benchmark runs: every well-formed task, the paper's 40-task subset, or
//! a listed one.

use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::sync::Arc;

use coherent_core::Task;
use coherent_core::files::{self, Limit, MIB};

/// The most a subset file may hold: tens of thousands of `scene task_id` lines.
pub const FILE_LIMIT: Limit = Limit {
    bytes: MIB,
    what: "a subset file",
    raise: None,
};

use crate::error::Error;

/// The paper's 40-task subset (docs/semantics.md, "Steps, the budget and the scores"): 8 tasks per scene, by the scene's
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
    /// The subsets that have a name.
    pub const NAMES: [&'static str; 3] = ["all", "paper40", "native40"];

    pub fn named(name: &str) -> Option<Subset> {
        match name {
            "all" => Some(Subset::All),
            "paper40" => Some(Subset::Paper40),
            "native40" => Some(Subset::Listed(coherent_core::benchmark::subset40())),
            _ => None,
        }
    }

    /// Reads a subset file of at most [`FILE_LIMIT`]; errors name the file and the line.
    pub fn read_file(path: &Path) -> Result<Subset, Error> {
        let bytes = files::read(path, &FILE_LIMIT).map_err(Error::file)?;
        let text = String::from_utf8(bytes).map_err(|e| Error::Format {
            file: path.display().to_string(),
            line: None,
            message: format!("not UTF-8: {e}"),
        })?;
        let mut pairs = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let at = |message: String| Error::at_line(path, i + 1, message);
            let mut words = line.split_whitespace();
            let (Some(scene), Some(id), None) = (words.next(), words.next(), words.next()) else {
                return Err(at(format!("expected `scene task_id`, found {line:?}")));
            };
            let id: i64 = id
                .parse()
                .map_err(|_| at(format!("task id {id:?} is not an integer")))?;
            pairs.push((scene.to_owned(), id));
        }
        Ok(Subset::Listed(pairs))
    }

    /// The `(scene, task_id)` pairs the subset names; `None` for every task.
    pub fn pairs(&self) -> Option<Vec<(String, i64)>> {
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
pub fn select(tasks: Vec<Task>, subset: &Subset) -> Result<Selection, Error> {
    let mut by_key: HashMap<(String, i64), Arc<Task>> = HashMap::new();
    let mut order = Vec::new();
    for t in tasks {
        let key = (t.meta.scene.clone(), t.meta.task_id);
        if by_key.contains_key(&key) {
            return Err(Error::Invalid(same_key_twice(&key)));
        }
        order.push(key.clone());
        by_key.insert(key, Arc::new(t));
    }
    let Some(wanted) = subset.pairs() else {
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

/// Why a run refuses two tasks with the same scene and task id (`key`).
pub fn same_key_twice((scene, task_id): &(String, i64)) -> String {
    format!(
        "two tasks with scene {scene:?} and task_id {task_id}: results could not tell them apart"
    )
}
