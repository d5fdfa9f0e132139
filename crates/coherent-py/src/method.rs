//! Methods written in Python: a class (or any callable) `M` becomes a method of the
//! engine (an `External` method of the session's engine): `M(task)` once per episode, then
//! `act(view)` once per step, given a `View` and answering a `Decision` or a
//! `(robot, action)` tuple (in a parallel episode, a list of them, one per robot that
//! acts). `M(task)` and a plain `act` run on the episode's method thread
//! (`crate::stepper`), with the GIL held for the call only, while the episode waits
//! without it (and may stop waiting: Ctrl-C, the step's time limit); a coroutine that
//! `act` returns runs on the run's event loop (`coherent._methods.Loop`), where those of
//! concurrent episodes overlap.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use std::path::Path;

use coherent::session::backend::RecordedRun;
use coherent::session::bench::recorded_method;
use coherent::session::engine::{
    Act, BoxFuture, Builtin, Call, Choice, External, MakePolicy, MethodFailure, MethodSpec, NodeId,
    Policy, ReadLimits, RobotView, StepView, Task,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyList, PyTuple};
use tokio::sync::oneshot;

use crate::convert::{json_at, py_repr, to_py};
use crate::errors::{self, PyCoherentResult};
use crate::stepper::{Stepper, Threads};
use crate::task::PyTask;

/// `coherent._methods`, imported once.
pub(crate) fn helpers(py: Python<'_>) -> PyResult<&Bound<'_, PyModule>> {
    static MODULE: PyOnceLock<Py<PyModule>> = PyOnceLock::new();
    MODULE
        .get_or_try_init(py, || Ok(py.import("coherent._methods")?.unbind()))
        .map(|m| m.bind(py))
}

/// The model calls one step made through `coherent.LLM`, filed by the call as it ends.
#[pyclass(module = "coherent._coherent", frozen)]
pub(crate) struct Recorder {
    calls: Arc<Mutex<Vec<Call>>>,
}

impl Recorder {
    pub(crate) fn push(&self, call: Call) {
        self.calls
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(call);
    }

    /// The recorder of the step being decided on this thread or task, if any.
    pub(crate) fn current(py: Python<'_>) -> PyResult<Option<Py<Recorder>>> {
        let current = helpers(py)?.getattr("_step")?.call_method0("get")?;
        Ok(current.cast_into::<Recorder>().ok().map(Bound::unbind))
    }
}

/// What a method is shown at each step.
#[pyclass(name = "View", module = "coherent._coherent", frozen)]
pub(crate) struct PyView {
    view: Arc<StepView>,
    task: Py<PyTask>,
}

fn robot_of(view: &StepView, robot: i64) -> PyResult<&RobotView> {
    view.robot(NodeId(robot)).ok_or_else(|| {
        let ids: Vec<String> = view.robots.iter().map(|r| r.id.0.to_string()).collect();
        PyValueError::new_err(format!(
            "robot {robot} is not in the team ({})",
            ids.join(", ")
        ))
    })
}

#[pymethods]
impl PyView {
    /// The task of the episode (the same object every step).
    #[getter]
    fn task(&self, py: Python<'_>) -> Py<PyTask> {
        self.task.clone_ref(py)
    }

    /// The step about to be taken, from 1.
    #[getter]
    fn step(&self) -> u32 {
        self.view.step
    }

    /// The step budget (2 x GT unless set; 2 x the fewest joint steps in parallel).
    #[getter]
    fn max_steps(&self) -> u32 {
        self.view.max_steps
    }

    /// What happened since the last step that the team did not do (the task's events,
    /// docs/dynamic.md), a sentence each; empty without events.
    #[getter]
    fn news(&self) -> Vec<String> {
        self.view.news.clone()
    }

    /// `"sequential"` (`act` answers one decision a step) or `"parallel"` (a list: one
    /// decision per robot that acts, all carried out at once).
    #[getter]
    fn execution(&self) -> &'static str {
        self.view.execution.name()
    }

    /// Node ids of the robots, in the task's order.
    #[getter]
    fn robots(&self) -> Vec<i64> {
        self.view.robots.iter().map(|r| r.id.0).collect()
    }

    /// Robot node id -> `"quadrotor"`, `"robot dog"` or `"robot arm"`.
    #[getter]
    fn robot_types<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for r in &self.view.robots {
            dict.set_item(r.id.0, r.kind.class_name())?;
        }
        Ok(dict)
    }

    /// Robot node id -> the action strings it may use now.
    #[getter]
    fn actions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for r in &self.view.robots {
            dict.set_item(r.id.0, &r.actions)?;
        }
        Ok(dict)
    }

    /// Every earlier step, oldest first: `(robot, action, ok, reason)`, robot and action
    /// None for a step without an action, reason None when it ran; of a parallel step,
    /// one for each robot given an action in it, in team order.
    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for h in &self.view.history {
            let item = (h.robot.map(|r| r.0), &h.action, h.ok, &h.reason);
            list.append(item.into_pyobject(py)?)?;
        }
        Ok(list)
    }

    /// What `robot` sees, as `Env.observe` gives it: `{"room", "nodes", "edges"}`.
    fn observation<'py>(&self, py: Python<'py>, robot: i64) -> PyResult<Bound<'py, PyDict>> {
        let r = robot_of(&self.view, robot)?;
        let task = &self.view.task;
        let o = &r.observation;
        let graph = task.raw_subgraph(&self.view.state, &o.nodes, &o.edges);
        let dict = PyDict::new(py);
        dict.set_item("room", o.room.map(|room| task.id(room).0))?;
        dict.set_item("nodes", to_py(py, &graph.nodes)?)?;
        dict.set_item("edges", to_py(py, &graph.edges)?)?;
        Ok(dict)
    }

    /// The observation of `robot` as relation facts, one per line, in one block (the
    /// paper's layout of the executors' prompts); with no robot, every robot's merged, as
    /// the task assigner's and the central prompt have it.
    #[pyo3(signature = (robot = None))]
    fn observation_text(&self, robot: Option<i64>) -> PyResult<String> {
        if let Some(id) = robot {
            robot_of(&self.view, id)?;
        }
        Ok(self
            .view
            .observation_text(robot.map(NodeId))
            .unwrap_or_default())
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let meta = &self.view.task.meta;
        format!(
            "View(scene={}, task_id={}, step={}, max_steps={}, robots={:?})",
            py_repr(py, &meta.scene),
            meta.task_id,
            self.view.step,
            self.view.max_steps,
            self.robots()
        )
    }
}

