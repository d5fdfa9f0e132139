//! `LLM`: an OpenAI-compatible endpoint, as the episodes' backend and as a client of
//! its own for methods written in Python: `chat` and `achat` go through the project's
//! client (timeouts, retries with backoff and `Retry-After`, structured outputs with
//! fallbacks, token accounting, the key in no text), and inside a method's `act` each
//! call is filed in that step's round of the transcript, like a built-in method's.

use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use coherent::session::engine::{
    Answer, ApiKey, Backend, Backoff, Call, Chat, Finish, LlmError, Message, OpenAiClient,
    OpenAiConfig, OutputMode, Role, redacted,
};
use coherent::session::{self, backend};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyCFunction, PyDict, PyList, PyString};

use crate::args;
use crate::convert::{json_at, py_repr, to_py};
use crate::errors::{self, PyCoherentResult};
use crate::method::{Recorder, helpers};

/// The session's runtime, which the model calls of Python code run on.
fn runtime() -> PyCoherentResult<&'static tokio::runtime::Runtime> {
    Ok(session::runtime()?)
}

/// Asks `client`, and files the call with `recorder` (the step being decided), if any.
async fn ask(
    client: Arc<OpenAiClient>,
    chat: Chat,
    call: Call,
    recorder: Option<Py<Recorder>>,
) -> Result<Answer, LlmError> {
    let response = client.chat(&chat).await;
    let result = response.result;
    if let Some(recorder) = recorder {
        recorder.get().push(Call {
            answer: result.as_ref().ok().cloned(),
            error: result.as_ref().err().cloned(),
            endpoint: response.endpoint,
            ..call
        });
    }
    result
}

/// How to reach an OpenAI-compatible endpoint, or several serving one model (a list of
/// base URLs: each request goes to the least busy, one that fails rests). Arguments left
/// out come from the environment as on the command line (`OPENAI_BASE_URL`,
/// `OPENAI_API_KEY`, `COHERENT_MODEL`). The key is kept out of `repr`, transcripts and
/// logs.
#[pyclass(name = "LLM", module = "coherent._coherent", frozen)]
pub(crate) struct PyLlm {
    /// The one client of this endpoint: `chat` and `achat`, and the episodes of `run`
    /// and `bench` given this `LLM` (its connections, its limit on requests in flight
    /// and its answer format last taken are shared by all of them).
    pub(crate) client: Arc<OpenAiClient>,
}

