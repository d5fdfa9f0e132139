//! `coherent.generate()`: a generated task set (docs/generate.md), the same tasks as
//! `coherent generate` makes with the same knobs, handed back with their manifest lines
//! and written to a folder when `out` is given.

use std::path::PathBuf;

use coherent::session::engine::Cancel;
use coherent::session::generate::{Kept, Knobs};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyInt, PyList, PyString, PyTuple};

use crate::convert::{Unsigned, expected, finite, interruptible, json_to_py, text, unsigned};
use crate::errors::PyCoherentResult;
use crate::task::PyTask;

/// The set: a list of `(task, manifest)`, `manifest` the task's line of
/// `manifest.jsonl` as a dict. Spans are an int or a str (`3`, `"2-6"`), `team` a str
/// (`"quadrotor=2,legged=0-3"`) or a dict of counts or spans by kind, `type` a str or a
/// list of type names, `split` a str or three shares. A knob out of range, or a request
/// the draws cannot meet, raises `ArgumentError` naming the knob.
#[pyfunction]
#[pyo3(signature = (
    tasks = None, *, seed = None, scenes = None, rooms = None, upstairs = None, closed = None,
    team = None, robots = None, predicates = None, r#type = None, needed = None, steps = None,
    ratio = None, proven = false, physics = false, max_states = None, max_memory = None,
    max_draws = None, split = None, jobs = None, out = None,
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn generate<'py>(
    py: Python<'py>,
    tasks: Option<&Bound<'py, PyAny>>,
    seed: Option<&Bound<'py, PyAny>>,
    scenes: Option<&Bound<'py, PyAny>>,
    rooms: Option<&Bound<'py, PyAny>>,
    upstairs: Option<&Bound<'py, PyAny>>,
    closed: Option<&Bound<'py, PyAny>>,
    team: Option<&Bound<'py, PyAny>>,
    robots: Option<&Bound<'py, PyAny>>,
    predicates: Option<&Bound<'py, PyAny>>,
    r#type: Option<&Bound<'py, PyAny>>,
    needed: Option<&Bound<'py, PyAny>>,
    steps: Option<&Bound<'py, PyAny>>,
    ratio: Option<&Bound<'py, PyAny>>,
    proven: bool,
    physics: bool,
    max_states: Option<&Bound<'py, PyAny>>,
    max_memory: Option<&Bound<'py, PyAny>>,
    max_draws: Option<&Bound<'py, PyAny>>,
    split: Option<&Bound<'py, PyAny>>,
    jobs: Option<&Bound<'py, PyAny>>,
    out: Option<&Bound<'py, PyAny>>,
) -> PyCoherentResult<Bound<'py, PyList>> {
    let mut knobs = Knobs::default();
    if let Some(n) = size(tasks, "tasks")? {
        knobs.tasks = n;
    }
    if let Some(n) = given(seed).map(|o| whole::<u64>(o, "seed")).transpose()? {
        knobs.seed = n;
    }
    knobs.scenes = size(scenes, "scenes")?;
    if let Some(r) = given(rooms) {
        knobs.rooms = span(r, "rooms")?;
    }
    if let Some(p) = given(upstairs) {
        knobs.upstairs = finite(p, "upstairs")?;
    }
    if let Some(p) = given(closed) {
        knobs.closed = finite(p, "closed")?;
    }
    knobs.team = given(team).map(team_text).transpose()?;
    knobs.robots = given(robots).map(|r| span(r, "robots")).transpose()?;
    if let Some(p) = given(predicates) {
        knobs.predicates = span(p, "predicates")?;
    }
    knobs.types = given(r#type).map(|t| listed(t, "type")).transpose()?;
    knobs.needed = given(needed).map(|n| span(n, "needed")).transpose()?;
    knobs.steps = given(steps).map(|s| span(s, "steps")).transpose()?;
    knobs.ratio = given(ratio)
        .map(|r| text_or_number(r, "ratio"))
        .transpose()?;
    knobs.proven = proven;
    knobs.physics = physics;
    if let Some(n) = size(max_states, "max_states")? {
        knobs.max_states = n;
    }
    if let Some(n) = size(max_memory, "max_memory")? {
        knobs.max_memory = n;
    }
    knobs.max_draws = size(max_draws, "max_draws")?;
    if let Some(s) = given(split) {
        knobs.split = listed(s, "split")?;
    }
    knobs.jobs = size(jobs, "jobs")?;
    let out: Option<PathBuf> = given(out).map(crate::args::out).transpose()?;

    let request = knobs.request(out)?;
    let cancel = Cancel::default();
    let stop = cancel.clone();
    let (kept, made) = interruptible(
        py,
        move || stop.cancel(),
        move || {
            let mut kept: Vec<Kept> = Vec::new();
            let made = request.run(&cancel, &mut |k| kept.push(k), &mut |_| {});
            (kept, made)
        },
    )?;
    // An interrupt raised `KeyboardInterrupt` above, the folder holding the tasks
    // written until then, whole, with their manifest and datasheet.
    made?;
    let pairs = kept
        .into_iter()
        .map(|k| {
            let task = Bound::new(py, PyTask::new(k.task))?;
            let manifest = json_to_py(py, &k.manifest)?;
            PyTuple::new(py, [task.into_any(), manifest])
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok(PyList::new(py, pairs)?)
}

/// A knob given: not left out, not None.
fn given<'a, 'py>(obj: Option<&'a Bound<'py, PyAny>>) -> Option<&'a Bound<'py, PyAny>> {
    obj.filter(|o| !o.is_none())
}

/// A count knob, when given.
fn size(obj: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<Option<usize>> {
    given(obj).map(|o| whole(o, name)).transpose()
}

/// A count knob: an int (not a bool), 0 or more.
fn whole<T: Unsigned>(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<T> {
    if obj.is_instance_of::<PyBool>() || !obj.is_instance_of::<PyInt>() {
        return Err(expected(obj, name, "an int"));
    }
    unsigned(obj, name)
}

/// A knob given as a str: its text, as the command line would take it.
fn as_typed(obj: &Bound<'_, PyAny>, name: &str) -> Option<PyResult<String>> {
    obj.is_instance_of::<PyString>()
        .then(|| text(obj, name).map(str::to_owned))
}

/// A span knob: an int (`3`) or a str (`"2-6"`).
fn span(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<String> {
    if let Some(typed) = as_typed(obj, name) {
        return typed;
    }
    if obj.is_instance_of::<PyBool>() || !obj.is_instance_of::<PyInt>() {
        return Err(expected(obj, name, "an int or a str"));
    }
    unsigned::<u64>(obj, name).map(|n| n.to_string())
}

/// `ratio`, and an item of `type` or `split`: a str or a finite number (`1.5`).
fn text_or_number(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<String> {
    as_typed(obj, name).unwrap_or_else(|| finite(obj, name).map(|x| x.to_string()))
}

/// `type` or `split`: a str, or a list or tuple of names (`["mono", "trio"]`) or of
/// shares (`[0.8, 0.1, 0.1]`), joined by commas.
fn listed(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<String> {
    if let Some(typed) = as_typed(obj, name) {
        return typed;
    }
    if !(obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>()) {
        return Err(expected(obj, name, "a str, a list or a tuple"));
    }
    obj.try_iter()?
        .map(|item| text_or_number(&item?, name))
        .collect::<PyResult<Vec<_>>>()
        .map(|parts| parts.join(","))
}

/// `team`: a str (`"quadrotor=2,legged=0-3"`) or a dict of counts or spans by kind.
fn team_text(obj: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Some(typed) = as_typed(obj, "team") {
        return typed;
    }
    let Ok(dict) = obj.cast::<PyDict>() else {
        return Err(expected(obj, "team", "a str or a dict"));
    };
    dict.iter()
        .map(|(kind, n)| Ok(format!("{}={}", text(&kind, "team")?, span(&n, "team")?)))
        .collect::<PyResult<Vec<_>>>()
        .map(|parts| parts.join(","))
}
