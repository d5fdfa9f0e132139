//! One episode: prepared (the task, the settings, the budget, the backend, the
//! environment), then run with its transcript written as it goes; or a recorded episode
//! replayed from its transcript and checked against it.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::bench::BackendChoice;
use coherent_agents::episode::{self, Budget, Settings};
use coherent_agents::llm::{Backend, BackendInfo, Usage};
use coherent_agents::transcript::{self, Round, Transcript};
use coherent_agents::{Cancel, Episode, PriceTable, Replay};
use coherent_core::planner::Limits;
use coherent_core::text::number;
use coherent_core::{Environment, SymbolicEnv, Task, native};

/// Why an episode could not run.
#[derive(Debug)]
pub enum Failure {
    /// The physical world could not be built for the task.
    Physics(coherent_sim::PhysicsError),
    /// Anything else: a budget that cannot be sized, a transcript that cannot be read or
    /// written, a recording that does not fit the task given.
    Other(String),
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Failure::Physics(e) => write!(f, "physics: {}", e.message),
            Failure::Other(why) => f.write_str(why),
        }
    }
}

impl From<String> for Failure {
    fn from(why: String) -> Failure {
        Failure::Other(why)
    }
}

/// Who carries an episode's actions out.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum Robots {
    /// This process: the rules, and Rapier too with physics.
    #[default]
    Local,
    /// One ROS 2 action server per robot (`coherent robots serve`, or real robots).
    Ros2(coherent_ros::BridgeOptions),
}

impl Robots {
    /// Robots over ROS 2 under `namespace` (made absolute), each allowed `robot_timeout`
    /// seconds of silence in a step, all awaited `server_wait` seconds before the first.
    pub fn ros2(namespace: &str, robot_timeout: f64, server_wait: f64) -> Result<Robots, String> {
        let seconds = |what: &str, s: f64| {
            std::time::Duration::try_from_secs_f64(s)
                .map_err(|_| format!("{what} must be seconds from 0 to 1.8e19, not {}", number(s)))
        };
        Ok(Robots::Ros2(coherent_ros::BridgeOptions {
            namespace: coherent_ros::wire::namespace(namespace)?,
            robot_timeout: seconds("the robot timeout", robot_timeout)?,
            server_wait: seconds("the wait for the servers", server_wait)?,
        }))
    }
}

/// The environment an episode runs in: Rapier with `physics`, else the rules alone; over
/// ROS 2 with [`Robots::Ros2`] (physics is then the servers' business), once every
/// robot's server is there, with `cancel` cancelling the goal in flight.
pub fn environment(
    task: &Arc<Task>,
    physics: bool,
    robots: &Robots,
    cancel: &Cancel,
) -> Result<Box<dyn Environment + Send + Sync>, Failure> {
    Ok(match robots {
        Robots::Local if physics => {
            Box::new(coherent_sim::PhysicalEnv::new(Arc::clone(task)).map_err(Failure::Physics)?)
        }
        Robots::Local => Box::new(SymbolicEnv::new(Arc::clone(task))),
        Robots::Ros2(_) if physics => {
            return Err(Failure::Other(
                "over ROS 2 physics is the robots' business: pass --physics to \
                 `coherent robots serve` instead"
                    .into(),
            ));
        }
        Robots::Ros2(options) => Box::new(
            coherent_ros::Ros2Env::connect(Arc::clone(task), options.clone(), Some(cancel.flag()))
                .map_err(|e| Failure::Other(e.to_string()))?,
        ),
    })
}

/// What a new episode is to be.
#[derive(Debug)]
pub struct EpisodeSpec {
    pub task: Arc<Task>,
    /// The method, its history window, the sampling settings, physics or not, the
    /// prompt set.
    pub settings: Settings,
    /// Overrides the budget of 2 x GT.
    pub max_steps: Option<u32>,
    pub backend: BackendChoice,
    /// Most states one planner search may visit (the budget without a GT, the built-in
    /// and simulated backends, the optimal method).
    pub max_states: usize,
    /// The folder the transcript goes to.
    pub out: PathBuf,
    /// Prices the episode's tokens ([`Ran::cost_usd`]).
    pub prices: PriceTable,
    /// Who carries the actions out.
    pub robots: Robots,
}

/// An episode ready to run.
pub struct Prepared {
    pub task: Arc<Task>,
    pub settings: Settings,
    pub budget: Budget,
    backend: Arc<dyn Backend>,
    env: Box<dyn Environment + Send + Sync>,
    out: PathBuf,
    prices: PriceTable,
    /// The recording a replay answers from and is checked against, and its file.
    recording: Option<(Replay, PathBuf)>,
}

impl std::fmt::Debug for Prepared {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Prepared")
            .field("task", &self.task.meta.name)
            .field("settings", &self.settings)
            .field("budget", &self.budget)
            .field("backend", &self.backend.info())
            .finish_non_exhaustive()
    }
}

