//! Python bindings of `coherent`: the `coherent._coherent` extension module.
//!
//! Thin on purpose: this file converts types and errors and releases the GIL around
//! long work; behaviour lives in `coherent-core` and in the `coherent` command line.

use std::ffi::OsString;
use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use coherent_core::planner::{self, Limits};
use coherent_core::{
    Environment, Error, NodeId, RawGraph, SymbolicEnv, Task, action, load, native, original,
};
use pyo3::IntoPyObjectExt;
use pyo3::exceptions::{PyException, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyList, PyString, PyTuple, PyType};
use serde_json::Value;

const MODULE: &str = "coherent._coherent";

// ---------------------------------------------------------------------------------------
// Exceptions

/// The exception tree. Built with `type(...)` rather than `create_exception!` because
/// two of them also derive from `ValueError` (bad input), which needs two bases.
struct Exceptions {
    base: Py<PyType>,
    task_format: Py<PyType>,
    unknown_robot: Py<PyType>,
    action_parse: Py<PyType>,
    physics: Py<PyType>,
}

static EXCEPTIONS: PyOnceLock<Exceptions> = PyOnceLock::new();

fn exceptions(py: Python<'_>) -> PyResult<&'static Exceptions> {
    EXCEPTIONS.get_or_try_init(py, || {
        let make = |name: &str, bases: Vec<Bound<'_, PyType>>, doc: &str| -> PyResult<Py<PyType>> {
            let namespace = PyDict::new(py);
            namespace.set_item("__module__", MODULE)?;
            namespace.set_item("__doc__", doc)?;
            let bases = PyTuple::new(py, bases)?;
            let ty = py.get_type::<PyType>().call1((name, bases, namespace))?;
            Ok(ty.cast_into::<PyType>()?.unbind())
        };
        let value_error = py.get_type::<PyValueError>();
        let base = make(
            "CoherentError",
            vec![py.get_type::<PyException>()],
            "Base class of every error raised by coherent.",
        )?;
        let task_format = make(
            "TaskFormatError",
            vec![base.bind(py).clone(), value_error.clone()],
            "A task file or folder that cannot be read or does not follow its format.\n\n\
             The message names the file, the JSON path and the offending value; the\n\
             attributes `file` and `json_path` (None when the file could not be read at\n\
             all) hold the first two.",
        )?;
        let unknown_robot = make(
            "UnknownRobotError",
            vec![base.bind(py).clone()],
            "A robot id that is not a robot of the task; the message lists its robots.",
        )?;
        let action_parse = make(
            "ActionParseError",
            vec![base.bind(py).clone(), value_error],
            "An action string that does not follow the grammar `[verb] <name>(id)`.\n\n\
             Attributes: `action` (the text) and `reason`.",
        )?;
        let physics = make(
            "PhysicsError",
            vec![base.bind(py).clone()],
            "The physical simulation cannot build a task's scene; the message says why,\n\
             with the numbers.",
        )?;
        Ok(Exceptions {
            base,
            task_format,
            unknown_robot,
            action_parse,
            physics,
        })
    })
}

/// Converts a `coherent-core` error into the matching Python exception.
fn py_err(py: Python<'_>, e: Error) -> PyErr {
    match build_py_err(py, &e) {
        Ok(err) => err,
        // Only when Python itself fails (e.g. out of memory): say that, keeping the message.
        Err(inner) => PyRuntimeError::new_err(format!("{e} (while raising it: {inner})")),
    }
}

fn build_py_err(py: Python<'_>, e: &Error) -> PyResult<PyErr> {
    let exc = exceptions(py)?;
    let message = e.to_string();
    let value = match e {
        Error::Io { file, .. } => {
            let v = exc.task_format.bind(py).call1((message,))?;
            v.setattr("file", file)?;
            v.setattr("json_path", py.None())?;
            v
        }
        Error::Malformed { file, path, .. } => {
            let v = exc.task_format.bind(py).call1((message,))?;
            v.setattr("file", file)?;
            v.setattr("json_path", path.to_string())?;
            v
        }
        Error::UnknownRobot(_) => exc.unknown_robot.bind(py).call1((message,))?,
        Error::BadAction { action, reason } => {
            let v = exc.action_parse.bind(py).call1((message,))?;
            v.setattr("action", action)?;
            v.setattr("reason", reason)?;
            v
        }
    };
    Ok(PyErr::from_value(value))
}

// ---------------------------------------------------------------------------------------
// Conversions

