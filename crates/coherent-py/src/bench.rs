//! The benchmark: picking a subset, running methods x tasks x seeds into a results file,
//! and the paper's tables of the results, through the session layer
//! (`coherent::session::bench`) as `coherent bench` does.

use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;

use coherent::session;
use coherent::session::backend::{BackendKind, BackendProblem, BackendRequest};
use coherent::session::bench::{self as session_bench, TableFormat};
use coherent_agents::Cancel;
use coherent_agents::bench::{
    self, BackendChoice, BenchConfig, BenchOutcome, Event, Progress, ResultLine, Subset,
};
use coherent_agents::episode::Method;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};

use crate::convert::{interruptible, py_to_json, to_py};
use crate::errors;
use crate::run::{PyLlm, method_of};
use crate::task::PyTask;

/// `"all"`, `"paper40"`, a file of `scene task_id` lines, or a list of `(scene, task_id)`.
fn subset_of(subset: &Bound<'_, PyAny>) -> PyResult<Subset> {
    if let Ok(s) = subset.cast::<PyString>()
        && let Some(named) = Subset::named(&s.to_cow()?)
    {
        return Ok(named);
    }
    if let Ok(path) = subset.extract::<PathBuf>() {
        return Subset::read_file(&path).map_err(|e| errors::coherent(subset.py(), e));
    }
    subset
        .extract::<Vec<(String, i64)>>()
        .map(Subset::Listed)
        .map_err(|_| {
            PyTypeError::new_err(
                "subset: expected \"all\", \"paper40\", \"native40\", a path to a file of \
                 `scene task_id` lines, or a list of (scene, task_id) pairs",
            )
        })
}

/// The tasks picked, and the `(scene, task_id)` pairs named but missing.
type Selected = (Vec<PyTask>, Vec<(String, i64)>);

/// The tasks `subset` picks from `tasks`, in the subset's order, and the
/// `(scene, task_id)` pairs it names that are not among them.
#[pyfunction]
pub(crate) fn select(
    tasks: Vec<Bound<'_, PyTask>>,
    subset: &Bound<'_, PyAny>,
) -> PyResult<Selected> {
    let subset = subset_of(subset)?;
    let owned = tasks.iter().map(|t| (*t.get().task).clone()).collect();
    let selection = bench::select(owned, &subset).map_err(PyValueError::new_err)?;
    Ok((
        selection.tasks.into_iter().map(PyTask::shared).collect(),
        selection.missing,
    ))
}

pub(crate) fn outcome_dict<'py>(py: Python<'py>, o: &BenchOutcome) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("total", o.total)?;
    d.set_item("skipped", o.skipped)?;
    d.set_item("written", o.written)?;
    d.set_item("unfinished", o.unfinished)?;
    d.set_item("interrupted", o.interrupted)?;
    d.set_item("skipped_tasks", &o.skipped_tasks)?;
    d.set_item("repaired_bytes", o.repaired_bytes)?;
    d.set_item("orphaned", &o.orphaned)?;
    Ok(d)
}

/// The methods of a run, checked with its seeds and tasks as `coherent.bench` checks them.
pub(crate) fn run_methods(methods: &[String], seeds: u32, tasks: usize) -> PyResult<Vec<Method>> {
    let methods = methods
        .iter()
        .map(|m| method_of(m))
        .collect::<PyResult<Vec<_>>>()?;
    if methods.is_empty() {
        return Err(PyValueError::new_err("methods: name at least one method"));
    }
    if seeds == 0 {
        return Err(PyValueError::new_err("seeds must be at least 1"));
    }
    if tasks == 0 {
        return Err(PyValueError::new_err("tasks: no tasks to run"));
    }
    Ok(methods)
}

/// The backend `coherent.bench`'s `backend`, `sim_errors` and `replay_from` ask for, and
/// the temperature the episodes record (an LLM's).
pub(crate) fn run_backend(
    py: Python<'_>,
    backend: Option<&Bound<'_, PyAny>>,
    sim_errors: Option<&Bound<'_, PyAny>>,
    replay_from: Option<PathBuf>,
) -> PyResult<(BackendChoice, Option<f32>)> {
    let (kind, endpoint) = match backend {
        Some(b) if b.is_instance_of::<PyLlm>() => (
            BackendKind::OpenAi,
            Some(b.cast::<PyLlm>()?.get().config.clone()),
        ),
        None => (BackendKind::Builtin, None),
        Some(b) => match b.extract::<String>().as_deref() {
            Ok("builtin") => (BackendKind::Builtin, None),
            Ok("simulated") => (BackendKind::Simulated, None),
            Ok("replay") => (BackendKind::Replay, None),
            _ => {
                return Err(PyValueError::new_err(format!(
                    "backend {}: expected \"builtin\", \"simulated\", \"replay\" or an LLM",
                    b.repr()?
                )));
            }
        },
    };
    let temperature = endpoint.as_ref().map(|c| c.temperature);
    let choice = BackendRequest {
        kind,
        endpoint,
        sim_errors: crate::run::error_rates(sim_errors)?,
        replay_from,
    }
    .choose()
    .map_err(|e| match e {
        BackendProblem::RatesNeedSimulated | BackendProblem::RatesAndEndpoint => {
            PyValueError::new_err("sim_errors needs backend=\"simulated\"")
        }
        BackendProblem::ReplayNeedsFile => {
            PyValueError::new_err("backend=\"replay\" needs replay_from=, an earlier results file")
        }
        BackendProblem::FileNeedsReplay => {
            PyValueError::new_err("replay_from needs backend=\"replay\"")
        }
        other => errors::coherent(py, other.to_string()),
    })?;
    Ok((choice, temperature))
}

