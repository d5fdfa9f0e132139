//! Conversions between JSON values and Python objects, of arguments whose values Rust
//! cannot take as they are (into `ArgumentError`s that name them), and running long work
//! off the GIL where Ctrl-C can stop it.

use std::path::PathBuf;
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use coherent::session::engine::Execution;
use coherent::session::events::EventsSource;
use pyo3::IntoPyObjectExt;
use pyo3::exceptions::{PyOverflowError, PyRuntimeError, PyTypeError, PyUnicodeEncodeError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::Value;

use crate::errors::{self, short_repr};

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
/// missing values holds them. A value JSON cannot hold (an infinite float, an int beyond
/// 64 bits, a str with a lone surrogate) is an `ArgumentError` naming where it is: `at`
/// (an argument's name, an item of it: `lines[3]`) and the path below it.
pub(crate) fn json_at(obj: &Bound<'_, PyAny>, at: &str) -> PyResult<Value> {
    if obj.is_none() {
        Ok(Value::Null)
    } else if let Ok(b) = obj.cast::<PyBool>() {
        Ok(Value::Bool(b.is_true()))
    } else if obj.is_instance_of::<PyInt>() {
        match obj.extract::<i64>() {
            Ok(i) => Ok(i.into()),
            Err(_) => obj.extract::<u64>().map(Value::from).map_err(|_| {
                errors::argument(at, obj, "an int beyond the 64 bits of JSON numbers")
            }),
        }
    } else if let Ok(f) = obj.cast::<PyFloat>() {
        let x = f.value();
        if x.is_nan() {
            Ok(Value::Null)
        } else if x.fract() == 0.0 && x.abs() < 9.0e15 {
            Ok((x as i64).into())
        } else {
            serde_json::Number::from_f64(finite(obj, at)?)
                .map(Value::Number)
                .ok_or_else(|| errors::argument(at, obj, "not a JSON number"))
        }
    } else if obj.is_instance_of::<PyString>() {
        Ok(Value::String(text(obj, at)?.to_owned()))
    } else if let Ok(d) = obj.cast::<PyDict>() {
        let mut map = serde_json::Map::new();
        for (k, v) in d.iter() {
            let place = format!("{at}[{}]", short_repr(&k));
            if !k.is_instance_of::<PyString>() {
                return Err(PyTypeError::new_err(format!(
                    "{place}: a key that is not a string"
                )));
            }
            map.insert(text(&k, &place)?.to_owned(), json_at(&v, &place)?);
        }
        Ok(Value::Object(map))
    } else if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        obj.try_iter()?
            .enumerate()
            .map(|(i, item)| json_at(&item?, &format!("{at}[{i}]")))
            .collect::<PyResult<Vec<Value>>>()
            .map(Value::Array)
    } else {
        Err(PyTypeError::new_err(format!(
            "{at}: {} is not JSON data (dict, list, str, int, float, bool or None)",
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

/// The UTF-8 text of a str, or why it has none: a Python str may hold a lone surrogate,
/// which is no character and which UTF-8 (so Rust) cannot encode.
pub(crate) fn utf8<'a>(s: &'a Bound<'_, PyString>) -> Result<&'a str, String> {
    s.to_str().map_err(|e| unencodable(s, &e))
}

/// What the `UnicodeEncodeError` `e` of encoding `s` is about: the lone surrogate and where.
fn unencodable(s: &Bound<'_, PyAny>, e: &PyErr) -> String {
    let at = e
        .value(s.py())
        .getattr("start")
        .and_then(|i| i.extract::<usize>());
    match at.and_then(|i| Ok((i, s.get_item(i)?.repr()?))) {
        Ok((i, c)) => format!("{c} at index {i} is a lone surrogate, not a character"),
        Err(_) => e.to_string(),
    }
}

/// The `TypeError` of an argument of another type than `what`, naming the argument:
/// `rooms: expected an int or a str, not list`.
pub(crate) fn expected(obj: &Bound<'_, PyAny>, name: &str, what: &str) -> PyErr {
    match obj.get_type().name() {
        Ok(type_name) => PyTypeError::new_err(format!("{name}: expected {what}, not {type_name}")),
        Err(e) => e,
    }
}

/// A str argument's text: another type is a `TypeError`, a str with a lone surrogate an
/// `ArgumentError` naming `name`.
pub(crate) fn text<'a>(obj: &'a Bound<'_, PyAny>, name: &str) -> PyResult<&'a str> {
    let Ok(s) = obj.cast::<PyString>() else {
        return Err(expected(obj, name, "a str"));
    };
    utf8(s).map_err(|why| errors::argument(name, obj, why))
}

/// An action argument's text (`[verb] <name>(id)`); a str with a lone surrogate is an
/// `ActionParseError`, like any action that does not parse.
pub(crate) fn action_text(obj: &Bound<'_, PyAny>) -> PyResult<String> {
    let s = obj.cast::<PyString>()?;
    utf8(s)
        .map(str::to_owned)
        .map_err(|why| errors::not_text_action(s, why))
}

/// A float argument that is finite: NaN, the infinities and an int too large for a
/// float are `ArgumentError`s naming `name`; another type is a `TypeError`.
pub(crate) fn finite(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<f64> {
    match obj.extract::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err(errors::argument(name, obj, "not a finite number")),
        Err(e) if e.is_instance_of::<PyOverflowError>(obj.py()) => {
            Err(errors::argument(name, obj, "too large for a float"))
        }
        Err(e) => Err(e),
    }
}

/// The unsigned ints that int arguments (counts, limits, seeds) convert to.
pub(crate) trait Unsigned: TryFrom<u64> {
    const MAX: u64;
}

impl Unsigned for u32 {
    const MAX: u64 = u32::MAX as u64;
}

impl Unsigned for u64 {
    const MAX: u64 = u64::MAX;
}

impl Unsigned for usize {
    const MAX: u64 = usize::MAX as u64;
}

/// An int argument as `T`: a negative int, or one above `T::MAX`, is an `ArgumentError`
/// naming `name` and the range; another type is a `TypeError`.
pub(crate) fn unsigned<T: Unsigned>(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<T> {
    at_most(obj, name, T::MAX)
}

/// [`unsigned`] up to `max` (no more than `T::MAX`), for a count with a smaller limit.
pub(crate) fn at_most<T: Unsigned>(obj: &Bound<'_, PyAny>, name: &str, max: u64) -> PyResult<T> {
    let out_of_range = || errors::argument(name, obj, format!("out of range: 0 to {max}"));
    match obj.extract::<u64>() {
        Ok(n) if n <= max => T::try_from(n).map_err(|_| out_of_range()),
        Ok(_) => Err(out_of_range()),
        Err(e) if e.is_instance_of::<PyOverflowError>(obj.py()) => Err(out_of_range()),
        Err(e) => Err(e),
    }
}

/// A path argument (a str or an `os.PathLike`, as `PathBuf` takes them; an item of
/// `argv` too, with `into_os_string`): a str the file system encoding cannot encode (a
/// lone surrogate that is no escaped byte) is an `ArgumentError` naming `name`, where
/// PyO3's own conversion panics; another type is a `TypeError`.
pub(crate) fn path(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<PathBuf> {
    let py = obj.py();
    let fspath = py.import("os")?.call_method1("fspath", (obj,))?;
    if let Err(e) = py.import("os")?.call_method1("fsencode", (&fspath,)) {
        return Err(if e.is_instance_of::<PyUnicodeEncodeError>(py) {
            errors::argument(name, obj, unencodable(&fspath, &e))
        } else {
            e
        });
    }
    fspath.extract()
}

/// An argument that may be None: None is `None`, any other value goes through `convert`.
pub(crate) fn optional<'a, 'py, T>(
    obj: &'a Bound<'py, PyAny>,
    convert: impl FnOnce(&'a Bound<'py, PyAny>) -> PyResult<T>,
) -> PyResult<Option<T>> {
    if obj.is_none() {
        Ok(None)
    } else {
        convert(obj).map(Some)
    }
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

/// An execution's name: `"sequential"` or `"parallel"`, for the argument `name`.
pub(crate) fn execution(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Execution> {
    let given = text(obj, name)?;
    given
        .parse()
        .map_err(|_| errors::argument(name, obj, "expected \"sequential\" or \"parallel\""))
}

/// `events=`: a list of events (or a dict with an `events` list), or the path of a JSON
/// file of them (docs/dynamic.md).
pub(crate) fn events_source(obj: &Bound<'_, PyAny>) -> PyResult<EventsSource> {
    if obj.is_instance_of::<PyList>()
        || obj.is_instance_of::<PyTuple>()
        || obj.is_instance_of::<PyDict>()
    {
        Ok(EventsSource::Given {
            name: "events=".to_owned(),
            value: json_at(obj, "events")?,
        })
    } else {
        Ok(EventsSource::File(path(obj, "events")?))
    }
}
