//! Episodes: `LLM` (an endpoint's settings), `run`, `replay`, `load_episode` and the
//! `Episode` they give. The episode is the session layer's
//! (`coherent::session::episode`), as for `coherent run`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent::session;
use coherent::session::backend::{BackendKind, BackendRequest};
use coherent::session::endpoint::{Endpoint, Patience};
use coherent::session::episode::{self as session_episode, EpisodeSpec, Failure, Prepared, Ran};
use coherent_agents::episode::{self, Method, Settings};
use coherent_agents::transcript::{self, Status, Summary, Transcript};
use coherent_agents::{ApiKey, Cancel, ErrorRates, OpenAiClient, OpenAiConfig, OutputMode};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};

use crate::convert::{interruptible, py_repr, to_py};
use crate::errors::{self, Kind};
use crate::task::PyTask;

/// How to reach an OpenAI-compatible endpoint, or several serving one model (a list of
/// base URLs). Arguments left out come from the environment as on the command line
/// (`OPENAI_BASE_URL`, `OPENAI_API_KEY`, `COHERENT_MODEL`). The key is kept out of
/// `repr`, transcripts and logs.
#[pyclass(name = "LLM", module = "coherent._coherent", frozen)]
pub(crate) struct PyLlm {
    pub config: OpenAiConfig,
}

#[pymethods]
impl PyLlm {
    #[new]
    #[pyo3(signature = (
        base_url = None, model = None, api_key = None, *, temperature = 0.0, seed = None,
        format = "json_schema", connect_timeout = 10.0, read_timeout = 120.0, timeout = 300.0,
        max_retries = 4, concurrency = 4,
        max_response_bytes = OpenAiConfig::DEFAULT_MAX_RESPONSE_BYTES
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        base_url: Option<&Bound<'_, PyAny>>,
        model: Option<String>,
        api_key: Option<String>,
        temperature: f32,
        seed: Option<u64>,
        format: &str,
        connect_timeout: f64,
        read_timeout: f64,
        timeout: f64,
        max_retries: u32,
        concurrency: usize,
        max_response_bytes: usize,
    ) -> PyResult<PyLlm> {
        let format: OutputMode = serde_json::from_value(format.into()).map_err(|_| {
            PyValueError::new_err(format!(
                "format {format:?}: expected \"json_schema\", \"json_object\" or \"text\""
            ))
        })?;
        let endpoint = Endpoint {
            base_urls: base_urls(base_url)?,
            api_key: api_key.map(ApiKey::new),
            model,
            temperature,
            seed,
            format,
            patience: Patience {
                connect_timeout,
                read_timeout,
                timeout,
                max_retries,
            },
            requests: concurrency,
            max_response_bytes,
        };
        let config = endpoint.config().map_err(|e| errors::backend(py, e))?.ok_or_else(|| {
            errors::backend(
                py,
                "no endpoint: pass base_url= and model= (or set OPENAI_BASE_URL and COHERENT_MODEL)",
            )
        })?;
        // The client checks the rest (the model name, the URL); fail here, not mid-run.
        OpenAiClient::new(config.clone()).map_err(|e| errors::backend(py, e.to_string()))?;
        Ok(PyLlm { config })
    }

    /// The base URL; several comma-separated when several serve the model.
    #[getter]
    fn base_url(&self) -> String {
        self.config.base_urls.join(",")
    }

    /// Every base URL.
    #[getter]
    fn base_urls(&self) -> Vec<String> {
        self.config.base_urls.clone()
    }

    #[getter]
    fn model(&self) -> &str {
        &self.config.model
    }

    /// Whether a key is set (the key itself cannot be read back).
    #[getter]
    fn has_api_key(&self) -> bool {
        self.config.api_key.is_some()
    }

    #[getter]
    fn temperature(&self) -> f32 {
        self.config.temperature
    }

    #[getter]
    fn seed(&self) -> Option<u64> {
        self.config.seed
    }

    /// The keyword arguments that build this LLM again elsewhere (a Ray worker), all but
    /// the key, which never leaves this process: there it comes from `OPENAI_API_KEY`;
    /// `has_api_key` says whether this one has a key.
    fn _settings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = &self.config;
        let d = PyDict::new(py);
        d.set_item("base_url", &c.base_urls)?;
        d.set_item("model", &c.model)?;
        d.set_item("temperature", c.temperature)?;
        d.set_item("seed", c.seed)?;
        d.set_item("format", to_py(py, &c.output)?)?;
        d.set_item("connect_timeout", c.connect_timeout.as_secs_f64())?;
        d.set_item("read_timeout", c.read_timeout.as_secs_f64())?;
        d.set_item("timeout", c.total_timeout.as_secs_f64())?;
        d.set_item("max_retries", c.backoff.max_retries)?;
        d.set_item("concurrency", c.concurrency)?;
        d.set_item("max_response_bytes", c.max_response_bytes)?;
        d.set_item("has_api_key", self.has_api_key())?;
        Ok(d)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "LLM(base_url={}, model={}, api_key={}, temperature={:?})",
            match self.config.base_urls.as_slice() {
                [one] => py_repr(py, one),
                several => format!(
                    "[{}]",
                    several
                        .iter()
                        .map(|u| py_repr(py, u))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            },
            py_repr(py, &self.config.model),
            if self.has_api_key() {
                "'[hidden]'"
            } else {
                "None"
            },
            self.config.temperature
        )
    }
}

