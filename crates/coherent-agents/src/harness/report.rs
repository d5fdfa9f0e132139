//! The paper's tables from a results file ([`crate::harness`]): Table I (success rate and
//! average steps by task type, mono/dual/trio and the average), Table II (the same by
//! scene), Table III (the same by team size, when the tasks have teams of more than one
//! size: generated sets, `coherent generate`), each with the ground-truth row, and each method's LLM calls, tokens and cost
//! (per task and per success, from the lines' `cost_usd`). A method's parallel episodes
//! are a row of their own, `<method> (parallel)`, and a run with parallel episodes adds
//! the makespan table ([`crate::harness::speedup`]).
//!
//! AS counts a failed episode as 2 x GT + 1 steps (docs/semantics.md, "Steps, the budget and the scores"; for a task
//! without GT, and for a parallel episode, its budget plus one). With several seeds each cell is the mean over seeds of the
//! per-seed value, with the half-width of a 95% confidence interval from Student's t.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use coherent_core::Execution;
use coherent_core::text::shown;
use serde::Serialize;

use crate::harness::dynamic::{self, EventRow};
use crate::harness::results::{EpisodeKey, ResultLine};
use crate::harness::run_settings::{RunSettings, method_text};
use crate::harness::speedup::{self, SpeedRow, row_name, row_order};
use crate::records::transcript::headline;
use crate::setting::{Setting, field};

/// Two-sided 95% quantiles of Student's t, t(0.975, df) for df = 1..30 (the standard
/// table, e.g. NIST/SEMATECH e-Handbook of Statistical Methods, section 1.3.6.7.2); the
/// normal 1.96 beyond.
const T975: [f64; 30] = [
    12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
    2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
    2.052, 2.048, 2.045, 2.042,
];

/// t(0.975, df); `df` must be at least 1.
pub fn t975(df: usize) -> f64 {
    T975.get(df.wrapping_sub(1)).copied().unwrap_or(1.96)
}

/// A mean over seeds and, with two seeds or more, the half-width of its 95% interval.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Stat {
    pub mean: f64,
    pub ci95: Option<f64>,
}

impl Stat {
    /// Mean and t-interval of per-seed values.
    pub fn of(values: &[f64]) -> Option<Stat> {
        let k = values.len();
        if k == 0 {
            return None;
        }
        let mean = values.iter().sum::<f64>() / k as f64;
        let ci95 = (k >= 2).then(|| {
            let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (k - 1) as f64;
            t975(k - 1) * (var / k as f64).sqrt()
        });
        Some(Stat { mean, ci95 })
    }
}

/// One method in one column.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Cell {
    /// Episodes counted, all seeds together.
    pub episodes: usize,
    pub sr: Stat,
    #[serde(rename = "as")]
    pub avg_steps: Stat,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    pub method: String,
    /// One per column; `None` where the method ran no task of that column.
    pub cells: Vec<Option<Cell>>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table {
    pub title: String,
    pub columns: Vec<String>,
    /// Distinct tasks per column.
    pub tasks: Vec<usize>,
    pub rows: Vec<Row>,
    /// Mean GT steps of the column's tasks (the ground-truth row).
    pub gt: Vec<Option<f64>>,
}

