//! One episode, whoever asks for it, and the one runner of them all. A front end fills a
//! request, a new episode ([`RunRequest`]: `coherent run`, `coherent.run`) or the replay
//! of a transcript ([`ReplayRequest`]), and prepares it in one call that does the whole
//! sequence (the prompt set, the prices, the task, the endpoint and the backend, the
//! budget, the environment); a benchmark prepares each of its episodes
//! ([`crate::session::bench`]). Each becomes an [`EpisodeSpec`] (the task, the settings,
//! the budget, the backend, the robots); [`prepare`] builds its environment, and
//! [`Prepared::run`] runs it: the transcript written as it goes, a replay compared with
//! its recording, the model calls priced ([`ModelUse`]), into a [`Ran`].

use std::path::{Path, PathBuf};
use std::sync::Arc;

use coherent_agents::episode::{Budget, HISTORY_WINDOW, Method};
use coherent_agents::llm::Backend;
use coherent_agents::run::new_transcript;
use coherent_agents::run::replay::recorded_task;
use coherent_agents::transcript::{self, Round, Status, Transcript};
use coherent_agents::{BackendInfo, Cancel, Episode, ModelUse, PriceTable, Replay};
use coherent_agents::{MethodSpec, Settings};
use coherent_core::planner::Limits;
use coherent_core::{Environment, Execution, SymbolicEnv, Task, native};

use crate::session::backend::{BackendChoice, BackendRequest};
use crate::session::error::Error;
use crate::session::events::{self, EventsSource};
use crate::session::prompts::{PriceSource, PromptSource};
use crate::session::robots::{Robots, ros_error};
use crate::session::tasks::TaskSource;
use crate::session::waiting::Waiting;

/// A new episode.
#[derive(Debug)]
pub struct RunRequest {
    pub task: TaskSource,
    pub method: MethodSpec,
    /// One robot's action a step (the paper's), or joint steps.
    pub execution: Execution,
    /// Who answers the method's questions.
    pub backend: BackendRequest,
    pub prompts: PromptSource,
    pub prices: PriceSource,
    /// Who carries the actions out.
    pub robots: Robots,
    /// Every action in Rapier too.
    pub physics: bool,
    /// Overrides the budget of 2 x GT (2 x the makespan in joint steps).
    pub max_steps: Option<u32>,
    /// Rounds of history the methods see.
    pub history: usize,
    /// The episode's seed: the simulated backend's mistakes, MCTS's search, DMRS's
    /// speaking order (the model's sampling seed is the endpoint's).
    pub seed: Option<u64>,
    /// Most states one planner search may visit (the budget without a GT, the built-in
    /// and simulated backends, the optimal method).
    pub max_states: usize,
    /// The folder the transcript goes to.
    pub out: PathBuf,
    /// Events in place of the task's own (docs/dynamic.md).
    pub events: Option<EventsSource>,
}

impl RunRequest {
    /// `method` on `task` with the defaults: sequential, the backend the environment
    /// configures, the built-in prompts and prices, local robots, no physics, 2 x GT
    /// steps, the history window, transcripts into `runs/`.
    pub fn new(task: TaskSource, method: MethodSpec) -> RunRequest {
        RunRequest {
            task,
            method,
            execution: Execution::Sequential,
            backend: BackendRequest::default(),
            prompts: PromptSource::default(),
            prices: PriceSource::default(),
            robots: Robots::Local,
            physics: false,
            max_steps: None,
            history: HISTORY_WINDOW,
            seed: None,
            max_states: Limits::DEFAULT_MAX_STATES,
            out: PathBuf::from("runs"),
            events: None,
        }
    }

