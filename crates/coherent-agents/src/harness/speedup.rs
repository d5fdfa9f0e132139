//! The makespan table of a benchmark run with parallel episodes: per method, execution
//! and task type, the success rate, the average makespan (the joint steps of the
//! successful episodes; one action a step in a sequential episode) against the optimal
//! makespan of the same tasks, the actions carried out, the model calls per action, the
//! simulated seconds where physics ran, and the speed-up over the same method run
//! sequentially: on the (task, seed) pairs both executions solved, the sequential
//! episodes' steps over the parallel ones'.
//!
//! Plain means over episodes (no intervals over seeds): the speed-up is a ratio of sums
//! over pairs, which has no per-seed mean to take.

use std::collections::HashMap;

use serde::Serialize;

use crate::harness::results::ResultLine;
use coherent_core::Execution;

use crate::run::settings::Builtin;

/// A row's name in the tables: the method, with ` (parallel)` for its parallel
/// episodes (a sequential row keeps the method's name alone, as before parallel
/// episodes).
pub fn row_name(method: &str, execution: Execution) -> String {
    match execution {
        Execution::Sequential => method.to_owned(),
        Execution::Parallel => format!("{method} (parallel)"),
    }
}

/// How rows are ordered: the paper's methods in their order, then the others by name;
/// each method's sequential row before its parallel one.
pub fn row_order(method: &str, execution: Execution) -> (usize, String, Execution) {
    let at = Builtin::ALL
        .iter()
        .position(|m| m.name() == method)
        .unwrap_or(Builtin::ALL.len());
    (at, method.to_owned(), execution)
}

/// One method, execution and task type.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpeedRow {
    pub method: String,
    pub execution: Execution,
    /// `mono`, `dual`, `trio` or `Avg`.
    pub column: String,
    pub episodes: usize,
    pub sr: f64,
    /// Mean joint steps of the successful episodes; `None` without one.
    pub makespan: Option<f64>,
    /// Mean optimal makespan of the tasks of those episodes; `None` where unknown.
    pub optimal_makespan: Option<f64>,
    /// Mean actions carried out per episode; `None` where the lines do not say.
    pub actions: Option<f64>,
    /// Model calls over actions carried out, all episodes together.
    pub calls_per_action: Option<f64>,
    /// Mean simulated seconds of the successful episodes, where physics ran.
    pub sim_seconds: Option<f64>,
    /// The same method's sequential steps over these parallel ones, on the (task, seed)
    /// pairs both solved; `None` for a sequential row, or without such a pair.
    pub speedup: Option<f64>,
    /// How many such pairs.
    pub pairs: usize,
}

/// The makespan table of `finals` (one final line per episode), or empty when no
/// episode ran in parallel.
pub fn build(finals: &[&ResultLine]) -> Vec<SpeedRow> {
    if finals.iter().all(|l| l.execution.is_sequential()) {
        return Vec::new();
    }
    let mut keys: Vec<(String, Execution)> = finals
        .iter()
        .map(|l| (l.method.clone(), l.execution))
        .collect();
    keys.sort_by_key(|(m, e)| row_order(m, *e));
    keys.dedup();
    // Sequential steps of each solved (method, task, seed), for the speed-up.
    let solved: HashMap<(&str, &str, i64, u32), u32> = finals
        .iter()
        .filter(|l| l.execution.is_sequential() && l.success)
        .map(|l| {
            (
                (l.method.as_str(), l.scene.as_str(), l.task_id, l.seed),
                l.steps,
            )
        })
        .collect();
    let mut rows = Vec::new();
    for (method, execution) in keys {
        for column in ["mono", "dual", "trio", "Avg"] {
            let mine: Vec<&ResultLine> = finals
                .iter()
                .copied()
                .filter(|l| l.method == method && l.execution == execution)
                .filter(|l| column == "Avg" || l.task_type.as_deref() == Some(column))
                .collect();
            if mine.is_empty() {
                continue;
            }
            rows.push(row(&method, execution, column, &mine, &solved));
        }
    }
    rows
}