/// A JSON value as the Python object `json.loads` would give (key order kept).
fn json_to_py<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    match value {
        Value::Null => Ok(py.None().into_bound(py)),
        Value::Bool(b) => b.into_bound_py_any(py),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_bound_py_any(py)
            } else if let Some(u) = n.as_u64() {
                u.into_bound_py_any(py)
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_bound_py_any(py)
            }
        }
        Value::String(s) => s.into_bound_py_any(py),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(json_to_py(py, item)?)?;
            }
            Ok(list.into_any())
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, v) in map {
                dict.set_item(k, json_to_py(py, v)?)?;
            }
            Ok(dict.into_any())
        }
    }
}

/// Puts `graph`'s `nodes` and `edges` (the original format's field names) into `dict`.
fn put_graph(dict: &Bound<'_, PyDict>, graph: &RawGraph) -> PyResult<()> {
    dict.set_item("nodes", to_py(dict.py(), &graph.nodes)?)?;
    dict.set_item("edges", to_py(dict.py(), &graph.edges)?)
}

/// Any serializable value as a Python object, through JSON.
fn to_py<'py, T: serde::Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    let value = serde_json::to_value(value).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    json_to_py(py, &value)
}

/// Runs `f` on its own thread with the GIL released, checking for Ctrl-C (and other
/// signals) every 50 ms. On an interrupt it sets `cancel`, which stops the planner
/// within a few milliseconds, waits for the thread, and raises the interrupt.
fn interruptible<T, F>(py: Python<'_>, cancel: Arc<AtomicBool>, f: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce() -> T + Send + 'static,
{
    let (tx, mut rx) = mpsc::channel();
    let worker = std::thread::Builder::new()
        .name("coherent-planner".to_owned())
        .spawn(move || {
            // The receiver is gone only after an interrupt; nobody wants the result then.
            let _ = tx.send(f());
        })
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start the planner thread: {e}")))?;
    loop {
        // A `&mut` borrow, not `&`: the receiver may move to another thread but not be shared.
        let receiver = &mut rx;
        match py.detach(move || receiver.recv_timeout(Duration::from_millis(50))) {
            Ok(result) => return Ok(result),
            Err(RecvTimeoutError::Timeout) => {
                if let Err(interrupt) = py.check_signals() {
                    cancel.store(true, Ordering::Relaxed);
                    // The search notices within about a thousand states.
                    let _ = py.detach(move || worker.join());
                    return Err(interrupt);
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err(
                    "the planner thread panicked (a bug in coherent-core; see the message on stderr)",
                ));
            }
        }
    }
}

fn py_repr(py: Python<'_>, s: &str) -> String {
    PyString::new(py, s)
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| format!("{s:?}"))
}

// ---------------------------------------------------------------------------------------
// Task

/// A task: the scene graph at the start, the robots, the goal and the ground truth.
#[pyclass(name = "Task", module = "coherent._coherent", frozen)]
struct PyTask(Arc<Task>);

#[pymethods]
impl PyTask {
    /// The scene: the original file's stem (`env0`) or the native file's `scene`.
    #[getter]
    fn scene(&self) -> &str {
        &self.0.meta.scene
    }

    #[getter]
    fn task_id(&self) -> i64 {
        self.0.meta.task_id
    }

    #[getter]
    fn name(&self) -> &str {
        &self.0.meta.name
    }

    #[getter]
    fn instruction(&self) -> &str {
        &self.0.meta.instruction
    }

    /// The ground truth's number of steps, when the file gives one.
    #[getter]
    fn gt_steps(&self) -> Option<u32> {
        self.0.meta.gt_steps
    }

    /// Node ids of the robots, in graph order.
    #[getter]
    fn robots(&self) -> Vec<i64> {
        self.0.robots.iter().map(|r| self.0.id(r.node).0).collect()
    }

    /// Robot node id -> `"quadrotor"`, `"robot dog"` or `"robot arm"`.
    #[getter]
    fn robot_types<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for r in &self.0.robots {
            dict.set_item(self.0.id(r.node).0, r.kind.class_name())?;
        }
        Ok(dict)
    }

    /// The goal predicates, as `on_<apple>(3)_<table>(5)` / `inside_<a>(i)_<b>(j)`.
    #[getter]
    fn goal(&self) -> Vec<String> {
        self.0
            .goal
            .iter()
            .map(|p| self.0.predicate_label(p))
            .collect()
    }

    /// The task as a native task file (a JSON object).
    fn to_native<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &native::to_value(&self.0))
    }

    /// The task in the original format (one element of a scene file's list).
    fn to_original<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &original::to_value(&self.0))
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let meta = &self.0.meta;
        format!(
            "Task(scene={}, task_id={}, name={}, robots={:?}, goal={:?})",
            py_repr(py, &meta.scene),
            meta.task_id,
            py_repr(py, &meta.name),
            self.robots(),
            self.goal()
        )
    }
}

