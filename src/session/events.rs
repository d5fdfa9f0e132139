//! A task's events (docs/dynamic.md) as a front end gives them: in the task file, in a
//! file of their own (`coherent run --events FILE`), or as Python values (`events=`);
//! read against the task, and checked against the episode before it starts: within the
//! step budget, and in a world that carries them out (the rules, and physics but for a
//! robot joining elsewhere than the task placed it; not yet robots over ROS 2).

use std::path::PathBuf;
use std::sync::Arc;

use coherent_core::files::{self, Limit, MIB};
use coherent_core::{Happening, JsonPath, Task, events, json};
use serde_json::Value;

use crate::session::error::Error;
use crate::session::robots::Robots;

/// The most an events file may hold.
const EVENTS_FILE_LIMIT: Limit = Limit {
    bytes: 16 * MIB,
    what: "an events file",
    raise: None,
};

/// Where an episode's events come from, when not from its task file: they replace the
/// task's own.
#[derive(Clone, Debug)]
pub enum EventsSource {
    /// A JSON file: a list of events, or an object with an `events` list.
    File(PathBuf),
    /// Values given in memory (Python's `events=`), named `name` in errors.
    Given { name: String, value: Value },
}

/// Where the events of an episode were read, for errors about them: the file, and the
/// JSON path of the list in it.
#[derive(Clone, Debug)]
pub struct Origin {
    pub file: String,
    pub path: JsonPath,
}

/// `task` with the events of `source` in place of its own, and where they were read;
/// the task as it is, with its file (`task_file`), without a source.
pub fn attach(
    task: Arc<Task>,
    source: Option<EventsSource>,
    task_file: &str,
) -> Result<(Arc<Task>, Origin), Error> {
    let (file, value) = match source {
        None => {
            let origin = Origin {
                file: task_file.to_owned(),
                path: JsonPath::root().key("events"),
            };
            return Ok((task, origin));
        }
        Some(EventsSource::File(path)) => {
            let file = path.display().to_string();
            let bytes = files::read(&path, &EVENTS_FILE_LIMIT)?;
            (file.clone(), json::parse(&file, &bytes)?)
        }
        Some(EventsSource::Given { name, value }) => (name, value),
    };
    let (list, path) = match value.get("events") {
        Some(list) if value.is_object() => (list.clone(), JsonPath::root().key("events")),
        _ => (value, JsonPath::root()),
    };
    let read = events::read(&task, &list, &file, path.clone())?;
    let mut task = Arc::unwrap_or_clone(task);
    task.events = read;
    Ok((Arc::new(task), Origin { file, path }))
}

/// Refuses, before the episode starts, events it cannot run: an event at a step past
/// the budget (`max_steps`), and events in a world that does not carry them out.
pub fn check(
    task: &Task,
    origin: &Origin,
    max_steps: u32,
    physics: bool,
    robots: &Robots,
) -> Result<(), Error> {
    if task.events.is_empty() {
        return Ok(());
    }
    if let Some((i, step)) = events::last_step(&task.events)
        && step > max_steps
    {
        return Err(Error::Task(coherent_core::Error::Malformed {
            file: origin.file.clone(),
            path: origin.path.index(i).key("step"),
            message: format!(
                "step {step} is past the episode's step budget ({max_steps}): it would never happen"
            ),
        }));
    }
    if let Robots::Ros2(_) = robots {
        return Err(Error::Invalid(format!(
            "{}: the task has {} events, and robots over ROS 2 do not carry events out yet \
             (the rules and physics do: leave out --robots ros2)",
            origin.file,
            task.events.len()
        )));
    }
    if physics
        && let Some(i) = task
            .events
            .iter()
            .position(|e| matches!(e.happening, Happening::RobotUp { room: Some(_), .. }))
    {
        return Err(Error::Task(coherent_core::Error::Malformed {
            file: origin.file.clone(),
            path: origin.path.index(i).key("room"),
            message: "physics does not carry a robot anywhere at an event: in physics a robot \
                      joins where the task placed it (leave out `room`, or --physics)"
                .into(),
        }));
    }
    Ok(())
}
