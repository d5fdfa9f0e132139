//! Episodes: `run`, `replay`, `load_episode` and the `Episode` they give. The episode is
//! the session's (`coherent::session::episode`), as for `coherent run`:
//! this file converts the arguments and the results.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use coherent::session::backend::{BackendRequest, EndpointSource};
use coherent::session::engine::{
    Cancel, DEFAULT_MAX_TRANSCRIPT_BYTES, ErrorRates, Execution, Limits, PriceTable, ReadLimits,
    Summary, Transcript, executed_actions,
};
use coherent::session::episode::{self, Prepared, Ran, ReplayRequest, RunRequest};
use coherent::session::tasks::TaskSource;
use coherent::session::view::{Given, Source, ViewRequest, page};
use coherent::session::{self, Error};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};

use crate::args;
use crate::convert::{self, finite, interruptible, py_repr, text, to_py};
use crate::errors::{self, PyCoherentResult, short_repr};
use crate::llm::PyLlm;
use crate::method::{MethodArg, Methods};
use crate::prompts::{price_source, prompt_source};
use crate::task::{PyTask, robots_arg};

/// An episode as recorded in its transcript: the settings, every round, the summary.
#[pyclass(name = "Episode", module = "coherent._coherent", frozen)]
pub(crate) struct PyEpisode {
    pub transcript: Transcript,
    summary: Summary,
    path: PathBuf,
    pub task: Py<PyTask>,
    pub cost_usd: Option<f64>,
}

impl PyEpisode {
    /// Reads the transcript at `path`; it must hold a finished episode. Its cost is at
    /// the built-in prices, by the same rule as the episode's when it ran.
    fn read(py: Python<'_>, path: &Path) -> PyCoherentResult<PyEpisode> {
        let recorded = episode::recorded(path, DEFAULT_MAX_TRANSCRIPT_BYTES)?;
        let summary = recorded.finished()?.clone();
        let cost_usd = recorded.cost(&PriceTable::builtin());
        Ok(PyEpisode {
            transcript: recorded.transcript,
            summary,
            path: path.to_owned(),
            task: Py::new(py, PyTask::shared(recorded.task))?,
            cost_usd,
        })
    }

    /// The episode (a copy), to show.
    pub(crate) fn given(&self) -> Given {
        Given {
            task: Arc::clone(&self.task.get().task),
            transcript: self.transcript.clone(),
            cost_usd: self.cost_usd,
            cut: None,
        }
    }

    /// The episode as it ran, from memory: its transcript and the very task it ran.
    fn from_ran(ran: Ran, task: Py<PyTask>) -> PyEpisode {
        let summary = ran.summary().clone();
        PyEpisode {
            transcript: ran.transcript,
            summary,
            path: ran.path,
            task,
            cost_usd: ran.cost_usd,
        }
    }
}

#[pymethods]
impl PyEpisode {
    /// The episode's page (`coherent.view`) in a frame, as a notebook shows it inline.
    fn _repr_html_(&self, py: Python<'_>) -> PyResult<String> {
        let request = ViewRequest {
            source: Source::Episode(Box::new(self.given())),
            other: None,
            limits: ReadLimits::default(),
        };
        // The view's errors are text, of no kind to convert by.
        let html = py
            .detach(|| request.page(&|_| {}))
            .map_err(|e| errors::session_err(py, e))?;
        Ok(page::framed(&html))
    }

    /// The task the episode ran (for a loaded transcript, as recorded in it).
    #[getter]
    fn task(&self, py: Python<'_>) -> Py<PyTask> {
        self.task.clone_ref(py)
    }

    #[getter]
    fn method(&self) -> &str {
        &self.transcript.header.method
    }

