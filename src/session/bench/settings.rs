//! What every episode of a benchmark run shares: the methods, the backend, the prompt set
//! and the prices, the budget and the robots; as a front end asks for them
//! ([`EpisodesRequest`]) and as the episodes get them ([`EpisodeSettings`]).

use std::collections::BTreeMap;

use coherent_agents::bench::RunSettings;
use coherent_agents::episode::HISTORY_WINDOW;
use coherent_agents::transcript::RobotsRecord;
use coherent_agents::{MethodSpec, PriceTable, Prompts};
use coherent_core::Execution;
use coherent_core::planner::Limits;

use crate::session::backend::{BackendChoice, BackendRequest};
use crate::session::error::Error;
use crate::session::prompts::{PriceSource, PromptSource};
use crate::session::robots::Robots;

/// What every episode of a benchmark run shares, as a front end asks for it.
#[derive(Debug)]
pub struct EpisodesRequest {
    /// The run's methods; an episode's key names its method.
    pub methods: Vec<MethodSpec>,
    /// How the robots take their steps, each method run in each (an episode's key names
    /// it).
    pub executions: Vec<Execution>,
    /// Who answers the model-using methods.
    pub backend: BackendRequest,
    pub prompts: PromptSource,
    pub prices: PriceSource,
    /// Rounds of history the methods see.
    pub history: usize,
    /// Most states one planner search may visit.
    pub max_states: usize,
    /// The step budget of every episode; `None` for the paper's 2 x GT.
    pub max_steps: Option<u32>,
    /// Every action in Rapier too.
    pub physics: bool,
    /// Who carries the actions out.
    pub robots: Robots,
}

impl EpisodesRequest {
    /// `methods` with the paper's settings: sequential, the backend the environment
    /// configures, the built-in prompts and prices, the history window, the default
    /// planner bound, 2 x GT steps, local robots without physics.
    pub fn new(methods: Vec<MethodSpec>) -> EpisodesRequest {
        EpisodesRequest {
            methods,
            executions: vec![Execution::Sequential],
            backend: BackendRequest::default(),
            prompts: PromptSource::default(),
            prices: PriceSource::default(),
            history: HISTORY_WINDOW,
            max_states: Limits::DEFAULT_MAX_STATES,
            max_steps: None,
            physics: false,
            robots: Robots::Local,
        }
    }

    /// The settings, checked: the prompt set first (a bad template costs nothing), the
    /// prices, distinct method names, the executions (each method must run each), the
    /// backend.
    pub fn prepare(self) -> Result<EpisodeSettings, Error> {
        let prompts = self.prompts.read()?;
        let prices = self.prices.read()?;
        if self.methods.is_empty() {
            return Err(Error::Invalid("no methods to run".into()));
        }
        distinct_names(&self.methods)?;
        let mut executions = self.executions;
        executions.sort();
        executions.dedup();
        if executions.is_empty() {
            return Err(Error::Invalid("no execution to run the methods in".into()));
        }
        for method in &self.methods {
            for &execution in &executions {
                method.check_runs(execution)?;
            }
        }
        Ok(EpisodeSettings {
            methods: self.methods,
            executions,
            backend: self.backend.choose()?,
            history: self.history,
            max_states: self.max_states,
            max_steps: self.max_steps,
            prompts,
            prices,
            physics: self.physics,
            robots: self.robots,
        })
    }
}

/// What every episode of a run shares: the methods, the backend and the settings.
#[derive(Clone, Debug)]
pub struct EpisodeSettings {
    pub methods: Vec<MethodSpec>,
    /// Sequential, parallel or both, in that order.
    pub executions: Vec<Execution>,
    pub backend: BackendChoice,
    pub history: usize,
    pub max_states: usize,
    pub max_steps: Option<u32>,
    /// The templates the methods' prompts are rendered from (a replay renders the
    /// recorded ones).
    pub prompts: Prompts,
    /// Prices each line's model calls (`cost_usd`).
    pub prices: PriceTable,
    pub physics: bool,
    pub robots: Robots,
}

impl EpisodeSettings {
    /// What the results lines of each method (by name) record of a run of these
    /// settings with seed indices `0..seeds`: the settings that make them comparable.
    pub fn record(&self, seeds: u32) -> BTreeMap<String, RunSettings> {
        let info = self.backend.info();
        let (model, sim_errors) = match &self.backend {
            BackendChoice::Builtin => (None, None),
            BackendChoice::Simulated(rates) => (None, Some(rates.label())),
            BackendChoice::OpenAi(_) | BackendChoice::Replay(_) => {
                (Some(info.model).filter(|m| !m.is_empty()), None)
            }
        };
        let model_seed = match &self.backend {
            BackendChoice::OpenAi(client) => client.config().seed,
            _ => None,
        };
        let run = RunSettings {
            backend: info.kind,
            model,
            sim_errors,
            temperature: self.backend.temperature(),
            model_seed,
            seeds,
            // The set of every template the run renders: the parallel set holds the
            // sequential one's templates too.
            prompts: self
                .prompts
                .hash(self.executions.iter().copied().max().unwrap_or_default())
                .to_owned(),
            history: self.history,
            max_steps: self.max_steps,
            max_states: self.max_states,
            physics: self.physics,
            robots: match self.robots.record() {
                RobotsRecord::Local => "local".to_owned(),
                RobotsRecord::Ros2 { .. } => "ros2".to_owned(),
            },
            coherent: coherent_agents::VERSION.to_owned(),
            executions: self.executions.clone(),
            method: BTreeMap::new(),
        };
        self.methods
            .iter()
            .map(|m| {
                let own = RunSettings {
                    method: m.own_settings(),
                    ..run.clone()
                };
                (m.name().to_owned(), own)
            })
            .collect()
    }
}

/// Refuses two methods of one name: results are keyed by the method's name, so one
/// written outside the crate needs its own.
pub fn distinct_names(methods: &[MethodSpec]) -> Result<(), Error> {
    let names: Vec<&str> = methods.iter().map(|m| m.name()).collect();
    match methods
        .iter()
        .find(|m| m.builtin().is_none() && names.iter().filter(|&&n| n == m.name()).count() > 1)
    {
        Some(m) => Err(Error::Invalid(format!(
            "two methods are named {:?}: give each its own name",
            m.name()
        ))),
        None => Ok(()),
    }
}
