//! Python bindings of `coherent`: the `coherent._coherent` extension module.
//!
//! Thin on purpose: these files convert types and errors and release the GIL around
//! long work; behaviour lives in the session layer (`coherent::session`), which the
//! `coherent` command uses too. They name nothing below the session: the types they
//! need of the crates under it are the session's re-exports
//! (`coherent::session::engine`). `cli_main` starts that very command for the console
//! script.

mod args;
mod bench;
mod convert;
mod distributed;
mod errors;
mod generate;
mod llm;
mod method;
mod pddl;
mod prompts;
mod run;
mod scene;
mod stepper;
mod task;
mod training;
mod view;

use std::ffi::OsString;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use coherent::session::engine::{
    Budget, Builtin, Execution, External, Limits, Mention, Subset, load_tasks as read_all,
    parse_action as parse,
};
use coherent::session::{Error, check, tasks};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use convert::{interruptible, json_to_py};
use errors::{PyCoherentResult, core_err};
use method::Methods;
use task::PyTask;

// ---------------------------------------------------------------------------------------
// Functions

/// Every task at `path`: an original env file, a native task file, or a folder of them.
#[pyfunction]
fn load_tasks(
    py: Python<'_>,
    #[pyo3(from_py_with = args::path)] path: PathBuf,
) -> PyCoherentResult<Vec<PyTask>> {
    let tasks = py.detach(|| read_all(&path))?;
    Ok(tasks.into_iter().map(PyTask::new).collect())
}

/// Every well-formed task at `path`, and a `TaskFormatError` for each malformed one, so
/// that one bad task does not hide the others (as `coherent validate` reports them).
/// A path that cannot be read, or a file that is not JSON, still raises.
#[pyfunction]
fn read_tasks(
    py: Python<'_>,
    #[pyo3(from_py_with = args::path)] path: PathBuf,
) -> PyCoherentResult<(Vec<PyTask>, Vec<Py<PyAny>>)> {
    let results = py.detach(|| tasks::read_tasks(&path))?;
    let mut tasks = Vec::new();
    let mut errors = Vec::new();
    for r in results {
        match r {
            Ok(t) => tasks.push(PyTask::new(t)),
            Err(e) => errors.push(core_err(py, e).into_value(py).into_any()),
        }
    }
    Ok((tasks, errors))
}

/// The project's own benchmark, compiled in: every task, or with `subset="40"` its
/// 40-task subset (per scene 2 mono, 3 dual, 3 trio).
#[pyfunction]
#[pyo3(signature = (subset = None))]
fn benchmark_tasks(
    py: Python<'_>,
    #[pyo3(from_py_with = args::subset)] subset: Option<&str>,
) -> PyCoherentResult<Vec<PyTask>> {
    let subset = match subset {
        None => Subset::All,
        Some("40") => Subset::named("native40").expect("a subset name"),
        Some(other) => {
            return Err(errors::choice(py, "subset", other, "expected None or \"40\"").into());
        }
    };
    let tasks = py.detach(|| tasks::benchmark(&subset))?;
    Ok(tasks.into_iter().map(PyTask::shared).collect())
}

/// Plans `task` optimally: one line of `coherent plan --json`, as a dict; with
/// `parallel`, of `coherent plan --parallel --json` (the fewest joint steps too); with
/// `physics`, of `--physics` (the plans carried out in Rapier, the makespan plan too
/// with `parallel`).
///
/// The default `max_states` is `Limits::DEFAULT_MAX_STATES` (Python shows it as `...` in
/// the signature; the module has it as `DEFAULT_MAX_STATES`).
#[pyfunction]
#[pyo3(signature = (task, max_states = Limits::DEFAULT_MAX_STATES, parallel = false, physics = false))]
fn plan<'py>(
    py: Python<'py>,
    task: &Bound<'py, PyTask>,
    #[pyo3(from_py_with = args::max_states)] max_states: usize,
    parallel: bool,
    physics: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let task = Arc::clone(&task.get().task);
    let cancel = Arc::new(AtomicBool::new(false));
    let limits = Limits {
        cancel: Some(Arc::clone(&cancel)),
        ..Limits::max_states(max_states)
    };
    let stop = Arc::clone(&cancel);
    let json = interruptible(
        py,
        move || stop.store(true, Ordering::Relaxed),
        move || {
            let options = check::PlanOptions { physics, parallel };
            check::plan(&task, &limits, options).to_json(&task)
        },
    )?;
    json_to_py(py, &json)
}

