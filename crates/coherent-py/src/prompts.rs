//! The `prompts=` and `prices=` keyword arguments of `run`, `replay` and `run_bench`:
//! the prompt set and the price table, read by the session layer
//! (`coherent::session::prompts`) as `--prompts` and `--prices` are.

use std::ffi::CString;
use std::path::PathBuf;

use coherent::session::prompts;
use coherent_agents::{PriceTable, Prompts};
use pyo3::exceptions::{PyTypeError, PyUserWarning};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::convert::{json_at, path, text};
use crate::errors;

/// Whether `obj` names a file: a str or an `os.PathLike`.
fn is_path(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    Ok(obj.is_instance_of::<PyString>() || obj.hasattr("__fspath__")?)
}

/// `prompts=`: None (the built-in templates), a folder of template files, or a dict of
/// `{file name: text}`; each replaces the built-in template of that name. A template
/// with an unknown placeholder raises `PromptError` before anything runs.
pub(crate) fn prompt_set(spec: Option<&Bound<'_, PyAny>>) -> PyResult<Prompts> {
    let Some(spec) = spec else {
        return Ok(Prompts::builtin());
    };
    let py = spec.py();
    let (set, origin) = if let Ok(d) = spec.cast::<PyDict>() {
        let files = d
            .iter()
            .map(|(k, v)| {
                let name = text(&k, "prompts")?.to_owned();
                Ok((
                    name.clone(),
                    text(&v, &format!("prompts[{name:?}]"))?.to_owned(),
                ))
            })
            .collect::<PyResult<Vec<_>>>()?;
        let origin = PathBuf::from("prompts");
        (Prompts::from_texts(&origin, files), origin)
    } else if is_path(spec)? {
        let dir = path(spec, "prompts")?;
        (prompts::prompt_set(Some(&dir)), dir)
    } else {
        return Err(PyTypeError::new_err(
            "prompts: expected a folder of template files or a dict of {file name: text}",
        ));
    };
    let set = set.map_err(|e| errors::prompt(py, &e))?;
    for warning in prompts::blank_warnings(&origin, &set) {
        PyErr::warn(
            py,
            &py.get_type::<PyUserWarning>(),
            &CString::new(warning)?,
            1,
        )?;
    }
    Ok(set)
}

/// `prices=`: None (the built-in table), a price file (JSON, or TOML for a `.toml`
/// file), or a dict of `{model: {"input": .., "cached_input": .., "output": ..}}` in USD
/// per million tokens; added to the built-in table.
pub(crate) fn price_table(spec: Option<&Bound<'_, PyAny>>) -> PyResult<PriceTable> {
    let Some(spec) = spec else {
        return Ok(PriceTable::builtin());
    };
    let py = spec.py();
    if spec.is_instance_of::<PyDict>() {
        let text = json_at(spec, "prices")?.to_string();
        let table = PriceTable::parse_json(&text, "prices").map_err(|e| errors::coherent(py, e))?;
        return Ok(PriceTable::builtin().overridden_by(table));
    }
    if !is_path(spec)? {
        return Err(PyTypeError::new_err(
            "prices: expected a price file (JSON or TOML) or a dict by model",
        ));
    }
    let file = path(spec, "prices")?;
    prompts::price_table(Some(&file)).map_err(|e| errors::coherent(py, e))
}