/// A method's decision for one step.
#[pyclass(name = "Decision", module = "coherent._coherent", frozen, eq)]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PyDecision {
    /// The robot that acts; None for no action this step (it still costs the step).
    #[pyo3(get)]
    robot: Option<i64>,
    /// The action, as written; one outside the robot's list is refused with the reason.
    #[pyo3(get)]
    action: Option<String>,
    /// Your own words about the step, kept in the transcript.
    #[pyo3(get)]
    note: String,
    /// Tokens and calls of models the method asked through its own clients (those asked
    /// through `coherent.LLM` inside `act` are counted already).
    #[pyo3(get)]
    prompt_tokens: u64,
    #[pyo3(get)]
    completion_tokens: u64,
    #[pyo3(get)]
    calls: u32,
}

#[pymethods]
impl PyDecision {
    #[new]
    #[pyo3(signature = (robot, action, note = String::new(), prompt_tokens = 0, completion_tokens = 0, calls = 0))]
    fn new(
        robot: Option<i64>,
        action: Option<String>,
        note: String,
        prompt_tokens: u64,
        completion_tokens: u64,
        calls: u32,
    ) -> PyResult<PyDecision> {
        if robot.is_some() && action.is_none() {
            return Err(PyValueError::new_err(
                "a decision for a robot needs an action (robot=None is no action)",
            ));
        }
        Ok(PyDecision {
            robot,
            action,
            note,
            prompt_tokens,
            completion_tokens,
            calls,
        })
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let text = |s: &Option<String>| s.as_deref().map_or("None".into(), |s| py_repr(py, s));
        format!(
            "Decision(robot={}, action={}, note={}, prompt_tokens={}, completion_tokens={}, calls={})",
            self.robot.map_or("None".into(), |r| r.to_string()),
            text(&self.action),
            py_repr(py, &self.note),
            self.prompt_tokens,
            self.completion_tokens,
            self.calls
        )
    }
}

/// What `act` answered: its decisions, one per robot that acts, or why none could be
/// read (the method's own words).
type Answered = Result<Vec<Choice>, String>;

/// What `act` returned, as its choices: a list of decisions (several robots' in a
/// parallel episode), or one; anything else is the method's error.
fn choices_of(answer: &Bound<'_, PyAny>) -> Answered {
    match answer.cast::<PyList>() {
        Ok(list) => list.iter().map(|item| choice_of(&item)).collect(),
        Err(_) => choice_of(answer).map(|c| vec![c]),
    }
}