/// A method's model use.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Cost {
    pub method: String,
    pub episodes: usize,
    pub steps: u64,
    pub llm_calls: u64,
    pub prompt_tokens: u64,
    pub completion_tokens: u64,
    /// The part of `prompt_tokens` the servers read from their prompt caches.
    pub cached_tokens: u64,
    /// `cached_tokens` over `prompt_tokens` (`None` without prompt tokens).
    pub cached_share: Option<f64>,
    pub calls_per_episode: f64,
    pub tokens_per_episode: f64,
    pub calls_per_step: Option<f64>,
    pub tokens_per_step: Option<f64>,
    /// USD of all its episodes; `None` unless every one has a `cost_usd`.
    pub cost_usd: Option<f64>,
    /// USD per episode (one run of one task).
    pub cost_per_task: Option<f64>,
    /// USD per successful episode: all of the cost over the successes (`None` without one).
    pub cost_per_success: Option<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// Every backend that answered a model-using method, as labelled in the headers.
    pub backends: Vec<String>,
    pub seeds: Vec<u32>,
    pub table1: Table,
    pub table2: Table,
    /// By the robots in the task's team, when the tasks have more than one team size.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub table3: Option<Table>,
    pub costs: Vec<Cost>,
    /// Episodes with no final line (only backend errors, the method's errors or
    /// interruptions).
    pub unfinished: usize,
    /// Those of them whose last line failed with an error
    /// ([`ResultLine::failed_with_error`]).
    pub errors: usize,
    /// Tasks the planner finds no plan for (task type null): in the average only.
    pub untyped_tasks: usize,
    /// The makespan table, when some episode ran in parallel ([`speedup::build`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub makespan: Vec<SpeedRow>,
    /// The events table, when some task had events ([`dynamic::build`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<EventRow>,
    /// The settings every line was run with (none for lines that record none).
    pub settings: Option<RunSettings>,
    /// The settings methods written outside the crate declared, by method.
    pub method_settings: BTreeMap<String, BTreeMap<String, serde_json::Value>>,
    /// The episodes that failed with an error, by method.
    pub failures: Vec<Failure>,
}

/// The episodes of one method that failed with an error
/// ([`ResultLine::failed_with_error`], and no final line since).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Failure {
    pub method: String,
    pub episodes: usize,
    /// The first one's error: the method's exception and where it was raised
    /// ([`crate::transcript::headline`]), or why the episode could not go on.
    pub first_error: String,
    /// The first one's transcript (a method's whole traceback; for an episode that had
    /// no transcript, the file that could not be created).
    pub transcript: String,
}

/// Lines of more than one set of settings, which one report would mix.
#[derive(Clone, Debug, PartialEq)]
pub struct Mixed {
    /// Each set of run-wide settings (none: not recorded) and how many lines have it.
    pub groups: Vec<(Option<RunSettings>, usize)>,
    /// The settings in which they differ.
    pub differing: Vec<Setting>,
}

impl std::fmt::Display for Mixed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<&str> = self.differing.iter().map(|s| field(*s)).collect();
        write!(
            f,
            "the results hold {} runs of different settings (they differ in {}), which one \
             table would mix:",
            self.groups.len(),
            names.join(", ")
        )?;
        for (i, (settings, n)) in self.groups.iter().enumerate() {
            let what = settings
                .as_ref()
                .map_or_else(|| "settings not recorded".to_owned(), RunSettings::summary);
            write!(f, "\n  run {}: {n} lines: {what}", i + 1)?;
        }
        Ok(())
    }
}

/// The steps AS counts for one episode.
pub fn counted_steps(l: &ResultLine) -> f64 {
    if l.success {
        f64::from(l.steps)
    } else {
        match l.gt_steps.filter(|_| l.execution.is_sequential()) {
            Some(gt) => 2.0 * f64::from(gt) + 1.0,
            None => f64::from(l.max_steps) + 1.0,
        }
    }
}

/// `simulated: optimal-planner with errors hallucinate=0.1,...`.
fn backend_label(l: &ResultLine) -> String {
    let b = &l.backend;
    let mut s = format!("{}: {}", b.kind, b.model);
    if let Some(url) = &b.base_url {
        s.push_str(&format!(" at {url}"));
    }
    s
}

/// The final line of each episode (the last one, should one have been re-run), and how
/// many episodes have none.
pub fn final_lines(lines: &[ResultLine]) -> (Vec<&ResultLine>, usize) {
    let mut last: BTreeMap<EpisodeKey, &ResultLine> = BTreeMap::new();
    let mut all = BTreeSet::new();
    for l in lines {
        all.insert(l.key());
        if l.is_final() {
            last.insert(l.key(), l);
        }
    }
    let unfinished = all.len() - last.len();
    (last.into_values().collect(), unfinished)
}

/// The episodes with no final line whose last line failed with an error
/// ([`ResultLine::failed_with_error`]), in the order of the file.
fn errors(lines: &[ResultLine]) -> Vec<&ResultLine> {
    let mut last: HashMap<EpisodeKey, usize> = HashMap::new();
    for (i, l) in lines.iter().enumerate() {
        last.insert(l.key(), i);
    }
    let finished: BTreeSet<EpisodeKey> = lines
        .iter()
        .filter(|l| l.is_final())
        .map(ResultLine::key)
        .collect();
    lines
        .iter()
        .enumerate()
        .filter(|(i, l)| {
            last.get(&l.key()) == Some(i) && l.failed_with_error() && !finished.contains(&l.key())
        })
        .map(|(_, l)| l)
        .collect()
}