fn row(
    method: &str,
    execution: Execution,
    column: &str,
    mine: &[&ResultLine],
    solved: &HashMap<(&str, &str, i64, u32), u32>,
) -> SpeedRow {
    let mean = |xs: &[f64]| (!xs.is_empty()).then(|| xs.iter().sum::<f64>() / xs.len() as f64);
    let wins: Vec<&&ResultLine> = mine.iter().filter(|l| l.success).collect();
    let makespans: Vec<f64> = wins.iter().map(|l| f64::from(l.steps)).collect();
    let optimal: Vec<f64> = wins
        .iter()
        .filter_map(|l| l.optimal_makespan.map(f64::from))
        .collect();
    let actions: Option<Vec<f64>> = mine.iter().map(|l| l.actions.map(f64::from)).collect();
    let done: Option<f64> = actions.as_ref().map(|a| a.iter().sum());
    let calls: f64 = mine.iter().map(|l| f64::from(l.llm_calls)).sum();
    let sims: Vec<f64> = wins.iter().filter_map(|l| l.sim_seconds).collect();
    let (mut before, mut after, mut pairs) = (0u64, 0u64, 0usize);
    if execution == Execution::Parallel {
        for l in &wins {
            let key = (method, l.scene.as_str(), l.task_id, l.seed);
            if let Some(&steps) = solved.get(&key) {
                before += u64::from(steps);
                after += u64::from(l.steps);
                pairs += 1;
            }
        }
    }
    SpeedRow {
        method: method.to_owned(),
        execution,
        column: column.to_owned(),
        episodes: mine.len(),
        sr: wins.len() as f64 / mine.len() as f64,
        makespan: mean(&makespans),
        optimal_makespan: (optimal.len() == makespans.len())
            .then(|| mean(&optimal))
            .flatten(),
        actions: actions.as_deref().and_then(mean),
        calls_per_action: done.filter(|&d| d > 0.0).map(|d| calls / d),
        sim_seconds: (sims.len() == wins.len()).then(|| mean(&sims)).flatten(),
        speedup: (after > 0).then(|| before as f64 / after as f64),
        pairs,
    }
}

fn column_name(c: &str) -> &str {
    match c {
        "mono" => "Mono",
        "dual" => "Dual",
        "trio" => "Trio",
        other => other,
    }
}

/// The table in Markdown (empty without rows), each row's name written by `name` (the
/// report's escaping of a name from a results line in a cell).
pub fn markdown(rows: &[SpeedRow], name: fn(&str) -> String) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let opt = |x: Option<f64>, d: usize| x.map_or("-".into(), |x| format!("{x:.d$}"));
    let mut out = String::from("### Makespan: steps to the goal with robots acting at once\n\n");
    out.push_str(
        "Makespan: the joint steps of the successful episodes (one action a step in a \
         sequential one), against the optimal makespan of the same tasks. Speed-up: the \
         method's sequential steps over its parallel ones, on the (task, seed) pairs both \
         solved.  \n\n",
    );
    out.push_str(
        "| Method | Tasks | Episodes | SR | Makespan | Optimal makespan | Actions / episode | LLM calls / action | Sim s | Speed-up |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let speedup = r
            .speedup
            .map_or("-".into(), |x| format!("{x:.2}x (n={})", r.pairs));
        out.push_str(&format!(
            "| {} | {} | {} | {:.3} | {} | {} | {} | {} | {} | {speedup} |\n",
            name(&row_name(&r.method, r.execution)),
            column_name(&r.column),
            r.episodes,
            r.sr,
            opt(r.makespan, 1),
            opt(r.optimal_makespan, 1),
            opt(r.actions, 1),
            opt(r.calls_per_action, 2),
            opt(r.sim_seconds, 1),
        ));
    }
    out
}