/// An episode as it ran: the transcript as written (in memory), where it is, whether the
/// goal holds at the end, and for a replay whether it came out as recorded.
#[derive(Debug)]
pub struct Ran {
    pub task: Arc<Task>,
    pub transcript: Transcript,
    pub path: PathBuf,
    pub goal_satisfied: bool,
    /// `Some(Err(why))` when a replayed round or summary differs from the recording.
    pub replay: Option<Result<(), String>>,
    /// What the model calls cost in USD (`PriceTable::episode_cost`); `None` when the
    /// model has no price.
    pub cost_usd: Option<f64>,
}

impl Ran {
    pub fn summary(&self) -> &transcript::Summary {
        self.transcript
            .summary
            .as_ref()
            .expect("a finished episode has its summary")
    }
}

/// Prepares a new episode: sizes its budget (which may plan, stopped by `cancel`),
/// builds its backend and its environment.
pub fn prepare(spec: EpisodeSpec, cancel: &Cancel) -> Result<Prepared, Failure> {
    let limits = Limits {
        cancel: Some(cancel.flag()),
        ..Limits::max_states(spec.max_states)
    };
    let budget = Budget::of(&spec.task, spec.max_steps, &limits)?;
    let seed = spec.settings.seed.unwrap_or(0);
    let backend = spec.backend.for_episode(&limits, seed).ok_or_else(|| {
        Failure::Other("a benchmark's replay backend answers benchmark episodes only".into())
    })?;
    let env = environment(&spec.task, spec.settings.physics, &spec.robots, cancel)?;
    Ok(Prepared {
        task: spec.task,
        settings: spec.settings,
        budget,
        backend,
        env,
        out: spec.out,
        prices: spec.prices,
        recording: None,
    })
}

/// Prepares the replay of the episode recorded at `path`: the task, settings (the prompt
/// set included) and budget as recorded, answered from the recording (no network). With
/// `given`, the recorded task must be that task. `prices` prices the recorded tokens; a
/// transcript of more than `max_bytes` is refused.
pub fn prepare_replay(
    path: &Path,
    given: Option<&Task>,
    out: PathBuf,
    prices: PriceTable,
    max_bytes: u64,
) -> Result<Prepared, Failure> {
    let recorded = transcript::read_within(path, max_bytes)?;
    if let Some(given) = given
        && native::to_value(given) != recorded.header.task
    {
        return Err(Failure::Other(format!(
            "the task given differs from the one recorded in {}",
            path.display()
        )));
    }
    let replay = Replay::prepare(&recorded, path)?;
    let env = environment(
        &replay.task,
        replay.settings.physics,
        &Robots::Local,
        &Cancel::default(),
    )?;
    Ok(Prepared {
        task: Arc::clone(&replay.task),
        settings: replay.settings.clone(),
        budget: replay.budget,
        backend: Arc::clone(&replay.backend) as Arc<dyn Backend>,
        env,
        out,
        prices,
        recording: Some((replay, path.to_owned())),
    })
}

impl Prepared {
    /// The backend that answers, as the transcript records it.
    pub fn backend_info(&self) -> BackendInfo {
        self.backend.info()
    }

    /// The transcript a replay answers from.
    pub fn replaying(&self) -> Option<&Path> {
        self.recording.as_ref().map(|(_, p)| p.as_path())
    }

    /// Runs the episode, writing its transcript into the output folder; `progress` sees
    /// each round as it ends; `cancel` ends it between rounds or in a model call.
    pub async fn run(
        mut self,
        cancel: &Cancel,
        progress: &mut (dyn FnMut(&Round) + Send),
    ) -> Result<Ran, Failure> {
        let path = episode::transcript_path(&self.out, &self.task, self.settings.method.name());
        let (episode, header) = episode::run(
            &self.task,
            self.env.as_mut(),
            self.backend.as_ref(),
            &self.settings,
            self.budget,
            &path,
            cancel,
            progress,
        )
        .await?;
        let replay = self
            .recording
            .as_ref()
            .map(|(replay, _)| replay.check(&episode));
        let Episode { rounds, summary } = episode;
        let usage = Usage {
            prompt_tokens: summary.prompt_tokens,
            completion_tokens: summary.completion_tokens,
            cached_tokens: summary.cached_tokens,
        };
        let uses_model = self.settings.method.uses_model();
        let cost_usd = self
            .prices
            .episode_cost(&header.backend.model, uses_model, &usage);
        Ok(Ran {
            task: self.task,
            transcript: Transcript {
                header,
                rounds,
                summary: Some(summary),
            },
            path,
            goal_satisfied: self.env.goal_satisfied(),
            replay,
            cost_usd,
        })
    }
}