/// The failed episodes of `errors` by method, in the order methods first failed.
fn failures(errors: &[&ResultLine]) -> Vec<Failure> {
    let mut out: Vec<Failure> = Vec::new();
    for l in errors {
        match out.iter_mut().find(|f| f.method == l.method) {
            Some(f) => f.episodes += 1,
            None => out.push(Failure {
                method: l.method.clone(),
                episodes: 1,
                first_error: headline(l.error.as_deref().unwrap_or("")),
                transcript: l.transcript.clone(),
            }),
        }
    }
    out
}

/// Builds both tables, the costs and the makespan table of lines of one set of
/// settings; lines of several
/// ([`groups`]) are refused, since one table would mix them.
pub fn build(lines: &[ResultLine]) -> Result<Report, Mixed> {
    let groups = groups(lines);
    if groups.len() > 1 {
        return Err(Mixed {
            differing: differing(&groups),
            groups: groups
                .into_iter()
                .map(|g| (g.settings, g.lines.len()))
                .collect(),
        });
    }
    let settings = groups.into_iter().next().and_then(|g| g.settings);
    Ok(build_one(lines, settings))
}

/// The tables of no lines at all.
pub fn empty() -> Report {
    build_one(&[], None)
}

/// The tables of lines that share `settings`.
fn build_one(lines: &[ResultLine], settings: Option<RunSettings>) -> Report {
    let (finals, unfinished) = final_lines(lines);
    let mut rows: Vec<(String, Execution)> = finals
        .iter()
        .map(|l| (l.method.clone(), l.execution))
        .collect();
    rows.sort_by_key(|(m, e)| row_order(m, *e));
    rows.dedup();
    let methods: Vec<String> = rows.iter().map(|(m, e)| row_name(m, *e)).collect();
    let seeds: BTreeSet<u32> = finals.iter().map(|l| l.seed).collect();
    let backends: BTreeSet<String> = finals
        .iter()
        .filter(|l| l.uses_model)
        .map(|l| backend_label(l))
        .collect();
    let mut tasks: HashMap<(String, i64), &ResultLine> = HashMap::new();
    for l in &finals {
        tasks.entry((l.scene.clone(), l.task_id)).or_insert(l);
    }
    let untyped_tasks = tasks.values().filter(|l| l.task_type.is_none()).count();

    let types = ["mono", "dual", "trio"];
    let by_type = |l: &ResultLine, col: &str| col == "Avg" || l.task_type.as_deref() == Some(col);
    let mut cols1: Vec<String> = types.iter().map(|t| (*t).to_owned()).collect();
    cols1.push("Avg".into());
    let table1 = table(
        "Table I: success rate (SR) and average steps (AS) by task type",
        &cols1,
        &methods,
        &finals,
        &tasks,
        &by_type,
    );
    let scenes: BTreeSet<String> = finals.iter().map(|l| l.scene.clone()).collect();
    let mut cols2: Vec<String> = scenes.into_iter().collect();
    cols2.push("Avg".into());
    let by_scene = |l: &ResultLine, col: &str| col == "Avg" || l.scene == col;
    let table2 = table(
        "Table II: success rate (SR) and average steps (AS) by scene",
        &cols2,
        &methods,
        &finals,
        &tasks,
        &by_scene,
    );
    let table3 = team_table(&methods, &finals, &tasks);
    let costs = methods
        .iter()
        .map(|m| {
            let mine: Vec<&&ResultLine> = finals.iter().filter(|l| &row_of(l) == m).collect();
            let steps: u64 = mine.iter().map(|l| u64::from(l.steps)).sum();
            let calls: u64 = mine.iter().map(|l| u64::from(l.llm_calls)).sum();
            let prompt: u64 = mine.iter().map(|l| l.prompt_tokens).sum();
            let completion: u64 = mine.iter().map(|l| l.completion_tokens).sum();
            let cached: u64 = mine.iter().map(|l| l.cached_tokens).sum();
            let n = mine.len().max(1) as f64;
            let per_step = |x: u64| (steps > 0).then(|| x as f64 / steps as f64);
            let cost: Option<f64> = mine.iter().map(|l| l.cost_usd).sum();
            let successes = mine.iter().filter(|l| l.success).count();
            Cost {
                method: m.clone(),
                episodes: mine.len(),
                steps,
                llm_calls: calls,
                prompt_tokens: prompt,
                completion_tokens: completion,
                cached_tokens: cached,
                cached_share: (prompt > 0).then(|| cached as f64 / prompt as f64),
                calls_per_episode: calls as f64 / n,
                tokens_per_episode: (prompt + completion) as f64 / n,
                calls_per_step: per_step(calls),
                tokens_per_step: per_step(prompt + completion),
                cost_usd: cost,
                cost_per_task: cost.map(|c| c / n),
                cost_per_success: cost.filter(|_| successes > 0).map(|c| c / successes as f64),
            }
        })
        .collect();
    let errors = errors(lines);
    let mut method_settings = BTreeMap::new();
    for l in lines {
        if let Some(own) = l
            .settings
            .as_ref()
            .map(|s| &s.method)
            .filter(|m| !m.is_empty())
        {
            method_settings.insert(l.method.clone(), own.clone());
        }
    }
    Report {
        backends: backends.into_iter().collect(),
        seeds: seeds.into_iter().collect(),
        table1,
        table2,
        table3,
        costs,
        unfinished,
        errors: errors.len(),
        untyped_tasks,
        makespan: speedup::build(&finals),
        events: dynamic::build(&finals),
        settings,
        method_settings,
        failures: failures(&errors),
    }
}