#[pymethods]
impl PyLlm {
    #[new]
    #[pyo3(signature = (
        base_url = None, model = None, api_key = None, *,
        temperature = OpenAiConfig::default().temperature, seed = None, format = "json_schema",
        connect_timeout = OpenAiConfig::default().connect_timeout,
        read_timeout = OpenAiConfig::default().read_timeout,
        timeout = OpenAiConfig::default().total_timeout,
        max_retries = OpenAiConfig::default().backoff.max_retries,
        concurrency = OpenAiConfig::default().concurrency,
        max_response_bytes = OpenAiConfig::default().max_response_bytes
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        #[pyo3(from_py_with = args::base_url)] base_url: Option<Vec<String>>,
        #[pyo3(from_py_with = args::model)] model: Option<String>,
        #[pyo3(from_py_with = args::api_key)] api_key: Option<String>,
        #[pyo3(from_py_with = args::temperature)] temperature: f32,
        #[pyo3(from_py_with = args::seed)] seed: Option<u64>,
        #[pyo3(from_py_with = args::format)] format: &str,
        #[pyo3(from_py_with = args::connect_timeout)] connect_timeout: Duration,
        #[pyo3(from_py_with = args::read_timeout)] read_timeout: Duration,
        #[pyo3(from_py_with = args::timeout)] timeout: Duration,
        #[pyo3(from_py_with = args::max_retries)] max_retries: u32,
        #[pyo3(from_py_with = args::concurrency)] concurrency: usize,
        #[pyo3(from_py_with = args::max_response_bytes)] max_response_bytes: usize,
    ) -> PyCoherentResult<PyLlm> {
        let format: OutputMode = serde_json::from_value(format.into()).map_err(|_| {
            errors::choice(
                py,
                "format",
                format,
                "expected \"json_schema\", \"json_object\" or \"text\"",
            )
        })?;
        let given = OpenAiConfig {
            base_urls: base_url.unwrap_or_default(),
            api_key: api_key.map(ApiKey::new),
            model: model.unwrap_or_default(),
            temperature,
            seed,
            connect_timeout,
            read_timeout,
            total_timeout: timeout,
            backoff: Backoff {
                max_retries,
                ..Backoff::default()
            },
            concurrency: concurrency.max(1),
            output: format,
            max_response_bytes,
        };
        let none = "no endpoint: pass base_url= and model= (or set OPENAI_BASE_URL and \
                    COHERENT_MODEL)";
        let config = backend::complete(given)?.ok_or_else(|| errors::backend(py, none))?;
        // The client checks the rest (the model name, the URL); fail here, not mid-run.
        let client = OpenAiClient::new(config)?;
        Ok(PyLlm {
            client: Arc::new(client),
        })
    }

    /// Asks the model: `messages` is a list of `{"role", "content"}` dicts (or one str,
    /// a user message); with `schema` (a JSON schema) the answer follows it, by the
    /// server's structured outputs or the client's fallbacks (then check it). Retries on
    /// 408, 429, 5xx and lost connections; raises `BackendError` when the server fails
    /// for good. Inside `act`, the call is filed in the step's round (`role` and `robot`
    /// say whom it was for: `"assigner"`, about the team, or `"executor"` of a robot).
    /// Ctrl-C stops the wait.
    #[pyo3(signature = (messages, schema = None, *, max_tokens = 400, role = "assigner", robot = None))]
    fn chat(
        &self,
        py: Python<'_>,
        messages: &Bound<'_, PyAny>,
        schema: Option<&Bound<'_, PyAny>>,
        max_tokens: u32,
        role: &str,
        robot: Option<i64>,
    ) -> PyCoherentResult<PyReply> {
        let (chat, call) = self.request(messages, schema, max_tokens, role, robot)?;
        let recorder = Recorder::current(py)?;
        let (tx, mut rx) = mpsc::channel();
        let client = Arc::clone(&self.client);
        let task = runtime()?.spawn(async move {
            let _ = tx.send(ask(client, chat, call, recorder).await);
        });
        loop {
            let receiver = &mut rx;
            match py.detach(move || receiver.recv_timeout(Duration::from_millis(50))) {
                Ok(result) => return Ok(PyReply { answer: result? }),
                Err(RecvTimeoutError::Timeout) => {
                    if let Err(interrupt) = py.check_signals() {
                        task.abort();
                        return Err(interrupt.into());
                    }
                }
                Err(RecvTimeoutError::Disconnected) => {
                    let why = "the model call stopped unanswered";
                    return Err(PyRuntimeError::new_err(why).into());
                }
            }
        }
    }

    /// `chat`, awaited: `reply = await llm.achat(messages)` (an asyncio future of the
    /// running loop), or `asyncio.run(llm.achat(messages))` outside any loop (a coroutine
    /// that starts the call on the loop that awaits it). Calls of concurrent coroutines
    /// are in flight together, up to the LLM's `concurrency`.
    #[pyo3(signature = (messages, schema = None, *, max_tokens = 400, role = "assigner", robot = None))]
    fn achat<'py>(
        &self,
        py: Python<'py>,
        messages: &Bound<'py, PyAny>,
        schema: Option<&Bound<'py, PyAny>>,
        max_tokens: u32,
        role: &str,
        robot: Option<i64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (chat, call) = self.request(messages, schema, max_tokens, role, robot)?;
        let recorder = Recorder::current(py)?;
        let client = Arc::clone(&self.client);
        let asyncio = py.import("asyncio")?;
        if let Ok(event_loop) = asyncio.call_method0("get_running_loop") {
            return start(py, &event_loop, client, chat, call, recorder);
        }
        // No loop runs yet: the call starts when the coroutine is awaited, on its loop.
        let once = Mutex::new(Some((client, chat, call, recorder)));
        let begin = PyCFunction::new_closure(py, None, None, move |args, _| {
            let py = args.py();
            let taken = once.lock().unwrap_or_else(PoisonError::into_inner).take();
            let (client, chat, call, recorder) = taken
                .ok_or_else(|| PyRuntimeError::new_err("this achat call was awaited already"))?;
            let event_loop = py.import("asyncio")?.call_method0("get_running_loop")?;
            start(py, &event_loop, client, chat, call, recorder).map(Bound::unbind)
        })?;
        helpers(py)?.call_method1("_when_awaited", (begin,))
    }

    /// The base URL; several comma-separated when several serve the model.
    #[getter]
    fn base_url(&self) -> String {
        self.client.config().base_urls.join(",")
    }

    /// Every base URL.
    #[getter]
    fn base_urls(&self) -> Vec<String> {
        self.client.config().base_urls.clone()
    }

    #[getter]
    fn model(&self) -> &str {
        &self.client.config().model
    }

    /// Whether a key is set (the key itself cannot be read back).
    #[getter]
    fn has_api_key(&self) -> bool {
        self.client.config().api_key.is_some()
    }

    #[getter]
    fn temperature(&self) -> f32 {
        self.client.config().temperature
    }

    #[getter]
    fn seed(&self) -> Option<u64> {
        self.client.config().seed
    }

    /// The keyword arguments that build this LLM again elsewhere (a Ray worker), all but
    /// the key, which never leaves this process: there it comes from `OPENAI_API_KEY`;
    /// `has_api_key` says whether this one has a key.
    fn _settings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = self.client.config();
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

    /// The base URLs as shown anywhere: without user or password, query values redacted.
    fn __repr__(&self, py: Python<'_>) -> String {
        let base_url = match self.client.config().base_urls.as_slice() {
            [one] => py_repr(py, &redacted(one)),
            several => format!(
                "[{}]",
                several
                    .iter()
                    .map(|u| py_repr(py, &redacted(u)))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        format!(
            "LLM(base_url={}, model={}, api_key={}, temperature={:?})",
            base_url,
            py_repr(py, &self.client.config().model),
            if self.has_api_key() {
                "'[hidden]'"
            } else {
                "None"
            },
            self.client.config().temperature
        )
    }
}

/// Starts the call of `chat` on `event_loop` (running): an asyncio future of that loop,
/// settled from the session's runtime when the answer comes.
fn start<'py>(
    py: Python<'py>,
    event_loop: &Bound<'py, PyAny>,
    client: Arc<OpenAiClient>,
    chat: Chat,
    call: Call,
    recorder: Option<Py<Recorder>>,
) -> PyResult<Bound<'py, PyAny>> {
    let future = event_loop.call_method0("create_future")?;
    let settle = helpers(py)?.getattr("_settle")?.unbind();
    let (event_loop, pending) = (event_loop.clone().unbind(), future.clone().unbind());
    runtime()?.spawn(async move {
        let result = ask(client, chat, call, recorder).await;
        Python::attach(|py| {
            let (ok, value) = match result {
                Ok(answer) => match Py::new(py, PyReply { answer }) {
                    Ok(reply) => (true, reply.into_any()),
                    Err(e) => (false, e.into_value(py).into_any()),
                },
                Err(e) => (
                    false,
                    errors::backend(py, e.to_string()).into_value(py).into_any(),
                ),
            };
            // A loop closed meanwhile has nobody waiting.
            let _ =
                event_loop.call_method1(py, "call_soon_threadsafe", (settle, pending, ok, value));
        });
    });
    Ok(future)
}