    /// `"success"`, `"failure"` (the step budget is spent), `"backend_error"`,
    /// `"interrupted"` or `"error"` (a method written in Python raised).
    #[getter]
    fn status<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.summary.status)
    }

    #[getter]
    fn success(&self) -> bool {
        self.summary.success
    }

    #[getter]
    fn steps(&self) -> u32 {
        self.summary.steps
    }

    #[getter]
    fn gt_steps(&self) -> Option<u32> {
        self.summary.gt_steps
    }

    #[getter]
    fn max_steps(&self) -> u32 {
        self.summary.max_steps
    }

    #[getter]
    fn llm_calls(&self) -> u32 {
        self.summary.llm_calls
    }

    #[getter]
    fn prompt_tokens(&self) -> u64 {
        self.summary.prompt_tokens
    }

    #[getter]
    fn completion_tokens(&self) -> u64 {
        self.summary.completion_tokens
    }

    /// Prompt and completion tokens together.
    #[getter]
    fn tokens(&self) -> u64 {
        self.summary.prompt_tokens + self.summary.completion_tokens
    }

    /// The part of `prompt_tokens` the server read from its prompt cache.
    #[getter]
    fn cached_tokens(&self) -> u64 {
        self.summary.cached_tokens
    }

    /// What the model calls cost in USD, at the price table given to `run` or `replay`
    /// (the built-in one for `load_episode`); None when the model has no price.
    #[getter]
    fn cost_usd(&self) -> Option<f64> {
        self.cost_usd
    }

    #[getter]
    fn wall_ms(&self) -> f64 {
        self.summary.wall_ms
    }

    /// `"sequential"` (one robot's action a step) or `"parallel"` (joint steps).
    #[getter]
    fn execution(&self) -> &'static str {
        self.transcript.header.execution.name()
    }

    /// The joint steps it took to reach the goal (its steps); None when it did not.
    #[getter]
    fn makespan(&self) -> Option<u32> {
        self.summary.success.then_some(self.summary.steps)
    }

    /// The actions carried out (in a parallel episode, several a step).
    #[getter]
    fn actions(&self) -> u32 {
        executed_actions(&self.transcript.rounds)
    }

    /// The simulated seconds it took, with physics; None otherwise.
    #[getter]
    fn sim_seconds(&self) -> Option<f64> {
        self.summary.sim_seconds
    }

    /// Why the episode stopped early, when it did.
    #[getter]
    fn error(&self) -> Option<&str> {
        self.summary.error.as_deref()
    }

    /// `{"kind", "model", "base_url"}` of the backend that answered.
    #[getter]
    fn backend<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.transcript.header.backend)
    }

    /// The transcript file.
    #[getter]
    fn path(&self) -> &Path {
        &self.path
    }

    /// The transcript's first line: the task, the method and the settings.
    #[getter]
    fn header<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.transcript.header)
    }

    /// One dict per round (step), as in the transcript file: the calls with their
    /// prompts and answers, the proposal, the action list, the decision, the outcome.
    #[getter]
    fn transcript<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for round in &self.transcript.rounds {
            list.append(to_py(py, round)?)?;
        }
        Ok(list)
    }

    /// The summary line as a dict.
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.summary)
    }

    /// One row per step (pandas): robot, subtask, action, outcome, reason, tokens, ...
    fn to_dataframe<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        py.import("coherent.analysis")?
            .getattr("episode_frame")?
            .call1((slf,))
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let meta = &self.task.get().task.meta;
        Ok(format!(
            "Episode(scene={}, task_id={}, method={}, status={}, steps={}, gt_steps={}, tokens={})",
            py_repr(py, &meta.scene),
            meta.task_id,
            py_repr(py, self.method()),
            self.status(py)?.repr()?,
            self.summary.steps,
            self.summary
                .gt_steps
                .map_or("None".to_owned(), |g| g.to_string()),
            self.tokens()
        ))
    }
}

/// `"all=0.1"`, `{"hallucinate": 0.1, ...}` or None.
pub(crate) fn error_rates(spec: Option<&Bound<'_, PyAny>>) -> PyResult<Option<ErrorRates>> {
    let Some(spec) = spec else { return Ok(None) };
    let written = if spec.is_instance_of::<PyString>() {
        text(spec, "sim_errors")?.to_owned()
    } else if let Ok(d) = spec.cast::<PyDict>() {
        let mut parts = Vec::new();
        for (k, v) in d.iter() {
            let place = format!("sim_errors[{}]", short_repr(&k));
            let kind = text(&k, &place)?;
            // A key must not read as more than one kind (`"all=1,hallucinate"`).
            if kind.contains([',', '=']) {
                return Err(errors::argument(&place, &k, "not an error kind"));
            }
            parts.push(format!("{kind}={}", finite(&v, &place)?));
        }
        parts.join(",")
    } else {
        return Err(PyTypeError::new_err(
            "sim_errors: expected a str such as \"all=0.1\" or a dict of rates by kind",
        ));
    };
    // The argument's name, which the parser does not know.
    ErrorRates::parse(&written)
        .map(Some)
        .map_err(|e| errors::invalid(spec.py(), format!("sim_errors: {e}")))
}

/// Runs a prepared episode on a worker thread (Ctrl-C cancels it between rounds or in a
/// model call); `prepare` runs there too, since sizing a budget may plan and robots over
/// ROS 2 are awaited.
fn episode_off_the_gil(
    py: Python<'_>,
    prepare: impl FnOnce(&Cancel) -> Result<Prepared, Error> + Send + 'static,
) -> PyCoherentResult<Ran> {
    let cancel = Cancel::default();
    let stop = cancel.clone();
    let ran = interruptible(
        py,
        move || stop.cancel(),
        move || -> Result<Ran, Error> {
            let prepared = prepare(&cancel)?;
            session::block_on(prepared.run(&cancel, &mut |_| {}))?
        },
    )?;
    Ok(ran?)
}

