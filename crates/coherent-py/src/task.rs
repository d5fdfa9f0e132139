//! `Task` and `Env`: a task's data, and stepping its world by hand.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

use coherent::session::check;
use coherent::session::engine::{
    Cancel, DEFAULT_NAMESPACE, Environment, Limits, NodeId, RawGraph, Task, TaskError, feasibility,
    most_actions, native, original, predicate_holds, robot_names,
};
use coherent::session::episode::environment;
use coherent::session::events::{self, Stepping};
use coherent::session::robots::Robots;
use pyo3::exceptions::{PyOverflowError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::convert::{
    action_text, events_source, interruptible, json_to_py, optional, py_repr, to_py, unsigned,
};

use crate::errors::{self, PyCoherentResult, core_err, short_repr};

/// A task: the scene graph at the start, the robots, the goal and the ground truth.
#[pyclass(name = "Task", module = "coherent._coherent", frozen)]
pub(crate) struct PyTask {
    pub task: Arc<Task>,
    /// The planner's task type, computed when first asked for.
    kind: OnceLock<Option<&'static str>>,
}

impl PyTask {
    pub fn new(task: Task) -> PyTask {
        PyTask::shared(Arc::new(task))
    }

    pub fn shared(task: Arc<Task>) -> PyTask {
        PyTask {
            task,
            kind: OnceLock::new(),
        }
    }
}

#[pymethods]
impl PyTask {
    /// The scene: the original file's stem (`env0`) or the native file's `scene`.
    #[getter]
    fn scene(&self) -> &str {
        &self.task.meta.scene
    }

    #[getter]
    fn task_id(&self) -> i64 {
        self.task.meta.task_id
    }

    #[getter]
    fn name(&self) -> &str {
        &self.task.meta.name
    }

    #[getter]
    fn instruction(&self) -> &str {
        &self.task.meta.instruction
    }

    /// The ground truth's number of steps, when the file gives one.
    #[getter]
    fn gt(&self) -> Option<u32> {
        self.task.meta.gt_steps
    }

    /// `"mono"`, `"dual"` or `"trio"`: the fewest robot types that can reach the goal, by
    /// the optimal planner (searched once, on first use); None when it finds no plan.
    #[getter(r#type)]
    fn task_type(&self, py: Python<'_>) -> PyResult<Option<&'static str>> {
        if let Some(kind) = self.kind.get() {
            return Ok(*kind);
        }
        let task = Arc::clone(&self.task);
        let cancel = Arc::new(AtomicBool::new(false));
        let limits = Limits {
            cancel: Some(Arc::clone(&cancel)),
            ..Limits::default()
        };
        let kind = interruptible(
            py,
            move || cancel.store(true, Ordering::Relaxed),
            move || {
                check::plan(&task, &limits, check::PlanOptions::default())
                    .analysis
                    .task_type
                    .map(|k| k.name())
            },
        )?;
        Ok(*self.kind.get_or_init(|| kind))
    }

    /// Node ids of the robots, in graph order.
    #[getter]
    fn robots(&self) -> Vec<i64> {
        robot_ids(&self.task)
    }

    /// Robot node id -> `"quadrotor"`, `"robot dog"` or `"robot arm"`.
    #[getter]
    fn robot_types<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for r in &self.task.robots {
            dict.set_item(self.task.id(r.node).0, r.kind.class_name())?;
        }
        Ok(dict)
    }

    /// Robot node id -> the robot's name, e.g. `"robot_dog_13"`: its ROS 2 name
    /// (`coherent robots serve`) and its agent in `coherent.marl`.
    #[getter]
    fn robot_names<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (r, name) in self.task.robots.iter().zip(robot_names(&self.task)) {
            dict.set_item(self.task.id(r.node).0, name)?;
        }
        Ok(dict)
    }

    /// The most actions `robot` is ever offered at once in this task (each of its
    /// type's verbs once per node): the size of a fixed action space.
    fn most_actions(
        &self,
        py: Python<'_>,
        #[pyo3(from_py_with = robot_arg)] robot: RobotArg,
    ) -> PyCoherentResult<usize> {
        let id = node_id(py, &self.task, robot)?;
        let r = self.task.robot_by_id(id)?;
        Ok(most_actions(&self.task, r.kind))
    }

    /// The goal predicates, as `on_<apple>(3)_<table>(5)` / `inside_<a>(i)_<b>(j)`.
    #[getter]
    fn goal(&self) -> Vec<String> {
        self.task
            .goal
            .iter()
            .map(|p| self.task.predicate_label(p))
            .collect()
    }

    /// The task as a native task file (a JSON object).
    fn to_native<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &native::to_value(&self.task))
    }

    /// The native task file's text, as `coherent import` writes it with `indent`.
    #[pyo3(signature = (indent = false))]
    fn to_json(&self, indent: bool) -> String {
        let value = native::to_value(&self.task);
        if indent {
            serde_json::to_string_pretty(&value)
        } else {
            serde_json::to_string(&value)
        }
        .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }

    /// The task in the original format (one element of a scene file's list).
    fn to_original<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &original::to_value(&self.task))
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let meta = &self.task.meta;
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

