//! The project's own benchmark, compiled in: five scenes with geometry and one hundred
//! tasks under the `geometric` rule set (`benchmark/README.md`), loadable by name with
//! no files at hand (`coherent bench --tasks native`, `coherent.benchmark.tasks()`).

use crate::{Result, Task};

mod files {
    include!(concat!(env!("OUT_DIR"), "/benchmark_files.rs"));
}

/// The name that selects the benchmark where a task path is expected.
pub const NAME: &str = "native";

/// Every task of the benchmark, in file order (scene, then task id).
pub fn tasks() -> Result<Vec<Task>> {
    files::FILES
        .iter()
        .map(|(path, text)| {
            let file = format!("benchmark/{path}");
            let value = crate::json::parse(&file, text.as_bytes())?;
            crate::native::read(&file, &value)
        })
        .collect()
}

/// The 40-task subset (per scene 2 mono, 3 dual and 3 trio tasks, the paper's
/// proportions) as `(scene, task_id)` pairs.
pub fn subset40() -> Vec<(String, i64)> {
    files::SUBSET_40
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .filter_map(|l| {
            let (scene, id) = l.split_once(' ')?;
            Some((scene.to_owned(), id.trim().parse().ok()?))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_benchmark_reads_and_its_subset_names_its_tasks() {
        let tasks = super::tasks().expect("the embedded benchmark reads");
        assert_eq!(tasks.len(), 100);
        let subset = super::subset40();
        assert_eq!(subset.len(), 40);
        for (scene, id) in &subset {
            assert!(
                tasks
                    .iter()
                    .any(|t| &t.meta.scene == scene && t.meta.task_id == *id),
                "{scene} {id} is not a benchmark task"
            );
        }
    }
}
