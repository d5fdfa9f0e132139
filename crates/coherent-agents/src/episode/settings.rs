//! How an episode is run: the method (built in, or written outside the crate) and its
//! settings as a transcript records them. The step budget is apart ([`crate::episode::budget`]).

use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;
use std::time::Duration;

use coherent_core::Task;

pub use crate::episode::execution::Execution;
use crate::episode::policy::{MakePolicy, MethodFailure, Policy};
use crate::episode::rounds::HISTORY_WINDOW;
use crate::error::Error;
use crate::methods::templates::Prompts;
use crate::records::transcript::RobotsRecord;

/// A planning method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// COHERENT's loop with the assigner's history window.
    Pefa,
    /// The paper's "w/o history" ablation: the window is 0.
    PefaNoHistory,
    /// One central model choosing one robot's action per step.
    Cmrs,
    /// Decentralised dialogue, one round per step.
    Dmrs1d,
    /// Decentralised dialogue, two rounds per step.
    Dmrs2d,
    /// Primitive MCTS with the authors' settings; no model.
    Mcts,
    /// MCTS with a language-model prior at the root of each step's tree.
    LlmMcts,
    /// The optimal planner's plan: the ground-truth row; no model.
    Optimal,
}

impl Method {
    pub const ALL: [Method; 8] = [
        Method::Pefa,
        Method::PefaNoHistory,
        Method::Cmrs,
        Method::Dmrs1d,
        Method::Dmrs2d,
        Method::Mcts,
        Method::LlmMcts,
        Method::Optimal,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::Pefa => "pefa",
            Method::PefaNoHistory => "pefa-no-history",
            Method::Cmrs => "cmrs",
            Method::Dmrs1d => "dmrs-1d",
            Method::Dmrs2d => "dmrs-2d",
            Method::Mcts => "mcts",
            Method::LlmMcts => "llm-mcts",
            Method::Optimal => "optimal",
        }
    }

    /// Whether the method asks the episode's backend at all.
    pub fn asks_backend(self) -> bool {
        !matches!(self, Method::Mcts | Method::Optimal)
    }

    /// Whether the method can run `execution`: the tree searches, MCTS and LLM-MCTS,
    /// are sequential only (their tree's edges are one robot's action; a tree over
    /// joint steps is a method of its own, which the paper does not have).
    pub fn runs(self, execution: Execution) -> bool {
        execution == Execution::Sequential || !matches!(self, Method::Mcts | Method::LlmMcts)
    }

    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// A method written outside the crate (a Python class, say), by name: each episode gets
/// its own [`Policy`] from the maker.
#[derive(Clone)]
pub struct External {
    name: String,
    make: Arc<MakePolicy>,
    /// The longest one step may take (the policy's `act`, and its making at the first
    /// step); `None` for no limit.
    step_timeout: Option<Duration>,
    /// What the method declares of its own settings, recorded in each results line.
    settings: BTreeMap<String, serde_json::Value>,
}

impl External {
    /// The method `name`, whose episodes get their policy from `make`. The name goes
    /// into results, tables and transcript file names: letters, digits, `-`, `_` and `.`
    /// (not first), and none of the built-in methods' names.
    pub fn new(name: &str, make: Arc<MakePolicy>) -> Result<External, Error> {
        let allowed = |c: char| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.');
        if name.is_empty() || !name.chars().all(allowed) || name.starts_with('.') {
            return Err(Error::Invalid(format!(
                "method name {name:?}: use letters, digits, '-', '_' and '.' (not first)"
            )));
        }
        if Method::from_name(name).is_some() {
            return Err(Error::Invalid(format!(
                "method name {name:?} is a built-in method's: give yours another name"
            )));
        }
        Ok(External {
            name: name.to_owned(),
            make,
            step_timeout: None,
            settings: BTreeMap::new(),
        })
    }

    /// The method with each step limited to `limit` (`None`: no limit): a step that takes
    /// longer ends as the method's error.
    pub fn with_step_timeout(mut self, limit: Option<Duration>) -> External {
        self.step_timeout = limit;
        self
    }