pub(crate) fn robot_ids(task: &Task) -> Vec<i64> {
    task.robots.iter().map(|r| task.id(r.node).0).collect()
}

/// `seed` of `Env` and `Env.reset`, as `crate::args` reads `run`'s (which this module
/// cannot name: `args` names the methods, which name `Task`).
fn seed_arg(obj: &Bound<'_, PyAny>) -> PyResult<Option<u64>> {
    optional(obj, |o| unsigned(o, "seed"))
}

/// A robot argument: a node id, or the repr of an int beyond the 64 bits of node ids, which
/// is no robot either.
type RobotArg = Result<NodeId, String>;

fn robot_arg(obj: &Bound<'_, PyAny>) -> PyResult<RobotArg> {
    match obj.extract::<i64>() {
        Ok(id) => Ok(Ok(NodeId(id))),
        Err(e) if e.is_instance_of::<PyOverflowError>(obj.py()) => Ok(Err(short_repr(obj))),
        Err(e) => Err(e),
    }
}

/// A `TypeError` of argument `name` says which argument it is, as PyO3 says it for the
/// arguments it converts itself (`step`'s take one of two shapes, so it converts them by
/// hand); other errors pass as they are.
fn named<T>(py: Python<'_>, name: &str, converted: PyResult<T>) -> PyResult<T> {
    converted.map_err(|e| {
        if !e.is_instance_of::<PyTypeError>(py) {
            return e;
        }
        let named = PyTypeError::new_err(format!("argument '{name}': {}", e.value(py)));
        named.set_cause(py, Some(e));
        named
    })
}

/// The node id of a robot argument; an int too large for a node id is an
/// `UnknownRobotError` as any other id that is not a robot is (the others are left to
/// the environment, which names its robots).
fn node_id(py: Python<'_>, task: &Task, robot: RobotArg) -> PyResult<NodeId> {
    robot.map_err(|repr| {
        let robots: Vec<String> = task
            .robots
            .iter()
            .map(|r| format!("{} ({})", task.id(r.node), r.kind))
            .collect();
        core_err(
            py,
            TaskError::UnknownRobot(format!(
                "robot={repr}: no node id is that large; the robots of task {}/{} are {}",
                task.meta.scene,
                task.meta.task_id,
                robots.join(", ")
            )),
        )
    })
}

/// Puts `graph`'s `nodes` and `edges` (the original format's field names) into `dict`.
fn put_graph(dict: &Bound<'_, PyDict>, graph: &RawGraph) -> PyResult<()> {
    dict.set_item("nodes", to_py(dict.py(), &graph.nodes)?)?;
    dict.set_item("edges", to_py(dict.py(), &graph.edges)?)
}

/// A task's environment: robots observe and act, one action at a time or several robots
/// at once in a joint step, by the rules, and with `physics=True` also in Rapier; with
/// `robots="ros2"` robots behind ROS 2 action servers carry the actions out. The task's
/// events (or those of `events=`) happen as in an episode (docs/dynamic.md): each call
/// of `step` is one step, and the events due before the next are carried out after it.
#[pyclass(name = "Env", module = "coherent._coherent")]
pub(crate) struct PyEnv {
    env: Box<dyn Environment + Send + Sync>,
    /// The task with its events (those of `events=` in place of its own).
    task: Py<PyTask>,
    physics: bool,
    /// The namespace of the robots' actions over ROS 2; None when local.
    namespace: Option<String>,
    /// The events along the steps taken since the start, and the steps' count.
    events: Stepping,
}

