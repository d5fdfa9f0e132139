//! The benchmark: picking a subset, running methods x tasks x seeds into a results file,
//! and the paper's tables of the results, through the session layer
//! (`coherent::session::bench`) as `coherent bench` does.

use std::ffi::CString;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use coherent::session::backend::{BackendName, BackendRequest, EndpointSource};
use coherent::session::bench::{self as session_bench, BenchConfig, EpisodesRequest, TableFormat};
use coherent::session::engine::{
    BenchOutcome, Cancel, DEFAULT_MAX_RESULTS_BYTES, Event, Execution, HISTORY_WINDOW, Limits,
    MethodSpec, Progress, Report, ResultLine, Setting, Style, Subset,
    read_results as read_results_file, select as select_tasks, setting_field,
};
use coherent::session::error::BackendProblem;
use coherent::session::{self, Error};
use pyo3::exceptions::{PyOverflowError, PyTypeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};

use crate::convert::{self, interruptible, to_py};
use crate::errors::PyCoherentResult;
use crate::llm::PyLlm;
use crate::method::{MethodArg, Methods};
use crate::prompts::{price_source, prompt_source};
use crate::task::{PyTask, robots_arg};
use crate::{args, errors};
use coherent::session::prompts::PriceSource;

/// `"all"`, `"paper40"`, a file of `scene task_id` lines, or a list of `(scene, task_id)`.
fn subset_of(subset: &Bound<'_, PyAny>) -> PyCoherentResult<Subset> {
    let py = subset.py();
    // A str that is not text (a lone surrogate) may still be a file's name.
    if let Ok(s) = subset.cast::<PyString>()
        && let Some(named) = convert::utf8(s).ok().and_then(Subset::named)
    {
        return Ok(named);
    }
    match convert::path(subset, "subset") {
        Ok(path) => {
            return Ok(session_bench::subset_file(&path)?);
        }
        // A `TypeError`: no path, so maybe pairs; else a path that names no file.
        Err(e) if !e.is_instance_of::<PyTypeError>(py) => return Err(e.into()),
        Err(_) => {}
    }
    let wrong = || {
        PyTypeError::new_err(
            "subset: expected \"all\", \"paper40\", \"native40\", a path to a file of \
             `scene task_id` lines, or a list of (scene, task_id) pairs",
        )
    };
    let pairs = subset
        .extract::<Vec<Bound<'_, PyAny>>>()
        .map_err(|_| wrong())?;
    let mut listed = Vec::with_capacity(pairs.len());
    for (i, pair) in pairs.iter().enumerate() {
        let Ok((scene, task_id)) = pair.extract::<(Bound<'_, PyAny>, Bound<'_, PyAny>)>() else {
            return Err(wrong().into());
        };
        if !scene.is_instance_of::<PyString>() {
            return Err(wrong().into());
        }
        let scene = convert::text(&scene, &format!("subset[{i}][0]"))?.to_owned();
        let task_id = match task_id.extract::<i64>() {
            Ok(id) => id,
            Err(e) if e.is_instance_of::<PyOverflowError>(py) => {
                let why = "beyond the 64 bits of task ids";
                return Err(errors::argument(&format!("subset[{i}][1]"), &task_id, why).into());
            }
            Err(_) => return Err(wrong().into()),
        };
        listed.push((scene, task_id));
    }
    Ok(Subset::Listed(listed))
}

/// The tasks picked, and the `(scene, task_id)` pairs named but missing.
type Selected = (Vec<PyTask>, Vec<(String, i64)>);

/// The tasks `subset` picks from `tasks`, in the subset's order, and the
/// `(scene, task_id)` pairs it names that are not among them.
#[pyfunction]
pub(crate) fn select(
    py: Python<'_>,
    tasks: Vec<Bound<'_, PyTask>>,
    subset: &Bound<'_, PyAny>,
) -> PyResult<Selected> {
    let subset = subset_of(subset)?;
    let owned = tasks.iter().map(|t| (*t.get().task).clone()).collect();
    // The argument the fault is in, which the selection does not know.
    let selection =
        select_tasks(owned, &subset).map_err(|e| errors::invalid(py, format!("tasks: {e}")))?;
    Ok((
        selection.tasks.into_iter().map(PyTask::shared).collect(),
        selection.missing,
    ))
}

