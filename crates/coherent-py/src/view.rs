//! `coherent.view`: an episode, two side by side, or benchmark results as one HTML page
//! (one `ViewRequest` of the session layer, as for `coherent view`), and the frame a
//! notebook shows it in.

use coherent::session::engine::ReadLimits;
use coherent::session::view::{Source, ViewRequest, page};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyList;

use crate::bench::result_lines;
use crate::convert;
use crate::errors;
use crate::run::PyEpisode;

/// An `Episode`, or the path of a transcript or a results file.
fn source(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Source> {
    if let Ok(e) = obj.cast::<PyEpisode>() {
        return Ok(Source::Episode(Box::new(e.get().given())));
    }
    match convert::path(obj, name) {
        Ok(path) => Ok(Source::File(path)),
        Err(_) => Err(PyTypeError::new_err(format!(
            "{name}: expected an Episode or the path of a transcript or results file, not {}",
            obj.get_type().name()?
        ))),
    }
}

/// The page of an episode (an `Episode` or a transcript's path), of two side by side
/// (`other`), or of a results file (its index, without episode pages).
#[pyfunction]
#[pyo3(signature = (source_, other = None))]
pub(crate) fn view_page(
    py: Python<'_>,
    source_: &Bound<'_, PyAny>,
    other: Option<&Bound<'_, PyAny>>,
) -> PyResult<String> {
    let request = ViewRequest {
        source: source(source_, "source")?,
        other: other.map(|o| source(o, "other")).transpose()?,
        // The Python API reads with the command line's default limits.
        limits: ReadLimits::default(),
    };
    py.detach(move || request.page(&|_| {}))
        .map_err(|e| errors::session_err(py, e))
}

/// The index page of results lines (dicts, as `coherent.results` reads them), titled
/// with `name`.
#[pyfunction]
pub(crate) fn results_page(lines: &Bound<'_, PyList>, name: &str) -> PyResult<String> {
    let py = lines.py();
    let request = ViewRequest {
        source: Source::Lines {
            name: name.to_owned(),
            lines: result_lines(lines)?,
        },
        other: None,
        limits: ReadLimits::default(),
    };
    request
        .page(&|_| {})
        .map_err(|e| errors::session_err(py, e))
}

/// A page in a sandboxed frame of its own, as a notebook shows it inline.
#[pyfunction]
pub(crate) fn framed_page(html: &str) -> String {
    page::framed(html)
}