/// Table III, by team size (`"3 robots"`), when the tasks have teams of more than one
/// size.
fn team_table(
    methods: &[String],
    finals: &[&ResultLine],
    tasks: &HashMap<(String, i64), &ResultLine>,
) -> Option<Table> {
    let sizes: BTreeSet<u32> = tasks.values().filter_map(|l| l.team_size).collect();
    if sizes.len() < 2 {
        return None;
    }
    let name = |n: u32| format!("{n} robot{}", if n == 1 { "" } else { "s" });
    let mut cols: Vec<String> = sizes.into_iter().map(name).collect();
    cols.push("Avg".into());
    let by_size =
        |l: &ResultLine, col: &str| col == "Avg" || l.team_size.map(name).as_deref() == Some(col);
    Some(table(
        "Table III: success rate (SR) and average steps (AS) by team size",
        &cols,
        methods,
        finals,
        tasks,
        &by_size,
    ))
}

/// The row of `l` in the tables: its method, and its execution when parallel.
fn row_of(l: &ResultLine) -> String {
    row_name(&l.method, l.execution)
}

fn table(
    title: &str,
    columns: &[String],
    methods: &[String],
    finals: &[&ResultLine],
    tasks: &HashMap<(String, i64), &ResultLine>,
    belongs: &dyn Fn(&ResultLine, &str) -> bool,
) -> Table {
    let rows = methods
        .iter()
        .map(|m| Row {
            method: m.clone(),
            cells: columns
                .iter()
                .map(|c| {
                    let mine: Vec<&ResultLine> = finals
                        .iter()
                        .copied()
                        .filter(|l| &row_of(l) == m && belongs(l, c))
                        .collect();
                    cell(&mine)
                })
                .collect(),
        })
        .collect();
    let in_col = |c: &str| -> Vec<&ResultLine> {
        tasks.values().copied().filter(|l| belongs(l, c)).collect()
    };
    Table {
        title: title.to_owned(),
        columns: columns.to_vec(),
        tasks: columns.iter().map(|c| in_col(c).len()).collect(),
        rows,
        gt: columns
            .iter()
            .map(|c| {
                let gts: Vec<f64> = in_col(c)
                    .iter()
                    .filter_map(|l| l.gt_steps.map(f64::from))
                    .collect();
                (!gts.is_empty()).then(|| gts.iter().sum::<f64>() / gts.len() as f64)
            })
            .collect(),
    }
}

