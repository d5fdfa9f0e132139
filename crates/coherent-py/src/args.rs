//! The arguments of the module's functions that Rust cannot take as Python gives them,
//! for PyO3's `from_py_with`: one function per argument name, since PyO3 passes none,
//! each naming its argument in its errors. A value of the wrong type stays a
//! `TypeError`; a value of the right type that cannot be used is an `ArgumentError`:
//! a path or a str with a lone surrogate, an int out of range, a float that is not
//! finite. Choices among names (`format`, `method`) are checked where they are used.

use std::ffi::OsString;
use std::path::PathBuf;
use std::time::Duration;

use pyo3::prelude::*;
use pyo3::types::PyString;
use tokio::sync::Semaphore;

use coherent::session::engine::Execution;

use crate::convert::{self, at_most, finite, optional, text, unsigned};
use crate::errors;
use crate::method::MethodArg;

// ---------------------------------------------------------------------------------------
// Paths

/// `path` of `load_tasks`, `read_tasks`, `load_episode` and `read_results`.
pub(crate) fn path(obj: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
    convert::path(obj, "path")
}

/// `transcript` of `replay`.
pub(crate) fn transcript(obj: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
    convert::path(obj, "transcript")
}

/// `out` of `run`, `replay` (a folder) and `run_bench` (a file): not empty, which would
/// be the current folder.
pub(crate) fn out(obj: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
    let out = convert::path(obj, "out")?;
    if out.as_os_str().is_empty() {
        return Err(errors::argument("out", obj, "an empty path"));
    }
    Ok(out)
}

/// `out` of `run_bench` and the Ray executor's ledger: a results file, or None for the
/// name the run's settings give.
pub(crate) fn results_out(obj: &Bound<'_, PyAny>) -> PyResult<Option<PathBuf>> {
    optional(obj, out)
}

/// `replay_from` of `run_bench`.
pub(crate) fn replay_from(obj: &Bound<'_, PyAny>) -> PyResult<Option<PathBuf>> {
    optional(obj, |o| convert::path(o, "replay_from"))
}

/// `argv` of `cli_main`: a sequence, not a str, each item converted as a path is.
pub(crate) fn argv(obj: &Bound<'_, PyAny>) -> PyResult<Vec<OsString>> {
    each(obj, "argv", |item, name| {
        convert::path(item, name).map(PathBuf::into_os_string)
    })
}

// ---------------------------------------------------------------------------------------
// Counts and seeds

/// `max_states` of `plan`, `validate`, `run` and `run_bench`.
pub(crate) fn max_states(obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    unsigned(obj, "max_states")
}

/// `history` of `run` and `run_bench`.
pub(crate) fn history(obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    unsigned(obj, "history")
}

/// `concurrency` of `LLM` and `run_bench`: at most the permits a semaphore holds (those
/// that limit the requests and the episodes in flight), far beyond any useful count.
pub(crate) fn concurrency(obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    at_most(obj, "concurrency", Semaphore::MAX_PERMITS as u64)
}

/// `max_response_bytes` of `LLM`.
pub(crate) fn max_response_bytes(obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    unsigned(obj, "max_response_bytes")
}

/// `max_retries` of `LLM`.
pub(crate) fn max_retries(obj: &Bound<'_, PyAny>) -> PyResult<u32> {
    unsigned(obj, "max_retries")
}

/// `seeds` of `run_bench`.
pub(crate) fn seeds(obj: &Bound<'_, PyAny>) -> PyResult<u32> {
    unsigned(obj, "seeds")
}

/// `max_steps` of `run`.
pub(crate) fn max_steps(obj: &Bound<'_, PyAny>) -> PyResult<Option<u32>> {
    optional(obj, |o| unsigned(o, "max_steps"))
}

/// `seed` of `LLM` and `run`.
pub(crate) fn seed(obj: &Bound<'_, PyAny>) -> PyResult<Option<u64>> {
    optional(obj, |o| unsigned(o, "seed"))
}

// ---------------------------------------------------------------------------------------
// Floats

/// `temperature` of `LLM`: finite, and within the 32 bits the model's settings hold it in.
pub(crate) fn temperature(obj: &Bound<'_, PyAny>) -> PyResult<f32> {
    let wide = finite(obj, "temperature")?;
    // Rounds to the nearest 32-bit float; beyond the largest, to an infinity.
    let narrow = wide as f32;
    if narrow.is_finite() {
        Ok(narrow)
    } else {
        Err(errors::argument(
            "temperature",
            obj,
            format!("out of range: at most {:e} in magnitude", f32::MAX),
        ))
    }
}

