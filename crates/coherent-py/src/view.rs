//! `coherent.view`: an episode, two side by side, or benchmark results as one HTML page
//! (the session layer's `coherent::session::view`, as for `coherent view`), and the
//! frame a notebook shows it in.

use std::path::PathBuf;
use std::sync::Arc;

use coherent::session::engine::{ReadLimits, Task, Transcript, read_results_within};
use coherent::session::view::{self, Holds, Shown, page};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyList;

use crate::bench::result_lines;
use crate::convert;
use crate::errors;
use crate::run::PyEpisode;

/// An episode as given: in memory, or read from its transcript.
struct Given {
    task: Arc<Task>,
    transcript: Transcript,
    cost_usd: Option<f64>,
}

impl Given {
    fn shown(&self) -> Shown<'_> {
        Shown {
            task: &self.task,
            transcript: &self.transcript,
            cost_usd: self.cost_usd,
        }
    }
}

fn of_episode(e: &PyEpisode) -> Given {
    Given {
        task: Arc::clone(&e.task.get().task),
        transcript: e.transcript.clone(),
        cost_usd: e.cost_usd,
    }
}

/// An `Episode`, or the path of a transcript or a results file.
enum Source {
    Episode(Box<Given>),
    Path(PathBuf),
}

fn source(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Source> {
    if let Ok(e) = obj.cast::<PyEpisode>() {
        return Ok(Source::Episode(Box::new(of_episode(e.get()))));
    }
    match convert::path(obj, name) {
        Ok(path) => Ok(Source::Path(path)),
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
    let first = source(source_, "source")?;
    let second = other.map(|o| source(o, "other")).transpose()?;
    // The Python API reads with the command line's default limits.
    let limits = ReadLimits::default();
    py.detach(move || -> Result<String, String> {
        let episode = |s: Source| -> Result<Given, String> {
            match s {
                Source::Episode(g) => Ok(*g),
                Source::Path(path) => match view::holds(&path, limits)? {
                    Holds::Transcript => {
                        let (task, transcript) =
                            view::read_episode(&path, limits.transcript_bytes)?;
                        Ok(Given {
                            task,
                            transcript,
                            cost_usd: None,
                        })
                    }
                    Holds::Results => Err(format!(
                        "{}: a results file, where an episode was expected",
                        path.display()
                    )),
                },
            }
        };
        match (first, second) {
            (Source::Path(path), None) if view::holds(&path, limits)? == Holds::Results => {
                let lines = read_results_within(&path, limits.results_bytes)
                    .map_err(|e| e.to_string())?
                    .lines;
                view::results_html(&path, &lines, &[], None)
            }
            (a, None) => view::episode_html(&episode(a)?.shown()),
            (a, Some(b)) => {
                let (a, b) = (episode(a)?, episode(b)?);
                view::compare_html(&a.shown(), &b.shown())
            }
        }
    })
    .map_err(|e| errors::error(py, errors::Kind::Coherent, e, None))
}

/// The index page of results lines (dicts, as `coherent.results` reads them), titled
/// with `name`.
#[pyfunction]
pub(crate) fn results_page(lines: &Bound<'_, PyList>, name: &str) -> PyResult<String> {
    let py = lines.py();
    let lines = result_lines(lines)?;
    view::results_html(&PathBuf::from(name), &lines, &[], None)
        .map_err(|e| errors::error(py, errors::Kind::Coherent, e, None))
}

/// A page in a sandboxed frame of its own, as a notebook shows it inline.
#[pyfunction]
pub(crate) fn framed_page(html: &str) -> String {
    page::framed(html)
}