    /// The method with its own settings declared (recorded in every results line, so
    /// that results of other settings are not taken for its own).
    pub fn with_settings(mut self, settings: BTreeMap<String, serde_json::Value>) -> External {
        self.settings = settings;
        self
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The longest one step may take.
    pub fn step_timeout(&self) -> Option<Duration> {
        self.step_timeout
    }

    /// Its own settings, as declared.
    pub fn settings(&self) -> &BTreeMap<String, serde_json::Value> {
        &self.settings
    }

    /// The policy of one episode of `task`, or why there is none.
    pub fn make(&self, task: &Arc<Task>) -> Result<Box<dyn Policy>, MethodFailure> {
        (self.make)(task)
    }
}

impl fmt::Debug for External {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("External")
            .field("name", &self.name)
            .field("step_timeout", &self.step_timeout)
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

/// Two are the same method when they have the same name, the same maker and the same
/// step limit and settings.
impl PartialEq for External {
    fn eq(&self, other: &External) -> bool {
        self.name == other.name
            && Arc::ptr_eq(&self.make, &other.make)
            && self.step_timeout == other.step_timeout
            && self.settings == other.settings
    }
}

/// The method of an episode: one of the built-in ones, or one written outside the crate.
#[derive(Clone, Debug, PartialEq)]
pub enum MethodSpec {
    Builtin(Method),
    External(External),
}

impl MethodSpec {
    /// The name in results, tables and transcripts.
    pub fn name(&self) -> &str {
        match self {
            MethodSpec::Builtin(m) => m.name(),
            MethodSpec::External(e) => e.name(),
        }
    }

    /// Whether the episode's backend answers the method's questions (a method written
    /// outside the crate asks its own models, if any). Whether an episode used a model
    /// is another question, answered by its calls ([`crate::ModelUse`]).
    pub fn asks_backend(&self) -> bool {
        match self {
            MethodSpec::Builtin(m) => m.asks_backend(),
            MethodSpec::External(_) => false,
        }
    }

    /// Whether the method can run `execution` (a method written outside the crate can:
    /// its `act` answers a decision per robot).
    pub fn runs(&self, execution: Execution) -> bool {
        self.builtin().is_none_or(|m| m.runs(execution))
    }

    /// `Ok` when the method can run `execution`, else the error that says it cannot.
    pub fn check_runs(&self, execution: Execution) -> Result<(), Error> {
        if self.runs(execution) {
            return Ok(());
        }
        Err(Error::Invalid(format!(
            "{} is sequential only: its search tree takes one robot's action a step; \
             run it with execution sequential",
            self.name()
        )))
    }

    /// The method's own settings: what a method written outside the crate declares;
    /// none for a built-in one (its settings are the run's).
    pub fn own_settings(&self) -> BTreeMap<String, serde_json::Value> {
        match self {
            MethodSpec::Builtin(_) => BTreeMap::new(),
            MethodSpec::External(e) => e.settings.clone(),
        }
    }

    /// The built-in method, when it is one.
    pub fn builtin(&self) -> Option<Method> {
        match self {
            MethodSpec::Builtin(m) => Some(*m),
            MethodSpec::External(_) => None,
        }
    }
}

impl From<Method> for MethodSpec {
    fn from(m: Method) -> MethodSpec {
        MethodSpec::Builtin(m)
    }
}

/// How an episode is run, as recorded in its transcript's header. The step budget is
/// apart ([`Budget`](crate::episode::Budget)).
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub method: MethodSpec,
    /// One robot's action a step (the paper's), or joint steps.
    pub execution: Execution,
    /// Rounds of history the assigner sees (ignored by `pefa-no-history`); for the
    /// baselines, the executed actions in their prompts (the paper: 5 for both).
    pub history: usize,
    pub temperature: Option<f32>,
    /// The model's sampling seed; also the MCTS search's and the DMRS speaking order's
    /// (0 when unset).
    pub seed: Option<u64>,
    /// Whether the environment is physical (recorded; the caller builds the environment).
    pub physics: bool,
    /// Who carries the actions out (recorded; the caller builds the environment).
    pub robots: RobotsRecord,
    /// The templates the method's prompts are rendered from (checked when made).
    pub prompts: Prompts,
}

impl Settings {
    pub fn new(method: impl Into<MethodSpec>) -> Settings {
        Settings {
            method: method.into(),
            execution: Execution::Sequential,
            history: HISTORY_WINDOW,
            temperature: None,
            seed: None,
            physics: false,
            robots: RobotsRecord::Local,
            prompts: Prompts::builtin(),
        }
    }
}
