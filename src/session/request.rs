//! An episode as a front end asks for it: a new one ([`RunRequest`]) or the replay of a
//! transcript ([`ReplayRequest`]). The command line and Python fill one from their own
//! arguments and call `prepare`, which does the whole sequence (the prompt set, the
//! prices, the task, the endpoint and the backend, the budget, the environment) and
//! gives the episode, ready for the one runner ([`crate::session::episode`]).

use std::path::PathBuf;
use std::sync::Arc;

use coherent_agents::episode::{Budget, HISTORY_WINDOW, MethodSpec, Settings};
use coherent_agents::llm::Backend;
use coherent_agents::{Cancel, Replay, transcript};
use coherent_core::native;
use coherent_core::planner::Limits;

use crate::session::backend::BackendRequest;
use crate::session::episode::{self, EpisodeSpec, Prepared};
use crate::session::error::Error;
use crate::session::prompts::{PriceSource, PromptSource};
use crate::session::robots::Robots;
use crate::session::tasks::TaskSource;

/// A new episode.
#[derive(Debug)]
pub struct RunRequest {
    pub task: TaskSource,
    pub method: MethodSpec,
    /// Who answers the method's questions.
    pub backend: BackendRequest,
    pub prompts: PromptSource,
    pub prices: PriceSource,
    /// Who carries the actions out.
    pub robots: Robots,
    /// Every action in Rapier too.
    pub physics: bool,
    /// Overrides the budget of 2 x GT.
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
}

impl RunRequest {
    /// `method` on `task` with the defaults: the backend the environment configures, the
    /// built-in prompts and prices, local robots, no physics, 2 x GT steps, the history
    /// window, transcripts into `runs/`.
    pub fn new(task: TaskSource, method: MethodSpec) -> RunRequest {
        RunRequest {
            task,
            method,
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
        }
    }

    /// The episode, ready to run. The prompt set is read first, so that a bad template
    /// costs nothing; sizing the budget may plan (`cancel` stops it); over ROS 2 the
    /// robots' servers are awaited.
    pub fn prepare(self, cancel: &Cancel) -> Result<Prepared, Error> {
        let prompts = self.prompts.read()?;
        let prices = self.prices.read()?;
        let task = self.task.task()?;
        let choice = self.backend.choose()?;
        let limits = Limits {
            cancel: Some(cancel.flag()),
            ..Limits::max_states(self.max_states)
        };
        let budget = Budget::searched(&task, self.max_steps, &limits)?;
        let backend = choice.for_episode(&limits, self.seed.unwrap_or(0))?;
        let settings = Settings {
            method: self.method,
            history: self.history,
            temperature: choice.temperature(),
            seed: self.seed,
            physics: self.physics,
            robots: self.robots.record(),
            prompts,
        };
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
        episode::prepare(spec, cancel)
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
}

impl ReplayRequest {
    /// The replay, ready to run.
    pub fn prepare(self) -> Result<Prepared, Error> {
        let prices = self.prices.read()?;
        let path = self.transcript;
        let recorded = transcript::read(&path)?;
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
        episode::prepare(spec, &Cancel::default())
    }
}