/// How `progress` asks for the run's progress to be shown: `"bar"` (redrawn in place),
/// `"lines"` (one per episode) or None (not at all).
pub(crate) fn progress_style(py: Python<'_>, progress: Option<&str>) -> PyResult<Option<Style>> {
    match progress {
        None => Ok(None),
        Some("bar") => Ok(Some(Style::Bar)),
        Some("lines") => Ok(Some(Style::Lines)),
        Some(other) => Err(errors::choice(
            py,
            "progress",
            other,
            "expected \"bar\", \"lines\" or None",
        )),
    }
}

/// Writes `text` to Python's `sys.stderr` (which a notebook shows in the cell, where
/// the process's own stderr would not be seen), taking the GIL for it.
pub(crate) fn to_stderr(text: &str) {
    Python::attach(|py| {
        if let Ok(stderr) = py.import("sys").and_then(|sys| sys.getattr("stderr")) {
            let _ = stderr.call_method1("write", (text,));
            let _ = stderr.call_method0("flush");
        }
    });
}

pub(crate) fn outcome_dict<'py>(py: Python<'py>, o: &BenchOutcome) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("total", o.total)?;
    d.set_item("skipped", o.skipped)?;
    d.set_item("written", o.written)?;
    d.set_item("finished", o.finished)?;
    d.set_item("unfinished", o.unfinished)?;
    d.set_item("method_errors", o.method_errors)?;
    d.set_item("not_started", o.not_started)?;
    d.set_item("interrupted", o.interrupted)?;
    d.set_item("skipped_tasks", &o.skipped_tasks)?;
    d.set_item("repaired_bytes", o.repaired_bytes)?;
    let orphaned: Vec<String> = o.orphaned.iter().map(|p| p.display().to_string()).collect();
    d.set_item("orphaned", orphaned)?;
    Ok(d)
}

/// The methods of a run, checked with its seeds and tasks as `coherent.bench` checks
/// them; those written in Python are added to `python` (`tasks`: the run's). A run that
/// replays the results file `replay` runs the recorded methods (by name: one written in
/// Python needs no code then).
pub(crate) fn run_methods(
    py: Python<'_>,
    methods: &[MethodArg],
    seeds: u32,
    tasks: &[Py<PyTask>],
    python: &mut Methods,
    replay: Option<&Path>,
) -> PyResult<Vec<MethodSpec>> {
    let methods = methods
        .iter()
        .map(|m| match replay {
            Some(results) => m.recorded(py, results),
            None => m.spec(py, python, tasks),
        })
        .collect::<PyCoherentResult<Vec<_>>>()?;
    if methods.is_empty() {
        return Err(errors::invalid(py, "methods: name at least one method"));
    }
    // The argument, and the attribute that names a method written in Python.
    session_bench::distinct_names(&methods)
        .map_err(|e| errors::invalid(py, format!("methods: {e} (its `name`)")))?;
    if seeds == 0 {
        return Err(errors::invalid(py, "seeds must be at least 1"));
    }
    if tasks.is_empty() {
        return Err(errors::invalid(py, "tasks: no tasks to run"));
    }
    Ok(methods)
}

/// The results file a run replays: `replay_from` when `backend` is `"replay"`.
pub(crate) fn replaying<'a>(
    backend: Option<&Bound<'_, PyAny>>,
    replay_from: Option<&'a Path>,
) -> Option<&'a Path> {
    let replay = backend
        .and_then(|b| b.cast::<PyString>().ok())
        .is_some_and(|b| convert::utf8(b).is_ok_and(|name| name == "replay"));
    replay_from.filter(|_| replay)
}

