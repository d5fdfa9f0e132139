//! The `prompts=` and `prices=` keyword arguments of `run`, `replay` and `run_bench`,
//! as the session's sources of a prompt set and a price table
//! (`coherent::session::prompts`), read by the session as `--prompts` and `--prices`
//! are.

use coherent::session::prompts::{PriceSource, PromptSource};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::convert::{json_at, path, text};

/// Whether `obj` names a file: a str or an `os.PathLike`.
fn is_path(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    Ok(obj.is_instance_of::<PyString>() || obj.hasattr("__fspath__")?)
}

/// `prompts=`: None (the built-in templates), `"paper-layout"` (the built-in templates in
/// the paper's layout), a folder of template files, or a dict of `{file name: text}`;
/// each file replaces the built-in template of that name (a template
/// with an unknown placeholder raises `PromptError` when the session reads the set,
/// before anything runs).
pub(crate) fn prompt_source(spec: Option<&Bound<'_, PyAny>>) -> PyResult<PromptSource> {
    let Some(spec) = spec else {
        return Ok(PromptSource::Builtin);
    };
    if let Ok(d) = spec.cast::<PyDict>() {
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
        Ok(PromptSource::Texts(files))
    } else if is_path(spec)? {
        Ok(PromptSource::from_arg(&path(spec, "prompts")?))
    } else {
        Err(PyTypeError::new_err(
            "prompts: expected a folder of template files or a dict of {file name: text}",
        ))
    }
}

/// `prices=`: None (the built-in table), a price file (JSON, or TOML for a `.toml`
/// file), or a dict of `{model: {"input": .., "cached_input": .., "output": ..}}` in USD
/// per million tokens; added to the built-in table.
pub(crate) fn price_source(spec: Option<&Bound<'_, PyAny>>) -> PyResult<PriceSource> {
    let Some(spec) = spec else {
        return Ok(PriceSource::Builtin);
    };
    if spec.is_instance_of::<PyDict>() {
        return Ok(PriceSource::Json(json_at(spec, "prices")?.to_string()));
    }
    if !is_path(spec)? {
        return Err(PyTypeError::new_err(
            "prices: expected a price file (JSON or TOML) or a dict by model",
        ));
    }
    Ok(PriceSource::File(path(spec, "prices")?))
}
