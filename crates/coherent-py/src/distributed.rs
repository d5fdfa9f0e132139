//! The two halves of a benchmark run that other executors than the local one drive
//! (`coherent.executors.RayExecutor`): the driver's `_BenchLedger` (the results file,
//! the episodes still to run, each result written once) and a worker's `_BenchWorker`
//! (one episode at a time by its key, through the session layer's `Worker`, as the
//! local executor runs them).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use coherent::session::bench::{EpisodesRequest, RunTasks, Worker, default_out};
use coherent::session::engine::{
    Cancel, DEFAULT_MAX_RESULTS_BYTES, EpisodeKey, EpisodeResult, Event, Execution, HISTORY_WINDOW,
    Ledger, Limits, PriceTable, Progress, ResultLine, Style, native,
};
use coherent::session::prompts::{PriceSource, PromptSource};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::bench::{
    outcome_dict, progress_style, replaying, run_backend, run_methods, settings_err, to_stderr,
};
use crate::convert::{json_at, text, to_py};
use crate::errors::PyCoherentResult;
use crate::method::{MethodArg, Methods};
use crate::prompts::{price_source, prompt_source};
use crate::task::PyTask;
use crate::{args, errors};

/// An episode's key as Python holds it: `(method, scene, task_id, seed, execution)`.
type Key = (String, String, i64, u32, String);

/// What a worker hands the driver: `("line", <results line as JSON>)`,
/// `("skipped", <why the task cannot run>)` or `("not_started", None)`.
type Handed = (String, Option<String>);

fn key_of(py: Python<'_>, (method, scene, task_id, seed, execution): Key) -> PyResult<EpisodeKey> {
    let execution: Execution = execution
        .parse()
        .map_err(|e| errors::invalid(py, format!("an episode's key: execution {e}")))?;
    Ok(EpisodeKey {
        method,
        scene,
        task_id,
        seed,
        execution,
    })
}

/// The driver's side of a run: checks the run's settings as `coherent.bench` does (the
/// backend's too, though the workers build their own), opens (and repairs) the results
/// file `out`, refusing one of other settings, knows the episodes still to run, writes
/// each result handed to it, once, with the run's settings.
#[pyclass(name = "_BenchLedger", module = "coherent._coherent")]
pub(crate) struct PyLedger {
    /// The results file.
    out: PathBuf,
    ledger: Option<Ledger>,
    pending: Vec<EpisodeKey>,
    progress: Option<Progress>,
    /// The prompt set's replaced templates, by file name.
    prompts: BTreeMap<String, String>,
    /// The whole price table, the built-in one with what `prices` added.
    prices: PriceTable,
}

impl PyLedger {
    fn ledger(&mut self) -> PyResult<&mut Ledger> {
        self.ledger
            .as_mut()
            .ok_or_else(|| PyValueError::new_err("the run is finished"))
    }
}