/// The backend `coherent.bench`'s `backend`, `sim_errors` and `replay_from` ask for
/// (`prompts`: whether a prompt set was given, which a replay refuses).
pub(crate) fn run_backend(
    backend: Option<&Bound<'_, PyAny>>,
    sim_errors: Option<&Bound<'_, PyAny>>,
    replay_from: Option<PathBuf>,
    prompts: bool,
) -> PyResult<BackendRequest> {
    let (name, endpoint) = match backend {
        Some(b) if b.is_instance_of::<PyLlm>() => (
            BackendName::OpenAi,
            EndpointSource::Client(Arc::clone(&b.cast::<PyLlm>()?.get().client)),
        ),
        None => (BackendName::Builtin, EndpointSource::None),
        Some(b) => match b.cast::<PyString>().map(convert::utf8) {
            Ok(Ok("builtin")) => (BackendName::Builtin, EndpointSource::None),
            Ok(Ok("simulated")) => (BackendName::Simulated, EndpointSource::None),
            Ok(Ok("replay")) if prompts => {
                return Err(PyValueError::new_err(
                    "prompts= and backend=\"replay\" do not go together: a replay renders \
                     the prompt set its transcripts recorded",
                ));
            }
            Ok(Ok("replay")) => (BackendName::Replay, EndpointSource::None),
            _ => {
                let expected = "expected \"builtin\", \"simulated\", \"replay\" or an LLM";
                return Err(errors::argument("backend", b, expected));
            }
        },
    };
    Ok(BackendRequest {
        name,
        endpoint,
        sim_errors: crate::run::error_rates(sim_errors)?,
        replay_from,
        ..BackendRequest::default()
    })
}

/// The exception of an error in preparing a run's episodes: the backend's problems
/// worded with `coherent.bench`'s keyword arguments, the others by their kind. Its call
/// sites convert with it, not with `?`: the wording is `coherent.bench`'s, which the
/// conversion of the session's errors (the neutral words) cannot know.
pub(crate) fn settings_err(py: Python<'_>, e: Error) -> PyErr {
    let Error::Backend(problem) = &e else {
        return errors::session_err(py, e);
    };
    let message = match problem {
        BackendProblem::RatesNeedSimulated | BackendProblem::RatesAndEndpoint => {
            "sim_errors needs backend=\"simulated\""
        }
        BackendProblem::ReplayNeedsFile => {
            "backend=\"replay\" needs replay_from=, an earlier results file"
        }
        BackendProblem::FileNeedsReplay => "replay_from needs backend=\"replay\"",
        BackendProblem::NoEndpoint | BackendProblem::ReplayIsForBenchmarks => {
            return errors::session_err(py, e);
        }
    };
    errors::invalid(py, message)
}

