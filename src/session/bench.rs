//! Benchmarks: the tasks a subset picks, methods x tasks x seeds run concurrently into a
//! resumable results file (`coherent_agents::bench`), and the paper's tables of it.

use std::path::Path;
use std::sync::Arc;

use coherent_agents::bench::{
    self, BenchConfig, BenchOutcome, Event, ResultLine, Selection, Subset,
};
use coherent_agents::{Cancel, MethodSpec, report};
use coherent_core::{Error, Task};

/// A subset by name (`all`, `paper40`, `native40`), else a file of `scene task_id` lines.
pub fn subset(name_or_file: &str) -> Result<Subset, String> {
    match Subset::named(name_or_file) {
        Some(named) => Ok(named),
        None => Subset::read_file(Path::new(name_or_file)),
    }
}

/// The tasks a subset picks from the tasks at a path, and the malformed tasks left out.
#[derive(Debug)]
pub struct Chosen {
    pub selection: Selection,
    pub malformed: Vec<Error>,
}

/// The tasks `subset` picks from every well-formed task at `path`.
pub fn choose(path: &Path, subset: &Subset) -> Result<Chosen, String> {
    let mut tasks = Vec::new();
    let mut malformed = Vec::new();
    for r in super::tasks::read_tasks(path).map_err(|e| e.to_string())? {
        match r {
            Ok(t) => tasks.push(t),
            Err(e) => malformed.push(e),
        }
    }
    Ok(Chosen {
        selection: bench::select(tasks, subset)?,
        malformed,
    })
}

/// Runs the benchmark `config` on `tasks`: every method on every task for every seed,
/// skipping the episodes already finished in the results file, appending one line per
/// episode. `cancel` stops it (episodes in flight end as interrupted).
pub async fn run(
    tasks: &[Arc<Task>],
    config: &BenchConfig,
    cancel: &Cancel,
    progress: &mut (dyn FnMut(Event<'_>) + Send),
) -> Result<BenchOutcome, String> {
    if tasks.is_empty() {
        return Err("no tasks to run".into());
    }
    if config.methods.is_empty() {
        return Err("no methods to run".into());
    }
    distinct_names(&config.methods)?;
    if config.seeds == 0 {
        return Err("seeds must be at least 1".into());
    }
    bench::run(tasks, config, cancel, progress).await
}

/// Refuses two methods of one name: results are keyed by the method's name, so one
/// written outside the crate needs its own.
pub fn distinct_names(methods: &[MethodSpec]) -> Result<(), String> {
    let names: Vec<&str> = methods.iter().map(|m| m.name()).collect();
    match methods
        .iter()
        .find(|m| m.builtin().is_none() && names.iter().filter(|&&n| n == m.name()).count() > 1)
    {
        Some(m) => Err(format!(
            "two methods are named {:?}: give each its own name",
            m.name()
        )),
        None => Ok(()),
    }
}

/// How the tables are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableFormat {
    Markdown,
    Csv,
    Json,
}

impl TableFormat {
    pub fn from_name(name: &str) -> Option<TableFormat> {
        match name {
            "markdown" => Some(TableFormat::Markdown),
            "csv" => Some(TableFormat::Csv),
            "json" => Some(TableFormat::Json),
            _ => None,
        }
    }
}

/// The paper's tables (Table I by task type, Table II by scene, the costs) of results
/// lines, as text.
pub fn tables(lines: &[ResultLine], format: TableFormat) -> String {
    let r = report::build(lines);
    match format {
        TableFormat::Markdown => report::markdown(&r),
        TableFormat::Csv => report::csv(&r),
        TableFormat::Json => report::json(&r),
    }
}