/// The episode that `ran`, or the exception its ending raises (`BackendError`,
/// `MethodError` with the method's exception as its cause when there is one,
/// `ReplayMismatchError`, `RobotError`), with the episode attached.
fn finished(
    py: Python<'_>,
    ran: Ran,
    task: Py<PyTask>,
    cause: Option<PyErr>,
) -> PyResult<Py<PyEpisode>> {
    let ending = ran.ending();
    let episode = Py::new(py, PyEpisode::from_ran(ran, task))?;
    match errors::ending_err(py, &ending, episode.clone_ref(py).into_any()) {
        None => Ok(episode),
        Some(raised) => {
            raised.set_cause(py, cause);
            Err(raised)
        }
    }
}

/// Runs `method` on `task` as `coherent run` does and returns the episode; its
/// transcript goes to `out`. With `robots="ros2"`, each robot's ROS 2 action server
/// under `namespace` carries the actions out.
#[pyfunction]
#[pyo3(signature = (
    task, method = MethodArg::Name("pefa".to_owned()), *, execution = Execution::Sequential,
    llm = None, sim_errors = None,
    history = coherent::session::engine::HISTORY_WINDOW, max_steps = None, physics = false,
    seed = None, out = PathBuf::from("runs"), max_states = Limits::DEFAULT_MAX_STATES,
    prompts = None, prices = None, robots = "local", namespace = None, robot_timeout = 10.0,
    server_wait = 10.0, step_timeout = None, events = None
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run(
    py: Python<'_>,
    task: &Bound<'_, PyTask>,
    #[pyo3(from_py_with = args::method)] method: MethodArg,
    #[pyo3(from_py_with = args::execution)] execution: Execution,
    llm: Option<&Bound<'_, PyLlm>>,
    sim_errors: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = args::history)] history: usize,
    #[pyo3(from_py_with = args::max_steps)] max_steps: Option<u32>,
    physics: bool,
    #[pyo3(from_py_with = args::seed)] seed: Option<u64>,
    #[pyo3(from_py_with = args::out)] out: PathBuf,
    #[pyo3(from_py_with = args::max_states)] max_states: usize,
    prompts: Option<&Bound<'_, PyAny>>,
    prices: Option<&Bound<'_, PyAny>>,
    robots: &str,
    namespace: Option<&str>,
    robot_timeout: f64,
    server_wait: f64,
    #[pyo3(from_py_with = args::step_timeout)] step_timeout: Option<Duration>,
    events: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyEpisode>> {
    let events = events.map(convert::events_source).transpose()?;
    let prompts = prompt_source(prompts)?;
    let prices = price_source(prices)?;
    let robots = robots_arg(py, robots, namespace, robot_timeout, server_wait)?;
    let mut methods = Methods::new(py, step_timeout)?;
    let method = method.spec(py, &mut methods, &[task.clone().unbind()])?;
    let request = RunRequest {
        backend: BackendRequest {
            endpoint: llm.map_or(EndpointSource::None, |l| {
                EndpointSource::Client(Arc::clone(&l.get().client))
            }),
            sim_errors: error_rates(sim_errors)?,
            ..BackendRequest::default()
        },
        prompts,
        prices,
        robots,
        physics,
        max_steps,
        history,
        seed,
        max_states,
        out,
        execution,
        events,
        ..RunRequest::new(TaskSource::Given(Arc::clone(&task.get().task)), method)
    };
    let ran = episode_off_the_gil(py, move |cancel| request.prepare(cancel));
    methods.close(py)?;
    let cause = methods.methods.first().and_then(|m| m.take_error());
    finished(py, ran?, task.clone().unbind(), cause)
}

/// Re-runs the episode of a transcript, answering from it (no network) with the prompt
/// set it recorded, and checks that every round comes out as recorded; raises
/// `ReplayMismatchError` when one does not. `prices` prices the recorded tokens.
#[pyfunction]
#[pyo3(signature = (transcript, *, out = PathBuf::from("runs"), prices = None))]
pub(crate) fn replay(
    py: Python<'_>,
    #[pyo3(from_py_with = args::transcript)] transcript: PathBuf,
    #[pyo3(from_py_with = args::out)] out: PathBuf,
    prices: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyEpisode>> {
    let request = ReplayRequest {
        transcript,
        task: None,
        prices: price_source(prices)?,
        out,
        max_bytes: DEFAULT_MAX_TRANSCRIPT_BYTES,
    };
    let ran = episode_off_the_gil(py, move |_| request.prepare())?;
    let task = Py::new(py, PyTask::shared(Arc::clone(&ran.task)))?;
    finished(py, ran, task, None)
}

/// The episode recorded in a transcript file (`coherent run` or `coherent bench` wrote it).
#[pyfunction]
pub(crate) fn load_episode(
    py: Python<'_>,
    #[pyo3(from_py_with = args::path)] path: PathBuf,
) -> PyCoherentResult<PyEpisode> {
    PyEpisode::read(py, &path)
}
