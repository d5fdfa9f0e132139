//! A task's events (docs/dynamic.md) as a front end gives them: in the task file, in a
//! file of their own (`coherent run --events FILE`), or as Python values (`events=`);
//! read against the task, and checked against the episode before it starts: within the
//! step budget, and in a world that carries them out (the rules, and physics but for a
//! robot joining elsewhere than the task placed it; not yet robots over ROS 2). And
//! the events met by a world stepped by hand (Python's `Env`): [`Stepping`].

use std::path::PathBuf;
use std::sync::Arc;

use coherent_agents::episode::action_failure;
use coherent_core::files::{self, Limit, MIB};
use coherent_core::{Environment, Happening, JsonPath, NodeId, Schedule, Task, events, json};
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
    let ros2 = matches!(robots, Robots::Ros2(_));
    if (physics || ros2)
        && let Some(i) = task
            .events
            .iter()
            .position(|e| matches!(e.happening, Happening::RobotUp { room: Some(_), .. }))
    {
        return Err(Error::Task(coherent_core::Error::Malformed {
            file: origin.file.clone(),
            path: origin.path.index(i).key("room"),
            message: if ros2 {
                "robots over ROS 2 are not carried anywhere at an event: a robot joins where \
                 the task placed it (leave out `room`, or --robots ros2)"
            } else {
                "physics does not carry a robot anywhere at an event: in physics a robot \
                 joins where the task placed it (leave out `room`, or --physics)"
            }
            .into(),
        }));
    }
    Ok(())
}

/// A task's events met by a world stepped by hand (Python's `Env`, and the Gymnasium
/// and PettingZoo environments on it) as the episode's loop meets them: the world as it
/// starts (robots that join later out of the team), then before each step the events due
/// carried out (the team told of them in [`Stepping::news`]), until the goal holds; and
/// a failing-actions event's draws, the loop's own ([`action_failure`]). Each step taken,
/// whatever it did, is one step of the episode.
#[derive(Clone, Debug)]
pub struct Stepping {
    schedule: Schedule,
    seed: u64,
    /// The steps taken since the start.
    taken: u32,
    /// What the team was told before the coming step.
    news: Vec<String>,
}

impl Stepping {
    /// `task`'s events from the start, in `env` in its initial state: the world as it
    /// starts put into it, and the events due before step 1 carried out. `seed` seeds the
    /// failing actions' draws. A task without events leaves `env` as it is.
    pub fn start(
        task: &Arc<Task>,
        seed: u64,
        env: &mut dyn Environment,
    ) -> Result<Stepping, Error> {
        let mut stepping = Stepping {
            schedule: Schedule::new(Arc::clone(task)),
            seed,
            taken: 0,
            news: Vec::new(),
        };
        if !task.events.is_empty() {
            env.befall(stepping.schedule.world(), env.state().clone())?;
        }
        stepping.before_next(env)?;
        Ok(stepping)
    }

    /// After a step is taken in `env`: the events due before the next one, carried out.
    pub fn taken(&mut self, env: &mut dyn Environment) -> Result<(), Error> {
        self.taken += 1;
        self.before_next(env)
    }

    /// The events due before the coming step, carried out on `env` unless the goal holds
    /// (the episode is over, as the loop's is).
    fn before_next(&mut self, env: &mut dyn Environment) -> Result<(), Error> {
        self.news.clear();
        if self.schedule.task().events.is_empty() || env.goal_satisfied() {
            return Ok(());
        }
        let mut state = env.state().clone();
        let changes = self.schedule.before_step(self.taken + 1, &mut state);
        if changes.is_empty() {
            return Ok(());
        }
        self.news = changes
            .iter()
            .filter(|c| !c.told.is_empty())
            .map(|c| c.told.clone())
            .collect();
        env.befall(self.schedule.world(), state)?;
        Ok(())
    }

    /// The steps taken since the start.
    pub fn steps(&self) -> u32 {
        self.taken
    }

    /// The task as given, events and all.
    pub fn task(&self) -> &Arc<Task> {
        self.schedule.task()
    }

    /// The seed of the failing actions' draws.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// What the team was told before the coming step: a sentence per event that tells
    /// something (empty when none happened).
    pub fn news(&self) -> &[String] {
        &self.news
    }

    /// Why `robot`'s action in the coming step fails, when a failing-actions event draws
    /// so: the loop's draw and words, `env` the world the events left.
    pub fn fails(&self, env: &dyn Environment, robot: NodeId) -> Option<String> {
        action_failure(&self.schedule, env.task(), self.seed, self.taken + 1, robot)
    }
}