/// SR and AS per seed, then their mean and interval over seeds.
fn cell(lines: &[&ResultLine]) -> Option<Cell> {
    let mut per_seed: BTreeMap<u32, (f64, f64, usize)> = BTreeMap::new();
    for l in lines {
        let e = per_seed.entry(l.seed).or_default();
        e.0 += f64::from(u8::from(l.success));
        e.1 += counted_steps(l);
        e.2 += 1;
    }
    let sr: Vec<f64> = per_seed.values().map(|(s, _, n)| s / *n as f64).collect();
    let avg: Vec<f64> = per_seed.values().map(|(_, a, n)| a / *n as f64).collect();
    Some(Cell {
        episodes: lines.len(),
        sr: Stat::of(&sr)?,
        avg_steps: Stat::of(&avg)?,
    })
}

fn header_lines(r: &Report) -> Vec<String> {
    let backend = if r.backends.is_empty() {
        "none (no method here asks a model)".to_owned()
    } else {
        r.backends.join("; ")
    };
    let mut out = vec![format!("Backend: {backend}")];
    out.push(match &r.settings {
        Some(s) => format!("Settings: {}", s.summary()),
        None => "Settings: not recorded (results written before lines kept them)".to_owned(),
    });
    for (method, own) in &r.method_settings {
        out.push(format!("Settings of {method}: {}", method_text(own)));
    }
    let seeds = r.seeds.len();
    out.push(if seeds > 1 {
        format!(
            "Seeds: {seeds}; each cell is the mean over seeds ± the half-width of a 95% confidence interval (Student's t, df = seeds - 1)"
        )
    } else {
        format!("Seeds: {seeds}")
    });
    out.push("AS counts a failed episode as 2 x GT + 1 steps.".into());
    if r.untyped_tasks > 0 {
        out.push(format!(
            "{} task(s) have no plan (no type): they count in Avg only.",
            r.untyped_tasks
        ));
    }
    let others = r.unfinished - r.errors;
    if others > 0 {
        out.push(format!(
            "{others} episode(s) have no final result (the backend failed or the run was interrupted) and are left out; run the same command again to finish them."
        ));
    }
    if r.errors > 0 {
        out.push(format!(
            "{} episode(s) failed with an error (the method's own, a robot that stopped answering, a transcript that could not be created) and are left out (see \"Episodes that failed with an error\").",
            r.errors
        ));
    }
    out
}

/// The failed episodes by method, in Markdown; empty without any.
fn failures_markdown(r: &Report) -> String {
    if r.failures.is_empty() {
        return String::new();
    }
    let mut out = String::from(
        "### Episodes that failed with an error\n\n| Method | Episodes | First error | Its transcript (a method's whole traceback) |\n|---|---|---|---|\n",
    );
    for f in &r.failures {
        out.push_str(&format!(
            "| {} | {} | {} | {} |\n",
            f.method,
            f.episodes,
            f.first_error.replace('|', "\\|"),
            f.transcript
        ));
    }
    out.push('\n');
    out
}

fn stat_text(s: &Stat, decimals: usize) -> String {
    match s.ci95 {
        Some(ci) => format!("{:.decimals$} ± {ci:.decimals$}", s.mean),
        None => format!("{:.decimals$}", s.mean),
    }
}

fn column_name(c: &str) -> String {
    match c {
        "mono" => "Mono".into(),
        "dual" => "Dual".into(),
        "trio" => "Trio".into(),
        other => other.to_owned(),
    }
}

/// A name from a results line in a Markdown cell: escaped for a terminal ([`shown`]),
/// and its `|` escaped, which would end the cell.
fn md(name: &str) -> String {
    shown(name).replace('|', "\\|")
}