/// Runs every method on every task for every seed into the results file `out` (JSON
/// lines, appended, resumable: finished episodes are skipped), as `coherent bench`
/// does. Returns what the run did.
#[pyfunction]
#[pyo3(signature = (
    tasks, methods, *, backend = None, sim_errors = None, replay_from = None, seeds = 1,
    concurrency = 4, history = 5, max_states = 5_000_000, out = PathBuf::from("results.jsonl"),
    progress = false
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_bench<'py>(
    py: Python<'py>,
    tasks: Vec<Bound<'py, PyTask>>,
    methods: Vec<String>,
    backend: Option<&Bound<'py, PyAny>>,
    sim_errors: Option<&Bound<'py, PyAny>>,
    replay_from: Option<PathBuf>,
    seeds: u32,
    concurrency: usize,
    history: usize,
    max_states: usize,
    out: PathBuf,
    progress: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let methods = run_methods(&methods, seeds, tasks.len())?;
    let (choice, temperature) = run_backend(py, backend, sim_errors, replay_from)?;
    let tasks: Vec<_> = tasks.iter().map(|t| Arc::clone(&t.get().task)).collect();
    let config = BenchConfig {
        methods,
        seeds,
        concurrency: concurrency.max(1),
        backend: choice,
        history,
        temperature,
        max_states,
        out,
    };
    let cancel = Cancel::default();
    let stop = cancel.clone();
    let result = interruptible(
        py,
        move || stop.cancel(),
        move || {
            let mut lines = Progress::new(false);
            let mut show = |e: Event<'_>| {
                if let Some(text) = lines.line(&e).filter(|_| progress) {
                    let _ = std::io::stderr().write_all(text.as_bytes());
                }
            };
            session::block_on(session_bench::run(&tasks, &config, &cancel, &mut show))?
        },
    )?;
    let outcome = result.map_err(|e| errors::coherent(py, e))?;
    outcome_dict(py, &outcome)
}

/// The lines of a results file, as dicts; a last line cut off mid-write is left out.
#[pyfunction]
pub(crate) fn read_results(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyList>> {
    let file = py
        .detach(|| bench::read_results(&path))
        .map_err(|e| errors::coherent(py, e))?;
    let list = PyList::empty(py);
    for line in &file.lines {
        list.append(to_py(py, line)?)?;
    }
    Ok(list)
}

/// Results lines (dicts with the results file's fields) as the harness's type; errors
/// name the line and the field.
fn result_lines(lines: &Bound<'_, PyList>) -> PyResult<Vec<ResultLine>> {
    lines
        .iter()
        .enumerate()
        .map(|(i, item)| {
            let value = py_to_json(&item)?;
            serde_json::from_value(value)
                .map_err(|e| PyValueError::new_err(format!("results line {i}: {e}")))
        })
        .collect()
}

/// The paper's tables of results lines: Table I (by task type), Table II (by scene),
/// the costs, as `coherent bench --report FILE --format json` gives them.
#[pyfunction]
pub(crate) fn report_tables<'py>(
    py: Python<'py>,
    lines: &Bound<'py, PyList>,
) -> PyResult<Bound<'py, PyAny>> {
    let lines = result_lines(lines)?;
    to_py(py, &coherent_agents::report::build(&lines))
}

/// The tables as text: `"markdown"`, `"csv"` or `"json"`, as `coherent bench --report`
/// prints them.
#[pyfunction]
#[pyo3(signature = (lines, format = "markdown"))]
pub(crate) fn report_text(lines: &Bound<'_, PyList>, format: &str) -> PyResult<String> {
    let lines = result_lines(lines)?;
    let format = TableFormat::from_name(format).ok_or_else(|| {
        PyValueError::new_err(format!(
            "format {format:?}: expected \"markdown\", \"csv\" or \"json\""
        ))
    })?;
    Ok(session_bench::tables(&lines, format))
}