/// The step budget of an episode of `task` in `execution`, as every episode gets it
/// (`coherent run`, `coherent.run`, the Gymnasium and PettingZoo environments):
/// `max_steps` when given, else 2 x GT, else 2 x the optimum the planner finds; in joint
/// steps 2 x the makespan.
#[pyfunction]
#[pyo3(signature = (task, execution = Execution::Sequential, max_steps = None, max_states = Limits::DEFAULT_MAX_STATES))]
fn budget(
    py: Python<'_>,
    task: &Bound<'_, PyTask>,
    #[pyo3(from_py_with = args::execution)] execution: Execution,
    #[pyo3(from_py_with = args::max_steps)] max_steps: Option<u32>,
    #[pyo3(from_py_with = args::max_states)] max_states: usize,
) -> PyResult<u32> {
    let task = Arc::clone(&task.get().task);
    let cancel = Arc::new(AtomicBool::new(false));
    let limits = Limits {
        cancel: Some(Arc::clone(&cancel)),
        ..Limits::max_states(max_states)
    };
    let stop = Arc::clone(&cancel);
    let budget = interruptible(
        py,
        move || stop.store(true, Ordering::Relaxed),
        move || Budget::searched(&task, execution, max_steps, &limits),
    )?;
    let budget = budget.map_err(|e| errors::session_err(py, Error::from(e)))?;
    Ok(budget.steps())
}

/// Problems of `task` (empty when it is clean), as `coherent validate` lists them: the
/// rules' findings and the geometry's.
#[pyfunction(name = "validate")]
#[pyo3(signature = (task, max_states = Limits::DEFAULT_MAX_STATES))]
fn validate_task(
    py: Python<'_>,
    task: &Bound<'_, PyTask>,
    #[pyo3(from_py_with = args::max_states)] max_states: usize,
) -> PyResult<Vec<String>> {
    let task = Arc::clone(&task.get().task);
    let cancel = Arc::new(AtomicBool::new(false));
    let limits = Limits {
        cancel: Some(Arc::clone(&cancel)),
        ..Limits::max_states(max_states)
    };
    let stop = Arc::clone(&cancel);
    interruptible(
        py,
        move || stop.store(true, Ordering::Relaxed),
        move || check::findings(&task, &limits),
    )
}

/// Parses an action string: `{"verb", "object": {"name", "id"}, "target": ... | None}`.
#[pyfunction]
fn parse_action<'py>(
    py: Python<'py>,
    #[pyo3(from_py_with = convert::action_text)] text: String,
) -> PyCoherentResult<Bound<'py, PyDict>> {
    let parsed = parse(&text)?;
    let mention = |m: &Mention| -> PyResult<Bound<'py, PyDict>> {
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
/// exit status. `--method` and `--methods` take methods written in Python here, as
/// `MODULE:CLASS` (a module or a `.py` file).
#[pyfunction]
fn cli_main(
    py: Python<'_>,
    #[pyo3(from_py_with = args::argv)] argv: Vec<OsString>,
) -> PyResult<u8> {
    let methods = Mutex::new(Methods::new(py, None)?);
    let load = |spec: &str| -> Result<External, Error> {
        Python::attach(|py| -> PyResult<External> {
            let found = method::helpers(py)?.call_method1("load", (spec,))?;
            let mut methods = methods.lock().unwrap_or_else(PoisonError::into_inner);
            Ok(methods.add(&found, &[])?)
        })
        // The other way round: the command line's error, naming the spec it was given.
        .map_err(|e| Error::Invalid(format!("{spec}: {e}")))
    };
    let code = py.detach(|| {
        let code = coherent::cli::run_with(argv, Some(&load));
        // Python may exit right after; lines already end in newlines, this is for the rest.
        let _ = std::io::stdout().flush();
        code
    });
    methods
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .close(py)?;
    Ok(code)
}