/// One decision `act` returned, as a choice; anything else is the method's error.
fn choice_of(answer: &Bound<'_, PyAny>) -> Result<Choice, String> {
    if let Ok(d) = answer.cast::<PyDecision>() {
        let d = d.get();
        return Ok(Choice {
            robot: d.robot.map(NodeId),
            action: d.action.clone(),
            note: d.note.clone(),
            prompt_tokens: d.prompt_tokens,
            completion_tokens: d.completion_tokens,
            calls: d.calls,
        });
    }
    let pair = answer
        .cast::<PyTuple>()
        .ok()
        .filter(|t| t.len() == 2)
        .and_then(|t| t.extract::<(Option<i64>, Option<String>)>().ok());
    match pair {
        Some((robot, action)) if robot.is_none() || action.is_some() => Ok(Choice {
            robot: robot.map(NodeId),
            action,
            ..Choice::default()
        }),
        _ => Err(format!(
            "act returned {}: expected a coherent.Decision or a (robot, action) tuple of an \
             int (or None) and a str (or, in a parallel episode, a list of them)",
            answer
                .repr()
                .map_or_else(|_| "an object".into(), |r| r.to_string())
        )),
    }
}

/// One method written in Python, for the runs of one `run`, `bench` or command.
pub(crate) struct PythonMethod {
    factory: Py<PyAny>,
    /// The Python tasks of the run, so that `M(task)` gets the caller's own objects.
    tasks: Vec<Py<PyTask>>,
    /// The run's event loop (`coherent._methods.Loop`).
    runner: Py<PyAny>,
    /// The last exception the method raised, to chain when `run` raises.
    last_error: Mutex<Option<PyErr>>,
    /// The threads its episodes' calls run on.
    threads: Threads,
}

impl PythonMethod {
    /// The exception the method raised last, if any (taken).
    pub(crate) fn take_error(&self) -> Option<PyErr> {
        self.last_error
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take()
    }

    /// `error` as the text of the transcript and results line, kept for `run` to chain
    /// (unless it is the interruption of a call the episode stopped waiting for).
    fn failed(&self, py: Python<'_>, error: PyErr) -> String {
        let text = helpers(py)
            .and_then(|h| h.call_method1("describe", (error.value(py), error.traceback(py))))
            .and_then(|t| t.extract::<String>())
            .unwrap_or_else(|_| error.to_string());
        let stopped = helpers(py)
            .and_then(|h| h.getattr("StepStopped"))
            .is_ok_and(|t| error.get_type(py).is(&t));
        if !stopped {
            *self
                .last_error
                .lock()
                .unwrap_or_else(PoisonError::into_inner) = Some(error);
        }
        text
    }

    fn task_object(&self, py: Python<'_>, task: &Arc<Task>) -> PyResult<Py<PyTask>> {
        match self.tasks.iter().find(|t| Arc::ptr_eq(&t.get().task, task)) {
            Some(t) => Ok(t.clone_ref(py)),
            None => Py::new(py, PyTask::shared(Arc::clone(task))),
        }
    }
}

/// A run's methods written in Python and its event loop, closed when the run ends.
pub(crate) struct Methods {
    runner: Py<PyAny>,
    pub methods: Vec<Arc<PythonMethod>>,
    /// The longest one step of each may take (`step_timeout=`).
    step_timeout: Option<Duration>,
}

impl Methods {
    pub(crate) fn new(py: Python<'_>, step_timeout: Option<Duration>) -> PyResult<Methods> {
        Ok(Methods {
            runner: helpers(py)?.getattr("Loop")?.call0()?.unbind(),
            methods: Vec::new(),
            step_timeout,
        })
    }

    /// `method` (a class or any callable) as a method of the engine, named by its `name`
    /// or its class's name, with the settings it declares (`settings`, recorded in its
    /// results lines); `tasks` are the run's Python tasks.
    pub(crate) fn add(
        &mut self,
        method: &Bound<'_, PyAny>,
        tasks: &[Py<PyTask>],
    ) -> PyCoherentResult<External> {
        let py = method.py();
        if !method.is_callable() {
            return Err(PyTypeError::new_err(format!(
                "method {}: expected a method's name, or a class (any callable) whose \
                 objects have act(view)",
                method.repr()?
            ))
            .into());
        }
        let name: String = helpers(py)?
            .call_method1("method_name", (method,))?
            .extract()?;
        let declared = helpers(py)?.call_method1("method_settings", (method,))?;
        let settings = match json_at(&declared, &format!("{name}.settings"))? {
            serde_json::Value::Object(map) => map.into_iter().collect(),
            _ => BTreeMap::new(),
        };
        let shared = Arc::new(PythonMethod {
            factory: method.clone().unbind(),
            tasks: tasks.iter().map(|t| t.clone_ref(py)).collect(),
            runner: self.runner.clone_ref(py),
            last_error: Mutex::new(None),
            threads: Threads::default(),
        });
        let maker = Arc::clone(&shared);
        // The object is made on the episode's method thread, at its first step: a
        // constructor that never returns is stopped as a step would be.
        let make: Arc<MakePolicy> = Arc::new(move |task: &Arc<Task>| {
            Ok(Box::new(PythonPolicy {
                method: Arc::clone(&maker),
                task: Arc::clone(task),
                object: Arc::new(Mutex::new(None)),
                stepper: Stepper::start(&maker.threads).map_err(MethodFailure)?,
            }) as Box<dyn Policy>)
        });
        let external = External::new(&name, make)?
            .with_step_timeout(self.step_timeout)
            .with_settings(settings);
        self.methods.push(shared);
        Ok(external)
    }

