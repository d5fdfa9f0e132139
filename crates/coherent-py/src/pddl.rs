//! `coherent.pddl()` and `coherent.check_pddl_plan()`: a task in PDDL, and a PDDL plan
//! played through the rules (docs/pddl.md).

use coherent::session::pddl;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::core_err;
use crate::task::PyTask;

/// The task in PDDL: `(domain, problem)`, its rule set's domain and its problem. A task
/// the domain cannot express raises `TaskFormatError` with the reason.
#[pyfunction(name = "pddl")]
pub(crate) fn pddl_texts(py: Python<'_>, task: &Bound<'_, PyTask>) -> PyResult<(String, String)> {
    let p = pddl::export(&task.get().task).map_err(|e| core_err(py, e))?;
    Ok((p.domain, p.problem))
}

/// Plays the PDDL plan `text` (one `(action args...)` a line) through the rules of
/// `task`: `valid`, `length`, `goal_reached`, `failure` (`(line, reason)` or None) and
/// `actions` (the rules' actions, `<robot id> [verb] ...`, up to the first that failed).
#[pyfunction]
pub(crate) fn check_pddl_plan<'py>(
    py: Python<'py>,
    task: &Bound<'py, PyTask>,
    text: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let check = pddl::check_plan(&task.get().task, text);
    let d = PyDict::new(py);
    d.set_item("valid", check.valid())?;
    d.set_item("length", check.length)?;
    d.set_item("goal_reached", check.goal_reached)?;
    d.set_item("failure", check.failure.clone())?;
    d.set_item("actions", check.actions.clone())?;
    Ok(d)
}