/// `base_url=`: a URL, a comma-separated list of them, a list of them, or None (from the
/// environment).
fn base_urls(given: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(given) = given.filter(|g| !g.is_none()) else {
        return Ok(Vec::new());
    };
    if let Ok(one) = given.cast::<PyString>() {
        return Ok(vec![one.to_cow()?.into_owned()]);
    }
    let several: Vec<String> = given
        .extract()
        .map_err(|_| PyTypeError::new_err("base_url: expected a str, a list of str, or None"))?;
    if several.is_empty() {
        return Err(PyValueError::new_err("base_url: an empty list"));
    }
    Ok(several)
}

/// An episode as recorded in its transcript: the settings, every round, the summary.
#[pyclass(name = "Episode", module = "coherent._coherent", frozen)]
pub(crate) struct PyEpisode {
    pub transcript: Transcript,
    summary: Summary,
    path: PathBuf,
    pub task: Py<PyTask>,
}

impl PyEpisode {
    /// Reads the transcript at `path`; it must hold a finished episode.
    fn read(py: Python<'_>, path: &Path) -> PyResult<PyEpisode> {
        let transcript = transcript::read(path).map_err(|e| errors::coherent(py, e))?;
        let summary = transcript.summary.clone().ok_or_else(|| {
            errors::coherent(
                py,
                format!(
                    "{}: no summary line: the episode did not finish",
                    path.display()
                ),
            )
        })?;
        let task =
            episode::recorded_task(&transcript, path).map_err(|e| errors::coherent(py, e))?;
        Ok(PyEpisode {
            transcript,
            summary,
            path: path.to_owned(),
            task: Py::new(py, PyTask::new(task))?,
        })
    }
}

impl PyEpisode {
    /// The episode as it ran, from memory: its transcript and the very task it ran.
    fn from_ran(ran: Ran, task: Py<PyTask>) -> PyEpisode {
        let summary = ran.summary().clone();
        PyEpisode {
            transcript: ran.transcript,
            summary,
            path: ran.path,
            task,
        }
    }
}

#[pymethods]
impl PyEpisode {
    /// The task the episode ran (for a loaded transcript, as recorded in it).
    #[getter]
    fn task(&self, py: Python<'_>) -> Py<PyTask> {
        self.task.clone_ref(py)
    }

    #[getter]
    fn method(&self) -> &str {
        &self.transcript.header.method
    }

    /// `"success"`, `"failure"` (the step budget is spent), `"backend_error"` or
    /// `"interrupted"`.
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

    #[getter]
    fn wall_ms(&self) -> f64 {
        self.summary.wall_ms
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
    let text = if let Ok(s) = spec.cast::<PyString>() {
        s.to_cow()?.into_owned()
    } else if let Ok(d) = spec.cast::<PyDict>() {
        let mut parts = Vec::new();
        for (k, v) in d.iter() {
            parts.push(format!(
                "{}={}",
                k.extract::<String>()?,
                v.extract::<f64>()?
            ));
        }
        parts.join(",")
    } else {
        return Err(PyTypeError::new_err(
            "sim_errors: expected a str such as \"all=0.1\" or a dict of rates by kind",
        ));
    };
    ErrorRates::parse(&text)
        .map(Some)
        .map_err(|e| PyValueError::new_err(format!("sim_errors: {e}")))
}

pub(crate) fn method_of(name: &str) -> PyResult<Method> {
    Method::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        PyValueError::new_err(format!(
            "unknown method {name:?}; the methods: {}",
            names.join(", ")
        ))
    })
}