    /// The episode, ready to run. The prompt set is read first, so that a bad template
    /// costs nothing; sizing the budget may plan (`cancel` stops it); over ROS 2 the
    /// robots' servers are awaited.
    pub fn prepare(self, cancel: &Cancel) -> Result<Prepared, Error> {
        let prompts = self.prompts.read()?;
        let prices = self.prices.read()?;
        let task_file = self.task.file_name();
        let (task, events_origin) = events::attach(self.task.task()?, self.events, &task_file)?;
        let choice = self.backend.choose()?;
        let limits = Limits {
            cancel: Some(cancel.flag()),
            ..Limits::max_states(self.max_states)
        };
        let settings = Settings {
            method: self.method,
            execution: self.execution,
            history: self.history,
            temperature: choice.temperature(),
            seed: self.seed,
            physics: self.physics,
            robots: self.robots.record(),
            prompts,
            max_states: self.max_states,
        };
        // Built before the budget is searched for: a method that cannot run the
        // execution costs no search.
        let method = settings.build(&task, cancel)?;
        let budget = Budget::searched(&task, self.execution, self.max_steps, &limits)?;
        events::check(
            &task,
            &events_origin,
            budget.steps(),
            self.physics,
            &self.robots,
        )?;
        let backend = choice.for_episode(&limits, self.seed.unwrap_or(0))?;
        let spec = EpisodeSpec {
            task,
            settings,
            budget,
            backend,
            robots: self.robots,
            out: self.out,
            prices,
            recording: None,
            choice: Some(choice),
        };
        prepare_with(spec, method, cancel)
    }
}

/// The replay of a recorded episode: its task, settings (the prompt set included) and
/// budget as recorded, answered from the recording (no network), the robots in this
/// process.
#[derive(Debug)]
pub struct ReplayRequest {
    /// The transcript.
    pub transcript: PathBuf,
    /// When given, the recorded task must be this one.
    pub task: Option<TaskSource>,
    /// Prices the recorded tokens.
    pub prices: PriceSource,
    /// The folder the replay's transcript goes to.
    pub out: PathBuf,
    /// The most the transcript may hold.
    pub max_bytes: u64,
}

impl ReplayRequest {
    /// The replay, ready to run; a transcript of more than `max_bytes` is refused.
    pub fn prepare(self) -> Result<Prepared, Error> {
        let prices = self.prices.read()?;
        let path = self.transcript;
        let recorded = transcript::read_within(&path, self.max_bytes)?;
        if recorded.summary.is_none() {
            return Err(Error::File {
                file: path.display().to_string(),
                line: None,
                message: format!(
                    "unfinished: the episode was stopped after {} rounds (the transcript has \
                     no summary line), so there is no end to replay it to",
                    recorded.rounds.len()
                ),
            });
        }
        if let Some(given) = self.task
            && native::to_value(&*given.task()?) != recorded.header.task
        {
            return Err(Error::Invalid(format!(
                "the task given differs from the one recorded in {}",
                path.display()
            )));
        }
        let replay = Replay::prepare(&recorded, &path)?;
        let spec = EpisodeSpec {
            task: Arc::clone(&replay.task),
            settings: replay.settings.clone(),
            budget: replay.budget,
            backend: Arc::clone(&replay.backend) as Arc<dyn Backend>,
            robots: Robots::Local,
            out: self.out,
            prices,
            recording: Some((replay, path)),
            choice: None,
        };
        prepare(spec, &Cancel::default())
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
) -> Result<Box<dyn Environment + Send + Sync>, Error> {
    Ok(match robots {
        Robots::Local if physics => Box::new(coherent_sim::PhysicalEnv::new(Arc::clone(task))?),
        Robots::Local => Box::new(SymbolicEnv::new(Arc::clone(task))),
        Robots::Ros2(_) if physics => {
            return Err(Error::Invalid(
                "over ROS 2 physics is the robots' business: pass --physics to \
                 `coherent robots serve` instead"
                    .into(),
            ));
        }
        Robots::Ros2(options) => Box::new(
            coherent_ros::Ros2Env::connect(Arc::clone(task), options.clone(), Some(cancel.flag()))
                .map_err(ros_error)?,
        ),
    })
}

/// Everything one episode runs with.
pub struct EpisodeSpec {
    pub task: Arc<Task>,
    /// The method, its history window, the sampling settings, physics or not, the
    /// prompt set (the robots are recorded from [`EpisodeSpec::robots`]).
    pub settings: Settings,
    pub budget: Budget,
    /// Answers the method's questions.
    pub backend: Arc<dyn Backend>,
    /// Who carries the actions out.
    pub robots: Robots,
    /// The folder the transcript goes to.
    pub out: PathBuf,
    /// Prices the model calls ([`Ran::cost_usd`]).
    pub prices: PriceTable,
    /// The recording a replay answers from and is compared with, and its file.
    pub recording: Option<(Replay, PathBuf)>,
    /// The backend chosen for a new episode, as the front ends describe it (none for a
    /// replay).
    pub choice: Option<BackendChoice>,
}

/// An episode ready to run: its spec, its method and its environment.
pub struct Prepared {
    spec: EpisodeSpec,
    method: Box<dyn Method>,
    env: Box<dyn Environment + Send + Sync>,
}

impl std::fmt::Debug for EpisodeSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EpisodeSpec")
            .field("task", &self.task.meta.name)
            .field("settings", &self.settings)
            .field("budget", &self.budget)
            .field("backend", &self.backend.info())
            .field("robots", &self.robots)
            .finish_non_exhaustive()
    }
}