/// A timeout in seconds: finite, not negative, and at most what a `Duration` holds.
fn seconds(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Duration> {
    let s = finite(obj, name)?;
    Duration::try_from_secs_f64(s).map_err(|_| {
        let why = format!("out of range: 0 to {} seconds", Duration::MAX.as_secs());
        errors::argument(name, obj, why)
    })
}

/// `step_timeout` of `run`, `run_bench` and the Ray worker: the longest one step of a
/// method written in Python may take, or None for no limit.
pub(crate) fn step_timeout(obj: &Bound<'_, PyAny>) -> PyResult<Option<Duration>> {
    optional(obj, |o| {
        let limit = seconds(o, "step_timeout")?;
        if limit.is_zero() {
            return Err(errors::argument(
                "step_timeout",
                o,
                "0 seconds: no step could end",
            ));
        }
        Ok(limit)
    })
}

/// `connect_timeout` of `LLM`.
pub(crate) fn connect_timeout(obj: &Bound<'_, PyAny>) -> PyResult<Duration> {
    seconds(obj, "connect_timeout")
}

/// `read_timeout` of `LLM`.
pub(crate) fn read_timeout(obj: &Bound<'_, PyAny>) -> PyResult<Duration> {
    seconds(obj, "read_timeout")
}

/// `timeout` of `LLM`.
pub(crate) fn timeout(obj: &Bound<'_, PyAny>) -> PyResult<Duration> {
    seconds(obj, "timeout")
}

// ---------------------------------------------------------------------------------------
// Text

/// `base_url` of `LLM`: a URL (or a comma-separated list of them), or a list of them,
/// for servers of one model.
pub(crate) fn base_url(obj: &Bound<'_, PyAny>) -> PyResult<Option<Vec<String>>> {
    optional(obj, |o| {
        if o.is_instance_of::<PyString>() {
            return Ok(vec![text(o, "base_url")?.to_owned()]);
        }
        let urls = each(o, "base_url", |item, name| {
            text(item, name).map(str::to_owned)
        })?;
        if urls.is_empty() {
            return Err(errors::argument("base_url", o, "an empty list"));
        }
        Ok(urls)
    })
}

/// `model` of `LLM`.
pub(crate) fn model(obj: &Bound<'_, PyAny>) -> PyResult<Option<String>> {
    optional(obj, |o| text(o, "model").map(str::to_owned))
}

/// `api_key` of `LLM`: text with something in it (None is no key). Its messages never
/// show the key.
pub(crate) fn api_key(obj: &Bound<'_, PyAny>) -> PyResult<Option<String>> {
    optional(obj, |o| {
        let hidden = |why: &str| errors::invalid(o.py(), format!("api_key=[hidden]: {why}"));
        let key = convert::utf8(o.cast::<PyString>()?).map_err(|why| hidden(&why))?;
        if key.trim().is_empty() {
            return Err(hidden("no key in it; leave api_key out (None) for none"));
        }
        Ok(key.to_owned())
    })
}

/// `format` of `LLM` and `report_text`, each checking it against its own choices.
pub(crate) fn format<'a>(obj: &'a Bound<'_, PyAny>) -> PyResult<&'a str> {
    text(obj, "format")
}

/// `method` of `run`.
pub(crate) fn method(obj: &Bound<'_, PyAny>) -> PyResult<MethodArg> {
    method_arg(obj, "method")
}

/// `methods` of `run_bench`: a sequence (not a str) of names and methods.
pub(crate) fn methods(obj: &Bound<'_, PyAny>) -> PyResult<Vec<MethodArg>> {
    each(obj, "methods", method_arg)
}

/// A method argument: a str is a name (a built-in method's, or `MODULE:CLASS`), which
/// must be text; a class or any other callable is a method written in Python.
fn method_arg(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<MethodArg> {
    if obj.is_instance_of::<PyString>() {
        Ok(MethodArg::Name(text(obj, name)?.to_owned()))
    } else if obj.is_callable() {
        Ok(MethodArg::Python(obj.clone().unbind()))
    } else {
        Err(convert::expected(
            obj,
            name,
            "a method's name, or a class (or any callable) of a method written in Python",
        ))
    }
}

/// `execution` of `run` and `Env`: `"sequential"` or `"parallel"`.
pub(crate) fn execution(obj: &Bound<'_, PyAny>) -> PyResult<Execution> {
    convert::execution(obj, "execution")
}

/// `execution` of `bench` (`run_bench`, `_BenchLedger`, `_BenchWorker`): one execution's
/// name, or a sequence of them (each method runs in each).
pub(crate) fn executions(obj: &Bound<'_, PyAny>) -> PyResult<Vec<Execution>> {
    if obj.is_instance_of::<PyString>() {
        return Ok(vec![convert::execution(obj, "execution")?]);
    }
    let all = each(obj, "execution", convert::execution)?;
    if all.is_empty() {
        return Err(errors::argument("execution", obj, "an empty list"));
    }
    Ok(all)
}

/// `subset` of `benchmark_tasks`.
pub(crate) fn subset<'a>(obj: &'a Bound<'_, PyAny>) -> PyResult<Option<&'a str>> {
    optional(obj, |o| text(o, "subset"))
}

/// Each item of the sequence argument `name` (a str is none: a `TypeError`, as for any
/// `Vec`) through `convert`, which names it `name[i]`.
fn each<T>(
    obj: &Bound<'_, PyAny>,
    name: &str,
    convert: impl Fn(&Bound<'_, PyAny>, &str) -> PyResult<T>,
) -> PyResult<Vec<T>> {
    obj.extract::<Vec<Bound<'_, PyAny>>>()?
        .iter()
        .enumerate()
        .map(|(i, item)| convert(item, &format!("{name}[{i}]")))
        .collect()
}
