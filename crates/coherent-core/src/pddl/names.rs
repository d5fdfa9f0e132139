//! The PDDL names of a task's nodes and of its problem.

use rustc_hash::FxHashMap;

use crate::graph::Idx;
use crate::task::Task;

/// The PDDL names of a task's nodes: the class name in lower case, every run of other
/// characters than letters and digits one `-`, then `_` and the id (`m` before a
/// negative one): `<kitchen table>(32)` is `kitchen-table_32`.
#[derive(Clone, Debug)]
pub struct Names {
    names: Vec<String>,
    by_name: FxHashMap<String, Idx>,
    /// The problem's name: the scene's and the task's.
    pub problem: String,
}

impl Names {
    pub fn of_task(task: &Task) -> Names {
        let names: Vec<String> = task
            .nodes
            .iter()
            .map(|n| format!("{}_{}", word(&n.class_name, "node"), id_word(n.id.0)))
            .collect();
        let by_name = names
            .iter()
            .enumerate()
            .map(|(i, name)| (name.clone(), Idx(i as u16)))
            .collect();
        let problem = format!(
            "{}_task-{}",
            word(&task.meta.scene, "scene"),
            id_word(task.meta.task_id)
        );
        Names {
            names,
            by_name,
            problem,
        }
    }

    /// The name of node `x`.
    pub fn of(&self, x: Idx) -> &str {
        &self.names[x.get()]
    }

    /// The node named `name` (PDDL names compare without case).
    pub fn node(&self, name: &str) -> Option<Idx> {
        self.by_name.get(&name.to_ascii_lowercase()).copied()
    }
}

/// `text` as a PDDL name: lower-case letters and digits, other runs one `-`, starting
/// with a letter (`fallback` when nothing is left).
fn word(text: &str, fallback: &str) -> String {
    let mut w = String::new();
    for c in text.chars() {
        if c.is_ascii_alphanumeric() {
            w.push(c.to_ascii_lowercase());
        } else if !w.is_empty() && !w.ends_with('-') {
            w.push('-');
        }
    }
    while w.ends_with('-') {
        w.pop();
    }
    if w.is_empty() {
        return fallback.to_owned();
    }
    if !w.starts_with(|c: char| c.is_ascii_alphabetic()) {
        w.insert(0, 'n');
    }
    w
}

fn id_word(id: i64) -> String {
    if id < 0 {
        format!("m{}", id.unsigned_abs())
    } else {
        id.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::{id_word, word};

    #[test]
    fn names_are_pddl_words() {
        assert_eq!(word("kitchen table", "node"), "kitchen-table");
        assert_eq!(word("  Café  (big) ", "node"), "caf-big");
        assert_eq!(word("3d printer", "node"), "n3d-printer");
        assert_eq!(word("***", "node"), "node");
        assert_eq!(id_word(-5), "m5");
        assert_eq!(id_word(32), "32");
    }
}
