//! The `prompts=` and `prices=` keyword arguments of `run`, `replay` and `run_bench`:
//! the prompt set and the price table, read by the session layer
//! (`coherent::session::prompts`) as `--prompts` and `--prices` are.

use std::path::{Path, PathBuf};

use coherent::session::prompts;
use coherent_agents::{PriceTable, Prompts};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::py_to_json;
use crate::errors;

/// `prompts=`: None (the built-in templates), a folder of template files, or a dict of
/// `{file name: text}`; each replaces the built-in template of that name. A template
/// with an unknown placeholder raises `PromptError` before anything runs.
pub(crate) fn prompt_set(spec: Option<&Bound<'_, PyAny>>) -> PyResult<Prompts> {
    let Some(spec) = spec else {
        return Ok(Prompts::builtin());
    };
    let py = spec.py();
    let set = if let Ok(d) = spec.cast::<PyDict>() {
        let files = d
            .iter()
            .map(|(k, v)| Ok((k.extract::<String>()?, v.extract::<String>()?)))
            .collect::<PyResult<Vec<_>>>()
            .map_err(|_| PyTypeError::new_err("prompts: a dict of {file name: text}, both str"))?;
        Prompts::from_texts(Path::new("prompts"), files)
    } else if let Ok(dir) = spec.extract::<PathBuf>() {
        prompts::prompt_set(Some(&dir))
    } else {
        return Err(PyTypeError::new_err(
            "prompts: expected a folder of template files or a dict of {file name: text}",
        ));
    };
    set.map_err(|e| errors::prompt(py, &e))
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
        let text = py_to_json(spec)?.to_string();
        let table = PriceTable::parse_json(&text, "prices").map_err(|e| errors::coherent(py, e))?;
        return Ok(PriceTable::builtin().overridden_by(table));
    }
    let file = spec.extract::<PathBuf>().map_err(|_| {
        PyTypeError::new_err("prices: expected a price file (JSON or TOML) or a dict by model")
    })?;
    prompts::price_table(Some(&file)).map_err(|e| errors::coherent(py, e))
}