impl std::fmt::Debug for Prepared {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Prepared")
            .field("spec", &self.spec)
            .finish_non_exhaustive()
    }
}

/// Builds the method and the environment of the episode `spec` (over ROS 2, once the
/// robots' servers are there; `cancel` cancels a goal in flight, and stops the optimal
/// method's search).
pub fn prepare(spec: EpisodeSpec, cancel: &Cancel) -> Result<Prepared, Error> {
    let method = spec.settings.build(&spec.task, cancel)?;
    prepare_with(spec, method, cancel)
}

/// [`prepare`] with its method already built.
fn prepare_with(
    mut spec: EpisodeSpec,
    method: Box<dyn Method>,
    cancel: &Cancel,
) -> Result<Prepared, Error> {
    spec.settings.robots = spec.robots.record();
    let env = environment(&spec.task, spec.settings.physics, &spec.robots, cancel)?;
    Ok(Prepared { spec, method, env })
}

/// An episode read back from its transcript: the task it ran and what it recorded.
#[derive(Debug)]
pub struct Recorded {
    pub task: Arc<Task>,
    pub transcript: Transcript,
    /// The transcript's file.
    pub path: PathBuf,
}

/// The episode recorded in the transcript at `path`, of at most `max_bytes`.
pub fn recorded(path: &Path, max_bytes: u64) -> Result<Recorded, Error> {
    let transcript = transcript::read_within(path, max_bytes)?;
    let task = Arc::new(recorded_task(&transcript, path)?);
    Ok(Recorded {
        task,
        transcript,
        path: path.to_owned(),
    })
}

impl Recorded {
    /// The summary of a finished episode; an error when the transcript has none (the
    /// episode was killed before its end).
    pub fn finished(&self) -> Result<&transcript::Summary, Error> {
        self.transcript.summary.as_ref().ok_or_else(|| Error::File {
            file: self.path.display().to_string(),
            line: None,
            message: "no summary line: the episode did not finish".into(),
        })
    }

    /// What its model calls cost at `prices`, by the rule they cost when it ran
    /// ([`ModelUse`]); `None` when the model has no price or the episode did not finish.
    pub fn cost(&self, prices: &PriceTable) -> Option<f64> {
        let t = &self.transcript;
        let summary = t.summary.as_ref()?;
        ModelUse::of(&t.header, &t.rounds, summary).cost(prices)
    }
}

/// How an episode's replay came out.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ReplayCheck {
    /// Every round and the summary as recorded.
    Same,
    /// It first differs here.
    Differs(String),
}

/// An episode as it ran: the transcript as written (in memory), where it is, whether the
/// goal holds at the end, for a replay whether it came out as recorded, and what its
/// model calls cost.
#[derive(Debug)]
pub struct Ran {
    pub task: Arc<Task>,
    pub transcript: Transcript,
    pub path: PathBuf,
    pub goal_satisfied: bool,
    /// `Some` for a replay.
    pub replay: Option<ReplayCheck>,
    /// The model that answered, the tokens and the calls.
    pub model_use: ModelUse,
    /// What the model calls cost in USD ([`ModelUse::cost`]); `None` when the model has
    /// no price.
    pub cost_usd: Option<f64>,
}

