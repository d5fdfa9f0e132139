//! The scene from above: its geometry, the robots' paths in physics, and the SVG picture
//! of `coherent render`.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use coherent::session::engine::{Limits, Task, Transcript};
use coherent::session::render::{self, Paths, RobotPath};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

use crate::convert::{interruptible, to_py};
use crate::errors::PyCoherentResult;
use crate::run::PyEpisode;
use crate::task::PyTask;

/// The geometry of `task`'s scene (its own, or the one generated from its graph), as the
/// `geometry` object of a native task file: `rooms` (each on its storey's `level`),
/// `doors`, `stairs` (when any), `items`, `robots`, `specs`, `wall_height`; metres,
/// `[x, z]` on the floor plan, `y` up.
#[pyfunction]
pub(crate) fn scene_layout<'py>(
    py: Python<'py>,
    task: &Bound<'py, PyTask>,
) -> PyCoherentResult<Bound<'py, PyAny>> {
    let layout = render::scene_layout(&task.get().task)?;
    Ok(to_py(py, &layout)?)
}

/// A task (its optimal plan) or an episode (its executed actions), as given to Python.
enum Source {
    Plan(Arc<Task>),
    Episode(Arc<Task>, Box<Transcript>),
}

fn source_of(source: &Bound<'_, PyAny>) -> PyResult<Source> {
    if let Ok(task) = source.cast::<PyTask>() {
        return Ok(Source::Plan(Arc::clone(&task.get().task)));
    }
    if let Ok(episode) = source.cast::<PyEpisode>() {
        let e = episode.get();
        return Ok(Source::Episode(
            Arc::clone(&e.task.get().task),
            Box::new(e.transcript.clone()),
        ));
    }
    Err(PyTypeError::new_err(format!(
        "expected a Task or an Episode, not {}",
        source.get_type().name()?
    )))
}

/// The paths, off the GIL; Ctrl-C stops the plan search.
fn paths_of(py: Python<'_>, source: Source) -> PyCoherentResult<(Arc<Task>, Vec<RobotPath>)> {
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&cancel);
    let result = interruptible(
        py,
        move || flag.store(true, Ordering::Relaxed),
        move || match source {
            Source::Plan(task) => {
                let limits = Limits {
                    cancel: Some(cancel),
                    ..Limits::default()
                };
                render::plan_paths(&task, &limits).map(|p| (task, p))
            }
            Source::Episode(task, transcript) => {
                render::replay_paths(&task, &transcript).map(|p| (task, p))
            }
        },
    )?;
    let (task, Paths { paths, warning }) = result?;
    if let Some(why) = warning {
        eprintln!("warning: {why}");
    }
    Ok((task, paths))
}

/// A robot's track as Python gets it: `(x, y, z)` points.
type Track = Vec<(f32, f32, f32)>;

/// Each mobile robot's track, `{robot id: [(x, y, z), ...]}` (`y` up, as in the
/// layout), when a task's optimal plan or an episode's executed actions are carried out
/// in physics.
#[pyfunction]
pub(crate) fn robot_paths(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
) -> PyCoherentResult<BTreeMap<i64, Track>> {
    let (_, paths) = paths_of(py, source_of(source)?)?;
    Ok(paths
        .into_iter()
        .map(|(id, points)| {
            (
                id.0,
                points.into_iter().map(|[x, y, z]| (x, y, z)).collect(),
            )
        })
        .collect())
}

/// The scene from above as SVG, as `coherent render` draws it; with `paths`, each
/// robot's path along the task's optimal plan or the episode's executed actions.
#[pyfunction]
#[pyo3(signature = (source, *, paths = true))]
pub(crate) fn render_svg(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    paths: bool,
) -> PyCoherentResult<String> {
    let source = source_of(source)?;
    let (task, drawn) = if paths {
        let (task, p) = paths_of(py, source)?;
        (task, Some(p))
    } else {
        match source {
            Source::Plan(task) | Source::Episode(task, _) => (task, None),
        }
    };
    Ok(render::svg(&task, drawn.as_deref())?)
}