#[pymethods]
impl PyEnv {
    #[new]
    #[pyo3(signature = (
        task, physics = false, *, robots = "local", namespace = None, robot_timeout = 10.0,
        server_wait = 10.0, events = None, seed = 0
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        task: Bound<'_, PyTask>,
        physics: bool,
        robots: &str,
        namespace: Option<&str>,
        robot_timeout: f64,
        server_wait: f64,
        events: Option<&Bound<'_, PyAny>>,
        #[pyo3(from_py_with = seed_arg)] seed: Option<u64>,
    ) -> PyCoherentResult<PyEnv> {
        let robots = robots_arg(py, robots, namespace, robot_timeout, server_wait)?;
        let source = events.map(events_source).transpose()?;
        let given = source.is_some();
        let (t, origin) = events::attach(Arc::clone(&task.get().task), source, "the task given")?;
        // No step budget here: an event past any the caller keeps never happens.
        events::check(&t, &origin, u32::MAX, physics, &robots)?;
        let namespace = match &robots {
            Robots::Ros2(options) => Some(options.namespace.clone()),
            Robots::Local => None,
        };
        let built = py.detach(|| environment(&t, physics, &robots, &Cancel::default()));
        let mut env = built?;
        let stepping = Stepping::start(&t, seed.unwrap_or(0), &mut *env)?;
        let task = if given {
            Py::new(py, PyTask::shared(t))?
        } else {
            task.unbind()
        };
        Ok(PyEnv {
            env,
            task,
            physics,
            namespace,
            events: stepping,
        })
    }

    /// Whether actions are also carried out in physics.
    #[getter]
    fn physics(&self) -> bool {
        self.physics
    }

    /// The namespace of the robots' ROS 2 actions; None when they act in this process.
    #[getter]
    fn namespace(&self) -> Option<String> {
        self.namespace.clone()
    }

    /// The task this environment runs.
    #[getter]
    fn task(&self, py: Python<'_>) -> Py<PyTask> {
        self.task.clone_ref(py)
    }

    /// Node ids of the robots in the team now: without those that went down or have
    /// not joined yet (docs/dynamic.md).
    #[getter]
    fn robots(&self) -> Vec<i64> {
        robot_ids(self.env.task())
    }

    /// What the team was told before the coming step, that it did not do: a sentence
    /// per event that happened then (empty when none did).
    #[getter]
    fn news(&self) -> Vec<String> {
        self.events.news().to_vec()
    }

    /// The steps taken since the start (or the last `reset`): calls of `step`.
    #[getter]
    fn steps(&self) -> u32 {
        self.events.steps()
    }

    /// The seed of a failing-actions event's draws.
    #[getter]
    fn seed(&self) -> u64 {
        self.events.seed()
    }

    /// The goal predicates now, as `Task.goal` writes them (an event may change them).
    #[getter]
    fn goal(&self) -> Vec<String> {
        let task = self.env.task();
        task.goal.iter().map(|p| task.predicate_label(p)).collect()
    }

    /// The instruction now (an event that changes the goal words it anew).
    #[getter]
    fn instruction(&self) -> String {
        self.env.task().meta.instruction.clone()
    }

    /// What `robot` sees: `{"room": id | None, "nodes": [...], "edges": [...]}`, nodes and
    /// edges with the original format's field names.
    fn observe<'py>(
        &self,
        py: Python<'py>,
        #[pyo3(from_py_with = robot_arg)] robot: RobotArg,
    ) -> PyCoherentResult<Bound<'py, PyDict>> {
        let robot = node_id(py, self.env.task(), robot)?;
        let obs = self.env.observe(robot)?;
        let task = self.env.task();
        let graph = task.raw_subgraph(self.env.state(), &obs.nodes, &obs.edges);
        let dict = PyDict::new(py);
        dict.set_item("room", obs.room.map(|r| task.id(r).0))?;
        put_graph(&dict, &graph)?;
        Ok(dict)
    }

    /// The action strings `robot` may use now.
    fn actions(
        &self,
        py: Python<'_>,
        #[pyo3(from_py_with = robot_arg)] robot: RobotArg,
    ) -> PyCoherentResult<Vec<String>> {
        let robot = node_id(py, self.env.task(), robot)?;
        Ok(self.env.actions(robot)?)
    }

    /// Why `robot` cannot do `action` now, by the rules, without doing it; None when it
    /// can. An unparsable action gets the parser's reason; a str that is not text (a lone
    /// surrogate) raises `ActionParseError`.
    fn why_not(
        &self,
        py: Python<'_>,
        #[pyo3(from_py_with = robot_arg)] robot: RobotArg,
        #[pyo3(from_py_with = action_text)] action: String,
    ) -> PyCoherentResult<Option<String>> {
        let task = self.env.task();
        let robot = node_id(py, task, robot)?;
        let r = task.robot_by_id(robot)?;
        Ok(feasibility::check(task, self.env.state(), r, &action)
            .err()
            .map(|why| why.message))
    }

    /// Tries `action` for `robot`: `(ok, reason, done)`. An infeasible or unparsable
    /// action is not an error: `ok` is False and `reason` says why. A str that is not text
    /// (a lone surrogate) cannot be tried and raises `ActionParseError`; a robot out of the
    /// team now (down, or not joined yet) raises `UnknownRobotError` and takes no step.
    /// An action that a failing-actions event draws to fail does not run: `ok` is False,
    /// `reason` says so. After the step, the events due before the next are carried out.
    ///
    /// `step(actions)` tries one joint step, several robots acting at once
    /// (docs/semantics.md, "Parallel steps"): `actions` is a dict `{robot: action}` or a
    /// list of `(robot, action)` pairs, at most one action a robot. It gives `(oks,
    /// reasons, done)`: a list each, one per pair in the order given. A step the rules
    /// refuse (an action not offered, two actions that interfere, a robot given two)
    /// carries out nothing, and each reason says what that means for its robot.
    #[pyo3(signature = (robot, action = None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        robot: &Bound<'py, PyAny>,
        action: Option<&Bound<'py, PyAny>>,
    ) -> PyCoherentResult<Bound<'py, PyTuple>> {
        let Some(action) = action else {
            return self.step_joint(py, robot);
        };
        let robot = node_id(py, self.env.task(), named(py, "robot", robot_arg(robot))?)?;
        let action = named(py, "action", action_text(action))?;
        // A robot out of the team is refused before the step is taken.
        self.env.task().robot_by_id(robot)?;
        let (executed, reason) = match self.events.fails(&*self.env, robot) {
            Some(why) => (false, Some(why)),
            None => {
                let outcome = if self.acts_elsewhere() {
                    let env = &mut self.env;
                    py.detach(|| env.step(robot, &action))
                } else {
                    self.env.step(robot, &action)
                }?;
                (outcome.executed(), outcome.infeasible.map(|i| i.message))
            }
        };
        let done = self.next_step()?;
        Ok((executed, reason, done).into_pyobject(py)?)
    }

    /// Whether each goal predicate holds now, in the order of `Env.goal` (`Task.goal`
    /// unless an event changed the goal).
    fn goal_holds(&self) -> Vec<bool> {
        let state = self.env.state();
        let goal = &self.env.task().goal;
        goal.iter().map(|p| predicate_holds(state, p)).collect()
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

    /// Back to the task's initial state, its events from the start again; `seed`, when
    /// given, seeds the failing actions' draws from now on.
    #[pyo3(signature = (seed = None))]
    fn reset(
        &mut self,
        #[pyo3(from_py_with = seed_arg)] seed: Option<u64>,
    ) -> PyCoherentResult<()> {
        self.env.reset();
        let task = Arc::clone(self.events.task());
        self.events = Stepping::start(&task, seed.unwrap_or(self.events.seed()), &mut *self.env)?;
        Ok(())
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let meta = &self.env.task().meta;
        let flag = |b: bool| if b { "True" } else { "False" };
        format!(
            "Env(scene={}, task_id={}, robots={:?}, physics={}, goal_satisfied={})",
            py_repr(py, &meta.scene),
            meta.task_id,
            self.robots(),
            flag(self.physics),
            flag(self.env.goal_satisfied())
        )
    }
}