/// The tables in Markdown, the paper's layout: one row per method, `SR / AS` per column.
/// Names from the results (methods, scenes, backends) are shown escaped.
pub fn markdown(r: &Report) -> String {
    let mut out = String::new();
    for t in [Some(&r.table1), Some(&r.table2), r.table3.as_ref()]
        .into_iter()
        .flatten()
    {
        out.push_str(&format!("### {}\n\n", t.title));
        for h in header_lines(r) {
            out.push_str(&format!("{}  \n", shown(&h)));
        }
        out.push('\n');
        let heads: Vec<String> = t
            .columns
            .iter()
            .zip(&t.tasks)
            .map(|(c, n)| format!("{} (n={n}) SR / AS", md(&column_name(c))))
            .collect();
        out.push_str(&format!("| Method | {} |\n", heads.join(" | ")));
        out.push_str(&format!("|---|{}\n", "---|".repeat(heads.len())));
        for row in &t.rows {
            let cells: Vec<String> = row
                .cells
                .iter()
                .map(|c| match c {
                    Some(c) => format!("{} / {}", stat_text(&c.sr, 3), stat_text(&c.avg_steps, 1)),
                    None => "-".into(),
                })
                .collect();
            out.push_str(&format!(
                "| {} | {} |\n",
                md(&row.method),
                cells.join(" | ")
            ));
        }
        let gt: Vec<String> =
            t.gt.iter()
                .map(|g| g.map_or("- / -".into(), |g| format!("- / {g:.1}")))
                .collect();
        out.push_str(&format!("| Ground truth | {} |\n\n", gt.join(" | ")));
    }
    out.push_str(&failures_markdown(r));
    out.push_str("### LLM calls, tokens and cost per method\n\n");
    out.push_str(&format!("{}  \n", shown(&header_lines(r)[0])));
    out.push_str(
        "Cached: the share of prompt tokens the servers read from their prompt caches. Cost \
         in USD from each episode's `cost_usd` (cached tokens at the cached input price); - \
         where a model has no price.  \n\n",
    );
    out.push_str("| Method | Episodes | Steps | LLM calls / episode | Tokens / episode | LLM calls / step | Tokens / step | Cached | Cost / task | Cost / success |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for c in &r.costs {
        let opt = |x: Option<f64>, d: usize| x.map_or("-".into(), |x| format!("{x:.d$}"));
        out.push_str(&format!(
            "| {} | {} | {} | {:.2} | {:.0} | {} | {} | {} | {} | {} |\n",
            md(&c.method),
            c.episodes,
            c.steps,
            c.calls_per_episode,
            c.tokens_per_episode,
            opt(c.calls_per_step, 2),
            opt(c.tokens_per_step, 0),
            opt(c.cached_share, 2),
            opt(c.cost_per_task, 6),
            opt(c.cost_per_success, 6)
        ));
    }
    if !r.makespan.is_empty() {
        out.push('\n');
        out.push_str(&speedup::markdown(&r.makespan, md));
    }
    if !r.events.is_empty() {
        out.push('\n');
        out.push_str(&dynamic::markdown(&r.events, md));
    }
    out
}

/// A field of the CSV: escaped for a terminal ([`shown`]: no line break or control
/// character stays raw), quoted when it holds a comma or a quote.
fn csv_field(s: &str) -> String {
    let s = shown(s);
    if s.contains([',', '"']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.into_owned()
    }
}