#[pymethods]
impl PyLedger {
    #[new]
    #[pyo3(signature = (
        tasks, methods, *, seeds, out, execution = vec![Execution::Sequential], backend = None,
        sim_errors = None, replay_from = None, history = HISTORY_WINDOW,
        max_states = Limits::DEFAULT_MAX_STATES, max_steps = None, physics = false,
        progress = None, prompts = None, prices = None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        tasks: Vec<Bound<'_, PyTask>>,
        #[pyo3(from_py_with = args::methods)] methods: Vec<MethodArg>,
        #[pyo3(from_py_with = args::seeds)] seeds: u32,
        #[pyo3(from_py_with = args::results_out)] out: Option<PathBuf>,
        #[pyo3(from_py_with = args::executions)] execution: Vec<Execution>,
        backend: Option<&Bound<'_, PyAny>>,
        sim_errors: Option<&Bound<'_, PyAny>>,
        #[pyo3(from_py_with = args::replay_from)] replay_from: Option<PathBuf>,
        #[pyo3(from_py_with = args::history)] history: usize,
        #[pyo3(from_py_with = args::max_states)] max_states: usize,
        #[pyo3(from_py_with = args::max_steps)] max_steps: Option<u32>,
        physics: bool,
        progress: Option<&str>,
        prompts: Option<&Bound<'_, PyAny>>,
        prices: Option<&Bound<'_, PyAny>>,
    ) -> PyCoherentResult<PyLedger> {
        let prompts_given = prompts.is_some();
        let request = EpisodesRequest {
            prompts: prompt_source(prompts)?,
            prices: price_source(prices)?,
            backend: run_backend(backend, sim_errors, replay_from.clone(), prompts_given)?,
            executions: execution,
            history,
            max_states,
            max_steps,
            physics,
            ..EpisodesRequest::new(Vec::new())
        };
        // The methods written in Python are only named here; the workers run them.
        let objects: Vec<Py<PyTask>> = tasks.iter().map(|t| t.clone().unbind()).collect();
        let mut python = Methods::new(py, None)?;
        let replay = replaying(backend, replay_from.as_deref());
        let methods = run_methods(py, &methods, seeds, &objects, &mut python, replay);
        python.close(py)?;
        let methods = methods?;
        // The settings checked as `coherent.bench` checks them (the backend's too, though
        // the workers make their own).
        let settings = EpisodesRequest { methods, ..request }
            .prepare()
            .map_err(|e| settings_err(py, e))?;
        let tasks: Vec<_> = tasks.iter().map(|t| Arc::clone(&t.get().task)).collect();
        // The argument the fault is in, and an argument's error whatever the kind.
        RunTasks::new(&tasks).map_err(|e| errors::invalid(py, format!("tasks: {e}")))?;
        let out = out.unwrap_or_else(|| default_out(&settings, seeds));
        let mut ledger = Ledger::open(&out, DEFAULT_MAX_RESULTS_BYTES, &settings.record(seeds))?;
        let pending = ledger.plan(&tasks, &settings.methods, &settings.executions, seeds);
        let mut progress = progress_style(py, progress)?.map(Progress::new);
        if let Some(p) = progress.as_mut() {
            let start = Event::Start {
                to_run: pending.len(),
                skipped: ledger.outcome().skipped,
            };
            show(p.line(&start));
        }
        Ok(PyLedger {
            out,
            ledger: Some(ledger),
            pending,
            progress,
            prompts: settings.prompts.replaced_texts(),
            prices: settings.prices,
        })
    }

    /// The prompt set and the price table as data for the workers' `prompts` and
    /// `prices` (a folder or price file named on this machine may not exist on theirs).
    fn worker_settings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("prompts", &self.prompts)?;
        d.set_item("prices", to_py(py, &self.prices)?)?;
        Ok(d)
    }

    /// The episodes to run, in order: `(method, scene, task_id, seed, execution)`.
    fn pending(&self) -> Vec<Key> {
        self.pending
            .iter()
            .map(|k| {
                let execution = k.execution.name().to_owned();
                (
                    k.method.clone(),
                    k.scene.clone(),
                    k.task_id,
                    k.seed,
                    execution,
                )
            })
            .collect()
    }

    /// Records what a worker handed back for one episode; returns whether a line was
    /// written (not when this run already wrote that episode's line).
    fn record(&mut self, handed: Handed) -> PyCoherentResult<bool> {
        let result = match handed {
            (kind, Some(json)) if kind == "line" => {
                // What the text is, which the parser does not know.
                let line: ResultLine = serde_json::from_str(&json)
                    .map_err(|e| PyValueError::new_err(format!("a results line: {e}")))?;
                EpisodeResult::Line(Box::new(line))
            }
            (kind, Some(why)) if kind == "skipped" => EpisodeResult::TaskSkipped(why),
            (kind, None) if kind == "not_started" => EpisodeResult::NotStarted,
            (kind, _) => {
                let kind = format!("an episode's result of kind {kind:?}");
                return Err(PyValueError::new_err(kind).into());
            }
        };
        let written = self.ledger()?.record(result)?;
        if let (Some(line), Some(p)) = (&written, self.progress.as_mut()) {
            show(p.line(&Event::Finished(line)));
        }
        Ok(written.is_some())
    }

    /// Ends the run and says what it did, as `coherent.bench`'s outcome; `interrupted`
    /// when it was stopped from outside. With `orphans`, the transcripts no results line
    /// points to (left by workers that died mid-episode) are renamed
    /// `*.jsonl.unfinished` first, as resuming would.
    #[pyo3(signature = (*, interrupted, orphans = false))]
    fn finish<'py>(
        &mut self,
        py: Python<'py>,
        interrupted: bool,
        orphans: bool,
    ) -> PyCoherentResult<Bound<'py, PyDict>> {
        let mut ledger = self
            .ledger
            .take()
            .ok_or_else(|| PyValueError::new_err("the run is finished"))?;
        if orphans {
            ledger.mark_orphans()?;
        }
        if self.progress.as_ref().map(Progress::style) == Some(Style::Bar) {
            // The bar's last redraw ends its line.
            to_stderr("\n");
        }
        let d = outcome_dict(py, &ledger.finish(interrupted))?;
        d.set_item("out", self.out.display().to_string())?;
        Ok(d)
    }

    /// The results file (the name the settings give when `out` was None).
    #[getter]
    fn out(&self) -> String {
        self.out.display().to_string()
    }
}