impl PyLlm {
    /// The request and the transcript's record of it, from `chat`'s arguments.
    fn request(
        &self,
        messages: &Bound<'_, PyAny>,
        schema: Option<&Bound<'_, PyAny>>,
        max_tokens: u32,
        role: &str,
        robot: Option<i64>,
    ) -> PyResult<(Chat, Call)> {
        let messages = messages_of(messages)?;
        let schema = match schema {
            Some(s) if !s.is_none() => Some(("answer".to_owned(), json_at(s, "schema")?)),
            _ => None,
        };
        let role = match role {
            "assigner" => Role::Assigner,
            "executor" => Role::Executor,
            other => {
                return Err(PyValueError::new_err(format!(
                    "role {other:?}: expected \"assigner\" or \"executor\""
                )));
            }
        };
        let call = Call {
            role,
            robot,
            messages: messages.clone(),
            answer: None,
            error: None,
            client: Some(self.client.info()),
            endpoint: None,
            shared_prefix: None,
        };
        let chat = Chat {
            messages,
            schema,
            max_tokens,
        };
        Ok((chat, call))
    }
}

/// Chat messages from a str (one user message) or a list of `{"role", "content"}`.
fn messages_of(messages: &Bound<'_, PyAny>) -> PyResult<Vec<Message>> {
    if let Ok(text) = messages.cast::<PyString>() {
        return Ok(vec![Message::user(text.to_cow()?.into_owned())]);
    }
    let wrong = || {
        PyTypeError::new_err(
            "messages: expected a str or a list of {\"role\": str, \"content\": str} dicts",
        )
    };
    let list = messages.cast::<PyList>().map_err(|_| wrong())?;
    list.iter()
        .map(|item| {
            let d = item.cast::<PyDict>().map_err(|_| wrong())?;
            let field = |key: &str| -> PyResult<String> {
                d.get_item(key)?
                    .ok_or_else(wrong)?
                    .extract::<String>()
                    .map_err(|_| wrong())
            };
            Ok(Message {
                role: field("role")?,
                content: field("content")?,
            })
        })
        .collect()
}