/// One CSV: a row per (table, method, column), ground-truth rows with `method` =
/// `ground truth`, and a `costs` row per method (with its cost per task and per success
/// in USD, empty where a model has no price, and the share of its prompt tokens read
/// from the servers' caches); every row has the seeds, the backend and the settings. A
/// run with parallel episodes adds seven columns after those (`execution` and the
/// makespan table's numbers) and a `makespan` row per method, execution and task type.
pub fn csv(r: &Report) -> String {
    let backend = csv_field(&r.backends.join("; "));
    let settings = csv_field(
        &r.settings
            .as_ref()
            .map_or_else(String::new, RunSettings::summary),
    );
    let backend = format!("{backend},{settings}");
    let mut out = String::from(
        "table,method,column,tasks,episodes,sr,sr_ci95,as,as_ci95,gt,calls_per_episode,tokens_per_episode,calls_per_step,tokens_per_step,cost_per_task,cost_per_success,seeds,backend,settings,cached_share",
    );
    if !r.makespan.is_empty() {
        out.push_str(
            ",execution,makespan,optimal_makespan,actions,calls_per_action,sim_seconds,speedup",
        );
    }
    out.push('\n');
    let num = |x: Option<f64>| x.map_or(String::new(), |x| format!("{x:.6}"));
    // Dollars in full: a small model's cost per task is a millionth of one.
    let usd = |x: Option<f64>| x.map_or(String::new(), |x| x.to_string());
    let seeds = r.seeds.len();
    // The makespan table's columns, empty in the other tables' rows.
    let pad = if r.makespan.is_empty() { "" } else { ",,,,,,," };
    let tables = [
        ("I", Some(&r.table1)),
        ("II", Some(&r.table2)),
        ("III", r.table3.as_ref()),
    ];
    for (name, t) in tables.into_iter().filter_map(|(n, t)| t.map(|t| (n, t))) {
        for row in &t.rows {
            for ((c, n), cell) in t.columns.iter().zip(&t.tasks).zip(&row.cells) {
                let Some(cell) = cell else { continue };
                out.push_str(&format!(
                    "{name},{},{},{n},{},{},{},{},{},,,,,,,,{seeds},{backend},{pad}\n",
                    csv_field(&row.method),
                    csv_field(c),
                    cell.episodes,
                    num(Some(cell.sr.mean)),
                    num(cell.sr.ci95),
                    num(Some(cell.avg_steps.mean)),
                    num(cell.avg_steps.ci95),
                ));
            }
        }
        for ((c, n), gt) in t.columns.iter().zip(&t.tasks).zip(&t.gt) {
            out.push_str(&format!(
                "{name},ground truth,{},{n},,,,,,{},,,,,,,{seeds},{backend},{pad}\n",
                csv_field(c),
                num(*gt)
            ));
        }
    }
    for c in &r.costs {
        out.push_str(&format!(
            "costs,{},all,,{},,,,,,{},{},{},{},{},{},{seeds},{backend},{}{pad}\n",
            csv_field(&c.method),
            c.episodes,
            num(Some(c.calls_per_episode)),
            num(Some(c.tokens_per_episode)),
            num(c.calls_per_step),
            num(c.tokens_per_step),
            usd(c.cost_per_task),
            usd(c.cost_per_success),
            num(c.cached_share),
        ));
    }
    for m in &r.makespan {
        out.push_str(&format!(
            "makespan,{},{},,{},{},,,,,,,,,,,{seeds},{backend},,{},{},{},{},{},{},{}\n",
            csv_field(&row_name(&m.method, m.execution)),
            m.column,
            m.episodes,
            num(Some(m.sr)),
            m.execution,
            num(m.makespan),
            num(m.optimal_makespan),
            num(m.actions),
            num(m.calls_per_action),
            num(m.sim_seconds),
            num(m.speedup),
        ));
    }
    out
}

/// The whole report as one JSON object.
pub fn json(r: &Report) -> String {
    serde_json::to_string_pretty(r).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}

/// Lines of one set of run-wide settings (`None`: lines that record none).
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    pub settings: Option<RunSettings>,
    pub lines: Vec<ResultLine>,
}

/// The lines by their run-wide settings, in the order each set first appears: the
/// tables are made of one group at a time.
pub fn groups(lines: &[ResultLine]) -> Vec<Group> {
    let mut out: Vec<Group> = Vec::new();
    for line in lines {
        let settings = line.settings.as_ref().map(RunSettings::run_wide);
        match out.iter_mut().find(|g| g.settings == settings) {
            Some(group) => group.lines.push(line.clone()),
            None => out.push(Group {
                settings,
                lines: vec![line.clone()],
            }),
        }
    }
    out
}

/// The settings in which the groups differ (run-wide), each once, in [`Setting`] order.
pub fn differing(groups: &[Group]) -> Vec<Setting> {
    let mut out: Vec<Setting> = Vec::new();
    let first = groups.first().and_then(|g| g.settings.as_ref());
    for g in groups.iter().skip(1) {
        let found = match (first, &g.settings) {
            (Some(a), Some(b)) => a.differences(b).into_iter().map(|d| d.setting).collect(),
            _ => vec![Setting::Unrecorded],
        };
        for s in found {
            if !out.contains(&s) {
                out.push(s);
            }
        }
    }
    out.sort();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_quantiles() {
        assert_eq!(t975(1), 12.706);
        assert_eq!(t975(30), 2.042);
        assert_eq!(t975(31), 1.96);
    }

    #[test]
    fn one_value_has_no_interval() {
        let s = Stat::of(&[0.5]).expect("one value");
        assert_eq!(
            s,
            Stat {
                mean: 0.5,
                ci95: None
            }
        );
        assert!(Stat::of(&[]).is_none());
    }
}