/// Runs a prepared episode on a worker thread (Ctrl-C cancels it between rounds or in a
/// model call); `prepare` runs there too, since sizing a budget may plan.
fn episode_off_the_gil(
    py: Python<'_>,
    prepare: impl FnOnce(&Cancel) -> Result<Prepared, Failure> + Send + 'static,
) -> PyResult<Ran> {
    let cancel = Cancel::default();
    let stop = cancel.clone();
    let ran = interruptible(
        py,
        move || stop.cancel(),
        move || -> Result<Ran, Failure> {
            let prepared = prepare(&cancel)?;
            session::block_on(prepared.run(&cancel, &mut |_| {}))?
        },
    )?;
    ran.map_err(|f| match f {
        Failure::Physics(e) => errors::physics(py, e),
        Failure::Other(e) => errors::coherent(py, e),
    })
}

/// Raises `BackendError` when the backend failed for good, with the episode attached.
fn backend_failure(py: Python<'_>, episode: PyEpisode) -> PyResult<Py<PyEpisode>> {
    let failed = episode.summary.status == Status::BackendError;
    let message = format!(
        "{} (transcript: {})",
        episode
            .summary
            .error
            .as_deref()
            .unwrap_or("the backend failed"),
        episode.path.display()
    );
    let episode = Py::new(py, episode)?;
    if failed {
        return Err(errors::error(
            py,
            Kind::Backend,
            message,
            Some(episode.into_any()),
        ));
    }
    Ok(episode)
}

/// Runs `method` on `task` as `coherent run` does and returns the episode; its
/// transcript goes to `out`.
#[pyfunction]
#[pyo3(signature = (
    task, method = "pefa", *, llm = None, sim_errors = None, history = 5, max_steps = None,
    physics = false, seed = None, out = PathBuf::from("runs"), max_states = 5_000_000
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run(
    py: Python<'_>,
    task: &Bound<'_, PyTask>,
    method: &str,
    llm: Option<&Bound<'_, PyLlm>>,
    sim_errors: Option<&Bound<'_, PyAny>>,
    history: usize,
    max_steps: Option<u32>,
    physics: bool,
    seed: Option<u64>,
    out: PathBuf,
    max_states: usize,
) -> PyResult<Py<PyEpisode>> {
    let method = method_of(method)?;
    let backend = BackendRequest {
        kind: BackendKind::Auto,
        endpoint: llm.map(|l| l.get().config.clone()),
        sim_errors: error_rates(sim_errors)?,
        replay_from: None,
    }
    .choose()
    .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let spec = EpisodeSpec {
        task: Arc::clone(&task.get().task),
        settings: Settings {
            method,
            history,
            temperature: llm.map(|l| l.get().config.temperature),
            seed,
            physics,
        },
        max_steps,
        backend,
        max_states,
        out,
    };
    let ran = episode_off_the_gil(py, move |cancel| session_episode::prepare(spec, cancel))?;
    backend_failure(py, PyEpisode::from_ran(ran, task.clone().unbind()))
}

/// Re-runs the episode of a transcript, answering from it (no network), and checks that
/// every round comes out as recorded; raises `ReplayMismatchError` when one does not.
#[pyfunction]
#[pyo3(signature = (transcript, *, out = PathBuf::from("runs")))]
pub(crate) fn replay(py: Python<'_>, transcript: PathBuf, out: PathBuf) -> PyResult<Py<PyEpisode>> {
    let path = transcript.clone();
    let ran = episode_off_the_gil(py, move |_| {
        session_episode::prepare_replay(&path, None, out)
    })?;
    let mismatch = ran.replay.clone().and_then(Result::err);
    let task = Py::new(py, PyTask::shared(Arc::clone(&ran.task)))?;
    let episode = PyEpisode::from_ran(ran, task);
    if let Some(why) = mismatch {
        let message = format!("{}: {why}", transcript.display());
        let episode = Py::new(py, episode)?.into_any();
        return Err(errors::error(
            py,
            Kind::ReplayMismatch,
            message,
            Some(episode),
        ));
    }
    backend_failure(py, episode)
}

/// The episode recorded in a transcript file (`coherent run` or `coherent bench` wrote it).
#[pyfunction]
pub(crate) fn load_episode(py: Python<'_>, path: PathBuf) -> PyResult<PyEpisode> {
    PyEpisode::read(py, &path)
}