fn show(text: Option<String>) {
    if let Some(text) = text {
        to_stderr(&text);
    }
}

/// Runs the episodes of a run one at a time by their key, as a Ray worker does: the
/// tasks come as native task JSON, the settings as `coherent.bench` takes them, the
/// transcripts go beside the results file `out` as they would locally.
#[pyclass(name = "_BenchWorker", module = "coherent._coherent", frozen)]
pub(crate) struct PyWorker {
    worker: Worker,
    /// The event loop of the methods written in Python, for as long as the worker runs.
    _python: Methods,
}

#[pymethods]
impl PyWorker {
    #[new]
    #[pyo3(signature = (
        tasks, methods, *, execution = vec![Execution::Sequential], backend = None,
        sim_errors = None, replay_from = None, history = HISTORY_WINDOW,
        max_states = Limits::DEFAULT_MAX_STATES, max_steps = None, physics = false, out,
        prompts, prices, step_timeout = None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        tasks: Vec<String>,
        #[pyo3(from_py_with = args::methods)] methods: Vec<MethodArg>,
        #[pyo3(from_py_with = args::executions)] execution: Vec<Execution>,
        backend: Option<&Bound<'_, PyAny>>,
        sim_errors: Option<&Bound<'_, PyAny>>,
        #[pyo3(from_py_with = args::replay_from)] replay_from: Option<PathBuf>,
        #[pyo3(from_py_with = args::history)] history: usize,
        #[pyo3(from_py_with = args::max_states)] max_states: usize,
        #[pyo3(from_py_with = args::max_steps)] max_steps: Option<u32>,
        physics: bool,
        #[pyo3(from_py_with = args::out)] out: PathBuf,
        prompts: &Bound<'_, PyDict>,
        prices: &Bound<'_, PyDict>,
        #[pyo3(from_py_with = args::step_timeout)] step_timeout: Option<Duration>,
    ) -> PyCoherentResult<PyWorker> {
        let mut read = Vec::new();
        for (i, text) in tasks.iter().enumerate() {
            // Which task the text is, which the parser does not know.
            let value: serde_json::Value = serde_json::from_str(text)
                .map_err(|e| PyValueError::new_err(format!("task {i}: {e}")))?;
            let task = native::read(&format!("task {i}"), &value)?;
            read.push(Arc::new(task));
        }
        let objects = read
            .iter()
            .map(|t| Py::new(py, PyTask::shared(Arc::clone(t))))
            .collect::<PyResult<Vec<_>>>()?;
        let mut python = Methods::new(py, step_timeout)?;
        let replay = replaying(backend, replay_from.as_deref());
        let methods = run_methods(py, &methods, 1, &objects, &mut python, replay)?;
        // The driver refused a prompt set with a replay; the prompt set and the price
        // table come as the driver's data.
        let files = prompts
            .iter()
            .map(|(k, v)| {
                Ok((
                    text(&k, "prompts")?.to_owned(),
                    text(&v, "prompts")?.to_owned(),
                ))
            })
            .collect::<PyResult<Vec<_>>>()?;
        let settings = EpisodesRequest {
            backend: run_backend(backend, sim_errors, replay_from.clone(), false)?,
            prompts: PromptSource::Texts(files),
            prices: PriceSource::Json(json_at(prices.as_any(), "prices")?.to_string()),
            history,
            max_states,
            max_steps,
            physics,
            executions: execution,
            ..EpisodesRequest::new(methods)
        }
        .prepare()
        .map_err(|e| settings_err(py, e))?;
        let worker = Worker::new(&read, settings, &out)?;
        Ok(PyWorker {
            worker,
            _python: python,
        })
    }

    /// Runs the episode `(method, scene, task_id, seed, execution)` with the GIL released
    /// (other threads may run theirs meanwhile); returns what the driver records.
    fn run(&self, py: Python<'_>, key: Key) -> PyCoherentResult<Handed> {
        let key = key_of(py, key)?;
        let result = py.detach(|| self.worker.run(&key, &Cancel::default()))?;
        Ok(match result {
            EpisodeResult::Line(line) => {
                // What failed to be written, which the serializer does not know.
                let json = serde_json::to_string(&line)
                    .map_err(|e| PyValueError::new_err(format!("a results line: {e}")))?;
                ("line".to_owned(), Some(json))
            }
            EpisodeResult::TaskSkipped(why) => ("skipped".to_owned(), Some(why)),
            EpisodeResult::NotStarted => ("not_started".to_owned(), None),
        })
    }
}