#[pymodule]
fn _coherent(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("METHODS", Builtin::ALL.map(Builtin::name).to_vec())?;
    m.add("DEFAULT_MAX_STATES", Limits::DEFAULT_MAX_STATES)?;
    // Robots over ROS 2 start their link process as this Python with the console script's
    // module, which runs the same command line as the binary; this process's executable
    // is Python, not `coherent`.
    let python: Option<PathBuf> = py.import("sys")?.getattr("executable")?.extract()?;
    if let Some(python) = python.filter(|p| !p.as_os_str().is_empty()) {
        let args = ["-m", "coherent._cli"].map(OsString::from).to_vec();
        coherent::session::robots::start_links_with(python, args);
    }
    let exc = errors::exceptions(py)?;
    m.add("CoherentError", exc.base.clone_ref(py))?;
    m.add("ArgumentError", exc.argument.clone_ref(py))?;
    m.add("TaskFormatError", exc.task_format.clone_ref(py))?;
    m.add("UnknownRobotError", exc.unknown_robot.clone_ref(py))?;
    m.add("ActionParseError", exc.action_parse.clone_ref(py))?;
    m.add("PhysicsError", exc.physics.clone_ref(py))?;
    m.add("BackendError", exc.backend.clone_ref(py))?;
    m.add("ReplayMismatchError", exc.replay_mismatch.clone_ref(py))?;
    m.add("PromptError", exc.prompt.clone_ref(py))?;
    m.add("MethodError", exc.method.clone_ref(py))?;
    m.add("RobotError", exc.robot.clone_ref(py))?;
    m.add("DataFileError", exc.data_file.clone_ref(py))?;
    m.add_class::<PyTask>()?;
    m.add_class::<task::PyEnv>()?;
    m.add_class::<llm::PyLlm>()?;
    m.add_class::<llm::PyReply>()?;
    m.add_class::<method::PyView>()?;
    m.add_class::<method::PyDecision>()?;
    m.add_class::<run::PyEpisode>()?;
    m.add_class::<distributed::PyLedger>()?;
    m.add_class::<distributed::PyWorker>()?;
    m.add_function(wrap_pyfunction!(load_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(read_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(benchmark_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(plan, m)?)?;
    m.add_function(wrap_pyfunction!(generate::generate, m)?)?;
    m.add_function(wrap_pyfunction!(training::export_sft, m)?)?;
    m.add_function(wrap_pyfunction!(pddl::pddl_texts, m)?)?;
    m.add_function(wrap_pyfunction!(pddl::check_pddl_plan, m)?)?;
    m.add_function(wrap_pyfunction!(budget, m)?)?;
    m.add_function(wrap_pyfunction!(validate_task, m)?)?;
    m.add_function(wrap_pyfunction!(parse_action, m)?)?;
    m.add_function(wrap_pyfunction!(cli_main, m)?)?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add_function(wrap_pyfunction!(run::replay, m)?)?;
    m.add_function(wrap_pyfunction!(run::load_episode, m)?)?;
    m.add_function(wrap_pyfunction!(bench::select, m)?)?;
    m.add_function(wrap_pyfunction!(bench::run_bench, m)?)?;
    m.add_function(wrap_pyfunction!(bench::read_results, m)?)?;
    m.add_function(wrap_pyfunction!(bench::report_tables, m)?)?;
    m.add_function(wrap_pyfunction!(bench::report_text, m)?)?;
    m.add_function(wrap_pyfunction!(bench::price_lines, m)?)?;
    m.add_function(wrap_pyfunction!(scene::scene_layout, m)?)?;
    m.add_function(wrap_pyfunction!(scene::robot_paths, m)?)?;
    m.add_function(wrap_pyfunction!(scene::render_svg, m)?)?;
    m.add_function(wrap_pyfunction!(view::view_page, m)?)?;
    m.add_function(wrap_pyfunction!(view::results_page, m)?)?;
    m.add_function(wrap_pyfunction!(view::framed_page, m)?)?;
    Ok(())
}