/// How an episode ended, as the front ends report it (an exit status, an exception).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Ending {
    /// The goal holds.
    GoalReached,
    /// An event put the goal out of reach and the team stopped acting: right
    /// (docs/dynamic.md).
    Conceded,
    /// The step budget is spent.
    BudgetSpent,
    /// The model's server failed for good.
    BackendFailed(String),
    /// A replay did not come out as recorded.
    ReplayDiffers(String),
    /// A method written outside the crate (Python) raised.
    MethodFailed(String),
    /// A robot over ROS 2 stopped answering (or disagreed with the rules): the
    /// environment stopped the episode.
    RobotStopped(String),
    /// Stopped from outside (Ctrl-C).
    Interrupted,
}

impl Ran {
    pub fn summary(&self) -> &transcript::Summary {
        self.transcript
            .summary
            .as_ref()
            .expect("a finished episode has its summary")
    }

    /// How the episode ended; a replay that differs from its recording says so first.
    pub fn ending(&self) -> Ending {
        if let Some(ReplayCheck::Differs(why)) = &self.replay {
            return Ending::ReplayDiffers(why.clone());
        }
        let s = self.summary();
        let error = || s.error.clone().unwrap_or_default();
        match s.status {
            Status::Success => Ending::GoalReached,
            Status::Conceded => Ending::Conceded,
            Status::Failure => Ending::BudgetSpent,
            Status::BackendError => Ending::BackendFailed(error()),
            Status::Error => Ending::MethodFailed(error()),
            // Only the environment says why when it stops an episode; Ctrl-C says nothing.
            Status::Interrupted if s.error.is_some() => Ending::RobotStopped(error()),
            Status::Interrupted => Ending::Interrupted,
        }
    }
}

impl Prepared {
    pub fn task(&self) -> &Arc<Task> {
        &self.spec.task
    }

    pub fn settings(&self) -> &Settings {
        &self.spec.settings
    }

    pub fn budget(&self) -> Budget {
        self.spec.budget
    }

    /// The backend that answers, as the transcript records it.
    pub fn backend_info(&self) -> BackendInfo {
        self.spec.backend.info()
    }

    /// The backend chosen for a new episode (none for a replay).
    pub fn backend_choice(&self) -> Option<&BackendChoice> {
        self.spec.choice.as_ref()
    }

    /// Keeps the episode's model calls in a [`Waiting`] while they run, so that a front
    /// end can say which one it waits for when the model is slow.
    pub fn watch(&mut self) -> Arc<Waiting> {
        let waiting = Arc::new(Waiting::default());
        self.spec.backend = waiting.watch(Arc::clone(&self.spec.backend));
        waiting
    }

    /// The transcript a replay answers from.
    pub fn replaying(&self) -> Option<&Path> {
        self.spec.recording.as_ref().map(|(_, p)| p.as_path())
    }

    /// Runs the episode, writing its transcript into the output folder; `progress` sees
    /// each round as it ends; `cancel` ends it between rounds or in a model call.
    pub async fn run(
        mut self,
        cancel: &Cancel,
        progress: &mut (dyn FnMut(&Round) + Send),
    ) -> Result<Ran, Error> {
        let spec = &self.spec;
        let transcript = new_transcript(&spec.out, &spec.task, spec.settings.method.name())?;
        let path = transcript.path().to_owned();
        let (episode, header) = coherent_agents::run(
            &spec.task,
            self.env.as_mut(),
            spec.backend.as_ref(),
            self.method.as_mut(),
            &spec.settings,
            spec.budget,
            transcript,
            cancel,
            progress,
        )
        .await?;
        let replay = spec.recording.as_ref().map(|(replay, _)| {
            replay
                .difference(&episode)
                .map_or(ReplayCheck::Same, ReplayCheck::Differs)
        });
        let Episode { rounds, summary } = episode;
        let model_use = ModelUse::of(&header, &rounds, &summary);
        let cost_usd = model_use.cost(&spec.prices);
        Ok(Ran {
            task: Arc::clone(&spec.task),
            transcript: Transcript {
                header,
                rounds,
                summary: Some(summary),
            },
            path,
            goal_satisfied: self.env.goal_satisfied(),
            replay,
            model_use,
            cost_usd,
        })
    }
}