/// Runs every method on every task for every seed into the results file `out` (JSON
/// lines, appended, resumable: finished episodes are skipped), as `coherent bench`
/// does, with the prompt set `prompts` and each line priced from `prices`; with
/// `physics`, every action in Rapier too; with `robots="ros2"`, carried out by robots
/// over ROS 2 (one episode at a time). Returns what the run did.
#[pyfunction]
#[pyo3(signature = (
    tasks, methods, *, execution = vec![Execution::Sequential], backend = None,
    sim_errors = None, replay_from = None, seeds = 1,
    concurrency = 4, history = HISTORY_WINDOW, max_states = Limits::DEFAULT_MAX_STATES,
    max_steps = None, out = None, progress = None, prompts = None,
    prices = None, physics = false, robots = "local", namespace = None, robot_timeout = 10.0,
    server_wait = 10.0, step_timeout = None
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_bench<'py>(
    py: Python<'py>,
    tasks: Vec<Bound<'py, PyTask>>,
    #[pyo3(from_py_with = args::methods)] methods: Vec<MethodArg>,
    #[pyo3(from_py_with = args::executions)] execution: Vec<Execution>,
    backend: Option<&Bound<'py, PyAny>>,
    sim_errors: Option<&Bound<'py, PyAny>>,
    #[pyo3(from_py_with = args::replay_from)] replay_from: Option<PathBuf>,
    #[pyo3(from_py_with = args::seeds)] seeds: u32,
    #[pyo3(from_py_with = args::concurrency)] concurrency: usize,
    #[pyo3(from_py_with = args::history)] history: usize,
    #[pyo3(from_py_with = args::max_states)] max_states: usize,
    #[pyo3(from_py_with = args::max_steps)] max_steps: Option<u32>,
    #[pyo3(from_py_with = args::results_out)] out: Option<PathBuf>,
    progress: Option<&str>,
    prompts: Option<&Bound<'py, PyAny>>,
    prices: Option<&Bound<'py, PyAny>>,
    physics: bool,
    robots: &str,
    namespace: Option<&str>,
    robot_timeout: f64,
    server_wait: f64,
    #[pyo3(from_py_with = args::step_timeout)] step_timeout: Option<Duration>,
) -> PyCoherentResult<Bound<'py, PyDict>> {
    let style = progress_style(py, progress)?;
    let prompts_given = prompts.is_some();
    let request = EpisodesRequest {
        prompts: prompt_source(prompts)?,
        prices: price_source(prices)?,
        backend: run_backend(backend, sim_errors, replay_from.clone(), prompts_given)?,
        robots: robots_arg(py, robots, namespace, robot_timeout, server_wait)?,
        physics,
        history,
        max_states,
        max_steps,
        executions: execution,
        ..EpisodesRequest::new(Vec::new())
    };
    let objects: Vec<Py<PyTask>> = tasks.iter().map(|t| t.clone().unbind()).collect();
    let mut python = Methods::new(py, step_timeout)?;
    let replay = replaying(backend, replay_from.as_deref());
    let methods = run_methods(py, &methods, seeds, &objects, &mut python, replay)?;
    let settings = EpisodesRequest { methods, ..request }
        .prepare()
        .map_err(|e| settings_err(py, e))?;
    let tasks: Vec<_> = tasks.iter().map(|t| Arc::clone(&t.get().task)).collect();
    let out = out.unwrap_or_else(|| session_bench::default_out(&settings, seeds));
    let config = BenchConfig {
        episodes: settings,
        seeds,
        concurrency: concurrency.max(1),
        out,
        max_results_bytes: DEFAULT_MAX_RESULTS_BYTES,
    };
    if let Some(note) = config.concurrency_note() {
        let message = CString::new(note).unwrap_or_default();
        PyErr::warn(py, &py.get_type::<PyUserWarning>(), &message, 1)?;
    }
    let config_out = config.out.display().to_string();
    let cancel = Cancel::default();
    let stop = cancel.clone();
    let result = interruptible(
        py,
        move || stop.cancel(),
        move || {
            let mut lines = style.map(Progress::new);
            let mut show = |e: Event<'_>| {
                if let Some(text) = lines.as_mut().and_then(|p| p.line(&e)) {
                    to_stderr(&text);
                }
            };
            let ran = session::block_on(session_bench::run(&tasks, &config, &cancel, &mut show));
            if style == Some(Style::Bar) {
                to_stderr("\n");
            }
            ran?
        },
    );
    python.close(py)?;
    let outcome = result??;
    let d = outcome_dict(py, &outcome)?;
    d.set_item("out", &config_out)?;
    Ok(d)
}

/// The lines of a results file, as dicts; a last line cut off mid-write is left out.
/// With `prices`, each line's `cost_usd` is its recorded tokens at those prices.
#[pyfunction]
#[pyo3(signature = (path, prices = None))]
pub(crate) fn read_results<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = args::path)] path: PathBuf,
    prices: Option<&Bound<'py, PyAny>>,
) -> PyCoherentResult<Bound<'py, PyList>> {
    let prices = price_source(prices)?;
    let file = py.detach(|| read_results_file(&path))?;
    let lines = priced(file.lines, prices)?;
    let list = PyList::empty(py);
    for line in &lines {
        list.append(to_py(py, line)?)?;
    }
    Ok(list)
}

/// `lines` priced anew from their tokens at `prices`, or as they are without.
fn priced(lines: Vec<ResultLine>, prices: PriceSource) -> PyCoherentResult<Vec<ResultLine>> {
    if prices == PriceSource::Builtin {
        return Ok(lines);
    }
    Ok(session_bench::priced(lines, prices)?)
}

