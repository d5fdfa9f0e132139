//! Conversions between JSON values and Python objects, and running long work off the
//! GIL where Ctrl-C can stop it.

use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use pyo3::IntoPyObjectExt;
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::Value;

/// A JSON value as the Python object `json.loads` would give (key order kept).
pub(crate) fn json_to_py<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
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

/// Any serializable value as a Python object, through JSON.
pub(crate) fn to_py<'py, T: serde::Serialize>(
    py: Python<'py>,
    value: &T,
) -> PyResult<Bound<'py, PyAny>> {
    let value = serde_json::to_value(value).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    json_to_py(py, &value)
}

/// A Python object made of dicts, lists, tuples, strings, numbers, booleans and None as
/// JSON. A float NaN is null and a whole float an integer, as a pandas column with
/// missing values holds them.
pub(crate) fn py_to_json(obj: &Bound<'_, PyAny>) -> PyResult<Value> {
    if obj.is_none() {
        Ok(Value::Null)
    } else if let Ok(b) = obj.cast::<PyBool>() {
        Ok(Value::Bool(b.is_true()))
    } else if obj.is_instance_of::<PyInt>() {
        match obj.extract::<i64>() {
            Ok(i) => Ok(i.into()),
            Err(_) => Ok(obj.extract::<u64>()?.into()),
        }
    } else if let Ok(f) = obj.cast::<PyFloat>() {
        let x = f.value();
        if x.is_nan() {
            Ok(Value::Null)
        } else if x.fract() == 0.0 && x.abs() < 9.0e15 {
            Ok((x as i64).into())
        } else {
            serde_json::Number::from_f64(x)
                .map(Value::Number)
                .ok_or_else(|| PyValueError::new_err(format!("{x} is not a JSON number")))
        }
    } else if let Ok(s) = obj.cast::<PyString>() {
        Ok(Value::String(s.to_cow()?.into_owned()))
    } else if let Ok(d) = obj.cast::<PyDict>() {
        let mut map = serde_json::Map::new();
        for (k, v) in d.iter() {
            let key = k
                .cast::<PyString>()
                .map_err(|_| PyTypeError::new_err(format!("a key that is not a string: {k}")))?;
            map.insert(key.to_cow()?.into_owned(), py_to_json(&v)?);
        }
        Ok(Value::Object(map))
    } else if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        obj.try_iter()?
            .map(|item| py_to_json(&item?))
            .collect::<PyResult<Vec<Value>>>()
            .map(Value::Array)
    } else {
        Err(PyTypeError::new_err(format!(
            "{} is not JSON data (dict, list, str, int, float, bool or None)",
            obj.get_type().name()?
        )))
    }
}

pub(crate) fn py_repr(py: Python<'_>, s: &str) -> String {
    PyString::new(py, s)
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| format!("{s:?}"))
}

/// Runs `f` on its own thread with the GIL released, checking for Ctrl-C (and other
/// signals) every 50 ms. On an interrupt it calls `stop`, which makes the work end early
/// (a planner's cancel flag, an episode's `Cancel`), waits for the thread, and raises the
/// interrupt.
pub(crate) fn interruptible<T, F>(py: Python<'_>, stop: impl FnOnce(), f: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce() -> T + Send + 'static,
{
    let (tx, mut rx) = mpsc::channel();
    let worker = std::thread::Builder::new()
        .name("coherent-worker".to_owned())
        .spawn(move || {
            // The receiver is gone only after an interrupt; nobody wants the result then.
            let _ = tx.send(f());
        })
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start a worker thread: {e}")))?;
    loop {
        // A `&mut` borrow, not `&`: the receiver may move to another thread but not be shared.
        let receiver = &mut rx;
        match py.detach(move || receiver.recv_timeout(Duration::from_millis(50))) {
            Ok(result) => return Ok(result),
            Err(RecvTimeoutError::Timeout) => {
                if let Err(interrupt) = py.check_signals() {
                    stop();
                    // Searches notice within about a thousand states, episodes between
                    // rounds or during a model call.
                    let _ = py.detach(move || worker.join());
                    return Err(interrupt);
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err(
                    "the worker thread panicked (a bug in coherent; see the message on stderr)",
                ));
            }
        }
    }
}