impl PyEnv {
    /// Whether a step takes a while (physics, robots over ROS 2): then it runs without
    /// holding the GIL.
    fn acts_elsewhere(&self) -> bool {
        self.physics || self.namespace.is_some()
    }

    /// `step(actions)`: one joint step of `{robot: action}` or `[(robot, action), ...]`.
    fn step_joint<'py>(
        &mut self,
        py: Python<'py>,
        actions: &Bound<'py, PyAny>,
    ) -> PyCoherentResult<Bound<'py, PyTuple>> {
        let pairs: Vec<(Bound<'py, PyAny>, Bound<'py, PyAny>)> = match actions.cast::<PyDict>() {
            Ok(dict) => dict.iter().collect(),
            Err(_) => actions.extract().map_err(|_| {
                PyTypeError::new_err(format!(
                    "step(robot, action) tries one action, step(actions) a joint step: \
                     actions is a dict {{robot: action}} or a list of (robot, action) \
                     pairs, not {}",
                    short_repr(actions)
                ))
            })?,
        };
        let mut step = Vec::with_capacity(pairs.len());
        for (robot, action) in &pairs {
            let robot = node_id(py, self.env.task(), named(py, "actions", robot_arg(robot))?)?;
            step.push((robot, named(py, "actions", action_text(action))?));
        }
        // A robot out of the team is refused before the step is taken.
        for (robot, _) in &step {
            self.env.task().robot_by_id(*robot)?;
        }
        // The actions a failing-actions event makes fail do not run; the others' step
        // runs without them (an empty step still runs: the rules take it as it is).
        let failed: Vec<Option<String>> = step
            .iter()
            .map(|(robot, _)| self.events.fails(&*self.env, *robot))
            .collect();
        let acting: Vec<(NodeId, &str)> = step
            .iter()
            .zip(&failed)
            .filter(|(_, f)| f.is_none())
            .map(|((r, a), _)| (*r, a.as_str()))
            .collect();
        let outcome = if !acting.is_empty() || step.is_empty() {
            Some(if self.acts_elsewhere() {
                let env = &mut self.env;
                py.detach(|| env.step_joint(&acting))
            } else {
                self.env.step_joint(&acting)
            }?)
        } else {
            None
        };
        let mut parts = outcome.into_iter().flat_map(|o| o.parts);
        let mut oks = Vec::with_capacity(step.len());
        let mut reasons = Vec::with_capacity(step.len());
        for why in failed {
            let (ok, reason) = match why {
                Some(why) => (false, Some(why)),
                None => match parts.next() {
                    Some(p) => (p.executed(), p.infeasible.map(|i| i.message)),
                    None => (false, None),
                },
            };
            oks.push(ok);
            reasons.push(reason);
        }
        let done = self.next_step()?;
        Ok((oks, reasons, done).into_pyobject(py)?)
    }

    /// After a step: the events due before the next one, carried out. Whether the goal
    /// holds then.
    fn next_step(&mut self) -> PyCoherentResult<bool> {
        self.events.taken(&mut *self.env)?;
        Ok(self.env.goal_satisfied())
    }
}

/// The robots of `robots=` (`"local"` or `"ros2"`), with `namespace`, `robot_timeout`
/// and `server_wait` for robots over ROS 2: `Env`'s, `run`'s and `bench`'s arguments.
pub(crate) fn robots_arg(
    py: Python<'_>,
    robots: &str,
    namespace: Option<&str>,
    robot_timeout: f64,
    server_wait: f64,
) -> PyCoherentResult<Robots> {
    match (robots, namespace) {
        ("local", None) => Ok(Robots::Local),
        ("local", Some(_)) => Err(errors::invalid(py, "a namespace is for robots=\"ros2\"").into()),
        ("ros2", ns) => Ok(Robots::ros2(
            ns.unwrap_or(DEFAULT_NAMESPACE),
            robot_timeout,
            server_wait,
        )?),
        (other, _) => {
            let why = format!("robots={other:?}: \"local\" or \"ros2\"");
            Err(errors::invalid(py, why).into())
        }
    }
}