    /// Stops the run's event loop (coroutines still running are cancelled), and gives
    /// the methods' threads still ending a stopped call two seconds to end.
    pub(crate) fn close(&self, py: Python<'_>) -> PyResult<()> {
        let deadline = Instant::now() + Duration::from_secs(2);
        py.detach(|| {
            for m in &self.methods {
                m.threads.settle(deadline);
            }
        });
        self.runner.call_method0(py, "close").map(drop)
    }
}

/// The policy of one episode: the object `M(task)`, made at the first step, and the
/// thread its calls run on.
struct PythonPolicy {
    method: Arc<PythonMethod>,
    task: Arc<Task>,
    /// `M(task)`, once made (only the stepper's thread touches it).
    object: Arc<Mutex<Option<Py<PyAny>>>>,
    stepper: Stepper,
}

/// A step's answer: at once, or from the event loop.
enum Started {
    Now(Answered),
    Later(oneshot::Receiver<Answered>, Py<PyAny>),
}

/// The episode's object `M(task)`, made on its first call (in `slot` afterwards); an
/// error is the step's, in the words of the transcript.
fn made(
    py: Python<'_>,
    method: &PythonMethod,
    slot: &Mutex<Option<Py<PyAny>>>,
    task: &Arc<Task>,
) -> Result<Py<PyAny>, String> {
    let mut slot = slot.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some(object) = slot.as_ref() {
        return Ok(object.clone_ref(py));
    }
    let object = method
        .task_object(py, task)
        .and_then(|t| method.factory.call1(py, (t,)))
        .map_err(|e| method.failed(py, e))?;
    if !object.bind(py).hasattr("act").unwrap_or(false) {
        return Err(format!(
            "TypeError: {} has no act(view) method",
            object
                .bind(py)
                .repr()
                .map_or("the method".into(), |r| r.to_string())
        ));
    }
    *slot = Some(object.clone_ref(py));
    Ok(object)
}

/// Calls `object.act(view)` with the step's recorder current; a coroutine goes to the
/// loop.
fn start(
    py: Python<'_>,
    object: &Py<PyAny>,
    method: &Arc<PythonMethod>,
    view: Arc<StepView>,
    recorder: &Py<Recorder>,
) -> PyResult<Started> {
    let task = method.task_object(py, &view.task)?;
    let view = Py::new(py, PyView { view, task })?;
    let step = helpers(py)?.getattr("_step")?;
    let token = step.call_method1("set", (recorder,))?;
    let answer = object.call_method1(py, "act", (view,));
    step.call_method1("reset", (token,))?;
    let answer = match answer {
        Ok(a) => a.into_bound(py),
        Err(e) => return Ok(Started::Now(Err(method.failed(py, e)))),
    };
    if !answer.hasattr("__await__")? {
        return Ok(Started::Now(choices_of(&answer)));
    }
    let (tx, rx) = oneshot::channel();
    let done = Done {
        tx: Mutex::new(Some(tx)),
        method: Arc::clone(method),
    };
    let runner = method.runner.bind(py);
    let future = runner.call_method1("submit", (answer, recorder, done))?;
    Ok(Started::Later(rx, future.unbind()))
}

