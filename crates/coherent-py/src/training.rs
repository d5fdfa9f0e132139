//! `coherent.training.dataset()`: the training data of `coherent export sft`
//! (docs/training.md), written to a folder by the same code, its counts handed back.

use coherent::session::engine::{Builtin, Cancel, ErrorRates};
use coherent::session::training::{SftRequest, export};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::args;
use crate::convert::{interruptible, text};
use crate::errors::{self, PyCoherentResult};
use crate::prompts::prompt_source;

/// Writes the data into `out` and returns its counts: `examples` and `by_role` (dicts),
/// `tasks`, `left_out_eval`, `malformed` (the reasons), `no_answer`, `duplicates`,
/// `conflicts`, `unreadable` and `files`. The Python wrapper (`coherent.training`) adds
/// token counts.
#[pyfunction]
#[pyo3(signature = (
    files, method, out, *, execution = None, roles = None, sim_errors = "all=0.1",
    seeds = 2, history = None, prompts = None, split = (0.8, 0.1, 0.1),
    include_eval = false, max_states = None, command = "",
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn export_sft<'py>(
    py: Python<'py>,
    files: Vec<Bound<'py, PyAny>>,
    method: &Bound<'py, PyAny>,
    out: &Bound<'py, PyAny>,
    execution: Option<&Bound<'py, PyAny>>,
    roles: Option<Vec<String>>,
    sim_errors: &str,
    seeds: u64,
    history: Option<usize>,
    prompts: Option<&Bound<'py, PyAny>>,
    split: (f64, f64, f64),
    include_eval: bool,
    max_states: Option<usize>,
    command: &str,
) -> PyCoherentResult<Bound<'py, PyDict>> {
    let name = text(method, "method")?;
    let builtin = Builtin::from_name(name)
        .ok_or_else(|| errors::argument("method", method, "not a built-in method"))?;
    let files = files
        .iter()
        .enumerate()
        .map(|(i, f)| crate::convert::path(f, &format!("files[{i}]")))
        .collect::<PyResult<Vec<_>>>()?;
    let mut req = SftRequest::new(files, builtin, args::out(out)?);
    if let Some(e) = execution {
        req.executions = args::executions(e)?;
    }
    req.roles = roles.unwrap_or_default();
    req.errors = ErrorRates::parse(sim_errors).map_err(|e| {
        errors::argument("sim_errors", &PyString::new(py, sim_errors).into_any(), e)
    })?;
    req.seeds = seeds;
    if let Some(h) = history {
        req.history = h;
    }
    req.prompts = prompt_source(prompts)?;
    let shares = [split.0, split.1, split.2];
    if shares.iter().any(|s| !s.is_finite() || *s < 0.0) || shares.iter().sum::<f64>() <= 0.0 {
        return Err(errors::invalid(
            py,
            format!("split={split:?}: three shares, none negative, not all zero"),
        )
        .into());
    }
    req.split = shares;
    req.include_eval = include_eval;
    if let Some(n) = max_states {
        req.max_states = n;
    }
    req.command = command.to_owned();
    let cancel = Cancel::default();
    let stop = cancel.clone();
    let written = interruptible(
        py,
        move || stop.cancel(),
        move || export(&req, &cancel, &mut |_, _, _| {}),
    )??;
    let d = PyDict::new(py);
    let examples = PyDict::new(py);
    for (split, n) in &written.examples {
        examples.set_item(split.name(), n)?;
    }
    d.set_item("examples", examples)?;
    d.set_item("by_role", written.by_role.clone())?;
    d.set_item("tasks", written.tasks)?;
    d.set_item("left_out_eval", written.left_out_eval)?;
    d.set_item("malformed", written.malformed.clone())?;
    d.set_item("no_answer", written.no_answer)?;
    d.set_item("duplicates", written.duplicates)?;
    d.set_item("conflicts", written.conflicts)?;
    d.set_item("unreadable", written.unreadable)?;
    let paths: Vec<String> = written
        .files
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    d.set_item("files", paths)?;
    Ok(d)
}