// ---------------------------------------------------------------------------------------
// Env

/// A task's environment: robots observe and act one action at a time, by the rules, and
/// with `physics=True` also in Rapier.
#[pyclass(name = "Env", module = "coherent._coherent")]
struct PyEnv {
    env: Box<dyn Environment + Send + Sync>,
    task: Py<PyTask>,
    physics: bool,
}

#[pymethods]
impl PyEnv {
    #[new]
    #[pyo3(signature = (task, physics = false))]
    fn new(py: Python<'_>, task: Bound<'_, PyTask>, physics: bool) -> PyResult<PyEnv> {
        let t = Arc::clone(&task.get().0);
        let env: Box<dyn Environment + Send + Sync> = if physics {
            let built = py.detach(|| coherent_sim::PhysicalEnv::new(t));
            Box::new(built.map_err(|e| {
                exceptions(py).map_or_else(
                    |inner| inner,
                    |exc| PyErr::from_type(exc.physics.bind(py).clone(), e.message),
                )
            })?)
        } else {
            Box::new(SymbolicEnv::new(t))
        };
        Ok(PyEnv {
            env,
            task: task.unbind(),
            physics,
        })
    }

    /// Whether actions are also carried out in physics.
    #[getter]
    fn physics(&self) -> bool {
        self.physics
    }

    /// The task this environment runs.
    #[getter]
    fn task(&self, py: Python<'_>) -> Py<PyTask> {
        self.task.clone_ref(py)
    }

    /// Node ids of the robots.
    #[getter]
    fn robots(&self) -> Vec<i64> {
        let task = self.env.task();
        task.robots.iter().map(|r| task.id(r.node).0).collect()
    }

    /// What `robot` sees: `{"room": id | None, "nodes": [...], "edges": [...]}`, nodes and
    /// edges with the original format's field names.
    fn observe<'py>(&self, py: Python<'py>, robot: i64) -> PyResult<Bound<'py, PyDict>> {
        let obs = self.env.observe(NodeId(robot)).map_err(|e| py_err(py, e))?;
        let task = self.env.task();
        let graph = task.raw_subgraph(self.env.state(), &obs.nodes, &obs.edges);
        let dict = PyDict::new(py);
        dict.set_item("room", obs.room.map(|r| task.id(r).0))?;
        put_graph(&dict, &graph)?;
        Ok(dict)
    }

    /// The action strings `robot` may use now.
    fn actions(&self, py: Python<'_>, robot: i64) -> PyResult<Vec<String>> {
        self.env.actions(NodeId(robot)).map_err(|e| py_err(py, e))
    }

    /// Tries `action` for `robot`: `(ok, reason, done)`. An infeasible or unparsable
    /// action is not an error: `ok` is False and `reason` says why.
    fn step(
        &mut self,
        py: Python<'_>,
        robot: i64,
        action: &str,
    ) -> PyResult<(bool, Option<String>, bool)> {
        let outcome = self
            .env
            .step(NodeId(robot), action)
            .map_err(|e| py_err(py, e))?;
        Ok((
            outcome.executed(),
            outcome.infeasible.map(|i| i.message),
            outcome.done,
        ))
    }

    fn goal_satisfied(&self) -> bool {
        self.env.goal_satisfied()
    }

    /// The whole current graph: `{"nodes": [...], "edges": [...]}`.
    fn graph<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        put_graph(&dict, &self.env.task().raw_graph(self.env.state()))?;
        Ok(dict)
    }

    /// Back to the task's initial state.
    fn reset(&mut self) {
        self.env.reset();
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let meta = &self.env.task().meta;
        format!(
            "Env(scene={}, task_id={}, robots={:?}, physics={}, goal_satisfied={})",
            py_repr(py, &meta.scene),
            meta.task_id,
            self.robots(),
            if self.physics { "True" } else { "False" },
            if self.env.goal_satisfied() {
                "True"
            } else {
                "False"
            }
        )
    }
}

// ---------------------------------------------------------------------------------------
// Functions