/// Results lines (dicts with the results file's fields) as the harness's type; errors
/// name the line and the field.
pub(crate) fn result_lines(lines: &Bound<'_, PyList>) -> PyResult<Vec<ResultLine>> {
    lines
        .iter()
        .enumerate()
        .map(|(i, item)| {
            let value = convert::json_at(&item, &format!("lines[{i}]"))?;
            // The line's index, which the parser does not know.
            serde_json::from_value(value)
                .map_err(|e| errors::invalid(lines.py(), format!("results line {i}: {e}")))
        })
        .collect()
}

/// Results lines with each `cost_usd` worked out anew from their recorded tokens at
/// `prices` (a price file or a dict by model, added to the built-in table).
#[pyfunction]
pub(crate) fn price_lines<'py>(
    lines: &Bound<'py, PyList>,
    prices: &Bound<'py, PyAny>,
) -> PyCoherentResult<Bound<'py, PyList>> {
    let py = lines.py();
    let source = price_source(Some(prices))?;
    let priced = session_bench::priced(result_lines(lines)?, source)?;
    let list = PyList::empty(py);
    for line in &priced {
        list.append(to_py(py, line)?)?;
    }
    Ok(list)
}

/// The report of results lines of one set of settings; lines of several are an
/// `ArgumentError` that says how to pick one.
fn report_of(lines: &Bound<'_, PyList>) -> PyResult<Report> {
    let py = lines.py();
    let lines = result_lines(lines)?;
    // Which rows to pick, in pandas: Python's words, not the session's.
    session_bench::report(&lines).map_err(|mixed| {
        let example = match mixed.differing.first() {
            Some(&setting) if setting != Setting::Unrecorded => {
                let column = format!("settings_{}", setting_field(setting));
                let value = mixed
                    .groups
                    .first()
                    .and_then(|(s, _)| s.as_ref())
                    .and_then(|s| serde_json::to_value(s).ok())
                    .and_then(|v| v.get(setting_field(setting)).cloned())
                    .unwrap_or_default();
                match value {
                    serde_json::Value::Null => format!("df[df.{column}.isna()]"),
                    v => format!("df[df.{column} == {}]", py_literal(&v)),
                }
            }
            _ => "df[df.settings_backend.notna()]".to_owned(),
        };
        errors::invalid(
            py,
            format!(
                "{mixed}\nreport one run at a time: pick its rows by their settings_* \
                 columns, e.g. coherent.report({example})"
            ),
        )
    })
}

/// A JSON value as Python writes it (`True`, `None`, `'text'`, `3`).
fn py_literal(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Bool(true) => "True".into(),
        serde_json::Value::Bool(false) => "False".into(),
        serde_json::Value::Null => "None".into(),
        serde_json::Value::String(s) => format!("{s:?}"),
        other => other.to_string(),
    }
}

/// The paper's tables of results lines: Table I (by task type), Table II (by scene),
/// the costs, as `coherent bench --report FILE --format json` gives them.
#[pyfunction]
pub(crate) fn report_tables<'py>(
    py: Python<'py>,
    lines: &Bound<'py, PyList>,
) -> PyResult<Bound<'py, PyAny>> {
    to_py(py, &report_of(lines)?)
}

/// The tables as text: `"markdown"`, `"csv"` or `"json"`, as `coherent bench --report`
/// prints them.
#[pyfunction]
#[pyo3(signature = (lines, format = "markdown"))]
pub(crate) fn report_text(
    lines: &Bound<'_, PyList>,
    #[pyo3(from_py_with = args::format)] format: &str,
) -> PyResult<String> {
    let py = lines.py();
    let format = TableFormat::from_name(format).ok_or_else(|| {
        errors::choice(
            py,
            "format",
            format,
            "expected \"markdown\", \"csv\" or \"json\"",
        )
    })?;
    Ok(session_bench::text(&report_of(lines)?, format))
}