/// A model's answer to `LLM.chat`: the text, the tokens, the time.
#[pyclass(name = "Reply", module = "coherent._coherent", frozen)]
pub(crate) struct PyReply {
    answer: Answer,
}

#[pymethods]
impl PyReply {
    /// The answer's text (empty when the model refused or a filter withheld it).
    #[getter]
    fn text(&self) -> &str {
        &self.answer.text
    }

    #[getter]
    fn prompt_tokens(&self) -> u64 {
        self.answer.usage.prompt_tokens
    }

    #[getter]
    fn completion_tokens(&self) -> u64 {
        self.answer.usage.completion_tokens
    }

    /// From the request to the answer, retries included.
    #[getter]
    fn latency_ms(&self) -> f64 {
        self.answer.latency_ms
    }

    /// HTTP attempts it took (1 without retries).
    #[getter]
    fn attempts(&self) -> u32 {
        self.answer.attempts
    }

    /// Why generation stopped: `"stop"`, `"length"` (cut at `max_tokens`), `"refusal"`,
    /// `"content_filter"`, or the server's own word.
    #[getter]
    fn finish(&self) -> &str {
        match &self.answer.finish {
            Finish::Stop => "stop",
            Finish::Length => "length",
            Finish::Refusal(_) => "refusal",
            Finish::ContentFilter => "content_filter",
            Finish::Other(word) => word,
        }
    }

    /// The model's words when it refused.
    #[getter]
    fn refusal(&self) -> Option<&str> {
        match &self.answer.finish {
            Finish::Refusal(words) => Some(words),
            _ => None,
        }
    }

    /// The answer format the request asked for: `"json_schema"`, `"json_object"` (a
    /// server that refused a schema) or `"text"`.
    #[getter]
    fn format(&self) -> &'static str {
        match self.answer.mode {
            OutputMode::JsonSchema => "json_schema",
            OutputMode::JsonObject => "json_object",
            OutputMode::Text => "text",
        }
    }

    fn __str__(&self) -> &str {
        &self.answer.text
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "Reply(text={}, prompt_tokens={}, completion_tokens={}, latency_ms={:.1}, finish={})",
            py_repr(py, &self.answer.text),
            self.prompt_tokens(),
            self.completion_tokens(),
            self.answer.latency_ms,
            py_repr(py, self.finish())
        )
    }
}