impl Policy for PythonPolicy {
    fn act(&mut self, view: Arc<StepView>) -> BoxFuture<'_, Act> {
        Box::pin(async move {
            let calls = Arc::new(Mutex::new(Vec::new()));
            let (method, slot, task) = (
                Arc::clone(&self.method),
                Arc::clone(&self.object),
                Arc::clone(&self.task),
            );
            let recorded = Arc::clone(&calls);
            let started = self
                .stepper
                .run(move |py| -> Result<Started, String> {
                    let object = made(py, &method, &slot, &task)?;
                    let recorder = Py::new(py, Recorder { calls: recorded });
                    recorder
                        .and_then(|r| start(py, &object, &method, view, &r))
                        .map_err(|e| method.failed(py, e))
                })
                .await;
            let choice = match started {
                Some(Ok(Started::Now(choice))) => choice,
                Some(Ok(Started::Later(rx, future))) => {
                    // Dropped (the episode cancelled) before it ends: cancel the coroutine.
                    let mut pending = CancelOnDrop(Some(future));
                    let answer = rx.await;
                    pending.0 = None;
                    answer.unwrap_or_else(|_| Err("the coroutine of act was cancelled".into()))
                }
                Some(Err(why)) => Err(why),
                None => Err("the method's thread has ended".into()),
            };
            let calls = std::mem::take(&mut *calls.lock().unwrap_or_else(PoisonError::into_inner));
            Act {
                choices: choice.map_err(MethodFailure),
                calls,
            }
        })
    }
}

/// Cancels a coroutine's future when dropped while it is still set.
struct CancelOnDrop(Option<Py<PyAny>>);

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        if let Some(future) = self.0.take() {
            Python::attach(|py| {
                let _ = future.call_method0(py, "cancel");
            });
        }
    }
}

/// Called on the event loop's thread when a coroutine of `act` ends: its answer, or its
/// exception, goes to the waiting episode.
#[pyclass(module = "coherent._coherent", frozen)]
struct Done {
    tx: Mutex<Option<oneshot::Sender<Answered>>>,
    method: Arc<PythonMethod>,
}

#[pymethods]
impl Done {
    fn __call__(&self, future: &Bound<'_, PyAny>) {
        let py = future.py();
        let choice = match future.call_method0("result") {
            Ok(answer) => choices_of(&answer),
            Err(e) => Err(self.method.failed(py, e)),
        };
        if let Some(tx) = self
            .tx
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take()
        {
            // The episode may have stopped waiting (cancelled): nobody wants it then.
            let _ = tx.send(choice);
        }
    }
}

/// The built-in method named `name`; an `ArgumentError` listing them otherwise.
pub(crate) fn method_of(py: Python<'_>, name: &str) -> PyResult<Builtin> {
    Builtin::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Builtin::ALL.iter().map(|m| m.name()).collect();
        errors::invalid(
            py,
            format!("unknown method {name:?}; the methods: {}", names.join(", ")),
        )
    })
}

/// What `method=` and `methods=` take: a built-in method's name, `"MODULE:CLASS"`, or a
/// class (any callable) of a method written in Python.
pub(crate) enum MethodArg {
    Name(String),
    Python(Py<PyAny>),
}

impl MethodArg {
    /// The method, with those written in Python added to `methods` (`tasks`: the run's).
    pub(crate) fn spec(
        &self,
        py: Python<'_>,
        methods: &mut Methods,
        tasks: &[Py<PyTask>],
    ) -> PyCoherentResult<MethodSpec> {
        match self {
            MethodArg::Name(name) if name.contains(':') => {
                let found = helpers(py)?.call_method1("load", (name,))?;
                methods.add(&found, tasks).map(MethodSpec::External)
            }
            MethodArg::Name(name) => Ok(method_of(py, name)?.into()),
            MethodArg::Python(object) => methods
                .add(object.bind(py), tasks)
                .map(MethodSpec::External),
        }
    }

    /// The method as the replay of the results file `results` runs it: a built-in one,
    /// or the recorded one of the name a method written in Python goes by, whose
    /// decisions replay without its code (a `MODULE:CLASS` that cannot be loaded any
    /// more is an error listing the recorded names).
    pub(crate) fn recorded(&self, py: Python<'_>, results: &Path) -> PyCoherentResult<MethodSpec> {
        let name = match self {
            MethodArg::Name(name) if !name.contains(':') => {
                if let Some(method) = Builtin::from_name(name) {
                    return Ok(method.into());
                }
                name.clone()
            }
            MethodArg::Name(spec) => match helpers(py)?.call_method1("load", (spec,)) {
                Ok(found) => helpers(py)?
                    .call_method1("method_name", (found,))?
                    .extract()?,
                Err(e) => {
                    let names = RecordedRun::read(results, ReadLimits::default())?
                        .methods()
                        .join(", ");
                    return Err(errors::invalid(
                        py,
                        format!(
                            "method {spec}: {e}; a replay runs the recorded decisions and \
                             needs no code: name the method as {} records it ({names})",
                            results.display()
                        ),
                    )
                    .into());
                }
            },
            MethodArg::Python(object) => helpers(py)?
                .call_method1("method_name", (object,))?
                .extract()?,
        };
        Ok(recorded_method(results, &name, ReadLimits::default())?)
    }
}