/// Every task at `path`: an original env file, a native task file, or a folder of them.
#[pyfunction]
fn load_tasks(py: Python<'_>, path: PathBuf) -> PyResult<Vec<PyTask>> {
    let tasks = py
        .detach(|| load::load_tasks(&path))
        .map_err(|e| py_err(py, e))?;
    Ok(tasks.into_iter().map(|t| PyTask(Arc::new(t))).collect())
}

/// Every well-formed task at `path`, and a `TaskFormatError` for each malformed one, so
/// that one bad task does not hide the others (as `coherent validate` reports them).
/// A path that cannot be read, or a file that is not JSON, still raises.
#[pyfunction]
fn read_tasks(py: Python<'_>, path: PathBuf) -> PyResult<(Vec<PyTask>, Vec<Py<PyAny>>)> {
    let results = py
        .detach(|| load::read_tasks(&path))
        .map_err(|e| py_err(py, e))?;
    let mut tasks = Vec::new();
    let mut errors = Vec::new();
    for r in results {
        match r {
            Ok(t) => tasks.push(PyTask(Arc::new(t))),
            Err(e) => errors.push(py_err(py, e).into_value(py).into_any()),
        }
    }
    Ok((tasks, errors))
}

/// Plans `task` optimally: one line of `coherent plan --json`, as a dict.
///
/// The default `max_states` is `Limits::DEFAULT_MAX_STATES`, written out so that Python
/// shows it in the signature (a test pins the two together, through the CLI's `--help`).
#[pyfunction]
#[pyo3(signature = (task, max_states = 5_000_000))]
fn plan<'py>(
    py: Python<'py>,
    task: &Bound<'py, PyTask>,
    max_states: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let task = Arc::clone(&task.get().0);
    let cancel = Arc::new(AtomicBool::new(false));
    let limits = Limits {
        max_states,
        cancel: Some(Arc::clone(&cancel)),
    };
    let json = interruptible(py, cancel, move || {
        planner::analyse(&task, &limits).to_json(&task)
    })?;
    json_to_py(py, &json)
}

/// Semantic problems of `task` (empty when it is clean), as `coherent validate` lists them.
#[pyfunction(name = "validate")]
#[pyo3(signature = (task, max_states = 5_000_000))]
fn validate_task(
    py: Python<'_>,
    task: &Bound<'_, PyTask>,
    max_states: usize,
) -> PyResult<Vec<String>> {
    let task = Arc::clone(&task.get().0);
    let cancel = Arc::new(AtomicBool::new(false));
    let limits = Limits {
        max_states,
        cancel: Some(Arc::clone(&cancel)),
    };
    interruptible(py, cancel, move || {
        let analysis = planner::analyse(&task, &limits);
        coherent_core::validate::findings(&task, &analysis)
    })
}

/// Parses an action string: `{"verb", "object": {"name", "id"}, "target": ... | None}`.
#[pyfunction]
fn parse_action<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyDict>> {
    let parsed = action::parse(text).map_err(|e| py_err(py, e))?;
    let mention = |m: &action::Mention| -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("name", &m.name)?;
        d.set_item("id", m.id.0)?;
        Ok(d)
    };
    let dict = PyDict::new(py);
    dict.set_item("verb", parsed.verb.name())?;
    dict.set_item("object", mention(&parsed.object)?)?;
    dict.set_item("target", parsed.target.as_ref().map(mention).transpose()?)?;
    Ok(dict)
}

/// Runs the `coherent` command line; `argv` starts with the program name. Returns the
/// exit status.
#[pyfunction]
fn cli_main(py: Python<'_>, argv: Vec<OsString>) -> u8 {
    py.detach(|| {
        let code = coherent::cli::run(argv);
        // Python may exit right after; lines already end in newlines, this is for the rest.
        let _ = std::io::stdout().flush();
        code
    })
}

#[pymodule]
fn _coherent(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    let exc = exceptions(py)?;
    m.add("CoherentError", exc.base.clone_ref(py))?;
    m.add("TaskFormatError", exc.task_format.clone_ref(py))?;
    m.add("UnknownRobotError", exc.unknown_robot.clone_ref(py))?;
    m.add("ActionParseError", exc.action_parse.clone_ref(py))?;
    m.add("PhysicsError", exc.physics.clone_ref(py))?;
    m.add_class::<PyTask>()?;
    m.add_class::<PyEnv>()?;
    m.add_function(wrap_pyfunction!(load_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(read_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(plan, m)?)?;
    m.add_function(wrap_pyfunction!(validate_task, m)?)?;
    m.add_function(wrap_pyfunction!(parse_action, m)?)?;
    m.add_function(wrap_pyfunction!(cli_main, m)?)?;
    Ok(())
}
